"""Similarity measures as plug-ins, found by name (see :mod:`cbr.similarity.base`).

Built in: ``euclidean`` (feature vectors; mismatch count on binary QMP vectors), ``dtw``
(sequences, Sakoe–Chiba band, exact lower-bound cascade), ``signature`` (iisignature).
"""

from .base import (
    SimilarityMeasure,
    available_measures,
    get_measure,
    register_measure,
    smallest_k,
)
from .dtw import DTW
from .euclidean import Euclidean
from .signature import Signature

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
