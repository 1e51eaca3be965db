"""A confidence that is a probability: the winner's vote share calibrated, in fit, into the
chance that the answer is right, and the expected calibration error that measures it.

The training clips are classified held out as new people are (each by the cases of the other
subjects, or of the other clips when subjects are unknown: :func:`held_out`); isotonic
regression (scikit-learn's ``IsotonicRegression``) maps their winning vote shares to whether
the answer was right. The map is monotone and piecewise linear, stored as its knots with the
case base, so a loaded classifier answers with the same confidences.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .casebase import CaseBase
from .reuse import Weights, vote

#: bins of the expected calibration error (equal width over [0, 1], as Guo et al. 2017)
ECE_BINS = 10


@dataclass(frozen=True)
class HeldOut:
    """The training clips classified held out: ``nearest`` ``(q,)`` distance to the nearest
    case of another group, ``share`` ``(q,)`` the winning vote share and ``right`` ``(q,)``
    whether the winner was the clip's label."""

    nearest: np.ndarray
    share: np.ndarray
    right: np.ndarray


def held_out(
    cb: CaseBase,
    queries: np.ndarray,
    labels: np.ndarray,
    groups: np.ndarray,
    case_groups: np.ndarray,
    k: int,
    weights: Weights = "distance",
) -> HeldOut:
    """Each query ``(q, *problem_shape)`` (true label ``labels[i]``, group ``groups[i]``)
    classified by the ``k`` nearest cases of other groups (``case_groups`` ``(n_cases,)``),
    voting as the classifier does (:func:`cbr.reuse.vote`)."""
    classes, codes = np.unique(cb.labels.astype(str), return_inverse=True)
    measure, index = cb.measure, cb.index
    q = len(queries)
    dist = np.full((q, k), np.inf)
    code = np.zeros((q, k), dtype=np.int64)
    for i, p in enumerate(queries):  # one full scan per query: the measure's array work
        d = measure.distances(measure.represent_query(p), index)
        d = np.where(case_groups == groups[i], np.inf, d)
        top = np.argsort(d, kind="stable")[:k]
        dist[i, : len(top)], code[i, : len(top)] = d[top], codes[top]
    proba = vote(dist, code, len(classes), weights)
    win = np.argmax(proba, axis=1)
    right = classes[win] == np.asarray(labels).astype(str)
    return HeldOut(dist[:, 0], proba[np.arange(q), win], right)


@dataclass(frozen=True)
class ConfidenceCalibration:
    """Monotone piecewise-linear map from a winning vote share to the probability that the
    answer is right: knots ``x`` (shares) and ``y`` (probabilities); ``basis`` how the training
    clips were held out, ``n`` how many; ``accuracy`` their held-out accuracy."""

    x: tuple[float, ...]
    y: tuple[float, ...]
    basis: str
    n: int
    accuracy: float

    def __call__(self, share: float) -> float:
        if not self.x:
            return float(share)
        return float(np.interp(float(share), self.x, self.y))

    def to_dict(self) -> dict[str, Any]:
        return {"x": list(self.x), "y": list(self.y), "basis": self.basis, "n": self.n,
                "accuracy": self.accuracy}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ConfidenceCalibration:
        x = tuple(float(v) for v in d["x"])
        y = tuple(float(v) for v in d["y"])
        if len(x) != len(y) or any(b < a for a, b in zip(x, x[1:], strict=False)):
            raise ValueError("calibration knots must be paired and increasing")
        return cls(x, y, str(d["basis"]), int(d["n"]), float(d["accuracy"]))


#: no calibration: the confidence is the vote share (case bases stored before calibration)
UNCALIBRATED = ConfidenceCalibration((), (), "none", 0, float("nan"))


def calibrate_confidence(share: np.ndarray, right: np.ndarray, basis: str) -> ConfidenceCalibration:
    """Isotonic regression of ``right`` ``(q,)`` on the winning vote ``share`` ``(q,)``."""
    from sklearn.isotonic import IsotonicRegression

    share = np.asarray(share, dtype=np.float64)
    right = np.asarray(right, dtype=np.float64)
    if len(share) == 0:
        return UNCALIBRATED
    iso = IsotonicRegression(y_min=0.0, y_max=1.0, increasing=True, out_of_bounds="clip")
    iso.fit(share, right)
    x = tuple(float(v) for v in iso.X_thresholds_)
    y = tuple(float(v) for v in iso.y_thresholds_)
    return ConfidenceCalibration(x, y, basis, len(share), float(right.mean()))


def expected_calibration_error(
    confidence: np.ndarray, right: np.ndarray, bins: int = ECE_BINS
) -> float:
    """ECE (Naeini et al. 2015; Guo et al. 2017): over ``bins`` equal-width confidence bins,
    the share of clips in the bin times the gap between their accuracy and mean confidence."""
    c = np.asarray(confidence, dtype=np.float64)
    r = np.asarray(right, dtype=np.float64)
    if len(c) == 0:
        return float("nan")
    edges = np.linspace(0.0, 1.0, bins + 1)
    which = np.clip(np.digitize(c, edges[1:-1], right=True), 0, bins - 1)
    total = 0.0
    for b in range(bins):
        sel = which == b
        if sel.any():
            total += sel.mean() * abs(r[sel].mean() - c[sel].mean())
    return float(total)
