"""Hunt 45u: usability defects of the long-recording commands (issue 14) seen by a user.

1. ``train`` said every clip of an activity "shows no person's torso" when its clips (or the
   pieces ``--split`` cut) were only shorter than one movement can last (``MIN_PERIOD_S``).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from features.poses import save_pose
from features.repetitions import MIN_PERIOD_S
from tests.badinput import refused
from tests.moves import clip

FPS = 30.0


def _short(name: str) -> float:
    """Seconds of a clip of ``name`` shorter than one movement can last: 9 frames at 30 fps."""
    seconds = 9 / FPS
    assert seconds < MIN_PERIOD_S
    return seconds


def _nobody(seconds: float):  # type: ignore[no-untyped-def]
    """A squat clip of ``seconds`` whose every joint is missing (nobody in view)."""
    seq = clip("squat", seconds, FPS)
    return dataclasses.replace(seq, positions=np.full_like(seq.positions, np.nan))


@pytest.mark.parametrize("split", ["clips", "repetitions", "windows"])
def test_train_says_an_activity_whose_clips_are_too_short_is_short_not_unseen(
    split: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two squat clips of 2 s and two jumping-jack clips of 0.3 s, the person in full view in
    every frame: the jacks are no case because they are short (kept whole by ``--split
    repetitions`` and ``windows``: shorter than a repetition or a window). Before, the
    refusal said every clip of them "shows no person's torso"."""
    data = tmp_path / "data"
    for k in range(2):
        save_pose(clip("squat", 2.0, FPS), data / "squat" / f"s{k}.npz")
        save_pose(clip("jumping_jack", _short("jumping_jack"), FPS), data / "jack" / f"j{k}.npz")
    line = refused(
        ["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--split", split],
        tmp_path,
        capsys,
    )
    jacks = f"{data / 'jack' / 'j0.npz'}, {data / 'jack' / 'j1.npz'}"
    assert line == (
        "posecbr train: error: training set: only one activity ('squat') is left to learn "
        "from, a classifier needs two or more: every clip of 'jack' is shorter than one "
        f"movement can be (0.4 s): {jacks}"
    )


def test_train_of_clips_all_too_short_or_unseen_names_both_reasons(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One activity's clip too short, the other's showing nobody: nothing to learn from, for
    the two reasons, both named; the second too short as well: that reason alone (before,
    both said no clip "shows a person's torso for as long as one movement can last")."""
    data = tmp_path / "data"
    save_pose(clip("squat", _short("squat"), FPS), data / "squat" / "short.npz")
    save_pose(_nobody(2.0), data / "jack" / "empty.npz")
    db = str(tmp_path / "cb.sqlite")
    line = refused(["train", str(data), "--db", db], tmp_path, capsys)
    assert line == (
        "posecbr train: error: training set: every clip shows no person's torso (both "
        "shoulders and hips) or is shorter than one movement can be (0.4 s): nothing to "
        "learn from"
    )
    save_pose(clip("jumping_jack", _short("jumping_jack"), FPS), data / "jack" / "empty.npz")
    line = refused(["train", str(data), "--db", db], tmp_path, capsys)
    assert line == (
        "posecbr train: error: training set: every clip is shorter than one movement can be "
        "(0.4 s): nothing to learn from"
    )
