"""CaseBaseClassifier: the scikit-learn contract, bad input, explanations, tslearn parity."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.model_selection import cross_val_score
from tslearn.neighbors import KNeighborsTimeSeriesClassifier

from cbr.estimator import CaseBaseClassifier
from cbr.evaluation.peers import cache_tslearn_kernels
from features.errors import ConfigError, DataError
from features.fluents import evaluate
from tests.test_cbr_clips import ACTIVITIES, arm_dataset

# tslearn's DTW compiled once per machine, not once per process (numba's disk cache)
cache_tslearn_kernels()


# on one xdist worker: the module's data made once, not once per worker
pytestmark = pytest.mark.xdist_group("cbr_estimator")


@pytest.fixture(scope="module")
def data() -> tuple[list, np.ndarray, list, np.ndarray]:
    X, y = arm_dataset(8, seed=1)
    Xt, yt = arm_dataset(4, seed=2)
    return X, y, Xt, yt


def test_init_stores_params_and_clone_round_trips() -> None:
    clf = CaseBaseClassifier(similarity="signature", k=3, similarity_params={"depth": 3})
    assert clf.get_params()["similarity_params"] == {"depth": 3}
    twin = clone(clf)
    assert twin.get_params() == clf.get_params() and twin is not clf
    assert not hasattr(twin, "case_base_")


@pytest.mark.parametrize("similarity", ["euclidean", "dtw", "signature"])
def test_fit_predict_on_known_activities(similarity: str, data: tuple) -> None:
    X, y, Xt, yt = data
    clf = CaseBaseClassifier(similarity=similarity, k=3).fit(X, y)
    assert list(clf.classes_) == sorted(ACTIVITIES)
    assert clf.score(Xt, yt) == 1.0  # three clearly different arm movements
    proba = clf.predict_proba(Xt)
    assert proba.shape == (len(Xt), 3)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0)
    assert len(clf.case_base_) == len(X)


def test_cross_val_score_and_object_array_input(data: tuple) -> None:
    X, y, _, _ = data
    Xo = np.empty(len(X), dtype=object)
    Xo[:] = X
    scores = cross_val_score(CaseBaseClassifier(similarity="euclidean", k=1), Xo, y, cv=3)
    assert scores.shape == (3,) and scores.min() == 1.0


def test_integer_labels_come_back_as_integers(data: tuple) -> None:
    X, y, Xt, yt = data
    to_int = {a: i * 10 for i, a in enumerate(ACTIVITIES)}
    clf = CaseBaseClassifier(similarity="euclidean", k=1).fit(X, [to_int[v] for v in y])
    pred = clf.predict(Xt)
    assert pred.dtype.kind == "i"
    np.testing.assert_array_equal(pred, [to_int[v] for v in yt])


def test_bad_input_gets_clear_errors(data: tuple) -> None:
    X, y, _, _ = data
    with pytest.raises(DataError, match="training set is empty"):
        CaseBaseClassifier().fit([], [])
    with pytest.raises(DataError, match="only one activity"):
        CaseBaseClassifier().fit(X[:3], ["squat"] * 3)
    with pytest.raises(DataError, match="3 clips but y has shape"):
        CaseBaseClassifier().fit(X[:3], ["a", "b"])
    with pytest.raises(DataError, match=r"X\[1\] is a str"):
        CaseBaseClassifier().fit([X[0], "clip.npz"], ["a", "b"])
    with pytest.raises(ConfigError, match="k: must be a positive integer"):
        CaseBaseClassifier(k=0).fit(X, y)
    with pytest.raises(ConfigError, match="unknown similarity 'cosine'"):
        CaseBaseClassifier(similarity="cosine").fit(X, y)
    with pytest.raises(ConfigError, match="features: must be 'fluents' or 'qmp'"):
        CaseBaseClassifier(features="pixels").fit(X, y)


def test_explanations_cite_real_fluent_names(data: tuple) -> None:
    X, y, Xt, yt = data
    clf = CaseBaseClassifier(similarity="dtw", k=3).fit(X, y)
    left = next(i for i, v in enumerate(yt) if v == ACTIVITIES[0])
    exp = clf.explain([Xt[left]])[0]
    assert exp.label == ACTIVITIES[0]
    # the left arm swings out sideways above the 9pi/16 armpit threshold ("raised") and away
    # from the body in the frontal plane ("outward"); the right arm hangs still
    matched = [m.removesuffix(" (at times)") for m in exp.matched]
    assert {"left arm raised", "left arm outward"} & set(matched)
    assert "right arm raised" not in matched
    assert "left arm raised" not in exp.not_seen
    words = set(evaluate(Xt[left]).words)
    only_here = [m.removesuffix(" (at times)") for m in exp.only_here]
    assert set(matched) <= words and set(only_here) <= words
    assert exp.text.startswith(ACTIVITIES[0]) and exp.matched[0] in exp.verbose
    assert exp.contrast is not None and exp.contrast.label != ACTIVITIES[0]
    # under DTW a feature is a signal's channels over time; the counterfactual holds
    assert exp.contrast.valid and exp.contrast.answer == exp.contrast.label
    assert all(n["label"] in ACTIVITIES for n in exp.neighbours)


def test_dtw_classifier_predicts_like_tslearn_on_the_same_problems(data: tuple) -> None:
    X, y, Xt, _ = data
    rng = np.random.default_rng(0)
    y_noisy = y.copy()
    flip = rng.choice(len(y), 6, replace=False)  # label noise so k matters
    y_noisy[flip] = rng.permutation(y_noisy[flip])
    clf = CaseBaseClassifier(
        similarity="dtw", k=3, weights="uniform", similarity_params={"radius": 3}
    ).fit(X, y_noisy)
    train = np.stack([p.values for p in clf.problems(X)])
    test = np.stack([p.values for p in clf.problems(Xt)])
    peer = KNeighborsTimeSeriesClassifier(
        n_neighbors=3,
        metric="dtw",
        metric_params={"global_constraint": "sakoe_chiba", "sakoe_chiba_radius": 3},
    ).fit(train, y_noisy.astype(str))
    np.testing.assert_array_equal(clf.predict(Xt).astype(str), peer.predict(test))


def test_trim_at_fit_keeps_every_activity(data: tuple) -> None:
    X, y, Xt, yt = data
    clf = CaseBaseClassifier(similarity="euclidean", k=3, trim=0.5).fit(X, y)
    labels = clf.case_base_.labels
    assert len(labels) == 12
    assert {str(v): int((labels == v).sum()) for v in np.unique(labels)} == {
        a: 4 for a in ACTIVITIES
    }
    assert clf.score(Xt, yt) == 1.0
