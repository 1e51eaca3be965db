"""A column a clip never showed is a fill, not a measurement: it is left out of the distance
(hunt 53a). The distance over the measured columns is scaled to all of them as scikit-learn's
``nan_euclidean_distances`` scales a pair's present coordinates."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from sklearn.metrics.pairwise import nan_euclidean_distances

from cbr.estimator import CaseBaseClassifier
from cbr.problem import Problem, extract_problem
from cbr.similarity.euclidean import Euclidean
from features.datasets import split_by_track
from features.label_tracks import LabelTrack
from features.poses import PoseSequence
from tests.once import made_once
from tests.test_segment import NAMES, _cmu

LEG_WORDS = ("knee", "ankle", "heel", "foot")


def test_a_value_missing_on_the_query_side_is_left_out_and_the_rest_scaled_by_hand() -> None:
    # cases (0, 1, 2, 3) and (1, 1, 1, 1); the query (1, 0, ?, 2), its third value a fill (9)
    # row 0: (1 + 1 + 1) over 3 of 4 columns -> sqrt(4 / 3 * 3) = 2
    # row 1: (0 + 1 + 1) -> sqrt(4 / 3 * 2) = sqrt(8 / 3)
    rows = np.array([[0.0, 1.0, 2.0, 3.0], [1.0, 1.0, 1.0, 1.0]])
    problem = Problem(
        np.array([1.0, 0.0, 9.0, 2.0]), ("a", "b", "c", "d"), ("a", "b", "c", "d"), "fluents",
        unseen=frozenset({"c"}),
    )  # fmt: skip
    measured = problem.measured()
    assert measured is not None and measured.tolist() == [True, True, False, True]
    for exact in (False, True):
        e = Euclidean(exact=exact)
        d = e.distances_measured(problem.values, e.build_index(rows), measured)
        np.testing.assert_allclose(d, [2.0, math.sqrt(8.0 / 3.0)], rtol=1e-6)
    # the fill compared as a measurement, as before: sqrt(1 + 1 + 49 + 1) = sqrt(52)
    assert Euclidean().distances(problem.values, rows)[0] == pytest.approx(math.sqrt(52.0))


def test_a_summary_and_a_sequence_leave_out_every_value_of_a_column_never_shown() -> None:
    # a summary: the column's name before '@'; a (frames, columns) sequence, frame after frame
    names = ("x@mean", "y@mean", "x@min", "y@min", "x@phase1", "y@phase1")
    summary = Problem(np.zeros(6), names, names, "fluents", unseen=frozenset({"y"}))
    assert summary.measured().tolist() == [True, False] * 3  # type: ignore[union-attr]
    seq = Problem(np.zeros((3, 2)), ("x", "y"), ("x", "y"), "fluents", unseen=frozenset({"x"}))
    assert seq.measured().tolist() == [False, True] * 3  # type: ignore[union-attr]
    # every column measured, or none: nothing to leave out
    assert Problem(np.zeros(2), ("x", "y"), ("x", "y"), "fluents").measured() is None
    both = Problem(np.zeros(2), ("x", "y"), ("x", "y"), "fluents", unseen=frozenset({"x", "y"}))
    assert both.measured() is None


@pytest.fixture(scope="module")
def cmu_windows(
    shared_data: Path, tmp_path_factory: pytest.TempPathFactory
) -> tuple[CaseBaseClassifier, PoseSequence, PoseSequence]:
    """A case base of 2-s windows of CMU 13_29 (two of each labelled stretch that holds one:
    its start and its middle; every 4th frame, 30 fps), and the middle window of 13_30's
    twist, as filmed and with its legs out of the picture (knees, ankles, heels and feet
    missing in every frame)."""
    recordings = made_once(tmp_path_factory, "cmu-13-29-31", lambda _: _cmu(shared_data))
    names = tmp_path_factory.mktemp("hunt53a") / "names.txt"
    names.write_text(NAMES, encoding="utf-8")

    def stretches(t: str) -> list[tuple[PoseSequence, str]]:
        labels = LabelTrack(shared_data / "cmu-mocap6" / "truelabels" / f"{t}.txt", 0.1, names)
        return [(p, str(lab)) for p, lab in split_by_track(recordings[t], labels)]

    def window(p: PoseSequence, start: int) -> PoseSequence:
        return PoseSequence(p.positions[start : start + 240 : 4], p.joint_names, p.fps / 4)

    X, y = [], []
    for p, label in stretches("13_29"):
        if p.n_frames >= 240:
            X += [window(p, 0), window(p, (p.n_frames - 240) // 2)]
            y += [label, label]
    clf = CaseBaseClassifier(feature_weights="none").fit(X, y)
    twist = next(p for p, label in stretches("13_30") if label == "Twist")
    seen = window(twist, (twist.n_frames - 240) // 2)
    legs = [i for i, n in enumerate(seen.joint_names) if any(w in n for w in LEG_WORDS)]
    positions = seen.positions.copy()
    positions[:, legs] = np.nan
    return clf, seen, PoseSequence(positions, seen.joint_names, seen.fps)


def test_a_twist_with_its_legs_out_of_the_picture_is_told_by_what_it_shows(
    cmu_windows: tuple[CaseBaseClassifier, PoseSequence, PoseSequence],
) -> None:
    clf, seen, legless = cmu_windows
    assert clf.predict([seen]).tolist() == ["Twist"]
    solved = clf.solve([legless], flag=False)[0]
    problem = solved.problem
    assert any("knee" in n for n in problem.unseen)  # the leg columns are fills
    # the fills (a knee at 90 degrees, a leg not bent) made it a KneeRaise at 13.9, every
    # case 13.9 to 16 away; the columns it shows make it the twist it is
    assert solved.solution.label == "Twist"
    # the distances are scikit-learn's nan_euclidean_distances with the fills missing
    cb = clf.case_base_
    measured = problem.measured()
    assert measured is not None
    query = np.where(measured, np.asarray(problem.values).reshape(-1), np.nan)
    want = nan_euclidean_distances(query[None], np.asarray(cb.problems).reshape(len(cb), -1))[0]
    order = np.argsort(want, kind="stable")[: len(solved.retrieval.indices)]
    np.testing.assert_array_equal(solved.retrieval.indices, order)
    np.testing.assert_allclose(solved.retrieval.distances, want[order], rtol=1e-5)


def test_a_clip_computed_a_piece_at_a_time_knows_the_columns_it_never_showed(
    cmu_windows: tuple[CaseBaseClassifier, PoseSequence, PoseSequence],
) -> None:
    clf, _, legless = cmu_windows
    config = clf.case_base_.config
    whole = extract_problem(legless, config, 0)
    pieces = extract_problem(legless, config, 16)
    assert whole.unseen and pieces.unseen == whole.unseen
    np.testing.assert_allclose(pieces.values, whole.values, atol=1e-9)


def _label_by_hand(clf: CaseBaseClassifier, d: np.ndarray) -> str:
    """The label the k nearest cases at distances ``d`` vote, each by 1 / distance."""
    labels = np.asarray(clf.case_base_.labels).astype(str)
    near = np.argsort(d, kind="stable")[: int(clf.k)]
    votes: dict[str, float] = {}
    for i in near:
        votes[labels[i]] = votes.get(labels[i], 0.0) + 1.0 / float(d[i])
    return max(sorted(votes), key=lambda lab: votes[lab])


def test_feedback_and_counterfactuals_leave_out_the_fills_the_answer_left_out(
    cmu_windows: tuple[CaseBaseClassifier, PoseSequence, PoseSequence],
) -> None:
    # one query, one answer (hunt 53v): the legless twist's feedback (retain's novelty and
    # benefit, revise's nearest case) and its counterfactual compared its fills, which solve
    # leaves out: the nearest case at 13.9 and a KneeRaise answer instead of 7.3 and Twist
    from cbr.counterfactual import counterfactual
    from cbr.retain import decide_retention
    from cbr.revise import plan_revision

    clf, _, legless = cmu_windows
    solved = clf.solve([legless], flag=False)[0]
    problem, cb = solved.problem, clf.case_base_
    measured = problem.measured()
    assert measured is not None

    def by_hand(values: np.ndarray) -> np.ndarray:
        query = np.where(measured, np.asarray(values).reshape(-1), np.nan)
        return nan_euclidean_distances(query[None], np.asarray(cb.problems).reshape(len(cb), -1))[0]

    want = by_hand(problem.values)
    assert clf.answer(problem) == _label_by_hand(clf, want) == "Twist"
    revision = plan_revision(cb, problem, "Twist")
    assert revision.index == int(np.argmin(want))
    assert revision.distance == pytest.approx(float(want.min()), rel=1e-5)
    decision = decide_retention(cb, problem, "Twist", scale=1.0)
    assert decision.novelty == pytest.approx(float(want.min()), rel=1e-5)
    # the counterfactual toward another label, checked as the answer is: by the distances
    # over the columns shown, and it changes no column the clip never showed
    contrast = clf.explain_solved(solved).contrast
    assert contrast is not None
    other = contrast.label
    cf = counterfactual(
        cb,
        np.asarray(problem.values),
        other,
        lambda v: clf.answer(dataclasses.replace(problem, values=v)),
        int(clf.k),
        measured=measured,
    )
    assert cf.answer == _label_by_hand(clf, by_hand(cf.values))
    unshown = ~measured
    np.testing.assert_array_equal(
        cf.values.reshape(-1)[unshown], problem.values.reshape(-1)[unshown]
    )
    # the explanation's counterfactual is that one: its check says what the answer says
    assert (contrast.answer, contrast.valid) == (cf.answer, cf.answer == other)


def test_a_revision_moves_a_case_toward_what_the_clip_showed_not_toward_its_fills(
    cmu_windows: tuple[CaseBaseClassifier, PoseSequence, PoseSequence],
) -> None:
    # the legless twist's nearest case is a Twist: revised with rate 0.25 it moved every
    # value a quarter of the way toward the clip's, its knees toward the fills' 90 degrees
    # (hunt 53v); now the values the clip showed move, p + 0.25 (q - p), the others stay
    from cbr.revise import revise

    clf, _, legless = cmu_windows
    problem = clf.solve([legless], flag=False)[0].problem
    cb = clf.case_base_.subset(np.arange(len(clf.case_base_)))  # a copy to revise
    measured = problem.measured()
    assert measured is not None
    rev = revise(cb, problem, "Twist", rate=0.25)
    assert rev.action == "moved"
    before = np.asarray(clf.case_base_.problems[rev.index], dtype=np.float64).reshape(-1)
    q = np.asarray(problem.values, dtype=np.float64).reshape(-1)
    after = np.asarray(cb.problems[rev.index], dtype=np.float64).reshape(-1)
    np.testing.assert_allclose(after[measured], before[measured] + 0.25 * (q - before)[measured])
    np.testing.assert_array_equal(after[~measured], before[~measured])
    assert not np.allclose(q[~measured], before[~measured])  # the fills would have moved them
