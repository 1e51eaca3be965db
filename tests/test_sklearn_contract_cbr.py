"""CaseBaseClassifier keeps the scikit-learn estimator contract.

scikit-learn's own checks run where they apply. Those that fit feed numeric 2-D arrays, which
this estimator does not take (its X is a sequence of PoseSequence; ``input_tags.two_d_array``
is False, so ``check_estimator`` itself skips them): their promises are checked below on clips
instead (fit returns self, fit twice, pickle, clone, parameters untouched by fit, classes_ of
y's type, probabilities, score, cross-validation). ``check_param_validation`` does not apply:
bad parameters raise posecbr's ConfigError naming the parameter (one line on the command line)
rather than scikit-learn's private InvalidParameterError.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import sklearn.utils.estimator_checks as checks
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.model_selection import StratifiedKFold, cross_val_score

from cbr.estimator import CaseBaseClassifier
from features.errors import ConfigError, DataError
from tests.test_cbr_clips import arm_dataset

DATA_FREE_CHECKS = (
    "check_no_attributes_set_in_init",
    "check_parameters_default_constructible",
    "check_get_params_invariance",
    "check_set_params",
    "check_estimator_repr",
    "check_estimator_cloneable",
    "check_do_not_raise_errors_in_init_or_set_params",
    "check_estimator_tags_renamed",
    "check_valid_tag_types",
    "check_mixin_order",
    "check_estimators_unfitted",
)


@pytest.mark.parametrize("check", DATA_FREE_CHECKS)
def test_scikit_learn_checks_that_apply(check: str) -> None:
    getattr(checks, check)("CaseBaseClassifier", CaseBaseClassifier())


@pytest.fixture(scope="module")
def clips() -> tuple[list, np.ndarray, list, np.ndarray]:
    X, y = arm_dataset(4, seed=3)
    X_test, y_test = arm_dataset(2, seed=4)
    return X, y, X_test, y_test


def test_fit_returns_self_leaves_parameters_and_is_idempotent(clips: tuple) -> None:
    X, y, X_test, _ = clips
    clf = CaseBaseClassifier(k=3)
    params = clf.get_params()
    assert clf.fit(X, y) is clf
    assert clf.get_params() == params
    first = clf.predict_proba(X_test)
    clf.fit(X[:6], y[:6]).fit(X, y)  # another fit in between changes nothing
    np.testing.assert_array_equal(clf.predict_proba(X_test), first)


def test_pickle_round_trip_and_clone(clips: tuple) -> None:
    X, y, X_test, _ = clips
    clf = CaseBaseClassifier(k=3).fit(X, y)
    again = pickle.loads(pickle.dumps(clf))
    np.testing.assert_array_equal(again.predict(X_test), clf.predict(X_test))
    np.testing.assert_array_equal(again.predict_proba(X_test), clf.predict_proba(X_test))
    fresh = clone(clf)
    assert fresh.get_params() == clf.get_params() and not hasattr(fresh, "case_base_")
    with pytest.raises(NotFittedError):
        fresh.predict(X_test)


def test_classes_keep_the_type_of_y_and_probabilities_follow_them(clips: tuple) -> None:
    X, y, X_test, _ = clips
    codes = {lab: i for i, lab in enumerate(sorted(set(y)))}
    y_int = np.array([codes[v] * 10 for v in y])  # 0, 10, 20: sorted as numbers, not text
    clf = CaseBaseClassifier(k=3).fit(X, y_int)
    assert clf.classes_.dtype.kind == "i" and list(clf.classes_) == [0, 10, 20]
    proba = clf.predict_proba(X_test)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0)
    pred = clf.predict(X_test)
    assert pred.dtype.kind == "i"
    np.testing.assert_array_equal(pred, clf.classes_[np.argmax(proba, axis=1)])


def test_score_is_the_accuracy(clips: tuple) -> None:
    X, y, X_test, y_test = clips
    clf = CaseBaseClassifier(k=3).fit(X, y)
    right = sum(p == t for p, t in zip(clf.predict(X_test), y_test, strict=True))
    assert clf.score(X_test, y_test) == pytest.approx(right / len(y_test))


def test_cross_validation_drives_it_like_any_classifier(clips: tuple) -> None:
    X, y, _, _ = clips
    cv = StratifiedKFold(n_splits=2, shuffle=True, random_state=0)
    scores = cross_val_score(CaseBaseClassifier(k=1), X, y, cv=cv)
    by_hand = []
    for tr, te in cv.split(np.zeros(len(y)), y):
        clf = CaseBaseClassifier(k=1).fit([X[i] for i in tr], y[tr])
        by_hand.append(np.mean(clf.predict([X[i] for i in te]) == y[te]))
    np.testing.assert_allclose(scores, by_hand)


@pytest.mark.parametrize(
    ("bad_y", "message"),
    [
        ("none", r"y\[2\] is None"),
        ("nan", r"y\[2\] is nan"),
        ("empty", r"y\[2\] is ''"),
        ("short", "12 clips but y has shape"),
    ],
)
def test_bad_labels_are_refused_naming_the_entry(clips: tuple, bad_y: str, message: str) -> None:
    X, y, _, _ = clips
    labels: list[object] = list(y)
    if bad_y == "short":
        labels = labels[:-1]
    else:
        labels[2] = {"none": None, "nan": float("nan"), "empty": ""}[bad_y]
    with pytest.raises(DataError, match=message):
        CaseBaseClassifier().fit(X, labels)


def test_bad_inputs_and_parameters_are_one_clear_error(clips: tuple) -> None:
    X, y, _, _ = clips
    clf = CaseBaseClassifier(k=3).fit(X, y)
    with pytest.raises(DataError, match="no clips to classify"):
        clf.predict([])
    with pytest.raises(DataError, match="X: must be a sequence of PoseSequence"):
        clf.predict(X[0])
    with pytest.raises(DataError, match=r"X\[0\] is a ndarray"):
        clf.predict([np.zeros((3, 33, 3))])
    with pytest.raises(DataError, match="the training set is empty"):
        CaseBaseClassifier().fit([], [])
    for params, name in (
        ({"k": 0}, "k"),
        ({"k": True}, "k"),
        ({"length": 100_000_000}, "length"),
        ({"weights": "cosine"}, "weights"),
        ({"trim": 1.5}, "trim"),
        ({"editor": "magic"}, "editor"),
    ):
        with pytest.raises(ConfigError, match=name):
            CaseBaseClassifier(**params).fit(X, y)  # type: ignore[arg-type]
