"""The corrections of ``benchmarks.unknown_extrapolate`` (issue 14: the default judge's
held-out scan carried on to one person more), against values worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.unknown_extrapolate import (
    choose_correction,
    corrected,
    extrapolated,
    judges,
    median_ratio,
    one_more_person,
    people_scan,
    second_left_out,
)
from cbr.casebase import CaseBase
from cbr.problem import FeatureConfig
from cbr.similarity import Euclidean
from cbr.unknown import SpreadFar, SpreadMargin, held_out_activities

INF = math.inf


def _three_people() -> CaseBase:
    """People p, q, r, each doing a, b, c once, on a line: p 0, 10, 20; q 1, 12, 23; r 3,
    11, 26."""
    xs = (0.0, 10.0, 20.0, 1.0, 12.0, 23.0, 3.0, 11.0, 26.0)
    people = ("p",) * 3 + ("q",) * 3 + ("r",) * 3
    return CaseBase(FeatureConfig(), Euclidean(exact=True), np.array([[x, 0.0] for x in xs]),
                    np.array(["a", "b", "c"] * 3), ("x", "y"), ("x", "y"),
                    sources=tuple(f"{p}{i}" for i, p in enumerate(people)),
                    subjects=people)  # fmt: skip


def test_people_scan_by_hand() -> None:
    """p's case of a (at 0) against q: a 1, b 12, c 23; against r: a 3, b 11, c 26; against
    p itself nothing (held out). The scan's own distances are the least over people."""
    cb = _three_people()
    held, people = people_scan(cb)
    assert people.shape == (9, 3, 3)
    np.testing.assert_array_equal(people[0, 0], [INF, INF, INF])
    np.testing.assert_array_equal(people[0, 1], [1.0, 12.0, 23.0])
    np.testing.assert_array_equal(people[0, 2], [3.0, 11.0, 26.0])
    plain = held_out_activities(cb)
    np.testing.assert_array_equal(held[0], plain[0])
    np.testing.assert_array_equal(people.min(axis=1), plain[0])


def test_extrapolated_by_hand() -> None:
    """p's case of a: nearest person's distances X1 (1, 11, 23), second-nearest X2 (3, 12,
    26), two people each (n 2): leaving one of them out raises log X1 by (log X2 - log X1) /
    2 on average. The jackknife carries (n - 1) / (n + 1) = 1/3 of that on: X1 (X1 / X2) ^
    (1/6); the same step all of it: X1 (X1 / X2) ^ (1/2). An activity only one other person
    did (n 1), or X1 = 0: as it is."""
    _, people = people_scan(_three_people())
    x1, x2 = np.array([1.0, 11.0, 23.0]), np.array([3.0, 12.0, 26.0])
    np.testing.assert_allclose(extrapolated(people, "jackknife")[0], x1 * (x1 / x2) ** (1 / 6))
    np.testing.assert_allclose(extrapolated(people, "same step")[0], x1 * (x1 / x2) ** 0.5)
    lone = np.array([[[INF, INF], [2.0, 0.0], [INF, 5.0]]])
    np.testing.assert_allclose(extrapolated(lone, "jackknife"), [[2.0, 0.0]])
    with pytest.raises(ValueError, match="unknown correction"):
        extrapolated(lone, "median")


def test_median_ratio_by_hand() -> None:
    """Two held-out cases, three people. Case 0 (activity 0, person 0 held out): q (1, 5), r
    (2, 4): nearest 1; r left out too 1, q left out 2. Case 1 (activity 1, person 1 held
    out): p (3, 6), r (7, 9): nearest 3; r left out 3, p left out 7. Medians: nearest (1, 3)
    2, with a second person left out (1, 2, 3, 7) 2.5: 0.8. No people: 1."""
    people = np.array([[[INF, INF], [1.0, 5.0], [2.0, 4.0]],
                       [[3.0, 6.0], [INF, INF], [7.0, 9.0]]])  # fmt: skip
    np.testing.assert_array_equal(np.sort(second_left_out(people)), [1.0, 2.0, 3.0, 7.0])
    assert median_ratio(people, np.array([0, 1])) == pytest.approx(0.8)
    assert median_ratio(np.zeros((2, 0, 2)), np.array([0, 1])) == 1.0


def test_corrected_leaves_a_scan_without_people() -> None:
    """A case base of one person is held out by time: no people to leave out, the scan as it
    is; with people, the median ratio scales every distance and keeps the rest."""
    held = (np.array([[1.0, 2.0]]), np.array([0]), "time", np.array(["r"], dtype=object))
    assert corrected(held, np.zeros((1, 0, 2)), "jackknife") is held
    people = np.array([[[INF, INF], [1.0, 5.0], [2.0, 4.0]],
                       [[3.0, 6.0], [INF, INF], [7.0, 9.0]]])  # fmt: skip
    seen = people.min(axis=1)
    subject = (seen, np.array([0, 1]), "subject", np.array(["p", "q"], dtype=object))
    fixed = corrected(subject, people, "median ratio")
    np.testing.assert_allclose(fixed[0], 0.8 * seen)
    assert fixed[2] == "subject"


def test_judges_on_the_corrected_scan() -> None:
    """The judges are spread-margin (and spread-far) calibrated on the corrected scans: with
    the median ratio every held-out score stays (the margin and the distance in spreads), so
    the power and the thresholds are the uncorrected judge's, and the spreads and the far
    bound are the uncorrected ones times the ratio."""
    cb = _three_people()
    held, people = people_scan(cb)
    made = judges(cb.labels, held, people)
    plain = SpreadMargin.of(cb, held=held)
    k = median_ratio(people, held[1])
    assert 0.0 < k < 1.0
    assert isinstance(made["jackknife"], SpreadMargin)
    assert isinstance(made["median ratio + far"], SpreadFar)
    np.testing.assert_allclose(made["median ratio"].thresholds, plain.thresholds)
    assert made["median ratio"].power == plain.power
    np.testing.assert_allclose(made["median ratio"].spreads, np.array(plain.spreads) * k)
    far = SpreadFar.bounding(plain, held).far
    assert made["median ratio + far"].far == pytest.approx(far * k)


def test_one_more_person_by_hand() -> None:
    """Four held-out cases of activity 0, each measured against one other person (n 1): own
    distances 1, 2, 3, 4 (F 1/8, 3/8, 5/8, 7/8), cross distances 10, 20, 30, 40. The least of
    two people's at the same survival: the quantile 1 - sqrt(1 - F) of the pool, read
    linearly (1 + 3 q; 10 + 30 q). Against no person (n 0) an entry stays."""
    seen = np.array([[1.0, 10.0], [2.0, 20.0], [3.0, 30.0], [4.0, 40.0]])
    people = np.stack([np.full_like(seen, INF), seen], axis=1)
    q = 1.0 - np.sqrt(1.0 - np.array([1, 3, 5, 7]) / 8.0)
    moved = one_more_person(seen, np.zeros(4, dtype=int), people)
    np.testing.assert_allclose(moved[:, 0], 1.0 + 3.0 * q)
    np.testing.assert_allclose(moved[:, 1], 10.0 + 30.0 * q)
    alone = np.full((4, 2, 2), INF)
    np.testing.assert_array_equal(one_more_person(seen, np.zeros(4, dtype=int), alone), seen)


def test_choose_correction_needs_three_people_to_stand_in() -> None:
    """Each training person stands in for a new one against a case base of the others, which
    must itself hold out people: with three (p, q, r) every correction is tallied over all
    nine held-out cases, known (all nine: own activity and another within reach) and novel
    (own activity gone: the other two remain, all nine), and the choice is one of them; with
    two people (as HDM05's folds) or a scan held out by time, none and no tally."""
    cb = _three_people()
    held, people = people_scan(cb)
    chosen, tally = choose_correction(cb.labels, held, people)
    assert chosen in ("none", "jackknife", "same step", "median ratio", "one more person")
    assert set(tally) == {"none", "jackknife", "same step", "median ratio", "one more person"}
    assert all(t[1] == 9 and t[3] == 9 for t in tally.values())
    two = (held[0][:6], held[1][:6], "subject", held[3][:6])
    assert choose_correction(cb.labels, two, people[:6, :2]) == ("none", {})
    by_time = (held[0], held[1], "time", held[3])
    assert choose_correction(cb.labels, by_time, np.zeros((9, 0, 3))) == ("none", {})
