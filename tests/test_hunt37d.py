"""A posture got into and held while the pose model swaps the legs for a few frames: no
repetition, and ``train --split repetitions`` keeps the clip whole (:mod:`features.repetitions`,
``_drop_glitches``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from features.datasets import Clip
from features.poses import PoseSequence, save_pose
from features.repetitions import MIN_PERIOD_S, count_repetitions, split_repetitions
from posecbr.cli import main
from tests.bodies import squat_clip, to_sequence
from tests.test_hunt36b import _ease, _lunge, _swapped

FPS = 30.0
REST, DOWN, HOLD = 18, 30, 150  # 0.6 s standing, 1.0 s down, 5.0 s held low


def _lunge_held(glitch: int, up: bool = False) -> PoseSequence:
    """Standing 0.6 s, down into a lunge over 1.0 s, held still 5 s (198 frames); with ``up``
    back up over 1.0 s and 0.6 s of standing. The pose model swaps the legs for ``glitch``
    frames at 2.5 s and at 4.0 s (frames 75-79 and 120-124 for 5; 0: never), inside the hold
    (frames 48-197), as it swapped the bundled lunge's; every joint jitters by 2 mm."""
    parts = [np.zeros(REST), _ease(0.0, 1.0, DOWN / FPS), np.ones(HOLD)]
    if up:
        parts += [_ease(1.0, 0.0, DOWN / FPS), np.zeros(REST)]
    frames = [_lunge(d) for d in np.concatenate(parts)]
    for start in (75, 120):
        for f in range(start, start + glitch):
            frames[f] = _swapped(frames[f])
    rng = np.random.default_rng(0)  # 2 mm of tracking jitter: no posture is held exactly
    return to_sequence(*({j: p + rng.normal(0.0, 0.002, 3) for j, p in b.items()} for b in frames),
                       fps=FPS)  # fmt: skip


@pytest.mark.parametrize("glitch", [0, 4, 5])
def test_a_lunge_held_with_the_legs_swapped_a_moment_is_no_repetition(glitch: int) -> None:
    """Down into a lunge once and held to the end: no repetition by construction (the side
    plank's rule: a posture got into and held), whether or not the legs are swapped for 4 or
    5 frames (0.13-0.17 s, under half the shortest repetition, 0.4 s) twice in the hold.
    Before, the swaps read as the movement: 4 frames gave 3 repetitions (0-2.13, 2.13-2.93,
    2.93-4.30 s), 5 frames 2 short ones around the swaps (2.33-2.93 s, 2.93-4.33 s), which
    ``train --split repetitions`` stored as two cases of 18 and 42 frames; now one case, the
    whole clip."""
    seq = _lunge_held(glitch)
    result = count_repetitions(seq)
    assert result.count == 0, [(r.start_frame, r.end_frame) for r in result.repetitions]
    split = split_repetitions([Clip(seq, "lunge", None)])
    assert split.kept_whole == 1 and [c.seq.n_frames for c in split.clips] == [198]


def test_a_held_lunge_that_comes_back_up_is_one_repetition_whatever_the_swaps() -> None:
    """The same hold with the way up (1.0 s) and 0.6 s of standing after: one repetition,
    from where the body leaves standing (frame 18 plus the eased start's first tenth, within
    a few frames) to where it is back (frame 228 less as much), its far point in the hold
    (frames 48-197), with the legs swapped for 4 or 5 frames twice as without (before: 3
    repetitions, 0.80-2.57, 2.57-4.07 and 4.07-7.37 s, cut at the swaps)."""
    for glitch in (0, 4, 5):
        (rep,) = count_repetitions(_lunge_held(glitch, up=True)).repetitions
        assert 18 <= rep.start_frame <= 28 and 218 <= rep.end_frame <= 229, rep
        assert 48 <= rep.peak_frame < 198, rep


def test_glitch_filter_leaves_a_movement_and_drops_a_swap() -> None:
    """Worked out by hand on one angle at 30 fps (glitches of 4-5 samples: the running
    median of 7 drops 3 and fewer, half the shortest repetition is 6): the quickest
    repetition (a cosine of period 0.4 s, 60 degrees) and a quick out-and-back over several
    samples (a hurdle step's knee: 46, 16, 6, 16, 18, 51 degrees from 78) are left as they
    are; a held angle that jumps 100 degrees for 5 samples and back is put back to the hold,
    and so is one of 4 samples; a jump for 6 samples (0.2 s) is left."""
    from features.repetitions import _drop_glitches

    t = np.arange(60) / FPS
    quick = np.radians(30.0) * (1 - np.cos(2 * np.pi * t / MIN_PERIOD_S))[:, None]
    np.testing.assert_array_equal(_drop_glitches(quick, FPS, 4), quick)
    knee = np.radians([78.0] * 10 + [46, 16, 6, 16, 18, 51] + [66.0] * 10)[:, None]
    np.testing.assert_array_equal(_drop_glitches(knee, FPS, 4), knee)
    for n, dropped in ((4, True), (5, True), (6, False)):
        held = np.full((40, 1), 1.0)
        held[20 : 20 + n] += np.radians(100.0)
        out = _drop_glitches(held, FPS, 4)
        expected = np.full((40, 1), 1.0) if dropped else held
        np.testing.assert_array_equal(out, expected)


def test_train_split_repetitions_keeps_the_held_lunge_whole(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train --split repetitions`` of the held lunge with the legs swapped for 5 frames
    twice, beside three squats: the squats cut into 3 cases, the lunge one case, the whole
    clip, as ``reps`` counts it 0 (before: 2 cases, 0.60 and 1.40 s, ``reps`` 2)."""
    data = tmp_path / "data"
    save_pose(_lunge_held(5), data / "lunge" / "held.npz")
    one = squat_clip(0.9, frames=45)
    squats = PoseSequence(
        np.concatenate([one.positions] * 3), one.joint_names, one.fps, source="squats"
    )
    save_pose(squats, data / "squat" / "three.npz")
    capsys.readouterr()
    assert main(["reps", str(data / "lunge" / "held.npz"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["count"] == 0
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(data), "--db", str(db), "--split", "repetitions"]) == 0
    err = capsys.readouterr().err
    assert "cut 1 clip into 3 repetitions; 1 clip without a repetition kept whole" in err
