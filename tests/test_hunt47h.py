"""posecbr inside someone else's program (hunt 47h).

A fitted model answering from two threads at once must leave the calling program's warning
filters alone. The features and the novelty calibration silenced numpy's "Mean of empty
slice" over a column missing throughout with ``warnings.catch_warnings``, which swaps the
process's one list of filters: one thread leaving the block while another was inside let the
warning through, and the thread that entered second put back its copy, with "ignore
RuntimeWarning" in it, for the rest of the caller's program (seen with ``explain`` from four
threads on the demo UI-PRMD model: once in two runs). Each such reduction is run here in two
threads in the order that does it (A enters, B enters, A leaves, B leaves), held inside
numpy's reduction until the other thread is where it should be.
"""

from __future__ import annotations

import ast
import re
import threading
import warnings
import weakref
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.estimator_protocol import Classifier
from cbr.live import LiveSegmenter
from cbr.novelty import fit_neighbours, ranges_and_held, spread_of, summary
from cbr.segmentation import check_judge, check_k, movement_of, segment
from cbr.training import cut, train
from features import derived as derived_module
from features.body import left_moves_more
from features.errors import ConfigError, InputError, PoseFileError
from features.pose_estimation import stream_poses
from features.pose_estimation import video as video_module
from features.poses import PoseSequence
from features.repetitions import pelvis_height
from features.skeleton import BLAZEPOSE_33, JOINT_INDEX

ROOT = Path(__file__).resolve().parents[1]


def _interleaved(
    monkeypatch: pytest.MonkeyPatch, reduction: str, call: Callable[[], Any]
) -> tuple[list[Any], list[str], bool]:
    """``call()`` in threads A and B, each held at its first call of ``np.<reduction>``:
    A enters, B enters, A leaves, then B leaves. Returns both results, the warnings shown
    meanwhile, and whether the warning filters are as before."""
    real = getattr(np, reduction)
    a_in, b_in, a_out = threading.Event(), threading.Event(), threading.Event()
    held: set[str] = set()

    def holding(*args: Any, **kwargs: Any) -> Any:
        me = threading.current_thread().name
        if me not in held:
            held.add(me)
            if me == "A":
                a_in.set()
                b_in.wait(10)
            elif me == "B":
                b_in.set()
                a_out.wait(10)
        return real(*args, **kwargs)

    monkeypatch.setattr(np, reduction, holding)
    results: dict[str, Any] = {}

    def run(name: str) -> None:
        try:
            results[name] = call()
        except BaseException as exc:  # re-raised in the test's thread
            results[name] = exc
        finally:
            if name == "A":
                a_out.set()

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        before = list(warnings.filters)
        a = threading.Thread(target=run, args=("A",), name="A")
        b = threading.Thread(target=run, args=("B",), name="B")
        a.start()
        assert a_in.wait(10), f"np.{reduction} was never called"
        b.start()
        a.join(30)
        b.join(30)
        same = list(warnings.filters) == before
    for value in results.values():
        if isinstance(value, BaseException):
            raise value
    return [results["A"], results["B"]], [str(w.message) for w in caught], same


NAN = np.nan


def test_summary_from_two_threads_keeps_the_callers_warning_filters(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A problem's summary (every solve): mean, lowest, highest and standard deviation per
    column; a column missing throughout stays NaN, with no warning, from either thread."""
    v = np.array([[1.0, NAN], [3.0, NAN]])
    (a, b), shown, same = _interleaved(monkeypatch, "nanmean", lambda: summary(v))
    want = [2.0, NAN, 1.0, NAN, 3.0, NAN, 1.0, NAN]
    np.testing.assert_array_equal(a, want)
    np.testing.assert_array_equal(b, want)
    assert same, "the caller's warning filters changed"
    assert shown == []


def test_the_side_that_moves_more_from_two_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    """The left knee angle swings by 0.5 (standard deviation); the right one is never seen
    (0, not NaN, in the comparison): the left side moves more."""
    angles = np.array([[0.0, NAN], [1.0, NAN]])
    names = ("left_knee", "right_knee")
    got, shown, same = _interleaved(monkeypatch, "nanstd", lambda: left_moves_more(angles, names))
    assert got == [True, True]
    assert same, "the caller's warning filters changed"
    assert shown == []


def test_pelvis_height_from_two_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    """Hips 1.0 m up, shoulders 1.5 m (a trunk of 0.5 m), ankles 0.1 m up in the first three
    frames and lost in the fourth: (1.0 - 0.1) / 0.5 = 1.8 trunk lengths above the floor in
    every frame; the frame without hips is NaN."""
    p = np.full((5, 33, 3), NAN)
    for side, x in (("left", 0.1), ("right", -0.1)):
        p[:4, JOINT_INDEX[f"{side}_hip"]] = (x, 1.0, 0.0)
        p[:4, JOINT_INDEX[f"{side}_shoulder"]] = (x, 1.5, 0.0)
        p[:3, JOINT_INDEX[f"{side}_ankle"]] = (x, 0.1, 0.0)
    got, shown, same = _interleaved(monkeypatch, "nanmin", lambda: pelvis_height(p))
    for heights in got:
        np.testing.assert_allclose(heights, [1.8, 1.8, 1.8, 1.8, NAN])
    assert same, "the caller's warning filters changed"
    assert shown == []


def test_movement_of_windows_from_two_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    """The mean of the columns read: 0.3 for the first window, NaN for one without them."""
    values = np.array([[0.2, 0.4, 9.0], [NAN, NAN, 9.0]])
    columns = np.array([0, 1])
    got, shown, same = _interleaved(monkeypatch, "nanmean", lambda: movement_of(values, columns))
    for moved in got:
        np.testing.assert_allclose(moved, [0.3, NAN])
    assert same, "the caller's warning filters changed"
    assert shown == []


# Four cases of two people and two activities; the second feature no case has.
CASES = np.array([[0.0, NAN], [2.0, NAN], [4.0, NAN], [8.0, NAN]])
GROUPS = np.array(["p1", "p1", "p2", "p2"])
LABELS = np.array(["a", "a", "b", "b"])


def test_activity_spread_from_two_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    """Activity a's cases 0 and 2 (mean 1, deviation 1), b's 4 and 8 (mean 6, deviation 2);
    over all, deviation sqrt(8.75) = 2.96, whose quarter (0.74) is below both: the units
    are the activities' own deviations. The missing feature: NaN."""
    got, shown, same = _interleaved(monkeypatch, "nanstd", lambda: spread_of(CASES, LABELS))
    for spread in got:
        np.testing.assert_allclose(spread.centres, [[1.0, NAN], [6.0, NAN]])
        np.testing.assert_allclose(spread.units, [[1.0, NAN], [2.0, NAN]])
    assert same, "the caller's warning filters changed"
    assert shown == []


def test_summary_neighbours_from_two_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    """Centre 3.5 (the mean of 0, 2, 4, 8) and scale sqrt(8.75); the missing feature takes
    no part (centre 0, scale 1)."""
    got, shown, same = _interleaved(
        monkeypatch, "nanmean", lambda: fit_neighbours(CASES, GROUPS, LABELS, CASES, GROUPS)
    )
    for fitted in got:
        assert fitted is not None
        np.testing.assert_allclose(fitted[0].centre, [3.5, 0.0])
        np.testing.assert_allclose(fitted[0].scale, [np.sqrt(8.75), 1.0])
    assert same, "the caller's warning filters changed"
    assert shown == []


def test_feature_ranges_from_two_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    """Two people, two folds: each fold's range is the other person's cases', 0-2 and 4-8;
    the missing feature has none (NaN)."""
    got, shown, same = _interleaved(
        monkeypatch, "nanmin", lambda: ranges_and_held(CASES, GROUPS, CASES, GROUPS, LABELS)
    )
    for found in got:
        assert found is not None
        ranges = found[0]
        spans = sorted(zip(ranges.lo[:, 0].tolist(), ranges.hi[:, 0].tolist(), strict=True))
        assert spans == [(0.0, 2.0), (4.0, 8.0)]
        assert np.isnan(ranges.lo[:, 1]).all() and np.isnan(ranges.hi[:, 1]).all()
    assert same, "the caller's warning filters changed"
    assert shown == []


def test_no_module_a_fitted_model_runs_swaps_the_warning_filters() -> None:
    """features and cbr (but cbr.evaluation, which fits peers and draws pictures in a
    command's own process) never call ``warnings.catch_warnings``: numpy's reductions over
    what is seen (features.nanstats) give NaN without a warning instead."""
    found = []
    for path in sorted([*(ROOT / "features").rglob("*.py"), *(ROOT / "cbr").rglob("*.py")]):
        if "evaluation" in path.relative_to(ROOT).parts:
            continue
        text = path.read_text(encoding="utf-8")
        if "catch_warnings" not in text:
            continue
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Attribute) and node.attr == "catch_warnings":
                found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert found == []


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"joint_names": None}, "joint_names must be a sequence of names, got NoneType"),
        ({"joint_names": 33}, "joint_names must be a sequence of names, got int"),
        (
            {"positions": [[[0.0, 0.0, 0.0]], [[0.0, 0.0]]], "joint_names": ("nose",)},
            "positions must be an array, got rows of different lengths",
        ),
        (
            {"confidence": [[1.0] * 33, [1.0] * 32]},
            "confidence must be an array, got rows of different lengths",
        ),
    ],
)
def test_a_pose_sequence_of_arguments_it_cannot_hold_is_one_clear_error(
    kwargs: dict[str, Any], words: str
) -> None:
    """Another tracker's output put into a PoseSequence wrongly (no joint names, a joint
    count for the names, nested lists of a frame with a joint short): PoseFileError naming
    the argument, not numpy's "inhomogeneous shape" ValueError or "'NoneType' object is not
    iterable"."""
    args: dict[str, Any] = {"positions": np.zeros((2, 33, 3)), "joint_names": BLAZEPOSE_33}
    args.update(kwargs)
    with pytest.raises(PoseFileError) as raised:
        PoseSequence(fps=30.0, **args)
    assert str(raised.value) == words


@pytest.mark.parametrize("camera", [-1, -2, True])
def test_a_negative_camera_index_is_refused_before_opencv_sees_it(
    monkeypatch: pytest.MonkeyPatch, camera: int
) -> None:
    """``stream_poses(-1)``, OpenCV's old "any camera", killed the caller's process with a
    segmentation fault (OpenCV 5.1, no camera: ``cv2.VideoCapture(-1)`` alone does it). It is
    an InputError naming the argument now, and OpenCV is never asked (here a stand-in that
    records what it is asked, so that the old code fails without crashing the tests)."""
    asked: list[Any] = []

    class Capture:
        def __init__(self, *args: Any) -> None:
            asked.append(args)

        def isOpened(self) -> bool:  # noqa: N802 (OpenCV's name)
            return False

    monkeypatch.setattr(video_module.cv2, "VideoCapture", Capture)
    with pytest.raises(InputError) as raised:
        next(iter(stream_poses(camera)))
    assert str(raised.value) == (
        f"source: a camera index is a whole number from 0 (the first camera), got {camera!r}"
    )
    assert asked == []


@pytest.mark.parametrize("judge", [3, 0.5, np.float64(0.5), True])
def test_something_that_is_no_judge_is_refused_naming_judge(judge: Any) -> None:
    """``segment(clf, rec, 3)`` or ``LiveSegmenter(clf, fps, 0.5)`` (the judge's place taken
    by a number: ``k``, a threshold): an InputError naming ``judge``, not "'int' object has
    no attribute 'unlike'" from the first window judged (a stream: seconds after it
    started)."""
    clf = SimpleNamespace(
        classes_=np.array(["a", "b"]), case_base_=SimpleNamespace(labels=np.array(["a", "b"]))
    )
    words = (
        "judge: must be None or a judge of cbr.unknown (judge_of(clf, 'spread-margin')),"
        f" got {type(judge).__name__}"
    )
    with pytest.raises(InputError) as raised:
        LiveSegmenter(clf, 30.0, judge)
    assert str(raised.value) == words
    with pytest.raises(InputError) as raised:
        check_judge(judge, clf.classes_)  # what segment() checks its judge with
    assert str(raised.value) == words


def test_forgetting_a_clip_while_another_thread_computes_a_new_kind(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``fit`` forgets each clip's cached features once described, ``segment`` each piece of
    a long recording; another thread computing a kind of feature for the first time in the
    process meanwhile added to the dict of kinds being walked: "dictionary changed size
    during iteration" in the first. Thread A is held inside :func:`forget` (in a cache of
    its own, first in the walk) until thread B has computed a new kind."""
    seq = PoseSequence(np.zeros((2, 1, 3)), ("nose",), 30.0)
    other = PoseSequence(np.zeros((2, 1, 3)), ("nose",), 30.0)
    inside, done = threading.Event(), threading.Event()

    class Holding(weakref.WeakKeyDictionary):  # type: ignore[type-arg]
        def pop(self, key: Any, *default: Any) -> Any:
            inside.set()
            done.wait(10)
            return super().pop(key, *default)

    monkeypatch.setattr(derived_module, "_CACHES", {"held": Holding()})
    failed: list[BaseException] = []

    def forgetting() -> None:
        try:
            derived_module.forget(seq)
        except BaseException as exc:  # re-raised in the test's thread
            failed.append(exc)

    a = threading.Thread(target=forgetting)
    a.start()
    assert inside.wait(10)
    assert derived_module.derived(other, "a new kind", lambda s: s.n_frames) == 2
    done.set()
    a.join(10)
    assert failed == []
    assert set(derived_module._CACHES) == {"held", "a new kind"}


def test_a_k_the_classifier_does_not_retrieve_is_a_value_error_naming_it() -> None:
    """``segment(clf, rec, k=0)`` and ``LiveSegmenter(clf, fps, k=9)`` with a classifier of
    k = 5: a ParameterError, the ValueError a Python caller catches (and still the
    ConfigError the commands print as one line), not a ConfigError alone; so is a negative
    ``chunk_frames``."""
    clf = SimpleNamespace(
        k=5,
        classes_=np.array(["a", "b"]),
        case_base_=SimpleNamespace(labels=np.array(["a", "b"])),
    )
    words = "^" + re.escape(
        "k: must be from 1 to the case base's k (5, the nearest cases a window retrieves)"
    )
    for k in (0, 6, 2.0):  # named k, the argument (the commands say -k, their option)
        with pytest.raises(ValueError, match=words) as raised:
            check_k(clf, k)  # what segment() checks its k with
        assert isinstance(raised.value, ConfigError)
    with pytest.raises(ValueError, match=words):
        LiveSegmenter(clf, 30.0, k=9)
    clf.case_base_.check_not_empty = lambda name: None
    seq = PoseSequence(np.zeros((60, 33, 3)), BLAZEPOSE_33, 30.0)
    with pytest.raises(ValueError, match="^chunk_frames: must be None or a whole number >= 0"):
        segment(clf, seq, chunk_frames=-1)


class _Answers(Classifier):
    """A classifier that answers "a" then "b", whatever the clips."""

    def predict(self, X: Any) -> np.ndarray:
        return np.array(["a", "b"], dtype=object)


@pytest.mark.parametrize("y", [[["a"], ["b"]], np.array([["a"], ["b"]]), [("a",), ("b",)]])
def test_score_refuses_labels_given_as_a_column(y: Any) -> None:
    """Both answers right, the labels given as a column (a one-column table's rows, as
    ``fit`` refuses them): ``score`` said 0.0, each row compared whole to a label. Now an
    InputError naming ``y``; the same labels flat score 1.0."""
    clf = _Answers()
    assert clf.score([None, None], ["a", "b"]) == 1.0
    with pytest.raises(InputError, match=r"^y: must be 1-D, one label per clip: y\[0\] is a "):
        clf.score([None, None], y)


def test_train_names_its_labels_argument_and_stores_nothing(tmp_path: Path) -> None:
    """``train(db, name, clips, labels, ...)`` with one label short, or the labels as a
    generator: an InputError naming ``labels`` (it said ``y``, the estimator's word, which
    the caller never wrote; a generator was "y has shape ()"), before any clip is read and
    with no database made."""
    clips = [PoseSequence(np.zeros((30, 33, 3)), BLAZEPOSE_33, 30.0) for _ in range(2)]
    db = tmp_path / "robot.sqlite"
    with pytest.raises(InputError) as raised:
        train(db, "default", clips, ["squat"], CaseBaseClassifier())
    assert str(raised.value) == "labels: 2 clips but labels has shape (1,)"
    with pytest.raises(InputError) as raised:
        train(db, "default", clips, (v for v in ("a", "b")), CaseBaseClassifier())
    assert str(raised.value) == "labels: must hold one label per clip (2), got a generator"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kind", [set, frozenset, dict.fromkeys])
def test_clips_in_a_set_are_refused_their_order_being_not_the_clips(
    tmp_path: Path, kind: Callable[[list[PoseSequence]], Any]
) -> None:
    """Clips given as a set: ``predict`` answered in the set's order, which is not the order
    the caller holds the clips in, and ``train`` paired them with the labels in that order
    (a squat stored as a lunge). An InputError naming the argument now (a dict's keys
    were refused only as "X[0] is a int" when they were numbers); nothing stored."""
    clips = [PoseSequence(np.zeros((30, 33, 3)), BLAZEPOSE_33, 30.0) for _ in range(2)]
    with pytest.raises(InputError, match=r"^clips: must be a sequence of PoseSequence"):
        train(
            tmp_path / "cb.sqlite", "default", kind(clips), ["squat", "lunge"], CaseBaseClassifier()
        )
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match=r"its order is not the clips'"):
        cut(kind(clips), ["squat", "lunge"], "windows")
