"""Hunt 52d: movements done on each side in turn, one repetition per side: one side's
excursion that shows two far points while the body stays out (a side lunge's knees shifting
at the bottom), and a wobble cut off by the clip's end after the last repetition."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from features.body import mirrored
from features.joining import join_repetitions
from features.poses import PoseSequence
from features.readers.uiprmd import read_uiprmd_kinect
from features.repetitions import MovementSignals, count_in_signals, count_repetitions

FPS = 30.0
KNEES = ("left_knee", "right_knee")


def _knees(keys: list[tuple[int, float, float]]) -> np.ndarray:
    """Both knees' angles ``(n, 2)`` through the keyframes ``(sample, left bend, right bend)``
    (radians bent from straight, pi), linear between them."""
    at = np.array([k[0] for k in keys])
    n = np.arange(at[-1] + 1)
    bends = [np.interp(n, at, [k[i] for k in keys]) for i in (1, 2)]
    return np.pi - np.stack(bends, axis=1)


def _lunge(t: int, side: int, size: int) -> list[tuple[int, float, float]]:
    """One side lunge of ``size`` samples from ``t``, on the knee ``side`` (0 left, 1 right):
    that knee bends 1.2 rad and the other 0.3 (the body goes down and out to that side);
    halfway both are bent, 1.0 and 0.6 rad (the weight shifts, the hips stay down); then the
    first shape again, and both knees straight. Its far points to that side (the bend of one
    knee against the other: 0.9 rad, 0.4 at the shift) lie at 0.15 and 0.85 of the lunge."""
    out = [(0.15, 1.2, 0.3), (0.5, 1.0, 0.6), (0.85, 1.2, 0.3), (1.0, 0.0, 0.0)]
    keys = []
    for share, own, other in out:
        bend = (own, other) if side == 0 else (other, own)
        keys.append((t + int(round(share * size)), *bend))
    return keys


def test_side_lunges_whose_weight_shifts_at_the_bottom_count_one_each() -> None:
    """Six side lunges, left and right in turn (3 s each, 0.5 s standing between): each
    knee's bend against the other's comes back by more than half at the shift (0.9 rad out,
    0.4 at the shift: two far points to the lunge's side by the line alone), but the body
    stays down, both knees bent 1.0 and 0.6 rad where they went out to 1.2 and 0.3 (the
    posture there holds 90 % of the way out): one repetition per lunge, six. Before, each
    lunge's two far points counted: 12."""
    size, still = 90, 15
    keys = [(0, 0.0, 0.0)]
    for i in range(6):
        t = keys[-1][0] + still
        keys += [(t, 0.0, 0.0), *_lunge(t, i % 2, size)]
    keys.append((keys[-1][0] + still, 0.0, 0.0))
    signals = MovementSignals(_knees(keys), KNEES, FPS, 1)
    found = count_in_signals(signals, len(signals.values), FPS)
    assert found.alternating
    assert found.count == 6
    assert [r.side for r in found.repetitions] == ["left", "right"] * 3


def _bend(n: int, depth: float) -> np.ndarray:
    """A knee straight (pi) at rest bending by ``depth`` radians and back over ``n`` samples
    (one cosine cycle, deepest at sample ``n // 2``)."""
    return np.pi - 0.5 * depth * (1 - np.cos(2 * np.pi * np.arange(n) / n))


def test_a_wobble_cut_off_after_the_last_alternating_repetition_does_not_count() -> None:
    """Knees raised in turn (1.2 rad, 1.5 s each), left, right, left, right, with a wobble
    between each two (the knee just raised bends 0.3 rad, then the other, 0.4 s each way), and
    after the last, standing, the left knee starts to bend and the clip ends as it reaches
    0.45 rad: cut off, three eighths as far as the raises (a far point cut off counts when it
    got three quarters as far as the whole repetitions: it may be one not finished). Four.
    Before, it was measured against the median of every whole far point, wobbles included
    (a quarter as far as the raises), and counted: 5."""
    raise_, wobble, still = 1.2, 0.3, ("-", 0.0, 9)
    plan = [
        ("L", raise_, 45), still, ("R", wobble, 12), ("L", wobble, 12), still,
        ("R", raise_, 45), still, ("L", wobble, 12), ("R", wobble, 12), still,
        ("L", raise_, 45), still, ("R", wobble, 12), ("L", wobble, 12), still,
        ("R", raise_, 45), still, still,
    ]  # fmt: skip
    left = np.concatenate([_bend(n, d) if s == "L" else np.full(n, np.pi) for s, d, n in plan])
    right = np.concatenate([_bend(n, d) if s == "R" else np.full(n, np.pi) for s, d, n in plan])
    left = np.concatenate([left, _bend(30, 0.45)[:16]])  # bending, cut at its deepest
    right = np.concatenate([right, np.full(16, np.pi)])
    signals = MovementSignals(np.stack([left, right], axis=1), KNEES, FPS, 1)
    found = count_in_signals(signals, len(left), FPS)
    assert found.alternating
    assert found.count == 4
    assert [r.side for r in found.repetitions] == ["left", "right"] * 2


def _alternated(shared_data: Path, subject: str, takes: tuple[int, ...]) -> PoseSequence:
    """UI-PRMD Kinect side lunges (m04) of ``subject``, one file one lunge to one side, joined
    with every second one replaced by its mirror image (the same lunge to the other side):
    the lunges alternate sides, and the count is the number of takes by construction."""
    folder = shared_data / "ui-prmd" / "data" / "Segmented Movements" / "Kinect" / "Positions"
    reps = [
        read_uiprmd_kinect(folder / f"m04_{subject}_e{i:02d}_positions.txt.gz").to_canonical()
        for i in takes
    ]
    return join_repetitions([r if k % 2 == 0 else mirrored(r) for k, r in enumerate(reps)]).seq


def test_real_side_lunges_whose_knees_shift_at_the_bottom_count_one_each(
    shared_data: Path,
) -> None:
    """Subject s02's lunges e02 and e09 (mirrored): in each, the side-against-side line goes
    out (1.1 from the symmetric posture), back by half as the knees shift with the hips
    down (0.57 in e02) and out again (1.0): two lunges, one per side. Before, each lunge's
    two far points counted: 4."""
    found = count_repetitions(_alternated(shared_data, "s02", (2, 9)))
    assert found.alternating
    assert found.count == 2
    assert len({r.side for r in found.repetitions}) == 2


def test_real_side_lunges_keep_no_wobble_cut_off_at_either_end(shared_data: Path) -> None:
    """Subject s01's lunges e08, e05 (mirrored), e06, e10 (mirrored): four lunges, each
    reaching 1.36-1.45 from the symmetric posture, with wobbles of the trailing knee about
    it between them (0.17-0.30, not counted); the clip starts and ends in such a wobble, cut
    off (0.32 and 0.26: about a fifth as far as the lunges, where a far point cut off counts
    at three quarters, or half once the line has turned at it). Before, the cut-off ends were
    measured against the median of all whole far points, wobbles included (0.29), and
    counted: 6."""
    found = count_repetitions(_alternated(shared_data, "s01", (8, 5, 6, 10)))
    assert found.alternating
    assert found.count == 4
    sides = [r.side for r in found.repetitions]
    assert all(a != b for a, b in zip(sides, sides[1:], strict=False))
