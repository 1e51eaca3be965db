"""Python calls with bad arguments are refused with one clear error of the project's own types,
before anything is changed; labels of any one kind go in and come back out alike."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from sklearn.exceptions import NotFittedError

from casebase_store import StoreError, decode_array, encode_array
from cbr.casebase import CaseBase
from cbr.dad import DADClassifier
from cbr.estimator import CaseBaseClassifier
from cbr.problem import FeatureConfig
from cbr.retain import retain
from cbr.retrieve import retrieve, retrieve_many
from cbr.revise import apply_revision, revise
from cbr.segmentation import segment
from cbr.similarity import Euclidean
from features.errors import ConfigError, DataError, InputError
from features.fluents import DEFAULT_TABLE, evaluate_chunks
from features.poses import PoseSequence, load_pose
from features.timeline import describe_clip

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def _line(xs: list[float], labels: list[str]) -> CaseBase:
    """Cases on a line: problem = (x, 0) so every distance is |x_i - x_j|."""
    p = np.array([[x, 0.0] for x in xs])
    return CaseBase(FeatureConfig(), Euclidean(exact=True), p, labels, ("x", "y"), ("x", "y"))


@pytest.fixture(scope="module")
def squats_and_steps() -> tuple[list[PoseSequence], list[str], list[str]]:
    """Every third deep squat and hurdle step of the demo data: clips, labels, subjects."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["label"] in ("deep_squat", "hurdle_step")]
    rows = rows[::3]
    return (
        [load_pose(DEMO / r["path"]) for r in rows],
        [r["label"] for r in rows],
        [r["subject"] for r in rows],
    )


@pytest.fixture(scope="module")
def fitted(squats_and_steps: tuple[list[PoseSequence], list[str], list[str]]) -> CaseBaseClassifier:
    X, y, _ = squats_and_steps
    return CaseBaseClassifier().fit(X, y)


# -- revise, retain, retrieve


@pytest.mark.parametrize("rate", [float("nan"), 5, 1.5, 0.0, -0.25, float("inf"), True, "0.5"])
def test_revise_refuses_a_rate_outside_0_1_and_changes_nothing(rate: object) -> None:
    cb = _line([0.0, 4.0, 10.0], ["a", "a", "b"])
    with pytest.raises(ConfigError, match="rate"):
        revise(cb, np.array([2.0, 0.0]), "a", rate=rate)  # type: ignore[arg-type]
    np.testing.assert_array_equal(cb.problems, [[0.0, 0.0], [4.0, 0.0], [10.0, 0.0]])


def test_revise_with_rate_one_moves_the_case_onto_the_observation() -> None:
    cb = _line([0.0, 4.0, 10.0], ["a", "a", "b"])
    rev = revise(cb, np.array([1.0, 0.0]), "a", rate=1)  # nearest 'a' case: x=0
    np.testing.assert_allclose(cb.problems[0], [1.0, 0.0])  # 0 + 1 * (1 - 0)
    bad = dataclasses.replace(rev, rate=float("nan"))
    with pytest.raises(ConfigError, match="rate"):
        apply_revision(cb, bad, np.array([3.0, 0.0]))
    np.testing.assert_allclose(cb.problems[0], [1.0, 0.0])


@pytest.mark.parametrize("scale", [0.0, -1.0, float("nan"), float("inf")])
def test_retain_refuses_a_scale_that_is_not_a_finite_positive_number(scale: float) -> None:
    cb = _line([0.0, 1.0, 10.0, 11.0], ["a", "a", "b", "b"])
    with pytest.raises(ConfigError, match="scale"):
        retain(cb, np.array([6.0, 0.0]), "a", k=2, scale=scale)
    assert len(cb) == 4


@pytest.mark.parametrize("k", [0, -1, 1.5, True, "2"])
def test_retrieve_refuses_k_that_is_not_a_whole_number_of_at_least_one(k: object) -> None:
    cb = _line([0.0, 1.0, 3.0], ["a", "a", "b"])
    with pytest.raises(ConfigError, match="k: must be"):
        retrieve(cb, np.array([2.0, 0.0]), k)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="k: must be"):
        retrieve_many(cb, [np.array([2.0, 0.0])], k)  # type: ignore[arg-type]


def test_retrieve_takes_a_numpy_integer_k() -> None:
    cb = _line([0.0, 1.0, 3.0], ["a", "a", "b"])
    r = retrieve(cb, np.array([2.6, 0.0]), np.int64(2))  # type: ignore[arg-type]
    assert list(r.indices) == [2, 1]  # 0.4 from x=3, 1.6 from x=1


# -- labels


def test_case_base_classifier_reads_mixed_int_and_float_labels_as_numbers(
    squats_and_steps: tuple[list[PoseSequence], list[str], list[str]],
) -> None:
    X, y, subjects = squats_and_steps
    train = [i for i, s in enumerate(subjects) if s != "s03"]
    test = [i for i, s in enumerate(subjects) if s == "s03"]
    # 1 and 1.0 are one class, as scikit-learn reads them: deep squat 1, hurdle step 2
    numbers = [(1, 1.0) if y[i] == "deep_squat" else (2, 2.0) for i in train]
    mixed = [pair[j % 2] for j, pair in enumerate(numbers)]
    clf = CaseBaseClassifier().fit([X[i] for i in train], mixed)
    assert list(clf.classes_) == [1.0, 2.0]
    predicted = clf.predict([X[i] for i in test])
    assert list(predicted) == [1.0 if y[i] == "deep_squat" else 2.0 for i in test]


def test_case_base_classifier_predicts_int_labels_of_the_training_set(
    squats_and_steps: tuple[list[PoseSequence], list[str], list[str]],
) -> None:
    X, y, subjects = squats_and_steps
    train = [i for i, s in enumerate(subjects) if s != "s03"]
    test = [i for i, s in enumerate(subjects) if s == "s03"]
    code = {"deep_squat": 1, "hurdle_step": 2}
    clf = CaseBaseClassifier().fit([X[i] for i in train], [code[y[i]] for i in train])
    predicted = clf.predict([X[i] for i in test])
    assert predicted.dtype.kind == "i"
    assert list(predicted) == [code[y[i]] for i in test]


def test_dad_takes_a_plain_list_of_int_labels(
    squats_and_steps: tuple[list[PoseSequence], list[str], list[str]],
) -> None:
    X, _, _ = squats_and_steps
    dad = DADClassifier().fit(X[:4], [0, 1, 0, 1])
    assert list(dad.classes_) == [0, 1] and dad.classes_.dtype.kind == "i"
    assert dad.predict(X[:1])[0] in (0, 1)


# -- clips that cannot be classified


def test_dad_refuses_a_clip_without_a_person_or_of_one_frame(
    squats_and_steps: tuple[list[PoseSequence], list[str], list[str]],
) -> None:
    X, y, _ = squats_and_steps
    dad = DADClassifier().fit(X[:4], y[:4])
    nobody = dataclasses.replace(X[0], positions=np.full_like(X[0].positions, np.nan))
    with pytest.raises(DataError, match="shows no person"):
        dad.predict([X[1], nobody])
    with pytest.raises(DataError, match="has one frame"):
        dad.predict([X[0].slice_frames(0, 1)])
    with pytest.raises(DataError, match="shows no person"):
        dad.decision_function([nobody])


# -- segment


def test_segment_refuses_what_is_not_a_pose_sequence(fitted: CaseBaseClassifier) -> None:
    rec = load_pose(DEMO / "m01_s01_e01.npz")
    for bad in ([rec], rec.positions):
        with pytest.raises(InputError, match="a PoseSequence is expected"):
            segment(fitted, bad)  # type: ignore[arg-type]


def test_segment_refuses_an_unfitted_classifier() -> None:
    rec = load_pose(DEMO / "m01_s01_e01.npz")
    with pytest.raises(NotFittedError):
        segment(CaseBaseClassifier(), rec)


@pytest.mark.parametrize("chunk", [-5, 2.5])
def test_segment_refuses_a_chunk_that_is_not_a_whole_number_of_frames(
    fitted: CaseBaseClassifier, chunk: object
) -> None:
    rec = load_pose(DEMO / "m01_s01_e01.npz")
    with pytest.raises(ConfigError, match="chunk_frames"):
        segment(fitted, rec, chunk_frames=chunk)  # type: ignore[arg-type]


# -- fluents


def test_fluent_chunks_of_no_frames_are_refused() -> None:
    seq = load_pose(DEMO / "m01_s01_e01.npz")
    with pytest.raises(ConfigError, match="chunk_frames"):
        list(evaluate_chunks(seq, chunk_frames=0))
    with pytest.raises(ConfigError, match="chunk_frames"):
        describe_clip(seq, chunk_frames=0)


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("min_run", 2.5),
        ("min_run", 0),
        ("threshold", 2.0),
        ("threshold", float("nan")),
        ("threshold", 0.0),
    ],
)
def test_describe_clip_refuses_bad_options(option: str, value: float) -> None:
    seq = load_pose(DEMO / "m01_s01_e01.npz")
    with pytest.raises(ConfigError, match=option):
        describe_clip(seq, **{option: value})  # type: ignore[arg-type]


def test_an_unknown_fluent_is_named() -> None:
    with pytest.raises(ConfigError, match="unknown fluent 'foo'"):
        DEFAULT_TABLE.spec("foo")


# -- the store's arrays


def test_a_0d_array_keeps_its_shape_through_the_store() -> None:
    back = decode_array(encode_array(np.array(3.0)))
    assert back.shape == () and float(back) == 3.0


def test_an_array_of_objects_is_a_store_error() -> None:
    with pytest.raises(StoreError, match="dtype object"):
        encode_array(np.array([1, "a", None], dtype=object))
