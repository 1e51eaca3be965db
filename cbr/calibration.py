"""A confidence that is a probability: the winner's vote share calibrated, in fit, into the
chance that the answer is right, and the expected calibration error that measures it.

The training clips are classified held out as new people are (each by the cases of the other
subjects, or of the other clips when subjects are unknown: :func:`held_out`; with learned
feature weights, by case bases whose weights were learned without the clip's subject:
:func:`cbr.fitting.inner_loso_votes`); Platt scaling (a logistic curve of the vote share's
log-odds, fitted to whether the answer was right, with Platt's smoothed targets so a handful
of training clips do not make it certain; Platt 1999, as scikit-learn's ``sigmoid``
calibration) maps their winning vote shares to probabilities. The map is stored as knots of a
monotone piecewise-linear curve with the case base, so a loaded classifier answers with the
same confidences. Isotonic regression was tried too: on held-out UI-PRMD subjects it left a
correct-vs-incorrect ECE of 0.050 where Platt scaling leaves 0.038 (one case base per movement
learns from about 140 clips, too few for a free-form curve).
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


#: the vote shares the calibration curve is stored at (linear between them)
KNOTS = np.linspace(0.0, 1.0, 101)
_CLIP = 1e-3  # shares of 0 and 1 have infinite log-odds: taken as 0.001 and 0.999


def log_odds(share: np.ndarray) -> np.ndarray:
    p = np.clip(np.asarray(share, dtype=np.float64), _CLIP, 1.0 - _CLIP)
    return np.asarray(np.log(p / (1.0 - p)), dtype=np.float64)


def platt(x: np.ndarray, right: np.ndarray) -> tuple[float, float]:
    """Slope and intercept of ``P(right) = 1 / (1 + exp(-(a x + b)))`` by maximum likelihood
    on Platt's targets: ``(N+ + 1) / (N+ + 2)`` for a right answer, ``1 / (N- + 2)`` for a
    wrong one."""
    from scipy.optimize import minimize

    r = np.asarray(right, dtype=bool)
    n1, n0 = float(r.sum()), float((~r).sum())
    t = np.where(r, (n1 + 1.0) / (n1 + 2.0), 1.0 / (n0 + 2.0))

    def loss(ab: np.ndarray) -> tuple[float, np.ndarray]:
        z = ab[0] * x + ab[1]
        nll = np.sum(t * np.logaddexp(0.0, -z) + (1.0 - t) * np.logaddexp(0.0, z))
        g = 1.0 / (1.0 + np.exp(-z)) - t  # d nll / d z
        return float(nll), np.array([float(np.sum(g * x)), float(np.sum(g))])

    a, b = minimize(loss, np.array([1.0, 0.0]), jac=True, method="L-BFGS-B").x
    return float(a), float(b)


def calibrate_confidence(share: np.ndarray, right: np.ndarray, basis: str) -> ConfidenceCalibration:
    """Platt scaling of the winning vote ``share`` ``(q,)`` to whether the answer was right
    ``(q,)``; a curve that would fall (a share that is right less often the higher it is)
    becomes flat at the smoothed accuracy."""
    share = np.asarray(share, dtype=np.float64)
    right = np.asarray(right, dtype=bool)
    if len(share) == 0:
        return UNCALIBRATED
    accuracy = (float(right.sum()) + 1.0) / (len(right) + 2.0)
    if right.all() or not right.any():
        y = np.full(len(KNOTS), accuracy)
    else:
        a, b = platt(log_odds(share), right)
        y = (
            1.0 / (1.0 + np.exp(-(a * log_odds(KNOTS) + b)))
            if a > 0
            else np.full(len(KNOTS), accuracy)
        )
    return ConfidenceCalibration(
        tuple(float(v) for v in KNOTS), tuple(float(v) for v in y), basis, len(share),
        float(right.mean()),
    )  # fmt: skip


def expected_calibration_error(
    confidence: np.ndarray, right: np.ndarray, bins: int = ECE_BINS
) -> float:
    """ECE (Naeini et al. 2015; Guo et al. 2017): over ``bins`` equal-width confidence bins,
    the share of clips in the bin times the gap between their accuracy and mean confidence."""
    c = np.asarray(confidence, dtype=np.float64)
    r = np.asarray(right, dtype=np.float64)
    if len(c) == 0:
        return float("nan")
    which = _bin_of(c, bins)
    total = 0.0
    for b in range(bins):
        sel = which == b
        if sel.any():
            total += sel.mean() * abs(r[sel].mean() - c[sel].mean())
    return float(total)


def ece_interval(
    confidence: np.ndarray,
    right: np.ndarray,
    bins: int = ECE_BINS,
    resamples: int = 2000,
    seed: int = 0,
) -> tuple[float, float]:
    """The bootstrap 95 % interval (percentiles 2.5 and 97.5) of the ECE of ``confidence``
    ``(q,)`` against ``right`` ``(q,)``, clips resampled with replacement ``resamples`` times:
    what of an ECE is noise at a few hundred clips. All resamples at once: a bin's term is
    ``|sum(right) - sum(confidence)| / q`` over its clips."""
    c = np.asarray(confidence, dtype=np.float64)
    r = np.asarray(right, dtype=np.float64)
    q = len(c)
    if q == 0:
        return float("nan"), float("nan")
    pick = np.random.default_rng(seed).integers(0, q, (resamples, q))
    ece = _resampled_eces(_bin_of(c, bins), pick, (r - c)[pick], bins)
    lo, hi = np.percentile(ece, [2.5, 97.5])
    return float(lo), float(hi)


def ece_if_calibrated(
    confidence: np.ndarray,
    bins: int = ECE_BINS,
    resamples: int = 2000,
    seed: int = 0,
) -> tuple[float, float]:
    """What a perfectly calibrated confidence scores at these confidences ``(q,)``: the
    median and 95th percentile of the ECE when each clip's answer is right with exactly its
    confidence (consistency resampling, Bröcker and Smith 2007: clips resampled with
    replacement, then right or wrong drawn with their confidence). An ECE above the 95th
    percentile is a miscalibration; below it, at this many clips, the ECE cannot tell."""
    c = np.asarray(confidence, dtype=np.float64)
    q = len(c)
    if q == 0:
        return float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    pick = rng.integers(0, q, (resamples, q))
    drawn = rng.uniform(size=(resamples, q)) < c[pick]
    ece = _resampled_eces(_bin_of(c, bins), pick, drawn - c[pick], bins)
    mid, high = np.percentile(ece, [50, 95])
    return float(mid), float(high)


def _bin_of(confidence: np.ndarray, bins: int) -> np.ndarray:
    """The equal-width bin ``(q,)`` of each confidence ``(q,)`` (the ECE's bins)."""
    edges = np.linspace(0.0, 1.0, bins + 1)
    which: np.ndarray = np.clip(np.digitize(confidence, edges[1:-1], right=True), 0, bins - 1)
    return which


def _resampled_eces(which: np.ndarray, pick: np.ndarray, gaps: np.ndarray, bins: int) -> np.ndarray:
    """The ECE of every resample ``(resamples,)``: ``pick`` ``(resamples, q)`` the clips drawn,
    ``gaps`` ``(resamples, q)`` their right (1/0) minus confidence, ``which`` ``(q,)`` each
    clip's bin; all resamples at once, a bin's term ``|sum of gaps| / q``."""
    resamples, q = pick.shape
    slot = (which[pick] + bins * np.arange(resamples)[:, None]).ravel()
    gap = np.bincount(slot, weights=gaps.ravel(), minlength=resamples * bins)
    return np.asarray(np.abs(gap.reshape(resamples, bins)).sum(axis=1) / q)
