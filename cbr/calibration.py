"""A confidence that is a probability: the answer's soft vote calibrated, in fit, into the
chance that the answer is right, and the expected calibration error that measures it.

The answer is the k nearest cases' vote (:func:`cbr.reuse.vote`); its confidence comes from a
finer score than the k-vote's share (with k = 5 it takes six values, and most clips get 1.0,
whether the answer is right or not): the **soft vote** of the ``NEIGHBOURS`` nearest cases,
each case weighing ``exp(-(d / d_1)^2 / T)`` for its class (``d_1`` the query's nearest-case
distance, so the score depends on how much farther the other classes lie than the nearest
case, not on how dense the case base is), the answer's share of the weight being the score.
The temperature ``T`` is fitted to the training clips classified held out as new people are
(each by the cases of the other subjects, or of the other clips when subjects are unknown:
:func:`held_out`; with learned feature weights, by case bases whose weights were learned
without the clip's subject: :func:`cbr.fitting.inner_loso_neighbours`) by log loss
(temperature scaling, Guo et al. 2017); Platt scaling (a logistic curve of the score's
log-odds, fitted to whether the answer was right, with Platt's smoothed targets so a handful
of training clips do not make it certain; Platt 1999, as scikit-learn's ``sigmoid``
calibration) then maps the scores to probabilities. The map is stored as knots of a monotone
piecewise-linear curve with the case base, with ``T`` and the neighbourhood, so a loaded
classifier answers with the same confidences; a calibration stored before the soft vote maps
the vote share. Why not the vote share: a held-out training clip is classified by a case base
with one subject fewer than the deployed one, and the share means something else there (an
inner case base of one subject votes unanimously and rightly on its held-out clips where the
deployed case base's unanimous votes on a new subject are not always right:
docs/measurements.md, "The diagnosis with the vote share"); the relative distances carry over
between case-base sizes better. Isotonic regression was tried too and calibrated worse: a
case base learns from too few clips for a free-form curve (docs/measurements.md, "Figures
behind the code's rules: Isotonic regression for the confidence").
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .casebase import CaseBase, overlapping
from .reuse import EXACT, Weights, class_balance, vote

#: bins of the expected calibration error (equal width over [0, 1], as Guo et al. 2017)
ECE_BINS = 10
#: the nearest cases whose soft vote is the confidence's score (the answer is the k-vote's)
NEIGHBOURS = 10
#: the log loss of the temperature fit mixes this much of a uniform guess into the soft vote:
#: a true class absent from the neighbourhood would otherwise cost an infinite loss
_FLOOR = 1e-3


@dataclass(frozen=True)
class HeldOut:
    """The training clips classified held out: ``nearest`` ``(q,)`` distance to the nearest
    case of another group, ``share`` ``(q,)`` the winning vote share, ``right`` ``(q,)``
    whether the winner was the clip's label, ``answer`` ``(q,)`` the winner's class code;
    ``distances`` and ``codes`` ``(q, K)`` the ``K``
    nearest such cases (nearest first; ``inf`` where fewer) and their class codes, ``truth``
    ``(q,)`` the clip's class code and ``k`` the cases that voted."""

    nearest: np.ndarray
    share: np.ndarray
    right: np.ndarray
    answer: np.ndarray
    distances: np.ndarray
    codes: np.ndarray
    truth: np.ndarray
    k: int


def answered(h: HeldOut) -> HeldOut:
    """The held-out clips that had a case to answer them: a clip whose group held every case
    of the case base (one subject left after editing, held out) had none, and a clip whose
    group held every case of its activity (truth -1: the only subject who did it) could not
    be answered right; neither says how often an answer to a trained activity is right."""
    d = np.asarray(h.distances, dtype=np.float64)
    keep = np.isfinite(d[:, 0]) if d.shape[1] else np.zeros(len(d), dtype=bool)
    keep &= np.asarray(h.truth) >= 0
    if keep.all():
        return h
    return HeldOut(h.nearest[keep], h.share[keep], h.right[keep], h.answer[keep],
                   h.distances[keep], h.codes[keep], h.truth[keep], h.k)  # fmt: skip


def held_elsewhere(
    labels: np.ndarray, groups: np.ndarray, case_labels: np.ndarray, case_groups: np.ndarray
) -> np.ndarray:
    """Whether a case of each clip's label ``labels`` ``(q,)`` lies outside the clip's own
    group ``groups`` ``(q,)`` (cases ``case_labels`` of ``case_groups``, ``(n,)``): whether
    the clip, held out with its group, could be answered right."""
    labels, case_labels = np.asarray(labels).astype(str), np.asarray(case_labels).astype(str)
    own = np.char.add(np.char.add(labels, "\0"), np.asarray(groups).astype(str))
    cases = np.char.add(np.char.add(case_labels, "\0"), np.asarray(case_groups).astype(str))
    return np.asarray(_count(labels, case_labels) > _count(own, cases))


def _count(keys: np.ndarray, values: np.ndarray) -> np.ndarray:
    """How many of ``values`` ``(n,)`` equal each of ``keys`` ``(q,)``."""
    names, counts = np.unique(values, return_counts=True)
    if not len(names):
        return np.zeros(len(keys), dtype=np.int64)
    at = np.clip(np.searchsorted(names, keys), 0, len(names) - 1)
    return np.asarray(np.where(names[at] == keys, counts[at], 0))


@dataclass(frozen=True)
class HoldOut:
    """One way to hold the cases out of a query's neighbours (:func:`held_out`): the queries'
    groups ``(q,)``, the cases' ``(n_cases,)`` and, optionally, the queries' and the cases'
    frame ranges (the cases overlapping a query's frames held out with it too)."""

    groups: np.ndarray
    case_groups: np.ndarray
    frames: tuple[np.ndarray, np.ndarray] | None = None


def held_out(
    cb: CaseBase,
    queries: np.ndarray,
    labels: np.ndarray,
    groups: np.ndarray,
    case_groups: np.ndarray,
    k: int,
    weights: Weights = "distance",
    neighbours: int = NEIGHBOURS,
    frames: tuple[np.ndarray, np.ndarray] | None = None,
    balanced: bool = False,
) -> HeldOut:
    """Each query ``(q, *problem_shape)`` (true label ``labels[i]``, group ``groups[i]``)
    classified by the ``k`` nearest cases of other groups (``case_groups`` ``(n_cases,)``),
    voting as the classifier does (:func:`cbr.reuse.vote`), with its ``max(k, neighbours)``
    nearest such cases for the soft vote (``balanced``: each class's votes divided by its
    share of ``cb``'s cases, :func:`cbr.reuse.class_balance`). ``frames``: the queries' and
    the cases' frame ranges in their one recording, ``(q, 2)`` and ``(n_cases, 2)`` (start,
    end; -1 where not known): the cases whose frames overlap a query's are held out with it
    too (windows cut from one recording every 0.5 s overlap their neighbours, near copies of
    them)."""
    way = HoldOut(groups, case_groups, frames)
    return held_out_ways(cb, queries, labels, [way], k, weights, neighbours, balanced)[0]


def held_out_ways(
    cb: CaseBase,
    queries: np.ndarray,
    labels: np.ndarray,
    ways: Sequence[HoldOut],
    k: int,
    weights: Weights = "distance",
    neighbours: int = NEIGHBOURS,
    balanced: bool = False,
) -> list[HeldOut]:
    """:func:`held_out` of the same queries held out in each of several ``ways``, one
    :class:`HeldOut` per way, from one scan of the case base per query (the scan is the
    work: its distances do not depend on what is held out)."""
    classes, codes = np.unique(cb.labels.astype(str), return_inverse=True)
    measure, index = cb.measure, cb.index
    q, wide = len(queries), max(int(k), int(neighbours))
    dist = [np.full((q, wide), np.inf) for _ in ways]
    code = [np.zeros((q, wide), dtype=np.int64) for _ in ways]
    held = [held_elsewhere(labels, w.groups, cb.labels, w.case_groups) for w in ways]
    case_labels = cb.labels.astype(str)
    for i, p in enumerate(queries):  # one full scan per query: the measure's array work
        d = measure.distances(measure.represent_query(p), index)
        for w, way in enumerate(ways):
            out = way.case_groups == way.groups[i]
            if way.frames is not None:
                out = out | overlapping(way.frames[0][i], way.frames[1])
                held[w][i] = bool(np.any(~out & (case_labels == str(labels[i]))))
            mine = np.where(out, np.inf, d)
            top = np.argsort(mine, kind="stable")[:wide]
            dist[w][i, : len(top)], code[w][i, : len(top)] = mine[top], codes[top]
    balance = class_balance(cb.labels, classes) if balanced else None
    return [
        held_out_votes(dist[w], code[w], classes, labels, int(k), weights, held[w], balance)
        for w in range(len(ways))
    ]


def held_out_votes(
    distances: np.ndarray,
    codes: np.ndarray,
    classes: np.ndarray,
    labels: np.ndarray,
    k: int,
    weights: Weights = "distance",
    held: np.ndarray | None = None,
    balance: np.ndarray | None = None,
) -> HeldOut:
    """:class:`HeldOut` of clips whose nearest held-out cases are ``distances`` ``(q, K)``
    (nearest first) of class codes ``codes`` ``(q, K)`` into ``classes`` ``(C,)`` (sorted
    str), the first ``k`` of them voting; ``labels`` ``(q,)`` the clips' labels. A label no
    case has gets code -1 (its answers are all wrong), and so does a clip whose label no case
    it was held out against has (``held`` ``(q,)`` False: :func:`held_elsewhere`)."""
    labels = np.asarray(labels).astype(str)
    proba = vote(distances[:, :k], codes[:, :k], len(classes), weights, balance)
    win = np.argmax(proba, axis=1)
    at = np.clip(np.searchsorted(classes, labels), 0, len(classes) - 1)
    truth = np.where(classes[at] == labels, at, -1)
    if held is not None:
        truth = np.where(np.asarray(held, dtype=bool), truth, -1)
    share = proba[np.arange(len(win)), win]
    return HeldOut(distances[:, 0], share, win == truth, win, distances, codes, truth, int(k))


def soft_vote(
    distances: np.ndarray, codes: np.ndarray, n_classes: int, temperature: float
) -> np.ndarray:
    """The soft vote ``(q, n_classes)`` of each query's nearest cases, ``distances`` ``(q, K)``
    (nearest first, ``inf``: no case) of classes ``codes`` ``(q, K)``: a case weighs
    ``exp(-(d / d_1)^2 / temperature)`` for its class, ``d_1`` the query's nearest distance
    (an exact match, ``d_1 = 0``, takes all the weight with the cases at distance 0)."""
    d = np.asarray(distances, dtype=np.float64)
    present = np.isfinite(d)
    d1 = np.maximum(np.where(present[:, :1], d[:, :1], 1.0), EXACT)
    e = np.where(present, -((np.where(present, d, 0.0) / d1) ** 2) / float(temperature), -np.inf)
    # the nearest case weighs 1 (no underflow), a missing one nothing (a query without any
    # case has no maximum to subtract: 0)
    top = np.where(present.any(axis=1, keepdims=True), e.max(axis=1, keepdims=True), 0.0)
    w = np.exp(e - top)
    rows = np.repeat(np.arange(len(d)), d.shape[1])
    out = np.zeros((len(d), n_classes))
    np.add.at(out, (rows, np.where(present, codes, 0).ravel()), w.ravel())
    total = out.sum(axis=1, keepdims=True)
    # a query with no case at all has no vote: all zeros, never NaN
    return np.asarray(np.divide(out, total, out=np.zeros_like(out), where=total > 0))


def fit_temperature(
    distances: np.ndarray, codes: np.ndarray, truth: np.ndarray, n_classes: int
) -> float:
    """The temperature of :func:`soft_vote` that minimises the log loss of the clips' true
    classes ``truth`` ``(q,)`` (-1: a class no case has, left out), over ``log T`` in
    [-8, 8]."""
    from scipy.optimize import minimize_scalar

    known = np.asarray(truth) >= 0
    d, c, t = distances[known], codes[known], np.asarray(truth)[known]
    if len(t) == 0:
        return 1.0

    def loss(log_t: float) -> float:
        p = soft_vote(d, c, n_classes, float(np.exp(log_t)))[np.arange(len(t)), t]
        return float(-np.mean(np.log((1.0 - _FLOOR) * p + _FLOOR / n_classes)))

    return float(np.exp(minimize_scalar(loss, bounds=(-8.0, 8.0), method="bounded").x))


@dataclass(frozen=True)
class ConfidenceCalibration:
    """Monotone piecewise-linear map from a score of the answer to the probability that it is
    right: knots ``x`` (scores) and ``y`` (probabilities); ``basis`` how the training clips
    were held out, ``n`` how many; ``accuracy`` their held-out accuracy. The score is the
    answer's :func:`soft_vote` over the ``neighbours`` nearest cases at ``temperature``, or,
    with ``neighbours`` 0 (calibrations stored before the soft vote), its vote share.
    ``balanced_accuracy``: the mean over the classes of their held-out clips' recall (NaN
    when unknown: none held out, or a case base stored before it was)."""

    x: tuple[float, ...]
    y: tuple[float, ...]
    basis: str
    n: int
    accuracy: float
    temperature: float = 1.0
    neighbours: int = 0
    balanced_accuracy: float = float("nan")

    @property
    def calibrated(self) -> bool:
        """Whether the confidence is calibrated: False for :data:`UNCALIBRATED` (no training
        clip could be held out, or a model stored before calibrations), whose confidence is
        the raw vote share."""
        return bool(self.x)

    @property
    def words(self) -> str:
        """What the confidence is, as the verbose explanation says it."""
        if not self.x:  # UNCALIBRATED: no training clip could be held out, or stored before
            return "the vote share, not calibrated"
        score = "the nearest cases' soft vote" if self.neighbours else "the vote share"
        return f"{score} calibrated on the training clips"

    def __call__(self, score: float) -> float:
        if not self.x:
            return float(score)
        return float(np.interp(float(score), self.x, self.y))

    def score(self, distances: np.ndarray, codes: np.ndarray, n_classes: int, answer: int,
              share: float) -> float:  # fmt: skip
        """The score of the ``answer`` (a class code) of one query whose nearest cases are
        ``distances`` ``(K,)`` (nearest first) of class codes ``codes`` ``(K,)``: its soft
        vote, or its vote ``share`` when the calibration maps shares."""
        return float(self.scores(distances[None], codes[None], n_classes, [answer], [share])[0])

    def scores(
        self,
        distances: np.ndarray,
        codes: np.ndarray,
        n_classes: int,
        answers: Sequence[int],
        shares: Sequence[float],
    ) -> np.ndarray:
        """:meth:`score` of ``q`` queries at once: ``distances`` and ``codes`` ``(q, K)``,
        ``answers`` and ``shares`` ``(q,)``; ``(q,)``."""
        if self.neighbours == 0:
            return np.asarray(shares, dtype=np.float64)
        n = self.neighbours
        p = soft_vote(distances[:, :n], codes[:, :n], n_classes, self.temperature)
        return np.asarray(p[np.arange(len(p)), np.asarray(answers, dtype=np.int64)])

    def to_dict(self) -> dict[str, Any]:
        return {"x": list(self.x), "y": list(self.y), "basis": self.basis, "n": self.n,
                "accuracy": self.accuracy, "temperature": self.temperature,
                "neighbours": self.neighbours,
                "balanced_accuracy": (
                    self.balanced_accuracy if math.isfinite(self.balanced_accuracy) else None
                )}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ConfidenceCalibration:
        x = tuple(float(v) for v in d["x"])
        y = tuple(float(v) for v in d["y"])
        if len(x) != len(y) or any(b < a for a, b in zip(x, x[1:], strict=False)):
            raise ValueError("calibration knots must be paired and increasing")
        temperature, neighbours = float(d.get("temperature", 1.0)), int(d.get("neighbours", 0))
        if not temperature > 0 or neighbours < 0:
            raise ValueError("the soft vote needs a positive temperature and neighbourhood")
        read = cls(x, y, str(d["basis"]), int(d["n"]), float(d["accuracy"]), temperature,
                   neighbours)  # fmt: skip
        balanced = d.get("balanced_accuracy")  # none: unknown, or stored before it was
        return (
            read
            if balanced is None
            else dataclasses.replace(read, balanced_accuracy=float(balanced))
        )


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
    """Platt scaling of the answer's score ``share`` ``(q,)`` (a vote share, or a soft vote)
    to whether the answer was right ``(q,)``; a curve that would fall (a score that is right
    less often the higher it is) becomes flat at the smoothed accuracy."""
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


def calibrate_soft(h: HeldOut, n_classes: int, basis: str,
                   neighbours: int = NEIGHBOURS) -> ConfidenceCalibration:  # fmt: skip
    """The confidence from held-out clips ``h``: the temperature of the soft vote over their
    ``neighbours`` nearest cases fitted by log loss, then Platt scaling of their answers'
    soft votes (the answer is the k-vote's, :func:`held_out_votes`)."""
    h = answered(h)
    if len(h.share) == 0:
        return UNCALIBRATED
    n = min(int(neighbours), h.distances.shape[1])
    d, c = h.distances[:, :n], h.codes[:, :n]
    temperature = fit_temperature(d, c, h.truth, n_classes)
    score = soft_vote(d, c, n_classes, temperature)[np.arange(len(h.answer)), h.answer]
    cal = calibrate_confidence(score, h.right, basis)
    truth, right = np.asarray(h.truth), np.asarray(h.right, dtype=bool)
    balanced = float(np.mean([right[truth == t].mean() for t in np.unique(truth)]))
    return dataclasses.replace(
        cal, temperature=temperature, neighbours=n, balanced_accuracy=balanced
    )


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
