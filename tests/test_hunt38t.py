"""Hunt 38t: the command line's options, one idea under one name across commands, and what
each command says it did.

- ``compare -k 3`` was refused ("unrecognized arguments: -k 3") where ``train``,
  ``classify``, ``segment`` and ``casebase trim`` take ``-k``: compare now takes it too.
- worker processes are ``compare --jobs`` and ``extract --workers``: each now takes the
  other's name as well.
- the video with the stick figure drawn is ``segment --overlay`` and ``extract --overlay``,
  but ``watch --out``: watch now takes ``--overlay`` too.
- ``casebase trim`` said the editor's figures but not which case base of which store it
  changed: it now says so, as ``casebase export`` and ``copy`` say where they wrote.
- ``posecbr --help`` now says what each exit status means and how progress bars are turned
  off (``POSECBR_NO_PROGRESS``), which neither it nor README said.
- ``describe`` and ``dad`` now take ``--fps`` and ``--asf`` as ``reps`` and ``segment`` do.
- ``classify`` now takes ``--labels`` beside ``--subjects``, as ``train`` and ``compare`` do.
- ``posecbr thresholds`` now names ``describe``, the one command its file is given to.
- ``classify --feedback`` now says what it stored in which case base of which store (with
  ``--quiet`` it said nothing of it).
"""

from __future__ import annotations

import argparse
import io
import json
import shutil
import sys
from pathlib import Path

import pytest

from features.progress import progress_enabled
from posecbr.cli import build_parser, main
from posecbr.commands import thresholds
from tests.badinput import refused, small_case_base
from tests.test_cbr_cli import _write_classes

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


def test_compare_takes_k_as_the_other_commands_spell_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``-k 1``: the one case-base configuration retrieves 1 case, as ``--k 1`` says."""
    out = tmp_path / "results.json"
    argv = [
        "compare", str(DEMO), "--similarities", "euclidean", "--features", "fluents",
        "--no-dad", "--peers", "none", "--labels", "deep_squat,hurdle_step",
        "--explain", "0", "-k", "1", "--json", str(out),
    ]  # fmt: skip
    assert main(argv) == 0, capsys.readouterr().err
    assert json.loads(out.read_text())["settings"]["k"] == 1


def test_extract_takes_jobs_as_compare_spells_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract --jobs 0`` was "unrecognized arguments" (exit 2); it is ``--workers``, checked
    as such (the video is never opened: its bytes need not be one)."""
    video = tmp_path / "squat.mp4"
    video.write_bytes(b"not decoded")
    argv = ["extract", str(video), "--out", str(tmp_path / "poses"), "--jobs", "0"]
    refused(argv, tmp_path, capsys, "--workers (--jobs): must be at least 1, got 0")
    args = build_parser().parse_args(["extract", str(video), "--out", "p", "--jobs", "3"])
    assert args.workers == 3


def test_compare_takes_workers_as_extract_spells_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    refused(["compare", str(DEMO), "--workers", "0"], tmp_path, capsys,
            "--jobs: must be at least 1, got 0")  # fmt: skip
    assert build_parser().parse_args(["compare", str(DEMO), "--workers", "2"]).jobs == 2


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def test_watch_takes_overlay_as_segment_and_extract_name_it(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch --overlay V`` was "unrecognized arguments"; it is ``--out V``: refused over
    the video watched as ``--out`` is, before the video is read."""
    video = tmp_path / "squat.mp4"
    video.write_bytes(b"not decoded")
    argv = ["watch", str(video), "--db", str(case_base), "--overlay", str(video)]
    refused(argv, tmp_path, capsys, "the output video would overwrite an input")
    args = build_parser().parse_args(["watch", "0", "--db", "cb", "--overlay", "w.mp4"])
    assert args.out == Path("w.mp4")


def _cases_in_use(db: Path, capsys: pytest.CaptureFixture[str]) -> int:
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db), "--json"]) == 0
    return int(json.loads(capsys.readouterr().out)["case_bases"][0]["cases"])


def test_trim_says_which_case_base_of_which_store_it_changed(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``casebase trim`` printed the editor's figures alone, the same words as ``--dry-run``
    but for its note: not the store it wrote nor that cases were deactivated there. A dry
    run and a trim that drops nothing still say nothing of the kind."""
    db = tmp_path / "cb.sqlite"
    shutil.copy(case_base, db)
    before = _cases_in_use(db, capsys)
    assert main(["casebase", "trim", "--db", str(db), "--dry-run"]) == 0
    assert "deactivated" not in capsys.readouterr().out
    assert main(["casebase", "trim", "--db", str(db), "--keep", "0.5"]) == 0
    out = capsys.readouterr().out.splitlines()
    after = _cases_in_use(db, capsys)
    assert after < before
    gone = before - after
    said = f"  case base 'default' in {db}: {gone} case{'s' * (gone != 1)} deactivated"
    assert out[1] == said + " (casebase list --all lists them)", out
    capsys.readouterr()
    assert main(["casebase", "list", "--db", str(db), "--all", "--json"]) == 0
    cases = json.loads(capsys.readouterr().out)["cases"]
    assert sum(not c["active"] for c in cases) == gone


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_help_says_the_exit_statuses_and_each_is_what_a_command_gives(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``posecbr --help`` said nothing of exit statuses nor of turning progress bars off
    (README neither): each status it now names is the one the case gives."""
    with pytest.raises(SystemExit) as stop:
        main(["--help"])
    assert stop.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    for said in ("Exit status: 0 done; 1 a problem with the input",
                 "2 a command line that cannot be read", "130 stopped by Ctrl-C",
                 "143 by SIGTERM", "POSECBR_NO_PROGRESS=1 turns them off"):  # fmt: skip
        assert said in text, said
    assert main(["describe", str(tmp_path / "none.npz")]) == 1  # a problem with the input
    assert main(["classify", str(DEMO), "--db", "x", "--top", "-1"]) == 1  # an option's value
    for argv in (["describe", "--min-confidence", "high", "x.npz"], ["descibe"], ["describe"]):
        with pytest.raises(SystemExit) as stop:
            main(argv)
        assert stop.value.code == 2, argv
    assert main([]) == 2  # no command: the help
    assert "Exit status" in capsys.readouterr().out

    def stopped(args: object) -> int:
        raise KeyboardInterrupt

    monkeypatch.setattr(thresholds, "run", stopped)
    assert main(["thresholds"]) == 130
    monkeypatch.setattr(sys, "stderr", _Terminal())
    monkeypatch.delenv("POSECBR_NO_PROGRESS", raising=False)
    assert progress_enabled()
    monkeypatch.setenv("POSECBR_NO_PROGRESS", "1")
    assert not progress_enabled()


def test_describe_and_dad_take_the_rate_and_skeleton_as_reps_and_segment_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``describe`` and ``dad`` read an AMC file (120 fps assumed) or any clip at the rate its
    file gives, with no ``--fps`` or ``--asf`` to say otherwise, which ``reps``,
    ``segment`` and ``train`` take: a clip filmed at 60 fps was judged in windows of twice
    its time. Both now take them: the demo clip (73 frames at 30 fps) read at 60 fps lasts
    73/60 s."""
    clip = DEMO / "m01_s01_e01.npz"
    capsys.readouterr()
    assert main(["describe", str(clip), "--fps", "60", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["fps"], doc["frames"]) == (60.0, 73)
    assert main(["describe", str(clip), "--fps", "60"]) == 0
    assert capsys.readouterr().out.startswith(f"{clip}: 73 frames at 60 fps (1.2 s)")
    assert main(["dad", str(clip), "--fps", "60", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["fps"] == 60.0 and doc["duration_s"] == pytest.approx(73 / 60)
    for command in ("describe", "dad"):
        refused([command, str(clip), "--asf", str(tmp_path / "s.asf")], tmp_path, capsys,
                "--asf: goes with an AMC recording, not m01_s01_e01.npz")  # fmt: skip
        refused([command, str(clip), "--fps", "0"], tmp_path, capsys,
                "--fps: must be a frame rate in [0.01, 10000], got 0")  # fmt: skip


def test_classify_takes_labels_as_train_and_compare_do(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``classify DATASET --labels deep_squat`` was "unrecognized arguments" where it took
    ``--subjects`` and ``train`` and ``compare`` take both: the activities chosen now are
    the clips classified (the demo's labels.csv: those rows of subject s02)."""
    rows = [r.split(",") for r in (DEMO / "labels.csv").read_text().splitlines()[1:]]
    wanted = {"deep_squat", "side_lunge"}
    expected = sorted(str(DEMO / r[0]) for r in rows if r[1] in wanted and r[2] == "s02")
    assert len(expected) == 12
    capsys.readouterr()
    argv = ["classify", str(DEMO), "--db", str(case_base), "--json",
            "--labels", "deep_squat, side_lunge", "--subjects", "s02"]  # fmt: skip
    assert main(argv) == 0
    results = json.loads(capsys.readouterr().out)["results"]
    assert sorted(r["clip"] for r in results) == expected
    assert {r["true_label"] for r in results} == wanted
    argv = ["classify", str(DEMO), "--db", str(case_base), "--labels", "deep_squt"]
    # named with the labels the data have, as train and compare name them (hunt 38z)
    refused(argv, tmp_path, capsys, f"--labels: no clip labelled 'deep_squt' in {DEMO}: its labels")
    argv[1] = str(DEMO / "m01_s01_e01.npz")
    argv[-1] = "deep_squat"
    refused(argv, tmp_path, capsys, "--labels: filters the clips of a labels CSV or dataset")


def _parsers() -> dict[str, argparse.ArgumentParser]:
    """Every command's and action's parser, by its name ("casebase trim")."""
    found: dict[str, argparse.ArgumentParser] = {}

    def walk(parser: argparse.ArgumentParser, name: str) -> None:
        found[name] = parser
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for child, sub in action.choices.items():
                    walk(sub, f"{name} {child}".strip())

    walk(build_parser(), "")
    return found


def test_thresholds_names_the_command_its_file_is_given_to(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``posecbr thresholds`` said "edit it and pass --thresholds FILE" without the command:
    ``train``, ``classify`` and ``segment`` refuse ``--thresholds``; ``describe`` alone takes
    it, and the help now says so."""
    parsers = _parsers()
    takes = sorted(n for n, p in parsers.items() if "--thresholds" in p._option_string_actions)
    # and thresholds, which shows the table with the file's overrides (--from; hunt 39c)
    assert takes == ["describe", "thresholds"]
    with pytest.raises(SystemExit):
        main(["thresholds", "--help"])
    assert "pass it to describe --thresholds FILE" in " ".join(capsys.readouterr().out.split())


def _maintenance(db: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, int]:
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db), "--json"]) == 0
    return dict(json.loads(capsys.readouterr().out)["case_bases"][0]["maintenance"])


def test_classify_feedback_says_what_it_stored_where(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``classify --feedback LABEL --quiet`` changed the case base and said nothing of it (the
    clips' "feedback:" lines are not printed with --quiet), nor, without it, which store it
    wrote: a closing line now says how many clips were retained and cases revised in which
    case base of which store, the counts the case base's history then holds."""
    db = tmp_path / "cb.sqlite"
    shutil.copy(case_base, db)
    clips = _write_classes(tmp_path / "new", 1, 12)
    label = sorted(p.name for p in clips.iterdir())[0]
    clip = next((clips / label).iterdir())
    runs = [["--novelty", "0", "--benefit", "0", "--quiet"], ["--quiet"], []]
    for extra in runs:  # retained (every novelty passes 0); then the same clip: revised
        before = _maintenance(db, capsys)
        argv = ["classify", str(clip), "--db", str(db), "--feedback", label, *extra]
        assert main(argv) == 0
        last = capsys.readouterr().out.splitlines()[-1]
        after = _maintenance(db, capsys)
        retained = after.get("retain", 0) - before.get("retain", 0)
        revised = after.get("revise", 0) - before.get("revise", 0)
        assert retained + revised == 1
        assert last == (
            f"feedback stored in case base 'default' of {db}: {retained} clip"
            f"{'s' * (retained != 1)} retained as new cases, {revised} case"
            f"{'s' * (revised != 1)} revised"
        )
    assert after["retain"] == 1 and after["revise"] == 2


@pytest.mark.parametrize("names", [("-k", "--k"), ("--jobs", "--workers")])
def test_every_command_taking_one_spelling_takes_the_other(names: tuple[str, ...]) -> None:
    """The same idea under one set of names in every command: a command that takes one of
    ``names`` takes each, for the same setting."""
    for command, parser in _parsers().items():
        given = [n for n in names if n in parser._option_string_actions]
        if given:
            actions = {id(parser._option_string_actions.get(n)) for n in names}
            assert given == list(names) and len(actions) == 1, (command, given)
