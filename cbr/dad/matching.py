"""The heaviest chain of an activity's QMPs detected in order over the sliding windows."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def ordered_match(
    met: np.ndarray, weights: Sequence[int] | np.ndarray
) -> tuple[int, list[int | None]]:
    """Heaviest in-order subsequence of steps whose detections fall in non-decreasing windows.

    met: ``(steps, W)`` bool, step i detected in window w; weights: ``(steps,)``. Returns
    (matched weight, the window chosen for each step or None). Dynamic programme: f_i[w] is
    the heaviest chain over steps < i whose last window is <= w; QMPs in the same window may
    chain (several QMPs hold at once).
    """
    n_steps, n_win = met.shape
    f = [np.zeros(n_win, dtype=np.int64)]
    for i in range(n_steps):
        take = f[i] + np.where(met[i], int(weights[i]), 0)
        f.append(np.maximum.accumulate(np.maximum(f[i], take)))
    chosen: list[int | None] = [None] * n_steps
    if n_win == 0:
        return 0, chosen
    limit = n_win - 1
    total = int(f[n_steps][limit])
    target = total
    for i in range(n_steps - 1, -1, -1):
        # Take step i at the latest window <= limit that realises the target, if any.
        ok = np.flatnonzero(met[i, : limit + 1] & (f[i][: limit + 1] + int(weights[i]) == target))
        if len(ok):
            w = int(ok[-1])
            chosen[i] = w
            target -= int(weights[i])
            limit = w
    return total, chosen
