"""The rules of ``benchmarks.unknown_bounds`` (issue 14: the nearest distance calibrated on
the case base alone, with the default unknown judge), against values worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.unknown_bounds import (
    Bounded,
    bounds,
    choose_fisher_weight,
    fisher,
    near_bound,
    person_scale,
)
from cbr.casebase import CaseBase
from cbr.problem import FeatureConfig
from cbr.similarity import Euclidean
from cbr.unknown import Margin, SpreadMargin, held_out_activities


def _rows(pairs: list[tuple[float, float]]) -> np.ndarray:
    return np.array(pairs, dtype=np.float64)


def test_near_bound_by_hand() -> None:
    """Known nearest distances 1..10: the quantiles 0.9 .. 0.1 read at the sample values 9,
    8, .., 1. A margin judge (unknown above 0.5). Novel: (12, 13) caught, (8.5, 10) caught,
    (3, 30) not (margin 0.1), (6.5, 7) caught: at 9, 8 and 7 a caught one (8.5 or 6.5) lies
    no farther, at 6 none (the one at 3 is not caught): 6. With 100 novel cases one may be
    given up (1 %): 99 like (12, 13) and (6.5, 7): 9. A caught novel case at 0.5, below
    every quantile: no bound, 0."""
    known = _rows([(float(d), 100.0) for d in range(10, 0, -1)])
    judge = Margin(0.5, "subject", 10, 4)
    novel = _rows([(12.0, 13.0), (8.5, 10.0), (3.0, 30.0), (6.5, 7.0)])
    assert near_bound(judge, known, novel) == 6.0
    assert near_bound(judge, known, _rows([(12.0, 13.0)] * 99 + [(6.5, 7.0)])) == 9.0
    assert near_bound(judge, known, _rows([(0.5, 0.6)])) == 0.0
    assert near_bound(judge, known, np.zeros((0, 2))) == 0.0


def test_bounded_rule_by_hand() -> None:
    """A margin judge (above 0.5) between near 2 and far 10: (3, 4) margin 0.75, unknown;
    (1.5, 2) margin 0.75 but no farther than 2: known; (11, 100) margin 0.11 but beyond 10:
    unknown. With an offset of 2 the distances are less 2: (11, 100) lies 9, not beyond 10,
    known; (3, 4) lies 1, within the near bound, known."""
    judge = Margin(0.5, "subject", 10, 4)
    b = Bounded(judge, near=2.0, far=10.0)
    assert b.unlike(np.array([3.0, 4.0]))
    assert not b.unlike(np.array([1.5, 2.0]))
    assert b.unlike(np.array([11.0, 100.0])) and not judge.unlike(np.array([11.0, 100.0]))
    shifted = Bounded(judge, near=2.0, far=10.0, offset=2.0)
    assert not shifted.unlike(np.array([11.0, 100.0]))
    assert not shifted.unlike(np.array([3.0, 4.0]))
    assert not Bounded(judge).unlike(np.array([11.0, 100.0]))


def test_bounds_calibrated_on_two_people_by_hand() -> None:
    """tests/test_unknown28's two people (r1: a 0, b 10, c 20; r2: a 1 and 9, b 12, c 23),
    held out by person: spread-margin is the margin alone against 3/8 for every activity.
    The seven held-out cases' distances to a, b, c: r1 (1, 12, 23), (1, 2, 13), (11, 8, 3);
    r2 (1, 9, 19), (9, 1, 11), (12, 2, 8), (23, 13, 3): nearest 1, 1, 3, 1, 1, 2, 3; far,
    the 95 % quantile of seven (the 7th): 3. Their own activity gone: nearest (margin) 12
    (12/23), 1 (1/13), 8 (8/11), 9 (9/19), 1 (1/11), 8 (8/12), 13 (13/23): caught (above
    3/8) those at 8 to 13; none of them as near as the 90 % quantile of the known ones (the
    7th, 3): near 3."""
    cb = CaseBase(FeatureConfig(), Euclidean(exact=True),
                  np.array([[x, 0.0] for x in (0.0, 10.0, 20.0, 1.0, 9.0, 12.0, 23.0)]),
                  np.array(["a", "b", "c", "a", "a", "b", "c"]), ("x", "y"), ("x", "y"),
                  sources=tuple(["r1"] * 3 + ["r2"] * 4),
                  subjects=tuple(["r1"] * 3 + ["r2"] * 4))  # fmt: skip
    judge = SpreadMargin.of(cb)
    np.testing.assert_allclose(judge.thresholds, [3 / 8] * 3)
    assert bounds(judge, held_out_activities(cb)) == (3.0, 3.0)


def test_fisher_and_its_weight_by_hand() -> None:
    """Held-out known judge scores 1..4 and d1 10..40 (the k-th: both tails (6 - k) / 5):
    a window at judge 3.5 (one of four at or above: p 2/5) and d1 50 (none: 1/5): 2 log(5/2)
    + 2 w log 5. The known cases' own scores top out at 2 (1 + w) log(5/2), the threshold.
    Novel cases far in d1 alone (judge 1: p 1; d1 50: p 1/5) score 2 w log 5, above it only
    for w > log 2.5 / log 2 = 1.32: w = 2. Novel cases high in the judge's score alone
    (judge 5: p 1/5; d1 10: p 1) score 2 log 5, above it for w < log 5 / log 2.5 - 1 = 0.76:
    0, 0.25 and 0.5 tie, the smallest taken, 0."""
    known = {"judge": np.array([1.0, 2.0, 3.0, 4.0]), "d1": np.array([10.0, 20.0, 30.0, 40.0])}
    window = {"judge": np.array([3.5]), "d1": np.array([50.0])}
    for w in (0.0, 1.0):
        assert fisher(known, window, w)[0] == pytest.approx(
            2 * math.log(5 / 2) + 2 * w * math.log(5)
        )
    far = {"judge": np.array([1.0, 1.0]), "d1": np.array([50.0, 50.0])}
    assert choose_fisher_weight({"known": known, "novel": far}) == 2.0
    odd = {"judge": np.array([5.0, 5.0]), "d1": np.array([10.0, 10.0])}
    assert choose_fisher_weight({"known": known, "novel": odd}) == 0.0


def test_person_scale_by_hand() -> None:
    """Held-out known d1 whose 10 % quantile is 2; a recording of 8 windows whose 10 %
    quantile is 4: raw 2 / 4 = 0.5, shrunk half-way to 1 by 8 windows: 0.75. No finite
    distance: 1."""
    held = np.linspace(1.0, 11.0, 11)  # 10 % quantile 2
    rec = np.array([3.3, 4.0, 4.0, 4.0, 5.0, 6.0, 7.0, 8.0])  # 10 % quantile 3.3 + 0.7 * 0.7
    q = float(np.quantile(rec, 0.1))
    assert person_scale(held, rec) == pytest.approx(1.0 + (2.0 / q - 1.0) * 8 / 16)
    assert person_scale(held, np.array([np.inf])) == 1.0
