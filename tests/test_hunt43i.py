"""Session 43 (i): ``CaseBaseClassifier.fit`` refuses a clip too short to classify, as
``predict`` does; a stored classifier gives back ``states`` as it was given (list or tuple).
(``report`` loading no scikit-learn: tests/test_startup.py.)"""

from __future__ import annotations

import dataclasses
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import clone

from casebase_store import open_store
from cbr.described import describe_clips
from cbr.estimator import CaseBaseClassifier
from cbr.stored import load_classifier
from cbr.training import train
from features.errors import InputError
from features.poses import PoseSequence
from tests.test_cbr_clips import arm_dataset


def _small() -> CaseBaseClassifier:
    return CaseBaseClassifier(k=3, feature_weights="none", phases=0, mirror="off")


@pytest.fixture(scope="module")
def clips() -> tuple[list[PoseSequence], np.ndarray]:
    """Nine arm movements, each named as a file of its own (train refuses one stretch of a
    file listed twice)."""
    X, y = arm_dataset(3, 5)
    return [dataclasses.replace(c, source=f"arm_{i}.npz") for i, c in enumerate(X)], y


def _six_frames(clip: PoseSequence) -> tuple[PoseSequence, str]:
    """The first six frames of ``clip`` and how long they last, worked out from its rate."""
    short = clip.slice_frames(0, 6)
    assert 6 / clip.fps < 0.4  # shorter than the shortest movement (features.repetitions)
    return short, f"lasts {6 / clip.fps:.2f} s (6 frames)"


def test_fit_refuses_a_clip_too_short_to_classify(
    clips: tuple[list[PoseSequence], np.ndarray],
) -> None:
    """Before: fit made a case of six frames (0.2 s) that predict refuses to classify ("nothing
    to classify"), so the case base held a case no clip could be like."""
    X, y = clips
    short, lasts = _six_frames(X[0])
    short = dataclasses.replace(short, source="")  # a clip of no file: named by its place
    X_bad = [*X[:4], short, *X[4:]]
    y_bad = [*y[:4], y[0], *y[4:]]
    with pytest.raises(InputError) as caught:
        _small().fit(X_bad, y_bad)
    assert caught.value.message.startswith(lasts), caught.value.message
    assert "shorter than one movement can be (0.4 s)" in caught.value.message
    assert caught.value.source == "X[4]"  # which clip: its place, as predict names it
    assert isinstance(caught.value, ValueError)  # what scikit-learn users catch
    # predict refuses the same clip in the same words but for what it cannot do with it
    fitted = _small().fit(X, y)
    with pytest.raises(InputError) as asked:
        fitted.predict([short])
    assert asked.value.message.replace("classify", "learn from") == caught.value.message
    assert len(fitted.case_base_) == len(X)  # the clips long enough are all cases


def test_fit_described_refuses_a_clip_too_short_to_classify(
    clips: tuple[list[PoseSequence], np.ndarray],
) -> None:
    """Records made elsewhere (a cluster's workers) keep how long each clip lasts: a short one
    is refused by the fit too, named by its source. Before: a case was made of it."""
    X, y = clips
    short, lasts = _six_frames(X[1])
    short = dataclasses.replace(short, source="short.npz")
    clf = _small()
    described = list(describe_clips([*X, short], *clf.describe_plan()))
    with pytest.raises(InputError) as caught:
        clf.fit_described(described, [*y, y[1]])
    assert caught.value.message.startswith(lasts.split(" (")[0])
    assert "shorter than one movement can be (0.4 s)" in caught.value.message
    assert caught.value.source == "short.npz"


def test_train_still_skips_a_short_clip_naming_it(
    clips: tuple[list[PoseSequence], np.ndarray], tmp_path: Path
) -> None:
    """``train`` (library and command) skips such a clip and names it, as before: the
    refusal is the estimator's, which a skipped clip never reaches."""
    X, y = clips
    short, _ = _six_frames(X[2])
    result = train(tmp_path / "cb.sqlite", "default", [*X, short], [*y, y[2]], _small())
    assert result.too_short == [f"arm_2.npz (lasts {6 / X[2].fps:.2f} s)"]


ARM_STATES = ["left_arm_bent.bent", "left_arm_bent.straight", "right_arm_bent.bent",
              "right_arm_bent.straight"]  # fmt: skip


@pytest.mark.parametrize("kind", [list, tuple])
def test_states_come_back_as_given_from_the_store(
    clips: tuple[list[PoseSequence], np.ndarray], tmp_path: Path, kind: type
) -> None:
    """``get_params()["states"]`` is the object ``__init__`` was given, in a clone too, and
    of the same type once the classifier is stored and loaded back (JSON keeps both as a
    list). Before: a list came back from the store as a tuple, unequal to the list given
    (``["a"] != ("a",)``), and ``clone`` of the loaded classifier kept the tuple."""
    X, y = clips
    states = kind(ARM_STATES)
    clf = CaseBaseClassifier(states=states, k=3, feature_weights="none", mirror="off")
    assert clf.get_params()["states"] is states
    assert type(clone(clf).get_params()["states"]) is kind
    assert clone(clf).get_params()["states"] == states
    train(tmp_path / "cb.sqlite", "default", X, y, clf)
    store = open_store(tmp_path / "cb.sqlite", readonly=True)
    try:
        loaded = load_classifier(store, "default").classifier
    finally:
        store.close()
    got = loaded.get_params()["states"]
    assert type(got) is kind and got == states
    again = clone(loaded).get_params()["states"]
    assert type(again) is kind and again == states
    assert loaded.get_params() == clf.get_params()


def test_a_model_stored_before_reads_states_back_as_a_tuple(
    clips: tuple[list[PoseSequence], np.ndarray], tmp_path: Path
) -> None:
    """A model document without ``"tuples"`` (stored by an earlier posecbr) reads a list of
    states back as a tuple, as every earlier posecbr did."""
    X, y = clips
    db = tmp_path / "cb.sqlite"
    clf = CaseBaseClassifier(states=list(ARM_STATES), k=3, feature_weights="none", mirror="off")
    train(db, "default", X, y, clf)
    with sqlite3.connect(db) as con:
        con.execute("UPDATE case_bases SET model = json_remove(model, '$.tuples')")
    con.close()
    store = open_store(db, readonly=True)
    try:
        loaded = load_classifier(store, "default").classifier
    finally:
        store.close()
    assert loaded.get_params()["states"] == tuple(ARM_STATES)
