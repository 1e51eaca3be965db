"""Two steps of every clip classified, now done for all columns (all cases) at once: filling
the gaps of a problem's columns over time, and the nearest training clip in summary space
that the unknown judge scores. Each must give what the one-column-at-a-time or
one-query-at-a-time form gives, bit for bit: ``np.interp`` per column (numpy's own
interpolation, the peer) and :func:`nearest_rms` worked out afresh for each query.
"""

from __future__ import annotations

import numpy as np
import pytest

from cbr.novelty import SummaryNeighbours, nearest_rms
from cbr.problem import fill_nan_time


def _per_column(x: np.ndarray, fill: float | np.ndarray) -> np.ndarray:
    """Each column with a gap filled by ``np.interp`` over its valid frames (the edge value
    held beyond them); a column with none takes its ``fill``."""
    out = np.array(x, dtype=np.float64)
    fills = np.broadcast_to(np.asarray(fill, dtype=np.float64), (x.shape[1],))
    t = np.arange(len(x))
    for j in range(x.shape[1]):
        ok = ~np.isnan(x[:, j])
        out[:, j] = np.interp(t, t[ok], x[ok, j]) if ok.any() else fills[j]
    return out


def test_a_gap_is_filled_by_the_line_between_the_frames_around_it() -> None:
    x = np.array([[np.nan, 1.0], [2.0, np.nan], [np.nan, np.nan], [8.0, 7.0], [np.nan, np.nan]])
    got = fill_nan_time(x, 0.0)
    # by hand: column 0 holds 2 before its first value, 2 + (8 - 2) / 2 between, 8 after;
    # column 1 goes 1, 3, 5, 7 and holds 7
    assert got.tolist() == [[2.0, 1.0], [2.0, 3.0], [5.0, 5.0], [8.0, 7.0], [8.0, 7.0]]
    # a column without a value takes its fill; the input is not changed
    empty = np.array([[np.nan, 1.0], [np.nan, 2.0]])
    assert fill_nan_time(empty, np.array([9.0, 0.0])).tolist() == [[9.0, 1.0], [9.0, 2.0]]
    assert np.isnan(empty[:, 0]).all()


@pytest.mark.parametrize("seed", range(4))
def test_filling_all_columns_at_once_equals_np_interp_per_column(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(300):
        frames, cols = int(rng.integers(1, 60)), int(rng.integers(1, 15))
        x = rng.normal(size=(frames, cols)) * 10 ** rng.uniform(-4, 4)
        x[rng.random((frames, cols)) < rng.uniform(0, 1)] = np.nan
        if rng.random() < 0.3:
            x[:, rng.integers(cols)] = np.nan
        fill = rng.normal(size=cols) if rng.random() < 0.5 else float(rng.normal())
        got, want = fill_nan_time(x, fill), _per_column(x, fill)
        assert got.tobytes() == want.tobytes(), (x, got, want)


def test_the_summary_neighbours_answer_each_query_as_a_fresh_search_does() -> None:
    """The cases' terms of the distance are worked out once and kept; every query, before
    and after, finds what :func:`nearest_rms` of that query alone finds."""
    rng = np.random.default_rng(7)
    cases = np.clip(rng.normal(size=(300, 20)), -3, 3).astype(np.float16)
    cases[rng.random(cases.shape) < 0.1] = np.nan
    labels = tuple(f"activity {i % 7}" for i in range(300))
    centre, scale = rng.normal(size=20), rng.uniform(0.5, 2.0, size=20)
    neighbours = SummaryNeighbours(centre, scale, cases, labels)
    for _ in range(50):
        s = rng.normal(size=20) * scale + centre
        s[rng.random(20) < 0.2] = np.nan
        d, at = nearest_rms(neighbours.standardise(s)[None, :], cases)
        assert neighbours.nearest(s) == (float(d[0]), labels[int(at[0])])
    # a summary of other columns is near nothing
    assert neighbours.nearest(np.zeros(19)) == (float("inf"), "")
