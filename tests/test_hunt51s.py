"""Hunt 51s: repetitions of a movement that goes out to both sides of rest, one side at a time,
with small wobbles about the symmetric posture between them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.body import mirrored
from features.joining import join_repetitions
from features.readers.uiprmd import read_uiprmd_kinect
from features.repetitions import MovementSignals, count_in_signals, count_repetitions

RAISES = 8
FPS = 30.0


@pytest.fixture(scope="module")
def alternating_raises(shared_data: Path):  # type: ignore[no-untyped-def]
    """Real single repetitions of UI-PRMD's standing leg raise (subject s03, Kinect: one leg
    raised and lowered per file), every second one replaced by its mirror image (the same
    raise with the other leg): the raises alternate sides, eight in all, and the count is
    eight by construction (one repetition per side, as a coach counts "4 each side")."""
    folder = shared_data / "ui-prmd" / "data" / "Segmented Movements" / "Kinect" / "Positions"
    reps = [
        read_uiprmd_kinect(folder / f"m06_s03_e{i:02d}_positions.txt.gz").to_canonical()
        for i in range(1, RAISES + 1)
    ]
    return join_repetitions(
        [rep if i % 2 == 0 else mirrored(rep) for i, rep in enumerate(reps)]
    ).seq


def test_leg_raises_alternating_sides_count_one_per_side(alternating_raises) -> None:  # type: ignore[no-untyped-def]
    """Before, the side-against-side line's small wobbles about the symmetric posture between
    two raises (one to each side, a tenth as far as the raises) counted: 18."""
    found = count_repetitions(alternating_raises)
    assert found.count == RAISES
    assert found.alternating
    sides = [r.side for r in found.repetitions]
    # each raise is the mirror image of the one before: the sides take turns
    assert all(a != b for a, b in zip(sides, sides[1:], strict=False))
    assert set(sides) == {"left", "right"}


def _bend(n: int, depth: float) -> np.ndarray:
    """A knee straight (pi) at rest bending by ``depth`` radians and back over ``n`` samples
    (one cosine cycle, deepest at sample ``n // 2``)."""
    return np.pi - 0.5 * depth * (1 - np.cos(2 * np.pi * np.arange(n) / n))


def test_wobbles_between_alternating_raises_do_not_count_a_small_raise_does() -> None:
    """Knees raised in turn (1.2 rad, 1.5 s each), left, right, left, right, left, right;
    between the first two, the second two and the last two, a wobble: the knee of the side
    just raised bends 0.3 rad, then the other knee 0.3 rad (0.4 s each way); the fourth raise
    (right) is a small one, 0.5 rad, straight between two left ones. Six raises: the wobbles,
    a quarter as far as the raises on either side of them, are no repetition; the small raise,
    alone between two of the other side, is one (as a jog's fading steps are). Before, each
    wobble's two bends counted: 12."""
    raise_, wobble, still = 1.2, 0.3, ("-", 0.0, 9)
    plan = [
        ("L", raise_, 45), still, ("R", wobble, 12), ("L", wobble, 12), still,
        ("R", raise_, 45), still, ("L", wobble, 12), ("R", wobble, 12), still,
        ("L", raise_, 45), still, ("R", 0.5, 45), still,
        ("L", raise_, 45), still, ("R", wobble, 12), ("L", wobble, 12), still,
        ("R", raise_, 45),
    ]  # fmt: skip
    left = np.concatenate([_bend(n, d) if s == "L" else np.full(n, np.pi) for s, d, n in plan])
    right = np.concatenate([_bend(n, d) if s == "R" else np.full(n, np.pi) for s, d, n in plan])
    signals = MovementSignals(np.stack([left, right], axis=1), ("left_knee", "right_knee"), FPS, 1)
    found = count_in_signals(signals, len(left), FPS)
    assert found.alternating
    assert found.count == 6
    assert [r.side for r in found.repetitions] == ["left", "right"] * 3
    # each raise's deepest bend: 22 samples into its 45 (the small one's as well)
    starts = np.cumsum([0] + [n for _, _, n in plan])[:-1]
    raised = [int(a) + 22 for a, (_, d, n) in zip(starts, plan, strict=True) if n == 45]
    assert [r.peak_frame for r in found.repetitions] == pytest.approx(raised, abs=1)
