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

The search watches its own pruning: once, past a probe, most candidates need a full DTW
anyway (unstructured data, where no bound is tight), it stops bounding and computes the
candidates left (those whose stage-1 bound is under the k-th best so far) with
early-abandoning DTW on ``jobs`` threads (the kernels release the GIL). The brute force
(``distances``) uses the threads too. Every path computes a cost with the same kernel
(:func:`dtw_sq`), so they agree to the bit.

Per-case envelopes (upper/lower over the band) are the cached representation.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np

from features.errors import ConfigError, InputError

from .base import SimilarityMeasure, check_whole, register_measure


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
    prev = np.full(m + 2, inf)
    curr = np.full(m + 2, inf)
    prev[0] = 0.0
    for i in range(n):
        lo = max(0, i - radius)
        hi = min(m - 1, i + radius)
        # only the band is written: its left neighbour must read as "no path" (the cell right
        # of the band is reset after the row, for the next row's diagonal read)
        curr[lo] = inf
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
        curr[hi + 2] = inf
        if row_min + tail[i + 1] > best:
            return inf
        prev, curr = curr, prev
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
def _segment_means(q: np.ndarray, seg_len: np.ndarray) -> np.ndarray:
    """The query's mean frame over each segment, ``(S, d)``."""
    qm = np.zeros((seg_len.shape[0], q.shape[1]))
    start = 0
    for g in range(seg_len.shape[0]):
        for i in range(start, start + seg_len[g]):
            for c in range(q.shape[1]):
                qm[g, c] += q[i, c]
        for c in range(q.shape[1]):
            qm[g, c] /= seg_len[g]
        start += seg_len[g]
    return qm


@numba.njit(cache=True, nogil=True, fastmath=True)
def _first_bounds(
    q: np.ndarray,
    qm: np.ndarray,
    cases: np.ndarray,
    seg_len: np.ndarray,
    seg_up: np.ndarray,
    seg_lo: np.ndarray,
    lo: int,
    hi: int,
    out: np.ndarray,
) -> None:
    """Stage 1 for cases ``lo..hi-1`` into ``out``: max(LB_Kim, segment LB_Keogh)."""
    L = q.shape[0]
    for c in range(lo, hi):
        kim = _frame_cost(q, 0, cases[c], 0)
        if L > 1:
            kim += _frame_cost(q, L - 1, cases[c], L - 1)
        paa = _lb_paa(qm, seg_len, seg_up[c], seg_lo[c])
        out[c] = kim if kim > paa else paa


@numba.njit(cache=True, nogil=True, inline="always")
def _keep_best(best_i: np.ndarray, best_d: np.ndarray, c: int, dist: float) -> None:
    """Insert case ``c`` into the sorted k best (equal costs: the lower index first)."""
    k = best_d.shape[0]
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


SLACK = 1e-6  # rounding (float32 cases): never prune on a bound merely equal to the best
DONE, EXHAUSTED, FALLBACK = 0, 1, 2  # how a cascade ended


@numba.njit(cache=True, nogil=True, fastmath=True)
def _cascade(
    q: np.ndarray,
    q_upper: np.ndarray,
    q_lower: np.ndarray,
    cases: np.ndarray,
    upper: np.ndarray,
    lower: np.ndarray,
    radius: int,
    order: np.ndarray,
    lb: np.ndarray,
    best_i: np.ndarray,
    best_d: np.ndarray,
    probe: int,
    max_full: float,
) -> tuple[int, int, int]:
    """Stages 2-3 over the candidates ``order`` (increasing stage-1 bound ``lb``), updating
    the k best in place. Returns (candidates examined, full DTWs, DONE | EXHAUSTED |
    FALLBACK): DONE when a bound exceeds the k-th best (no later candidate can beat it);
    FALLBACK when, after ``probe`` candidates, more than ``max_full`` of the last 32 needed a
    full DTW (the bounds stopped pruning: the caller scans the rest without them)."""
    k = best_d.shape[0]
    L = q.shape[0]
    tail = np.zeros(L + 1)
    rows = np.empty(L)
    scratch = np.empty(L)
    recent = np.zeros(32, dtype=np.int64)  # 1 where the candidate needed a full DTW
    recent_full = 0
    computed = 0
    for t in range(order.shape[0]):
        if t >= probe and recent_full > max_full * 32:
            return t, computed, FALLBACK
        c = order[t]
        limit = best_d[k - 1] * (1.0 + SLACK) + 1e-300
        if lb[c] > limit:
            return t, computed, DONE
        full = 0
        # stage 2: full LB_Keogh both ways, only for the survivors
        if _lb_keogh_rows(q, upper[c], lower[c], rows) <= limit and (
            best_d[k - 1] == np.inf or _lb_keogh_rows(cases[c], q_upper, q_lower, scratch) <= limit
        ):
            acc = 0.0
            for i in range(L - 1, -1, -1):
                tail[i + 1] = acc * (1.0 - SLACK)
                acc += rows[i]
            # stage 3: early-abandoning DTW (row minimum + LB_Keogh of the remaining rows)
            dist = dtw_sq(q, cases[c], radius, limit, tail)
            computed += 1
            full = 1
            _keep_best(best_i, best_d, c, dist)
        recent_full += full - recent[t % 32]
        recent[t % 32] = full
    return order.shape[0], computed, EXHAUSTED


@numba.njit(cache=True, nogil=True, fastmath=True)
def _dtw_rows(
    q: np.ndarray, cases: np.ndarray, idx: np.ndarray, radius: int, limit: float, out: np.ndarray
) -> None:
    """Squared DTW cost of ``q`` to the cases ``idx`` into ``out`` (``inf`` once certainly
    above ``limit``; ``limit = inf`` computes every cost in full)."""
    tail = np.zeros(q.shape[0] + 1)
    for t in range(idx.shape[0]):
        out[t] = dtw_sq(q, cases[idx[t]], radius, limit, tail)


@numba.njit(cache=True, nogil=True, fastmath=True)
def _dtw_range(
    q: np.ndarray, cases: np.ndarray, lo: int, hi: int, radius: int, out: np.ndarray
) -> None:
    """Squared DTW cost of ``q`` to cases ``lo..hi-1`` into ``out[lo:hi]`` (brute force)."""
    tail = np.zeros(q.shape[0] + 1)
    for c in range(lo, hi):
        out[c] = dtw_sq(q, cases[c], radius, np.inf, tail)


_POOL: ThreadPoolExecutor | None = None


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=max(2, os.cpu_count() or 1))
    return _POOL


def _split(n: int, jobs: int, min_part: int) -> list[tuple[int, int]]:
    """Ranges splitting ``n`` items into at most ``jobs`` parts of at least ``min_part``."""
    parts = max(1, min(jobs, n // max(1, min_part)))
    cuts = np.linspace(0, n, parts + 1).astype(int)
    return [(int(a), int(b)) for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a]


def _in_threads(fn: Any, ranges: list[tuple[int, int]]) -> None:
    """``fn(lo, hi)`` for each range, in threads when there are several (the kernels release
    the GIL)."""
    if len(ranges) == 1:
        fn(*ranges[0])
        return
    for f in [_pool().submit(fn, a, b) for a, b in ranges]:
        f.result()


def dtw_all(q: np.ndarray, cases: np.ndarray, radius: int, jobs: int = 1) -> np.ndarray:
    """Squared DTW cost from ``q`` ``(L, d)`` to every case ``(n, L, d)`` (brute force), on
    ``jobs`` threads."""
    out = np.empty(len(cases))
    _in_threads(lambda a, b: _dtw_range(q, cases, a, b, radius, out), _split(len(cases), jobs, 64))
    return out


def _limit(best_d: np.ndarray) -> float:
    """The k-th best squared cost, widened by the rounding allowance."""
    return float(best_d[-1] * (1.0 + SLACK) + 1e-300)


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
    jobs: int = 1,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Exact k nearest of ``q`` ``(L, d)`` among ``cases`` ``(n, L, d)``.

    ``seg_len`` ``(S,)`` frames per segment; ``seg_up``/``seg_lo`` ``(n, S, d)``: the cases'
    envelopes over each segment (see :func:`segment_envelopes`). Returns (indices ``(k,)``,
    squared costs ``(k,)``, number of full DTW computations).

    Stage 1 for every case (on ``jobs`` threads for large case bases), then the cascade over
    the best-bounded candidates first; when the bounds stop pruning, the candidates left
    (those whose stage-1 bound is under the k-th best so far) get early-abandoning DTW on
    ``jobs`` threads, without further bounds.
    """
    n = len(cases)
    lb = np.empty(n)
    qm = _segment_means(q, seg_len)
    _in_threads(
        lambda a, b: _first_bounds(q, qm, cases, seg_len, seg_up, seg_lo, a, b, lb),
        _split(n, jobs, 20000),
    )
    best_i = np.full(k, n, dtype=np.int64)  # n = "no case yet" (larger than every index)
    best_d = np.full(k, np.inf)
    # the most promising candidates sorted (a partition, not a sort of every bound); the
    # others only if the cascade gets through all of those
    first = min(n, max(1024, 32 * k))
    order = np.argpartition(lb, first - 1)[:first] if first < n else np.arange(n)
    order = order[np.argsort(lb[order], kind="stable")]
    later = np.ones(n, dtype=bool)
    later[order] = False
    max_full = 0.5 if jobs > 1 else 0.85
    pos, computed, status = _cascade(
        q, q_upper, q_lower, cases, upper, lower, radius, order, lb, best_i, best_d,
        max(64, 4 * k, min(n // 8, 1024)), max_full,
    )  # fmt: skip
    if status == EXHAUSTED and later.any():
        rest = np.flatnonzero(later & (lb <= _limit(best_d)))
        order = rest[np.argsort(lb[rest], kind="stable")]
        later[:] = False
        pos, more, status = _cascade(
            q, q_upper, q_lower, cases, upper, lower, radius, order, lb, best_i, best_d,
            0, max_full,
        )  # fmt: skip
        computed += more
    if status != FALLBACK:
        return best_i, best_d, computed
    # the bounds stopped pruning: every candidate left whose first bound is under the k-th best
    later[order[pos:]] = True
    limit = _limit(best_d)
    left = np.flatnonzero(later & (lb <= limit))
    costs = np.empty(len(left))
    _in_threads(
        lambda a, b: _dtw_rows(q, cases, left[a:b], radius, limit, costs[a:b]),
        _split(len(left), jobs, 64),
    )
    both_i = np.concatenate([best_i, left])
    both_d = np.concatenate([best_d, costs])
    pick = np.lexsort((both_i, both_d))[:k]
    return both_i[pick], both_d[pick], computed + len(left)


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


def envelope(seqs: np.ndarray, radius: int) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower envelopes over ``[i-radius, i+radius]`` of ``(n, L, d)`` sequences."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d  # a third of a second: on use

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
@dataclass(frozen=True, repr=False)  # SimilarityMeasure's repr: one line
class DTW(SimilarityMeasure):
    """DTW on fluent/angle sequences ``(frames, channels)`` with a Sakoe–Chiba band.

    ``radius``: band half-width in frames; when None, ``band`` x sequence length (rounded,
    at least 1). ``band=1.0`` is unconstrained DTW. ``prune``: use the lower-bound cascade
    (exact either way; off = brute force). ``segment``: frames per segment of the first,
    cheapest bound (segment-averaged LB_Keogh). ``jobs``: threads for the full scans (brute
    force, and the candidates left once the bounds stop pruning); 0: one per core.
    """

    compares_sequences: ClassVar[bool] = True

    radius: int | None = None
    band: float = 0.1
    prune: bool = True
    segment: int = 4
    jobs: int = 0

    def __post_init__(self) -> None:
        check_whole("dtw", radius=self.radius, segment=self.segment, jobs=self.jobs)
        if self.radius is not None and int(self.radius) < 0:
            raise ConfigError(f"radius must be >= 0, got {self.radius!r}", "similarity dtw")
        if int(self.jobs) < 0:
            raise ConfigError(f"jobs must be >= 0, got {self.jobs!r}", "similarity dtw")
        if not 0.0 <= float(self.band) <= 1.0:
            raise ConfigError(f"band must be in [0, 1], got {self.band!r}", "similarity dtw")

    def threads(self) -> int:
        """Threads for a full scan (``jobs``, or one per core available to this process)."""
        if self.jobs > 0:
            return int(self.jobs)
        return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1

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
        _check_finite(reps[:, 0], "case rows")
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
        return self.index_from(cases, upper, lower)

    def index_from(self, cases: np.ndarray, upper: np.ndarray, lower: np.ndarray) -> Any:
        """The search index from sequences and their envelopes, each ``(n, L, d)``: float32
        or float64 C-contiguous arrays (read-only memory-mapped case matrices included) are
        used in place; only the segment envelopes ``(n, L / segment, d)`` are new."""
        seqs, up, lo = (np.ascontiguousarray(_float(a)) for a in (cases, upper, lower))
        if not seqs.shape == up.shape == lo.shape or seqs.ndim != 3:
            raise ConfigError(
                f"sequences and envelopes must share one shape (n, frames, channels), got "
                f"{seqs.shape}, {up.shape} and {lo.shape}",
                "similarity dtw",
            )
        _check_finite(seqs, "case rows")
        seg = segment_envelopes(up, lo, max(1, int(self.segment)))
        return _DTWIndex(seqs, up, lo, self.radius_for(seqs.shape[1]), *seg)

    def _check(self, query_rep: np.ndarray, index: _DTWIndex) -> np.ndarray:
        q = np.ascontiguousarray(query_rep[0], dtype=np.float64)
        if q.shape != index.cases.shape[1:]:
            raise ConfigError(
                f"query sequence shape {q.shape} differs from the cases' {index.cases.shape[1:]}",
                "similarity dtw",
            )
        _check_finite(q[None], "query")
        return q

    def distances(self, query_rep: np.ndarray, index: Any) -> np.ndarray:
        q = self._check(query_rep, index)
        out: np.ndarray = np.sqrt(dtw_all(q, index.cases, index.radius, self.threads()))
        return out

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
            self.threads(),
        )
        return idx, np.sqrt(sq)


def _check_finite(seqs: np.ndarray, what: str) -> None:
    """Refuse sequences ``(n, L, d)`` holding NaN or inf (``what``: "case rows" or "query"):
    a NaN cost is never below the k-th best, so such a case would silently never be a
    neighbour, and a NaN query would have no neighbour at all (every cost NaN); problems fill
    their missing values before they are compared. One float64 sum tells cheaply that all is
    well (float32 values cannot overflow it)."""
    if seqs.size == 0 or math.isfinite(float(np.sum(seqs, dtype=np.float64))):
        return
    bad = np.flatnonzero(~np.isfinite(seqs.reshape(len(seqs), -1)).all(axis=1))
    if not len(bad):  # finite values whose sum overflowed
        return
    if what == "query":
        raise InputError("dtw: the query holds NaN or inf: fill missing values before comparing")
    rows = ", ".join(map(str, bad[:5])) + (" ..." if len(bad) > 5 else "")
    raise InputError(f"dtw: {what} {rows} hold NaN or inf: fill missing values before comparing")


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
