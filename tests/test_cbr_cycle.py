"""The cycle's phases on tiny hand-made case bases whose answers are worked out by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from cbr.casebase import CaseBase
from cbr.maintenance import cnn, renn, trim_novelty_benefit
from cbr.problem import FeatureConfig
from cbr.retain import benefit, novelty, record_retention, retain
from cbr.retrieve import nearest_of_other_label, retrieve
from cbr.reuse import reuse
from cbr.revise import record_revision, revise
from cbr.similarity import Euclidean
from cbr.stored import case_records


def _line(xs: list[float], labels: list[str]) -> CaseBase:
    """Cases on a line: problem = (x, 0) so every distance is |x_i - x_j|."""
    p = np.array([[x, 0.0] for x in xs])
    return CaseBase(FeatureConfig(), Euclidean(exact=True), p, labels, ("x", "y"), ("x", "y"))


def test_reuse_weighted_vote_by_hand() -> None:
    cb = _line([0.0, 1.0, 3.0, 10.0], ["a", "a", "b", "b"])
    r = retrieve(cb, np.array([2.0, 0.0]), 3)  # neighbours at distance 1 (x=1, x=3), 2 (x=0)
    assert list(r.indices) == [1, 2, 0]  # tie at distance 1 -> lower index first
    sol = reuse(r, np.array(["a", "b"]), "distance")
    # weights 1/1 (a), 1/1 (b), 1/2 (a): a gets 1.5 of 2.5
    assert sol.label == "a" and sol.confidence == pytest.approx(0.6)
    uni = reuse(r, np.array(["a", "b"]), "uniform")
    assert uni.label == "a" and uni.confidence == pytest.approx(2 / 3)
    assert nearest_of_other_label(cb, np.array([0.2, 0.0]), "a") == (2, pytest.approx(2.8))


def test_revise_moves_the_nearest_same_label_case() -> None:
    cb = _line([0.0, 4.0, 10.0], ["a", "a", "b"])
    rev = revise(cb, np.array([2.0, 0.0]), "a", rate=0.25)  # nearest: x=0 (tie with 4 -> 0)
    assert rev.action == "moved" and rev.index == 0
    np.testing.assert_allclose(cb.problems[0], [0.5, 0.0])  # 0 + 0.25 * (2 - 0)
    # the index follows the change
    assert retrieve(cb, np.array([0.5, 0.0]), 1).distances[0] == 0.0


def test_revise_relabels_a_case_the_observation_sits_on() -> None:
    cb = _line([0.0, 5.0, 10.0], ["a", "b", "b"])
    rev = revise(cb, np.array([5.1, 0.0]), "a", relabel_margin=0.5)
    # 0.1 from the 'b' case at 5, 5.1 from the nearest 'a': 0.1 < 0.5 * 5.1 -> relabel
    assert (
        rev.action == "relabelled"
        and rev.old_label == "b"
        and list(cb.labels)
        == [
            "a",
            "a",
            "b",
        ]
    )
    cb2 = _line([0.0, 5.0, 10.0], ["a", "b", "b"])
    rev2 = revise(cb2, np.array([3.0, 0.0]), "a", rate=0.5)
    # 2 from 'b' at 5, 3 from 'a' at 0: not close enough to relabel; the 'a' case moves
    assert rev2.action == "moved" and rev2.index == 0
    np.testing.assert_allclose(cb2.problems[0], [1.5, 0.0])


def test_novelty_benefit_and_retain_by_hand() -> None:
    cb = _line([0.0, 1.0, 10.0, 11.0], ["a", "a", "b", "b"])
    q = np.array([6.0, 0.0])
    assert novelty(cb, q, scale=2.0) == pytest.approx(4.0 / 2.0)  # nearest case 4 away
    # k=2 neighbours: x=10 (d 4, b) and x=1 (d 5, a): votes b 1/4, a 1/5
    share_a = (1 / 5) / (1 / 4 + 1 / 5)
    assert benefit(cb, q, "a", k=2) == pytest.approx(1 - share_a)
    d = retain(cb, q, "a", k=2, novelty_threshold=1.5, benefit_threshold=0.5, scale=2.0)
    assert d.retained and len(cb) == 5 and cb.labels[-1] == "a" and cb.origins[-1] == "retained"
    d2 = retain(cb, np.array([0.5, 0.0]), "a", k=2, novelty_threshold=1.5, scale=2.0)
    assert not d2.retained and len(cb) == 5  # 0.5 from a stored case: not novel


def test_cnn_and_renn_by_hand() -> None:
    # two well separated groups plus one mislabelled point inside group a
    xs = [0.0, 0.5, 1.0, 1.5, 2.0, 10.0, 10.5, 11.0, 11.5, 1.2]
    ys = ["a", "a", "a", "a", "a", "b", "b", "b", "b", "b"]
    cb = _line(xs, ys)
    ed = renn(cb, k=3)
    assert ed.size_after == 9 and not ed.kept[9]  # Wilson editing removes the intruder only
    assert ed.accuracy_after >= ed.accuracy_before
    clean = _line(xs[:9], ys[:9])
    c = cnn(clean)
    # Hart: start with the first case of each class; every other case is then right by 1-NN
    assert list(np.flatnonzero(c.kept)) == [0, 5]
    # leave-one-out against {0, 5}: cases 0 and 5 only see the other class's prototype
    assert c.accuracy_after == pytest.approx(7 / 9) and c.accuracy_before == 1.0


def test_renn_and_icf_keep_the_middle_case_of_an_activity_they_drop_whole() -> None:
    """By hand: activity c's three cases (x = 4.9, 5.2, 5.6) sit among b's (x = 4.0 ... 7.0,
    every 0.5): each has two b cases among its three nearest, so ENN drops all three and c
    could no longer be answered. One is kept: 5.2, whose summed distance to the other two
    (0.3 + 0.4) is the least (4.9: 0.3 + 0.7; 5.6: 0.7 + 0.4); the summary says so."""
    from cbr.maintenance import icf

    xs = [0.0, 0.5, 1.0, 4.0, 4.5, 5.0, 5.5, 6.0, 6.5, 7.0, 4.9, 5.2, 5.6]
    ys = ["a"] * 3 + ["b"] * 7 + ["c"] * 3
    for editor in (renn, icf):
        rep = editor(_line(xs, ys), k=3)
        assert list(rep.kept[10:]) == [False, True, False], editor
        assert rep.kept_alone == ("c",)
        assert rep.summary().endswith(
            "; one case kept of 'c', every case of which the editor dropped"
        )
        assert "(3-NN, each of the 13 cases before left out in turn)" in rep.summary()


def test_trim_drops_near_duplicates_first() -> None:
    xs = [0.0, 0.01, 3.0, 6.0, 20.0, 20.01, 23.0, 26.0]
    ys = ["a"] * 4 + ["b"] * 4
    rep = trim_novelty_benefit(_line(xs, ys), keep=0.75, k=1)
    # per activity one of the two near-twins goes (lowest novelty); the spread is kept
    assert rep.size_after == 6
    assert rep.kept[[2, 3, 6, 7]].all() and rep.kept[[0, 1]].sum() == 1
    assert rep.kept[[4, 5]].sum() == 1


def test_revision_and_retention_are_logged_in_one_transaction(tmp_path: Path) -> None:
    store = open_store(tmp_path / "cb.sqlite", create=True)
    cb = _line([0.0, 4.0, 10.0], ["a", "a", "b"])
    with store.transaction() as tx:
        info = tx.create_case_base(
            "x", {"level": "fluents"}, ["x", "y"], ["x", "y"], {"name": "euclidean"}
        )
        ids = tx.add_cases(info, case_records(cb))
    cb.ids = np.array(ids)
    rev = revise(cb, np.array([2.0, 0.0]), "a", rate=0.25)
    q = np.array([7.0, 0.0])
    dec = retain(cb, q, "a", k=1, novelty_threshold=0.0, benefit_threshold=0.0, scale=1.0)
    with store.transaction() as tx:
        info = tx.case_base("x")
        record_revision(tx, info, rev, np.array([2.0, 0.0]))
        new_id = record_retention(tx, info, dec, q, "a")
    stored = store.load_cases("x")
    np.testing.assert_allclose(stored.features[0], [0.5, 0.0])
    assert stored.origins == ("revised", "trained", "trained", "retained")
    log = store.maintenance_log("x")
    assert [e.action for e in log] == ["revise", "retain"] and log[1].case_id == new_id
    assert log[1].novelty == pytest.approx(3.0)  # 7 is 3 from the case at 10


def test_same_features_finds_cases_of_other_activities_within_a_thousandth() -> None:
    """By hand: case 2 (b) differs from case 1 (a) by 0.0009 in one feature: the same; case 4
    (c) from case 3 (a) by 0.0011: not; case 5 equals case 3 but is of its activity; NaN
    matches NaN only (cases 6 and 7, of two activities), never a number (case 8)."""
    from cbr.training import same_features

    p = np.array(
        [[0.0, 0.0], [0.0009, 0.0], [0.0, 1.0], [0.0011, 1.0], [0.0, 1.0], [np.nan, 2.0],
         [np.nan, 2.0], [0.0, 2.0]]
    )  # fmt: skip
    labels = ["a", "b", "a", "c", "a", "d", "e", "f"]
    cb = CaseBase(FeatureConfig(), Euclidean(exact=True), p, labels, ("x", "y"), ("x", "y"),
                  sources=tuple(f"f{i}.npz" for i in range(1, 9)))  # fmt: skip
    assert same_features(cb) == ["f2.npz (b) = f1.npz (a)", "f7.npz (e) = f6.npz (d)"]
    assert same_features(cb.subset(np.array([2, 3, 4, 5, 7]))) == []


def test_trim_accuracy_leaves_out_the_windows_overlapping_each_case() -> None:
    """Cases on a line (1-NN, every distance |x_i - x_j|), windows of one recording: A at x
    0, 0.1, 0.2 (frames 0-240, 60-300, 120-360, all overlapping), B at 0.35, 0.45 (600-840,
    660-900) and A at 1.0 (1200-1440). Each left out alone: 0 -> 0.1 A, 0.1 -> 0 or 0.2 A,
    0.2 -> 0.1 A, 0.35 -> 0.45 B, 0.45 -> 0.35 B, 1.0 -> 0.45 B: 5 of 6 right. With the
    windows overlapping it left out too: 0, 0.1, 0.2 -> 0.35 B, 0.35 and 0.45 -> 0.2 A, 1.0
    -> 0.45 B: none right. From separate files, the first count stands."""
    xs = [0.0, 0.1, 0.2, 0.35, 0.45, 1.0]
    labels = ["A", "A", "A", "B", "B", "A"]
    spans = [(0, 240), (60, 300), (120, 360), (600, 840), (660, 900), (1200, 1440)]
    p = np.array([[x, 0.0] for x in xs])
    for sources, right in ((("rec.npz",) * 6, 0.0), (tuple(f"{i}.npz" for i in range(6)), 5 / 6)):
        cb = CaseBase(FeatureConfig(), Euclidean(exact=True), p, labels, ("x", "y"), ("x", "y"),
                      ids=np.arange(6), sources=sources, frames=tuple(spans))  # fmt: skip
        report = cnn(cb, k=1)
        assert report.accuracy_before == pytest.approx(right)
        assert ("overlapping" in report.measured) == (right == 0.0)
