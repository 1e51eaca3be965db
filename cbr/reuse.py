"""Reuse: the solution from the retrieved cases by a similarity-weighted vote."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .retrieve import Retrieval

Weights = Literal["distance", "uniform"]


@dataclass(frozen=True)
class Solution:
    """label, confidence in [0, 1] (the winner's share of the vote), proba ``(n_classes,)``."""

    label: str
    confidence: float
    proba: np.ndarray


def vote_weights(distances: np.ndarray, weights: Weights) -> np.ndarray:
    """Vote weight per retrieved case: 1 (uniform) or 1 / distance (exact matches dominate)."""
    if weights == "uniform":
        return np.ones_like(distances, dtype=np.float64)
    d = np.asarray(distances, dtype=np.float64)
    zero = d <= 1e-12
    if zero.any():  # identical cases decide alone, as in scikit-learn's KNeighborsClassifier
        return zero.astype(np.float64)
    return 1.0 / d


def reuse(retrieval: Retrieval, classes: np.ndarray, weights: Weights = "distance") -> Solution:
    """Weighted vote over ``classes`` (labels as str, in the caller's order); ties go to the
    first class in that order."""
    w = vote_weights(retrieval.distances, weights)
    where = {str(c): i for i, c in enumerate(classes)}
    pos = np.array([where[str(lab)] for lab in retrieval.labels], dtype=np.int64)
    proba = np.bincount(pos, weights=w, minlength=len(classes)).astype(np.float64)
    total = proba.sum()
    proba = proba / total if total > 0 else np.full(len(classes), 1.0 / len(classes))
    best = int(np.argmax(proba))
    return Solution(str(classes[best]), float(proba[best]), proba)
