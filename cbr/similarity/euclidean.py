"""Euclidean distance on (flattened) feature vectors.

On binary QMP vectors the squared distance is the number of mismatched features, so the
nearest cases are the ones with the most matched features.

Large case bases (``n >= prune_min_cases``, more than ``prune_dims`` dimensions) get an exact
lower-bound filter: with an orthonormal PCA basis ``B`` (``prune_dims`` columns, fitted on a
sample) and residual norms ``r``, ``|x - q|^2 >= |B'(x - q)|^2 + (r_x - r_q)^2`` (Pythagoras
plus the reverse triangle inequality). The bound for all cases costs ``n x prune_dims``; exact
distances are computed only for cases whose bound is below the k-th best candidate distance,
so the neighbours are exactly the brute-force ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .base import SimilarityMeasure, check_weighting, register_measure, smallest_k, weighted


def _matvec(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``a @ x`` without BLAS threads: a query is a matrix-vector product, memory-bound, and
    multi-threaded BLAS on a busy machine was measured 40-300x slower (thread hand-off)."""
    return np.einsum("ij,j->i", a, x)


def _sqnorm(x: np.ndarray) -> float:
    return float(np.einsum("i,i->", x, x))


@dataclass(frozen=True)
class _EuclideanIndex:
    rows: np.ndarray  # (n, D) float32 (float64 when exact=True)
    sq_norms: np.ndarray  # (n,) float64
    basis: np.ndarray | None = None  # (D, m) orthonormal, or None (no pruning)
    mean: np.ndarray | None = None  # (D,)
    proj: np.ndarray | None = None  # (n, m) float32
    proj_sq: np.ndarray | None = None  # (n,) float64
    resid: np.ndarray | None = None  # (n,) float64, norm of the part outside the basis


@register_measure("euclidean")
@dataclass(frozen=True)
class Euclidean(SimilarityMeasure):
    """``||a - b||_2`` over the flattened problem (a resampled fluent sequence or QMP vector).

    ``exact``: compute in float64 by differences instead of the float32 dot-product identity
    (slower; for tiny case bases or bit-exact comparisons).
    ``prune_min_cases`` / ``prune_dims``: when to use the PCA lower-bound filter, and its rank.
    ``centre`` / ``multiplier``: learned feature weighting (:mod:`cbr.weights`), one value per
    flattened column: the measure compares ``(x - centre) * multiplier``; None: raw values.
    """

    exact: bool = False
    prune_min_cases: int = 5000
    prune_dims: int = 32
    centre: tuple[float, ...] | None = None
    multiplier: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
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
        dtype = np.float64 if self.exact else np.float32
        rows: np.ndarray = np.ascontiguousarray(reps, dtype=dtype)
        sq = np.einsum("ij,ij->i", rows, rows, dtype=np.float64)
        n, dims = rows.shape
        if self.exact or n < self.prune_min_cases or dims <= 2 * self.prune_dims:
            return _EuclideanIndex(rows, sq)
        sample = rows[np.random.default_rng(0).choice(n, min(n, 1000), replace=False)]
        mean = sample.mean(axis=0, dtype=np.float64)
        centred = sample - mean
        # principal directions from the small Gram matrix (sample x sample), then QR so the
        # basis is orthonormal to rounding: the bound needs orthonormality, not optimality
        _, vecs = np.linalg.eigh(centred @ centred.T)
        top = centred.T @ vecs[:, ::-1][:, : self.prune_dims]  # (D, m)
        basis = np.ascontiguousarray(np.linalg.qr(top)[0], dtype=np.float32)
        proj = np.empty((n, basis.shape[1]), dtype=np.float32)
        resid = np.empty(n)
        m32 = mean.astype(np.float32)
        for a in range(0, n, 20000):  # chunks keep the centred copy small
            c = rows[a : a + 20000] - m32
            proj[a : a + 20000] = c @ basis
            tot = np.einsum("ij,ij->i", c, c, dtype=np.float64)
            inside = np.einsum(
                "ij,ij->i", proj[a : a + 20000], proj[a : a + 20000], dtype=np.float64
            )
            resid[a : a + 20000] = np.sqrt(np.maximum(tot - inside, 0.0))
        proj_sq = np.einsum("ij,ij->i", proj, proj, dtype=np.float64)
        return _EuclideanIndex(rows, sq, basis, mean, proj, proj_sq, resid)

    def _exact_rows(self, q: np.ndarray, index: _EuclideanIndex, idx: np.ndarray) -> np.ndarray:
        rows = index.rows[idx]
        if self.exact:
            return np.sqrt(((rows - q) ** 2).sum(axis=1))
        dots = _matvec(rows, q.astype(rows.dtype))
        sq = index.sq_norms[idx] - 2.0 * dots.astype(np.float64) + _sqnorm(q)
        return np.sqrt(np.maximum(sq, 0.0))

    def distances(self, query_rep: np.ndarray, index: Any) -> np.ndarray:
        if not isinstance(index, _EuclideanIndex):
            index = self.build_index(np.asarray(index, dtype=np.float64))
        q = np.asarray(query_rep, dtype=np.float64).reshape(-1)
        if self.exact:
            return np.sqrt(((index.rows - q) ** 2).sum(axis=1))
        # |c|^2 - 2 c.q + |q|^2: one matrix-vector product over the whole case base
        dots = _matvec(index.rows, q.astype(index.rows.dtype))
        sq = index.sq_norms - 2.0 * dots.astype(np.float64) + _sqnorm(q)
        return np.sqrt(np.maximum(sq, 0.0))

    def nearest(self, query_rep: np.ndarray, index: Any, k: int) -> tuple[np.ndarray, np.ndarray]:
        if not isinstance(index, _EuclideanIndex) or index.basis is None:
            return super().nearest(query_rep, index, k)
        assert index.mean is not None and index.proj is not None
        assert index.proj_sq is not None and index.resid is not None
        n = len(index.rows)
        k = min(int(k), n)
        q = np.asarray(query_rep, dtype=np.float64).reshape(-1)
        qc = q - index.mean
        qp = _matvec(index.basis.T, qc.astype(np.float32))
        qp_sq = _sqnorm(qp.astype(np.float64))
        q_res = np.sqrt(max(_sqnorm(qc) - qp_sq, 0.0))
        inside = index.proj_sq - 2.0 * _matvec(index.proj, qp).astype(np.float64) + qp_sq
        lb = np.sqrt(np.maximum(inside, 0.0) + (index.resid - q_res) ** 2)
        # start from the best bounds, then take every case whose bound can still beat them
        first = np.argpartition(lb, min(n - 1, max(4 * k, 64)))[: max(4 * k, 64)]
        kth = np.sort(self._exact_rows(q, index, first))[k - 1]
        slack = 1e-3 * kth + 1e-6  # float32 rounding in the bound
        cand = np.union1d(first, np.flatnonzero(lb <= kth + slack))
        idx, dist = smallest_k(self._exact_rows(q, index, cand), k)
        return cand[idx], dist
