"""The rate, prior and spread power of the per-activity thresholds, chosen on the held-out cases
so that each group (a person or a recording), held out in turn, keeps the budget of false
"unknown" against thresholds set from the others."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .unknown_held_out import known_rows
from .unknown_thresholds import ACTIVITY_PRIOR, FALSE_UNKNOWN, Weight, margins_of, threshold_grid

PRIOR_GRID = (0.0, 5.0, 10.0, 20.0, 40.0, 80.0, 160.0, 320.0, math.inf)
"""The weights :func:`choose_weight` tries, least shrinkage first (``inf``: the pooled
threshold for every activity)."""


RATE_SHARES = (1.0, 0.8, 0.6, 0.4, 0.2)
"""The shares of the false-unknown budget at which :func:`choose_weight` tries reading the
thresholds' quantiles, the whole budget first."""


def rightly_named(seen: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: the held-out known cases (:func:`known_rows`) whose nearest activity is
    their own."""
    return np.asarray(known_rows(seen, codes) & (np.argmin(seen, axis=1) == codes))


def inner_scores(
    seen: np.ndarray,
    codes: np.ndarray,
    groups: np.ndarray,
    weights: Sequence[Weight],
    power: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """For each ``(rate, prior)`` of ``weights``, how
    :class:`cbr.unknown_judges.ActivityMargin`'s thresholds set from the other groups' held-out
    cases fare on each group's own, every group (subject or recording) held out in turn, as a
    new person is; from held-out cases' distances to every activity ``(n, n_classes)``, their
    activities and groups ``(n,)`` each. ``over``: the share of the held-out group's rightly
    named known cases above their activity's threshold; ``caught``: the share of its cases of an
    activity ``a`` above the threshold of their nearest other activity when ``a`` is gone (its
    column and its cases left out of the thresholds too, as from a case base without it). Both
    ``(len(weights),)``; 0 where there is nothing to count. ``power``: the margins are
    :class:`cbr.unknown_judges.SpreadMargin`'s scores of that power (:func:`spread_scores`),
    each activity's spread read from the other groups' cases as the thresholds are; 0, the
    margins themselves."""
    over, caught = inner_grid(seen, codes, groups, weights, (power,))
    return over[0], caught[0]


def inner_grid(
    seen: np.ndarray,
    codes: np.ndarray,
    groups: np.ndarray,
    weights: Sequence[Weight],
    powers: Sequence[float] = (0.0,),
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`inner_scores` at every power of ``powers``, ``over`` and ``caught`` each
    ``(len(powers), len(weights))``: what the powers share (the groups held out, the
    activities gone, the spreads) is found once."""
    n_classes = seen.shape[1]
    over, caught = np.zeros((len(powers), len(weights))), np.zeros((len(powers), len(weights)))
    n_known = n_novel = 0
    spread = any(powers)
    right, margins = rightly_named(seen, codes), margins_of(seen)
    for g in np.unique(groups).tolist():  # over groups (subjects or recordings: a few)
        mine = groups == g
        train, test = right & ~mine, right & mine
        if not train.any():
            continue
        far = _spread_far(seen, activity_spreads(seen, codes, train)) if spread else margins
        n_known += int(test.sum())
        for i, power in enumerate(powers):
            scores = _scored(margins, far, power)
            per = threshold_grid(scores[train], codes[train], n_classes, weights)
            over[i] += np.sum(scores[test][None, :] > per[:, codes[test]], axis=1)
        for a in np.unique(codes[mine]).tolist():  # the group's activities, each gone in turn
            without = seen.copy()
            without[:, a] = np.inf
            kept = rightly_named(without, codes) & ~mine & (codes != a)
            novel = mine & (codes == a) & (np.isfinite(without).sum(axis=1) >= 2)
            if not kept.any() or not novel.any():
                continue
            m, near = margins_of(without), np.argmin(without[novel], axis=1)
            far = _spread_far(without, activity_spreads(without, codes, kept)) if spread else m
            n_novel += int(novel.sum())
            for i, power in enumerate(powers):
                scores = _scored(m, far, power)
                per = threshold_grid(scores[kept], codes[kept], n_classes, weights)
                caught[i] += np.sum(scores[novel][None, :] > per[:, near], axis=1)
    return over / max(n_known, 1), caught / max(n_novel, 1)


def choose_weight(
    seen: np.ndarray, codes: np.ndarray, groups: np.ndarray, budget: float = FALSE_UNKNOWN
) -> Weight:
    """The quantile rate (a share of ``budget``, :data:`RATE_SHARES`) and the prior
    (:data:`PRIOR_GRID`) of :class:`cbr.unknown_judges.ActivityMargin`'s thresholds, chosen on
    the held-out cases themselves (:func:`inner_scores`; arguments as there): of those whose
    thresholds, set from the other groups, the held-out group's known cases exceed no more often
    than ``budget``, the one that calls most of a gone activity's cases unknown (on a tie the
    larger rate, then the larger prior: the less tuned). An activity's own quantile, read from a few
    people, is exceeded more often by the next person than the pooled one: the prior and the
    rate are what keep the budget on people the thresholds were not set from. The least
    over-call when none keeps it; ``(budget, ACTIVITY_PRIOR)`` when no activity has
    held-out cases in two groups (no held-out group then has an own threshold to test)."""
    right = rightly_named(seen, codes)
    if not any(len(np.unique(groups[right & (codes == a)])) >= 2 for a in np.unique(codes)):
        return budget, ACTIVITY_PRIOR
    weights = [(budget * share, prior) for share in RATE_SHARES for prior in PRIOR_GRID]
    over, caught = inner_scores(seen, codes, groups, weights)
    within = [w for w in range(len(weights)) if over[w] <= budget]
    if within:
        best = max(within, key=lambda w: (caught[w], *weights[w]))
    else:
        best = min(range(len(weights)), key=lambda w: (over[w], -weights[w][0], -weights[w][1]))
    return weights[best]


SPREAD_POWERS = (0.0, 0.5, 1.0, 2.0, 4.0)
"""The powers of the spread :func:`choose_spread` tries (0: the margin alone, as
:class:`cbr.unknown_judges.ActivityMargin`'s)."""


def activity_spreads(seen: np.ndarray, codes: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``(n_classes,)``: how far a held-out known case of each activity usually lies from
    that activity's nearest case, the median of the distances to their own activity of the
    held-out cases ``rows`` (``(n,)`` bool; distances to every activity ``seen`` ``(n,
    n_classes)``, activities ``codes`` ``(n,)``) of that activity; their pooled median for an
    activity without such a case (1 when there is none at all)."""
    own = seen[np.arange(len(seen)), codes]
    pooled = float(np.median(own[rows])) if rows.any() else 1.0
    out = np.full(seen.shape[1], pooled)
    for a in np.unique(codes[rows]).tolist():  # over activities (a few dozen at most)
        out[a] = float(np.median(own[rows & (codes == a)]))
    return out


def spread_scores(nearest: np.ndarray, spreads: np.ndarray, power: float) -> np.ndarray:
    """:class:`cbr.unknown_judges.SpreadMargin`'s score of every row of ``nearest`` ``(n,
    n_classes)`` (distances to every activity): the margin ``d1 / d2`` times ``(d1 / s) **
    power``, ``s`` the spread (:func:`activity_spreads`, ``(n_classes,)``) of the row's nearest
    activity. ``(n,)``."""
    nearest = np.asarray(nearest, dtype=np.float64)
    m = margins_of(nearest)
    if not power or not len(nearest):
        return m
    return _scored(m, _spread_far(nearest, spreads), power)


def _spread_far(nearest: np.ndarray, spreads: np.ndarray) -> np.ndarray:
    """``(n,)``: the distance of every row of ``nearest`` ``(n, n_classes)`` (non-empty) to
    its nearest activity in that activity's spread ``spreads`` ``(n_classes,)`` (inf for a
    spread of 0, 1 when the distance is 0 too)."""
    a1 = np.argmin(nearest, axis=1)
    d1, s = nearest[np.arange(len(nearest)), a1], spreads[a1]
    return np.where(s > 0.0, d1 / np.where(s > 0.0, s, 1.0), np.where(d1 > 0.0, np.inf, 1.0))


def _scored(margins: np.ndarray, far: np.ndarray, power: float) -> np.ndarray:
    """:func:`spread_scores` from the rows' margins and :func:`_spread_far` ``(n,)`` each."""
    return margins if not power else np.asarray(margins * far**power)


def choose_spread(
    seen: np.ndarray, codes: np.ndarray, groups: np.ndarray, budget: float = FALSE_UNKNOWN
) -> tuple[float, float, float]:
    """The quantile rate, the prior and the power of :class:`cbr.unknown_judges.SpreadMargin`,
    chosen on the held-out cases as :func:`choose_weight` chooses the first two (arguments as
    there), over the powers of :data:`SPREAD_POWERS` too: of the triples whose thresholds the
    held-out group's known cases exceed no more often than ``budget``, the one that calls most of a
    gone activity's cases unknown (on a tie the larger rate, prior, then the smaller power);
    the least over-call when none keeps it. ``(budget, ACTIVITY_PRIOR, 0)`` when no activity
    has held-out cases in two groups."""
    right = rightly_named(seen, codes)
    if not any(len(np.unique(groups[right & (codes == a)])) >= 2 for a in np.unique(codes)):
        return budget, ACTIVITY_PRIOR, 0.0
    weights = [(budget * share, prior) for share in RATE_SHARES for prior in PRIOR_GRID]
    over, caught = inner_grid(seen, codes, groups, weights, SPREAD_POWERS)
    tried = [(p, w, over[i, w], caught[i, w]) for i, p in enumerate(SPREAD_POWERS)
             for w in range(len(weights))]  # fmt: skip
    within = [t for t in tried if t[2] <= budget]
    if within:
        p, w, *_ = max(within, key=lambda t: (t[3], *weights[t[1]], -t[0]))
    else:
        p, w, *_ = min(tried, key=lambda t: (t[2], -weights[t[1]][0], -weights[t[1]][1], t[0]))
    return weights[w][0], weights[w][1], p
