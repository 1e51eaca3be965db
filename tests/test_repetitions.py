"""Repetition counting: hand-built movements with known repetitions, the QMP period as an
independent check of the period, and real mocap stretches against counts made by hand
(tests/fixtures/repetition_counts.json)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.segmentation import counted_segments
from features.derived import signals_of
from features.errors import DataError
from features.pose_estimation import estimate_video
from features.poses import PoseSequence, save_pose
from features.qmp import fit_signals
from features.readers.asfamc import read_asf_amc
from features.repetitions import (
    MovementSignals,
    count_in_signals,
    count_repetitions,
    mirror_angles,
    movement_signals,
    pelvis_height,
)
from features.skeleton import JOINT_INDEX
from posecbr.cli import main
from tests.bodies import rot_x, rot_z, rotate, standing, to_sequence

FIXTURE = Path(__file__).parent / "fixtures" / "repetition_counts.json"
ARM = ("elbow", "wrist", "pinky", "index", "thumb")
FPS = 30.0


def _raise_arms(
    body: dict[str, np.ndarray], left_deg: float, right_deg: float
) -> dict[str, np.ndarray]:
    """Arms lifted sideways (abduction) by the given angles about the shoulders."""
    out = rotate(body, tuple(f"left_{j}" for j in ARM), rot_z(-left_deg), body["left_shoulder"])
    return rotate(out, tuple(f"right_{j}" for j in ARM), rot_z(right_deg), body["right_shoulder"])


def _bump(n: int) -> np.ndarray:
    """One excursion out and back over ``n`` frames: 0 -> 1 -> 0 (sin squared)."""
    return np.sin(np.pi * np.arange(n) / (n - 1)) ** 2


def _movement(pattern: list[str], rise_s: float = 1.2, rest_s: float = 0.6) -> PoseSequence:
    """Arm raises of 90 degrees, each ``rise_s`` long, with ``rest_s`` of standing before,
    between and after; pattern entries "both", "left" or "right"."""
    rest, rise = int(rest_s * FPS), int(rise_s * FPS)
    left = [np.zeros(rest)]
    right = [np.zeros(rest)]
    for arm in pattern:
        bump = 90.0 * _bump(rise)
        left += [bump if arm in ("both", "left") else np.zeros(rise), np.zeros(rest)]
        right += [bump if arm in ("both", "right") else np.zeros(rise), np.zeros(rest)]
    body = standing()
    frames = [
        _raise_arms(body, a, b)
        for a, b in zip(np.concatenate(left), np.concatenate(right), strict=True)
    ]
    return to_sequence(*frames, fps=FPS)


def _designed_peaks(n: int, rise_s: float = 1.2, rest_s: float = 0.6) -> np.ndarray:
    rest, rise = int(rest_s * FPS), int(rise_s * FPS)
    return rest + np.arange(n) * (rise + rest) + (rise - 1) / 2


def test_both_arms_raised_five_times() -> None:
    result = count_repetitions(_movement(["both"] * 5))
    assert result.count == 5
    assert not result.alternating
    peaks = np.array([r.peak_frame for r in result.repetitions])
    np.testing.assert_allclose(peaks, _designed_peaks(5), atol=2)
    # the period is one raise plus one rest: 1.8 s
    assert result.period_s == pytest.approx(1.8, abs=0.1)
    # repetitions follow one another, each containing its far point, the cut inside the rests
    rest, rise = 18, 36
    for k, (a, b) in enumerate(zip(result.repetitions[:-1], result.repetitions[1:], strict=True)):
        assert a.end_frame == b.start_frame
        rest_start = rest + (k + 1) * (rise + rest) - rest
        assert rest_start - 2 <= a.end_frame <= rest_start + rest + 2
    assert set(result.moving) & {"left_armpit", "right_armpit"}


def test_alternating_arms_count_one_per_side() -> None:
    result = count_repetitions(_movement(["left", "right"] * 3))
    assert result.alternating
    assert result.count == 6
    assert [r.side for r in result.repetitions] == ["left", "right"] * 3


def test_one_arm_only_is_not_alternating() -> None:
    result = count_repetitions(_movement(["left"] * 4))
    assert not result.alternating
    assert result.count == 4


def _hops(n: int, rise_m: float = 0.2, hop_s: float = 0.5, rest_s: float = 0.5) -> PoseSequence:
    """``n`` stiff-legged hops: the whole body lifted ``rise_m`` off the floor and back over
    ``hop_s`` each, with ``rest_s`` of standing before, between and after; the arms hang
    still and no joint angle changes."""
    rest, hop = int(rest_s * FPS), int(hop_s * FPS)
    lift = np.concatenate([np.zeros(rest)] + [rise_m * _bump(hop), np.zeros(rest)] * n)
    body = standing()
    return to_sequence(*({k: v + [0.0, h, 0.0] for k, v in body.items()} for h in lift), fps=FPS)


def test_pelvis_height_in_trunk_lengths() -> None:
    # standing(): hip centre 1.00 m, ankles 0.10 m, shoulders' centre 1.50 m: trunk 0.50 m
    seq = _hops(1)
    height = pelvis_height(seq.to_canonical().positions)
    assert height[0] == pytest.approx(0.90 / 0.50)
    # at the top of the hop (0.2 m up) the hips are 1.10 m above the floor the feet left
    assert height.max() == pytest.approx(1.10 / 0.50, abs=0.01)


@pytest.mark.parametrize("n", [3, 5])
def test_hops_with_still_arms_counted(n: int) -> None:
    result = count_repetitions(_hops(n))
    assert result.count == n
    peaks = np.array([r.peak_frame for r in result.repetitions])
    # the top of hop k: 15 frames of rest, then k hops of 15 + 15 frames, then 7 of the hop
    np.testing.assert_allclose(peaks, 15 + 30 * np.arange(n) + 7, atol=2)
    assert result.moving[0] == "pelvis_height"


def _bridge_pose(lift_deg: float) -> dict[str, np.ndarray]:
    """Lying on the back (head toward -z, shoulders' centre 0.10 m above the floor at z =
    -1.50), knees bent up and feet planted at z = -0.55; the trunk turned up about the
    shoulders by ``lift_deg`` (a glute bridge: the hips rise, head, shoulders, arms and feet
    stay on the floor; each knee where thigh and shin of 0.45 m meet above the line from hip
    to ankle)."""
    lying = {k: rot_x(-90.0) @ v + [0.0, 0.10, 0.0] for k, v in standing().items()}
    a = np.radians(lift_deg)
    for side, x in (("left", 0.15), ("right", -0.15)):
        hip = np.array([x, 0.10 + 0.50 * np.sin(a), -1.50 + 0.50 * np.cos(a)])
        ankle = np.array([x, 0.10, -0.55])
        d = ankle - hip
        half = 0.5 * float(np.linalg.norm(d))
        up = np.array([0.0, d[2], -d[1]]) / (2 * half)  # across the hip-ankle line, upward
        lying[f"{side}_hip"] = hip
        lying[f"{side}_knee"] = hip + 0.5 * d + np.sqrt(0.45**2 - half**2) * up
        lying[f"{side}_ankle"] = ankle
        lying[f"{side}_heel"] = ankle + [0.0, -0.05, -0.05]
        lying[f"{side}_foot_index"] = ankle + [0.0, -0.08, 0.12]
    return lying


def test_bridges_lying_on_the_back_counted_from_lying_flat() -> None:
    """Four glute bridges, each 0.8 s up, held 1.0 s with the hips up, 0.8 s down, with 0.6 s
    lying flat before, between and after (trunk 90 degrees from the vertical lying, 120 in the
    bridge): four, whatever standing at ease would say (the hips straighten toward standing as
    they rise, 119 -> 162 degrees: ease took the bridge for rest and counted the three
    lowerings between the bridges and the lying at both ends, 5)."""
    rest, move, hold = int(0.6 * FPS), int(0.8 * FPS), int(1.0 * FPS)
    up = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, move)))  # 0 -> 1, eased
    one = np.concatenate([up, np.ones(hold), up[::-1], np.zeros(rest)])
    lift = 30.0 * np.concatenate([np.zeros(rest), *[one] * 4])
    result = count_repetitions(to_sequence(*(_bridge_pose(a) for a in lift), fps=FPS))
    assert result.count == 4
    # each far point in its bridge's hold: frames 18 + 96 k + 24 to + 54
    peaks = np.array([r.peak_frame for r in result.repetitions])
    starts = rest + np.arange(4) * len(one) + move
    assert ((peaks >= starts - 2) & (peaks <= starts + hold + 2)).all()


def _arms_raised_and_held(hold_s: float = 6.0, lowered: bool = False) -> PoseSequence:
    """Standing 0.6 s, both arms raised sideways to 90 degrees over 0.8 s (eased), held still
    ``hold_s`` seconds; with ``lowered`` they come down again over 0.8 s and 0.6 s of standing
    follow."""
    rest, move, hold = int(0.6 * FPS), int(0.8 * FPS), int(hold_s * FPS)
    up = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, move)))  # 0 -> 1, eased
    parts = [np.zeros(rest), up, np.ones(hold)] + ([up[::-1], np.zeros(rest)] if lowered else [])
    body = standing()
    return to_sequence(*(_raise_arms(body, a, a) for a in 90.0 * np.concatenate(parts)), fps=FPS)


@pytest.mark.parametrize("reverse", [False, True])
def test_getting_into_a_held_posture_once_is_no_repetition(reverse: bool) -> None:
    """Arms raised once and held still for the 6 s until the clip ends (or, played backward,
    held from the start and lowered once): the movement goes out once and never comes back,
    no repetition by construction (the clip's start and end in the two postures, each
    posture as its end of the movement). Counted 1 before: the far point cut off at the end
    was kept, there being no whole one to measure it against."""
    seq = _arms_raised_and_held()
    if reverse:
        seq = PoseSequence(seq.positions[::-1].copy(), seq.joint_names, seq.fps)
    assert count_repetitions(seq).count == 0
    # raised, held as long and lowered again: one repetition
    assert count_repetitions(_arms_raised_and_held(lowered=True)).count == 1
    # a piece cut out of a longer recording (a segment) keeps the far point its cut ends at:
    # the piece beyond it decides whether the movement comes back
    assert count_repetitions(seq, recording_edges=False).count == 1


def _raised_settled_and_paused(pause_s: float) -> PoseSequence:
    """Standing 0.6 s, both arms raised sideways to 100 degrees over 0.8 s, brought back to 75
    degrees over 0.4 s, held there ``pause_s`` seconds, lowered over 0.8 s, 0.6 s of standing
    (each move eased): one repetition, far point at 1.4 s, paused on its way back."""

    def ease(a: float, b: float, s: float) -> np.ndarray:
        return a + (b - a) * 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, int(round(s * FPS)))))

    rest = np.zeros(int(0.6 * FPS))
    deg = np.concatenate([rest, ease(0, 100, 0.8), ease(100, 75, 0.4),
                          np.full(int(pause_s * FPS), 75.0), ease(75, 0, 0.8), rest])  # fmt: skip
    body = standing()
    return to_sequence(*(_raise_arms(body, a, a) for a in deg), fps=FPS)


@pytest.mark.parametrize("pause_s", [0.6, 2.0])
def test_a_pause_on_the_way_back_is_no_posture_held(pause_s: float) -> None:
    """Arms raised to 100 degrees, brought 25 degrees back and paused there: counted with the
    end every 0.1 s from the moment they are 15 degrees back (1.7 s), the count stays 1
    through the pause and after. Before, a clip ending 0.4 s into the pause read as a
    posture got into and held (the side plank's rule: one far point, the end still near the
    far end) and counted 0, then 1 again once the arms moved on. The far point was left by
    more than a repetition's return before the line stopped: a repetition paused."""
    seq = _raised_settled_and_paused(pause_s)
    ends = range(int(round(1.7 * FPS)), seq.n_frames + 1, 3)
    counts = [count_repetitions(seq.slice_frames(0, e)).count for e in ends]
    assert counts == [1] * len(counts), counts
    peak = count_repetitions(seq).repetitions[0].peak_frame
    assert abs(peak - 1.4 * FPS) <= 2


def test_standing_still_with_jitter_has_no_repetition() -> None:
    seq = _movement([])  # 0.6 s of rest only: too short, so build a longer hold
    body = standing()
    rng = np.random.default_rng(0)
    frames = [
        {k: v + rng.normal(0.0, 0.005, 3) for k, v in body.items()} for _ in range(int(4 * FPS))
    ]
    seq = to_sequence(*frames, fps=FPS)
    result = count_repetitions(seq)
    assert result.count == 0
    # and names no joint as moving: the jitter's direction is no movement ("0 repetitions
    # (moving left elbow)" of a still pose)
    assert result.moving == ()
    # nor a period: the jitter's autocorrelation has a peak somewhere ("0 repetitions (period
    # 0.77 s)" of CMU 13_31 held still with 2 mm of noise)
    assert result.period_s is None


def test_mirror_angles_swaps_sides_and_reflects_lateral_tilts() -> None:
    names = ("left_knee", "right_knee", "torso_frontal", "torso_sagittal")
    values = np.array([[1.0, 2.0, np.pi / 2 + 0.3, 1.2]])
    np.testing.assert_allclose(mirror_angles(values, names), [[2.0, 1.0, np.pi / 2 - 0.3, 1.2]])


def test_too_short_and_no_person_are_refused() -> None:
    with pytest.raises(DataError, match="shorter than one repetition"):
        count_repetitions(to_sequence(*[standing()] * 5, fps=FPS))
    nobody = PoseSequence(np.full((90, 33, 3), np.nan), _movement([]).joint_names, FPS, source="x")
    with pytest.raises(DataError, match="no person"):
        count_repetitions(nobody)


# ---- real mocap against hand counts -------------------------------------------------------


def _fixture() -> dict[str, Any]:
    data: dict[str, Any] = json.loads(FIXTURE.read_text(encoding="utf-8"))
    return data


# on one xdist worker: the module's recordings made once, not once per worker
pytestmark = pytest.mark.xdist_group("repetitions")


@pytest.fixture(scope="module")
def recordings(shared_data: Path) -> dict[str, PoseSequence]:
    out = {}
    for clip in _fixture()["clips"]:
        if clip["source"].endswith(".amc") and clip["source"] not in out:
            out[clip["source"]] = read_asf_amc(
                shared_data / clip["asf"], shared_data / clip["source"]
            )
    return out


def test_mocap_counts_against_hand_counts(recordings: dict[str, PoseSequence]) -> None:
    errors = []
    for clip in _fixture()["clips"]:
        if not clip["source"].endswith(".amc"):
            continue
        seq = recordings[clip["source"]].slice_frames(clip["start_frame"], clip["end_frame"])
        errors.append(count_repetitions(seq).count - clip["count"])
    err = np.abs(errors)
    assert len(err) == 18
    # the literature's measures: off-by-one accuracy and mean absolute error
    assert (err <= 1).all()
    assert err.mean() <= 0.15
    assert (err == 0).mean() >= 0.85


def test_a_single_twist_turning_back_as_the_clip_ends_counts_once(
    recordings: dict[str, PoseSequence],
) -> None:
    """13_31's one slow twist (left at 12.5 s, by hand), the stretch ending as the trunk turns
    the other way, about half as far: that turn, cut off by the stretch's end, is measured
    against the whole far point (three quarters of it), not counted for want of a whole one on
    its own side. One, on the left, at 12.5 s."""
    clip = next(c for c in _fixture()["clips"] if c["source"].endswith("13_31.amc")
                and c.get("activity") == "Twist" and c["count"] == 1)  # fmt: skip
    seq = recordings[clip["source"]].slice_frames(clip["start_frame"], clip["end_frame"])
    reps = count_repetitions(seq).repetitions
    assert len(reps) == 1, reps
    assert reps[0].side == "left"
    assert abs((clip["start_frame"] + reps[0].peak_frame) / seq.fps - 12.5) <= 0.3


def test_jogging_counts_one_repetition_per_step(recordings: dict[str, PoseSequence]) -> None:
    """Jogging alternates legs; bending the arms into the jogging posture at the start is a
    one-off change as large as the steps, not what repeats: one repetition per step, within
    one of the hand counts (9 and 7 steps; the ends fade into standing and bouncing)."""
    clips = [c for c in _fixture()["clips"] if c.get("activity") == "Jog"]
    assert len(clips) == 2
    for clip in clips:
        seq = recordings[clip["source"]].slice_frames(clip["start_frame"], clip["end_frame"])
        result = count_repetitions(seq)
        assert result.alternating, clip["how"]
        assert abs(result.count - clip["count"]) <= 1, (result.count, clip["how"])


def _jog_after_a_twist(steps: int, lead_s: float) -> tuple[MovementSignals, np.ndarray]:
    """Joint angles (radians, 30 Hz) of ``steps`` jogging steps, the left knee first, each
    knee bending 0.5 rad over 11 samples while the other stays straight, the arms swinging a
    little with them; before them ``lead_s`` seconds of the end of a twist: the upper arms
    turning back across each other by 2 rad, the trunk turning back from 0.7 to 0.2 rad (the
    person stays a little turned), the arms lowering and the elbows bending into the jogging
    posture. Returns the signals and the steps' far points (samples)."""
    k, lead = 11, int(round(lead_s * FPS))
    bend = 0.5 * np.sin(np.pi * np.arange(k) / (k - 1)) ** 2
    left = np.concatenate([bend if i % 2 == 0 else np.zeros(k) for i in range(steps)])
    right = np.concatenate([np.zeros(k) if i % 2 == 0 else bend for i in range(steps)])
    swing = 0.1 * (left - right)
    jogging = {
        "left_elbow": 1.6 + 0 * left,
        "right_elbow": 1.6 + 0 * left,
        "left_armpit": 0.5 - swing,
        "right_armpit": 0.5 + swing,
        "left_knee": np.pi - left,
        "right_knee": np.pi - right,
        "torso_transverse": np.pi / 2 + 0.2 + 0 * left,
        "left_upper_arm_turn": -0.3 + swing,
        "right_upper_arm_turn": -0.3 - swing,
    }
    before = {
        "left_elbow": 2.3,
        "right_elbow": 2.3,
        "left_armpit": 1.1,
        "right_armpit": 1.1,
        "left_knee": np.pi,
        "right_knee": np.pi,
        "torso_transverse": np.pi / 2 + 0.7,
        "left_upper_arm_turn": 1.7,
        "right_upper_arm_turn": -2.3,
    }
    back = 0.5 * (1 + np.cos(np.pi * np.arange(lead) / max(1, lead - 1)))  # 1 -> 0
    names = tuple(jogging)
    x = np.stack([np.r_[v[0] + (before[n] - v[0]) * back, v] for n, v in jogging.items()], axis=1)
    return MovementSignals(x, names, FPS, 1), lead + np.arange(steps) * k + (k - 1) / 2


def test_jogging_steps_counted_after_the_end_of_a_twist() -> None:
    """A jog of six steps whose signals start 0.7 s early, in the end of a twist (as a
    stretch cut up to half a second or so early does): that one-off change made the
    side-against-side movement repeat less clearly (autocorrelation below 0.5), and the
    alternation was then judged on the angles as recorded, where the arms lowering from the
    twist outweighed what the legs did against each other and a trunk left a little turned
    kept the steps from mirroring: 3 repetitions, one per pair of steps, not alternating.
    Six steps, each at its far point, left and right in turn (the twist's turning back at
    the first sample, a far point before the clip, is left aside)."""
    sig, designed = _jog_after_a_twist(6, 0.7)
    result = count_in_signals(sig, len(sig.values), FPS)
    assert result.alternating
    steps = [r for r in result.repetitions if r.peak_frame >= designed[0] - 3]
    np.testing.assert_allclose([r.peak_frame for r in steps], designed, atol=2)
    assert [r.side for r in steps] == ["left", "right"] * 3
    # without the twist before it, as before
    sig, designed = _jog_after_a_twist(6, 0.0)
    result = count_in_signals(sig, len(sig.values), FPS)
    assert result.alternating
    np.testing.assert_allclose([r.peak_frame for r in result.repetitions], designed, atol=2)


@pytest.mark.parametrize(
    ("asf", "early_s", "end_frame"),
    [
        ("hdm05/train/3/HDM_bd.asf", 0.0, 2052),
        ("hdm05/train/3/HDM_bd.asf", 0.25, 2052),
        ("hdm05/train/3/HDM_bd.asf", 0.5, 2052),
        ("hdm05/train/3/HDM_bd.asf", 0.7, 2028),
        ("hdm05/train/3/HDM_bd.asf", 0.75, 2052),
        ("hdm05/train/1/HDM_bk.asf", 0.7, 2028),
    ],
)
def test_jogging_counted_when_its_stretch_starts_in_the_twist_before(
    recordings: dict[str, PoseSequence], shared_data: Path, asf: str, early_s: float, end_frame: int
) -> None:
    """13_31's jog (frames 1608-2052; 7 steps by hand, knee troughs at 13.79, 14.1, 14.48,
    14.86, 15.25, 15.64 and 16.02 s) counted from up to 0.75 s earlier, in the end of the
    twist before it, as segmentation may cut it (frames 1524-2028: 0.7 s early, 0.2 s short),
    with the fixture's skeleton and another: alternating, seven steps from the labelled start
    on (the twist's turning back before it may add one of its own). Was 3, not alternating,
    from 0.7 s early."""
    clip = next(c for c in _fixture()["clips"] if c["source"].endswith("13_31.amc")
                and c.get("activity") == "Jog")  # fmt: skip
    if asf == clip["asf"]:
        rec = recordings[clip["source"]]
    else:
        rec = read_asf_amc(shared_data / asf, shared_data / clip["source"])
    start = clip["start_frame"] - int(round(early_s * rec.fps))
    result = count_repetitions(rec.slice_frames(start, end_frame))
    assert result.alternating
    steps = [r for r in result.repetitions if start + r.peak_frame >= clip["start_frame"]]
    assert len(steps) == clip["count"] == 7, [start + r.peak_frame for r in result.repetitions]


def test_squats_counted_when_their_stretch_ends_in_the_jog_after(
    recordings: dict[str, PoseSequence],
) -> None:
    """13_30's two squats (knee troughs at 13.0 and 15.4 s by hand) counted from 0.5 s before
    their stretch to 0.75 s after it, into the jog (its first step at 16.5 s): the
    side-against-side movement, three jogging steps at the end, repeats no more than noise
    would over the stretch (autocorrelation 0.03), and about a running mean over that
    "period" (0.6 s) the squats, slower, vanished from what both sides do alike: the clip
    was taken for alternating, 5. Two squats, not alternating (the jog's first step could
    add one: it lies in the clip)."""
    clip = next(c for c in _fixture()["clips"] if c["source"].endswith("13_30.amc")
                and c.get("activity") == "Squat")  # fmt: skip
    rec = recordings[clip["source"]]
    start = clip["start_frame"] - int(round(0.5 * rec.fps))
    end = clip["end_frame"] + int(round(0.75 * rec.fps))
    result = count_repetitions(rec.slice_frames(start, end))
    assert not result.alternating
    peaks = [(start + r.peak_frame) / rec.fps for r in result.repetitions]
    assert result.count in (2, 3), peaks
    for t in (13.0, 15.4):
        assert min(abs(p - t) for p in peaks) <= 0.3, peaks


#: sides marked by hand (tests/fixtures/repetition_counts.json, "how"): the leg a jogging step
#: or a knee raise lifts, at the knee's trough, seconds into the recording
HAND_SIDES: dict[tuple[str, str], dict[str, tuple[float, ...]]] = {
    ("cmu-mocap6/amc/13_30.amc", "Jog"): {
        "left": (16.5, 17.2, 18.0, 18.75, 19.45),
        "right": (16.9, 17.6, 18.4, 19.05),
    },
    ("cmu-mocap6/amc/13_29.amc", "KneeRaise"): {
        "left": (25.4, 28.0, 30.8),
        "right": (24.1, 26.6, 29.5),
    },
    ("cmu-mocap6/amc/13_30.amc", "KneeRaise"): {"left": (7.5, 9.9), "right": (8.7, 11.0)},
    ("cmu-mocap6/amc/13_31.amc", "KneeRaise"): {"left": (4.0, 7.6), "right": (5.2, 6.4)},
}


@pytest.mark.parametrize(("source", "activity"), sorted(HAND_SIDES))
def test_each_alternating_repetition_has_the_side_marked_by_hand(
    recordings: dict[str, PoseSequence], source: str, activity: str
) -> None:
    """Every marked step or knee raise has a repetition whose far point lies within 0.25 s
    of it, on the side marked. 13_30's jog was right, right, right, right, left, right, left,
    ... (both legs and arms move at every step; the right arm swings wider): the sides are
    now told by which side leads at one side's far points against the other's."""
    (clip,) = [c for c in _fixture()["clips"]
               if c["source"] == source and c.get("activity") == activity]  # fmt: skip
    seq = recordings[source].slice_frames(clip["start_frame"], clip["end_frame"])
    result = count_repetitions(seq)
    assert result.alternating
    peaks = [(clip["start_frame"] + r.peak_frame) / seq.fps for r in result.repetitions]
    for side, times in HAND_SIDES[(source, activity)].items():
        for t in times:
            i = int(np.argmin(np.abs(np.array(peaks) - t)))
            assert abs(peaks[i] - t) <= 0.25, (t, peaks)
            assert result.repetitions[i].side == side, (t, side, peaks[i])


def _shoulders_turned(seq: PoseSequence, frame: int) -> str:
    """Which way the shoulders are turned at ``frame``, from the positions alone: "left" when
    the left shoulder lies behind the right one along the way the feet point (toe minus
    ankle, both feet; a trunk twist leaves the feet where they stand)."""
    p = seq.positions[frame]
    forward = sum(p[JOINT_INDEX[f"{s}_foot_index"]] - p[JOINT_INDEX[f"{s}_ankle"]]
                  for s in ("left", "right"))  # fmt: skip
    across = p[JOINT_INDEX["left_shoulder"]] - p[JOINT_INDEX["right_shoulder"]]
    return "left" if float(across @ forward) < 0 else "right"


def test_each_twist_is_on_the_side_the_shoulders_turn(
    recordings: dict[str, PoseSequence],
) -> None:
    """A twist's side is the way its shoulders turn, not which arm turns farther: at every
    far point of CMU subject 13's four twist stretches, the side given is the one read off
    the shoulder line against the feet, and the sides take turns."""
    clips = [c for c in _fixture()["clips"] if c.get("activity") == "Twist"]
    assert len(clips) == 4
    for clip in clips:
        seq = recordings[clip["source"]].slice_frames(clip["start_frame"], clip["end_frame"])
        result = count_repetitions(seq)
        assert result.alternating, clip["how"]
        sides = [r.side for r in result.repetitions]
        assert sides == [_shoulders_turned(seq, r.peak_frame) for r in result.repetitions]
        assert all(a != b for a, b in zip(sides, sides[1:], strict=False)), sides


@pytest.mark.parametrize("activity", ["Squat", "JumpJack", "KneeRaise"])
def test_mocap_plain_exercises_counted_exactly(
    recordings: dict[str, PoseSequence], activity: str
) -> None:
    clips = [c for c in _fixture()["clips"] if c.get("activity") == activity]
    assert clips
    for clip in clips:
        seq = recordings[clip["source"]].slice_frames(clip["start_frame"], clip["end_frame"])
        result = count_repetitions(seq)
        assert result.count == clip["count"], clip["how"]
        assert result.alternating == (activity == "KneeRaise")


def test_joints_dropped_at_random_in_a_third_of_the_frames_are_still_followed(
    recordings: dict[str, PoseSequence],
) -> None:
    """CMU 13_29's hand-counted stretches with each joint missing (NaN) at random in 30 % of
    the frames, as a pose model unsure of a joint drops it now and then: each angle (three
    joints) is computed in about a third of the frames, a frame or two apart. Filled between
    its values it is counted nearly as before (the hand counts: 4 jumping jacks, 3 twists, 6
    arm circles, 3 toe touches, 6 knee raises, 2 squats; this draw loses one jumping jack,
    five others of six draws none). Before, an angle seen in less than half of the frames
    took no part: only the hips' height was left, and every stretch but the squats counted 0
    (the jumping jacks 6)."""
    rng = np.random.default_rng(0)
    counts, hand = [], []
    for clip in _fixture()["clips"]:
        if clip["source"] != "cmu-mocap6/amc/13_29.amc":
            continue
        seq = recordings[clip["source"]].slice_frames(clip["start_frame"], clip["end_frame"])
        positions = seq.positions.copy()
        positions[rng.random(positions.shape[:2]) < 0.3] = np.nan
        dropped = PoseSequence(positions, seq.joint_names, seq.fps, source=clip["activity"])
        counts.append(count_repetitions(dropped).count)
        hand.append(clip["count"])
    assert hand == [4, 3, 6, 3, 6, 2]
    errors = np.abs(np.subtract(counts, hand))
    assert errors.max() <= 1 and (errors == 0).sum() >= 5, counts


@pytest.mark.parametrize("activity", ["Squat", "JumpJack"])
def test_period_agrees_with_the_qmp_fit(recordings: dict[str, PoseSequence], activity: str) -> None:
    """The autocorrelation period against SINDy's fitted period (features.qmp) of the angles
    that move most, fitted over the whole stretch: two independent estimates."""
    clip = next(c for c in _fixture()["clips"] if c.get("activity") == activity)
    seq = recordings[clip["source"]].slice_frames(clip["start_frame"], clip["end_frame"])
    result = count_repetitions(seq)
    sig = signals_of(seq)
    names = [m for m in result.moving if m in sig.names][:2]
    fits = fit_signals(sig.values[:, [sig.names.index(n) for n in names]], seq.fps, names)
    qmp_period = np.nanmedian(fits.quantity("period_s")[0])
    assert result.period_s == pytest.approx(qmp_period, rel=0.05)


# ---- the command ---------------------------------------------------------------------------


def _squats_file(recordings: dict[str, PoseSequence], tmp_path: Path) -> Path:
    clip = next(c for c in _fixture()["clips"] if c.get("activity") == "Squat")
    seq = recordings[clip["source"]].slice_frames(clip["start_frame"], clip["end_frame"])
    return save_pose(seq, tmp_path / "squats.npz")


def test_reps_command_json_and_plot(
    recordings: dict[str, PoseSequence], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _squats_file(recordings, tmp_path)
    plot = tmp_path / "reps.png"
    assert main(["reps", str(path), "--json", "--plot", str(plot)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["clip"] == str(path) and doc["count"] == 2 and doc["fps"] == 120.0
    reps = doc["repetitions"]
    assert len(reps) == 2
    assert all(r["start_frame"] < r["peak_frame"] < r["end_frame"] for r in reps)
    assert reps[0]["end_frame"] == reps[1]["start_frame"]
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["reps", str(path)]) == 0
    assert "2 repetitions" in capsys.readouterr().out


def test_reps_command_reads_a_long_recording_in_pieces(
    recordings: dict[str, PoseSequence],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A recording longer than CHUNK_FRAMES (made 500 here) has its joint angles computed
    500 frames at a time, as segment reads it: no piece of the pose model's signals spans
    more (before, the whole recording's at once: 1 GB for 42 minutes at 120 fps), and the
    repetitions are the ones counted on the whole (13_29's knee raises, 1,104 frames: 6 by
    hand)."""
    import features.signals
    from cbr import long_clip

    rec = recordings["cmu-mocap6/amc/13_29.amc"]
    path = tmp_path / "long.npz"
    save_pose(PoseSequence(rec.positions[2700:3804], rec.joint_names, 120.0), path)
    assert main(["reps", str(path), "--json"]) == 0
    whole = json.loads(capsys.readouterr().out)
    sizes: list[int] = []

    def spy(real: Any) -> Any:
        def signals(seq: PoseSequence) -> Any:
            sizes.append(seq.n_frames)
            return real(seq)

        return signals

    monkeypatch.setattr(long_clip, "CHUNK_FRAMES", 500)
    monkeypatch.setattr(long_clip, "state_signals", spy(long_clip.state_signals))
    monkeypatch.setattr(features.signals, "state_signals", spy(features.signals.state_signals))
    assert main(["reps", str(path), "--json"]) == 0
    pieces = json.loads(capsys.readouterr().out)
    assert sizes and max(sizes) <= 500, sizes
    assert pieces == whole
    assert whole["count"] == 6


def test_reps_plot_of_a_long_recording_reads_its_fluents_in_pieces(
    recordings: dict[str, PoseSequence],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The picture of a recording longer than CHUNK_FRAMES (made 500 here) is drawn from its
    fluents computed 500 frames at a time, with the history their motion states read (as
    describe does): before, `reps --plot` and `segment --plot` computed the whole recording's
    at once (1.5-1.6 GB for 503 s at 120 fps, three times the count or segmentation). The
    timeline is the whole clip's: the same states, the same share of the clip each holds."""
    import features.fluents
    import features.timeline
    from cbr import long_clip
    from features.derived import fluents_of
    from features.timeline import Timeline, describe_clip

    rec = recordings["cmu-mocap6/amc/13_29.amc"]
    seq = PoseSequence(rec.positions[2700:3804], rec.joint_names, 120.0)
    path, plot = tmp_path / "long.npz", tmp_path / "long.png"
    save_pose(seq, path)
    whole = describe_clip(fluents_of(seq))
    sizes: list[int] = []
    real = features.fluents.evaluate

    def evaluate(clip: PoseSequence, *args: Any, **kwargs: Any) -> Any:
        sizes.append(clip.n_frames)
        return real(clip, *args, **kwargs)

    monkeypatch.setattr(features.fluents, "evaluate", evaluate)
    monkeypatch.setattr(features.timeline, "CHUNK_FRAMES", 500)
    monkeypatch.setattr(long_clip, "CHUNK_FRAMES", 500)
    assert main(["reps", str(path), "--plot", str(plot)]) == 0
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    history = features.fluents.history_frames(features.fluents.DEFAULT_TABLE, 120.0)
    assert sizes and max(sizes) <= 500 + history < seq.n_frames, sizes
    from features.timeline import timeline_of

    pieces = timeline_of(PoseSequence(seq.positions, seq.joint_names, 120.0))
    assert isinstance(pieces, Timeline) and pieces.n_frames == whole.n_frames
    assert pieces.layout.state_names == whole.layout.state_names
    np.testing.assert_allclose(pieces.share, whole.share, atol=1e-6)
    np.testing.assert_allclose(pieces.columns, whole.columns, atol=1e-6)


LOW_RATE_NOTE = (
    "note: {path}: at 2 fps a movement that repeats within 1 s (two frames) is not followed:"
    " its repetitions may be miscounted (the shortest, 0.4 s, needs 5 fps)"
)
GLITCH_RATE_NOTE = (
    "note: {path}: at {fps} fps the running median of three frames that drops a one-frame"
    " glitch of a pose model drops a quick repetition's far point as well (the shortest"
    " repetition, 0.4 s, stays out there 0.2 s: two frames need 10 fps): its repetitions may"
    " be miscounted"
)


def test_a_recording_too_slow_to_follow_a_repetition_is_noted(
    recordings: dict[str, PoseSequence], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """CMU 13_29's knee raises read at 2 fps (every 60th frame): a movement that repeats
    within 1 s, two frames, is not followed (the shortest repetition, 0.4 s, needs 5 fps);
    the count is still given, with a note naming the file. Before, nothing said so (13_31 at
    2 fps: 2 of its 7 jogging steps counted, 3 of its 4 knee raises). At 8 fps the counter's
    running median of three frames (0.2 s rounded) drops the far point of the shortest
    repetition, out there for 0.2 s, two frames only from 10 fps: noted too; at 5 fps this
    motion capture is read with no median (it has no pose model's glitch to drop) and at
    10 fps keeps two frames out there: nothing (tests/test_hunt45c.py: a pose model's poses
    are noted at 5 fps)."""
    rec = recordings["cmu-mocap6/amc/13_29.amc"]
    for fps in (2, 5, 8, 10):
        path = tmp_path / f"knee_{fps}.npz"
        positions = rec.positions[2700 : 3804 : 120 // fps]
        save_pose(PoseSequence(positions, rec.joint_names, float(fps)), path)
        assert main(["reps", str(path)]) == 0
        captured = capsys.readouterr()
        notes = [line for line in captured.err.splitlines() if line.startswith("note:")]
        expected = {
            2: [LOW_RATE_NOTE.format(path=path)],
            5: [],
            8: [GLITCH_RATE_NOTE.format(path=path, fps=8)],
            10: [],
        }
        assert notes == expected[fps], captured.err
        assert "repetition" in captured.out


def test_a_recording_at_a_very_high_rate_is_filtered_at_a_few_hundred_fps(
    recordings: dict[str, PoseSequence], monkeypatch: pytest.MonkeyPatch
) -> None:
    """13_29's jumping jacks (4 by hand) interpolated to 4800 fps (18,681 frames): the running
    median reads every 20th frame (240 fps), so it spans 49 samples, not 961 at every frame
    (29 s of a 5-s clip's count, before); the same 4 repetitions, at the same far points
    within a 120-fps frame as at 120 fps. Up to 240 fps every frame is read, as before."""
    import scipy.ndimage

    widths: list[tuple[int, int]] = []
    real = scipy.ndimage.median_filter  # what the running median imports when it runs

    def median(x: np.ndarray, size: int | tuple[int, int], **kwargs: Any) -> Any:
        widths.append((len(x), size if isinstance(size, int) else size[0]))
        return real(x, size=size, **kwargs)

    monkeypatch.setattr(scipy.ndimage, "median_filter", median)
    seq = recordings["cmu-mocap6/amc/13_29.amc"].slice_frames(0, 468)
    t = np.arange(seq.n_frames)
    fine = np.arange(0.0, seq.n_frames - 1 + 1e-9, 1 / 40)
    flat = seq.positions.reshape(seq.n_frames, -1)
    high = np.stack([np.interp(fine, t, flat[:, i]) for i in range(flat.shape[1])], axis=1)
    fast = PoseSequence(high.reshape(len(fine), *seq.positions.shape[1:]), seq.joint_names, 4800.0)
    at_120 = count_repetitions(seq)
    at_4800 = count_repetitions(fast)
    # one filter per angle (hunt 38h), each clip's angles at one width
    assert list(dict.fromkeys(widths)) == [(468, 25), (math.ceil(len(fine) / 20), 49)], widths
    assert at_120.count == at_4800.count == 4
    peaks = [r.peak_frame for r in at_120.repetitions]
    far = [r.peak_frame / 40 for r in at_4800.repetitions]
    assert np.abs(np.subtract(far, peaks)).max() <= 1, (far, peaks)


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_reps_command_refuses_a_clip_shorter_than_a_repetition(
    recordings: dict[str, PoseSequence], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    seq = next(iter(recordings.values())).slice_frames(0, 24)  # 0.2 s at 120 fps
    path = save_pose(seq, tmp_path / "short.npz")
    before = _sha(path)
    plot = tmp_path / "out.png"
    assert main(["reps", str(path), "--plot", str(plot)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "shorter than one repetition" in err and str(path) in err
    assert _sha(path) == before and not plot.exists()
    assert not list(tmp_path.glob(".*"))  # no stray temporary file


def test_reps_command_refuses_a_recording_with_no_person(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    seq = PoseSequence(np.full((90, 33, 3), np.nan), _movement([]).joint_names, FPS)
    path = save_pose(seq, tmp_path / "empty.npz")
    before = _sha(path)
    assert main(["reps", str(path), "--json"]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1 and "no person" in captured.err
    assert "Traceback" not in captured.err and _sha(path) == before


def test_far_points_of_a_video_lie_where_a_person_was_seen(lunge_poses: PoseSequence) -> None:
    """The reverse lunge (25 fps, as extract finds it) with nobody seen in its first second
    and from 4.8 to 6.8 s (frames 0-24 and 120-169 missing, as a pose model leaves a person
    out of view). What is filled in where nobody is seen (the first posture seen, held;
    gaps interpolated) holds no far point: each repetition's far point is at a frame that
    shows the person, or within the 0.4 s a repetition takes at least of one."""
    seq = lunge_poses.to_canonical()
    positions = seq.positions.copy()
    confidence = None if seq.confidence is None else seq.confidence.copy()
    for a, b in ((0, 25), (120, 170)):
        positions[a:b] = np.nan
        if confidence is not None:
            confidence[a:b] = 0.0
    gaps = dataclasses.replace(seq, positions=positions, confidence=confidence)
    seen = np.flatnonzero(np.isfinite(gaps.positions).all(axis=(1, 2)))
    result = count_repetitions(gaps)
    assert result.count > 0
    peaks = np.array([r.peak_frame for r in result.repetitions])
    nearest = np.abs(peaks[:, None] - seen[None, :]).min(axis=1)
    assert (nearest <= 0.4 * gaps.fps).all()
    assert peaks.min() >= seen.min()


def test_repetitions_counted_in_pieces_of_a_street_do_not_overlap(shared_data: Path) -> None:
    """The street video's first 40 s, the pose jumping from one pedestrian to another, cut
    into pieces as segments are (each counted on the recording's own signals): in every
    piece the repetitions follow one another without overlap, each holding its far point
    (they overlapped, one of them over a repetition of one frame, with 15-s pieces)."""
    found = estimate_video(shared_data / "media" / "vtest.avi", progress_bar=False, max_frames=400)
    seq = found.sequence.to_canonical()
    sig = movement_signals(seq)
    for length in (100, 150, 200):
        edges = [*range(0, seq.n_frames, length), seq.n_frames]
        bounds = list(zip(edges[:-1], edges[1:], strict=True))
        for (a, b), reps in zip(bounds, counted_segments(sig, bounds, seq.n_frames), strict=True):
            ends = [a, *(r.end_frame for r in reps)]
            for r, before in zip(reps, ends, strict=False):
                assert before <= r.start_frame <= r.peak_frame < r.end_frame <= b, (a, b, reps)


def test_reps_command_refuses_a_plot_over_its_input(
    recordings: dict[str, PoseSequence], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _squats_file(recordings, tmp_path)
    before = _sha(path)
    assert main(["reps", str(path), "--plot", str(path)]) == 1
    assert "would overwrite an input" in capsys.readouterr().err
    assert _sha(path) == before


def test_reps_command_on_a_real_squat_video(
    shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The 5-fps squat video end to end (BlazePose, then counting): three squats by hand."""
    video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    hand = next(c for c in _fixture()["clips"] if c["source"].endswith(video.name))
    assert main(["reps", str(video), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["count"] == hand["count"] == 3
    # far points at the bottoms seen by hand: 2.0 s, 6.8 s, and 12.0-12.8 s
    bottoms = [r["peak_frame"] / doc["fps"] for r in doc["repetitions"]]
    np.testing.assert_allclose(bottoms, [2.0, 6.8, 12.0], atol=0.7)


def _session_poses(
    bundled_poses: Callable[[str], PoseSequence], name: str, folder: Path
) -> tuple[Path, Path]:
    """The bundled video ``name`` and its poses as extract finds them, estimated once in the
    session, saved in ``folder`` as a pose file: ``reps`` of it gives what ``reps`` of the
    video gives but for the path (--json of both compared for the glute bridge and the leg
    raise), without the pose model again (the squat test above runs the video end to end)."""
    video = Path(name)
    return video, save_pose(bundled_poses(name), folder / f"{video.stem}.npz")


def test_reps_command_on_a_real_glute_bridge_video(
    bundled_poses: Callable[[str], PoseSequence],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A person lying on the back, three glute bridges by hand, the first and last held as the
    clip starts and ends: counted from lying flat, not from the bridge (the hips straighten
    toward standing at ease in it; the two lowerings between the bridges were counted)."""
    name = "glute_bridge/fit_glute_bridge_pexels6525487.mp4"
    video, poses = _session_poses(bundled_poses, name, tmp_path)
    hand = next(c for c in _fixture()["clips"] if c["source"].endswith(video.name))
    assert main(["reps", str(poses), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["count"] == hand["count"] == 3
    # far points in the hips-up stretches seen by hand, 0.0-1.1 s, 2.8-3.9 s and 5.9-6.6 s,
    # within 0.2 s (the hand's reading of the video's frames)
    tops = np.array([r["peak_frame"] / doc["fps"] for r in doc["repetitions"]])
    up, down = np.array([0.0, 2.8, 5.9]), np.array([1.1, 3.9, 6.6])
    assert ((tops >= up - 0.2) & (tops <= down + 0.2)).all()


def test_reps_command_on_a_real_side_lying_leg_raise_video(
    bundled_poses: Callable[[str], PoseSequence],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A person lying on her side raises the top leg twice (by hand: up 2.2-4.8 s and from
    8.4 s to the end): each far point lies where the leg is up. Before, the far points were
    put at 1.12 and 7.60 s, where the leg lies down: the angles that stay far from standing
    at ease throughout (the trunk lying, the lower arm under the head) swamped the two
    ends' distance from ease, so rest was taken from the clip's ends, which lie one down
    and one up."""
    name = "side_lying_leg_raise/fit_lateral_leg_raise_pexels6974513.mp4"
    video, poses = _session_poses(bundled_poses, name, tmp_path)
    hand = next(c for c in _fixture()["clips"] if c["source"].endswith(video.name))
    assert main(["reps", str(poses), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["count"] == hand["count"] == 2
    tops = np.array([r["peak_frame"] / doc["fps"] for r in doc["repetitions"]])
    up, down = np.array([2.2, 8.4]), np.array([4.8, 10.0])
    assert ((tops >= up - 0.2) & (tops <= down + 0.2)).all(), tops


def test_reps_command_on_a_real_side_plank_video(side_plank_reps: tuple[str, str]) -> None:
    """A person lying on the side gets into a side plank in the first 1.4 s and holds it to
    the end (8.6 s): no repetition by hand. Counted 1 before: the supporting shoulder's angle
    sags from 88 to about 72 degrees over the hold, and the movement line, mostly that angle,
    fell back from its far point at 2.2 s by more than a repetition's return. Now the clip is
    seen to start lying (the movement's rest end) and end in the plank, holding still."""
    name = "fit_side_plank_pexels6023266.mp4"  # reps VIDEO --json, run in conftest.py
    hand = next(c for c in _fixture()["clips"] if c["source"].endswith(name))
    doc = json.loads(side_plank_reps[1])
    assert doc["count"] == hand["count"] == 0
    assert doc["repetitions"] == []


def test_no_repetition_starts_where_nobody_is_seen(recordings: dict[str, PoseSequence]) -> None:
    """13_30 with its first 10 s blank (nobody seen, by construction): every repetition lies
    where the person is seen, from frame 1200 on (the first ran from 4.5 s, across 5.5 s of
    nobody, to its far point at 10.0 s)."""
    seq = recordings["cmu-mocap6/amc/13_30.amc"]
    positions = seq.positions.copy()
    positions[:1200] = np.nan
    blank = PoseSequence(positions, seq.joint_names, seq.fps)
    reps = count_repetitions(blank).repetitions
    assert reps and min(r.start_frame for r in reps) >= 1200, reps[:2]
