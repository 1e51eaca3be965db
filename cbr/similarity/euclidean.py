"""Euclidean distance on (flattened) feature vectors.

On binary QMP vectors the squared distance is the number of mismatched features, so the
nearest cases are the ones with the most matched features.

Every search returns exactly what :meth:`Euclidean.distances` and
:func:`cbr.similarity.base.smallest_k` give (ties -> lower case index): one compiled row kernel
(:func:`cbr.similarity.row_kernel._row_sq`, float32 rows, the squared differences summed in
float64) computes every distance a search returns; the paths differ only in which rows they hand
it, never in how a row's distance is computed. The bounds that choose the rows (BLAS products,
codes) are float32's, with their rounding allowed for.

- **Plain pass**: small case bases stream every row through the kernel with the k best kept
  on the fly (:func:`knn_scan`); from ``2^20`` values, one BLAS matrix-vector product on one
  thread, and only the rows within its rounding error bound (Higham) of the k-th best go to
  the kernel (:func:`select_from_products`).
- **Pruned search** for large case bases (``n >= prune_min_cases``, at least 40 dimensions;
  :func:`cbr.similarity.bounded_search._pca_knn`): with an orthonormal PCA basis ``B`` (``m``
  columns, a sixth of the dimensions, 8 to 128, fitted on a sample), every row's coordinates
  ``B'(x - mean)`` are stored as uint8 codes with each row's exact grid error ``e_x`` and the
  norm ``r_x`` of its part outside the basis, and ``|x - q|^2 >= max(|p_hat_q - p_hat_x| - e_q -
  e_x, 0)^2 + (r_x - r_q)^2``. The codes are bits allocated by variance: one grid whose step per
  dimension shrinks by a power of two (up to 8) where the dimension's range is narrower,
  so ``|p_hat_q - p_hat_x|^2`` is a fixed step squared times an exact integer sum, and they
  are stored dimension-major in blocks of :data:`cbr.similarity.grid_codes.BLOCK` rows so the
  integer kernel vectorises across rows: ``m`` bytes a case (a sixth of a float row's bytes at
  most). A case whose bound is below the running k-th distance gets its exact distance at once
  (kept by distance, then index, so the order cases are visited in never changes the answer).
  **Blocks of similar cases**: where the data has structure, the cases are stored in an
  order in which each block of :data:`~cbr.similarity.grid_codes.BLOCK` holds similar ones (a
  tree of balanced 2-means splits on the codes, :func:`cbr.similarity.grid_codes._tree_order`),
  and each block keeps its box of codes and a ball in the rows' space (centre and radius); per
  query one bound per block (:func:`cbr.similarity.bounded_search._block_order`: the box's grid
  distance and the ball's ``|q - c| - R``, both at most every one of its cases'), the blocks are
  visited nearest first and the pass stops at the first block whose bound exceeds the limit: the
  first blocks hold the neighbours, the k-th distance falls at once and most blocks are never
  read. Whether the blocks come out tight (median radius under
  :data:`cbr.similarity.grid_codes._TIGHT` of the cases' spread) is tried on a sample at build
  time; where they do not (unstructured data), the cases keep their own order, the exact
  distances stream from memory, and there are no boxes. The search measures its own pruning
  power: when more than ``FALLBACK`` of the cases pass the bound (unstructured data, where no
  low-rank bound prunes), the query is the quantized pass below, and later queries skip the PCA
  bound (re-probing every :data:`~cbr.similarity.pruning.PROBE_EVERY`).
- **Quantized pass** (VA-file style). On unstructured rows (no blocks of similar rows) of
  at most ``MAX_DIMS`` dimensions, on a CPU with AVX2: 4-bit codes of the whole rows,
  summed per query from a byte table by AVX2's byte shuffle, with each row's exact grid
  error (:mod:`cbr.similarity.nibbles`, :func:`nibble_knn`): half the bytes of the 8-bit
  codes and no multiplication, so a scan of 10^6 x 200 codes reads 100 MB. Elsewhere the same
  codes, kernel, blocks and pass as the PCA bound, on the identity basis:
  every whole row as uint8 codes (``x_hat = base + steps * code``, steps by range as above)
  with its exact grid error ``e_x``, so ``|q - x| >= |q_hat - x_hat| - e_q - e_x`` over a
  quarter of the float rows' bytes. On unstructured data the k-th neighbour lies far below
  the bulk and the grid error is small against that gap: all but ~0.01 % of the cases are
  pruned. When more than ``FALLBACK`` need their distance, the query is the plain pass (and
  later queries skip the quantized pass too, re-probing every
  :data:`~cbr.similarity.pruning.PROBE_EVERY`): an unprunable case base costs one plain pass per
  query.
- **Many queries** (:meth:`Euclidean.nearest_many`): one matrix product per block of queries
  (BLAS), then per query the cases whose product-based distance is within its rounding error
  bound of the k-th best are re-checked with the row kernel.

Rows are read where they lie: a read-only memory-mapped case matrix
(:mod:`casebase_store.case_matrix`) is used without a copy.

This module is the measure and which pass answers a query; the passes' parts are modules of
their own: the row kernel (:mod:`cbr.similarity.row_kernel`), the grid codes in blocks
(:mod:`cbr.similarity.grid_codes`), the search with their bound
(:mod:`cbr.similarity.bounded_search`) and the pruning record (:mod:`cbr.similarity.pruning`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from features.blas import one_blas_thread
from features.errors import ConfigError, InputError

from .base import SimilarityMeasure, check_weighting, check_whole, register_measure, weighted
from .bounded_search import codes_query, nibble_knn
from .grid_codes import PcaCodes, pca_basis, pca_codes
from .nibbles import HAS_SHUFFLE, MAX_DIMS, NibbleCodes, nibble_codes, nibble_tables
from .pruning import FALLBACK, PruningRecord
from .row_kernel import (
    all_distances,
    allowance_of,
    knn_scan,
    measured_distances,
    query32,
    select_from_products,
)

_U32 = 2.0**-24  # unit roundoff of float32


@dataclass(frozen=True, eq=False)
class _EuclideanIndex(PruningRecord):
    rows: np.ndarray  # (n, D) float32 (float64 when exact=True); may be a read-only memmap
    sq_norms: np.ndarray  # (n,) float64
    norms: np.ndarray  # (n,) float64
    pca: PcaCodes | None = None  # the rows' PCA codes, for the PCA bound
    max_norm: float = 0.0  # largest |row| (over rows without NaN or inf)
    # the whole rows' codes (identity basis; 4-bit on unstructured data): quantized pass
    codes: PcaCodes | _Nibbles | None = None
    # [running share of cases that survive the PCA bound, queries seen] (PruningRecord)
    pruning: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0]))

    @property
    def basis(self) -> np.ndarray | None:
        """The PCA bound's basis ``(D, m)``, or None when the index has no PCA bound."""
        return None if self.pca is None else self.pca.basis


@dataclass(frozen=True, eq=False)
class _Nibbles(PruningRecord):
    """The whole rows' 4-bit codes (:mod:`cbr.similarity.nibbles`) with their pruning record."""

    codes: NibbleCodes
    # [running share of cases given their distance, queries seen] (PruningRecord)
    pruning: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0]))


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

    leaves_out: ClassVar[bool] = True

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
        q32, q_sq = query32(q.reshape(-1))
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
        return all_distances(index.rows, q32)

    def distances_measured(
        self, query_rep: np.ndarray, index: Any, measured: np.ndarray
    ) -> np.ndarray:
        """The distance over the query's measured columns alone, scaled to all ``D`` as
        scikit-learn's ``nan_euclidean_distances`` scales a pair's present coordinates:
        ``sqrt(D / m * sum over the m measured columns of (x - q)^2)``, an estimate of the
        distance over all columns had the others differed as the measured ones do on
        average, so it stands against distances of all columns (the case base's own, the
        unknown judges' thresholds are calibrated on). One pass over every row (the row
        kernel's arithmetic, :func:`cbr.similarity.row_kernel.measured_distances`): the
        bounds of the pruned and quantized passes are over whole rows."""
        if not isinstance(index, _EuclideanIndex):
            index = self.build_index(np.asarray(index, dtype=np.float64))
        _check_width(np.size(query_rep), index)
        keep = np.asarray(measured, dtype=bool).reshape(-1)
        _check_width(len(keep), index)
        cols = np.flatnonzero(keep)
        if len(cols) in (0, len(keep)):  # nothing left out, or nothing to compare but fills
            return self.distances(query_rep, index)
        q = np.asarray(query_rep).reshape(-1)
        if not np.isfinite(q[cols]).all():
            raise InputError("euclidean: the query holds NaN or inf")
        q = np.where(keep, q, 0.0).astype(index.rows.dtype)  # a value left out weighs 0
        row: np.ndarray = measured_distances(index.rows, q, keep.astype(np.float64))
        return row

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
                out_i[a + j], out_d[a + j] = select_from_products(
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
    ``D 2^-53 (|c| + |q|)^2``, :func:`select_from_products` adds)."""
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
        return knn_scan(rows, q32, _ALL, k)
    n, dims = rows.shape
    gamma = dims * _U32 / (1.0 - dims * _U32)
    prods = _matvec_one_thread(rows, q32)
    return select_from_products(
        prods, rows, index.sq_norms, index.norms, q32, q_sq, _error(gamma, q_sq), k
    )


def _finite_max_norm(sq: np.ndarray) -> float:
    """Largest row norm over the rows whose squared norm is finite (0 when there is none)."""
    finite = sq[np.isfinite(sq)]
    return math.sqrt(float(finite.max())) if len(finite) else 0.0


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
    codes: PcaCodes,
    q32: np.ndarray,
    q_sq: float,
    k: int,
    max_count: int | None = None,
) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`cbr.similarity.bounded_search._pca_knn` for ``q32`` ``(D,)`` with ``codes`` (the
    PCA codes or the whole rows'), handing over once more than ``max_count`` (default:
    ``FALLBACK`` of the rows) need their distance."""
    if max_count is None:
        max_count = max(k, int(FALLBACK * len(index.rows)))
    grid, kernel, boxes = codes.kernel_args
    out: tuple[np.ndarray, np.ndarray, int] = codes_query(
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
    """:func:`nibble_knn` for ``q32`` ``(D,)``, handing over once more than ``max_count``
    (default: ``FALLBACK`` of the rows) need their distance."""
    if max_count is None:
        max_count = max(k, int(FALLBACK * len(index.rows)))
    luts, scale = nibble_tables(q32, nibbles.centres)
    rounding = allowance_of(index.rows.shape[1], index.max_norm, q_sq)
    out: tuple[np.ndarray, np.ndarray, int] = nibble_knn(
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
    pca = pca_codes(rows, pca_basis(rows, m))
    order, balls = None, None
    if pca is not None:
        order, balls = pca.order[: len(rows)], (pca.boxes[-2], pca.boxes[-1])
    if balls is not None and len(balls[1]) == 0:
        balls = None  # the rows' own order: no boxes for the whole rows either
    codes: PcaCodes | _Nibbles | None = None
    if balls is None and rows.shape[1] <= MAX_DIMS and HAS_SHUFFLE:  # half the bytes, no product
        nibbles = nibble_codes(rows)
        codes = None if nibbles is None else _Nibbles(nibbles)
    if codes is None and rows.shape[1] * 255**2 < 2**31:
        codes = pca_codes(rows, None, order, balls)
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


__all__ = ["FALLBACK", "MAX_DIMS", "SMALL_PRODUCT", "Euclidean"]
