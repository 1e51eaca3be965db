"""Thresholds read from held-out cases' margins ``d1 / d2`` at a budget of false "unknown": one
pooled quantile, each activity's own shrunk towards it, a joint rule of margin and distance,
and a floor for a case base of one person."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from features.errors import ParameterError

from .casebase import CaseBase
from .unknown_held_out import MARGIN_SAMPLE, held_out_activities, known_and_novel

FALSE_UNKNOWN = 0.05
"""The share of held-out training cases of a known activity the margin judge may call
unknown: its threshold is their margins' ``1 - FALSE_UNKNOWN`` quantile."""


ACTIVITY_PRIOR = 1.0 / FALSE_UNKNOWN
"""How many held-out cases the pooled threshold counts for in an activity's own threshold
(:func:`activity_thresholds`) when the case base cannot choose it
(:func:`cbr.unknown_weights.choose_weight`: no activity has held-out cases in two groups): 1 /
:data:`FALSE_UNKNOWN` (20), the number of cases at which the budget reaches one case. Also the
weight of :class:`cbr.unknown_judges.ActivityMargin` records stored before the weight was chosen."""


def margin_of(nearest: np.ndarray) -> float:
    """``d1 / d2``: the distance to the nearest activity over that to the next nearest, from
    the distances to each activity's nearest case ``(n_classes,)``; 1 when the two are equally
    near (or no second activity is there to compare with), 0 when the window is a case."""
    finite = np.sort(np.asarray(nearest, dtype=np.float64)[np.isfinite(nearest)])
    if len(finite) < 2 or finite[1] <= 0.0:
        return 1.0
    return float(finite[0] / finite[1])


def equal_error_threshold(known: np.ndarray, novel: np.ndarray) -> float:
    """The threshold ``t`` at which as large a share of ``known`` values lies above ``t`` as
    of ``novel`` values at or below it (the equal error rate; the first such value of the
    samples when they allow no exact equality). Both ``(n,)``, non-empty."""
    k, n = np.sort(known), np.sort(novel)
    candidates = np.unique(np.r_[k, n])
    known_above = 1.0 - np.searchsorted(k, candidates, side="right") / len(k)
    novel_below = np.searchsorted(n, candidates, side="right") / len(n)
    return float(candidates[int(np.argmin(np.abs(known_above - novel_below)))])


def false_unknown_threshold(known: np.ndarray, rate: float = FALSE_UNKNOWN) -> float:
    """The smallest of the ``known`` values ``(n,)`` (non-empty) that at most a share ``rate``
    of them exceed: the ``1 - rate`` quantile, taken at a sample value (never between two).
    A ``rate`` outside [0, 1) is refused with ParameterError naming it."""
    if not 0.0 <= rate < 1.0:
        raise ParameterError(f"the false-unknown rate must be in [0, 1), got {rate!r}", "rate")
    k = np.sort(np.asarray(known, dtype=np.float64))
    # the first sorted value with at most rate * n values above it
    return float(k[max(0, int(np.ceil(len(k) * (1.0 - rate) - 1e-9)) - 1)])


def calibration_margins(
    cb: CaseBase, sample: int = MARGIN_SAMPLE, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, str]:
    """The margins of training cases held out (:func:`cbr.unknown_held_out.held_out_basis`) with
    their activity in the case base (``known``) and without it (``novel``), and the basis. A
    seeded sample of at most ``sample`` real cases (not mirror images) is held out, each against
    all cases."""
    seen, codes, basis, _ = held_out_activities(cb, sample, seed)
    known, novel = known_and_novel(seen, codes)
    return margins_of(known), margins_of(novel), basis


def margins_of(nearest: np.ndarray) -> np.ndarray:
    """:func:`margin_of` of every row ``(n, n_classes)``: ``(n,)``."""
    if not len(nearest):
        return np.zeros(0)
    two = np.sort(np.asarray(nearest, dtype=np.float64), axis=1)[:, :2]
    if two.shape[1] < 2:
        return np.ones(len(two))
    apart = np.isfinite(two[:, 1]) & (two[:, 1] > 0.0)
    return np.where(apart, two[:, 0] / np.where(apart, two[:, 1], 1.0), 1.0)


JOINT_GRID = np.linspace(0.5, 1.0, 101)
"""The quantiles tried for the joint rule of :class:`cbr.unknown_judges.MarginDistance`, lowest
first."""


def joint_thresholds(
    margins: np.ndarray, distances: np.ndarray, above: float, budget: float
) -> tuple[float, float]:
    """The margin and distance ``(a, b)`` of the joint rule "margin above ``a`` and nearest
    case farther than ``b``": both the same quantile ``q`` of held-out known ``margins`` and
    ``distances`` (``(n,)`` each, paired; taken at sample values as
    :func:`false_unknown_threshold` takes them), the lowest ``q`` of :data:`JOINT_GRID` for
    which at most a share ``budget`` of the known cases that the margin alone (``above``)
    leaves known fall in the rule. ``(inf, inf)`` (the rule never fires) when none does."""
    alone = margins > above
    for q in JOINT_GRID.tolist():
        a = false_unknown_threshold(margins, 1.0 - q)
        b = false_unknown_threshold(distances, 1.0 - q)
        if np.mean((margins > a) & (distances > b) & ~alone) <= budget:
            return a, b
    return float("inf"), float("inf")


NOVEL_CATCH = 0.8
"""With one person in the case base, the share of its held-out cases of a left-out activity
that the margin judge's thresholds still call unknown (:func:`one_person_floor`): the least
threshold is the margin that this share of them exceed. Chosen with the person offset taken
(:func:`cbr.unknown.for_person`) on case bases of one person segmenting the others (``python -m
benchmarks.segment_people --train-people 1``): 0.8 gave the best mean of seen blocks named
rightly and left-out blocks called unknown, 0.7 caught fewer left-out blocks, 0.9 lost seen
ones. Without the offset 0.5 was best: a new person's known margins rise towards the novel
ones (docs/measurements.md, "Segmentation with one person's case base, and on other labs'
people, measured")."""


def one_person_floor(novel: np.ndarray, basis: str) -> float:
    """The least threshold of :class:`cbr.unknown_judges.ActivityMargin` and
    :class:`cbr.unknown_judges.Margin` when the case base cannot hold out a person (``basis``
    not "subject": its cases are held out from their own recording, or from the frames of their
    own that overlap them): the margin that :data:`NOVEL_CATCH` of the held-out cases with their
    own activity left out exceed (their margins ``novel`` ``(n,)``, of :func:`known_and_novel`);
    0 when it can (basis "subject") or no such case is there.

    Held out from the same person, a known case lies nearer its activity than a new person's
    will: the budget of false unknowns read there is spent many times over on anyone else
    (with one person's cases and no floor, most of another person's known blocks are called
    unknown: docs/measurements.md, "Segmentation with one person's case base, and on other
    labs' people, measured"). How far a new person's known movements lie the case
    base cannot tell; how unlike a movement it lacks looks it can: its thresholds are raised
    until they call only :data:`NOVEL_CATCH` of those unknown."""
    if basis == "subject":
        return 0.0
    return false_unknown_threshold(novel, NOVEL_CATCH) if len(novel) else 0.0


def activity_thresholds(
    margins: np.ndarray, activities: np.ndarray, n_classes: int, rate: float, prior: float
) -> tuple[np.ndarray, float]:
    """Per activity ``(n_classes,)``, the threshold of
    :class:`cbr.unknown_judges.ActivityMargin`, and the pooled one: from held-out known
    ``margins`` ``(n,)`` (non-empty) of cases of ``activities`` ``(n,)`` (indices), the pooled
    threshold ``t`` (:func:`false_unknown_threshold` at ``rate``) and each activity's own
    ``t_a`` from its ``n_a`` margins, shrunk: ``(n_a t_a + prior t) / (n_a + prior)``; ``t`` for
    an activity without margins, and for every activity when ``prior`` is inf."""
    pooled = false_unknown_threshold(margins, rate)
    out = np.full(n_classes, pooled)
    if math.isinf(prior):
        return out, pooled
    for a in np.unique(activities).tolist():  # over activities (a few dozen at most)
        mine = margins[activities == a]
        own = false_unknown_threshold(mine, rate)
        # (n_a t_a + prior t) / (n_a + prior), written so that prior 0 gives t_a exactly
        # and t_a = t gives t (a margin equal to its threshold is not above it)
        w = len(mine) / (len(mine) + prior)
        out[a] = own if own == pooled else w * own + (1.0 - w) * pooled
    return out, pooled


def _quantile_at(counts: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """Where :func:`false_unknown_threshold` reads its quantile among ``counts`` sorted values
    at each rate of ``rates`` (each in [0, 1)): ``(len(rates), len(counts))``."""
    at = np.ceil(counts[None, :] * (1.0 - rates[:, None]) - 1e-9).astype(np.int64) - 1
    return np.maximum(at, 0)


def threshold_grid(
    margins: np.ndarray, activities: np.ndarray, n_classes: int, weights: Sequence[Weight]
) -> np.ndarray:
    """``(len(weights), n_classes)``: for every ``(rate, prior)`` of ``weights``, the
    per-activity thresholds of :func:`activity_thresholds` (arguments as there), the margins
    sorted once for all of them and every activity at once; the same numbers, computed
    alike."""
    rates = np.array([w[0] for w in weights], dtype=np.float64)
    priors = np.array([w[1] for w in weights], dtype=np.float64)
    for rate in rates.tolist():
        if not 0.0 <= rate < 1.0:
            raise ParameterError(
                f"the false-unknown rate must be in [0, 1), got {rate!r}", "weights"
            )
    margins = np.asarray(margins, dtype=np.float64)
    pooled = np.sort(margins)[_quantile_at(np.array([len(margins)]), rates)[:, 0]]
    out = np.repeat(pooled[:, None], n_classes, axis=1)
    order = np.lexsort((margins, activities))  # by activity, then margin
    present, starts, counts = np.unique(activities[order], return_index=True, return_counts=True)
    own = margins[order][starts[None, :] + _quantile_at(counts, rates)]  # (weights, present)
    w = counts[None, :] / (counts[None, :] + priors[:, None])
    with np.errstate(invalid="ignore"):  # 0 * inf, as activity_thresholds' floats give
        mixed = np.where(own == pooled[:, None], own, w * own + (1.0 - w) * pooled[:, None])
    shrunk = ~np.isinf(priors)  # an inf prior: the pooled threshold for every activity
    out[np.ix_(shrunk, present)] = mixed[shrunk]
    return out


Weight = tuple[float, float]
"""The quantile rate and the prior of :func:`activity_thresholds`."""
