"""Euclidean distance on (flattened) feature vectors.

On binary QMP vectors the squared distance is the number of mismatched features, so the
nearest cases are the ones with the most matched features.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .base import SimilarityMeasure, register_measure


@dataclass(frozen=True)
class _EuclideanIndex:
    rows: np.ndarray  # (n, D) float32 (float64 when exact=True)
    sq_norms: np.ndarray  # (n,) float64


@register_measure("euclidean")
@dataclass(frozen=True)
class Euclidean(SimilarityMeasure):
    """``||a - b||_2`` over the flattened problem (a resampled fluent sequence or QMP vector).

    ``exact``: compute in float64 by differences instead of the float32 dot-product identity
    (slower; for tiny case bases or bit-exact comparisons).
    """

    exact: bool = False

    def represent(self, problems: np.ndarray) -> np.ndarray:
        p = np.asarray(problems, dtype=np.float64)
        return p.reshape(len(p), -1)

    def build_index(self, reps: np.ndarray) -> Any:
        rows = np.ascontiguousarray(reps, dtype=np.float64 if self.exact else np.float32)
        sq = np.einsum("ij,ij->i", reps, reps, dtype=np.float64)
        return _EuclideanIndex(rows, sq)

    def distances(self, query_rep: np.ndarray, index: Any) -> np.ndarray:
        if not isinstance(index, _EuclideanIndex):
            index = self.build_index(np.asarray(index, dtype=np.float64))
        q = np.asarray(query_rep, dtype=np.float64).reshape(-1)
        if self.exact:
            return np.sqrt(((index.rows - q) ** 2).sum(axis=1))
        # |c|^2 - 2 c.q + |q|^2: one matrix-vector product over the whole case base
        dots = index.rows @ q.astype(index.rows.dtype)
        sq = index.sq_norms - 2.0 * dots.astype(np.float64) + float(q @ q)
        return np.sqrt(np.maximum(sq, 0.0))
