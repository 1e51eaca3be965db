"""Repetition counts whose truth is known by construction: signals built with n cycles, and
real single repetitions of UI-PRMD and HDM05 joined one after the other
(:mod:`features.joining`), whose count is the number joined."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.geometry import joint_angle
from features.joining import join_repetitions
from features.poses import PoseSequence
from features.readers.asfamc import read_asf_amc
from features.readers.uiprmd import read_uiprmd_kinect, read_uiprmd_vicon
from features.repetitions import (
    MovementSignals,
    _bounds,
    count_in_signals,
    count_repetitions,
    periodic_share,
    upper_arm_turn,
)
from features.skeleton import JOINT_INDEX
from tests.bodies import rot_x, rot_y, rotate, standing, to_sequence

FPS = 30.0
KNEES = ("left_knee", "right_knee")


def _signals(values: np.ndarray, names: tuple[str, ...]) -> MovementSignals:
    return MovementSignals(values, names, FPS, 1)


def _bend(cycles: np.ndarray) -> np.ndarray:
    """Knee angles (radians) of squats: straight (pi) at rest, down by up to 1.2 rad, one
    cosine cycle per entry of ``cycles`` (its length in samples)."""
    return np.concatenate(
        [np.pi - 0.6 * (1 - np.cos(2 * np.pi * np.arange(n) / n)) for n in cycles]
    )


def test_cycles_with_a_small_extra_bump_count_the_cycles() -> None:
    """Six squats of 2 s and, in the rest between the third and fourth, a dip of a tenth of
    their depth: six."""
    knee = _bend(np.full(6, 60))
    rest = np.full(30, np.pi)
    dip = np.pi - 0.06 * (1 - np.cos(2 * np.pi * np.arange(20) / 20))
    rest[5:25] = dip
    knee = np.concatenate([knee[:180], rest, knee[180:]])
    result = count_in_signals(_signals(np.stack([knee, knee], axis=1), KNEES), len(knee), FPS)
    assert result.count == 6
    assert not result.alternating


def test_a_far_point_lies_where_the_person_was_seen() -> None:
    """The person out of view for the first 2 s (the values there are the first posture
    seen, held: knees bent 1.2 rad), then seen rising from that squat's bottom, resting and
    doing two more squats (bottoms 30 and 37 samples into cycles of 60 and 75 starting at
    sample 110). The held plateau's middle (sample 30) is no far point: the cut-off squat's
    is where it was first seen (sample 60)."""
    held = np.full(60, np.pi - 1.2)
    rise = np.pi - 1.2 + 0.6 * (1 - np.cos(np.pi * np.arange(30) / 30))
    knee = np.concatenate(
        [held, rise, np.full(20, np.pi), _bend(np.array([60, 75])), np.full(20, np.pi)]
    )
    blind = np.arange(len(knee)) < 60
    sig = MovementSignals(np.stack([knee, knee], axis=1), KNEES, FPS, 1, blind)
    result = count_in_signals(sig, len(knee), FPS)
    np.testing.assert_allclose([r.peak_frame for r in result.repetitions], [60, 140, 207.5], atol=1)
    # slicing keeps what was seen aligned with the values
    part = sig.part(50, 150)
    assert part.blind is not None and part.blind.sum() == 10 and len(part.values) == 100
    # nothing seen at all: nothing counted
    unseen = MovementSignals(sig.values, KNEES, FPS, 1, np.ones(len(knee), dtype=bool))
    assert count_in_signals(unseen, len(knee), FPS).count == 0


def test_a_wobble_just_past_the_symmetric_posture_is_no_repetition() -> None:
    """Knee raises left, right, left, right, left, left, right, left, right (1 s each, 1.2 rad,
    0.2 s rest after each); between the two lefts in a row the right knee bends 0.05 rad
    (3 degrees) for 0.4 s. That wobble is no right raise: nine repetitions, far points at
    the raises' middles (sample 15 of each 36; the wobble takes 18), sides as raised."""
    order = ["L", "R", "L", "R", "L", "w", "L", "R", "L", "R"]
    left: list[np.ndarray] = []
    right: list[np.ndarray] = []
    for o in order:
        n, depth = (12, 0.05) if o == "w" else (30, 1.2)
        bend = depth * 0.5 * (1 - np.cos(2 * np.pi * np.arange(n) / n))
        left += [bend if o == "L" else np.zeros(n), np.zeros(6)]
        right += [np.zeros(n) if o == "L" else bend, np.zeros(6)]
    values = np.pi - np.stack([np.concatenate(left), np.concatenate(right)], axis=1)
    result = count_in_signals(_signals(values, KNEES), len(values), FPS)
    assert result.alternating
    starts = [0, 36, 72, 108, 144, 198, 234, 270, 306]  # each raise's first sample
    assert [r.peak_frame for r in result.repetitions] == [a + 15 for a in starts]
    sides = [r.side for r in result.repetitions]
    assert sides == ["left", "right", "left", "right", "left", "left", "right", "left", "right"]


def test_repetitions_follow_one_another_each_holding_its_far_point() -> None:
    """Three far points, the second lower than everything after it up to the third (the other
    side's, barely past the symmetric posture): each repetition runs from the lowest point
    after the far point before it, so the three spans tile samples 0-6 without overlap and
    each holds its far point. (Sought from the far point itself, the lowest point after the
    second far point was that far point: spans [3, 4) and [3, 6) overlapped.)"""
    line = np.array([0.0, 1.0, 0.5, 0.2, 0.9, 0.0])
    assert _bounds(line, np.array([1, 3, 4]), reach=5) == [(0, 3), (3, 4), (4, 6)]


def test_uneven_cycles_of_several_people_count_exactly() -> None:
    """Ten squats of unequal length (1.3-2.7 s) and depth (0.8-1.2 of the mean), with
    sensor noise: a lag of the autocorrelation near the whole clip, estimated from few
    samples, must not pass for the period. Ten."""
    rng = np.random.default_rng(1)
    lengths = rng.integers(40, 81, size=10)
    depth = np.repeat(rng.uniform(0.8, 1.2, size=10), lengths)
    knee = np.pi - depth * (np.pi - _bend(lengths)) + rng.normal(0, 0.02, lengths.sum())
    result = count_in_signals(_signals(np.stack([knee, knee], axis=1), KNEES), len(knee), FPS)
    assert result.count == 10


def _ease(n: int, a: float, b: float) -> np.ndarray:
    """``n`` samples easing (half a cosine) from ``a`` to ``b``."""
    return a + (b - a) * 0.5 * (1 - np.cos(np.pi * np.arange(n) / n))


def test_shallow_repetitions_among_deep_ones_count() -> None:
    """Nine squats of unequal length (1.5-3.6 s) and rest, two of them a third as deep (0.45
    rad against 1.2: well above pose jitter, below 0.4 of the typical one): nine."""
    rng = np.random.default_rng(3)
    parts = [np.full(20, np.pi)]
    for n, depth in zip(
        rng.integers(45, 110, size=9), [1.2, 1.2, 0.45, 1.2, 1.2, 1.2, 1.2, 0.45, 1.2], strict=True
    ):
        down = _ease(int(n) // 2, 0.0, depth)
        parts += [
            np.pi - np.concatenate([down, down[::-1]]),
            np.full(int(rng.integers(5, 40)), np.pi),
        ]
    knee = np.concatenate(parts)
    result = count_in_signals(_signals(np.stack([knee, knee], axis=1), KNEES), len(knee), FPS)
    assert result.count == 9


def test_a_second_far_point_after_a_shallow_dip_is_the_same_repetition() -> None:
    """Seven lunges of unequal length (1.7-3.6 s), each going down 1.2 rad, coming up by 0.45,
    going down again to 1.14 (a wobble at the bottom, falling back by a third of the
    depth), then up to rest: seven, not fourteen."""
    rng = np.random.default_rng(3)
    parts = [np.full(20, np.pi)]
    for n in rng.integers(50, 110, size=7):
        q = int(n) // 4
        bend = [
            _ease(q, 0, 1.2),
            _ease(q, 1.2, 0.75),
            _ease(q, 0.75, 1.14),
            _ease(int(n) - 3 * q, 1.14, 0),
        ]
        parts += [np.pi - np.concatenate(bend), np.full(int(rng.integers(5, 40)), np.pi)]
    knee = np.concatenate(parts)
    result = count_in_signals(_signals(np.stack([knee, knee], axis=1), KNEES), len(knee), FPS)
    assert result.count == 7
    # each repetition's far point is its deeper first one
    assert all(abs(knee[r.peak_frame] - (np.pi - 1.2)) < 0.05 for r in result.repetitions)


def test_one_leg_moving_on_and_on_is_not_one_repetition_per_side() -> None:
    """The left knee bends five times with no rest between; the right stands by (a little
    sway): five, not ten."""
    rng = np.random.default_rng(1)
    left = _bend(np.full(5, 45))
    right = np.pi - 0.05 * (1 - np.cos(2 * np.pi * np.arange(len(left)) / 90))
    right = right + rng.normal(0, 0.01, len(left))
    result = count_in_signals(_signals(np.stack([left, right], axis=1), KNEES), len(left), FPS)
    assert not result.alternating
    assert result.count == 5


def test_legs_taking_turns_count_one_per_side() -> None:
    """Left, right, left, right, left, right knee bends: six, sides alternating."""
    one = _bend(np.full(1, 40))
    still = np.full(40, np.pi)
    left = np.concatenate([one, still] * 3)
    right = np.concatenate([still, one] * 3)
    result = count_in_signals(_signals(np.stack([left, right], axis=1), KNEES), len(left), FPS)
    assert result.alternating
    assert result.count == 6
    assert [r.side for r in result.repetitions] == ["left", "right"] * 3
    # first seen at the first bend's deepest (sample 20), after 50 samples out of view whose
    # values are that posture held: the cut-off bend's far point is where it was first seen
    values = np.stack([left, right], axis=1)[20:]
    values = np.concatenate([np.repeat(values[:1], 50, axis=0), values])
    blind = np.arange(len(values)) < 50
    late = count_in_signals(MovementSignals(values, KNEES, FPS, 1, blind), len(values), FPS)
    assert late.alternating
    assert [r.peak_frame for r in late.repetitions] == [50, 90, 130, 170, 210, 250]
    assert [r.side for r in late.repetitions] == ["left", "right"] * 3


# ---- joining single repetitions ------------------------------------------------------------


def _turned(seq, degrees: float, shift: np.ndarray):  # type: ignore[no-untyped-def]
    """``seq`` turned about the vertical by ``degrees`` and moved by ``shift`` (metres)."""
    a = np.radians(degrees)
    rot = np.array([[np.cos(a), 0, -np.sin(a)], [0, 1, 0], [np.sin(a), 0, np.cos(a)]])
    return seq.__class__(seq.positions @ rot.T + shift, seq.joint_names, seq.fps)


def _knee_angle(p: np.ndarray) -> np.ndarray:
    j = JOINT_INDEX
    return joint_angle(p[:, j["left_hip"]], p[:, j["left_knee"]], p[:, j["left_ankle"]])


def test_joining_places_each_repetition_where_the_previous_ended() -> None:
    """A second take turned by 90 degrees and 3 m away is put back: the seam has no jump
    (both takes stand the same), frames are kept whole, the blend lies between them, and
    the joint angles are those of the takes."""
    body = standing()
    bent = dict(body, left_knee=body["left_knee"] + np.array([0.0, 0.0, 0.15]))
    take = to_sequence(*([body] * 10 + [bent] * 10 + [body] * 10), fps=FPS)
    other = _turned(take, 90.0, np.array([3.0, 0.0, -2.0]))
    joined = join_repetitions([take, other])
    assert joined.seq.n_frames == 30 + 3 + 30  # 0.1 s of blending at 30 fps
    np.testing.assert_array_equal(joined.starts, [0, 33])
    assert joined.jumps_m[0] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(joined.seq.positions[33:], take.positions, atol=1e-9)
    np.testing.assert_allclose(
        _knee_angle(joined.seq.positions[33:]), _knee_angle(other.positions), atol=1e-9
    )


def test_joining_refuses_nothing_and_mixed_frame_rates() -> None:
    take = to_sequence(*[standing()] * 5, fps=FPS)
    with pytest.raises(DataError, match="no repetitions to join"):
        join_repetitions([])
    with pytest.raises(DataError, match="differ in frame rate"):
        join_repetitions([take, to_sequence(*[standing()] * 5, fps=60.0)])
    hipless = take.positions.copy()
    hipless[:, JOINT_INDEX["left_hip"]] = np.nan
    nobody = PoseSequence(hipless, take.joint_names, FPS, source="rep2.npz")
    with pytest.raises(DataError, match=r"rep2\.npz.*no frame shows both hips"):
        join_repetitions([take, nobody])


UIPRMD = Path("ui-prmd") / "data" / "Segmented Movements"


def test_joined_labels_change_mid_blend_and_refuse_a_wrong_number() -> None:
    """Takes of 30, 20 and 25 frames labelled a, b, b at 30 fps (3 frames of blending): the
    first 30 frames are a, then 2 blend frames a and 1 b (the change mid-blend), the 20
    frames of the second take b, the 3 blend frames b, the last 25 frames b."""
    take = to_sequence(*[standing()] * 30, fps=FPS)
    joined = join_repetitions(
        [take, take.slice_frames(0, 20), take.slice_frames(0, 25)], labels=["a", "b", "b"]
    )
    assert joined.labels is not None
    expected = ["a"] * 32 + ["b"] * (1 + 20 + 3 + 25)
    assert joined.labels.tolist() == expected
    assert join_repetitions([take]).labels is None
    with pytest.raises(DataError, match="1 labels for 2 repetitions"):
        join_repetitions([take, take], labels=["a"])


def test_joined_movements_are_labelled_where_their_frames_lie(shared_data: Path) -> None:
    """Real UI-PRMD Vicon repetitions of three movements of subject s06 (deep squat twice,
    shoulder abduction once, hurdle step twice): the frames of each take, found by counting
    frames (the takes' lengths and 0.1 s of blending between), carry its movement's label and
    its knee angles, and the labels change as often as the movement does, twice."""
    folder = shared_data / UIPRMD / "Vicon" / "Positions"
    names = [("m01", 1), ("m01", 2), ("m07", 3), ("m02", 4), ("m02", 5)]
    reps = [read_uiprmd_vicon(folder / f"{m}_s06_e{e:02d}_positions.txt.gz") for m, e in names]
    joined = join_repetitions(reps, labels=[m for m, _ in names])
    assert joined.labels is not None
    labels = joined.labels
    n_blend = int(round(0.1 * reps[0].fps))
    assert len(labels) == joined.seq.n_frames == sum(r.n_frames for r in reps) + 4 * n_blend
    assert int(np.sum(labels[1:] != labels[:-1])) == 2
    at = 0
    for i, (rep, (movement, _)) in enumerate(zip(reps, names, strict=True)):
        if i:
            at += n_blend
        piece = joined.seq.positions[at : at + rep.n_frames]
        assert set(labels[at : at + rep.n_frames].tolist()) == {movement}
        np.testing.assert_allclose(
            _knee_angle(piece), _knee_angle(rep.to_canonical().positions), atol=1e-9
        )
        at += rep.n_frames
    assert at == joined.seq.n_frames


@pytest.mark.parametrize(
    ("sensor", "movement", "subject", "episodes"),
    [
        ("Kinect", "m01", "s06", (3, 1, 7, 9, 2)),  # deep squat
        ("Kinect", "m07", "s08", (2, 4, 6, 8, 10, 1, 5)),  # shoulder abduction
        ("Vicon", "m05", "s07", (10, 2, 4, 6)),  # sit to stand
        ("Vicon", "m02", "s05", (1, 3, 5, 7, 9, 2, 4, 6, 8)),  # hurdle step, one leg
    ],
)
def test_joined_uiprmd_repetitions_count_exactly(
    shared_data: Path, sensor: str, movement: str, subject: str, episodes: tuple[int, ...]
) -> None:
    """Held-out subjects' single repetitions, one file each, played one after the other."""
    folder = shared_data / UIPRMD / sensor / "Positions"
    read = read_uiprmd_kinect if sensor == "Kinect" else read_uiprmd_vicon
    reps = [read(folder / f"{movement}_{subject}_e{e:02d}_positions.txt.gz") for e in episodes]
    result = count_repetitions(join_repetitions(reps).seq)
    assert result.count == len(episodes)
    assert not result.alternating


@pytest.mark.parametrize(
    ("action", "folder", "actor", "takes"),
    [
        ("squat1Reps", "10", "bk", (17, 19, 21, 18, 13)),
        ("rotateArmsBothBackward1Reps", "8", "bd", (1, 2, 3)),
        ("elbowToKnee1RepsLelbowStart", "2", "dg", (13, 14, 15, 16, 17, 18)),
        # a left kick whose arms and trunk swing to balance: over all angles both sides move
        # about equally, but the legs that carry the side-against-side movement do not, so it
        # does not alternate (counted as alternating, each kick out and back was two)
        ("kickLFront1Reps", "6", "dg", (16, 15, 18, 14, 17, 13)),
    ],
)
def test_joined_hdm05_repetitions_count_exactly(
    shared_data: Path, action: str, folder: str, actor: str, takes: tuple[int, ...]
) -> None:
    """HDM05 one-repetition takes of one actor, joined."""
    base = shared_data / "hdm05" / "train" / folder
    asf = base / f"HDM_{actor}.asf"
    reps = [read_asf_amc(asf, base / f"HDM_{actor}_{action}_{t:03d}_120.amc") for t in takes]
    assert count_repetitions(join_repetitions(reps).seq).count == len(takes)


# ---- a turn of the upper arm about its own axis ---------------------------------------------


def _elbow_bent(turn_deg: float, side: str = "right") -> dict[str, np.ndarray]:
    """Standing, the ``side`` upper arm hanging, the elbow bent 90 degrees with the forearm
    ahead (+z), then the upper arm turned out by ``turn_deg`` about its own (vertical) axis:
    the wrist 0.25 m from the elbow toward the side by sin(turn), ahead by cos(turn)."""
    body = standing()
    out = 1.0 if side == "left" else -1.0  # the person's left is +x
    a = np.radians(turn_deg)
    body[f"{side}_wrist"] = body[f"{side}_elbow"] + 0.25 * np.array(
        [out * np.sin(a), 0.0, np.cos(a)]
    )
    return body


def test_upper_arm_turn_is_the_sine_of_the_upper_arms_turn() -> None:
    """Elbow bent 90 degrees: sin(turn) for either arm turned outward (mirror twins agree),
    negative turned in; 0 with the forearm ahead and with the arm hanging straight; the
    same for the whole body turned to face another way or leaning forward."""
    frames = [_elbow_bent(t) for t in (0.0, 30.0, 60.0, -45.0)]
    frames += [_elbow_bent(30.0, "left"), standing()]
    seq = to_sequence(*frames)
    got = upper_arm_turn(seq.positions)
    right = np.sin(np.radians([0.0, 30.0, 60.0, -45.0, 0.0, 0.0]))
    np.testing.assert_allclose(got[:, 1], right, atol=1e-9)
    np.testing.assert_allclose(got[4, 0], 0.5, atol=1e-9)
    turned = to_sequence(
        *[rotate(f, tuple(f), rot_y(70.0) @ rot_x(20.0), np.zeros(3)) for f in frames]
    )
    np.testing.assert_allclose(upper_arm_turn(turned.positions), got, atol=1e-9)


def test_upper_arm_turn_is_missing_with_the_upper_arm_up_along_the_trunk() -> None:
    """An arm raised straight overhead has no frame swung from hanging: NaN, not a number."""
    body = standing()
    body["right_elbow"] = body["right_shoulder"] + np.array([0.0, 0.30, 0.0])
    body["right_wrist"] = body["right_elbow"] + np.array([0.0, 0.0, 0.25])
    got = upper_arm_turn(to_sequence(body).positions)
    assert np.isnan(got[0, 1])
    assert np.isfinite(got[0, 0])


def test_shoulder_turns_with_the_elbow_bent_count() -> None:
    """Seven turns of the right upper arm out by 70 degrees and back (1.5 s each, a little
    rest), elbow bent 90 degrees: no joint angle changes, seven repetitions."""
    cycle = [70.0 * 0.5 * (1 - np.cos(2 * np.pi * i / 45)) for i in range(45)] + [0.0] * 10
    seq = to_sequence(*[_elbow_bent(t) for t in cycle * 7], fps=FPS)
    result = count_repetitions(seq)
    assert result.count == 7
    assert result.moving[0] == "right_upper_arm_turn"


def test_periodic_share_is_the_autocorrelation_at_the_period() -> None:
    """A sine over whole periods recurs exactly one period later: its lagged products there
    average its variance, so the share is the lag's overlap weight 1 - T/n; white noise
    shares nothing (|share| within a few standard errors of 0, 1/sqrt(n))."""
    n, period = 600, 60
    t = np.arange(n)
    rng = np.random.default_rng(3)
    x = np.stack([np.sin(2 * np.pi * t / period), rng.normal(0, 1, n)], axis=1)
    share = periodic_share(x, period / FPS, FPS)
    assert share[0] == pytest.approx(1 - period / n, abs=1e-9)
    assert share[1] <= 4 / np.sqrt(n)
    np.testing.assert_array_equal(periodic_share(x, None, FPS), [1.0, 1.0])


def test_a_small_periodic_movement_is_counted_against_larger_jitter() -> None:
    """Eight leg raises moving the right hip by 0.35 rad, beside four angles that jitter
    (random walks of about the same range, as Kinect's joints do at rest): eight."""
    rng = np.random.default_rng(5)
    hip = np.pi - 0.175 * (1 - np.cos(2 * np.pi * np.arange(8 * 60) / 60))
    walks = np.cumsum(rng.normal(0, 0.02, (len(hip), 4)), axis=0)
    names = ("right_hip", "left_elbow", "right_elbow", "left_armpit", "right_armpit")
    values = np.column_stack([hip, np.pi + walks[:, :2], walks[:, 2:]])
    result = count_in_signals(_signals(values, names), len(hip), FPS)
    assert result.count == 8


@pytest.mark.parametrize(
    ("sensor", "subject", "episodes"),
    [("Kinect", "s06", (1, 3, 5, 7, 9, 2)), ("Vicon", "s07", (2, 4, 6, 8, 10))],
)
def test_joined_shoulder_rotations_count_exactly(
    shared_data: Path, sensor: str, subject: str, episodes: tuple[int, ...]
) -> None:
    """UI-PRMD m09 (shoulder internal and external rotation), held-out subjects: the upper
    arm turns about its own axis with the elbow bent."""
    folder = shared_data / UIPRMD / sensor / "Positions"
    read = read_uiprmd_kinect if sensor == "Kinect" else read_uiprmd_vicon
    reps = [read(folder / f"m09_{subject}_e{e:02d}_positions.txt.gz") for e in episodes]
    assert count_repetitions(join_repetitions(reps).seq).count == len(episodes)


def _turn_and_open(turn_deg: float, elbow_deg: float) -> dict[str, np.ndarray]:
    """Standing, the right upper arm hanging and turned out by ``turn_deg`` about its own
    (vertical) axis, the elbow at ``elbow_deg`` (90 = forearm level, more = opened toward
    straight, the forearm pointing down)."""
    body = standing()
    a, e = np.radians(turn_deg), np.radians(elbow_deg)
    level = np.array([-np.sin(a), 0.0, np.cos(a)])  # ahead, turned toward the person's right
    body["right_wrist"] = body["right_elbow"] + 0.25 * (
        np.sin(e) * level + np.cos(e) * np.array([0.0, 1.0, 0.0])
    )
    return body


def test_shoulder_turns_whose_elbow_opens_count_from_rest() -> None:
    """Seven turns of the right upper arm out by 70 degrees and back (1.5 s each, 0.5 s of
    rest before, between and after), the elbow opening from 80 to 110 degrees as the arm
    turns out: the far posture is nearer standing at ease (elbow straighter) than rest, but
    the movement is the arm's turn, which ease cannot place; rest is where the clip starts
    and ends. Seven, each far point in the middle of its turn."""
    rise = 44
    bump = 0.5 * (1 - np.cos(2 * np.pi * np.arange(rise) / rise))
    share = np.concatenate(
        [np.zeros(15), *[np.concatenate([bump, np.zeros(15)]) for _ in range(7)]]
    )
    frames = [_turn_and_open(70.0 * s, 80.0 + 30.0 * s) for s in share]
    seq = to_sequence(*frames, fps=FPS)
    assert joint_angle(
        seq.positions[:, JOINT_INDEX["right_shoulder"]],
        seq.positions[:, JOINT_INDEX["right_elbow"]],
        seq.positions[:, JOINT_INDEX["right_wrist"]],
    )[[0, 15 + rise // 2]] == pytest.approx(np.radians([80.0, 110.0]))
    result = count_repetitions(seq)
    assert result.count == 7
    assert result.moving[0] == "right_upper_arm_turn"
    designed = 15 + np.arange(7) * (rise + 15) + rise // 2
    peaks = np.array([r.peak_frame for r in result.repetitions])
    assert np.all(np.abs(peaks - designed) <= 3)


def test_a_kick_answered_by_the_other_arm_is_not_one_repetition_per_side() -> None:
    """Six kicks of the left leg (hip up by 1.4 rad, knee bent by 1.0 rad, 0.6 s, every 2 s),
    the right arm swinging forward as the leg comes down (armpit 1.2 rad, elbow 0.8 rad, 0.6 s
    from 0.23 s after each kick starts): the two sides do different things, so there is no
    one repetition per side, and six kicks."""
    k, cycle, width, lag = 6, 60, 18, 7

    def bumps(start: int) -> np.ndarray:
        out = np.zeros(15 + k * cycle)
        bump = 0.5 * (1 - np.cos(2 * np.pi * np.arange(width) / width))
        for i in range(k):
            out[15 + i * cycle + start : 15 + i * cycle + start + width] = bump
        return out

    kick, arm = bumps(0), bumps(lag)
    still = np.full_like(kick, np.pi)
    names = ("left_hip", "left_knee", "right_hip", "right_knee")
    names += ("left_armpit", "right_armpit", "left_elbow", "right_elbow")
    values = np.column_stack(
        [np.pi - 1.4 * kick, np.pi - 1.0 * kick, still, still]
        + [np.zeros_like(kick), 1.2 * arm, still, np.pi - 0.8 * arm]
    )
    result = count_in_signals(_signals(values, names), len(kick), FPS)
    assert not result.alternating
    assert result.count == k
