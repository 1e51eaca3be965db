"""The one vote (cbr.reuse.vote), worked out by hand, and its three users agreeing on ties."""

from __future__ import annotations

import numpy as np
import pytest

from cbr.casebase import CaseBase
from cbr.fitting import Cases, knn_predict
from cbr.maintenance import _knn_vote
from cbr.problem import FeatureConfig
from cbr.retrieve import retrieve
from cbr.reuse import decide, reuse, vote
from cbr.similarity import get_measure


def test_distance_vote_is_one_over_distance() -> None:
    # weights 1, 1/2, 1/4: a gets 1 / 1.75, b gets 0.75 / 1.75
    p = vote(np.array([[1.0, 2.0, 4.0]]), np.array([[0, 1, 1]]), 2)
    np.testing.assert_allclose(p, [[4 / 7, 3 / 7]])


def test_uniform_vote_counts_cases() -> None:
    p = vote(np.array([[1.0, 2.0, 3.0]]), np.array([[0, 1, 1]]), 3, "uniform")
    np.testing.assert_allclose(p, [[1 / 3, 2 / 3, 0.0]])


def test_exact_matches_decide_alone_and_ties_go_to_the_first_class() -> None:
    # two exact matches of different classes, one near case of class 1: only the exact ones
    # vote, one each: a tie, won by class 0
    d = np.array([[0.0, 1e-13, 0.5]])
    p = vote(d, np.array([[1, 0, 1]]), 2)
    np.testing.assert_allclose(p, [[0.5, 0.5]])
    assert decide(p)[0] == 0


def test_empty_slots_do_not_vote_and_an_empty_row_is_undecided() -> None:
    d = np.array([[2.0, np.inf], [np.inf, np.inf]])
    p = vote(d, np.array([[1, 0], [0, 0]]), 2)
    np.testing.assert_allclose(p, [[0.0, 1.0], [0.5, 0.5]])


def test_mismatched_shapes_are_refused() -> None:
    with pytest.raises(ValueError, match="must be"):
        vote(np.ones((2, 3)), np.zeros((2, 2), dtype=int), 2)


def test_reuse_inner_cross_validation_and_editors_break_a_tie_alike() -> None:
    # cases at x = -1 (label b) and x = +1 (label a); a query at 0 is equally far from both
    values = np.array([[-1.0], [1.0]])
    labels = np.array(["b", "a"], dtype=object)
    cb = CaseBase(
        FeatureConfig(level="qmp"), get_measure("euclidean"), values, labels, ("x",), ("x",)
    )
    by_reuse = reuse(retrieve(cb, np.array([0.0]), 2), np.array(["a", "b"])).label
    cases = Cases(values, labels, np.arange(2), None, False)
    by_inner = knn_predict(cases, np.array([[0.0]]), 2)[0]
    by_editor = _knn_vote(np.array([[1.0, 1.0]]), labels, np.array(["a", "b"]), 2, "distance")[0]
    assert by_reuse == by_inner == by_editor == "a"


def test_solutions_of_many_queries_are_each_querys_own_vote_by_hand() -> None:
    # query 0: weights 1, 1/2, 1/4 (a, b, b) -> a 4/7; query 1: an exact match of b alone
    # votes; query 2: no case retrieved, equal shares, the tie to the first class
    from cbr.reuse import solutions

    classes = np.array(["a", "b"], dtype=object)
    d = np.array([[1.0, 2.0, 4.0], [0.0, 0.5, 1.0], [np.inf, np.inf, np.inf]])
    c = np.array([[0, 1, 1], [1, 0, 0], [0, 0, 0]])
    got = solutions(d, c, classes)
    assert [s.label for s in got] == ["a", "b", "a"]
    assert [s.confidence for s in got] == pytest.approx([4 / 7, 1.0, 0.5])
    assert [s.vote_share for s in got] == pytest.approx([4 / 7, 1.0, 0.5])
    np.testing.assert_allclose(got[0].proba, [4 / 7, 3 / 7])
