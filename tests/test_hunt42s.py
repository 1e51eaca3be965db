"""Hunt 42s: the classifiers follow scikit-learn's estimator protocol without importing
scikit-learn (:mod:`cbr.estimator_protocol`; the commands that train or classify no longer load
it, ``tests/test_startup.py``). What scikit-learn's base classes gave them is checked against
those base classes themselves: a peer class built on ``sklearn.base.BaseEstimator`` and
``ClassifierMixin`` with the same ``__init__`` (what each classifier was before)."""

from __future__ import annotations

import base64
import math
import pickle
from typing import Any

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin, clone, is_classifier
from sklearn.exceptions import NotFittedError
from sklearn.metrics import accuracy_score
from sklearn.utils import get_tags

from cbr.dad import DADClassifier
from cbr.estimator import CaseBaseClassifier
from cbr.estimator_protocol import Classifier, unfitted_copy
from tests.test_cbr_clips import arm_dataset

# An unfitted CaseBaseClassifier(k=3, weights="uniform") pickled by the code before this change
# (a subclass of sklearn.base.BaseEstimator, scikit-learn 1.9.1), protocol 4.
OLD_PICKLE = base64.b64decode(
    "gASVKQEAAAAAAACMDWNici5lc3RpbWF0b3KUjBJDYXNlQmFzZUNsYXNzaWZpZXKUk5QpgZR9lCiMCGZlYXR1cmVz"
    "lIwHZmx1ZW50c5SMCnNpbWlsYXJpdHmUjAlldWNsaWRlYW6UjAFrlEsDjAd3ZWlnaHRzlIwHdW5pZm9ybZSMDGNs"
    "YXNzX3dlaWdodJSMBG5vbmWUjAZsZW5ndGiUSyCMBnN0YXRlc5SMBmFuZ2xlc5SMEXNpbWlsYXJpdHlfcGFyYW1z"
    "lE6MBHRyaW2UTmgQiIwHc3VtbWFyeZSMBGF1dG+UjAZtaXJyb3KUaBSMD2ZlYXR1cmVfd2VpZ2h0c5RoFIwGcGhh"
    "c2VzlGgUjAlwb3NpdGlvbnOUiIwGZWRpdG9ylE6MCHZlbG9jaXR5lIl1Yi4="
)


def _peer(cls: type) -> type:
    """A class named as ``cls``, with its ``__init__``, on scikit-learn's base classes."""
    return type(cls.__name__, (ClassifierMixin, BaseEstimator), {"__init__": cls.__init__})


PARAMS = [
    (CaseBaseClassifier, {}),
    (CaseBaseClassifier, {"k": 3}),
    (CaseBaseClassifier, {"k": np.int64(3), "trim": math.nan}),
    (CaseBaseClassifier, {"features": "qmp", "similarity": "dtw",
                          "similarity_params": {"band": 0.1}, "states": ("a", "b")}),
    (CaseBaseClassifier, {"editor": "cnn", "features": "qmp", "k": 3, "mirror": "off",
                          "phases": 3, "similarity": "dtw"}),
    (CaseBaseClassifier, {"k": 3, "features": "qmp", "similarity_params": {"band": 0.1},
                          "states": ("a", "b"), "trim": 0.5, "editor": "cnn", "mirror": "off",
                          "velocity": True, "phases": 3}),
    (DADClassifier, {}),
    (DADClassifier, {"window_s": 3.0}),
    (DADClassifier, {"add": "my_add.toml", "step_s": 0.5}),
]  # fmt: skip


@pytest.mark.parametrize(("cls", "params"), PARAMS)
def test_parameters_and_repr_are_scikit_learn_s(cls: type, params: dict[str, Any]) -> None:
    """get_params (the same names, values and order) and the repr (the parameters that differ
    from their defaults, wrapped at 80 columns) as scikit-learn's BaseEstimator gives them."""
    ours, peer = cls(**params), _peer(cls)(**params)
    assert list(ours.get_params().items()) == list(peer.get_params().items())
    assert ours.get_params(deep=False).keys() == peer.get_params(deep=False).keys()
    assert repr(ours) == repr(peer)


@pytest.mark.parametrize("cls", [CaseBaseClassifier, DADClassifier])
def test_tags_are_a_classifier_s_that_takes_no_table(cls: type) -> None:
    """scikit-learn's tags of a classifier (ClassifierMixin on BaseEstimator), except that X
    is a sequence of clips, not a 2-D array of numbers."""
    expected = get_tags(_peer(cls)())
    expected.input_tags.two_d_array = False
    assert get_tags(cls()) == expected
    assert is_classifier(cls())


def test_the_stored_parameters_are_the_documented_ones() -> None:
    """Stored case bases hold these parameters in their model documents, and
    ``cbr.stored._params`` keeps the ones get_params names: the names and defaults of the
    class's docstring."""
    assert CaseBaseClassifier().get_params() == {
        "angles": True, "class_weight": "none", "editor": None, "feature_weights": "auto",
        "features": "fluents", "k": 5, "length": 32, "mirror": "auto", "phases": "auto",
        "positions": True, "similarity": "euclidean", "similarity_params": None,
        "states": "angles", "summary": "auto", "trim": None, "velocity": False,
        "weights": "distance",
    }  # fmt: skip
    assert DADClassifier().get_params() == {"add": None, "step_s": None, "window_s": 4.0}


# on one xdist worker: the module's fitted made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt42s")


@pytest.fixture(scope="module")
def fitted() -> tuple[CaseBaseClassifier, list[Any]]:
    X, y = arm_dataset(3, seed=3)
    X_test, _ = arm_dataset(2, seed=4)
    return CaseBaseClassifier(k=3, similarity_params={"exact": True}).fit(X, y), X_test


@pytest.mark.parametrize("copier", [clone, unfitted_copy], ids=["sklearn-clone", "ours"])
def test_a_copy_has_the_parameters_copied_and_nothing_fitted(
    fitted: tuple[CaseBaseClassifier, list[Any]], copier: Any
) -> None:
    clf, X_test = fitted
    copy = copier(clf)
    assert type(copy) is CaseBaseClassifier and copy.get_params() == clf.get_params()
    assert copy.similarity_params is not clf.similarity_params  # a copy, not shared
    assert not hasattr(copy, "case_base_")
    with pytest.raises(NotFittedError, match="not fitted yet"):
        copy.predict(X_test)


def test_set_params_sets_all_or_none() -> None:
    clf = CaseBaseClassifier()
    assert clf.set_params(k=3, weights="uniform") is clf
    assert (clf.k, clf.weights) == (3, "uniform")
    with pytest.raises(ValueError, match="Invalid parameter 'neighbours'"):
        clf.set_params(k=7, neighbours=7)
    assert clf.k == 3  # the bad name refused before k was set


class _Answers(Classifier):
    """A classifier that answers ``answers``, whatever it is asked."""

    def __init__(self, answers: tuple[str, ...] = ("a", "b", "a", "c")) -> None:
        self.answers = answers

    def predict(self, X: Any) -> np.ndarray:
        return np.array(self.answers, dtype=object)


def test_score_is_the_weighted_accuracy() -> None:
    truth = ["a", "a", "a", "c"]  # right at 0, 2 and 3
    clf = _Answers()
    assert clf.score(None, truth) == 0.75
    weights = [1.0, 2.0, 1.0, 1.0]  # the wrong answer weighs 2 of 5
    assert clf.score(None, truth, sample_weight=weights) == pytest.approx(0.6)
    # as scikit-learn's accuracy (ClassifierMixin.score) gives it
    assert clf.score(None, truth, weights) == pytest.approx(
        accuracy_score(truth, clf.predict(None), sample_weight=weights)
    )
    with pytest.raises(ValueError, match=r"one label per clip \(4\), got 3 labels"):
        clf.score(None, truth[:3])


def test_a_pickle_of_the_classifier_before_loads() -> None:
    """Pickled when it subclassed scikit-learn's BaseEstimator: it loads, with its
    parameters, and fits and predicts as a new one."""
    old = pickle.loads(OLD_PICKLE)
    assert type(old) is CaseBaseClassifier
    new = CaseBaseClassifier(k=3, weights="uniform")
    assert old.get_params() == new.get_params() and repr(old) == repr(new)
    X, y = arm_dataset(3, seed=5)
    X_test, _ = arm_dataset(1, seed=6)
    np.testing.assert_array_equal(
        old.fit(X, y).predict_proba(X_test), new.fit(X, y).predict_proba(X_test)
    )


def test_a_pickle_holding_a_scikit_learn_version_loads(
    fitted: tuple[CaseBaseClassifier, list[Any]],
) -> None:
    """scikit-learn's BaseEstimator once wrote ``_sklearn_version`` into its estimators'
    pickles; a fitted classifier holding one loads and answers as it did."""
    clf, X_test = fitted
    marked = pickle.loads(pickle.dumps(clf))
    marked.__dict__["_sklearn_version"] = "1.2.2"
    again = pickle.loads(pickle.dumps(marked))
    assert again._sklearn_version == "1.2.2"
    np.testing.assert_array_equal(again.predict_proba(X_test), clf.predict_proba(X_test))
    assert again.get_params() == clf.get_params()
