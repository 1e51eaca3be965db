"""The Python API as an engineer drives it (hunt 26a): ``LiveSegmenter``, ``segment``,
``DADClassifier``, ``CaseBaseClassifier``, storing a fitted model (``store_fitted``,
``train``, ``open_store``) and ``PoseSequence`` given odd but plausible arguments (a reused
frame buffer, a frame of another skeleton, parameters of the wrong type, a source given as a
path). A mistake is one clear error naming the problem, with nothing kept or changed. Each
test says what happened before its fix.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from sklearn.exceptions import NotFittedError

from casebase_store import open_store
from cbr.dad import DADClassifier
from cbr.estimator import CaseBaseClassifier
from cbr.live import LiveSegmenter
from cbr.segmentation import segment
from cbr.training import store_fitted, train
from cbr.unknown import judge_of
from features.errors import ConfigError, InputError, PosecbrError, PoseFileError
from features.poses import PoseSequence, load_pose, save_pose
from features.skeleton import BLAZEPOSE_33
from tests.bodies import standing, to_sequence
from tests.test_cbr_clips import arm_dataset


@pytest.fixture(scope="module")
def fitted() -> tuple[CaseBaseClassifier, list[PoseSequence]]:
    X, y = arm_dataset(3, seed=3)
    return CaseBaseClassifier(k=3).fit(X, y), X


def _live(clf: CaseBaseClassifier) -> LiveSegmenter:
    # the arm clips have no activity with cases apart to calibrate the default judge on
    return LiveSegmenter(clf, 30.0, judge=judge_of(clf, "held-out"))


def test_live_keeps_each_frame_as_pushed_when_the_caller_reuses_its_buffer(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]],
) -> None:
    """A camera loop that fills one buffer and pushes it every frame: the frames kept are the
    three pushed. Before, the segmenter kept the caller's array itself, so every kept frame
    became the last one written (a stream of one posture)."""
    clf, X = fitted
    live = _live(clf)
    buf = np.empty((33, 3))
    conf = np.empty(33)
    for i in range(3):
        buf[:] = X[0].positions[i]
        conf[:] = 0.5 + 0.1 * i
        live.push(buf, conf)
    buf[:] = np.nan
    recent = live.recent(3)
    np.testing.assert_array_equal(recent.positions, X[0].positions[:3])
    assert recent.confidence is not None
    np.testing.assert_allclose(recent.confidence[:, 0], [0.5, 0.6, 0.7])


@pytest.mark.parametrize(
    ("frame", "confidence", "message"),
    [
        ("kinect", None, r"frame 2: world must have shape \(33, 3\), got \(25, 3\)"),
        ("2d", None, r"frame 2: world must have shape \(33, 3\), got \(33, 2\)"),
        ("inf", None, "frame 2: world contains infinite values"),
        ("text", None, "frame 2: world must be real numbers, got text"),
        ("ok", np.ones(5), r"frame 2: confidence must have shape \(33,\), got \(5,\)"),
        ("ok", np.full(33, 2.0), r"frame 2: confidence must lie in \[0, 1\], found 2"),
    ],
)
def test_live_refuses_a_bad_frame_when_pushed_and_keeps_going(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]],
    frame: str,
    confidence: np.ndarray | None,
    message: str,
) -> None:
    """A frame that is not 33 BlazePose joints' positions (another skeleton's 25 joints, 2-D
    points, an infinite coordinate, text) or whose confidence is not 33 values in [0, 1] is
    refused as it is pushed, naming the stream and the frame; the frames before stay, and the
    stream goes on. Before, it was kept: two seconds later, when a window first read it, a
    PoseFileError ("25 joints in positions but 33 joint names") came out of a later push, and
    out of every push after it (the frame stayed in the window)."""
    clf, X = fitted
    good = X[0].positions
    bad = {
        "kinect": good[0][:25],
        "2d": good[0][:, :2],
        "inf": np.where(np.arange(33)[:, None] == 5, np.inf, good[0]),
        "text": good[0].astype(str),
        "ok": good[0],
    }[frame]
    live = _live(clf)
    live.push(good[0])
    live.push(good[1])
    with pytest.raises(InputError, match=message) as err:
        live.push(bad, confidence)
    assert err.value.source == "stream"
    assert live.n == 2
    for i in range(2, 100):  # past the first window (2 s at 30 fps)
        live.push(good[i % len(good)])
    np.testing.assert_array_equal(live.recent(100).positions[:2], good[:2])


@pytest.mark.parametrize("fps", ["30", None, True])
def test_live_refuses_a_frame_rate_that_is_not_a_number(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]], fps: object
) -> None:
    """Before: "30" and None raised a bare TypeError from ``math.isfinite``, and True was a
    stream of 1 frame per second."""
    clf, _ = fitted
    with pytest.raises(InputError, match="the stream needs a frame rate > 0"):
        LiveSegmenter(clf, fps, judge=judge_of(clf, "held-out"))  # type: ignore[arg-type]


def test_live_refuses_an_unfitted_classifier() -> None:
    """As ``predict`` and ``segment`` do. Before: AttributeError ('CaseBaseClassifier'
    object has no attribute 'case_base_')."""
    with pytest.raises(NotFittedError):
        LiveSegmenter(CaseBaseClassifier(), 30.0)


def _recording(X: list[PoseSequence]) -> PoseSequence:
    return PoseSequence(np.concatenate([x.positions for x in X]), X[0].joint_names, 30.0)


@pytest.mark.parametrize("k", [1.5, "2", None, True])
def test_segment_refuses_a_k_that_is_not_a_whole_number(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]], k: object
) -> None:
    """Before: 1.5 and "2" raised a bare TypeError (a slice index, a comparison of int and
    str), None too, and True was taken for 1."""
    clf, X = fitted
    with pytest.raises(ConfigError, match=f"must be from 1 to .*a whole number, got {k!r}"):
        segment(clf, _recording(X), judge=judge_of(clf, "held-out"), k=k)  # type: ignore[arg-type]


def test_segment_and_live_refuse_a_judge_given_by_name(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]],
) -> None:
    """A judge's name where the judge is wanted is refused, pointing at ``judge_of``. Before:
    segment raised AttributeError ('str' object has no attribute 'unlike') after solving
    every window, and LiveSegmenter took it, to fail the same way at its first window."""
    clf, X = fitted
    with pytest.raises(InputError, match=r"judge: must be .*judge_of\(clf, 'held-out'\)"):
        segment(clf, _recording(X), judge="held-out")  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"judge: must be .*judge_of\(clf, 'held-out'\)"):
        LiveSegmenter(clf, 30.0, judge="held-out")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"angles": "no"}, "angles: must be True or False, got 'no'"),
        ({"positions": None}, "positions: must be True or False, got None"),
        ({"positions": "false"}, "positions: must be True or False, got 'false'"),
        ({"trim": True}, r"trim: must be in \(0, 1\], got True"),
        ({"similarity_params": "band=0.1"}, "similarity_params: must be None or a dict"),
        ({"similarity_params": [("band", 0.1)]}, "similarity_params: must be None or a dict"),
    ],
)
def test_classifier_refuses_parameters_of_the_wrong_kind(params: dict, message: str) -> None:
    """Before: ``angles="no"`` and ``positions="false"`` were true (``bool("no")``), None
    false, ``trim=True`` kept every case (1.0), and a ``similarity_params`` that is not a
    mapping raised a bare TypeError from ``get_measure(**params)``. Now one ConfigError naming
    the parameter, before any clip is read."""
    with pytest.raises(ConfigError, match=message) as err:
        CaseBaseClassifier(**params).describe_plan()
    assert err.value.source == next(iter(params))


@pytest.mark.parametrize("trim", [np.float32(0.5), np.float16(0.75), np.int64(1)])
def test_classifier_takes_a_numpy_number_for_trim(trim: object) -> None:
    """A trim from a numpy array (a grid of ``np.float32`` values) in (0, 1] is taken, as a
    numpy integer k is. Before: "trim must be in (0, 1], got np.float32(0.5)"."""
    clf = CaseBaseClassifier(trim=trim, angles=np.True_, positions=np.False_)  # type: ignore[arg-type]
    assert clf.describe_plan()[0].angles and not clf.describe_plan()[0].positions


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"window_s": "4"}, "window_s must be a number > 0, got '4'"),
        ({"window_s": None}, "window_s must be a number > 0, got None"),
        ({"window_s": True}, "window_s must be a number > 0, got True"),
        ({"step_s": True}, "step_s must be a number > 0, got True"),
    ],
)
def test_dad_refuses_windows_that_are_not_numbers(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]], params: dict, message: str
) -> None:
    """Before: a window_s of text or None raised a bare TypeError (``min(1.0, "4")``), and
    True was taken for windows of one second (``window_s``) or steps of one second."""
    _, X = fitted
    with pytest.raises(ConfigError, match=message):
        DADClassifier(**params).fit(X[:2], ["a", "b"])


def test_store_fitted_refuses_an_unfitted_classifier_before_the_store_is_made(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]], tmp_path: Path
) -> None:
    """Before: AttributeError ('CaseBaseClassifier' object has no attribute 'maintenance_')."""
    db = tmp_path / "cases.sqlite"
    with pytest.raises(NotFittedError):
        store_fitted(db, "arms", CaseBaseClassifier(), ["a", "b"])
    assert not db.exists()


@pytest.mark.parametrize("name", [None, 3, b"arms"])
def test_a_case_base_name_that_is_not_text_is_refused_and_nothing_stored(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]], tmp_path: Path, name: object
) -> None:
    """Before: store_fitted raised a bare TypeError ("argument of type 'NoneType' is not
    iterable", "a bytes-like object is required") and train an AttributeError ('NoneType'
    object has no attribute 'strip') after describing every clip."""
    clf, X = fitted
    db = tmp_path / "cases.sqlite"
    store_fitted(db, "kept", clf, ["a"] * len(X))
    with pytest.raises(PosecbrError, match=f"the case base name must be text, got {name!r}"):
        store_fitted(db, name, clf, ["a"] * len(X))  # type: ignore[arg-type]
    with pytest.raises(PosecbrError, match=f"the case base name must be text, got {name!r}"):
        train(db, name, X, ["a", "b"] * (len(X) // 2), CaseBaseClassifier())  # type: ignore[arg-type]
    with open_store(db, readonly=True) as store:
        assert [c.name for c in store.list_case_bases()] == ["kept"]


@pytest.mark.parametrize("timeout", ["5", float("nan"), -1.0, True, None])
def test_open_store_refuses_a_timeout_that_is_not_seconds(tmp_path: Path, timeout: object) -> None:
    """Before: "5" and None raised TypeError, NaN ValueError ("cannot convert float NaN to
    integer") and -1 and True were taken (SQLite's busy timeout turned off; one second)."""
    db = tmp_path / "cases.sqlite"
    with pytest.raises(ConfigError, match="timeout_s: must be a number of seconds >= 0, got"):
        open_store(db, timeout_s=timeout)  # type: ignore[arg-type]
    assert not db.exists()


def test_a_pose_sequence_made_from_a_path_keeps_it_as_text_and_saves(tmp_path: Path) -> None:
    """``source=Path(...)`` (the video a sequence was made from) is kept as its text, as a
    loaded sequence's source is, and the sequence saves and loads back naming it. Before: the
    Path was kept as it was, and ``save_pose`` refused the sequence with "metadata cannot be
    stored as JSON (PosixPath is not JSON serializable)"."""
    video = tmp_path / "take 1.mp4"
    body = np.zeros((2, 33, 3))
    seq = PoseSequence(body, BLAZEPOSE_33, 30.0, source=video)  # type: ignore[arg-type]
    assert seq.source == str(video) and isinstance(seq.source, str)
    back = load_pose(save_pose(seq, tmp_path / "pose.npz"))
    assert back.metadata["made_from"] == str(video)


@pytest.mark.parametrize("source", [123, None, ["a.mp4"]])
def test_a_pose_sequence_refuses_a_source_that_is_not_text(source: object) -> None:
    """Before: kept as given (an int, None, a list) where every reader expects text."""
    with pytest.raises(
        PoseFileError, match=re.escape(f"source must be text or a path, got {source!r}")
    ):
        PoseSequence(np.zeros((2, 33, 3)), BLAZEPOSE_33, 30.0, source=source)  # type: ignore[arg-type]


def test_dad_predict_is_the_argmax_of_its_probabilities() -> None:
    """A still standing clip, classes "aaa" (no ADD activity) and an ADD activity that
    scores 0 on it: decision_function ranks the activity's class first (0 less a tie-break
    of 1e-6 per rank, above -1), and predict names it, but predict_proba clipped both to 0
    and gave [0.5, 0.5], whose argmax is "aaa". Now the probabilities keep predict's order,
    still [0.5, 0.5] to 1e-3 (1e-9 each, and 1e-12 times one more than the score)."""
    seq = to_sequence(*[standing()] * 60)
    classes = ["aaa", "elbowToKnee1RepsLelbowStart"]
    clf = DADClassifier().fit([seq, seq], classes)
    decision = clf.decision_function([seq])[0]
    assert decision[0] == -1.0 and -1e-3 < decision[1] < 0.0  # the tie the clip makes
    proba = clf.predict_proba([seq])[0]
    assert clf.predict([seq])[0] == classes[int(np.argmax(proba))] == classes[1]
    np.testing.assert_allclose(proba, [0.5, 0.5], atol=1e-3)
    assert proba[1] > proba[0]
    assert proba.sum() == pytest.approx(1.0)


@pytest.mark.parametrize("where", [5, None, b"cb.sqlite", ["cb.sqlite"]])
def test_open_store_of_something_not_a_path_is_refused_and_makes_no_file(
    where: object, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``open_store(5)`` created a case base file named "5" in the working folder."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(PosecbrError, match="a file path or a SQLAlchemy URL, got"):
        open_store(where)  # type: ignore[arg-type]
    assert list(tmp_path.iterdir()) == []


def test_a_skeleton_that_is_not_a_name_is_the_unknown_skeleton_error() -> None:
    """``PoseSequence(..., skeleton=["blazepose33"])`` was a TypeError (a list is not
    hashable, looked up among the known skeletons); it is an unknown skeleton, named."""
    frames = to_sequence(*[standing()] * 3)
    with pytest.raises(PoseFileError, match=r"unknown skeleton \['blazepose33'\] \(known: "):
        PoseSequence(frames.positions, frames.joint_names, 30.0, skeleton=["blazepose33"])  # type: ignore[arg-type]


def test_a_model_fitted_on_numbered_labels_answers_with_numbers_once_stored(
    tmp_path: Path,
) -> None:
    """Labels 9 and 10 (numbers): the store keeps labels as text, and the loaded classifier's
    classes were ["10", "9"] (sorted as text), so its answers were text and ``score`` against
    the numbers 0. Now the loaded classes are [9, 10], as fitted, and it scores as the
    fitted classifier does."""
    from cbr.stored import load_classifier

    X, names = arm_dataset(3, seed=3)
    number = {name: 9 + i for i, name in enumerate(sorted(set(names)))}
    y = np.array([number[n] for n in names])
    clf = CaseBaseClassifier(k=3).fit(X, y)
    assert clf.classes_.tolist() == sorted(number.values())
    store_fitted(tmp_path / "cb.sqlite", "numbers", clf, [str(v) for v in y])
    with open_store(tmp_path / "cb.sqlite", readonly=True) as store:
        loaded = load_classifier(store, "numbers").classifier
    assert loaded.classes_.tolist() == clf.classes_.tolist()
    assert all(type(v) is int for v in loaded.predict(X).tolist())
    np.testing.assert_array_equal(loaded.predict(X), clf.predict(X))
    assert loaded.score(X, y) == clf.score(X, y) > 0.5


def test_a_table_of_clips_is_refused_as_dad_refuses_it(
    fitted: tuple[CaseBaseClassifier, list[PoseSequence]],
) -> None:
    """An object array of shape (2, 3) holding six clips was flattened and answered as six
    clips (any shape was), where DADClassifier refuses it: X is one clip per row."""
    clf, X = fitted
    table = np.empty((2, 3), dtype=object)
    for i, seq in enumerate(X[:6]):
        table[i // 3, i % 3] = seq
    with pytest.raises(InputError, match=r"got an object array of shape \(2, 3\)"):
        clf.predict(table)
    column = np.empty(6, dtype=object)
    column[:] = X[:6]
    np.testing.assert_array_equal(clf.predict(column), clf.predict(X[:6]))
