"""The spread-nearest judge (cbr.unknown.SpreadNearest): the spread-margin judge bounded by
the window's distance to its nearest case, never unknown as near as most held-out known
cases lie, always unknown farther than nearly all of them; bounds worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cbr.casebase import CaseBase
from cbr.problem import FeatureConfig
from cbr.similarity import Euclidean
from cbr.unknown import (
    AT_FIT,
    JUDGES,
    STORED,
    Margin,
    SpreadMargin,
    SpreadNearest,
    for_person,
    judges_from_dict,
    judges_to_dict,
    near_bound,
    unknown_evidence,
)


def _rows(pairs: list[tuple[float, float]]) -> np.ndarray:
    return np.array(pairs, dtype=np.float64)


def test_near_bound_by_hand() -> None:
    """Known nearest distances 1..10: the quantiles 0.9 .. 0.1 read at sample values 9, 8,
    .., 1. A margin judge (unknown above 0.5). Novel: (12, 13) caught, (8.5, 10) caught,
    (3, 30) not (margin 0.1), (6.5, 7) caught: at 9, 8 and 7 a caught one (8.5 or 6.5) lies
    no farther, at 6 none (the one at 3 is not caught): 6. With 100 novel cases one may be
    given up (NEAR_COST 1 %): 99 like (12, 13) and (6.5, 7): 9. A caught novel case at 0.5
    below every quantile: no bound, 0."""
    known = _rows([(float(d), 100.0) for d in range(10, 0, -1)])
    judge = Margin(0.5, "subject", 10, 4)
    novel = _rows([(12.0, 13.0), (8.5, 10.0), (3.0, 30.0), (6.5, 7.0)])
    assert near_bound(judge, known, novel) == 6.0
    many = _rows([(12.0, 13.0)] * 99 + [(6.5, 7.0)])
    assert near_bound(judge, known, many) == 9.0
    assert near_bound(judge, known, _rows([(0.5, 0.6)])) == 0.0
    assert near_bound(judge, known, np.zeros((0, 2))) == 0.0


def _judge(near: float, far: float) -> SpreadNearest:
    """tests/test_unknown28's spread-margin rule (thresholds 1 and 2, at the budget 0.5 and
    1, spreads 2 and 1, power 1) bounded by ``near`` and ``far``."""
    return SpreadNearest((1.0, 2.0), 1.0, "subject", 10, budget_thresholds=(0.5, 1.0),
                         rate=0.01, spreads=(2.0, 1.0), power=1.0, near=near,
                         far=far)  # fmt: skip


def test_spread_nearest_rule_by_hand() -> None:
    """(4, 5): score 0.8 * 4 / 2 = 1.6 above a's 1: unknown with near 2, known with near 4
    (it lies no farther than 4), evidence 0. (11, 100): margin 0.11 * 11 / 2 = 0.605, below
    a's 1 and its budget threshold 0.5 ... above it: spread-margin's evidence (0.605 - 0.5)
    / 0.5 = 0.21, not unlike; beyond far 10: unknown, evidence 1, told by its distance.
    (3, 5): 0.6 * 1.5 = 0.9, between the bounds: spread-margin's evidence 0.8."""
    plain = SpreadMargin((1.0, 2.0), 1.0, "subject", 10, budget_thresholds=(0.5, 1.0),
                         rate=0.01, spreads=(2.0, 1.0), power=1.0)  # fmt: skip
    judge = _judge(2.0, 10.0)
    assert judge.unlike(np.array([4.0, 5.0])) and plain.unlike(np.array([4.0, 5.0]))
    assert not _judge(4.0, 10.0).unlike(np.array([4.0, 5.0]))
    assert unknown_evidence(_judge(4.0, 10.0), np.array([4.0, 5.0])) == 0.0
    far = np.array([11.0, 100.0])
    assert not plain.unlike(far)
    assert unknown_evidence(plain, far) == pytest.approx(0.21)
    assert judge.unlike(far) and unknown_evidence(judge, far) == 1.0
    assert not _judge(2.0, math.inf).unlike(far)
    words = judge.describe(far, ["a", "b"])
    assert "its nearest case (a) lies 11 away, farther than 10" in words
    assert unknown_evidence(judge, np.array([3.0, 5.0])) == pytest.approx(0.8)
    assert judge.describe(np.array([4.0, 5.0]), ["a", "b"]) == plain.describe(
        np.array([4.0, 5.0]), ["a", "b"]
    )


def test_spread_nearest_is_stored_and_read_back() -> None:
    """A record of its fields, read back; a record without the bounds (spread-margin's) is
    spread-margin's rule (near 0, far inf); named, stored at fit."""
    judge = _judge(2.0, 10.0)
    assert judges_from_dict(judges_to_dict({"spread-nearest": judge})) == {"spread-nearest": judge}
    old = SpreadMargin((1.0, 2.0), 1.0, "subject", 10, spreads=(2.0, 1.0), power=1.0)
    read = SpreadNearest.from_dict(old.to_dict())
    assert (read.near, read.far) == (0.0, math.inf)
    with pytest.raises(ValueError, match="field 'far' must be a number >= 0"):
        SpreadNearest.from_dict({**judge.to_dict(), "far": -1.0})
    assert "spread-nearest" in JUDGES and JUDGES[0] == "spread-margin"
    assert STORED["spread-nearest"] is SpreadNearest and "spread-nearest" in AT_FIT


def _line(xs: list[float], labels: list[str], people: list[str]) -> CaseBase:
    """Cases on a line: problem = (x, 0), every distance |x_i - x_j|; held out by person."""
    return CaseBase(FeatureConfig(), Euclidean(exact=True), np.array([[x, 0.0] for x in xs]),
                    np.array(labels), ("x", "y"), ("x", "y"), sources=tuple(people),
                    subjects=tuple(people))  # fmt: skip


def test_spread_nearest_calibrated_by_hand() -> None:
    """tests/test_unknown28's two people (r1: a 0, b 10, c 20; r2: a 1 and 9, b 12, c 23):
    spread-margin is the margin alone against 3/8 for every activity. Held out by person,
    the seven cases' distances to a, b, c: r1 (1, 12, 23), (1, 2, 13), (11, 8, 3); r2 (1, 9,
    19), (9, 1, 11), (12, 2, 8), (23, 13, 3): nearest 1, 1, 3, 1, 1, 2, 3; far, the 95 %
    quantile of seven (the 7th): 3. Their own activity gone: nearest (margin) 12 (12/23), 1
    (1/13), 8 (8/11), 9 (9/19), 1 (1/11), 8 (8/12), 13 (13/23): caught (above 3/8) those at
    8 to 13; at the 90 % quantile of the known ones (the 7th, 3) none caught lies as near:
    near 3. A window at 2.5 is never unknown (its margin 2.5 / 2.6 above 3/8), one at 4
    always (margin 0.1)."""
    cb = _line([0.0, 10.0, 20.0, 1.0, 9.0, 12.0, 23.0], ["a", "b", "c", "a", "a", "b", "c"],
               ["r1"] * 3 + ["r2"] * 4)  # fmt: skip
    judge = SpreadNearest.of(cb)
    plain = SpreadMargin.of(cb)
    assert (judge.near, judge.far) == (3.0, 3.0)
    assert judge.thresholds == plain.thresholds and judge.power == plain.power == 0.0
    ambiguous, far = np.array([2.5, 2.6, 10.0]), np.array([4.0, 40.0, 40.0])
    assert plain.unlike(ambiguous) and not judge.unlike(ambiguous)
    assert not plain.unlike(far) and judge.unlike(far)
    # a multi-person case base: no person offset
    assert for_person(judge, np.array([5.0, 6.0])) is judge


def test_spread_nearest_with_one_person_is_spread_margin() -> None:
    """Two recordings of one person (held out by recording): no bounds, the judge answers as
    spread-margin (here the activity margin) does."""
    cb = CaseBase(FeatureConfig(), Euclidean(exact=True),
                  np.array([[x, 0.0] for x in (0.0, -10.0, 10.0, 1.0, -11.0, 11.0)]),
                  np.array(["a", "b", "c"] * 2), ("x", "y"), ("x", "y"),
                  sources=tuple(["r1"] * 3 + ["r2"] * 3))  # fmt: skip
    judge, plain = SpreadNearest.of(cb), SpreadMargin.of(cb)
    assert judge.basis == "recording" and (judge.near, judge.far) == (0.0, math.inf)
    for window in (np.array([0.5, 10.0, 10.0]), np.array([30.0, 31.0, 40.0])):
        assert judge.unlike(window) == plain.unlike(window)
        assert unknown_evidence(judge, window) == unknown_evidence(plain, window)
