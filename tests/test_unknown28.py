"""The spread-margin judge (cbr.unknown.SpreadMargin): the margin times how far a window lies
from its nearest activity in that activity's own spread, on hand-made distances and case
bases whose spreads, scores and choices are worked out by hand."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from cbr.casebase import CaseBase
from cbr.problem import FeatureConfig
from cbr.similarity import Euclidean
from cbr.unknown import (
    FALSE_UNKNOWN,
    JUDGES,
    STORED,
    ActivityMargin,
    SpreadMargin,
    activity_spreads,
    choose_spread,
    inner_scores,
    spread_scores,
    unknown_evidence,
)


def _line(xs: list[float], labels: list[str], people: list[str], subjects: bool) -> CaseBase:
    """Cases on a line: problem = (x, 0), so every distance is |x_i - x_j|; ``people`` are
    the recordings, named as subjects too when ``subjects``."""
    return CaseBase(
        FeatureConfig(),
        Euclidean(exact=True),
        np.array([[x, 0.0] for x in xs]),
        np.array(labels),
        ("x", "y"),
        ("x", "y"),
        sources=tuple(people),
        subjects=tuple(people) if subjects else tuple([None] * len(xs)),
    )


def _two_people() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Held-out distances to activities a, b, c, d of one case of each per person p and q
    (``seen`` ``(8, 4)``, activity codes, groups), every case nearest its own activity.
    Margins: a 0.1 (p) and 0.2 (q), b and c 0.8, d 1 / 7.2. Own distances (the spreads'
    samples): a 1 (p) and 2 (q), b and c 4, d 1."""
    clear = [[1.0, 10.0, 10.0, 10.0], [2.0, 10.0, 10.0, 10.0]]
    alike = [[10.0, 4.0, 5.0, 10.0], [10.0, 5.0, 4.0, 10.0]]
    like_a = [7.2, 10.0, 10.0, 1.0]
    seen = np.array([clear[0], *alike, like_a, clear[1], *alike, like_a])
    return seen, np.array([0, 1, 2, 3] * 2), np.array(["p"] * 4 + ["q"] * 4)


def test_activity_spreads_and_scores_by_hand() -> None:
    """Spreads of :func:`_two_people`: a the median of 1 and 2 = 1.5, b and c 4, d 1; of
    q's cases alone a 2. With a's cases left out of the rows, a takes the pooled median of
    the six others (4, 4, 1, 4, 4, 1): 4. Scores at power 1: q's a 0.2 * 2 / 1.5; a window
    at (3, 6, 9, 12): margin 0.5, 3 / 1.5 = 2 spreads from a: 1 (power 1), 2 (power 2), the
    margin 0.5 (power 0)."""
    seen, codes, _ = _two_people()
    every = np.ones(8, dtype=bool)
    np.testing.assert_allclose(activity_spreads(seen, codes, every), [1.5, 4.0, 4.0, 1.0])
    q = np.arange(8) >= 4
    np.testing.assert_allclose(activity_spreads(seen, codes, q), [2.0, 4.0, 4.0, 1.0])
    np.testing.assert_allclose(activity_spreads(seen, codes, codes != 0), [4.0, 4.0, 4.0, 1.0])
    spreads = np.array([1.5, 4.0, 4.0, 1.0])
    assert spread_scores(seen[4:5], spreads, 1.0)[0] == pytest.approx(0.2 * 2 / 1.5)
    window = np.array([[3.0, 6.0, 9.0, 12.0]])
    assert spread_scores(window, spreads, 1.0)[0] == pytest.approx(1.0)
    assert spread_scores(window, spreads, 2.0)[0] == pytest.approx(2.0)
    assert spread_scores(window, spreads, 0.0)[0] == pytest.approx(0.5)


def test_inner_scores_with_the_spread_by_hand() -> None:
    """Thresholds pooled (prior inf; the largest of four at any rate up to 5 %), spreads
    from the other person. Known: q held out, from p (spreads a 1, b c 4, d 1: scores a
    0.1, b c 0.8, d 1/7.2; threshold 0.8): q's a 0.2 * 2 = 0.4, b c 0.8, none above; p held
    out, from q (a's spread 2): p's a 0.1 / 2, none above. Gone activities, q's (p's alike):
    a's case (10, 10, 10): margin 1, nearest b, 10 / 4 spreads: 2.5 above 0.8; b's (10, 5,
    10): 0.5 nearest c, 5 / 4: 0.625 above c's 0.4 (the threshold of p's a 0.1, c 0.4, d
    0.139); c's likewise; d's (7.2, 10, 10): 0.72 nearest a, 7.2 spreads of p's a: 5.18
    above 0.8 (p's d from q's a, spread 2: 0.72 * 3.6 = 2.59). Caught 8/8; the margin alone
    misses both d's (0.72 below 0.8): 6/8."""
    seen, codes, groups = _two_people()
    over, caught = inner_scores(seen, codes, groups, [(0.05, math.inf)], 1.0)
    np.testing.assert_allclose([over[0], caught[0]], [0.0, 1.0])
    over, caught = inner_scores(seen, codes, groups, [(0.05, math.inf)], 0.0)
    np.testing.assert_allclose([over[0], caught[0]], [0.0, 6 / 8])


def test_choose_spread_by_hand() -> None:
    """:func:`_two_people`: the margin alone (power 0) catches 6/8 at prior inf (above) and
    8/8 only at a prior of 5; power 0.5 already catches 8/8 at prior inf (a's 1 * 2.5 **
    0.5 = 1.58, b's 0.5 * 1.25 ** 0.5 = 0.56 above 0.4, d's 0.72 * 7.2 ** 0.5 = 1.93 and
    0.72 * 3.6 ** 0.5 = 1.37 above 0.8) and calls none of the known above (q's a 0.2 * 2 **
    0.5 = 0.28, p's a 0.1 * 0.5 ** 0.5): of the ties at 8/8, the largest rate (every rate
    reads the same quantile of four), the largest prior, then the smallest power. Without
    an activity in two groups: the budget, 20 and the margin alone."""
    seen, codes, groups = _two_people()
    assert choose_spread(seen, codes, groups) == (FALSE_UNKNOWN, math.inf, 0.5)
    assert choose_spread(seen, codes, np.array(list("abcdabcd"))) == (FALSE_UNKNOWN, 20.0, 0.0)


def test_spread_margin_rule_by_hand() -> None:
    """Thresholds 1 (a) and 2 (b), at the budget 0.5 and 1, spreads a 2, b 1, power 1.
    (1, 4): margin 0.25, half a's spread: 0.125, known; (4, 5): 0.8 * 2 = 1.6, above a's 1,
    unknown (the margin alone, 0.8, is not above a's 1); (3, 5): 0.6 * 1.5 = 0.9, between
    a's 0.5 and 1: evidence (0.9 - 0.5) / 0.5 = 0.8; (5, 2): nearest b, 0.4 * 2 = 0.8,
    below b's 1: 0."""
    judge = SpreadMargin((1.0, 2.0), 1.0, "subject", 10, budget_thresholds=(0.5, 1.0),
                         rate=0.01, spreads=(2.0, 1.0), power=1.0)  # fmt: skip
    assert not judge.unlike(np.array([1.0, 4.0]))
    assert judge.ratio(np.array([1.0, 4.0])) == pytest.approx(0.125)
    assert judge.unlike(np.array([4.0, 5.0]))
    assert not ActivityMargin((1.0, 2.0), 1.0, "subject", 10).unlike(np.array([4.0, 5.0]))
    assert unknown_evidence(judge, np.array([4.0, 5.0])) == 1.0
    assert unknown_evidence(judge, np.array([3.0, 5.0])) == pytest.approx(0.8)
    assert unknown_evidence(judge, np.array([5.0, 2.0])) == 0.0
    words = judge.describe(np.array([4.0, 5.0]), ["a", "b"])
    assert "2.0x as far as a known a usually lies" in words and "below 1.00" in words
    # stored with the model as a record of its fields, and read back
    assert SpreadMargin.from_dict(judge.to_dict()) == judge
    with pytest.raises(ValueError, match="'spreads' has 1 values for 2 activities"):
        dataclasses.replace(judge, spreads=(1.0,))
    assert "spread-margin" in JUDGES and STORED["spread-margin"] is SpreadMargin


def test_spread_margin_calibrated_on_two_people_by_hand() -> None:
    """Person r1: a at 0, b at 10, c at 20; r2: a at 1 and 9, b at 12, c at 23, held out by
    person. Rightly named: r1 a (own 1), c (own 3); r2 a@1 (1), b (2), c (3): spreads a 1, b
    2, c 3. r1's c (margin 3/8, 1 spread from c: 3/8 at every power) lies above the
    thresholds from r2 (pooled 1/4), and r2's a@1 (1/9, 1 spread) above a's own 1/12 from
    r1 at prior 0: no power keeps the budget, and the least over-call (1/5) is taken with
    the largest rate and prior and the smallest power: the margin alone, every threshold
    r2 and r1's pooled 3/8, as :class:`ActivityMargin`'s."""
    cb = _line([0.0, 10.0, 20.0, 1.0, 9.0, 12.0, 23.0], ["a", "b", "c", "a", "a", "b", "c"],
               ["r1"] * 3 + ["r2"] * 4, subjects=True)  # fmt: skip
    judge = SpreadMargin.of(cb)
    assert (judge.basis, judge.power, judge.rate, judge.prior) == ("subject", 0.0, 0.05, math.inf)
    np.testing.assert_allclose(judge.spreads, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(judge.thresholds, [3 / 8] * 3)


def test_spread_margin_with_one_person_is_the_activity_margin() -> None:
    """Two recordings of one person (r1 a@0, b@-10, c@10; r2 a@1, b@-11, c@11: held out by
    recording): a spread read from one person says nothing of the next, so the judge is
    the activity margin, its floor and person reach included, without spreads."""
    cb = _line([0.0, -10.0, 10.0, 1.0, -11.0, 11.0], ["a", "b", "c"] * 2,
               ["r1"] * 3 + ["r2"] * 3, subjects=False)  # fmt: skip
    judge, plain = SpreadMargin.of(cb), ActivityMargin.of(cb)
    assert judge.basis == "recording" and judge.spreads == () and judge.power == 0.0
    for f in dataclasses.fields(plain):
        assert getattr(judge, f.name) == getattr(plain, f.name), f.name
    assert judge.floor > 0.0 and math.isfinite(judge.reach)
