"""``DADClassifier`` keeps the scikit-learn estimator contract for input that is a sequence of
PoseSequence (real UI-PRMD clips from the bundled demo).

``check_estimator`` cannot run as a whole: most of its checks feed numeric 2-D arrays, which
are no pose sequences (and DAD's tags say so: ``input_tags.two_d_array = False``). The checks
that do not depend on the input's kind run as they are (``APPLICABLE``); every other check
scikit-learn would run is listed in ``NUMERIC_ONLY`` with its reason, and where the property it
checks means something for pose sequences, a test below checks that property on real clips.
"""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import joblib
import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.model_selection import cross_val_score
from sklearn.pipeline import make_pipeline
from sklearn.utils import estimator_checks as ec

from cbr.dad import DADClassifier
from features.datasets import load_dataset
from features.errors import ConfigError, DataError, InputError
from features.poses import PoseSequence

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"

# Checks about the estimator object itself: they never look at what X holds.
APPLICABLE = (
    ec.check_estimator_cloneable,
    ec.check_estimator_tags_renamed,
    ec.check_valid_tag_types,
    ec.check_estimator_repr,
    ec.check_no_attributes_set_in_init,
    ec.check_mixin_order,
    ec.check_parameters_default_constructible,
    ec.check_get_params_invariance,
    ec.check_set_params,
    ec.check_do_not_raise_errors_in_init_or_set_params,
    # predict before fit must raise NotFittedError whatever X is (here a numeric array)
    ec.check_estimators_unfitted,
)

# Checks that feed numeric 2-D (or 1-D, sparse, complex, memmapped) arrays as X. The test named
# after the arrow checks the same property with pose sequences.
NUMERIC_ONLY = {
    "check_array_api_input": "array-API namespaces of numeric arrays",
    "check_classifier_data_not_an_array": "-> test_x_as_list_tuple_or_object_array",
    "check_classifiers_classes": "-> test_fit_learns_the_sorted_classes_and_predicts_among_them",
    "check_classifiers_one_label": "-> test_one_class_predicts_that_class",
    "check_classifiers_one_label_sample_weights": "DAD takes no sample weights",
    "check_classifiers_regression_target": "-> test_bad_y_is_refused (continuous)",
    "check_classifiers_train": "-> test_fit_learns_the_sorted_classes_and_predicts_among_them",
    "check_complex_data": "complex numbers in a numeric X",
    "check_decision_proba_consistency": "-> test_decision_function_proba_and_predict_agree",
    "check_dict_unchanged": "-> test_predicting_changes_nothing",
    "check_dont_overwrite_parameters": "-> test_fit_keeps_the_parameters",
    "check_dtype_object": "object dtype of a numeric table",
    "check_estimator_sparse_array": "sparse numeric X",
    "check_estimator_sparse_matrix": "sparse numeric X",
    "check_estimator_sparse_tag": "sparse numeric X",
    "check_estimators_dtypes": "float32/int dtypes of a numeric X",
    "check_estimators_empty_data_messages": "-> test_bad_x_is_refused (empty)",
    "check_estimators_fit_returns_self": "-> test_fit_learns_the_sorted_classes_and_...",
    "check_estimators_nan_inf": "NaN in a pose is a missing joint, which DAD handles",
    "check_estimators_overwrite_params": "-> test_fit_keeps_the_parameters",
    "check_estimators_partial_fit_n_features": "DAD has no partial_fit",
    "check_estimators_pickle": "-> test_pickle_round_trip_predicts_the_same",
    "check_f_contiguous_array_estimator": "memory layout of a numeric X",
    "check_fit1d": "-> test_bad_x_is_refused (numeric array)",
    "check_fit2d_1feature": "a table with one column",
    "check_fit2d_1sample": "-> test_one_clip_fits",
    "check_fit2d_predict1d": "-> test_bad_x_is_refused (single PoseSequence)",
    "check_fit_check_is_fitted": "-> test_unfitted_raises_not_fitted_error",
    "check_fit_idempotent": "-> test_fitting_twice_gives_the_same_predictions",
    "check_fit_score_takes_y": "-> test_score_is_accuracy_and_cross_validation_runs",
    "check_methods_sample_order_invariance": "-> test_order_and_batches_do_not_matter",
    "check_methods_subset_invariance": "-> test_order_and_batches_do_not_matter",
    "check_n_features_in": "a pose sequence has no feature count (n_features_in_)",
    "check_n_features_in_after_fitting": "a pose sequence has no feature count",
    "check_pipeline_consistency": "-> test_in_a_pipeline_it_predicts_the_same",
    "check_positive_only_tag_during_fit": "sign of numeric features",
    "check_readonly_memmap_input": "read-only memmapped numeric X",
    "check_requires_y_none": "-> test_bad_y_is_refused (None)",
    "check_supervised_y_2d": "-> test_bad_y_is_refused (2-D)",
    "check_supervised_y_no_nan": "-> test_bad_y_is_refused (NaN, None)",
    "check_non_transformer_estimators_n_iter": "applies to a max_iter parameter; DAD has none",
}


class _AsIfTabular(DADClassifier):
    """DAD claiming to take tables: what scikit-learn would then check."""

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.input_tags.two_d_array = True
        return tags


def _name(check: Any) -> str:
    return str(getattr(check, "func", check).__name__)


def test_every_check_is_run_or_listed_with_its_reason() -> None:
    would_run = {_name(c) for _, c in ec.estimator_checks_generator(_AsIfTabular(), legacy=True)}
    applicable = {_name(c) for c in APPLICABLE}
    assert applicable.isdisjoint(NUMERIC_ONLY)
    assert would_run == applicable | set(NUMERIC_ONLY)
    # and the test each listed property points to exists in this file
    for reason in NUMERIC_ONLY.values():
        if reason.startswith("-> "):
            test = reason[3:].split(" ")[0].rstrip(".")
            assert any(n.startswith(test) for n in globals()), test


@pytest.mark.parametrize("check", APPLICABLE, ids=_name)
def test_applicable_scikit_learn_check(check: Any) -> None:
    check("DADClassifier", DADClassifier())


@pytest.fixture(scope="module")
def clips() -> tuple[list[PoseSequence], np.ndarray]:
    """Subject s01's deep squats and shoulder abductions (6 + 6 real Kinect clips)."""
    data = load_dataset(
        DEMO, labels={"deep_squat", "standing_shoulder_abduction"}, subjects={"s01"}
    )
    return [c.seq for c in data], np.array([c.label for c in data])


def test_fit_learns_the_sorted_classes_and_predicts_among_them(
    clips: tuple[list[PoseSequence], np.ndarray],
) -> None:
    X, y = clips
    clf = DADClassifier()
    assert clf.fit(X, y) is clf
    assert list(clf.classes_) == ["deep_squat", "standing_shoulder_abduction"]
    pred = clf.predict(X)
    assert pred.shape == (12,) and set(pred) <= set(clf.classes_)
    # DAD's rules tell these two movements apart (no training involved)
    assert np.mean(pred == y) >= 0.9


def test_x_as_list_tuple_or_object_array(clips: tuple[list[PoseSequence], np.ndarray]) -> None:
    X, y = clips
    want = DADClassifier().fit(X, y).predict(X)
    as_array = np.empty(len(X), dtype=object)
    as_array[:] = X
    for x_kind, y_kind in ((tuple(X), list(y)), (as_array, tuple(y))):
        got = DADClassifier().fit(x_kind, y_kind).predict(x_kind)
        assert got.tolist() == want.tolist()


def test_one_class_predicts_that_class(clips: tuple[list[PoseSequence], np.ndarray]) -> None:
    X, _ = clips
    clf = DADClassifier().fit(X[:3], ["squat"] * 3)
    assert clf.predict(X).tolist() == ["squat"] * 12


def test_one_clip_fits(clips: tuple[list[PoseSequence], np.ndarray]) -> None:
    X, y = clips
    assert DADClassifier().fit(X[:1], y[:1]).predict(X[:2]).tolist() == [y[0]] * 2


def test_decision_function_proba_and_predict_agree(
    clips: tuple[list[PoseSequence], np.ndarray],
) -> None:
    X, y = clips
    clf = DADClassifier().fit(X, y)
    scores, proba = clf.decision_function(X), clf.predict_proba(X)
    assert scores.shape == proba.shape == (12, 2)
    assert np.allclose(proba.sum(axis=1), 1.0) and (proba >= 0).all()
    pred = clf.predict(X)
    assert (clf.classes_[scores.argmax(axis=1)] == pred).all()
    assert (clf.classes_[proba.argmax(axis=1)] == pred).all()


def test_predicting_changes_nothing(clips: tuple[list[PoseSequence], np.ndarray]) -> None:
    X, y = clips
    clf = DADClassifier().fit(X, y)
    before = joblib.hash(clf.__dict__)
    for method in (clf.predict, clf.predict_proba, clf.decision_function):
        method(X[:2])
        assert joblib.hash(clf.__dict__) == before, method.__name__


def test_fit_keeps_the_parameters(clips: tuple[list[PoseSequence], np.ndarray]) -> None:
    X, y = clips
    clf = DADClassifier(window_s=3.0, step_s=0.5)
    params = joblib.hash(clf.get_params())
    clf.fit(X, y)
    assert joblib.hash(clf.get_params()) == params
    assert clf.get_params() == {"add": None, "window_s": 3.0, "step_s": 0.5}


def test_get_and_set_params_and_clone(clips: tuple[list[PoseSequence], np.ndarray]) -> None:
    X, y = clips
    clf = DADClassifier().fit(X, y)
    assert clf.set_params(window_s=3.0) is clf and clf.get_params()["window_s"] == 3.0
    with pytest.raises(ValueError, match="Invalid parameter 'windows'"):
        clf.set_params(windows=3.0)
    copy = clone(clf)
    assert copy.get_params() == clf.get_params() and copy is not clf
    assert not hasattr(copy, "classes_")  # a clone is unfitted
    # a bad parameter is found at fit, naming it (scikit-learn validates in fit)
    with pytest.raises(ConfigError, match="window_s must be a number > 0, got -1"):
        DADClassifier(window_s=-1).fit(X, y)


def test_pickle_round_trip_predicts_the_same(
    clips: tuple[list[PoseSequence], np.ndarray],
) -> None:
    X, y = clips
    clf = DADClassifier().fit(X, y)
    again = pickle.loads(pickle.dumps(clf))
    assert again.get_params() == clf.get_params()
    assert again.predict(X).tolist() == clf.predict(X).tolist()
    np.testing.assert_array_equal(again.decision_function(X), clf.decision_function(X))


def test_fitting_twice_gives_the_same_predictions(
    clips: tuple[list[PoseSequence], np.ndarray],
) -> None:
    X, y = clips
    clf = DADClassifier()
    first = clf.fit(X, y).predict_proba(X)
    clf.fit(X[:4], ["a", "b", "a", "b"])  # fitted on something else in between
    np.testing.assert_array_equal(clf.fit(X, y).predict_proba(X), first)


def test_order_and_batches_do_not_matter(clips: tuple[list[PoseSequence], np.ndarray]) -> None:
    X, y = clips
    clf = DADClassifier().fit(X, y)
    whole = clf.decision_function(X)
    halves = np.vstack([clf.decision_function(X[:5]), clf.decision_function(X[5:])])
    np.testing.assert_array_equal(halves, whole)
    order = np.random.default_rng(0).permutation(len(X))
    np.testing.assert_array_equal(clf.decision_function([X[i] for i in order]), whole[order])


def test_in_a_pipeline_it_predicts_the_same(
    clips: tuple[list[PoseSequence], np.ndarray],
) -> None:
    X, y = clips
    pipe = make_pipeline(DADClassifier()).fit(X, y)
    assert pipe.predict(X).tolist() == DADClassifier().fit(X, y).predict(X).tolist()


def test_score_is_accuracy_and_cross_validation_runs(
    clips: tuple[list[PoseSequence], np.ndarray],
) -> None:
    X, y = clips
    clf = DADClassifier().fit(X, y)
    assert clf.score(X, y) == pytest.approx(np.mean(clf.predict(X) == y))
    scores = cross_val_score(DADClassifier(), X, y, cv=2)
    assert scores.shape == (2,) and ((scores >= 0) & (scores <= 1)).all()


def test_unfitted_raises_not_fitted_error(clips: tuple[list[PoseSequence], np.ndarray]) -> None:
    X, _ = clips
    for method in ("predict", "predict_proba", "decision_function"):
        with pytest.raises(NotFittedError):
            getattr(DADClassifier(), method)(X[:1])


@pytest.mark.parametrize(
    ("make_x", "message"),
    [
        (lambda X: np.zeros((12, 3)), "got a float64 array of shape (12, 3)"),
        (lambda X: X[0], "got a single PoseSequence"),
        (lambda X: [*X[:11], "clip.npz"], "X[11] is of type str, not a PoseSequence"),
        (lambda X: None, "got NoneType"),
    ],
    ids=["numeric array", "single PoseSequence", "a file name", "None"],
)
def test_bad_x_is_refused(
    clips: tuple[list[PoseSequence], np.ndarray], make_x: Any, message: str
) -> None:
    X, y = clips
    with pytest.raises(InputError) as info:
        DADClassifier().fit(make_x(X), y)
    assert message in str(info.value) and str(info.value).startswith("X: ")
    fitted = DADClassifier().fit(X, y)
    with pytest.raises(InputError, match="X: is empty: at least one clip is needed"):
        fitted.predict([])
    with pytest.raises(InputError, match="X: is empty"):
        DADClassifier().fit([], [])


@pytest.mark.parametrize(
    ("make_y", "message"),
    [
        (lambda y: None, "y: is None: one label per clip is needed"),
        (lambda y: [*y[:11], None], "y[11] is None: every clip needs a label"),
        (lambda y: [*y[:11], float("nan")], "y[11] is nan: every clip needs a label"),
        (lambda y: np.array([0.5, 1.0] * 6), "Unknown label type: continuous"),
        (lambda y: y.reshape(-1, 1), "y: must be 1-D (one label per clip), got shape (12, 1)"),
        (lambda y: y[:11], "X has 12 clips but y has 11 labels"),
        (lambda y: [*y[:11], 3], "y: mixes label types (number, string)"),
    ],
    ids=["None", "a None label", "a NaN label", "continuous", "2-D", "too short", "mixed"],
)
def test_bad_y_is_refused(
    clips: tuple[list[PoseSequence], np.ndarray], make_y: Any, message: str
) -> None:
    X, y = clips
    with pytest.raises(InputError) as info:
        DADClassifier().fit(X, make_y(y))
    # one line, naming y; a ValueError for scikit-learn code, a DataError for the command line
    text = str(info.value)
    assert message in text and text.startswith("y: ") and "\n" not in text
    assert isinstance(info.value, ValueError) and isinstance(info.value, DataError)
