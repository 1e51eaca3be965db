"""NaN-skipping reductions that give NaN, without a warning, where every value is missing.

numpy's ``nanmean``, ``nanstd``, ``nanmin``, ``nanmedian``, ... warn ("Mean of empty slice",
"All-NaN slice encountered") over a slice of NaN only. Silencing them with
``warnings.catch_warnings`` is not thread-safe: it swaps the process's one list of warning
filters on entry and puts its copy back on exit, so two threads inside at once (a fitted model
answering from several threads) let the warning through and can leave the copy of the thread
that entered second behind, ignoring every RuntimeWarning of the caller's program from then
on. :func:`over_seen` calls the reduction on the slices that hold a value only.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


def over_seen(reduce: Callable[..., Any], values: Any, axis: int | None = None) -> np.ndarray:
    """``reduce(values, axis=axis)`` (a numpy NaN-skipping reduction, or one of its partials)
    over the slices along ``axis`` (None: all of ``values``) that hold a number, NaN over the
    others, with no warning: the same numbers as ``reduce`` alone gives, as an array
    (0-dimensional for ``axis=None``)."""
    a = np.asarray(values, dtype=np.float64)
    if axis is None:
        a, axis = a.reshape(-1), 0
    a = np.moveaxis(a, axis, 0)
    seen = ~np.isnan(a).all(axis=0)
    if seen.all() and a.shape[0]:
        return np.asarray(reduce(a, axis=0))
    out = np.full(a.shape[1:], np.nan)
    if seen.any():
        out[seen] = reduce(a[:, seen], axis=0)
    return out
