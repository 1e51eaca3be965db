"""Degenerate but legal data (hunt 25b): what ``reps`` and the calibrated confidence made of
clips and training sets that are legal but lopsided. Each test says what happened before its
fix.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from features.poses import save_pose
from posecbr.cli import main
from tests.bodies import squat_clip

# one squat of tests.bodies: 45 frames at 30 fps, standing at its first and last frame and
# deepest at frame 22 (its depth is 0.5 (1 - cos(2 pi i / 44)), largest at i = 22)
SQUAT_FRAMES, DEEPEST = 45, 22


def _squats_and_rests(tmp_path: Path, *parts: int | str) -> tuple[Path, list[int]]:
    """A pose file of ``parts`` in turn: an int is that many squats, ``"rest N"`` N frames
    of standing still (the squat's first frame held); and the frame of every squat's deepest
    point."""
    squat = squat_clip(1.0)
    pieces, deepest, at = [], [], 0
    for part in parts:
        if isinstance(part, int):
            pieces += [squat.positions] * part
            deepest += [at + i * SQUAT_FRAMES + DEEPEST for i in range(part)]
            at += part * SQUAT_FRAMES
        else:
            n = int(part.split()[1])
            pieces.append(np.repeat(squat.positions[:1], n, axis=0))
            at += n
    seq = replace(squat, positions=np.concatenate(pieces), source="")
    return save_pose(seq, tmp_path / "squats.npz"), deepest


@pytest.mark.parametrize(
    "parts",
    [
        (1, "rest 900"),  # one squat, then 30 s standing: was 0 repetitions
        ("rest 900", 1),  # 30 s standing, then one squat: was 0
        ("rest 600", 2, "rest 600"),  # was 3: far points in both rests, none at a squat
        (3, "rest 1000", 3),  # was 7: one more in the middle of the rest
        (1, "rest 1000", 1),  # was 3: at frame 0, mid-rest and the last frame
    ],
)
def test_reps_counts_the_squats_of_a_clip_that_mostly_stands_still(
    parts: tuple[int | str, ...], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip that stands still for most of its frames: the movement's line was read upside
    down (its 10th and 90th percentiles both lay in the rest, so neither end looked like the
    movement) and far points were found in the rest, or a long rest between repetitions,
    measured about the running mean, stood out as a far point of its own."""
    path, deepest = _squats_and_rests(tmp_path, *parts)
    assert main(["reps", str(path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["count"] == len(deepest)
    peaks = [r["peak_frame"] for r in doc["repetitions"]]
    assert np.abs(np.array(peaks) - np.array(deepest)).max() <= 2, (peaks, deepest)
    for r, peak in zip(doc["repetitions"], deepest, strict=True):
        assert r["start_frame"] < peak < r["end_frame"]
