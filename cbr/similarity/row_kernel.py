"""A query's exact Euclidean distances to float32 rows by the one compiled row kernel every search
of :mod:`cbr.similarity.euclidean` computes them with, the k best kept (ties to the lower
index) and the kernel's rounding bounded."""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, fastmath=True, inline="always")
def _row_sq(rows: np.ndarray, i: int, q: np.ndarray) -> float:
    """Distance of row ``i`` to ``q``: the squares of the differences summed in float64 (a
    difference of two float32 values is exact in float64), square-rooted. Within about
    ``D 2^-53`` of the distance between the float32 row and query, on every CPU. Before, the
    identity ``|c|^2 - 2 c.q + |q|^2`` with a float32 dot product: its rounding, some
    ``2^-24 D |c| |q|``, is large against a small distance, and its summation order (how
    wide the CPU's vectors are) decided it: a clip's distance to its own case was 0.0 on an
    AVX2 CPU and 0.0022 on an AVX-512 one."""
    s = 0.0
    for j in range(rows.shape[1]):
        d = np.float64(rows[i, j]) - np.float64(q[j])
        s += d * d
    return math.sqrt(s)


@numba.njit(cache=True, nogil=True, fastmath=True)
def row_distance(rows: np.ndarray, i: int, q: np.ndarray) -> float:
    """:func:`_row_sq` as a function of its own, for callers compiled without fastmath (the
    flags of the code it is inlined into decide its summation order, so its value)."""
    return _row_sq(rows, i, q)


@numba.njit(cache=True, nogil=True, inline="always")
def insert(best_i: np.ndarray, best_d: np.ndarray, i: int, d: float) -> None:
    """Insert (i, d) into the sorted k best; rows arrive in increasing index order, so an equal
    distance never displaces an earlier (lower) index."""
    k = best_d.shape[0]
    if not d < best_d[k - 1]:
        return
    pos = k - 1
    while pos > 0 and d < best_d[pos - 1]:
        best_d[pos] = best_d[pos - 1]
        best_i[pos] = best_i[pos - 1]
        pos -= 1
    best_d[pos] = d
    best_i[pos] = i


@numba.njit(cache=True, nogil=True, inline="always")
def insert_any(best_i: np.ndarray, best_d: np.ndarray, i: int, d: float) -> None:
    """Insert (i, d) into the k best sorted by distance, then index: rows may arrive in any
    order and an equal distance still keeps the lower index."""
    k = best_d.shape[0]
    if d > best_d[k - 1] or (d == best_d[k - 1] and i >= best_i[k - 1]):
        return
    pos = k - 1
    while pos > 0 and (d < best_d[pos - 1] or (d == best_d[pos - 1] and i < best_i[pos - 1])):
        best_d[pos] = best_d[pos - 1]
        best_i[pos] = best_i[pos - 1]
        pos -= 1
    best_d[pos] = d
    best_i[pos] = i


@numba.njit(cache=True, nogil=True, fastmath=True)
def all_distances(rows: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Distances from ``q`` ``(D,)`` float32 to every row of ``rows`` ``(n, D)`` float32."""
    out = np.empty(rows.shape[0])
    for i in range(rows.shape[0]):
        out[i] = _row_sq(rows, i, q)
    return out


@numba.njit(cache=True, nogil=True, fastmath=True)
def measured_distances(rows: np.ndarray, q: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Distances from ``q`` ``(D,)`` to every row of ``rows`` ``(n, D)`` over the columns
    ``keep`` ``(D,)`` marks 1 (the query's measured ones; the others 0), scaled to all ``D``
    columns as scikit-learn's ``nan_euclidean_distances`` scales them: ``sqrt(D / m * sum
    over the m kept columns of (row - q)^2)``, the squares summed in float64 as
    :func:`_row_sq` sums them. Every column is read, in order, the left-out ones weighed 0:
    the loop over a row runs on contiguous memory (6 times as fast as reading the kept
    columns by index, 10,000 rows of 1,200)."""
    out = np.empty(rows.shape[0])
    n_cols = rows.shape[1]
    m = 0.0
    for j in range(n_cols):
        m += keep[j]
    scale = n_cols / m
    for i in range(rows.shape[0]):
        s = 0.0
        for j in range(n_cols):
            d = np.float64(rows[i, j]) - np.float64(q[j])
            s += keep[j] * d * d
        out[i] = math.sqrt(scale * s)
    return out


@numba.njit(cache=True, nogil=True, fastmath=True)
def knn_scan(
    rows: np.ndarray, q: np.ndarray, idx: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """The k nearest among the rows listed in ``idx`` (increasing), or all rows when ``idx``
    is empty: (indices ``(k,)``, distances ``(k,)``)."""
    best_i = np.full(k, rows.shape[0], dtype=np.int64)
    best_d = np.full(k, np.inf)
    if idx.shape[0] == 0:
        for i in range(rows.shape[0]):
            insert(best_i, best_d, i, _row_sq(rows, i, q))
    else:
        for t in range(idx.shape[0]):
            i = idx[t]
            insert(best_i, best_d, i, _row_sq(rows, i, q))
    return best_i, best_d


@numba.njit(cache=True, nogil=True, fastmath=True)
def select_from_products(
    prods: np.ndarray,
    rows: np.ndarray,
    sq: np.ndarray,
    norms: np.ndarray,
    q: np.ndarray,
    q_sq: float,
    err: float,
    k: int,
) -> tuple[np.ndarray, np.ndarray]:
    """The k nearest of one query from its BLAS products ``prods`` ``(n,)`` float32.

    ``err * norms[i]`` bounds how far the product-based squared distance of row i may be from
    the row kernel's; the k-th smallest upper bound is a threshold every true neighbour's lower
    bound is under, and only those rows are re-computed with :func:`_row_sq`."""
    n = prods.shape[0]
    # the float64 rounding of |c|^2 - 2 c.q + |q|^2, and the row kernel's (allowance_of)
    rel = 1e-12 + 2.02 * (rows.shape[1] + 1) * 2.0**-53
    ub_i = np.full(k, -1, dtype=np.int64)
    ub_d = np.full(k, np.inf)
    for i in range(n):
        d2 = sq[i] - 2.0 * np.float64(prods[i]) + q_sq
        d2 += err * norms[i] + rel * (sq[i] + q_sq)
        if d2 < ub_d[k - 1]:
            insert(ub_i, ub_d, i, d2)
    limit = max(ub_d[k - 1], 0.0)
    best_i = np.full(k, n, dtype=np.int64)
    best_d = np.full(k, np.inf)
    for i in range(n):
        d2 = sq[i] - 2.0 * np.float64(prods[i]) + q_sq
        if d2 - err * norms[i] - rel * (sq[i] + q_sq) <= limit:
            insert(best_i, best_d, i, _row_sq(rows, i, q))
    return best_i, best_d


@numba.njit(cache=True, nogil=True)
def allowance_of(dims: int, max_norm: float, q_sq: float) -> float:
    """How far a row kernel's squared distance may be from the true one: its float64 sum of
    ``D`` exact differences squared is within ``gamma_(D+1) d^2`` of it (Higham, ``u =
    2^-53``), and ``d <= |c| + |q|``; plus ``D 2^-1074`` for squares that underflow."""
    u = 2.0**-53
    gamma = (dims + 1) * u / (1.0 - (dims + 1) * u)
    q_norm = math.sqrt(q_sq)
    return 1.01 * gamma * (max_norm + q_norm) ** 2 + dims * 2.0**-1074


@numba.njit(cache=True, nogil=True)
def query32(q: np.ndarray) -> tuple[np.ndarray, float]:
    """The query ``q`` ``(D,)`` (float64 or float32) as the float32 vector ``(D,)`` the row
    kernel multiplies with, and its squared norm summed in float64 in order (the one value
    of ``|q|^2`` every path uses)."""
    q32 = np.empty(q.shape[0], dtype=np.float32)
    q_sq = 0.0
    for j in range(q.shape[0]):
        v = np.float32(q[j])
        q32[j] = v
        q_sq += np.float64(v) * np.float64(v)
    return q32, q_sq
