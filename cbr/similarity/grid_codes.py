"""Rows as uint8 codes on a grid over an orthonormal basis (the leading PCA directions, or the
whole row) with their exact grid errors, stored in blocks of similar rows, each block with its
box of codes and its ball (the index of :mod:`cbr.similarity.euclidean`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from .pruning import PruningRecord

BLOCK = 64  # rows per block of the PCA codes (stored dimension-major within a block)


@dataclass(frozen=True, eq=False)
class PcaCodes(PruningRecord):
    """Every row's coordinates on an orthonormal basis (the leading PCA directions, or the
    identity: the whole row) as uint8 codes on one grid (``p_hat = base + steps * code``),
    stored in blocks of ``BLOCK`` similar rows (``order``), dimension-major within a block,
    with each block's box; with the exact remainder: the residual norm outside the basis."""

    basis: np.ndarray | None  # (D, m) float64 orthonormal columns; None: the identity
    mean: np.ndarray  # (D,) float64 (zeros for the identity)
    codes: np.ndarray  # (blocks, m, BLOCK) uint8, the rows in the order ``order``
    code_sq: np.ndarray  # (blocks * BLOCK,) int32 squared norms of the codes
    errs: np.ndarray  # (blocks * BLOCK,) float32 |p_x - p_hat| rounded up; inf: NaN/padding
    resid: np.ndarray  # (blocks * BLOCK,) float32 residual norms; inf: NaN/padding
    base: np.ndarray  # (m,) float64
    step: float  # the finest step
    steps: np.ndarray  # (m,) float64 each dimension's step, step sqrt(weights)
    weights: np.ndarray  # (m,) int32 powers of 4 up to 64 (max(w) m 255^2 < 2^31)
    top_norm: float  # largest |row - mean| over rows without NaN or inf
    order: np.ndarray  # (blocks * BLOCK,) int64 the row stored at each place (n: padding)
    # each block's box: lo, hi (m, blocks) uint8 codes; largest e_x, smallest and largest
    # r_x (blocks,) float64 (e_x inf: the block holds a row without a bound)
    # and its ball in the rows' space: centres (blocks, D) float64, radii (blocks,) float64
    boxes: tuple[np.ndarray, ...]

    @cached_property
    def kernel_args(self) -> tuple[tuple[Any, ...], tuple[Any, ...], tuple[Any, ...]]:
        """The grid, the codes and the boxes as
        :func:`cbr.similarity.bounded_search.codes_query` takes them."""
        basis = np.zeros((len(self.mean), 0)) if self.basis is None else self.basis
        return (
            (self.mean, basis, self.base, self.steps, self.weights, self.top_norm),
            (self.codes, self.code_sq, self.errs, self.resid, self.step, self.order),
            (self.weights, *self.boxes),
        )

    # [running share of cases given their distance, queries seen] (PruningRecord; used for
    # the whole rows' codes)
    pruning: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0]))


def pca_basis(rows: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
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


def pca_codes(
    rows: np.ndarray,
    fitted: tuple[np.ndarray, np.ndarray] | None,
    order: np.ndarray | None = None,
    balls: tuple[np.ndarray, np.ndarray] | None = None,
) -> PcaCodes | None:
    """The codes of ``rows`` ``(n, D)`` on the basis ``fitted`` = (mean, basis ``(D, m)``)
    or, for None, of the whole rows: two passes in chunks (the grid's range, then the
    codes), so a memmap is read without a float64 copy of it; None without a finite range.
    Stored in the order ``order`` ``(n,)`` with the blocks' ``balls`` (:func:`_balls`;
    both None: :func:`_cluster_order`'s, or the rows' own order without boxes)."""
    n, dims = rows.shape
    mean, basis = (np.zeros(dims), None) if fitted is None else fitted
    m = dims if basis is None else basis.shape[1]
    chunk = max(BLOCK, ((1 << 22) // dims) // BLOCK * BLOCK)  # float64 chunks of ~32 MB
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
    return PcaCodes(
        basis, mean, codes, code_sq, errs, resid, lo, step, steps, weights, math.sqrt(top_sq),
        np.concatenate([order, np.full(-n % BLOCK, n)]), boxes,
    )  # fmt: skip


def _no_boxes(m: int, dims: int) -> tuple[np.ndarray, ...]:
    """The boxes of :class:`PcaCodes` for codes in the rows' own order: none."""
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
    """An order of the rows ``(n,)`` in which each block of ``BLOCK`` holds similar codes
    ``(n, m)`` uint8 (grid steps ``(m,)``), so the blocks' boxes and balls are small: a
    tree, each group split at a multiple of ``BLOCK`` near its median between the means of
    a 2-means clustering of its points on the grid (:func:`_split_key`), down to single
    blocks."""
    n = len(codes)
    order = np.arange(n)
    todo = [(0, n)]
    scale = steps.astype(np.float32)
    while todo:
        a, b = todo.pop()
        if b - a <= BLOCK:
            continue
        key = _split_key(codes[order[a:b]].astype(np.float32) * scale)
        if key is None:
            continue  # every point alike
        half = max(BLOCK, (b - a + BLOCK) // 2 // BLOCK * BLOCK)
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
    """The codes ``(n, m)`` uint8 in the order ``order`` in blocks of ``BLOCK`` rows,
    dimension-major within a block ``(blocks, m, BLOCK)``, and the rows' code_sq, errs and
    resid ``(n,)`` in the same order, padded (inf for the padding)."""
    n, m = flat.shape
    blocks = -(-n // BLOCK)
    codes = np.zeros((blocks, m, BLOCK), dtype=np.uint8)
    step = max(1, (1 << 24) // max(m, 1) // BLOCK)  # blocks at a time, ~16 MB
    for b in range(0, blocks, step):
        part = flat[order[b * BLOCK : (b + step) * BLOCK]]
        full = np.zeros((-(-len(part) // BLOCK) * BLOCK, m), dtype=np.uint8)
        full[: len(part)] = part
        codes[b : b + len(full) // BLOCK] = full.reshape(-1, BLOCK, m).transpose(0, 2, 1)
    pad = blocks * BLOCK - n
    return (
        codes,
        np.concatenate([code_sq[order], np.zeros(pad, dtype=np.int32)]),
        np.concatenate([errs[order], np.full(pad, np.inf, dtype=np.float32)]),
        np.concatenate([resid[order], np.full(pad, np.inf, dtype=np.float32)]),
    )


def _boxes(
    flat: np.ndarray, errs: np.ndarray, resid: np.ndarray, order: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Each block's box (:class:`PcaCodes`): lo, hi ``(m, blocks)`` uint8 of its rows'
    codes ``flat`` ``(n, m)`` in the order ``order``; its largest ``errs`` and smallest and
    largest ``resid`` ``(blocks,)`` float64."""
    n, m = flat.shape
    blocks = -(-n // BLOCK)
    lo = np.empty((m, blocks), dtype=np.uint8)
    hi = np.empty((m, blocks), dtype=np.uint8)
    e = np.empty(blocks)
    r_lo = np.empty(blocks)
    r_hi = np.empty(blocks)
    for b in range(blocks):
        rows = order[b * BLOCK : (b + 1) * BLOCK]
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
    blocks = -(-len(order) // BLOCK)
    centres = np.empty((blocks, dims), dtype=np.float32)
    radii = np.empty(blocks)
    for b in range(blocks):
        part = np.asarray(rows[np.sort(order[b * BLOCK : (b + 1) * BLOCK])], dtype=np.float64)
        with np.errstate(over="ignore", invalid="ignore"):
            centres[b] = part.mean(axis=0)
        diff = part - centres[b].astype(np.float64)
        radii[b] = math.sqrt(float(np.einsum("ij,ij->i", diff, diff).max())) * (1.0 + 1e-12)
    radii[~np.isfinite(radii)] = np.inf
    centres[~np.isfinite(centres)] = 0.0
    return centres, radii


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
