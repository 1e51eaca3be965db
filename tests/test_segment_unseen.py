"""Segments counted with a joint missing (NaN) in their frames only, seen in the rest of the
recording: ``segment`` counts each segment on the signals of the whole recording
(:func:`cbr.segmentation.counted_segments`), which keep an angle whose joint is seen in most
of the recording and fill it in across the segment, where it is missing throughout. A segment
counts on the angles a clip of its frames alone is counted on
(:meth:`features.repetitions.MovementSignals.alone`)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from cbr.segmentation import count_in_segment, counted_segments, windows_of
from features.poses import PoseSequence
from features.readers.asfamc import read_asf_amc
from features.repetitions import MIN_VALID_SHARE, MovementSignals, movement_signals
from features.skeleton import JOINT_INDEX

FIXTURE = Path(__file__).parent / "fixtures" / "repetition_counts.json"
ARM_JOINTS = ("left_elbow", "right_elbow", "left_wrist", "right_wrist")


# on one xdist worker: the module's cmu_13_31 made once, not once per worker
pytestmark = pytest.mark.xdist_group("segment_unseen")


@pytest.fixture(scope="module")
def cmu_13_31(shared_data: Path) -> tuple[PoseSequence, dict[str, dict]]:
    """CMU 13_31 on the canonical skeleton, and its stretches counted by hand by activity
    (the first of each)."""
    clips = [
        c for c in json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
        if c["source"].endswith("13_31.amc")
    ]  # fmt: skip
    rec = read_asf_amc(shared_data / clips[0]["asf"], shared_data / clips[0]["source"])
    by_activity: dict[str, dict] = {}
    for c in clips:
        by_activity.setdefault(c["activity"], c)
    return rec.to_canonical(), by_activity


def _without(rec: PoseSequence, joint: str, a: int, b: int) -> PoseSequence:
    positions = rec.positions.copy()
    positions[a:b, JOINT_INDEX[joint]] = np.nan
    return dataclasses.replace(rec, positions=positions)


@pytest.mark.parametrize("joint", ARM_JOINTS)
def test_a_segment_with_an_arm_joint_unseen_counts_as_the_clip_alone(
    cmu_13_31: tuple[PoseSequence, dict[str, dict]], joint: str
) -> None:
    """13_31's jog (7 steps by hand) and first twist (2 turns by hand) with an arm joint
    missing in their own frames only, cut as segments of the whole recording: the jog counts
    what its frames count as a clip alone, at least 6 (alone, the fading last step loses
    height with an arm's angles gone), the twist its 2 turns. Before, the arm's angles,
    filled in across the segment from the rest of the recording, were an arm held still
    while the other swung: the jog counted 5, 3, 2 and 3 steps, the twist 1."""
    rec, hand = cmu_13_31
    for activity, least in (("Jog", 6), ("Twist", 2)):
        a, b = hand[activity]["start_frame"], hand[activity]["end_frame"]
        seq = _without(rec, joint, a, b)
        piece = counted_segments(movement_signals(seq), [(a, b)], seq.n_frames)[0]
        clip = seq.slice_frames(a, b)
        alone = count_in_segment(
            movement_signals(clip), clip.n_frames, clip.fps, (a == 0, b >= seq.n_frames)
        )
        assert len(piece) == alone.count, (activity, joint)
        assert least <= len(piece) <= hand[activity]["count"], (activity, joint)


def test_alone_leaves_out_an_angle_missing_in_most_of_the_piece() -> None:
    """Two knees bending over 100 frames at 10 fps (one frame a sample), the left knee's
    angle followed in the first 60 frames only: the whole keeps it (60 of 100, at least
    half), frames 40-100 leave it out (20 of 60), frames 0-70 keep it (60 of 70); its
    values and name go together."""
    n = 100
    values = np.stack([np.linspace(1, 2, n), np.linspace(2, 3, n)], axis=1)
    followed = np.ones((n, 2), dtype=np.int32)
    followed[60:, 0] = 0
    shown = np.ones(n, dtype=np.int32)
    sig = MovementSignals(values, ("left_knee", "right_knee"), 10.0, 1, None, followed, shown)
    assert MIN_VALID_SHARE == 0.5  # the shares above are worked out for half
    late = sig.alone(40, 100)
    assert late is not None
    assert late.names == ("right_knee",)
    np.testing.assert_array_equal(late.values, values[40:, 1:])
    early = sig.alone(0, 70)
    assert early is not None and early.names == ("left_knee", "right_knee")
    shown[:] = 0  # nobody shown: nothing followed, nothing kept
    followed[:] = 0
    assert sig.alone(0, 50) is None


def test_frames_followed_are_counted_per_sample(
    cmu_13_31: tuple[PoseSequence, dict[str, dict]],
) -> None:
    """The left elbow missing in frames 1608-2052 of 13_31 (120 fps, four frames a sample):
    the recording keeps the left elbow's angle (its joint seen in 2573 of 3017 frames); the
    samples 402-513 (frames 1608-2052) follow it in no frame and show the person in all four
    of each, the samples before in all four; and the piece alone leaves the angles on that
    elbow out (the elbow angle, the armpit angle, the upper arm's turn)."""
    rec, _ = cmu_13_31
    sig = movement_signals(_without(rec, "left_elbow", 1608, 2052))
    assert sig.step == 4 and sig.followed is not None and sig.shown is not None
    elbow = sig.names.index("left_elbow")
    assert sig.followed[402:513, elbow].sum() == 0
    assert (sig.followed[:402, elbow] == 4).all()
    assert (sig.shown[:754] == 4).all()
    piece = sig.alone(402, 513)
    assert piece is not None
    gone = {"left_elbow", "left_armpit", "left_upper_arm_turn"}
    assert set(sig.names) - set(piece.names) == gone


def test_the_strides_of_a_jog_with_an_arm_joint_unseen_are_its_windows(
    cmu_13_31: tuple[PoseSequence, dict[str, dict]],
) -> None:
    """The repetition windows ``segment`` classifies inside 13_31's jog (frames 1608-2052),
    an arm joint missing there only: at least three quarters last one stride, 0.5-1.0 s (by
    hand, left and right knee troughs 0.37-0.39 s apart: a stride of two steps about 0.75
    s; with nothing missing 15 of its 16 windows do). Each span is read on the angles a clip
    of its frames alone takes, as ``watch`` reads it. Before, the arm's angles filled in from
    the rest of the recording stood still while the other arm swung: with the left elbow
    missing 4 of 7 windows were a stride (others 1.2-2.8 s), with the left wrist 5 of 10."""
    rec, hand = cmu_13_31
    a, b = hand["Jog"]["start_frame"], hand["Jog"]["end_frame"]
    for joint in ARM_JOINTS:
        seq = _without(rec, joint, a, b)
        windows = windows_of(movement_signals(seq), seq.n_frames, seq.fps)
        inside = [
            (w.stop - w.start) / seq.fps
            for w in windows
            if w.repetition and a <= w.start and w.stop <= b
        ]
        strides = [s for s in inside if 0.5 <= s <= 1.0]
        assert len(inside) >= 6, (joint, inside)
        assert len(strides) >= 0.75 * len(inside), (joint, inside)
