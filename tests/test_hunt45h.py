"""Session 45's fresh-eyes hunt over compare, report, convert, casebase, train --append and demo."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from features.poses import save_pose
from posecbr.cli import main
from tests.badinput import ROOT, refused, small_case_base, standing_clip
from tests.test_hunt40j import THREE


@pytest.mark.parametrize(
    ("name", "content"),
    [("results.json", '{"my": "own results"}\n'), ("results.csv", "run,score\na,1\n")],
)
def test_compare_out_keeps_a_results_file_it_did_not_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, content: str
) -> None:
    """``compare --out DIR`` replaced a ``results.json`` or ``results.csv`` of another tool
    (or the user's own) in DIR without a word; a rerun replaces its own results only."""
    out = tmp_path / "out"
    out.mkdir()
    (out / name).write_text(content)
    refused([*THREE, "--out", str(out)], tmp_path, capsys,
            str(out), f"holds {name}, not written by posecbr compare")  # fmt: skip
    assert (out / name).read_text() == content


def test_demo_data_given_as_its_labels_csv_is_told_to_give_the_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``demo --data data/labels.csv`` said "demo data not found (expected labels.csv)" of
    the very labels.csv it had been given."""
    labels = tmp_path / "data" / "labels.csv"
    labels.parent.mkdir()
    labels.write_text("path,label,subject\n")
    refused(["demo", "--data", str(labels), "--out", str(tmp_path / "o")], tmp_path, capsys,
            f"{labels}: is a file: --data takes the folder holding the demo's labels.csv: give"
            f" its folder, {labels.parent}")  # fmt: skip


def test_compare_where_no_method_could_be_scored_exits_1_writing_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Every method failed (here the one case-base configuration: --trim 0.05 keeps one case
    of each of three activities in each fold, fewer than the 5 it votes with) and compare
    exited 0, writing results that measured nothing; train --trim refuses such a case base."""
    out, json_file = tmp_path / "out", tmp_path / "r.json"
    code = main([*THREE, "--trim", "0.05", "--out", str(out), "--json", str(json_file)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    failed = [line for line in err if line.startswith("note: cbr fluents/euclidean failed: ")]
    assert len(failed) == 1 and "trimming kept 3 of 12 cases, fewer than the 5" in failed[0], err
    assert err[-1] == (
        f"posecbr compare: error: {THREE[1]}: no method could be scored: every one failed or"
        " was skipped (the notes say why); no results written"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_python_m_posecbr_exits_with_its_status_after_an_interrupt_escaped_an_eval(
    tmp_path: Path,
) -> None:
    """CPython run with ``-m`` ends itself by SIGINT at exit, whatever status ``sys.exit``
    was given, once a KeyboardInterrupt escaped an ``exec``/``eval`` of a string, even one
    caught: SIGTERM landing while a dataclass was made at import said "terminated (SIGTERM)"
    and exited 130, not 143 (1 run in 14 of ``compare`` sent SIGTERM 3-12 s in). Here the
    interrupt escapes an ``exec`` once the modules are imported (an import's ``exec`` would
    clear the mark), then posecbr's ``__main__`` runs ``thresholds``: exit 0, not SIGINT."""
    (tmp_path / "escaped_then_posecbr.py").write_text(
        "import contextlib, io, runpy, sys\n"
        "from posecbr.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['thresholds'])  # every module it needs imported first\n"
        "try:\n"
        "    exec('raise KeyboardInterrupt')\n"
        "except KeyboardInterrupt:\n"
        "    pass\n"
        "sys.argv = ['posecbr', 'thresholds']\n"
        "runpy.run_module('posecbr', run_name='__main__')\n"
    )
    proc = subprocess.run(
        [sys.executable, "-m", "escaped_then_posecbr"],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, (proc.returncode, proc.stderr)
    assert json.loads(proc.stdout)["window"] == 5  # the table, printed whole (5 frames)


def test_classify_quiet_says_why_a_clip_was_unclassifiable(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``classify --quiet`` of clips none of which could be classified ended "no clip could
    be classified (1 clip, each unclassifiable: see above)" above a summary naming the clip
    alone: the reason, on the clip's own line, is left out by --quiet. The summary's line
    now gives it."""
    db = small_case_base(tmp_path)
    capsys.readouterr()  # train's output
    clip = tmp_path / "one.npz"
    save_pose(standing_clip(1), clip)  # one frame at 30 fps: 0.03 s, below a movement's 0.4 s
    code = main(["classify", str(clip), "--db", str(db), "--quiet"])
    out, err = capsys.readouterr()
    assert code == 1
    assert err.endswith("(1 clip, each unclassifiable: see above)\n")
    assert (
        f"unclassifiable: {clip} (lasts 0.03 s (1 frame), shorter than one movement can be"
        " (0.4 s): nothing to classify)"
    ) in out.splitlines()


def test_append_says_a_new_label_is_a_file_name_only_when_it_is_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train --append`` ended its note on new activities "(a pose file converted alone is
    labelled with its name)" whatever they were: also for a labels CSV's own activity, no
    file's name. The hint is now given for the labels that are their clip's file name."""
    db = small_case_base(tmp_path)
    for name, frames in (("13_31", 20), ("take", 21)):  # not one clip twice: refused
        save_pose(standing_clip(frames), tmp_path / f"{name}.npz")  # 0.7 s at 30 fps
    csv = tmp_path / "more.csv"
    csv.write_text("path,label\n13_31.npz,13_31\ntake.npz,plank\n")
    capsys.readouterr()  # train's output
    assert main(["train", str(csv), "--db", str(db), "--append"]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "added as new" in line]
    assert notes == [
        "note: 2 activities the case base did not hold, added as new: 13_31, plank (13_31: the"
        " name of its file, as a pose file converted alone is labelled)"
    ]


def test_compare_refuses_folds_with_leave_one_subject_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``compare --cv loso --folds 3`` ran leave-one-subject-out (as many folds as subjects)
    and said nothing of the --folds it ignored."""
    argv = ["compare", str(THREE[1]), "--cv", "loso", "--folds", "3", "--json",
            str(tmp_path / "r.json")]  # fmt: skip
    refused(argv, tmp_path, capsys, "posecbr compare: error: --folds: goes with --cv kfold")
