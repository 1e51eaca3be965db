"""Euclidean distance on (flattened) feature vectors.

On binary QMP vectors the squared distance is the number of mismatched features, so the
nearest cases are the ones with the most matched features.

Every search returns exactly what :meth:`Euclidean.distances` and :func:`smallest_k` give (ties
-> lower case index): one compiled row kernel (:func:`_row_sq`, float32 rows, the squared
differences summed in float64) computes every distance a search returns; the paths differ only
in which rows they hand it, never in how a row's distance is computed. The bounds that choose
the rows (BLAS products, codes) are float32's, with their rounding allowed for.

- **Plain pass**: small case bases stream every row through the kernel with the k best kept
  on the fly (:func:`_knn_scan`); from ``2^20`` values, one BLAS matrix-vector product on one
  thread, and only the rows within its rounding error bound (Higham) of the k-th best go to
  the kernel (:func:`_select_from_products`).
- **Pruned search** for large case bases (``n >= prune_min_cases``, at least 40 dimensions;
  :func:`_pca_knn`): with an orthonormal PCA basis ``B`` (``m`` columns, a sixth of the
  dimensions, 8 to 128, fitted on a sample), every row's coordinates ``B'(x - mean)`` are
  stored as uint8 codes with each row's exact grid error ``e_x`` and the norm ``r_x`` of its
  part outside the basis, and ``|x - q|^2 >= max(|p_hat_q - p_hat_x| - e_q - e_x, 0)^2 +
  (r_x - r_q)^2``. The codes are bits allocated by variance: one grid whose step per
  dimension shrinks by a power of two (up to 8) where the dimension's range is narrower,
  so ``|p_hat_q - p_hat_x|^2`` is a fixed step squared times an exact integer sum, and they
  are stored dimension-major in blocks of ``_BLOCK`` rows so the integer kernel vectorises
  across rows: ``m`` bytes a case (a sixth of a float row's bytes at most). A case whose
  bound is below the running k-th distance gets its exact distance at once (kept by
  distance, then index, so the order cases are visited in never changes the answer).
  **Blocks of similar cases**: where the data has structure, the cases are stored in an
  order in which each block of ``_BLOCK`` holds similar ones (a tree of balanced 2-means
  splits on the codes, :func:`_tree_order`), and each block keeps its box of codes and a
  ball in the rows' space (centre and radius); per query one bound per block
  (:func:`_block_order`: the box's grid distance and the ball's ``|q - c| - R``, both at
  most every one of its cases'), the blocks are visited nearest first and the pass stops
  at the first block whose bound exceeds the limit: the first blocks hold the neighbours,
  the k-th distance falls at once and most blocks are never read. Whether the blocks come
  out tight (median radius under ``_TIGHT`` of the cases' spread) is tried on a sample at
  build time; where they do not (unstructured data), the cases keep their own order, the
  exact distances stream from memory, and there are no boxes. The search measures its own
  pruning power: when more than ``FALLBACK`` of the
  cases pass the bound (unstructured data, where no low-rank bound prunes), the query is
  the quantized pass below, and later queries skip the PCA bound (re-probing every
  ``PROBE_EVERY``).
- **Quantized pass** (VA-file style). On unstructured rows (no blocks of similar rows) of
  at most ``MAX_DIMS`` dimensions, on a CPU with AVX2: 4-bit codes of the whole rows,
  summed per query from a byte table by AVX2's byte shuffle, with each row's exact grid
  error (:mod:`cbr.similarity.nibbles`, :func:`_nibble_knn`): half the bytes of the 8-bit
  codes and no multiplication, so a scan of 10^6 x 200 codes reads 100 MB. Elsewhere the same
  codes, kernel, blocks and pass as the PCA bound, on the identity basis:
  every whole row as uint8 codes (``x_hat = base + steps * code``, steps by range as above)
  with its exact grid error ``e_x``, so ``|q - x| >= |q_hat - x_hat| - e_q - e_x`` over a
  quarter of the float rows' bytes. On unstructured data the k-th neighbour lies far below
  the bulk and the grid error is small against that gap: all but ~0.01 % of the cases are
  pruned. When more than ``FALLBACK`` need their distance, the query is the plain pass (and
  later queries skip the quantized pass too, re-probing every ``PROBE_EVERY``): an
  unprunable case base costs one plain pass per query.
- **Many queries** (:meth:`Euclidean.nearest_many`): one matrix product per block of queries
  (BLAS), then per query the cases whose product-based distance is within its rounding error
  bound of the k-th best are re-checked with the row kernel.

Rows are read where they lie: a read-only memory-mapped case matrix
(:mod:`casebase_store.case_matrix`) is used without a copy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numba
import numpy as np

from features.blas import one_blas_thread
from features.errors import ConfigError, InputError

from .base import SimilarityMeasure, check_weighting, check_whole, register_measure, weighted
from .nibbles import (
    HAS_SHUFFLE,
    MAX_DIMS,
    NIBBLE_BLOCK,
    NibbleCodes,
    limit_code,
    nibble_codes,
    nibble_tables,
    scalar_block_mask,
    shuffle_block_mask,
)

FALLBACK = 0.5  # candidate share above which the pruned search turns into the plain pass
PROBE_EVERY = 16  # an index that stopped pruning tries the bound again every this many queries
_U32 = 2.0**-24  # unit roundoff of float32


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
def _row_distance(rows: np.ndarray, i: int, q: np.ndarray) -> float:
    """:func:`_row_sq` as a function of its own, for callers compiled without fastmath (the
    flags of the code it is inlined into decide its summation order, so its value)."""
    return _row_sq(rows, i, q)


@numba.njit(cache=True, nogil=True, inline="always")
def _insert(best_i: np.ndarray, best_d: np.ndarray, i: int, d: float) -> None:
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
def _insert_any(best_i: np.ndarray, best_d: np.ndarray, i: int, d: float) -> None:
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
def _all_distances(rows: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Distances from ``q`` ``(D,)`` float32 to every row of ``rows`` ``(n, D)`` float32."""
    out = np.empty(rows.shape[0])
    for i in range(rows.shape[0]):
        out[i] = _row_sq(rows, i, q)
    return out


@numba.njit(cache=True, nogil=True, fastmath=True)
def _knn_scan(
    rows: np.ndarray, q: np.ndarray, idx: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """The k nearest among the rows listed in ``idx`` (increasing), or all rows when ``idx``
    is empty: (indices ``(k,)``, distances ``(k,)``)."""
    best_i = np.full(k, rows.shape[0], dtype=np.int64)
    best_d = np.full(k, np.inf)
    if idx.shape[0] == 0:
        for i in range(rows.shape[0]):
            _insert(best_i, best_d, i, _row_sq(rows, i, q))
    else:
        for t in range(idx.shape[0]):
            i = idx[t]
            _insert(best_i, best_d, i, _row_sq(rows, i, q))
    return best_i, best_d


_BLOCK = 64  # rows per block of the PCA codes (stored dimension-major within a block)


@numba.njit(cache=True, nogil=True)
def _grid_codes(
    v: np.ndarray, base: np.ndarray, steps: np.ndarray, weights: np.ndarray
) -> tuple[np.ndarray, int, float]:
    """``v`` ``(m,)`` float64 on the grid ``base + steps * code`` (codes clipped to 0..255):
    (``weights * code`` ``(m,)`` int32, ``sum(weights code^2)``, ``|v - v_hat|`` rounded up
    as :func:`_quantize` does it; inf when ``v`` has a NaN or inf)."""
    m = v.shape[0]
    codes = np.zeros(m, dtype=np.int32)
    code_sq = 0
    err = 0.0
    v_sq = 0.0
    sc_sq = 0.0
    base_sq = 0.0
    for t in range(m):
        if not math.isfinite(v[t]):
            return codes, 0, np.inf
        c = min(max(round((v[t] - base[t]) / steps[t]), 0.0), 255.0)
        codes[t] = np.int32(c) * weights[t]
        code_sq += int(c) * int(c) * int(weights[t])
        sc = steps[t] * c
        diff = v[t] - (base[t] + sc)
        err += diff * diff
        v_sq += v[t] * v[t]
        sc_sq += sc * sc
        base_sq += base[t] * base[t]
    u = 2.0**-53
    spread = math.sqrt(v_sq) + math.sqrt(sc_sq) + math.sqrt(base_sq)
    return codes, code_sq, math.sqrt(err) * (1.0 + 4.0 * (m + 4) * u) + 4.0 * u * spread


@numba.njit(cache=True, nogil=True)
def _project_query(
    q: np.ndarray, mean: np.ndarray, basis: np.ndarray
) -> tuple[np.ndarray, float, float]:
    """``q`` ``(D,)`` float32 on the basis ``(D, m)``: (coordinates ``B'(q - mean)`` ``(m,)``,
    the norm of the part outside the basis, ``|q - mean|``)."""
    dims, m = basis.shape
    qp = np.zeros(m)
    tot = 0.0
    for j in range(dims):
        c = np.float64(q[j]) - mean[j]
        tot += c * c
        for t in range(m):
            qp[t] += c * basis[j, t]
    p_sq = 0.0
    for t in range(m):
        p_sq += qp[t] * qp[t]
    return qp, math.sqrt(max(tot - p_sq, 0.0)), math.sqrt(tot)


@numba.njit(cache=True, nogil=True, fastmath=True)
def _block_dots(codes: np.ndarray, b: int, qc: np.ndarray, dots: np.ndarray) -> None:
    """``dots[t]`` = the integer ``c_x.c_q`` of row ``t`` of block ``b`` of ``codes``
    ``(blocks, m, _BLOCK)`` uint8 and the query's weighted codes ``qc`` ``(m,)`` int32
    (exact: ``max(w) m 255^2 < 2^31``). Dimension-major within the block: the loop over
    rows vectorises with no horizontal sum per row."""
    for t in range(_BLOCK):
        dots[t] = 0
    for j in range(codes.shape[1]):
        qj = np.int32(qc[j])
        for t in range(_BLOCK):
            dots[t] += np.int32(codes[b, j, t]) * qj


@numba.njit(cache=True, nogil=True)
def _up32(x: float) -> float:
    """The smallest float32 value at least ``x``, as a float."""
    y = np.float32(x)
    return float(y) if float(y) >= x else float(np.nextafter(y, np.float32(np.inf)))


@numba.njit(cache=True, nogil=True)
def _down32(x: float) -> float:
    """The largest float32 value at most ``x``, as a float."""
    y = np.float32(x)
    return float(y) if float(y) <= x else float(np.nextafter(y, np.float32(-np.inf)))


@numba.njit(cache=True, nogil=True)
def _block_bounds(
    dots: np.ndarray,
    code_sq: np.ndarray,
    errs: np.ndarray,
    resid: np.ndarray,
    a: int,
    query: tuple[int, float, float, float],
    out: np.ndarray,
) -> None:
    """``out[t]`` ``(_BLOCK,)`` float32: the squared bound of row ``a + t`` (see
    :func:`_pca_knn`) from the block's integer dot products ``dots``, -1 for a row without
    a bound (``e_x`` inf: a NaN or inf, or the padding).
    ``query`` = (the query codes' squared norm, ``e_q`` and ``r_q`` as float32 rounded up,
    ``step`` as float32 rounded down). In float32, so the loop vectorises 16 rows wide:
    every term is below ``~1.1 sqrt(scale)`` and each of the few operations errs by
    ``2^-24`` of its result, so the computed bound exceeds the exact one by less than
    ``1e-6 scale``. ``s2 = sum(w (c_q - c_x)^2)`` is below ``2^31``, so its sum in int32
    is exact although the terms wrap around (arithmetic modulo ``2^32``)."""
    qc_sq, e_q, r_q, step = query
    e32 = np.float32(e_q)
    r32 = np.float32(r_q)
    step32 = np.float32(step)
    c32 = np.uint32(qc_sq)
    for t in range(_BLOCK):
        s2 = np.int32(np.uint32(code_sq[a + t]) + c32 - np.uint32(2) * np.uint32(dots[t]))
        p = step32 * np.float32(math.sqrt(np.float32(s2))) - e32 - errs[a + t]
        p = p if p > np.float32(0.0) else np.float32(0.0)
        r = resid[a + t] - r32
        v = p * p + r * r
        v = v if errs[a + t] < np.float32(np.inf) else np.float32(-1.0)
        out[t] = v


@numba.njit(cache=True, nogil=True)
def _block_order(
    boxes: tuple[np.ndarray, ...],
    q: np.ndarray,
    qc: np.ndarray,
    e_q: float,
    r_q: float,
    step: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Every block's squared bound ``(blocks,)`` float64 (-1: a block with a row without a
    bound) and the blocks in increasing order of it.

    ``boxes`` = (weights ``(m,)``, lo and hi ``(m, blocks)`` uint8: the box of the block's
    codes, the block's largest ``e_x``, its smallest and largest ``r_x`` ``(blocks,)``): every
    row ``x`` of block ``b`` has ``|p_hat_q - p_hat_x|^2 >= step^2 sum(w d^2)`` with ``d``
    the distance of ``c_q`` to the box (an exact integer sum), so the row's bound of
    :func:`_pca_knn` is at least ``max(step sqrt(sum(w d^2)) - e_q - max e_x, 0)^2 +
    dist(r_q, [min r_x, max r_x])^2`` (float64: its rounding is ~1e-16 of the terms)."""
    weights, box_lo, box_hi, box_err, box_rlo, box_rhi, centres, radii = boxes
    m, blocks = box_lo.shape
    centre_sq = np.empty(blocks, dtype=np.float32)
    _centre_distances_sq(centres, q, centre_sq)
    dims = centres.shape[1]
    gamma = (dims + 2) * 2.0**-24 / (1.0 - (dims + 2) * 2.0**-24)
    shrink = 1.0 - 2.0 * gamma  # the float32 sum of squares is at most (1 + gamma) times
    g = np.zeros(blocks, dtype=np.int32)  # below 2^31 as every code sum (_PcaCodes)
    for j in range(m):
        w = np.int32(weights[j])
        c = np.int32(qc[j] // weights[j])
        for b in range(blocks):
            d = max(np.int32(box_lo[j, b]) - c, c - np.int32(box_hi[j, b]), np.int32(0))
            g[b] += np.int32(w * d * d)
    bound = np.empty(blocks)
    for b in range(blocks):
        if not (box_err[b] < np.inf and centre_sq[b] < np.inf):
            bound[b] = -1.0  # no bound: a row with NaN or inf, or a square that overflows
            continue
        p = max(step * math.sqrt(np.float64(g[b])) - e_q - box_err[b], 0.0)
        r = max(box_rlo[b] - r_q, r_q - box_rhi[b], 0.0)
        ball = max(math.sqrt(centre_sq[b] * shrink) - radii[b], 0.0)
        bound[b] = max(p * p + r * r, ball * ball)
    return bound, np.argsort(bound)


@numba.njit(cache=True, nogil=True, fastmath=True)
def _centre_distances_sq(centres: np.ndarray, q: np.ndarray, out: np.ndarray) -> None:
    """``out[b]`` = ``|q - centres[b]|^2`` for the centres ``(blocks, D)`` float32 and the
    query ``q`` ``(D,)`` float32, in float32 (vectorised, in any order): each difference,
    square and sum errs by ``2^-24`` relative and every term is positive, so the result is
    within ``gamma_(D+2)`` relative of the exact one (a smaller one where a term underflows,
    inf where one overflows)."""
    for b in range(centres.shape[0]):
        s = np.float32(0.0)
        for j in range(centres.shape[1]):
            d = centres[b, j] - q[j]
            s += d * d
        out[b] = s


@numba.njit(cache=True, nogil=True)
def _pca_knn(
    pca: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, np.ndarray],
    boxes: tuple[np.ndarray, ...],
    query_pca: tuple[np.ndarray, int, float, float],
    rows: np.ndarray,
    q: np.ndarray,
    k: int,
    rounding: float,
    scale: float,
    max_count: int,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Exact k nearest of ``q`` ``(D,)`` float32 with the bound of the PCA codes: (indices
    ``(k,)``, distances ``(k,)``, rows whose kernel distance was computed), or a count of -1
    once more than ``max_count`` were (the caller then runs a pass that prunes better, or
    the plain pass).

    ``pca`` = (codes ``(blocks, m, _BLOCK)`` uint8, code_sq int32, errs float32, resid
    float32 ``(blocks _BLOCK,)``, step, order ``(blocks _BLOCK,)`` int64): the rows in the
    order ``order`` (similar rows share a block, :func:`_cluster_order`), each row's
    coordinates ``p_x = B'(x - mean)`` on the orthonormal basis ``B`` ``(D, m)`` on the grid
    ``base + step * code``, ``e_x = |p_x - p_hat|`` rounded up and the residual norm ``r_x =
    |x - mean - B p_x|`` (both inf for a row with NaN or inf, which has no bound and always
    goes to the row kernel, as in the plain pass, and for the padding of the last block,
    never visited); ``boxes``: each block's box (:func:`_block_order`); ``query_pca`` =
    (``w c_q`` ``(m,)`` int32, ``sum(w c_q^2)``, ``e_q``, ``r_q``) the same for the query
    (``w`` the dimensions' weights, :class:`_PcaCodes`). ``rounding``: what a row kernel's
    squared distance may lack of the true one; ``scale``: ``(top_norm + |q - mean|)^2``.

    Why no neighbour is lost. Pythagoras on the basis and its complement, the reverse
    triangle inequality on the complement and the triangle inequality on the grid:
    ``|q - x|^2 = |p_q - p_x|^2 + |(I - BB')(q - x)|^2 >= max(g - e_q - e_x, 0)^2
    + (r_x - r_q)^2`` with ``g^2 = step^2 sum(w (c_q - c_x)^2)`` (an exact integer sum;
    dimension ``j``'s grid step is ``step sqrt(w_j)``).
    The computed bound exceeds this by the float64 projection (``~D u64`` of the norms), the
    basis' orthonormality (``~1e-15``), the root of the residual's ``|x - mean|^2 -
    |p_x|^2`` (at most ``sqrt(2 D u64)`` of ``|x - mean|``, ~3e-7), ``resid``'s float32
    storage (6e-8 relative) and the float32 evaluation (:func:`_block_bounds`, < 1e-6
    scale): all far inside the ``1e-5 scale`` the limit allows. A row is pruned when its
    bound exceeds ``limit = (d_k^2 + rounding)(1 + 1e-5) + 1e-5 scale`` with ``d_k`` the
    running k-th smallest kernel distance: its true squared distance then exceeds ``d_k^2 +
    rounding``, so its kernel distance exceeds ``d_k``; ``d_k`` only falls, so it exceeds
    the final k-th distance too. A block is pruned, with all its rows, when its bound (at
    most each row's, :func:`_block_order`) exceeds the limit. So whatever the order the rows
    are visited in, no row pruned could be among the k nearest, and the k best kept by
    distance then index (:func:`_insert_any`) are the plain pass's (ties keep the lower
    index). The blocks are visited in increasing order of their bound: the first ones hold
    the neighbours or rows near them, so ``d_k`` falls early, and the pass stops at the
    first block whose bound exceeds the limit.
    """
    codes, code_sq, errs, resid, step, order = pca
    qc, qc_sq, e_q, r_q = query_pca
    lo = 1.0 - 4.0 * 2.0**-53
    n = len(rows)
    best_i = np.full(k, n, dtype=np.int64)
    best_d = np.full(k, np.inf)
    dots = np.empty(_BLOCK, dtype=np.int32)
    lb = np.empty(_BLOCK, dtype=np.float32)
    query32 = (qc_sq, _up32(e_q), _up32(r_q), _down32(step * lo))
    if boxes[-1].shape[0] == 0:  # blocks in the rows' own order: no box to order them by
        block_bound, visit = np.full(codes.shape[0], -1.0), np.arange(codes.shape[0])
    else:
        block_bound, visit = _block_order(boxes, q, qc, _up32(e_q), r_q, step * lo)
    limit = np.inf
    count = 0
    for v in range(len(visit)):
        b = int(visit[v])
        if block_bound[b] > limit:
            break  # every block left has a larger bound
        a = b * _BLOCK
        _block_dots(codes, b, qc, dots)
        _block_bounds(dots, code_sq, errs, resid, a, query32, lb)
        for t in range(min(_BLOCK, n - a)):
            if not lb[t] <= limit:
                continue
            i = order[a + t]
            count += 1
            if count > max_count:
                return best_i, best_d, -1
            d = _row_distance(rows, i, q)
            if d <= best_d[k - 1]:
                _insert_any(best_i, best_d, i, d)
                if best_d[k - 1] < np.inf:
                    limit = (best_d[k - 1] ** 2 + rounding) * (1.0 + 1e-5) + 1e-5 * scale
    return best_i, best_d, count


@numba.njit(cache=True, nogil=True)
def _nibble_knn(
    nibbles: tuple[np.ndarray, np.ndarray, float, np.ndarray, float],
    distance: tuple[np.ndarray, np.ndarray, float],
    k: int,
    max_count: int,
    shuffle: bool,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Exact k nearest of ``q`` with the 4-bit bound (:mod:`cbr.similarity.nibbles`):
    (indices ``(k,)``, distances ``(k,)``, cases whose distance was computed; -1 once more
    than ``max_count`` were).

    ``nibbles`` = (the codes, each case's ``e_x`` ``(n,)`` float32 and the largest, the
    query's tables ``(m 32,)`` uint8, their scale ``s``); ``distance`` = (rows ``(n, D)``
    float32, ``q`` ``(D,)`` float32, ``rounding``:
    what a row kernel's squared distance may lack of the true one).

    Cases are visited in index order, 64 at a time. With ``d_k`` the running k-th kernel
    distance and ``r = sqrt((d_k^2 + rounding)(1 + 1e-9))``, a case is pruned when its table
    sum ``S`` exceeds ``floor(s (r + max e_x)^2 (1 + 1e-9))`` (the block's mask) or ``s (r +
    e_x)^2 (1 + 1e-9)`` (its own ``e_x``): then ``|q - x| >= sqrt(S / s) - e_x > r`` (the
    ``1e-9`` margins exceed the float64 rounding of these few operations), so its true
    squared distance exceeds ``d_k^2 + rounding``, its kernel distance exceeds ``d_k``, and
    ``d_k`` only falls. The others get their kernel distance and are kept as the plain pass
    keeps them (ties to the lower index). ``shuffle``: AVX2's kernel (only where
    :data:`~cbr.similarity.nibbles.HAS_SHUFFLE`), else the scalar one; both give the same
    sums."""
    codes, errs, top_err, luts, scale = nibbles
    rows, q, rounding = distance
    n = len(errs)
    m = luts.shape[0] // 32
    best_i = np.full(k, n, dtype=np.int64)
    best_d = np.full(k, np.inf)
    sums = np.empty(NIBBLE_BLOCK, dtype=np.uint16)
    radius = np.inf
    most = 65535
    count = 0
    for b in range(-(-n // NIBBLE_BLOCK)):
        mask: int
        if shuffle:
            mask = shuffle_block_mask(codes, b * m * 32, luts, m, most, sums)  # type: ignore[call-arg]
        else:
            mask = scalar_block_mask(codes, b * m * 32, luts, m, most, sums)
        while mask != 0:
            t = 0
            while not (mask >> t) & 1:
                t += 1
            mask &= mask - 1  # the lowest bit set: cases in increasing index order
            i = b * NIBBLE_BLOCK + t
            if i >= n:
                break  # the padding of the last block
            reach = radius + np.float64(errs[i])
            if np.float64(sums[t]) > scale * reach * reach * (1.0 + 1e-9):
                continue
            count += 1
            if count > max_count:
                return best_i, best_d, -1
            d = _row_distance(rows, i, q)
            if d < best_d[k - 1]:
                _insert(best_i, best_d, i, d)
                if best_d[k - 1] < np.inf:
                    radius = math.sqrt((best_d[k - 1] ** 2 + rounding) * (1.0 + 1e-9))
                    far = radius + top_err
                    most = limit_code(far * far * (1.0 + 1e-9), scale)
    return best_i, best_d, count


@numba.njit(cache=True, nogil=True, fastmath=True)
def _select_from_products(
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
    # the float64 rounding of |c|^2 - 2 c.q + |q|^2, and the row kernel's (_allowance_of)
    rel = 1e-12 + 2.02 * (rows.shape[1] + 1) * 2.0**-53
    ub_i = np.full(k, -1, dtype=np.int64)
    ub_d = np.full(k, np.inf)
    for i in range(n):
        d2 = sq[i] - 2.0 * np.float64(prods[i]) + q_sq
        d2 += err * norms[i] + rel * (sq[i] + q_sq)
        if d2 < ub_d[k - 1]:
            _insert(ub_i, ub_d, i, d2)
    limit = max(ub_d[k - 1], 0.0)
    best_i = np.full(k, n, dtype=np.int64)
    best_d = np.full(k, np.inf)
    for i in range(n):
        d2 = sq[i] - 2.0 * np.float64(prods[i]) + q_sq
        if d2 - err * norms[i] - rel * (sq[i] + q_sq) <= limit:
            _insert(best_i, best_d, i, _row_sq(rows, i, q))
    return best_i, best_d


class _PruningRecord:
    """How well a bound has been pruning: ``pruning`` = [running share of the cases it let
    through, queries seen], a heuristic shared by the queries of one index (races between
    threads only change a speed decision)."""

    pruning: np.ndarray

    def worth_it(self) -> bool:
        """Whether the next query should compute the bound (see the module docstring)."""
        share, seen = self.pruning
        return bool(seen == 0 or share <= FALLBACK or seen % PROBE_EVERY == 0)

    def record(self, share: float) -> None:
        old, seen = self.pruning
        self.pruning[0] = share if seen == 0 else 0.7 * old + 0.3 * share
        self.pruning[1] = seen + 1

    def skip(self) -> None:
        self.pruning[1] += 1


@dataclass(frozen=True, eq=False)
class _EuclideanIndex(_PruningRecord):
    rows: np.ndarray  # (n, D) float32 (float64 when exact=True); may be a read-only memmap
    sq_norms: np.ndarray  # (n,) float64
    norms: np.ndarray  # (n,) float64
    pca: _PcaCodes | None = None  # the rows' PCA codes, for the PCA bound
    max_norm: float = 0.0  # largest |row| (over rows without NaN or inf)
    # the whole rows' codes (identity basis; 4-bit on unstructured data): quantized pass
    codes: _PcaCodes | _Nibbles | None = None
    # [running share of cases that survive the PCA bound, queries seen] (_PruningRecord)
    pruning: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0]))

    @property
    def basis(self) -> np.ndarray | None:
        """The PCA bound's basis ``(D, m)``, or None when the index has no PCA bound."""
        return None if self.pca is None else self.pca.basis


@dataclass(frozen=True, eq=False)
class _PcaCodes(_PruningRecord):
    """Every row's coordinates on an orthonormal basis (the leading PCA directions, or the
    identity: the whole row) as uint8 codes on one grid (``p_hat = base + steps * code``),
    stored in blocks of ``_BLOCK`` similar rows (``order``), dimension-major within a block,
    with each block's box; with the exact remainder: the residual norm outside the basis."""

    basis: np.ndarray | None  # (D, m) float64 orthonormal columns; None: the identity
    mean: np.ndarray  # (D,) float64 (zeros for the identity)
    codes: np.ndarray  # (blocks, m, _BLOCK) uint8, the rows in the order ``order``
    code_sq: np.ndarray  # (blocks * _BLOCK,) int32 squared norms of the codes
    errs: np.ndarray  # (blocks * _BLOCK,) float32 |p_x - p_hat| rounded up; inf: NaN/padding
    resid: np.ndarray  # (blocks * _BLOCK,) float32 residual norms; inf: NaN/padding
    base: np.ndarray  # (m,) float64
    step: float  # the finest step
    steps: np.ndarray  # (m,) float64 each dimension's step, step sqrt(weights)
    weights: np.ndarray  # (m,) int32 powers of 4 up to 64 (max(w) m 255^2 < 2^31)
    top_norm: float  # largest |row - mean| over rows without NaN or inf
    order: np.ndarray  # (blocks * _BLOCK,) int64 the row stored at each place (n: padding)
    # each block's box: lo, hi (m, blocks) uint8 codes; largest e_x, smallest and largest
    # r_x (blocks,) float64 (e_x inf: the block holds a row without a bound)
    # and its ball in the rows' space: centres (blocks, D) float64, radii (blocks,) float64
    boxes: tuple[np.ndarray, ...]

    @cached_property
    def kernel_args(self) -> tuple[tuple[Any, ...], tuple[Any, ...], tuple[Any, ...]]:
        """The grid, the codes and the boxes as :func:`_codes_query` takes them."""
        basis = np.zeros((len(self.mean), 0)) if self.basis is None else self.basis
        return (
            (self.mean, basis, self.base, self.steps, self.weights, self.top_norm),
            (self.codes, self.code_sq, self.errs, self.resid, self.step, self.order),
            (self.weights, *self.boxes),
        )

    # [running share of cases given their distance, queries seen] (_PruningRecord; used for
    # the whole rows' codes)
    pruning: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0]))


@dataclass(frozen=True, eq=False)
class _Nibbles(_PruningRecord):
    """The whole rows' 4-bit codes (:mod:`cbr.similarity.nibbles`) with their pruning record."""

    codes: NibbleCodes
    # [running share of cases given their distance, queries seen] (_PruningRecord)
    pruning: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0]))


def _pca_basis(rows: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """The mean ``(D,)`` and the leading ``m`` principal directions ``(D, m)`` (orthonormal
    to float64 rounding) of a sample of 1000 rows of ``rows`` ``(n, D)``."""
    n = len(rows)
    pick = np.random.default_rng(0).choice(n, min(n, 1000), replace=False)
    sample = np.asarray(rows[np.sort(pick)], dtype=np.float64)
    sample = sample[np.isfinite(sample).all(axis=1)]
    mean = sample.mean(axis=0) if len(sample) else np.zeros(rows.shape[1])
    centred = sample - mean
    # principal directions from the small Gram matrix (sample x sample), then QR so the
    # basis is orthonormal to rounding: the bound needs orthonormality, not optimality
    _, vecs = np.linalg.eigh(centred @ centred.T)
    top = centred.T @ vecs[:, ::-1][:, :m]  # (D, m)
    return mean, np.linalg.qr(top)[0]


def _project(
    part: np.ndarray, mean: np.ndarray, basis: np.ndarray | None
) -> tuple[np.ndarray, ...]:
    """Coordinates ``(c, m)`` on ``basis`` (None: the identity) of the rows ``part`` ``(c, D)``
    less ``mean``, the squared norms ``(c,)`` of the centred rows and a mask of the rows
    without NaN or inf."""
    c = np.asarray(part, dtype=np.float64) - mean  # float64: the residual needs it
    finite = np.isfinite(c).all(axis=1)
    c[~finite] = 0.0
    return c if basis is None else c @ basis, np.einsum("ij,ij->i", c, c), finite


def _pca_codes(
    rows: np.ndarray,
    fitted: tuple[np.ndarray, np.ndarray] | None,
    order: np.ndarray | None = None,
    balls: tuple[np.ndarray, np.ndarray] | None = None,
) -> _PcaCodes | None:
    """The codes of ``rows`` ``(n, D)`` on the basis ``fitted`` = (mean, basis ``(D, m)``)
    or, for None, of the whole rows: two passes in chunks (the grid's range, then the
    codes), so a memmap is read without a float64 copy of it; None without a finite range.
    Stored in the order ``order`` ``(n,)`` with the blocks' ``balls`` (:func:`_balls`;
    both None: :func:`_cluster_order`'s, or the rows' own order without boxes)."""
    n, dims = rows.shape
    mean, basis = (np.zeros(dims), None) if fitted is None else fitted
    m = dims if basis is None else basis.shape[1]
    chunk = max(_BLOCK, ((1 << 22) // dims) // _BLOCK * _BLOCK)  # float64 chunks of ~32 MB
    lo, hi = np.full(m, np.inf), np.full(m, -np.inf)
    top_sq = 0.0
    for a in range(0, n, chunk):
        p, tot, finite = _project(rows[a : a + chunk], mean, basis)
        if finite.any():
            lo = np.minimum(lo, p[finite].min(axis=0))
            hi = np.maximum(hi, p[finite].max(axis=0))
            top_sq = max(top_sq, float(tot[finite].max()))
    widest = float(np.max(hi - lo))
    if not (math.isfinite(widest) and widest > 0.0):
        return None
    # bits by variance: dimension j's step is the widest range's / 255 divided by the power
    # of two (up to 8) its own range allows, so narrow dimensions get a finer grid; with
    # ``step`` the finest step, dimension j's is ``step sqrt(w_j)``, ``w_j`` in 1, 4, 16, 64,
    # and ``|p_hat_q - p_hat_x|^2 = step^2 sum(w (c_q - c_x)^2)`` stays an exact integer sum
    # (the finest level kept so every integer sum stays in int32: weights * m * 255^2 < 2^31)
    levels = float(min(3, math.floor(math.log(2**31 / (m * 255**2), 4))))
    width = np.maximum(hi - lo, widest / 256.0)
    shrink = np.minimum(np.floor(np.log2(widest / width)), levels)
    weights = (4.0 ** (levels - shrink)).astype(np.int32)
    step = widest / 255.0 / 2.0**levels
    steps = step * np.sqrt(weights.astype(np.float64))
    flat = np.empty((n, m), dtype=np.uint8)
    code_sq = np.empty(n, dtype=np.int32)
    errs = np.empty(n, dtype=np.float32)
    resid = np.empty(n, dtype=np.float32)
    for a in range(0, n, chunk):
        p, tot, finite = _project(rows[a : a + chunk], mean, basis)
        c, e = _quantize(p, lo, steps)
        e[~finite] = np.inf
        r = np.sqrt(np.maximum(tot - np.einsum("ij,ij->i", p, p), 0.0))
        r[~finite] = np.inf
        end = a + len(p)
        flat[a:end] = c
        code_sq[a:end] = np.einsum("ij,ij,j->i", c.astype(np.int32), c.astype(np.int32), weights)
        errs[a:end] = np.nextafter(e.astype(np.float32), np.float32(np.inf))  # rounded up
        resid[a:end] = r
    if order is None and balls is None:
        order = _cluster_order(flat, steps, rows)
        balls = None if order is None else _balls(rows, order)
    if order is None or balls is None:  # the rows' own order, without boxes
        order, boxes = np.arange(n), _no_boxes(m, dims)
    else:
        boxes = (*_boxes(flat, errs, resid, order), *balls)
    codes, code_sq, errs, resid = _blocked(flat, code_sq, errs, resid, order)
    return _PcaCodes(
        basis, mean, codes, code_sq, errs, resid, lo, step, steps, weights, math.sqrt(top_sq),
        np.concatenate([order, np.full(-n % _BLOCK, n)]), boxes,
    )  # fmt: skip


def _no_boxes(m: int, dims: int) -> tuple[np.ndarray, ...]:
    """The boxes of :class:`_PcaCodes` for codes in the rows' own order: none."""
    return (
        np.zeros((m, 0), dtype=np.uint8), np.zeros((m, 0), dtype=np.uint8), np.zeros(0),
        np.zeros(0), np.zeros(0), np.zeros((0, dims), dtype=np.float32), np.zeros(0),
    )  # fmt: skip


def _cluster_order(codes: np.ndarray, steps: np.ndarray, rows: np.ndarray) -> np.ndarray | None:
    """:func:`_tree_order` of the rows ``(n, D)`` by their codes ``(n, m)`` uint8 (grid
    steps ``(m,)``) when it makes blocks much tighter than the rows' spread (tried on a
    sample of ``_SAMPLE`` rows first: the blocks' median radius under ``_TIGHT`` of the
    rows' median distance from their mean); None when it does not (unstructured data: every
    block spans the whole cloud, its bounds prune nothing, and rows read in their own order
    stream from memory)."""
    n = len(codes)
    pick = np.arange(n)
    if n > _SAMPLE:
        pick = np.sort(np.random.default_rng(1).choice(n, _SAMPLE, replace=False))
    order = pick[_tree_order(codes[pick], steps)]
    _, radii = _balls(rows, order)
    if not np.median(radii) < _TIGHT * _median_spread(rows, pick[:: max(1, len(pick) // 2048)]):
        return None
    return order if n <= _SAMPLE else _tree_order(codes, steps)


_SAMPLE = 16384  # rows of the sample that decides whether similar rows share blocks
_TIGHT = 0.9  # blocks' median radius / rows' median spread under which they do


def _median_spread(rows: np.ndarray, pick: np.ndarray) -> float:
    """The median distance of the rows ``rows[pick]`` from their mean (float64, in chunks)."""
    total = np.zeros(rows.shape[1])
    for a in range(0, len(pick), 1024):
        total += np.asarray(rows[pick[a : a + 1024]], dtype=np.float64).sum(axis=0)
    mean = total / len(pick)
    dist = np.empty(len(pick))
    for a in range(0, len(pick), 1024):
        diff = np.asarray(rows[pick[a : a + 1024]], dtype=np.float64) - mean
        dist[a : a + 1024] = np.sqrt(np.einsum("ij,ij->i", diff, diff))
    return float(np.median(dist))


def _tree_order(codes: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """An order of the rows ``(n,)`` in which each block of ``_BLOCK`` holds similar codes
    ``(n, m)`` uint8 (grid steps ``(m,)``), so the blocks' boxes and balls are small: a
    tree, each group split at a multiple of ``_BLOCK`` near its median between the means of
    a 2-means clustering of its points on the grid (:func:`_split_key`), down to single
    blocks."""
    n = len(codes)
    order = np.arange(n)
    todo = [(0, n)]
    scale = steps.astype(np.float32)
    while todo:
        a, b = todo.pop()
        if b - a <= _BLOCK:
            continue
        key = _split_key(codes[order[a:b]].astype(np.float32) * scale)
        if key is None:
            continue  # every point alike
        half = max(_BLOCK, (b - a + _BLOCK) // 2 // _BLOCK * _BLOCK)
        order[a:b] = order[a:b][np.argpartition(key, half)]
        todo += [(a, a + half), (a + half, b)]
    return order


def _split_key(x: np.ndarray) -> np.ndarray | None:
    """Where each point of ``x`` ``(g, m)`` float32 lies along the line between the two
    means of a 2-means clustering of them (two Lloyd steps from two far points, split at
    the median: whole clusters fall on one side), or None when the points are all alike."""
    sq = np.einsum("ij,ij->i", x, x)
    a = x[np.argmax(sq - 2.0 * (x @ x[0]))]
    b = x[np.argmax(sq - 2.0 * (x @ a))]
    if np.array_equal(a, b):
        return None
    key: np.ndarray = x @ (b - a)
    for _ in range(2):
        near_a = key < np.median(key)
        if near_a.all() or not near_a.any():
            break
        key = x @ (x[~near_a].mean(axis=0) - x[near_a].mean(axis=0))
    return key


def _blocked(
    flat: np.ndarray, code_sq: np.ndarray, errs: np.ndarray, resid: np.ndarray, order: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The codes ``(n, m)`` uint8 in the order ``order`` in blocks of ``_BLOCK`` rows,
    dimension-major within a block ``(blocks, m, _BLOCK)``, and the rows' code_sq, errs and
    resid ``(n,)`` in the same order, padded (inf for the padding)."""
    n, m = flat.shape
    blocks = -(-n // _BLOCK)
    codes = np.zeros((blocks, m, _BLOCK), dtype=np.uint8)
    step = max(1, (1 << 24) // max(m, 1) // _BLOCK)  # blocks at a time, ~16 MB
    for b in range(0, blocks, step):
        part = flat[order[b * _BLOCK : (b + step) * _BLOCK]]
        full = np.zeros((-(-len(part) // _BLOCK) * _BLOCK, m), dtype=np.uint8)
        full[: len(part)] = part
        codes[b : b + len(full) // _BLOCK] = full.reshape(-1, _BLOCK, m).transpose(0, 2, 1)
    pad = blocks * _BLOCK - n
    return (
        codes,
        np.concatenate([code_sq[order], np.zeros(pad, dtype=np.int32)]),
        np.concatenate([errs[order], np.full(pad, np.inf, dtype=np.float32)]),
        np.concatenate([resid[order], np.full(pad, np.inf, dtype=np.float32)]),
    )


def _boxes(
    flat: np.ndarray, errs: np.ndarray, resid: np.ndarray, order: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Each block's box (:class:`_PcaCodes`): lo, hi ``(m, blocks)`` uint8 of its rows'
    codes ``flat`` ``(n, m)`` in the order ``order``; its largest ``errs`` and smallest and
    largest ``resid`` ``(blocks,)`` float64."""
    n, m = flat.shape
    blocks = -(-n // _BLOCK)
    lo = np.empty((m, blocks), dtype=np.uint8)
    hi = np.empty((m, blocks), dtype=np.uint8)
    e = np.empty(blocks)
    r_lo = np.empty(blocks)
    r_hi = np.empty(blocks)
    for b in range(blocks):
        rows = order[b * _BLOCK : (b + 1) * _BLOCK]
        part = flat[rows]
        lo[:, b] = part.min(axis=0)
        hi[:, b] = part.max(axis=0)
        e[b] = errs[rows].max()
        r_lo[b] = resid[rows].min()
        r_hi[b] = resid[rows].max()
    return lo, hi, e, r_lo, r_hi


def _balls(rows: np.ndarray, order: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each block's ball in the rows' space: the mean ``(blocks, D)`` of its rows
    ``rows[order[...]]`` rounded to float32 and the largest distance ``(blocks,)`` float64
    of one of them from that point, raised by far more than its float64 rounding (``D u64``
    relative), so every row of the block lies inside (inf for a block with NaN or inf)."""
    dims = rows.shape[1]
    blocks = -(-len(order) // _BLOCK)
    centres = np.empty((blocks, dims), dtype=np.float32)
    radii = np.empty(blocks)
    for b in range(blocks):
        part = np.asarray(rows[np.sort(order[b * _BLOCK : (b + 1) * _BLOCK])], dtype=np.float64)
        with np.errstate(over="ignore", invalid="ignore"):
            centres[b] = part.mean(axis=0)
        diff = part - centres[b].astype(np.float64)
        radii[b] = math.sqrt(float(np.einsum("ij,ij->i", diff, diff).max())) * (1.0 + 1e-12)
    radii[~np.isfinite(radii)] = np.inf
    centres[~np.isfinite(centres)] = 0.0
    return centres, radii


def _check_finite(sq: np.ndarray, what: str) -> None:
    """Refuse rows whose squared norms ``sq`` ``(n,)`` are not finite: a NaN or inf value has
    no distance, and a missing value must not become a neighbour at distance 0 (problems fill
    their missing values before they are compared)."""
    bad = np.flatnonzero(~np.isfinite(sq))
    if len(bad):
        raise InputError(
            f"euclidean: {what} {', '.join(map(str, bad[:5]))}{' ...' if len(bad) > 5 else ''} "
            "hold NaN or inf (or overflow float32): fill missing values before comparing"
        )


def _check_width(size: int, index: _EuclideanIndex) -> None:
    """Refuse a query of another number of values than the cases' columns: the row kernel
    would read past a shorter query's end (whatever lies in memory there) or leave a longer
    one's last values out, and answer either without a word."""
    dims = index.rows.shape[1]
    if int(size) != dims:
        raise ConfigError(
            f"the query has {int(size)} values but the cases have {dims}", "similarity euclidean"
        )


@register_measure("euclidean")
@dataclass(frozen=True, repr=False)  # SimilarityMeasure's repr: one line
class Euclidean(SimilarityMeasure):
    """``||a - b||_2`` over the flattened problem (a resampled fluent sequence or QMP vector).

    ``exact``: compute in float64 by differences instead of the float32 dot-product identity
    (slower; for tiny case bases or bit-exact comparisons).
    ``prune_min_cases`` / ``prune_dims``: when to use the PCA lower-bound filter, and its rank
    (0: a sixth of the dimensions, 8 to 128 and at most a quarter; its uint8 codes cost a
    twenty-fourth of a plain pass's bytes or less).
    ``centre`` / ``multiplier``: learned feature weighting (:mod:`cbr.weights`), one value per
    flattened column: the measure compares ``(x - centre) * multiplier``; None: raw values.
    """

    exact: bool = False
    prune_min_cases: int = 5000
    prune_dims: int = 0
    centre: tuple[float, ...] | None = None
    multiplier: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        check_whole("euclidean", prune_min_cases=self.prune_min_cases, prune_dims=self.prune_dims)
        check_weighting(self.centre, self.multiplier, "euclidean")

    def represent(self, problems: np.ndarray) -> np.ndarray:
        p = np.asarray(problems)
        if p.dtype != np.float32:
            p = p.astype(np.float64)
        p = p.reshape(len(p), -1)
        if self.multiplier is not None:
            return weighted(p, self.centre, self.multiplier, "euclidean")
        return p

    def build_index(self, reps: np.ndarray) -> Any:
        """Index over ``reps`` ``(n, D)``; float32 rows (a memmap included) are used in place."""
        dtype = np.float64 if self.exact else np.float32
        rows: np.ndarray = np.asarray(reps)
        if rows.dtype != dtype or not rows.flags.c_contiguous:
            rows = np.ascontiguousarray(rows, dtype=dtype)
        sq = _row_norms_sq(rows)
        _check_finite(sq, "case rows")
        n, dims = rows.shape
        m = self.prune_dims or min(max(dims // 6, 8), 128)
        m = min(m, dims // 4)
        if self.exact or n < self.prune_min_cases or m < 4:
            return _EuclideanIndex(rows, sq, np.sqrt(sq))
        return _pruning_index(rows, sq, m)

    def _query(self, query_rep: np.ndarray) -> tuple[np.ndarray, float]:
        q = np.asarray(query_rep)
        if q.dtype != np.float32 and q.dtype != np.float64:
            q = q.astype(np.float64)
        q32, q_sq = _query32(q.reshape(-1))
        if not math.isfinite(q_sq):
            raise InputError("euclidean: the query holds NaN or inf (or overflows float32)")
        return q32, q_sq

    def distances(self, query_rep: np.ndarray, index: Any) -> np.ndarray:
        if not isinstance(index, _EuclideanIndex):
            index = self.build_index(np.asarray(index, dtype=np.float64))
        _check_width(np.size(query_rep), index)
        if self.exact:
            q = np.asarray(query_rep, dtype=np.float64).reshape(-1)
            if not np.isfinite(q).all():  # as the float32 path refuses it (:meth:`_query`)
                raise InputError("euclidean: the query holds NaN or inf")
            exact: np.ndarray = np.sqrt(((index.rows - q) ** 2).sum(axis=1))
            return exact
        q32, q_sq = self._query(query_rep)
        return _all_distances(index.rows, q32)

    def nearest(self, query_rep: np.ndarray, index: Any, k: int) -> tuple[np.ndarray, np.ndarray]:
        if not isinstance(index, _EuclideanIndex) or self.exact:
            return super().nearest(query_rep, index, k)
        _check_width(np.size(query_rep), index)
        k = min(int(k), len(index.rows))
        if k <= 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0)
        q32, q_sq = self._query(query_rep)
        if index.basis is not None and index.worth_it():
            return _pruned_search(index, q32, q_sq, k)
        if index.basis is not None:
            index.skip()
        return _quantized_search(index, q32, q_sq, k)

    def nearest_many(
        self, query_reps: np.ndarray, index: Any, k: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """The k nearest of each query ``(m, D)``: indices and distances ``(m, k)``.

        One matrix product per block of queries (BLAS: all its threads for a large product,
        one for a small one, :func:`_product`) unless the index prunes well (then query by
        query), with the rounding error of the product bounded so the neighbours are exactly
        :meth:`nearest`'s."""
        queries = np.asarray(query_reps, dtype=np.float64).reshape(len(query_reps), -1)
        if isinstance(index, _EuclideanIndex):
            _check_width(queries.shape[1], index)
        _check_finite(np.einsum("ij,ij->i", queries, queries), "queries")
        if not isinstance(index, _EuclideanIndex) or self.exact or len(queries) < 2:
            return super().nearest_many(queries, index, k)
        n, dims = index.rows.shape
        k = min(int(k), n)
        first = self.nearest(queries[0], index, k)
        if (index.basis is not None and index.pruning[0] <= 0.25) or _nibbles_prune(index):
            rest = super().nearest_many(queries[1:], index, k)
            return np.vstack([first[0], rest[0]]), np.vstack([first[1], rest[1]])
        out_i = np.empty((len(queries), k), dtype=np.int64)
        out_d = np.empty((len(queries), k))
        out_i[0], out_d[0] = first
        norms = index.norms
        gamma = dims * _U32 / (1.0 - dims * _U32)  # Higham's bound of a float32 dot product
        block = max(1, min(256, (1 << 26) // (4 * n)))  # <= 64 MB of products at a time
        q32s = queries.astype(np.float32)
        for a in range(1, len(queries), block):
            prods = _product(q32s[a : a + block], index.rows)  # (block, n)
            for j in range(len(prods)):
                q32, q_sq = self._query(queries[a + j])
                out_i[a + j], out_d[a + j] = _select_from_products(
                    prods[j], index.rows, index.sq_norms, norms, q32, q_sq, _error(gamma, q_sq), k
                )
        return out_i, out_d


_ALL = np.zeros(0, dtype=np.int64)
_BLAS_MIN = 1 << 20  # rows x dims from which BLAS's matrix-vector product beats the row kernel


def _nibbles_prune(index: _EuclideanIndex) -> bool:
    """Whether the 4-bit pass has been letting through at most 2 % of the cases: then a query
    costs less than its share of a batch's matrix product (measured at 10^5 and 10^6 x 200
    uniform rows: 1.3 % and 0.2 % let through, 1.1 and 20.6 ms a query against 2.4 and 25.5
    batched; at 10^4, 6 %, the batch wins)."""
    codes = index.codes
    return isinstance(codes, _Nibbles) and codes.pruning[1] > 0 and codes.pruning[0] <= 0.02


def _error(gamma: float, q_sq: float) -> float:
    """Coefficient ``e`` with ``|product-based d^2 - row-kernel d^2| <= e |c|`` for a float32
    dot product of D terms (``gamma = D u / (1 - D u)``, Higham's bound: twice it for the
    product's ``2 c.q``, and as much again to spare; the row kernel's own rounding, some
    ``D 2^-53 (|c| + |q|)^2``, :func:`_select_from_products` adds)."""
    return 4.0 * gamma * math.sqrt(q_sq) * 1.01 + 1e-9


def _matvec_one_thread(rows: np.ndarray, q32: np.ndarray) -> np.ndarray:
    """``rows @ q32`` by BLAS on one thread (:func:`features.blas.one_blas_thread`): a query
    is memory-bound, and BLAS threads on a busy machine were measured 40-300x slower (thread
    hand-off). Any product ``a @ b`` (:func:`_product`'s small ones too)."""
    with one_blas_thread():
        product: np.ndarray = rows @ q32
    return product


SMALL_PRODUCT = 1 << 28
"""Multiply-adds up to which a block of queries' product runs on one BLAS thread
(:func:`_product`): about 10-20 ms on one core. A recording's windows are solved 32 at a
time, so against a case base of hundreds of windows each product is 10-100 M multiply-adds;
on this 2-core machine at load 7, 32 x 500 x 5600 took 476 ms on two BLAS threads against
27 ms on one (each thread waits for a time slice at every hand-off), 256 x 2000 x 212 70 ms
against 1.5 ms. Larger products keep all of BLAS's threads, which pay there on a quiet
machine (the README's retrieval figures were measured with BLAS pinned to one thread: they
do not move)."""


def _product(queries: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``queries @ rows.T`` ``(m, n)`` float32: on one BLAS thread when it is at most
    :data:`SMALL_PRODUCT` multiply-adds, else on all of them. The number of threads does not
    change the neighbours: every candidate's distance is computed again by the row kernel."""
    if queries.shape[0] * rows.shape[0] * rows.shape[1] <= SMALL_PRODUCT:
        return _matvec_one_thread(queries, rows.T)
    product: np.ndarray = queries @ rows.T
    return product


def _plain_search(
    index: _EuclideanIndex, q32: np.ndarray, q_sq: float, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Exact k nearest by one pass over every row: the row kernel for small case bases, one
    BLAS matrix-vector product (re-checked within its error bound) for large ones."""
    rows = index.rows
    if rows.size < _BLAS_MIN:
        return _knn_scan(rows, q32, _ALL, k)
    n, dims = rows.shape
    gamma = dims * _U32 / (1.0 - dims * _U32)
    prods = _matvec_one_thread(rows, q32)
    return _select_from_products(
        prods, rows, index.sq_norms, index.norms, q32, q_sq, _error(gamma, q_sq), k
    )


@numba.njit(cache=True, nogil=True)
def _allowance_of(dims: int, max_norm: float, q_sq: float) -> float:
    """How far a row kernel's squared distance may be from the true one: its float64 sum of
    ``D`` exact differences squared is within ``gamma_(D+1) d^2`` of it (Higham, ``u =
    2^-53``), and ``d <= |c| + |q|``; plus ``D 2^-1074`` for squares that underflow."""
    u = 2.0**-53
    gamma = (dims + 1) * u / (1.0 - (dims + 1) * u)
    q_norm = math.sqrt(q_sq)
    return 1.01 * gamma * (max_norm + q_norm) ** 2 + dims * 2.0**-1074


@numba.njit(cache=True, nogil=True)
def _query32(q: np.ndarray) -> tuple[np.ndarray, float]:
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


@numba.njit(cache=True, nogil=True)
def _codes_query(
    grid: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float],
    codes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, np.ndarray],
    boxes: tuple[np.ndarray, ...],
    rows: np.ndarray,
    q32: np.ndarray,
    q_sq: float,
    k: int,
    max_norm: float,
    max_count: int,
) -> tuple[np.ndarray, np.ndarray, int]:
    """One query of :func:`_pca_knn`, its codes computed here: ``grid`` = (mean ``(D,)``,
    basis ``(D, m)`` (``(D, 0)``: the identity, the whole rows' codes), base, steps
    ``(m,)``, weights ``(m,)``, top_norm) of :class:`_PcaCodes`."""
    mean, basis, base, steps, weights, top_norm = grid
    if basis.shape[1] == 0:  # the whole rows: no projection, nothing outside the grid
        qp = q32.astype(np.float64)
        r_q, q_norm = 0.0, math.sqrt(q_sq)
    else:
        qp, r_q, q_norm = _project_query(q32, mean, basis)
    qc, qc_sq, e_q = _grid_codes(qp, base, steps, weights)
    rounding = _allowance_of(rows.shape[1], max_norm, q_sq)
    return _pca_knn(
        codes, boxes, (qc, qc_sq, e_q, r_q), rows, q32, k, rounding,
        (top_norm + q_norm) ** 2, max_count,
    )  # fmt: skip


def _finite_max_norm(sq: np.ndarray) -> float:
    """Largest row norm over the rows whose squared norm is finite (0 when there is none)."""
    finite = sq[np.isfinite(sq)]
    return math.sqrt(float(finite.max())) if len(finite) else 0.0


def _quantize(
    x: np.ndarray, base: np.ndarray, step: float | np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Codes ``(m, D)`` uint8 of ``x`` ``(m, D)`` on the grid ``base + step * code`` (clipped to
    0..255) and ``|x - x_hat|`` ``(m,)`` float64 rounded up (inf for a row with NaN or inf).

    The float64 difference ``x - (base + step c)`` is within ``3 u64 (|x| + |base| + |step c|)``
    per value of the exact one, the sum of squares and root within ``(D + 2) u64`` relative:
    the error norm is raised by both (generously) so it never falls below the exact one."""
    x64 = np.asarray(x, dtype=np.float64)
    finite = np.asarray(np.isfinite(x64).all(axis=1))
    with np.errstate(invalid="ignore", over="ignore"):
        c = np.clip(np.rint((x64 - base) / step), 0.0, 255.0)
    c[~np.isfinite(c)] = 0.0
    sc = step * c
    diff = x64 - (base + sc)
    err = np.sqrt(np.einsum("ij,ij->i", diff, diff))
    u = 2.0**-53
    dims = x64.shape[1]
    xs = np.where(finite[:, None], x64, 0.0)
    spread = np.sqrt(np.einsum("ij,ij->i", xs, xs)) + np.sqrt(np.einsum("ij,ij->i", sc, sc))
    spread += float(np.linalg.norm(base))
    err = err * (1.0 + 4.0 * (dims + 4) * u) + 4.0 * u * spread
    err[~finite] = np.inf
    return c.astype(np.uint8), err


def _quantized_search(
    index: _EuclideanIndex, q32: np.ndarray, q_sq: float, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Exact k nearest with the bound of the whole rows' codes, or the plain pass when it
    prunes too little (or the index has no codes, or the query has a NaN or inf)."""
    codes = index.codes
    if codes is None or not math.isfinite(q_sq):
        return _plain_search(index, q32, q_sq, k)
    if not codes.worth_it():
        codes.skip()
        return _plain_search(index, q32, q_sq, k)
    n = len(index.rows)
    if isinstance(codes, _Nibbles):
        idx, dist, count = _nibbles_search(index, codes.codes, q32, q_sq, k)
    else:
        idx, dist, count = _codes_search(index, codes, q32, q_sq, k)
    if count < 0:
        codes.record(1.0)
        return _plain_search(index, q32, q_sq, k)
    codes.record(count / n)
    return idx, dist


def _codes_search(
    index: _EuclideanIndex,
    codes: _PcaCodes,
    q32: np.ndarray,
    q_sq: float,
    k: int,
    max_count: int | None = None,
) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`_pca_knn` for ``q32`` ``(D,)`` with ``codes`` (the PCA codes or the whole
    rows'), handing over once more than ``max_count`` (default: ``FALLBACK`` of the rows)
    need their distance."""
    if max_count is None:
        max_count = max(k, int(FALLBACK * len(index.rows)))
    grid, kernel, boxes = codes.kernel_args
    out: tuple[np.ndarray, np.ndarray, int] = _codes_query(
        grid, kernel, boxes, index.rows, q32, q_sq, k, index.max_norm, max_count
    )
    return out


def _nibbles_search(
    index: _EuclideanIndex,
    nibbles: NibbleCodes,
    q32: np.ndarray,
    q_sq: float,
    k: int,
    max_count: int | None = None,
    shuffle: bool = HAS_SHUFFLE,
) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`_nibble_knn` for ``q32`` ``(D,)``, handing over once more than ``max_count``
    (default: ``FALLBACK`` of the rows) need their distance."""
    if max_count is None:
        max_count = max(k, int(FALLBACK * len(index.rows)))
    luts, scale = nibble_tables(q32, nibbles.centres)
    rounding = _allowance_of(index.rows.shape[1], index.max_norm, q_sq)
    out: tuple[np.ndarray, np.ndarray, int] = _nibble_knn(
        (nibbles.codes, nibbles.errs, nibbles.top_err, luts, scale),
        (index.rows, q32, rounding),
        k,
        max_count,
        shuffle,
    )
    return out


def _row_norms_sq(rows: np.ndarray) -> np.ndarray:
    """``(n,)`` float64 squared norms of ``rows`` ``(n, D)``, in chunks (a memmap is read once
    without a float64 copy of it)."""
    out = np.empty(len(rows))
    for a in range(0, len(rows), 65536):
        part = rows[a : a + 65536]
        out[a : a + 65536] = np.einsum("ij,ij->i", part, part, dtype=np.float64)
    return out


def _pruning_index(rows: np.ndarray, sq: np.ndarray, m: int) -> _EuclideanIndex:
    """The index with the PCA codes of rank ``m`` and the whole rows' codes (either left out
    when the rows have no finite range), both in the blocks of similar rows the PCA codes
    make."""
    pca = _pca_codes(rows, _pca_basis(rows, m))
    order, balls = None, None
    if pca is not None:
        order, balls = pca.order[: len(rows)], (pca.boxes[-2], pca.boxes[-1])
    if balls is not None and len(balls[1]) == 0:
        balls = None  # the rows' own order: no boxes for the whole rows either
    codes: _PcaCodes | _Nibbles | None = None
    if balls is None and rows.shape[1] <= MAX_DIMS and HAS_SHUFFLE:  # half the bytes, no product
        nibbles = nibble_codes(rows)
        codes = None if nibbles is None else _Nibbles(nibbles)
    if codes is None and rows.shape[1] * 255**2 < 2**31:
        codes = _pca_codes(rows, None, order, balls)
    return _EuclideanIndex(rows, sq, np.sqrt(sq), pca, _finite_max_norm(sq), codes)


def _probe_most(index: _EuclideanIndex, k: int) -> int:
    """How many rows the PCA bound may send to the row kernel before the query hands over:
    ``FALLBACK`` of the rows, or, once the 4-bit pass has been answering (the PCA bound
    stopped pruning and is only re-probed), four times the share that pass lets through
    (the PCA pass is then no better, and a failed probe at 10^6 uniform rows costs a few
    thousand distances instead of half a million)."""
    n = len(index.rows)
    most = max(k, int(FALLBACK * n))
    codes = index.codes
    if isinstance(codes, _Nibbles) and codes.pruning[1] > 0 and index.pruning[0] > FALLBACK:
        most = min(most, max(k, 64, int(4.0 * codes.pruning[0] * n)))
    return most


def _pruned_search(
    index: _EuclideanIndex, q32: np.ndarray, q_sq: float, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Exact k nearest with the PCA bound, or the whole rows' codes (which may turn into the
    plain pass) when the bound prunes too little or the query has a NaN or inf."""
    pca = index.pca
    assert pca is not None
    if not math.isfinite(q_sq):
        return _quantized_search(index, q32, q_sq, k)
    idx, dist, count = _codes_search(index, pca, q32, q_sq, k, _probe_most(index, k))
    if count < 0:  # too many rows needed their distance: a pass that prunes better
        index.record(1.0)
        return _quantized_search(index, q32, q_sq, k)
    index.record(count / len(index.rows))
    return idx, dist
