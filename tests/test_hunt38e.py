"""Hunt 38e: a robotics engineer's loop over the Python API, their own tracker's frames
(dropped frames, joints lost, nobody in view) pushed for a long time, and a Kinect
skeleton named by its own joints."""

from __future__ import annotations

import csv
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.live import MAX_SEGMENT_S, LiveSegment, LiveSegmenter, activity_distances
from cbr.segmentation import NO_FRAMES, NOBODY, solve_recording
from cbr.training import train
from features.body import torso_share
from features.errors import InputError, PoseFileError
from features.poses import PoseSequence, load_pose
from features.skeleton import BLAZEPOSE_33, KINECT_V2_JOINTS
from tests.badinput import assert_unchanged, snapshot

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


class _Seen(LiveSegmenter):
    """Activity "a" in every window that shows the person, every activity alike where none
    does (as the real segmenter votes there); no classifier behind it."""

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        if torso_share(self._sequence(n - self.window, n)) == 0.0:
            return np.full(2, 0.5), 0.5
        return np.eye(2)[0], 0.0

    def _repetition_windows(self, n: int) -> None:
        """The fixed windows only (the frames are noise: nothing repeats)."""


def _seen() -> _Seen:
    labels = np.array(["a", "b"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    return _Seen(clf, 30.0, judge=SimpleNamespace(), source="robot")


def test_dropped_frames_over_a_long_stream_are_not_all_remembered() -> None:
    """10 minutes at 30 fps with every tenth frame dropped (pushed NaN, absent=True): 1,800
    gaps, each remembered to the end (the list grew by 3 a second, and every stretch with
    nobody in view read it whole). Only those the frames kept could still need stay: at
    most one in ten of MAX_SEGMENT_S of frames, two windows, a hop and the longest window.
    A 3-s gap of the video after it is still told as no frames, and 3 s out of view as
    nobody in view."""
    live = _seen()
    rng = np.random.default_rng(0)
    gone = np.full((33, 3), np.nan)
    segments: list[LiveSegment] = []
    for i in range(10 * 60 * 30):
        dropped = i % 10 == 9
        segments += live.push(gone if dropped else rng.normal(size=(33, 3)), absent=dropped)
    kept = MAX_SEGMENT_S * 30 + 2 * live.window + live.hop + live.longest
    assert len(live.absent) <= kept / 10 + 1 < 1800
    for frames, absent in ((90, True), (60, False), (90, False), (60, False)):
        for _ in range(frames):
            seen = absent or (frames == 90 and not absent)
            segments += live.push(gone if seen else rng.normal(size=(33, 3)), absent=absent)
    segments += live.finish()
    told = [(s.label, s.explanation) for s in segments]
    assert told == [("a", told[0][1]), (None, NO_FRAMES), ("a", told[2][1]), (None, NOBODY),
                    ("a", told[4][1])]  # fmt: skip
    assert abs(segments[1].start_frame - 18000) <= 1 and abs(segments[1].end_frame - 18090) <= 1
    assert abs(segments[3].start_frame - 18150) <= 1 and abs(segments[3].end_frame - 18240) <= 1


def test_a_kinect_skeleton_named_by_its_joints_is_told_how_to_declare_it() -> None:
    """README: another tracker's joints by name, ``PoseSequence(xyz, names, fps)
    .to_canonical()``. Kinect v2's 25 SDK names were refused as "not BlazePose landmark
    names: SpineBase, ..." and no more; the refusal now says they are kinect_v2's and how to
    say so, and so declared the frame maps: Kinect joint j at (j, 2j, 3j) cm puts
    ShoulderLeft (4) at BlazePose's left_shoulder and WristRight (10) at right_wrist."""
    xyz = np.arange(25)[None, :, None] * np.array([0.01, 0.02, 0.03])
    said = (
        r"names: SpineBase, SpineMid, Neck, Head, ShoulderLeft "
        r'\(these are kinect_v2 joint names: give skeleton="kinect_v2"\)$'
    )
    with pytest.raises(PoseFileError, match=said):
        PoseSequence(xyz, KINECT_V2_JOINTS, 30.0).to_canonical()
    frame = PoseSequence(xyz, KINECT_V2_JOINTS, 30.0, skeleton="kinect_v2").to_canonical()
    np.testing.assert_allclose(frame.positions[0, BLAZEPOSE_33.index("left_shoulder")],
                               [0.04, 0.08, 0.12])  # fmt: skip
    np.testing.assert_allclose(frame.positions[0, BLAZEPOSE_33.index("right_wrist")],
                               [0.10, 0.20, 0.30])  # fmt: skip


def test_names_of_no_known_skeleton_get_no_hint() -> None:
    """A name that is no skeleton's (a typo beside Kinect's) is refused as before, naming
    no skeleton it is not."""
    names = ("SpineBase", "Shoulderleft")
    with pytest.raises(PoseFileError, match=r"names: SpineBase, Shoulderleft$"):
        PoseSequence(np.zeros((1, 2, 3)), names, 30.0).to_canonical()


def _demo_clips() -> tuple[list[PoseSequence], list[str]]:
    """Six demo clips of two activities as a tracker's arrays (three people)."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["movement"] in ("m01", "m02")]
    rows = [r for r in rows if r["correct"] == "true" and r["episode"] == "1"]
    clips = [
        PoseSequence(
            load_pose(DEMO / r["path"]).to_canonical().positions,
            BLAZEPOSE_33,
            30.0,
            metadata={"subject": r["subject"]},
        )
        for r in rows
    ]
    return clips, [r["label"] for r in rows]


@pytest.mark.parametrize(
    ("change", "said"),
    [
        ({"cases": "frames"}, "cases: must be one of 'clips', 'repetitions', 'windows', "
         "got 'frames'"),
        ({"cases": None}, "cases: must be one of"),
        ({"target": 3}, "target: must be the name of a column, got 3"),
        ({"target": " "}, "target: must be the name of a column, got ' '"),
        ({"estimator": CaseBaseClassifier}, "estimator: a CaseBaseClassifier is expected, got "
         "the class itself: give one, CaseBaseClassifier()"),
        ({"estimator": None}, "estimator: a CaseBaseClassifier is expected, got NoneType"),
        ({"clips": "first"}, "clips: clips[0] is a ndarray, not a PoseSequence"),
    ],
)  # fmt: skip
def test_train_refuses_what_no_case_base_could_be_stored_with(
    tmp_path: Path, change: dict[str, Any], said: str
) -> None:
    """``cbr.training.train(..., cases="frames")`` stored the case base as holding "frames"
    (`casebase info` then said "18 held-out frames are too few"), ``target=3`` one that
    "predicts 3"; the class CaseBaseClassifier for an instance, None, or a tracker's array
    among the clips, stopped in a TypeError or AttributeError from inside ("unhashable type:
    'numpy.ndarray'"). Each is refused with InputError naming the argument, before any clip
    is read, and no store file is made."""
    clips, labels = _demo_clips()
    args: dict[str, Any] = {"estimator": CaseBaseClassifier(), "target": "label"}
    args["cases"] = "clips"
    args.update(change)
    if args.pop("clips", None) == "first":
        clips = [clips[0].positions, *clips[1:]]
    before = snapshot(tmp_path)
    with pytest.raises(InputError) as got:
        train(tmp_path / "robot.sqlite", "default", clips, labels, **args)
    assert str(got.value).startswith(said)
    assert_unchanged(tmp_path, before)


def test_train_takes_the_clips_from_a_generator(tmp_path: Path) -> None:
    """``clips`` read as they come (a generator) stopped in "object of type 'generator' has
    no len()"; now the case base stored holds the same six cases, of the same labels, as
    from a list."""
    clips, labels = _demo_clips()
    done = train(tmp_path / "robot.sqlite", "default", (c for c in clips), labels,
                 CaseBaseClassifier(mirror="off", feature_weights="fisher", phases=0))  # fmt: skip
    assert (done.n_cases, done.label_counts) == (6, {"deep_squat": 3, "hurdle_step": 3})


class _Logged(LiveSegmenter):
    """The live segmenter keeping every window it judged: (start, stop) -> the distance to
    the nearest case of each activity."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.log: dict[tuple[int, int], np.ndarray] = {}

    def _judged(self, solved: Any, start: int, stop: int) -> tuple[np.ndarray, float]:
        self.log[(start, stop)] = activity_distances(self.clf, solved, self.codes)
        return super()._judged(solved, start, stop)


def test_a_live_window_that_begins_part_way_through_a_movement_is_read_as_segment_reads_it() -> (
    None
):
    """Nine demo clips of three activities one after another, streamed: each window was
    read from its own frames alone, so one that begins part-way through a squat had its first
    frames' motion states read cold (the window of frames 11-73 lay 48.0 from its nearest
    squat case; cut from the recording, as ``segment`` and ``train --split windows`` cut
    them, 9.8). Now a window keeps the frames before it as context: every window both
    judge lies as far from each activity as ``segment``'s window of the same frames."""
    clips, labels = _demo_clips()
    with open(DEMO / "labels.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["movement"] == "m07"]
    rows = [r for r in rows if r["correct"] == "true" and r["episode"] == "1"]
    clips += [PoseSequence(load_pose(DEMO / r["path"]).to_canonical().positions, BLAZEPOSE_33,
                           30.0, metadata={"subject": r["subject"]}) for r in rows]  # fmt: skip
    labels += [r["label"] for r in rows]
    clf = CaseBaseClassifier(mirror="off", feature_weights="fisher", phases=0).fit(clips, labels)
    stream = PoseSequence(np.concatenate([c.positions for c in clips]), BLAZEPOSE_33, 30.0)
    live = _Logged(clf, 30.0)
    for frame in stream.positions:
        live.push(frame)
    live.finish()
    offline = {(w.start, w.stop): w.nearest for w in solve_recording(clf, stream).windows}
    both = sorted(live.log.keys() & offline.keys())
    assert len(both) >= 5
    for key in both:
        np.testing.assert_allclose(live.log[key], offline[key], rtol=1e-6, err_msg=str(key))
