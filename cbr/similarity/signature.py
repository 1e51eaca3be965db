"""Path signatures (iisignature) compared by Euclidean distance.

A problem sequence ``(frames, channels)`` becomes a path; optional augmentations:
``basepoint`` prepends the origin (signatures are translation invariant; without it a state
held the whole clip, e.g. an arm raised throughout, would be invisible), ``time`` adds a
channel running 0 -> 1 (makes the signature see speed/parametrisation),
``lead_lag`` doubles the channels with the lead-lag transform (level 2 then carries the
quadratic variation). The truncated signature up to ``depth`` has
``sum_{m=1..depth} d^m`` terms for ``d`` path channels; signatures are cached per case in the
store (kind ``signature:depth=..,time=..,lead_lag=..``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import iisignature
import numpy as np

from features.errors import ConfigError, InputError

from .base import SimilarityMeasure, check_whole, register_measure
from .euclidean import Euclidean


def lead_lag(paths: np.ndarray) -> np.ndarray:
    """Lead-lag transform of ``(n, L, d)`` paths -> ``(n, 2L - 1, 2d)`` (lead, lag)."""
    rep = np.repeat(paths, 2, axis=1)
    lead = rep[:, 1:]
    lag = rep[:, :-1]
    return np.concatenate([lead, lag], axis=2)


def augment(
    paths: np.ndarray, *, time: bool, lead_lag_: bool, basepoint: bool = False
) -> np.ndarray:
    """Apply basepoint, lead-lag then time augmentation to ``(n, L, d)`` paths."""
    p = np.asarray(paths, dtype=np.float64)
    if basepoint:  # start every path at the origin: the signature then sees absolute levels
        p = np.concatenate([np.zeros_like(p[:, :1]), p], axis=1)
    if lead_lag_:
        p = lead_lag(p)
    if time:
        t = np.broadcast_to(np.linspace(0.0, 1.0, p.shape[1])[None, :, None], (*p.shape[:2], 1))
        p = np.concatenate([t, p], axis=2)
    return p


@register_measure("signature")
@dataclass(frozen=True, repr=False)  # SimilarityMeasure's repr: one line
class Signature(SimilarityMeasure):
    """Euclidean distance between truncated path signatures of the problem sequences.

    ``prune_dims``: rank of the exact PCA lower-bound filter used on large case bases (see
    :mod:`cbr.similarity.euclidean`); signatures spread over more directions than raw
    sequences, so the filter needs more of them to be selective.
    """

    compares_sequences: ClassVar[bool] = True

    depth: int = 2
    time: bool = True
    lead_lag: bool = False
    basepoint: bool = True
    prune_dims: int = 128

    def __post_init__(self) -> None:
        check_whole("signature", depth=self.depth, prune_dims=self.prune_dims)
        if not 1 <= int(self.depth) <= 6:
            raise ConfigError(f"depth must be 1..6, got {self.depth!r}", "similarity signature")

    def cache_kind(self, problem_shape: tuple[int, ...]) -> str | None:
        del problem_shape  # a signature's settings alone fix its representation
        return (
            f"signature:depth={int(self.depth)},time={int(bool(self.time))},"
            f"lead_lag={int(bool(self.lead_lag))},basepoint={int(bool(self.basepoint))}"
        )

    def represent(self, problems: np.ndarray) -> np.ndarray:
        """``(n, L, d)`` sequences -> ``(n, sig_len)`` signatures."""
        p = np.asarray(problems, dtype=np.float64)
        if p.ndim == 2:
            p = p[:, :, None]
        if p.ndim != 3:
            raise ConfigError(
                f"signature compares sequences (n, frames, channels), got {p.shape}",
                "similarity signature",
            )
        if not np.isfinite(p).all():  # else the Euclidean search of the signatures says so
            raise InputError(
                "signature: the problems hold NaN or inf: fill missing values before comparing"
            )
        path = np.ascontiguousarray(
            augment(p, time=self.time, lead_lag_=self.lead_lag, basepoint=self.basepoint)
        )
        if len(path) == 0:
            return np.zeros((0, iisignature.siglength(path.shape[2], int(self.depth))))
        return np.asarray(iisignature.sig(path, int(self.depth)), dtype=np.float64)

    def _euclidean(self) -> Euclidean:
        return Euclidean(prune_dims=int(self.prune_dims))

    def build_index(self, reps: np.ndarray) -> Any:
        return self._euclidean().build_index(reps)

    def distances(self, query_rep: np.ndarray, index: Any) -> np.ndarray:
        return self._euclidean().distances(query_rep, index)

    def nearest(self, query_rep: np.ndarray, index: Any, k: int) -> tuple[np.ndarray, np.ndarray]:
        return self._euclidean().nearest(query_rep, index, k)
