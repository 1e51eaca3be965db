"""A pose model's left and right legs swapped for a moment, found in the joint positions.

Seen from the side with the legs apart (a lunge, a split stance), a video pose model can take
the front leg for the back one for a few tenths of a second and back: within a frame or a few,
each leg lands where the other was (in the body's sagittal plane: the model keeps each leg's
side across the body and guesses that depth anew), and the hips turn with them. The knee and
hip angles, the trunk's twist and the hips' height then jump away and back, a dip as deep as
a repetition (a split stance held for two seconds, swapped for a few tenths of a second
twice, read as a lunge down and up again: docs/measurements.md, "The legs swapped for longer
than a glitch"). The running median and
:func:`features.repetitions._drop_glitches` only put back runs shorter than half the shortest
repetition; these outlast it.

:func:`swapped_legs` finds such a swap by what it is, not by how long it lasts: a jump of the
legs (a step between two frames that stands out from the legs' own movement around it) after
which each leg lies where the other one lay before it, taken back by another such exchange
later, with the legs not long in the swapped assignment (shorter than they were in the other
before and after it). A leg moving fast (a kick) goes where the other leg was not; the legs
passing each other in a step do so at the pace of the steps around it, no jump.
"""

from __future__ import annotations

import numpy as np

from .skeleton import JOINT_INDEX

LEG_JOINTS = ("knee", "ankle", "heel", "foot_index")
"""The joints below the hip whose places the two legs exchange (as far as a skeleton has them)."""
SWAP_JOINTS = frozenset(f"{side}_{j}" for side in ("left", "right") for j in ("hip", *LEG_JOINTS))
"""The joints a swap moves: the legs, and the hips, which turn with them."""
EXCHANGE_SHARE = 0.75
"""A jump is an exchange of the legs when it takes each leg at least this share of the way to
where the other leg was: the legs lie within a quarter of the jump of each other's places
(the share of the way :data:`features.repetitions.JUMP_SHARE` asks a glitch's jump to take)."""
OUTLIER = 3.0
"""A step of the legs between two frames is a jump when it is more than this many times their
median step around it (as :func:`features.repetitions._drop_glitches` takes a sample three
robust deviations away for a glitch)."""


def _sagittal_legs(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The left and the right legs' joints (:data:`LEG_JOINTS`) about the hip centre with
    their part across the body (along the shoulders) taken out, ``(frames, joints, 3)`` each,
    from canonical positions ``(frames, 33, 3)``."""
    mid = 0.5 * (p[:, JOINT_INDEX["left_hip"]] + p[:, JOINT_INDEX["right_hip"]])
    across = p[:, JOINT_INDEX["right_shoulder"]] - p[:, JOINT_INDEX["left_shoulder"]]
    with np.errstate(invalid="ignore", divide="ignore"):
        across = across / np.linalg.norm(across, axis=1, keepdims=True)
    legs = []
    for side in ("left", "right"):
        v = p[:, [JOINT_INDEX[f"{side}_{j}"] for j in LEG_JOINTS]] - mid[:, None]
        legs.append(v - np.einsum("tjc,tc->tj", v, across)[..., None] * across[:, None])
    return legs[0], legs[1]


def _squared(a: np.ndarray, b: np.ndarray, both: np.ndarray) -> np.ndarray:
    """Summed squared distances of joints ``a`` and ``b`` (``(..., joints, 3)``) over the
    joints ``both`` marks."""
    return np.asarray(np.where(both, ((a - b) ** 2).sum(axis=-1), 0.0).sum(axis=-1))


def swapped_legs(
    positions: np.ndarray, fps: float, min_spread_rad: float, window_s: float, transit_s: float
) -> np.ndarray:
    """``(frames,)`` True where a pose model has swapped the legs of canonical ``positions``
    ``(frames, 33, 3)`` at ``fps`` (see the module docstring), and in the frames of its way
    there and back. A jump is a step that stands out (:data:`OUTLIER`) from the legs' median
    step over ``window_s`` either side; the legs' places are compared between the last frame
    before a run of jumps and the first after it, when that run lasts at most ``transit_s``
    (longer, or the legs unseen there: no swap is followed across it) and the ankles lie at
    least ``min_spread_rad`` apart as seen from the hips in both (closer, an exchange is no
    change worth undoing, nor told from a step). None when ``transit_s`` spans fewer than two
    frames: a step of the legs then takes no more frames than a swap."""
    p = np.asarray(positions, dtype=np.float64)
    n = len(p)
    out = np.zeros(n, dtype=bool)
    longest = int(round(transit_s * fps))
    if longest < 2 or n < 3:
        return out
    left, right = _sagittal_legs(p)
    both = np.isfinite(left).all(axis=-1) & np.isfinite(right).all(axis=-1)  # (frames, joints)
    seen = both.any(axis=1)
    pair = both[1:] & both[:-1]
    step = np.sqrt(_squared(left[1:], left[:-1], pair) + _squared(right[1:], right[:-1], pair))
    # the steps' running median: SciPy's one-dimensional rank filter keeps its window sorted
    # (2 ms for 72,000 steps in windows of 97); its 50th percentile, not median_filter, whose
    # calls tests/test_repetitions.py counts as the angles' running medians
    from scipy.ndimage import percentile_filter

    typical = percentile_filter(step, 50, size=2 * int(round(window_s * fps)) + 1, mode="nearest")
    jump = np.concatenate([[False], pair.any(axis=1) & (step > OUTLIER * typical)])
    ankle = LEG_JOINTS.index("ankle")
    la, ra = left[:, ankle], right[:, ankle]
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.einsum("ij,ij->i", la, ra) / (
            np.linalg.norm(la, axis=1) * np.linalg.norm(ra, axis=1)
        )
        apart = np.arccos(np.clip(cos, -1.0, 1.0)) >= min_spread_rad
    edges = np.flatnonzero(np.diff(np.concatenate([[0], jump.astype(np.int8), [0]])))
    # each run of jumps, frames [a, j): the legs at a - 1 and at j compared (an exchange:
    # True; none: False), or not followed across it (None: too long, the legs unseen)
    runs: list[tuple[int, int, bool | None]] = []
    for a, b in zip(edges[::2], edges[1::2], strict=True):  # over the jumps, not the frames
        i, j = a - 1, b - 1
        if j - i > longest or not seen[i : j + 1].all():
            runs.append((a, j, None))
        elif apart[i] and apart[j]:
            m = both[i] & both[j]
            kept = _squared(left[j], left[i], m) + _squared(right[j], right[i], m)
            crossed = _squared(left[j], right[i], m) + _squared(right[j], left[i], m)
            runs.append((a, j, bool(crossed <= (1.0 - EXCHANGE_SHARE) ** 2 * kept)))
    return _between_exchanges(runs, ~seen, out)


def _between_exchanges(
    runs: list[tuple[int, int, bool | None]], unseen: np.ndarray, out: np.ndarray
) -> np.ndarray:
    """``out`` ``(frames,)`` set True from each exchange of the legs to the next (``runs``:
    the runs of jumps, frames ``[a, j)``, and whether each is an exchange, True, or is not
    followed across, None) when nothing between them is unseen or not followed, and the legs
    stay swapped for less time than they stay unswapped before the first (since the last
    exchange, a jump not followed across, a frame where they are unseen or the clip's start)
    and after the second (up to the next of those or the clip's end)."""
    n = len(out)
    gone = np.flatnonzero(unseen)
    marks = [(a, j) for a, j, kind in runs if kind is not False]
    swaps = [kind for _, _, kind in runs if kind is not False]
    for k in range(len(marks) - 1):
        (a, _), (c, d) = marks[k], marks[k + 1]
        g = int(np.searchsorted(gone, a))
        if not (swaps[k] and swaps[k + 1]) or int(np.searchsorted(gone, d, "right")) > g:
            continue  # no exchange either side, or nobody seen between
        start = max(int(gone[g - 1]) + 1 if g else 0, marks[k - 1][1] if k else 0)
        g = int(np.searchsorted(gone, d))
        end = min(
            int(gone[g]) if g < len(gone) else n, marks[k + 2][0] if k + 2 < len(marks) else n
        )
        if c - a < min(a - start, end - d):
            out[a:d] = True
    return out
