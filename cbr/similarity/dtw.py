"""Dynamic time warping with a Sakoe–Chiba band and an exact lower-bound cascade.

Distances are tslearn's ``dtw`` (square root of the summed squared Euclidean frame costs
along the best warping path, band ``|i - j| <= radius``) for equal-length multivariate
sequences ``(frames, channels)``.

k-nearest search (the UCR-suite recipe, Rakthanmanon et al. 2012) returns exactly the brute
force neighbours (ties -> lower case index):

1. for every case: LB_Kim (first and last frames must be matched: cost(q0, c0) +
   cost(q_end, c_end)) and a segment-averaged LB_Keogh (a few frames per segment, 4x cheaper);
2. candidates in increasing order of that bound; stop when it exceeds the k-th best;
3. LB_Keogh both ways: each query frame i is matched to some case frame in [i-r, i+r], so
   its cost is at least its squared distance to the case's envelope (and vice versa);
4. early-abandoning DTW: stop a row-by-row DTW once the row minimum plus the LB_Keogh of the
   remaining rows exceeds the k-th best.

Per-case envelopes (upper/lower over the band) are the cached representation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np
from scipy.ndimage import maximum_filter1d, minimum_filter1d

from features.errors import ConfigError

from .base import SimilarityMeasure, register_measure


@numba.njit(cache=True, nogil=True, fastmath=True)
def _frame_cost(a: np.ndarray, i: int, b: np.ndarray, j: int) -> float:
    s = 0.0
    for c in range(a.shape[1]):
        t = a[i, c] - b[j, c]
        s += t * t
    return s


@numba.njit(cache=True, nogil=True, fastmath=True)
def dtw_sq(a: np.ndarray, b: np.ndarray, radius: int, best: float, tail: np.ndarray) -> float:
    """Squared DTW cost of ``a`` ``(n, d)`` vs ``b`` ``(n, d)`` within ``radius``.

    Returns ``inf`` as soon as it is certain to exceed ``best`` (``tail[i]``: a lower bound of
    the cost of rows ``i..n-1``; ``tail[n] == 0``). ``best = inf`` computes the full value.
    """
    n = a.shape[0]
    m = b.shape[0]
    inf = np.inf
    prev = np.full(m + 1, inf)
    curr = np.full(m + 1, inf)
    prev[0] = 0.0
    for i in range(n):
        lo = max(0, i - radius)
        hi = min(m - 1, i + radius)
        curr[:] = inf
        row_min = inf
        for j in range(lo, hi + 1):
            # prev[j] = D[i-1][j-1], prev[j+1] = D[i-1][j], curr[j] = D[i][j-1] (1-based shift)
            best_prev = prev[j]
            if prev[j + 1] < best_prev:
                best_prev = prev[j + 1]
            if curr[j] < best_prev:
                best_prev = curr[j]
            v = _frame_cost(a, i, b, j) + best_prev
            curr[j + 1] = v
            if v < row_min:
                row_min = v
        if row_min + tail[i + 1] > best:
            return inf
        prev, curr = curr, prev
        if i == 0:
            prev[0] = inf
    return float(prev[m])


@numba.njit(cache=True, nogil=True, fastmath=True)
def _lb_keogh_rows(q: np.ndarray, upper: np.ndarray, lower: np.ndarray, out: np.ndarray) -> float:
    """LB_Keogh of ``q`` against one envelope, per row into ``out`` ``(L,)``; the total."""
    total = 0.0
    for i in range(q.shape[0]):
        s = 0.0
        for c in range(q.shape[1]):  # branch-free so the channel loop vectorises
            x = q[i, c]
            t = max(x - upper[i, c], 0.0) + max(lower[i, c] - x, 0.0)
            s += t * t
        out[i] = s
        total += s
    return total


@numba.njit(cache=True, nogil=True, fastmath=True)
def _lb_paa(qm: np.ndarray, seg_len: np.ndarray, seg_up: np.ndarray, seg_lo: np.ndarray) -> float:
    """LB_Keogh on segments: ``sum_s |s| * dist(mean of q over s, [min lower, max upper])^2``.

    A lower bound of LB_Keogh: widening each row's interval to the segment's only shrinks the
    distance, and the squared distance to an interval is convex (Jensen)."""
    total = 0.0
    for g in range(qm.shape[0]):
        s = 0.0
        for c in range(qm.shape[1]):
            x = qm[g, c]
            t = max(x - seg_up[g, c], 0.0) + max(seg_lo[g, c] - x, 0.0)
            s += t * t
        total += seg_len[g] * s
    return total


@numba.njit(cache=True, nogil=True, fastmath=True)
def knn_dtw(
    q: np.ndarray,
    q_upper: np.ndarray,
    q_lower: np.ndarray,
    cases: np.ndarray,
    upper: np.ndarray,
    lower: np.ndarray,
    radius: int,
    k: int,
    seg_len: np.ndarray,
    seg_up: np.ndarray,
    seg_lo: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Exact k nearest of ``q`` ``(L, d)`` among ``cases`` ``(n, L, d)``.

    ``seg_len`` ``(S,)`` frames per segment; ``seg_up``/``seg_lo`` ``(n, S, d)``: the cases'
    envelopes over each segment (see :func:`segment_envelopes`). Returns (indices ``(k,)``,
    squared costs ``(k,)``, number of full DTW computations).
    """
    n = cases.shape[0]
    L = q.shape[0]
    d = q.shape[1]
    n_seg = seg_len.shape[0]
    qm = np.zeros((n_seg, d))  # the query's segment means
    start = 0
    for g in range(n_seg):
        for i in range(start, start + seg_len[g]):
            for c in range(d):
                qm[g, c] += q[i, c]
        for c in range(d):
            qm[g, c] /= seg_len[g]
        start += seg_len[g]
    # stage 1 for every case (cheap): LB_Kim and the segment bound
    lb = np.empty(n)
    for c in range(n):
        kim = _frame_cost(q, 0, cases[c], 0)
        if L > 1:
            kim += _frame_cost(q, L - 1, cases[c], L - 1)
        paa = _lb_paa(qm, seg_len, seg_up[c], seg_lo[c])
        lb[c] = kim if kim > paa else paa
    order = np.argsort(lb, kind="mergesort")
    best_d = np.full(k, np.inf)
    best_i = np.full(k, n, dtype=np.int64)  # n = "no case yet" (larger than every index)
    tail = np.zeros(L + 1)
    rows = np.empty(L)
    scratch = np.empty(L)
    computed = 0
    slack = 1e-6  # rounding (float32 cases): never prune on a bound merely equal to the best
    for t in range(n):
        c = order[t]
        limit = best_d[k - 1] * (1.0 + slack) + 1e-300
        if lb[c] > limit:
            break  # sorted: no later candidate can beat the k-th best
        # stage 2: full LB_Keogh both ways, only for the survivors
        if _lb_keogh_rows(q, upper[c], lower[c], rows) > limit:
            continue
        if best_d[k - 1] < np.inf:
            if _lb_keogh_rows(cases[c], q_upper, q_lower, scratch) > limit:
                continue
        acc = 0.0
        for i in range(L - 1, -1, -1):
            tail[i + 1] = acc * (1.0 - slack)
            acc += rows[i]
        # stage 3: early-abandoning DTW (row minimum + LB_Keogh of the remaining rows)
        dist = dtw_sq(q, cases[c], radius, limit, tail)
        computed += 1
        if dist < best_d[k - 1] or (dist == best_d[k - 1] and c < best_i[k - 1]):
            pos = k - 1
            while pos > 0 and (
                dist < best_d[pos - 1] or (dist == best_d[pos - 1] and c < best_i[pos - 1])
            ):
                best_d[pos] = best_d[pos - 1]
                best_i[pos] = best_i[pos - 1]
                pos -= 1
            best_d[pos] = dist
            best_i[pos] = c
    return best_i, best_d, computed


def segment_envelopes(
    upper: np.ndarray, lower: np.ndarray, segment: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frames per segment ``(S,)`` and the max of ``upper`` / min of ``lower`` over each
    segment of ``segment`` frames, ``(n, S, d)`` each (the last segment may be shorter)."""
    n, L, d = upper.shape
    full = L // segment
    seg_len = np.array([segment] * full + ([L - full * segment] if L % segment else []))
    cut = full * segment
    # whole segments by a reshape (fast, contiguous); a shorter last segment separately
    parts_up = [upper[:, :cut].reshape(n, full, segment, d).max(axis=2)]
    parts_lo = [lower[:, :cut].reshape(n, full, segment, d).min(axis=2)]
    if cut < L:
        parts_up.append(upper[:, cut:].max(axis=1, keepdims=True))
        parts_lo.append(lower[:, cut:].min(axis=1, keepdims=True))
    seg_up = np.concatenate(parts_up, axis=1) if len(parts_up) > 1 else parts_up[0]
    seg_lo = np.concatenate(parts_lo, axis=1) if len(parts_lo) > 1 else parts_lo[0]
    return seg_len.astype(np.int64), np.ascontiguousarray(seg_up), np.ascontiguousarray(seg_lo)


@numba.njit(cache=True, nogil=True, fastmath=True)
def dtw_all(q: np.ndarray, cases: np.ndarray, radius: int) -> np.ndarray:
    """Squared DTW cost from ``q`` ``(L, d)`` to every case ``(n, L, d)`` (brute force)."""
    n = cases.shape[0]
    out = np.empty(n)
    tail = np.zeros(q.shape[0] + 1)
    for c in range(n):
        out[c] = dtw_sq(q, cases[c], radius, np.inf, tail)
    return out


def envelope(seqs: np.ndarray, radius: int) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower envelopes over ``[i-radius, i+radius]`` of ``(n, L, d)`` sequences."""
    size = 2 * radius + 1
    up = maximum_filter1d(seqs, size=size, axis=1, mode="nearest")
    lo = minimum_filter1d(seqs, size=size, axis=1, mode="nearest")
    return up, lo


@dataclass(frozen=True)
class _DTWIndex:
    cases: np.ndarray  # (n, L, d)
    upper: np.ndarray
    lower: np.ndarray
    radius: int
    seg_len: np.ndarray  # (S,)
    seg_up: np.ndarray  # (n, S, d)
    seg_lo: np.ndarray


@register_measure("dtw")
@dataclass(frozen=True)
class DTW(SimilarityMeasure):
    """DTW on fluent/angle sequences ``(frames, channels)`` with a Sakoe–Chiba band.

    ``radius``: band half-width in frames; when None, ``band`` x sequence length (rounded,
    at least 1). ``band=1.0`` is unconstrained DTW. ``prune``: use the lower-bound cascade
    (exact either way; off = brute force). ``segment``: frames per segment of the first,
    cheapest bound (segment-averaged LB_Keogh).
    """

    compares_sequences: ClassVar[bool] = True

    radius: int | None = None
    band: float = 0.1
    prune: bool = True
    segment: int = 4

    def __post_init__(self) -> None:
        if self.radius is not None and int(self.radius) < 0:
            raise ConfigError(f"radius must be >= 0, got {self.radius!r}", "similarity dtw")
        if not 0.0 <= float(self.band) <= 1.0:
            raise ConfigError(f"band must be in [0, 1], got {self.band!r}", "similarity dtw")

    def radius_for(self, length: int) -> int:
        if self.radius is not None:
            return int(self.radius)
        return max(1, int(math.floor(self.band * length + 0.5)))

    def cache_kind(self, problem_shape: tuple[int, ...]) -> str | None:
        return f"dtw_envelope:radius={self.radius_for(problem_shape[0])}"

    def represent(self, problems: np.ndarray) -> np.ndarray:
        """``(n, L, d)`` -> ``(n, 3, L, d)``: the sequence, its upper and lower envelope."""
        p = _as_sequences(problems)
        up, lo = envelope(p, self.radius_for(p.shape[1]))
        return np.stack([p, up, lo], axis=1)

    def build_index(self, reps: np.ndarray) -> Any:
        reps = _float(reps)  # float32 stays float32 (large case bases), costs sum in float64
        upper = np.ascontiguousarray(reps[:, 1])
        lower = np.ascontiguousarray(reps[:, 2])
        seg = segment_envelopes(upper, lower, max(1, int(self.segment)))
        return _DTWIndex(
            np.ascontiguousarray(reps[:, 0]),
            upper,
            lower,
            self.radius_for(reps.shape[2]),
            *seg,
        )

    def index_for(self, problems: np.ndarray, chunk: int = 5000) -> Any:
        """The search index straight from problems ``(n, L, d)`` (envelopes computed in
        chunks, no stacked copy): for large case bases that are not cached in a store."""
        cases = np.ascontiguousarray(_as_sequences(problems))
        radius = self.radius_for(cases.shape[1])
        upper = np.empty_like(cases)
        lower = np.empty_like(cases)
        for a in range(0, len(cases), chunk):
            upper[a : a + chunk], lower[a : a + chunk] = envelope(cases[a : a + chunk], radius)
        seg = segment_envelopes(upper, lower, max(1, int(self.segment)))
        return _DTWIndex(cases, upper, lower, radius, *seg)

    def _check(self, query_rep: np.ndarray, index: _DTWIndex) -> np.ndarray:
        q = np.ascontiguousarray(query_rep[0], dtype=np.float64)
        if q.shape != index.cases.shape[1:]:
            raise ConfigError(
                f"query sequence shape {q.shape} differs from the cases' {index.cases.shape[1:]}",
                "similarity dtw",
            )
        return q

    def distances(self, query_rep: np.ndarray, index: Any) -> np.ndarray:
        q = self._check(query_rep, index)
        return np.sqrt(dtw_all(q, index.cases, index.radius))

    def nearest(self, query_rep: np.ndarray, index: Any, k: int) -> tuple[np.ndarray, np.ndarray]:
        q = self._check(query_rep, index)
        n = len(index.cases)
        k = min(int(k), n)
        if k <= 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0)
        if not self.prune:
            return super().nearest(query_rep, index, k)
        qr = np.asarray(query_rep, dtype=np.float64)
        idx, sq, _ = knn_dtw(
            q,
            np.ascontiguousarray(qr[1]),
            np.ascontiguousarray(qr[2]),
            index.cases,
            index.upper,
            index.lower,
            index.radius,
            k,
            index.seg_len,
            index.seg_up,
            index.seg_lo,
        )
        return idx, np.sqrt(sq)


def _float(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a)
    return a if a.dtype == np.float32 else a.astype(np.float64)


def _as_sequences(problems: np.ndarray) -> np.ndarray:
    p = _float(problems)
    if p.ndim == 2:  # (n, L): univariate sequences
        p = p[:, :, None]
    if p.ndim != 3:
        raise ConfigError(
            f"dtw compares sequences (n, frames, channels), got problems of shape {p.shape}",
            "similarity dtw",
        )
    return np.ascontiguousarray(p)
