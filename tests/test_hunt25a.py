"""What the hunt of the configuration files and outputs (25a) found in ``dad --add``,
``thresholds``, ``describe --thresholds`` and ``casebase export``: a traceback for an ADD
number too large for a float, a fluent's own threshold left out of the printed table, a
duplicated key of a JSON thresholds file dropped in silence, and a traceback or a file
beside the folder for ``casebase export --out`` a folder.
"""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path

import pytest

from features.fluents import FluentTable
from posecbr.cli import main
from tests.badinput import good_pose_file, refused, small_case_base

_MINI_ADD = """schema = 1
[qmp.knees]
words = "knees swinging"
conditions = [ {{ signal = "left_knee", quantity = "amplitude", min = {min} }} ]
[qmp.hips]
words = "hips swinging"
conditions = [ {{ signal = "left_hip", quantity = "amplitude", min = 0.1 }} ]
[activity.swing]
words = "swing"
labels = ["swing"]
sequence = [ {{ qmp = "knees", weight = 1 }}, {{ qmp = "hips", weight = 2 }} ]
"""


def test_dad_add_with_a_number_past_any_float_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """TOML's integers have any length in Python's reader: ``min = 999...9`` (400 digits) in
    an ADD ended ``posecbr dad --add`` in a TypeError traceback from numpy's isfinite."""
    clip = good_pose_file(tmp_path / "still.npz", frames=60)
    add = tmp_path / "add.toml"
    add.write_text(_MINI_ADD.format(min="9" * 400))
    line = refused(["dad", str(clip), "--add", str(add)], tmp_path, capsys)
    assert line == (
        f"posecbr dad: error: {add}: qmp 'knees': conditions[0]: field 'min': expected a "
        "finite number, got 99999999999999999999...(400 characters)"
    )
    add.write_text(_MINI_ADD.format(min="nan"))  # NaN and inf are refused as they were
    refused(["dad", str(clip), "--add", str(add)], tmp_path, capsys,
            "field 'min': expected a finite number, got nan")  # fmt: skip
    add.write_text(_MINI_ADD.format(min="-0.0"))  # and a good file still runs
    assert main(["dad", str(clip), "--add", str(add)]) == 0
    assert "swing" in capsys.readouterr().out


def test_thresholds_from_shows_a_near_pair_of_its_own_and_reads_back_the_same(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The near pairs were printed as one ``near`` entry copied from the first pair. An
    override of one pair (``near:left_index~nose``) was missing from ``thresholds --from``,
    which says it shows the table after the overrides; an override of the first pair
    (``near:left_index~right_index``) was printed as the family's, so the printed table,
    passed back with ``--thresholds``, set all 74 pairs to it."""
    for pair, tau in (("near:left_index~nose", 1.5), ("near:left_index~right_index", 1.25)):
        overrides = tmp_path / "pair.toml"
        overrides.write_text(f'[fluents."{pair}".lower]\ntau = {tau}\n')
        assert main(["thresholds", "--from", str(overrides)]) == 0
        printed = capsys.readouterr().out
        fluents = json.loads(printed)["fluents"]
        assert fluents["near"]["lower"] == {"tau": 0.5, "delta": 0.25}
        assert fluents[pair]["lower"] == {"tau": tau, "delta": 0.25}
        assert [k for k in fluents if k.startswith("near")] == ["near", pair]
        table = tmp_path / "t.json"  # the documented round trip: the same table again
        table.write_text(printed)
        assert FluentTable.from_file(table) == FluentTable.from_file(overrides)
        assert main(["thresholds", "--from", str(table)]) == 0
        assert capsys.readouterr().out == printed


def test_a_key_given_twice_in_a_json_thresholds_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """JSON's reader keeps the last of a repeated key: ``left_leg_bent`` given twice (its
    lower tau, then its motion) had ``describe --thresholds`` and ``thresholds --from`` run
    with the motion alone, the tau dropped unsaid; ``epsilon`` twice took the second. TOML's
    reader refused both already; JSON's now does too, naming the key."""
    clip = good_pose_file(tmp_path / "still.npz")
    twice = tmp_path / "t.json"
    twice.write_text(
        '{"fluents": {"left_leg_bent": {"lower": {"tau": 3.0}},\n'
        '             "left_leg_bent": {"motion": {"tau": 0.1}}}}\n'
    )
    message = f"{twice}: the key 'left_leg_bent' is given twice in one object"
    line = refused(["describe", str(clip), "--thresholds", str(twice)], tmp_path, capsys)
    assert line == f"posecbr describe: error: {message}"
    assert refused(["thresholds", "--from", str(twice)], tmp_path, capsys) == (
        f"posecbr thresholds: error: {message}"
    )
    twice.write_text('{"epsilon": 0.01, "epsilon": 0.2}')
    refused(["thresholds", "--from", str(twice)], tmp_path, capsys,
            "the key 'epsilon' is given twice in one object")  # fmt: skip
    once = tmp_path / "once.json"  # the same key in two objects is no repeat
    once.write_text('{"fluents": {"leg_bent": {"lower": {"tau": 2.0}, "motion": {"tau": 0.1}},'
                    ' "arm_bent": {"lower": {"tau": 2.0}}}}')  # fmt: skip
    assert main(["thresholds", "--from", str(once)]) == 0
    fluents = json.loads(capsys.readouterr().out)["fluents"]
    assert fluents["left_leg_bent"]["lower"]["tau"] == fluents["left_arm_bent"]["lower"]["tau"]


def test_casebase_export_out_a_folder_is_refused_as_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--out`` gets ``.npz`` added when it has another ending, and the folder check came
    after: ``casebase export --out .`` (or ``/``) ended in a ValueError traceback from
    pathlib ("has an empty name"), and ``--out cases/``, an existing folder, wrote
    ``cases.npz`` beside it; ``--out ..`` wrote a file named ``...npz``."""
    db = small_case_base(tmp_path)
    capsys.readouterr()
    (tmp_path / "cases").mkdir()
    monkeypatch.chdir(tmp_path / "cases")
    folders = [(".", "."), ("/", "/"), ("..", ".."), (f"{tmp_path}/cases/", f"{tmp_path}/cases")]
    for out, named in folders:
        line = refused(["casebase", "export", "--db", str(db), "--out", out], tmp_path, capsys)
        assert line == (
            f"posecbr casebase export: error: {named}: the export file is a folder, not a file"
        )
    # a name without .npz still gets it, added as numpy adds it (cases.v2 was cases.npz);
    # one ending in .NPZ keeps its name (it became x.npz)
    for given, written in (("e", "e.npz"), ("cases.v2", "cases.v2.npz"), ("x.NPZ", "x.NPZ")):
        assert main(["casebase", "export", "--db", str(db), "--out", str(tmp_path / given)]) == 0
        assert (tmp_path / written).is_file()
    assert not (tmp_path / "cases.npz").exists() and not (tmp_path / "x.npz").exists()


def test_add_schema_true_and_an_empty_label_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An ADD with ``schema = true`` was taken for schema 1 (true == 1 in Python), and
    ``labels = [""]`` for an activity no clip can be labelled: each is refused in one line."""
    clip = good_pose_file(tmp_path / "still.npz", frames=60)
    add = tmp_path / "add.toml"
    add.write_text(_MINI_ADD.format(min=0.1).replace("schema = 1", "schema = true"))
    refused(["dad", str(clip), "--add", str(add)], tmp_path, capsys, "unsupported ADD schema True")
    add.write_text(_MINI_ADD.format(min=0.1).replace('labels = ["swing"]', 'labels = [" "]'))
    refused(["dad", str(clip), "--add", str(add)], tmp_path, capsys,
            "activity 'swing'", "field 'labels' holds an empty label")  # fmt: skip


def test_a_thresholds_pipe_that_goes_on_is_cut_at_the_size_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The 10 MB limit of a configuration file was checked on its size on disk, which a
    pipe or a device does not have: ``--thresholds /dev/zero`` (or a pipe that goes on) was
    read whole, until the memory ran out (a MemoryError traceback). Here a pipe of 11 MB of
    spaces, which was read whole and then called "not valid JSON"."""
    root = tmp_path / "clip"
    root.mkdir()
    clip = good_pose_file(root / "still.npz")
    pipe = tmp_path / "t.json"
    os.mkfifo(pipe)

    def feed() -> None:
        try:
            with open(pipe, "wb") as fh:
                for _ in range(11):
                    fh.write(b" " * 1024**2)
        except BrokenPipeError:  # the reader stopped at the limit
            pass

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    line = refused(["describe", str(clip), "--thresholds", str(pipe)], root, capsys)
    writer.join(timeout=10)
    assert line == (
        f"posecbr describe: error: {pipe}: the thresholds file is over 10 MB: too large for a"
        " configuration file"
    )


def test_dad_step_longer_than_the_window_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``dad --window 1 --step 3`` on a 4-s clip judged the windows at 0-1 s and 3-4 s and
    said "2 windows of up to 1 s": the 2 s between them were judged by none, unsaid. Refused
    in one line, from the command and from Python (``DADConfig``)."""
    from cbr.dad import DADConfig
    from features.errors import ConfigError

    clip = good_pose_file(tmp_path / "still.npz", frames=120)
    refused(["dad", str(clip), "--window", "1", "--step", "3"], tmp_path, capsys,
            "--step: must not be longer than --window (1 s), got 3 s")  # fmt: skip
    with pytest.raises(ConfigError, match="longer than window_s"):
        DADConfig(window_s=1.0, step_s=3.0)
    assert DADConfig(window_s=2.0, step_s=2.0).step_s == 2.0  # windows end to end: all judged


def test_report_of_a_named_pipe_says_what_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``report`` given a named pipe said "no such results file" of a file that is there."""
    fifo = tmp_path / "results.json"
    os.mkfifo(fifo)
    outputs = tmp_path / "out"  # checked unchanged (reading the pipe itself would wait)
    outputs.mkdir()
    refused(["report", str(fifo), "--out", str(outputs / "report.html")], outputs, capsys,
            f"{fifo}: is a pipe, socket or device, not a results file")  # fmt: skip


def test_dad_window_shorter_than_the_step_steps_by_the_window(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``dad --window 0.5`` without ``--step`` (default 1 s) on a 4-s clip: windows end to
    end, 0-0.5 s, 0.5-1 s, ... (8 of them), not every other half second judged; the same from
    Python with ``DADClassifier(window_s=0.5)``."""
    from cbr.dad import DADClassifier
    from features.poses import load_pose

    clip = good_pose_file(tmp_path / "still.npz", frames=120)  # 30 fps: 4 s
    capsys.readouterr()
    assert main(["dad", str(clip), "--window", "0.5", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    starts = [w[0] for w in doc["windows_s"]]
    assert starts == pytest.approx([0.5 * i for i in range(8)])
    dad = DADClassifier(window_s=0.5).fit([load_pose(clip)], ["still"])
    assert (
        dad.config_.step_s == 0.5
        and DADClassifier().fit([load_pose(clip)], ["x"]).config_.step_s == 1.0
    )
