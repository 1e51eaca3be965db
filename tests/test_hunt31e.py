"""What the hunt of the evaluation path (31e) found in ``posecbr compare`` and ``posecbr
report``: the files asked for not written when standard output's reader stopped reading
(``| head``); the report of a ``--json`` file beside the ``--out`` folder without the run's
pictures, or with another run's; figures of models never trained (one class to learn from,
or none) without a word; the per-group table's columns run together and a label's escape
sequence printed raw.
"""

from __future__ import annotations

import base64
import contextlib
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cbr.evaluation.results import CompareResults, ConfusionPicture, Pictures, TimelinePicture
from cbr.evaluation.tables import group_table
from features.poses import load_pose
from posecbr.cli import main
from tests.badinput import ROOT, refused, small_case_base
from tests.processes import terminal_job

DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
# 24 clips, one configuration: a comparison of a few seconds
SMALL = [
    "--labels", "deep_squat,hurdle_step", "--subjects", "s01,s02", "--peers", "none",
    "--no-dad", "--features", "fluents", "--similarities", "euclidean", "--explain", "0",
]  # fmt: skip


def _small(*given: str) -> list[str]:
    """SMALL with the options of ``given`` (option, value pairs) in place of its own: an
    option given twice is refused."""
    kept, words = [], iter(SMALL)
    for word in words:
        if word in given[::2]:
            next(words)  # its value
        else:
            kept.append(word)
    return [*kept, *given]


def test_compare_piped_into_a_reader_that_stops_still_writes_its_files(tmp_path: Path) -> None:
    """``posecbr compare DATA --json r.json --out DIR | head -1``: the reader closed the pipe
    after the table's first line, the next line raised BrokenPipeError, and the command
    ended with status 0 having written neither r.json nor DIR (unbuffered output, as with
    PYTHONUNBUFFERED=1, or a table longer than the pipe's buffer). The table is what is
    printed; the files are what was asked for."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "POSECBR_NO_PROGRESS": "1"}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    argv = [sys.executable, "-m", "posecbr", "compare", str(DEMO), *SMALL]
    argv += ["--json", str(tmp_path / "r.json"), "--out", str(tmp_path / "o")]
    proc = subprocess.Popen(
        argv, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader has gone before the first line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=600) == 0, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    doc = json.loads((tmp_path / "r.json").read_text())
    assert [m["name"] for m in doc["methods"]] == ["cbr fluents/euclidean"]
    assert len(doc["clips"]) == 24  # 2 movements x 2 subjects x 6 clips
    assert json.loads((tmp_path / "o" / "results.json").read_text())["clips"] == doc["clips"]
    assert (tmp_path / "o" / "results.csv").is_file()
    assert (tmp_path / "o" / "accuracy.png").is_file()


def _inlined(page: str) -> list[bytes]:
    """The PNG pictures an HTML report inlines, in order."""
    found = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    return [base64.b64decode(data) for data in found]


def test_report_of_a_json_beside_the_out_folder_shows_that_runs_pictures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], compared_small: tuple[Path, str]
) -> None:
    """``compare --json run.json --out run``: run.json named its pictures as the folder
    run/ holds them ("timeline_00.png"), but ``report run.json`` reads them from run.json's
    own folder: it left out the prevalence and timelines of the run, and inlined a
    timeline_00.png of another run lying beside run.json, captioned as this run's. (The run
    is a copy of tests/conftest.py's compared_small, that command made once.)"""
    decoy = tmp_path / "timeline_00.png"
    decoy.write_bytes((ROOT / "docs" / "workout_timeline.png").read_bytes())
    run = tmp_path / "run"
    shutil.copytree(compared_small[0] / "run", run)
    shutil.copy(compared_small[0] / "run.json", tmp_path / "run.json")
    doc = json.loads((tmp_path / "run.json").read_text())
    assert doc["pictures"]["timelines"][0]["file"] == "run/timeline_00.png"
    assert doc["pictures"]["accuracy"] == "run/accuracy.png"
    assert main(["report", str(tmp_path / "run.json"), "--out", str(tmp_path / "r.html")]) == 0
    capsys.readouterr()
    # the run's five pictures, as in its folder (the order of the page): none other
    names = ["accuracy", "confusion_cbr_fluents_euclidean", "prevalence"]
    names += ["timeline_00", "timeline_01"]
    expected = [(run / f"{n}.png").read_bytes() for n in names]
    assert _inlined((tmp_path / "r.html").read_text()) == expected
    assert decoy.read_bytes() not in expected


def test_a_results_file_away_from_the_pictures_names_none() -> None:
    """A --json file whose folder does not hold the --out folder cannot name the pictures
    from its folder: it names none (``report`` draws the accuracy and confusion pictures
    from the results)."""
    from posecbr.commands.compare import _pictures_seen_from

    pics = Pictures(
        accuracy="accuracy.png",
        confusion=[ConfusionPicture("dad", "confusion_dad.png")],
        prevalence="prevalence.png",
        timelines=[TimelinePicture("squat", "a.npz", "timeline_00.png")],
    )
    away = _pictures_seen_from(pics, Path("/data/x/r.json"), Path("/data/y/o"))
    assert away.to_dict() == {}
    below = _pictures_seen_from(pics, Path("/data/r.json"), Path("/data/y/o"))
    assert below.files() == [
        "y/o/accuracy.png", "y/o/prevalence.png", "y/o/confusion_dad.png", "y/o/timeline_00.png"
    ]  # fmt: skip
    assert _pictures_seen_from(pics, Path("/data/y/o/r.json"), Path("/data/y/o")) == pics


def test_compare_refuses_a_model_per_subject_under_leave_one_subject_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--target correct --within subject`` (cv loso): each subject's model was trained on
    the clips of that subject the fold left in, none, so every clip got the fallback answer
    'correct': a table of 50.0 % crowned best, no case base, without a word (the fallback
    was noted only inside the JSON)."""
    argv = ["compare", str(DEMO), *SMALL, "--target", "correct", "--within", "subject"]
    refused([*argv, "--json", str(tmp_path / "r.json")], tmp_path, capsys, "--within: ")
    line = refused(argv, tmp_path, capsys, "'subject'", "--cv kfold")
    assert "no model" in line


# on one xdist worker: the module's per_movement made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt31e")


@pytest.fixture(scope="module")
def per_movement(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, object], str]:
    """A comparison with one model per movement (one activity each): the results document
    and what was printed on stderr."""
    out = tmp_path_factory.mktemp("per_movement") / "r.json"
    argv = ["compare", str(DEMO), *SMALL, "--within", "movement", "--json", str(out)]
    argv.remove("--no-dad")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("POSECBR_NO_PROGRESS", "1")
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            assert main(argv) == 0
    return json.loads(out.read_text()), err.getvalue()


def test_compare_says_where_no_model_was_trained(
    per_movement: tuple[dict[str, object], str],
) -> None:
    """Each movement's clips are one activity: its model had one class to learn from in
    every fold and answered it for the fold's 6 clips of the movement (2 subjects, 6 clips
    each), which the table counted as 100 % without a word."""
    doc, err = per_movement
    expected = [
        f"{m}: training fold has only {a!r}; predicted {a!r} for its 6 test clips (no model "
        "trained there; the figures count that answer)"
        for m, a in (("m01", "deep_squat"), ("m02", "hurdle_step"))
    ]
    assert [n for n in doc["notes"] if "training fold" in n] == expected  # type: ignore[attr-defined]
    for note in expected:
        assert f"note: {note}\n" in err


def test_compare_table_per_group_keeps_its_columns_apart(
    per_movement: tuple[dict[str, object], str],
) -> None:
    """The per-group table gave each method a column as wide as its name and two spaces:
    "dad" (5) printed "100.0100.0" beside the case base's column, and a header "movement"
    wider than the groups ("m01") shifted the row under it; a label's escape sequence was
    printed raw (an ANSI colour)."""
    doc, _ = per_movement
    lines = group_table(CompareResults.from_dict(doc))
    assert lines[1:] == [
        "accuracy % per movement (one model each):",
        "movement    cbr fluents/euclidean    dad",
        "m01                         100.0  100.0",
        "m02                         100.0  100.0",
    ]
    hostile = json.loads(json.dumps(doc).replace('"m01"', '"m\\u001b[31m01"'))
    lines = group_table(CompareResults.from_dict(hostile))
    assert "\x1b" not in "".join(lines)
    # the escaped name (12 characters) and two spaces, then the columns as above
    assert lines[3] == "m\\x1b[31m01" + " " * 2 + " " * 18 + "100.0" + "  100.0"


@pytest.mark.parametrize(
    ("flag", "value", "needle"),
    [
        ("--labels", "deep_squat,hurdle_step,sit_to_stnd", "no clip labelled 'sit_to_stnd'"),
        ("--subjects", "s01,s02,s9", "no clip of subject 's9'"),
    ],
)
def test_compare_refuses_a_label_or_subject_no_clip_has(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flag: str, value: str, needle: str
) -> None:
    """A mistyped ``--labels`` or ``--subjects`` entry was dropped without a word: the
    comparison of two movements was printed and written as the one of three asked for
    (``classify --subjects`` refuses the same mistake)."""
    argv = ["compare", str(DEMO), *_small(flag, value), "--json", str(tmp_path / "r.json")]
    refused(argv, tmp_path, capsys, f"{flag}: ", needle)


@pytest.mark.parametrize("split", [None, "windows"])  # clips read by entries, or in memory
@pytest.mark.parametrize(
    ("flag", "value", "needle"),
    [
        ("--labels", "deep_squat,sit_to_stnd", "no clip labelled 'sit_to_stnd'"),
        ("--subjects", "s01,s9", "no clip of subject 's9'"),
    ],
)
def test_train_refuses_a_label_or_subject_no_clip_has(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    flag: str,
    value: str,
    needle: str,
    split: str | None,
) -> None:
    """As ``compare``: ``train --labels deep_squat,sit_to_stnd`` stored a case base of deep
    squats alone without a word (with the other option the demo's s01-s03 narrow it to one
    movement and subject, 6 clips; the case base is not written)."""
    narrow = ["--subjects", "s01"] if flag == "--labels" else ["--labels", "deep_squat"]
    argv = ["train", str(DEMO / "labels.csv"), "--db", str(tmp_path / "cb.sqlite"), flag, value,
            *narrow, "-k", "1", *(["--split", split] if split else [])]  # fmt: skip
    refused(argv, tmp_path, capsys, f"{flag}: ", needle)


def test_train_refuses_a_trim_that_leaves_fewer_cases_than_k(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train --trim 0.1`` of 12 clips (s01's deep squats and hurdle steps, 6 each) kept a
    tenth of each activity, fewer cases than the 5 it votes with, and stored them without a
    word (``casebase trim`` refuses the same). With ``-k 1`` the same trim is stored."""
    argv = ["train", str(DEMO / "labels.csv"), "--subjects", "s01", "--labels",
            "deep_squat,hurdle_step", "--trim", "0.1"]  # fmt: skip
    refused([*argv, "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
            "fewer than the 5 the case base votes with (k): nothing stored")  # fmt: skip
    assert main([*argv, "--db", str(tmp_path / "one.sqlite"), "-k", "1"]) == 0


@pytest.mark.parametrize(
    ("params", "needle"),
    [
        (["--similarities", "dtw", "--param", 'similarity_params={"band": 2}'],
         "band must be in [0, 1], got 2 (cbr fluents/dtw)"),
        (["--similarities", "dtw", "--param", "feature_weights=fisher"],
         "learned feature weights need vector problems"),
        (["--param", 'similarity_params={"band": 0.2}'],
         "similarity 'euclidean' has no parameter band"),
    ],
)  # fmt: skip
def test_compare_refuses_a_measure_its_configurations_cannot_build(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], params: list[str], needle: str
) -> None:
    """``--param similarity_params={"band": 2}`` (or a weighting the measure cannot take)
    was checked only when each fold fitted: every configuration failed as a row of the
    table, and the command ended with status 0 having written a results file of failures.
    Like the other case-base parameters, it is refused before any work."""
    argv = ["compare", str(DEMO), *_small(*params), "--json", str(tmp_path / "r.json")]
    refused(argv, tmp_path, capsys, "--param: ", needle)


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["compare", str(DEMO), *SMALL, "--json", "-"], "-: the JSON output goes to a file"),
        (["compare", str(DEMO), *SMALL, "--csv", "-"], "-: the CSV output goes to a file"),
        (["compare", str(DEMO), *SMALL, "--out", "-"], "-: --out is a folder"),
    ],
)
def test_an_output_named_dash_is_refused_not_a_file_named_dash(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    argv: list[str],
    needle: str,
) -> None:
    """``--json -`` (standard output, as a user of Unix tools writes it) wrote the results
    to a file named "-" in the current folder, and nothing to standard output."""
    monkeypatch.chdir(tmp_path)
    refused(argv, tmp_path, capsys, needle)


def test_casebase_export_to_dash_is_refused_not_dash_npz(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``casebase export --out -`` wrote "-.npz" in the current folder."""
    db = small_case_base(tmp_path)
    capsys.readouterr()
    monkeypatch.chdir(tmp_path)
    argv = ["casebase", "export", "--db", str(db), "--out", "-"]
    refused(argv, tmp_path, capsys, "-: the export file goes to a file")


def test_report_to_dash_is_refused_not_a_file_named_dash(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    per_movement: tuple[dict[str, object], str],
) -> None:
    """``report r.json --out -`` wrote the page to a file named "-"."""
    (tmp_path / "r.json").write_text(json.dumps(per_movement[0]))
    monkeypatch.chdir(tmp_path)
    refused(["report", "r.json", "--out", "-"], tmp_path, capsys, "-: the report goes to a file")


def test_picture_notes_print_a_labels_control_character_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A label holding an escape character: the pictures' note "the font has no glyph for
    ..." named the character itself, printed raw on the terminal by ``compare --out`` and by
    ``report`` (every other line escapes it)."""
    rows = ["path,label,subject"]
    for movement, label in (("m01", "squat\x1b[31m"), ("m02", "hurdle_step")):
        for subject in ("s01", "s02"):
            for clip in sorted(DEMO.glob(f"{movement}_{subject}_*.npz")):
                rows.append(f"{clip},{label},{subject}")
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    argv = ["compare", str(tmp_path / "labels.csv"), "--peers", "none", "--no-dad"]
    argv += ["--features", "fluents", "--similarities", "euclidean", "--explain", "0"]
    assert main([*argv, "--out", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert "pictures: the font has no glyph for \\x1b (in names drawn)" in err
    assert "\x1b" not in err
    doc = json.loads((tmp_path / "o" / "results.json").read_text())
    doc["pictures"] = {}  # the report draws the accuracy and confusion pictures itself
    (tmp_path / "r.json").write_text(json.dumps(doc))
    assert main(["report", str(tmp_path / "r.json"), "--out", str(tmp_path / "r.html")]) == 0
    err = capsys.readouterr().err
    assert "pictures: the font has no glyph for \\x1b (in names drawn)" in err
    assert "\x1b" not in err


@pytest.mark.parametrize(
    ("flags", "needle"),
    [
        (["--features", "qmp", "--similarities", "dtw"],
         "--features: qmp features are one vector per clip, compared by euclidean only"),
        (["--features", "fluents,fluents"], "--features: feature level 'fluents' given twice"),
        (["--similarities", "euclidean,dtw,euclidean"],
         "--similarities: similarity 'euclidean' given twice"),
        (["--peers", "dtw-knn,dtw-knn"], "--peers: peer 'dtw-knn' given twice"),
    ],
)  # fmt: skip
def test_compare_refuses_a_method_list_of_nothing_or_twice_the_same(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], needle: str
) -> None:
    """``--features qmp --similarities dtw --no-dad``: QMP vectors are compared by euclidean
    alone, so no method was left, and the command printed an empty table and wrote its
    results with status 0. ``--features fluents,fluents``: every configuration twice, rows of
    one name (their pictures one file)."""
    argv = ["compare", str(DEMO), *_small(*flags), "--json", str(tmp_path / "r.json")]
    refused(argv, tmp_path, capsys, needle)


def test_compare_says_qmp_is_not_compared_when_no_measure_takes_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--similarities dtw`` with the default feature levels (fluents, qmp): the note said
    "qmp features ...: compared by euclidean only", and no QMP configuration was run (no
    euclidean): it says they were not compared."""
    argv = ["compare", str(DEMO), *_small("--similarities", "dtw", "--features", "fluents,qmp")]
    assert main([*argv, "--json", str(tmp_path / "r.json")]) == 0
    note = (
        "qmp features are one vector per clip, compared by euclidean only, which "
        "--similarities leaves out: not compared"
    )
    assert f"note: {note}\n" in capsys.readouterr().err
    doc = json.loads((tmp_path / "r.json").read_text())
    assert note in doc["notes"]
    assert [m["name"] for m in doc["methods"]] == ["cbr fluents/dtw"]


def test_compare_into_an_earlier_runs_folder_leaves_none_of_its_pictures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], compared_slice: Path
) -> None:
    """``compare --out DIR`` over the folder of an earlier comparison: the earlier run's
    pictures this one did not draw (DAD's confusion matrix, a third activity's timeline)
    stayed beside the new results as if they were this run's. The earlier run is a copy of
    the session's comparison of three activities with DAD (tests/conftest.py
    compared_slice: compare names no folder in its files, so a copy is that run)."""
    out = tmp_path / "o"
    shutil.copytree(compared_slice / "o", out)
    assert (out / "confusion_dad.png").is_file() and (out / "timeline_02.png").is_file()
    (out / "mine.png").write_bytes((out / "timeline_02.png").read_bytes())  # not compare's
    assert main(["compare", str(DEMO), *SMALL, "--out", str(out)]) == 0
    capsys.readouterr()
    doc = json.loads((out / "results.json").read_text())
    drawn = ["accuracy.png", "confusion_cbr_fluents_euclidean.png", "prevalence.png"]
    drawn += ["timeline_00.png", "timeline_01.png"]
    assert sorted(doc["pictures"]["timelines"][i]["file"] for i in range(2)) == drawn[3:]
    files = sorted(p.name for p in out.iterdir())
    assert files == sorted([*drawn, "mine.png", "results.csv", "results.json"])


@pytest.mark.skipif(sys.platform != "linux", reason="process groups and /proc: Linux")
def test_ctrl_c_of_a_compare_with_workers_prints_one_line(tmp_path: Path) -> None:
    """Ctrl-C in a terminal signals every process of the group: the spawned workers of
    ``compare --jobs 2`` each printed a KeyboardInterrupt traceback (of a task or of their
    imports) under "posecbr compare: interrupted". The workers now leave Ctrl-C to the
    command, which stops them: the one line, status 130, no process left, nothing
    written."""
    argv = ["compare", str(DEMO), "--peers", "none"]
    argv += ["--labels", "deep_squat,hurdle_step,sit_to_stand", "--jobs", "2"]
    argv += ["--out", str(tmp_path / "o")]
    proc = terminal_job(argv, tmp_path)
    children: list[str] = []
    deadline = time.monotonic() + 300
    while not children and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)
        found = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True)
        children = found.stdout.split()
    assert children, "the workers never started"
    time.sleep(1.5)  # the workers importing, or at their first tasks
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert (proc.returncode, err.decode(), out.decode()) == (
        130,
        "posecbr compare: interrupted\n",
        "",
    )
    left = ["?"]
    for _ in range(50):  # the workers (and multiprocessing's tracker) end with the command
        found = subprocess.run(["pgrep", "-g", str(proc.pid)], capture_output=True, text=True)
        left = found.stdout.split()
        if not left:
            break
        time.sleep(0.2)
    assert left == []
    assert not (tmp_path / "o").exists()


def test_classify_differences_name_no_joint_the_clip_never_showed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A Kinect clip (19 of BlazePose's 33 joints never seen: face, fingers, heels) against
    a case base of BlazePose clips: "Differs from it most in: left index to the left
    (highest) 0.00 torso lengths here, 1.68 there" (``--verbose``; "differences" in the
    JSON), the fill of a joint the clip has not, read as what it did (the counterfactual
    already said "not seen")."""
    from tests.test_cbr_cli import _write_classes

    train = _write_classes(tmp_path / "train", 3, 5)  # synthetic BlazePose-33 arm movements
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(train), "--db", str(db)]) == 0  # clip summaries, euclidean
    clip = DEMO / "m01_s01_e01.npz"
    missing = [n for n, gone in zip(load_pose(clip).joint_names,
                                    np.isnan(load_pose(clip).positions).all(axis=(0, 2)),
                                    strict=True) if gone]  # fmt: skip
    assert len(missing) == 19 and "left_index" in missing
    capsys.readouterr()
    assert main(["classify", str(clip), "--db", str(db), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)["results"][0]
    assert result["differences"]
    for d in result["differences"]:
        assert not any(j.replace("_", " ") in d["feature"] for j in missing), d


def test_removing_an_earlier_runs_pictures_keeps_what_is_not_its_own(tmp_path: Path) -> None:
    """Only PNG files directly in the --out folder are removed: a name in a folder of its
    own ("o/accuracy.png", a --json results file naming another run's --out), a file that
    is no PNG image and a link are kept."""
    from posecbr.commands.compare import _remove_stale

    png = (ROOT / "docs" / "workout_timeline.png").read_bytes()
    (tmp_path / "o").mkdir()
    for name in ("o/accuracy.png", "timeline_02.png", "confusion_dad.png"):
        (tmp_path / name).write_bytes(png)
    (tmp_path / "prevalence.png").write_text("not a picture")
    (tmp_path / "linked.png").symlink_to(tmp_path / "o" / "accuracy.png")
    earlier = ["o/accuracy.png", "timeline_02.png", "confusion_dad.png", "prevalence.png"]
    _remove_stale(tmp_path, [*earlier, "linked.png", "gone.png"], ["confusion_dad.png"])
    left = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))
    assert left == ["confusion_dad.png", "linked.png", "o", "o/accuracy.png", "prevalence.png"]


def test_compare_refuses_a_clip_listed_twice(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV listing one clip twice was compared with both copies: the clip counted
    twice, and cross-validated over clips (``--cv kfold``) one copy could be the training
    case that answers the other. ``train`` and ``classify`` refuse the same CSV."""
    rows = ["path,label,subject"]
    for movement, label in (("m01", "deep_squat"), ("m02", "hurdle_step")):
        for clip in sorted(DEMO.glob(f"{movement}_s0[12]_*.npz")):
            rows.append(f"{clip},{label},{clip.name[4:7]}")
    rows.append(rows[-1])
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    argv = ["compare", str(tmp_path / "labels.csv"), "--peers", "none", "--no-dad"]
    argv += ["--features", "fluents", "--similarities", "euclidean", "--cv", "kfold"]
    needle = "m02_s02_e03_inc.npz frames 0-"
    refused([*argv, "--json", str(tmp_path / "r.json")], tmp_path, capsys, needle, "twice")
