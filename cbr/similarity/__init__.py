"""Similarity measures as plug-ins, found by name (see :mod:`cbr.similarity.base`).

Built in: ``euclidean`` (feature vectors; mismatch count on binary QMP vectors), ``dtw``
(sequences, Sakoe–Chiba band, exact lower-bound cascade), ``signature`` (iisignature).

Only the registry (:mod:`cbr.similarity.registry`) loads with the package: the names below are
imported on first use, and :func:`get_measure` imports a built-in measure's module when it is
first asked for, so that naming the measures (``posecbr --help``) loads neither numpy nor numba,
scipy or iisignature.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .registry import available_measures, get_measure, register_measure

if TYPE_CHECKING:
    from .base import SimilarityMeasure, smallest_k
    from .dtw import DTW
    from .euclidean import Euclidean
    from .signature import Signature

_LAZY = {
    "SimilarityMeasure": ".base",
    "smallest_k": ".base",
    "DTW": ".dtw",
    "Euclidean": ".euclidean",
    "Signature": ".signature",
}

__all__ = [
    "DTW",
    "Euclidean",
    "Signature",
    "SimilarityMeasure",
    "available_measures",
    "get_measure",
    "register_measure",
    "smallest_k",
]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
