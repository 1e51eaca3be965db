"""A robot engineer streaming a tracker's frames through the Python API (hunt 37l): the
stream's end, a frame after it, a frame that is not a frame, and a segment's JSON."""

from __future__ import annotations

import csv
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.live import LiveSegment, LiveSegmenter
from cbr.segmentation import Segment, segment
from cbr.unknown import judge_of
from features.errors import InputError
from features.poses import PoseSequence, load_pose
from features.skeleton import BLAZEPOSE_33

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
ACTIVITIES = ("deep_squat", "hurdle_step", "standing_shoulder_abduction")


class _Scripted(LiveSegmenter):
    """The live segmenter with each window's vote set by where it lies: activity "a" for a
    window centred before frame 300, "b" after (no classifier behind it)."""

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        return np.eye(2)[int(n - self.window / 2 >= 300)], 0.0

    def _repetition_windows(self, n: int) -> None:
        """The fixed windows only (the frames are noise: nothing repeats)."""


def _scripted(source: str = "stream") -> _Scripted:
    labels = np.array(["a", "b"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    return _Scripted(clf, 30.0, judge=SimpleNamespace(), source=source)


def test_finish_called_twice_gives_the_last_segment_once() -> None:
    """20 s at 30 fps, "a" then "b" from 10 s: the stream's segments are "a" and "b", the
    second ending at frame 600; a second finish() has no segment left to give (it gave the
    last one, "b", again)."""
    live = _scripted()
    rng = np.random.default_rng(0)
    segments: list[LiveSegment] = []
    for _ in range(600):
        segments += live.push(rng.normal(size=(33, 3)))
    segments += live.finish()
    assert [s.label for s in segments] == ["a", "b"]
    assert segments[-1].end_frame == 600
    assert live.finish() == []


def test_a_frame_pushed_after_finish_is_refused_saying_the_stream_ended() -> None:
    """A frame after the stream's end was taken, and the next finish() gave the last
    segment again one frame longer (frames 300-601 of a 600-frame stream); now it is refused
    (InputError naming the stream), nothing kept, and nothing more is finished."""
    live = _scripted("camera 0")
    rng = np.random.default_rng(1)
    for _ in range(600):
        live.push(rng.normal(size=(33, 3)))
    live.finish()
    with pytest.raises(InputError, match=r"^camera 0: frame 600: the stream has ended \(finish"):
        live.push(rng.normal(size=(33, 3)))
    assert live.n == 600
    assert live.finish() == []


# on one xdist worker: the module's clf_and_squat made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt37l")


@pytest.fixture(scope="module")
def clf_and_squat() -> tuple[CaseBaseClassifier, PoseSequence]:
    """A classifier of three demo activities (every third clip, as a tracker's arrays) and
    1.5 s of a squat clip left out of it: a stream shorter than the first 2-s window."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["label"] in ACTIVITIES]
    train = rows[::3]
    xyz = [load_pose(DEMO / r["path"]).to_canonical().positions for r in train]
    X = [PoseSequence(a, BLAZEPOSE_33, 30.0) for a in xyz]
    clf = CaseBaseClassifier(k=3, mirror=False).fit(X, [r["label"] for r in train])
    squat = next(r for r in rows[1::3] if r["label"] == "deep_squat")
    short = load_pose(DEMO / squat["path"]).to_canonical().positions[:45]
    return clf, PoseSequence(short, BLAZEPOSE_33, 30.0)


def test_finish_twice_on_a_stream_shorter_than_a_window_gives_its_segments_once(
    clf_and_squat: tuple[CaseBaseClassifier, PoseSequence],
) -> None:
    """A 1.5-s stream is segmented at its end as segment() segments the same 45 frames; a
    second finish() gave those segments all over again, and a frame pushed after was taken
    (a third finish() segmented 46 frames)."""
    clf, short = clf_and_squat
    judge = judge_of(clf, "spread-margin")
    offline = segment(clf, short, judge).segments
    live = LiveSegmenter(clf, 30.0, judge)
    for frame in short.positions:
        assert live.push(frame) == []
    first = live.finish()
    assert [(s.start_frame, s.end_frame, s.label) for s in first] == [
        (s.start_frame, s.end_frame, s.label) for s in offline
    ]
    assert first[-1].end_frame == 45
    assert live.finish() == []
    with pytest.raises(InputError, match="the stream has ended"):
        live.push(short.positions[0])


def test_a_frame_of_rows_of_different_lengths_is_refused_naming_the_frame() -> None:
    """A tracker's frame as nested lists with one joint of two numbers: numpy's "setting an
    array element with a sequence" came out; now the one line of any misshapen frame, naming
    the stream and the frame, nothing kept."""
    live = _scripted("tracker")
    live.push(np.zeros((33, 3)).tolist())  # lists of the right shape are a frame
    ragged = [[0.0, 0.0, 0.0]] * 32 + [[0.0, 0.0]]
    with pytest.raises(InputError, match=r"^tracker: frame 1: world must have shape"):
        live.push(ragged)
    with pytest.raises(InputError, match=r"^tracker: frame 1: confidence must have shape"):
        live.push(np.zeros((33, 3)), [[1.0]] * 32 + [[1.0, 1.0]])
    assert live.n == 1


@pytest.mark.parametrize("fps", [0, -30.0, None, float("nan"), "30"])
def test_to_dict_without_a_frame_rate_is_refused_in_one_line(fps: object) -> None:
    """``to_dict(fps)`` of a live or an offline segment: 0 gave a ZeroDivisionError, None a
    TypeError, NaN seconds of NaN; now an InputError saying fps must be a number > 0."""
    live = LiveSegment(0, 60, "a", 0.9, 1)
    offline = Segment(0, 60, "a", 0.9, (), "", 0.5)
    for seg in (live, offline):
        with pytest.raises(InputError, match=r"^to_dict: fps must be the frame rate"):
            seg.to_dict(fps)  # type: ignore[arg-type]


def test_to_dict_gives_seconds_at_the_frame_rate_given() -> None:
    """Frames 45-105 at 30 fps are 1.5-3.5 s; at 15 fps 3.0-7.0 s."""
    seg = LiveSegment(45, 105, "a", 0.91234, 2)
    assert {k: seg.to_dict(30)[k] for k in ("start_s", "end_s", "confidence", "count")} == {
        "start_s": 1.5,
        "end_s": 3.5,
        "confidence": 0.912,
        "count": 2,
    }
    assert (seg.to_dict(15.0)["start_s"], seg.to_dict(15.0)["end_s"]) == (3.0, 7.0)


def test_judge_of_an_unfitted_classifier_says_it_is_not_fitted() -> None:
    """``judge_of(CaseBaseClassifier(), ...)`` raised AttributeError "'CaseBaseClassifier'
    object has no attribute 'case_base_'"; now scikit-learn's NotFittedError, as segment and
    LiveSegmenter give for it."""
    from sklearn.exceptions import NotFittedError

    for name in ("spread-margin", "held-out", "margin"):
        with pytest.raises(NotFittedError, match="not fitted yet"):
            judge_of(CaseBaseClassifier(), name)


@pytest.mark.parametrize("frames", [0, -5, 2.5, "10", float("inf")])
def test_recent_of_no_frames_says_so_not_that_frames_are_no_longer_kept(frames: object) -> None:
    """``recent(0)`` on a stream of 100 frames said "stream frames 100-100 are no longer kept
    (from 0)", ``recent(-5)`` "frames 105-100": every frame is kept. Now the number asked
    for is named as what is wrong."""
    live = _scripted("tracker")
    for _ in range(100):
        live.push(np.zeros((33, 3)))
    with pytest.raises(InputError, match=r"^tracker: recent needs a number of frames > 0"):
        live.recent(frames)  # type: ignore[arg-type]


def test_recent_before_any_frame_says_none_was_pushed() -> None:
    """Before the first frame, "stream frames 0-0 are no longer kept"; now "no frame has been
    pushed yet". After 100 frames, recent(10) is the last 10 as pushed, recent(1000) all 100."""
    live = _scripted()
    with pytest.raises(InputError, match="no frame has been pushed yet"):
        live.recent(10)
    frames = np.arange(100 * 33 * 3, dtype=float).reshape(100, 33, 3) / 1e4
    for f in frames:
        live.push(f)
    assert np.array_equal(live.recent(10).positions, frames[90:])
    assert live.recent(1000).positions.shape == (100, 33, 3)


def test_counting_repetitions_of_an_array_says_a_pose_sequence_is_expected() -> None:
    """``count_repetitions(xyz)`` of a tracker's ``(frames, 33, 3)`` array raised
    AttributeError "'numpy.ndarray' object has no attribute 'duration_s'"; now InputError
    naming what it takes and how to make one."""
    from features.repetitions import count_repetitions

    with pytest.raises(InputError, match=r"^seq: a PoseSequence is expected, got ndarray"):
        count_repetitions(np.zeros((60, 33, 3)))  # type: ignore[arg-type]


@pytest.mark.parametrize("activities", [2, 5])
def test_another_classifiers_judge_is_refused_naming_both_counts(
    clf_and_squat: tuple[CaseBaseClassifier, PoseSequence], activities: int
) -> None:
    """A judge with a threshold per activity calibrated on a case base of 2 (or 5)
    activities, given to a classifier of 3: segment and LiveSegmenter read another
    activity's threshold, or raised IndexError "tuple index out of range" at the first window
    nearest an activity beyond the judge's; now InputError naming both counts, before any
    frame."""
    from cbr.unknown import ActivityMargin

    clf, short = clf_and_squat
    other = ActivityMargin((0.9,) * activities, 0.9, "subject", 10)
    words = rf"^judge: the judge was calibrated on a case base of {activities} activities, the"
    with pytest.raises(InputError, match=words + r" classifier has 3"):
        segment(clf, short, other)
    with pytest.raises(InputError, match=words):
        LiveSegmenter(clf, 30.0, other)
    LiveSegmenter(clf, 30.0, ActivityMargin((0.9,) * 3, 0.9, "subject", 10))  # its own count


def test_a_frame_of_none_says_what_to_push_for_nobody_or_no_frame() -> None:
    """A tracker that found nobody, or dropped a frame, gives None: pushing it said
    "positions must be real numbers, got Python objects"; now it says to push NaN (nobody
    seen) or NaN with absent=True (no frame), nothing kept; and that frame is taken."""
    live = _scripted("robot")
    with pytest.raises(InputError, match=r"^robot: frame 0: world is None: push a frame"):
        live.push(None)  # type: ignore[arg-type]
    assert live.n == 0
    live.push(np.full((33, 3), np.nan), absent=True)
    assert live.n == 1 and live.absent == [[0, 1]]


@pytest.mark.parametrize("fps", [0.001, 1e-6, 20_000.0])
def test_a_frame_rate_no_pose_file_takes_is_refused_when_the_segmenter_is_made(
    fps: float,
) -> None:
    """``LiveSegmenter(clf, 0.001)`` was made, and then every frame pushed was refused ("frame
    0: fps must be between 0.01 and 10000 frames per second"); now the segmenter is refused
    saying so, and the limits themselves are taken."""
    labels = np.array(["a", "b"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    with pytest.raises(InputError, match=r"^cam: the stream needs a frame rate between 0.01 and"):
        _Scripted(clf, fps, judge=SimpleNamespace(), source="cam")
    for ok in (0.01, 10_000.0):
        _Scripted(clf, ok, judge=SimpleNamespace()).push(np.zeros((33, 3)))


def test_a_judge_of_labels_fitted_as_numbers_reads_each_activitys_own_threshold() -> None:
    """Labels fitted as numbers, 2 and 10: ``classes_`` is [2, 10] and the distances a judge
    is given have their columns in that order, but the judges are calibrated in the labels'
    order as text, "10" before "2". The stored judge's threshold of "10" is 0.5 and of "2"
    0.9: a window nearest activity 2 was judged against 0.5 (activity 10's), its spread
    and budget threshold too. Now against 0.9, 3.0 and 0.8; text labels keep their order."""
    from cbr.unknown import SpreadMargin

    stored = SpreadMargin(
        (0.5, 0.9), 0.7, "subject", 10, budget_thresholds=(0.4, 0.8), spreads=(1.0, 3.0)
    )
    labels = np.array(["2", "10", "2", "10"], dtype=object)
    numbers = SimpleNamespace(
        classes_=np.array([2, 10]),
        case_base_=SimpleNamespace(labels=labels),
        judges_={"spread-margin": stored},
    )
    judge = judge_of(numbers, "spread-margin")
    assert judge.thresholds == (0.9, 0.5)  # type: ignore[attr-defined]
    assert judge.budget_thresholds == (0.8, 0.4)  # type: ignore[attr-defined]
    assert judge.spreads == (3.0, 1.0)  # type: ignore[attr-defined]
    assert judge.threshold(np.array([1.0, 5.0])) == 0.9  # type: ignore[attr-defined]
    text = SimpleNamespace(
        classes_=np.array(["10", "2"]),
        case_base_=SimpleNamespace(labels=labels),
        judges_={"spread-margin": stored},
    )
    # stored before judges named their activities: named from the case base, order kept
    kept = judge_of(text, "spread-margin")
    assert kept.thresholds == stored.thresholds  # type: ignore[attr-defined]
    assert kept.activities == ("10", "2")  # type: ignore[attr-defined]
