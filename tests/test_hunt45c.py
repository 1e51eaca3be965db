"""Hunt 45c: repetitions counted below 10 fps.

The counter's running median (``features.repetitions.MEDIAN_S``, 0.2 s) rounded to one sample
below 7.5 fps: no median at all, so a pose model's glitch of one frame, a posture for 0.13-0.2
s there, stood as a far point (the bundled reverse lunge, one lunge by hand, read at every 5th
frame of its 25 fps: 3, 5, 1 and 1 repetitions at the four phases). Poses a pose model
estimated (they carry its confidences) now take a median of three samples below 10 fps, the
fewest that drop a one-frame glitch (``median_width``); motion capture, which has no such
glitch, keeps the rounded width, and is no longer noted at 5-7.5 fps, where no median drops
its quickest repetitions' far points.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from features.poses import PoseSequence, save_pose
from features.repetitions import count_repetitions, median_width
from posecbr.cli import main
from tests.test_repetitions import GLITCH_RATE_NOTE

FIXTURE = Path(__file__).parent / "fixtures" / "repetition_counts.json"


def test_median_width_below_ten_fps() -> None:
    """Worked out by hand from 0.2 s (odd, at least one) and 10 fps (two frames in the far
    0.2 s of the shortest repetition, 0.4 s): 25 fps 5 samples, 30 fps 7, 10 fps 3 (two
    rounded up to odd) whoever estimated the poses; below 10 fps three samples for a pose
    model's poses, and 0.2 s rounded for the others: 8 fps 1.6 -> 2 -> 3, 6 fps 1.2 -> 1,
    5 fps 1."""
    for estimated in (True, False):
        assert [median_width(r, estimated) for r in (30.0, 25.0, 10.0)] == [7, 5, 3]
    assert [median_width(r, True) for r in (9.99, 8.0, 6.25, 5.0, 2.0)] == [3] * 5
    assert [median_width(r, False) for r in (9.99, 8.0, 6.25, 5.0, 2.0)] == [3, 3, 1, 1, 1]


def _every(seq: PoseSequence, k: int, phase: int) -> PoseSequence:
    """Every ``k``-th frame of ``seq`` from ``phase``: the recording as a camera taking
    ``k`` times fewer frames a second would have given it."""
    conf = None if seq.confidence is None else seq.confidence[phase::k]
    return dataclasses.replace(
        seq, positions=seq.positions[phase::k], confidence=conf, fps=seq.fps / k
    )


def test_a_real_lunge_read_at_5_fps_is_one_repetition(lunge_poses: PoseSequence) -> None:
    """The bundled reverse-lunge video (one slow lunge, by hand) at every 5th frame of its
    25 fps, each of the four first phases: one repetition, as at 25 fps. Before, 3, 5, 1
    and 1: the pose model's one-frame glitches (the legs flickering as she steps back,
    swapped for 0.28 and 0.44 s while she holds the split stance), no median below 7.5
    fps, stood as far points."""
    hand = next(
        c for c in json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
        if c["source"].endswith("fit_reverse_lunge_pexels8233047.mp4")
    )  # fmt: skip
    assert lunge_poses.confidence is not None and lunge_poses.fps == 25.0
    counts = [count_repetitions(_every(lunge_poses, 5, p)).count for p in range(4)]
    assert counts == [hand["count"]] * 4 == [1] * 4


@pytest.mark.parametrize("confidence", [False, True])
def test_the_low_rate_note_where_the_median_reads_three_frames(
    confidence: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A pose file of a figure standing still, at 5, 6, 8 and 10 fps: with a pose model's
    confidences it is noted below 10 fps (the counter's median of three drops a quick
    repetition's far point with a one-frame glitch); without (motion capture) only at 8 fps,
    where 0.2 s still rounds to three frames (before, at 5 and 6 fps as well, though no
    median was read there and no pose model's glitch was in the poses); at 10 fps neither."""
    from tests.bodies import standing, to_sequence

    noted = {}
    for fps in (5, 6, 8, 10):
        seq = to_sequence(*([standing()] * (3 * fps)), fps=float(fps))
        if confidence:
            seq = dataclasses.replace(seq, confidence=np.ones(seq.positions.shape[:2]))
        path = save_pose(seq, tmp_path / f"still_{fps}.npz")
        assert main(["reps", str(path)]) == 0
        err = capsys.readouterr().err
        notes = [line for line in err.splitlines() if line.startswith("note:")]
        noted[fps] = GLITCH_RATE_NOTE.format(path=path, fps=fps) in notes
    assert noted == {5: confidence, 6: confidence, 8: True, 10: False}
