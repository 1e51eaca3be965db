"""A query's exact k nearest rows found with a lower bound from the rows' codes (the grid codes'
blocks and rows, :mod:`cbr.similarity.grid_codes`, or the 4-bit codes,
:mod:`cbr.similarity.nibbles`): a row the bound cannot rule out gets its row-kernel distance."""

from __future__ import annotations

import math

import numba
import numpy as np

from .grid_codes import BLOCK
from .nibbles import NIBBLE_BLOCK, limit_code, scalar_block_mask, shuffle_block_mask
from .row_kernel import allowance_of, insert, insert_any, row_distance


@numba.njit(cache=True, nogil=True)
def _grid_codes(
    v: np.ndarray, base: np.ndarray, steps: np.ndarray, weights: np.ndarray
) -> tuple[np.ndarray, int, float]:
    """``v`` ``(m,)`` float64 on the grid ``base + steps * code`` (codes clipped to 0..255):
    (``weights * code`` ``(m,)`` int32, ``sum(weights code^2)``, ``|v - v_hat|`` rounded up
    as :func:`cbr.similarity.grid_codes._quantize` does it; inf when ``v`` has a NaN or inf)."""
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
    ``(blocks, m, BLOCK)`` uint8 and the query's weighted codes ``qc`` ``(m,)`` int32
    (exact: ``max(w) m 255^2 < 2^31``). Dimension-major within the block: the loop over
    rows vectorises with no horizontal sum per row."""
    for t in range(BLOCK):
        dots[t] = 0
    for j in range(codes.shape[1]):
        qj = np.int32(qc[j])
        for t in range(BLOCK):
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
    """``out[t]`` ``(BLOCK,)`` float32: the squared bound of row ``a + t`` (see
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
    for t in range(BLOCK):
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
    g = np.zeros(blocks, dtype=np.int32)  # below 2^31 as every code sum (PcaCodes)
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

    ``pca`` = (codes ``(blocks, m, BLOCK)`` uint8, code_sq int32, errs float32, resid
    float32 ``(blocks BLOCK,)``, step, order ``(blocks BLOCK,)`` int64): the rows in the
    order ``order`` (similar rows share a block,
    :func:`cbr.similarity.grid_codes._cluster_order`), each row's coordinates ``p_x = B'(x -
    mean)`` on the orthonormal basis ``B`` ``(D, m)`` on the grid ``base + step * code``, ``e_x
    = |p_x - p_hat|`` rounded up and the residual norm ``r_x = |x - mean - B p_x|`` (both inf
    for a row with NaN or inf, which has no bound and always goes to the row kernel, as in the
    plain pass, and for the padding of the last block, never visited); ``boxes``: each block's
    box (:func:`_block_order`); ``query_pca`` = (``w c_q`` ``(m,)`` int32, ``sum(w c_q^2)``,
    ``e_q``, ``r_q``) the same for the query (``w`` the dimensions' weights,
    :class:`cbr.similarity.grid_codes.PcaCodes`). ``rounding``: what a row kernel's squared
    distance may lack of the true one; ``scale``: ``(top_norm + |q - mean|)^2``.

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
    distance then index (:func:`insert_any`) are the plain pass's (ties keep the lower
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
    dots = np.empty(BLOCK, dtype=np.int32)
    lb = np.empty(BLOCK, dtype=np.float32)
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
        a = b * BLOCK
        _block_dots(codes, b, qc, dots)
        _block_bounds(dots, code_sq, errs, resid, a, query32, lb)
        for t in range(min(BLOCK, n - a)):
            if not lb[t] <= limit:
                continue
            i = order[a + t]
            count += 1
            if count > max_count:
                return best_i, best_d, -1
            d = row_distance(rows, i, q)
            if d <= best_d[k - 1]:
                insert_any(best_i, best_d, i, d)
                if best_d[k - 1] < np.inf:
                    limit = (best_d[k - 1] ** 2 + rounding) * (1.0 + 1e-5) + 1e-5 * scale
    return best_i, best_d, count


@numba.njit(cache=True, nogil=True)
def nibble_knn(
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
            d = row_distance(rows, i, q)
            if d < best_d[k - 1]:
                insert(best_i, best_d, i, d)
                if best_d[k - 1] < np.inf:
                    radius = math.sqrt((best_d[k - 1] ** 2 + rounding) * (1.0 + 1e-9))
                    far = radius + top_err
                    most = limit_code(far * far * (1.0 + 1e-9), scale)
    return best_i, best_d, count


@numba.njit(cache=True, nogil=True)
def codes_query(
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
    ``(m,)``, weights ``(m,)``, top_norm) of :class:`cbr.similarity.grid_codes.PcaCodes`."""
    mean, basis, base, steps, weights, top_norm = grid
    if basis.shape[1] == 0:  # the whole rows: no projection, nothing outside the grid
        qp = q32.astype(np.float64)
        r_q, q_norm = 0.0, math.sqrt(q_sq)
    else:
        qp, r_q, q_norm = _project_query(q32, mean, basis)
    qc, qc_sq, e_q = _grid_codes(qp, base, steps, weights)
    rounding = allowance_of(rows.shape[1], max_norm, q_sq)
    return _pca_knn(
        codes, boxes, (qc, qc_sq, e_q, r_q), rows, q32, k, rounding,
        (top_norm + q_norm) ** 2, max_count,
    )  # fmt: skip
