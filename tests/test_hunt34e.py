"""A physical-therapy clinic's engineer new to posecbr (hunt 34e): UI-PRMD correct and
incorrect repetitions, the exercise videos cut into repetitions, and what each command's
output tells a therapist."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from features.poses import load_pose, save_pose
from posecbr.cli import main
from tests.badinput import small_case_base


def test_classify_notes_clips_labelled_with_an_activity_the_case_base_lacks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip whose label the case base holds no case of (a new exercise, or a video
    labelled by its folder's name, as `extract videos/` labels `edge/`) is counted wrong
    whatever the answer: before, the summary said "accuracy: 0.000" and "[wrong: edge]" with
    nothing to tell the user that no answer could have been right."""
    db = small_case_base(tmp_path)
    capsys.readouterr()
    train = tmp_path / "train"
    known = sorted(p.name for p in train.iterdir())
    clip = sorted((train / known[0]).glob("*.npz"))[0]
    seq = load_pose(clip)
    odd = save_pose(seq.with_metadata(label="edge"), tmp_path / "odd.npz")
    same = save_pose(seq.with_metadata(label=known[0]), tmp_path / "same.npz")
    assert main(["classify", str(odd), str(same), "--db", str(db), "-q"]) == 0
    out, err = capsys.readouterr()
    assert "accuracy: 0.500 (1/2 labelled clips)" in out
    notes = [line for line in err.splitlines() if "has no case of" in line]
    assert notes == [
        "note: case base 'default' has no case of 'edge' (1 clip): that clip cannot be "
        f"answered right and counts as wrong (its activities: {', '.join(known)})"
    ], err
    # clips of the case base's own activities alone: no note
    assert main(["classify", str(same), "--db", str(db), "-q"]) == 0
    assert "has no case of" not in capsys.readouterr().err
    # --json keeps standard output for the document
    assert main(["classify", str(odd), "--db", str(db), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["summary"]["accuracy"] == 0.0
    assert "has no case of 'edge'" in err
