"""The Python API as a user of the library meets it: CaseBaseClassifier's bad input refused with
the ValueError scikit-learn users catch (features.errors.InputError, as DADClassifier does),
missing labels of every kind refused."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from features.errors import DataError, InputError
from features.poses import PoseSequence, load_pose

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


# on one xdist worker: the module's squats_and_steps, fitted, numbered made once
pytestmark = pytest.mark.xdist_group("api22")


@pytest.fixture(scope="module")
def squats_and_steps() -> tuple[list[PoseSequence], list[str]]:
    """Every third deep squat and hurdle step of the demo data: clips and labels."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["label"] in ("deep_squat", "hurdle_step")]
    rows = rows[::3]
    return [load_pose(DEMO / r["path"]) for r in rows], [r["label"] for r in rows]


@pytest.fixture(scope="module")
def fitted(squats_and_steps: tuple[list[PoseSequence], list[str]]) -> CaseBaseClassifier:
    X, y = squats_and_steps
    return CaseBaseClassifier(k=3).fit(X, y)


def _nobody(seq: PoseSequence) -> PoseSequence:
    return PoseSequence(np.full_like(seq.positions, np.nan), seq.joint_names, seq.fps)


# -- X and y of fit: the ValueError scikit-learn users catch, naming the problem


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ("empty", "empty"),
        ("one clip", "single PoseSequence"),
        ("numbers", r"float64 array of shape \(4, 10, 3\)"),
        ("a path", r"X\[1\] is a str"),
        ("none", "got NoneType"),
    ],
)
def test_fit_refuses_an_x_that_is_not_clips_with_a_value_error(
    squats_and_steps: tuple[list[PoseSequence], list[str]], bad: str, message: str
) -> None:
    X, y = squats_and_steps
    given: dict[str, Any] = {
        "empty": [],
        "one clip": X[0],
        "numbers": np.zeros((4, 10, 3)),
        "a path": [X[0], "clip.npz"],
        "none": None,
    }
    with pytest.raises(InputError, match=message) as info:
        CaseBaseClassifier().fit(given[bad], y[:4] if bad != "a path" else y[:2])
    assert isinstance(info.value, ValueError) and isinstance(info.value, DataError)


@pytest.mark.parametrize(
    ("labels", "message"),
    [
        (lambda y: y[:-1], "clips but y has shape"),
        (lambda y: np.array(y)[:, None], "clips but y has shape"),
        (lambda y: [None, *y[1:]], r"y\[0\] is None"),
        (lambda y: [*y[:-1], float("nan")], r"is nan: every clip needs a label"),
        (lambda y: ["deep_squat"] * len(y), "only one activity"),
    ],
)
def test_fit_refuses_bad_labels_with_a_value_error(
    squats_and_steps: tuple[list[PoseSequence], list[str]], labels: Any, message: str
) -> None:
    X, y = squats_and_steps
    with pytest.raises(ValueError, match=message) as info:
        CaseBaseClassifier().fit(X, labels(y))
    assert isinstance(info.value, InputError)


def test_fit_refuses_a_training_clip_with_nobody_in_it_with_a_value_error(
    squats_and_steps: tuple[list[PoseSequence], list[str]],
) -> None:
    X, y = squats_and_steps
    with pytest.raises(InputError, match="no person"):
        CaseBaseClassifier().fit([*X[:3], _nobody(X[3])], y[:4])


@pytest.mark.parametrize("missing", ["NA", "NaT", "None in a string column"])
def test_a_label_pandas_marks_missing_is_refused_not_made_a_class(
    squats_and_steps: tuple[list[PoseSequence], list[str]], missing: str
) -> None:
    pd = pytest.importorskip("pandas")
    X, y = squats_and_steps
    labels: Any
    if missing == "NA":  # pandas' "string" dtype: a missing value is pd.NA, its text "<NA>"
        labels = pd.Series([*y[:-1], None], dtype="string")
    elif missing == "NaT":
        labels = pd.Series([*y[:-1], pd.NaT], dtype=object)
    else:
        labels = pd.Series([*y[:-1], None], dtype=object)
    last = len(y) - 1
    with pytest.raises(InputError, match=rf"y\[{last}\] is .*: every clip needs a label"):
        CaseBaseClassifier().fit(X, labels)


# -- predict, predict_proba, solve: the same


def test_predict_refuses_no_clips_and_a_clip_with_nobody_with_a_value_error(
    fitted: CaseBaseClassifier, squats_and_steps: tuple[list[PoseSequence], list[str]]
) -> None:
    X, _ = squats_and_steps
    with pytest.raises(InputError, match="no clips to classify"):
        fitted.predict([])
    with pytest.raises(InputError, match="no person"):
        fitted.predict_proba([X[0], _nobody(X[1])])
    with pytest.raises(InputError, match="single PoseSequence"):
        fitted.solve(X[0])


# -- refresh after the case base changed (cbr.revise, cbr.retain on case_base_)


@pytest.fixture(scope="module")
def numbered(squats_and_steps: tuple[list[PoseSequence], list[str]]) -> tuple[Any, ...]:
    """A classifier fitted on the clips labelled 10 (deep squat) and 2 (hurdle step)."""
    X, y = squats_and_steps
    code = {"deep_squat": 10, "hurdle_step": 2}
    numbers = [code[v] for v in y]
    return X, numbers, CaseBaseClassifier(k=3).fit(X, numbers)


def test_refresh_without_a_change_keeps_number_classes_and_their_answers(
    numbered: tuple[Any, ...],
) -> None:
    X, numbers, fitted = clone_of(numbered)
    before = fitted.predict(X)
    fitted.refresh()  # nothing changed: nothing may change
    assert fitted.classes_.tolist() == [2, 10] and fitted.classes_.dtype.kind == "i"
    after = fitted.predict(X)
    assert after.dtype.kind == "i" and after.tolist() == before.tolist()
    assert fitted.score(X, numbers) == pytest.approx(np.mean(before == np.array(numbers)))


def test_refresh_after_a_revision_keeps_number_classes(numbered: tuple[Any, ...]) -> None:
    from cbr.revise import revise

    X, numbers, fitted = clone_of(numbered)
    revise(fitted.case_base_, fitted.problems(X[:1])[0], "10")  # its cases' labels are text
    fitted.refresh()
    assert fitted.classes_.tolist() == [2, 10]
    assert set(fitted.predict(X).tolist()) <= {2, 10}


def test_a_case_retained_with_a_new_label_is_named_until_refresh_then_answers(
    fitted: CaseBaseClassifier, squats_and_steps: tuple[list[PoseSequence], list[str]]
) -> None:
    from cbr.retain import retain

    X, _ = squats_and_steps
    clf = clone_of((fitted,))[0]
    half = X[0].positions[: X[0].n_frames // 2]  # the first half of a squat: no case's problem
    new = [PoseSequence(half, X[0].joint_names, X[0].fps, skeleton=X[0].skeleton)]
    # a tiny scale makes any case novel; the clip's own problem: benefit 1
    assert retain(clf.case_base_, clf.problems(new)[0], "lunge", scale=1e-9, k=3).retained
    with pytest.raises(DataError, match=r"'lunge'.*call refresh\(\)"):
        clf.predict(new)
    clf.refresh()
    assert clf.classes_.tolist() == ["deep_squat", "hurdle_step", "lunge"]
    # the retained case is the clip's own problem: at distance 0 it decides alone
    assert clf.predict(new).tolist() == ["lunge"]


def clone_of(items: tuple[Any, ...]) -> tuple[Any, ...]:
    """A deep copy of a module fixture's fitted classifiers (tests change their cases)."""
    import copy

    return tuple(copy.deepcopy(v) if isinstance(v, CaseBaseClassifier) else v for v in items)
