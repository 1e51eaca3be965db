"""Similarity measures as plug-ins, found by name (see :mod:`cbr.similarity.base`).

Built in: ``euclidean`` (feature vectors; mismatch count on binary QMP vectors), ``dtw``
(sequences, Sakoe–Chiba band, exact lower-bound cascade), ``signature`` (iisignature).
``DTW`` and ``Signature`` are imported on first use (numba and scipy, iisignature), as
:func:`get_measure` imports a built-in measure's module when it is first asked for.
"""

from typing import TYPE_CHECKING, Any

from .base import (
    SimilarityMeasure,
    available_measures,
    get_measure,
    register_measure,
    smallest_k,
)
from .euclidean import Euclidean

if TYPE_CHECKING:
    from .dtw import DTW
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


def __getattr__(name: str) -> Any:
    if name == "DTW":
        from .dtw import DTW

        return DTW
    if name == "Signature":
        from .signature import Signature

        return Signature
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
