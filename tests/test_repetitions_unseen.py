"""Repetition counts with a joint missing (NaN) in every frame of a clip, as a pose model
that never finds a joint leaves it: each joint of the skeleton in turn, over the real clips
whose counts are known (CMU subject 13's stretches counted by hand,
tests/fixtures/repetition_counts.json, and UI-PRMD and HDM05 single repetitions joined one
after the other, whose count is the number joined, as tests/test_repetitions_exact.py joins
them), and over signals built with a known count."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.joining import join_repetitions
from features.poses import PoseSequence
from features.readers.asfamc import read_asf_amc
from features.readers.uiprmd import read_uiprmd_kinect, read_uiprmd_vicon
from features.repetitions import (
    COUNTED_ANGLES,
    MovementSignals,
    count_in_signals,
    count_repetitions,
    counted_angles,
)
from features.skeleton import BLAZEPOSE_33, JOINT_INDEX
from tests.bodies import rot_x, rot_z, rotate, standing, to_sequence

FIXTURE = Path(__file__).parent / "fixtures" / "repetition_counts.json"
UIPRMD = Path("ui-prmd") / "data" / "Segmented Movements"
FPS = 30.0
TORSO = ("left_shoulder", "right_shoulder", "left_hip", "right_hip")
LIMBS = tuple(f"{s}_{j}" for j in ("elbow", "wrist", "knee", "ankle") for s in ("left", "right"))
"""The limb joints the counted angles rest on besides the torso (features.repetitions:
elbow, knee, armpit and hip angles, the upper arm's turn, the hips' height above the
ankles)."""
OTHERS = tuple(j for j in BLAZEPOSE_33 if j not in TORSO + LIMBS)
ALTERNATING = ("Twist", "Jog", "KneeRaise", "ToeTouchOneHand")
MOVING_MIDDLE = {
    "UI-PRMD Kinect m07 s08": "right_elbow",
    "UI-PRMD Vicon m02 s05": "right_knee",
    "UI-PRMD Kinect m09 s06": "right_elbow",
    "UI-PRMD Vicon m09 s07": "left_elbow",
}
"""The middle joint of the one limb that moves in each of these clips, as their angles with
nothing missing show (the shoulder abduction m07: the right armpit spans 139 degrees, the left
1; the hurdle step m02: the right knee 100, the left 4; the shoulder rotations m09: the
right, and in s07 the left, upper arm's turn 77 and 103, the other 4)."""
"""The fixture's alternating exercises (its rule: one repetition per side)."""
JOINED = (
    ("Kinect", "m01", "s06", (3, 1, 7, 9, 2)),
    ("Kinect", "m07", "s08", (2, 4, 6, 8, 10, 1, 5)),
    ("Vicon", "m05", "s07", (10, 2, 4, 6)),
    ("Vicon", "m02", "s05", (1, 3, 5, 7, 9, 2, 4, 6, 8)),
    ("Kinect", "m09", "s06", (1, 3, 5, 7, 9, 2)),
    ("Vicon", "m09", "s07", (2, 4, 6, 8, 10)),
)
"""UI-PRMD held-out subjects' single repetitions, as tests/test_repetitions_exact.py joins
them."""
HDM05 = (
    ("squat1Reps", "10", "bk", (17, 19, 21, 18, 13)),
    ("rotateArmsBothBackward1Reps", "8", "bd", (1, 2, 3)),
    ("elbowToKnee1RepsLelbowStart", "2", "dg", (13, 14, 15, 16, 17, 18)),
    ("kickLFront1Reps", "6", "dg", (16, 15, 18, 14, 17, 13)),
)


@dataclasses.dataclass(frozen=True)
class Known:
    name: str
    seq: PoseSequence
    count: int
    activity: str = ""


def _mocap(shared_data: Path) -> list[Known]:
    clips = json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
    read: dict[str, PoseSequence] = {}
    out = []
    for c in clips:
        if not c["source"].endswith(".amc"):
            continue
        if c["source"] not in read:
            read[c["source"]] = read_asf_amc(shared_data / c["asf"], shared_data / c["source"])
        seq = read[c["source"]].slice_frames(c["start_frame"], c["end_frame"])
        name = f"{Path(c['source']).stem} {c['activity']} {c['start_frame']}"
        out.append(Known(name, seq, c["count"], c["activity"]))
    return out


def _joined(shared_data: Path) -> list[Known]:
    out = []
    for sensor, movement, subject, episodes in JOINED:
        folder = shared_data / UIPRMD / sensor / "Positions"
        read = read_uiprmd_kinect if sensor == "Kinect" else read_uiprmd_vicon
        reps = [read(folder / f"{movement}_{subject}_e{e:02d}_positions.txt.gz") for e in episodes]
        seq = join_repetitions(reps).seq
        out.append(Known(f"UI-PRMD {sensor} {movement} {subject}", seq, len(episodes)))
    for action, folder, actor, takes in HDM05:
        base = shared_data / "hdm05" / "train" / folder
        asf = base / f"HDM_{actor}.asf"
        reps = [read_asf_amc(asf, base / f"HDM_{actor}_{action}_{t:03d}_120.amc") for t in takes]
        out.append(Known(f"HDM05 {action} {actor}", join_repetitions(reps).seq, len(takes)))
    return out


# on one xdist worker: the module's known made once, not once per worker
pytestmark = pytest.mark.xdist_group("repetitions_unseen")


@pytest.fixture(scope="module")
def known(shared_data: Path) -> list[Known]:
    return _mocap(shared_data) + _joined(shared_data)


def unseen(seq: PoseSequence, joints: tuple[str, ...]) -> list[PoseSequence]:
    """``seq`` on the canonical skeleton once per joint of ``joints``, that joint missing (NaN)
    in every frame: all copies made at once, ``(len(joints), frames, 33, 3)``."""
    canonical = seq.to_canonical()
    mask = np.zeros((len(joints), len(BLAZEPOSE_33)), dtype=bool)
    mask[np.arange(len(joints)), [JOINT_INDEX[j] for j in joints]] = True
    positions = np.where(mask[:, None, :, None], np.nan, canonical.positions[None])
    return [dataclasses.replace(canonical, positions=p) for p in positions]


def test_each_joint_unseen_throughout_real_clips(known: list[Known]) -> None:
    """Every clip, each joint missing in every frame in turn.

    - a shoulder or a hip: no torso, no body frame, the clip is refused (no person);
    - all the joints no counted angle rests on (face, hands, feet) at once: the count is the
      one with nothing missing;
    - each limb joint (elbow, wrist, knee, ankle): the count is the known one in more of the
      224 cases than before (192; 198; 200; now 205). What one side does against the other is
      read only
      where both sides are seen: an angle whose twin is unseen (the left elbow missing: the
      right elbow, armpit and upper-arm turn) counted as a limb on one side moving while the
      other stood by, and the twists and jogs no longer alternated (a twist's three turns
      counted 2, 13_31's seven jogging steps 2 with the left elbow missing). Now each twist
      counts its hand count and each jog alternates with any arm joint missing. The moving
      limb's own middle joint missing (:data:`MOVING_MIDDLE`) took every angle that moved
      away, though the limb's root and end were seen: UI-PRMD's one-arm abduction and
      shoulder rotations with that arm's elbow counted 0, the hurdle step with the stepping
      knee 5 of 9. The limb is now read along its line from root to end
      (:data:`features.repetitions.LIMB_LINES`): each counts its known count. Those still
      wrong: the shoulder rotation with the wrist missing (0: only the forearm turns, and
      nothing seen shows it), the arm circles with a wrist (13_31: 4 of 5, by hand uncertain
      by one) or an elbow (13_29's left: 5 of 6, 13_31's right: 4 of 5; 6 and 5 before: a
      line has no end nearer ease, and the far points are read half a circle on), and the
      jogs, whose fading last steps lose height with the angles of one limb gone (13_30: 7-8
      of 9 with an arm joint, 10 with a leg joint, as with none missing; 13_31: 6 of 7 with an
      arm joint, 2-3 with an ankle: the knee's angle is gone, and an untwinned angle is
      what both sides do alike).

      A knee missing is placed where its hinge puts it (features.repetitions._placed_knees):
      the knee raises and jogs count as with nothing missing and alternate (13_31's knee
      raises counted 3 of 4 before and its jog 2 of 7, not alternating: the line from hip to
      ankle stood in for the hip alone, and hardly turns with the heel drawn up under the
      hip), and the kick with its knee counts 6 (7 before: the knee's bend and the line's
      swing were two far points a kick)."""
    hits, cases = 0, 0
    for clip in known:
        whole = count_repetitions(clip.seq)
        for seq in unseen(clip.seq, TORSO):
            with pytest.raises(DataError, match="shows no torso"):
                count_repetitions(seq)
        canonical = clip.seq.to_canonical()
        positions = canonical.positions.copy()
        positions[:, [JOINT_INDEX[j] for j in OTHERS]] = np.nan
        others = dataclasses.replace(canonical, positions=positions)
        assert count_repetitions(others).count == whole.count, clip.name
        for joint, seq in zip(LIMBS, unseen(clip.seq, LIMBS), strict=True):
            result = count_repetitions(seq)
            hits += result.count == clip.count
            cases += 1
            if clip.activity == "Twist":
                assert result.count == clip.count, (clip.name, joint)
                sides = [r.side for r in result.repetitions]
                assert all(a != b for a, b in zip(sides, sides[1:], strict=False)), sides
            if clip.activity == "Jog" and joint.endswith(("elbow", "wrist")):
                assert result.alternating, (clip.name, joint)
            if clip.activity in ("KneeRaise", "Jog") and joint.endswith("knee"):
                assert (result.count, result.alternating) == (whole.count, True), (clip.name, joint)
            if MOVING_MIDDLE.get(clip.name) == joint:
                assert result.count == clip.count, (clip.name, joint, result.count)
    assert cases == 224
    assert hits > 200, hits


def test_a_one_arm_raise_with_its_elbow_unseen_is_read_along_the_arm() -> None:
    """The right arm, straight, raised sideways to the horizontal and lowered five times
    (44 frames up and down at 30 fps, 15 hanging between; the figure of tests/bodies.py),
    the rest of the body still, the right elbow missing in every frame: the right armpit's,
    elbow's and upper-arm turn's angles rest on it, and nothing else moves. The arm's line,
    shoulder to wrist against shoulder to hip, the hip 0.05 m in from the shoulder and 0.5 m
    below it: atan(0.05 / 0.5) = 5.71 degrees hanging, 90 + 5.71 raised; the lines of the
    limbs whose middle joint is seen take no part. Before, no counted angle moved: 0
    repetitions."""
    body = standing()
    del body["right_elbow"]
    raise_deg = 45.0 * (1 - np.cos(2 * np.pi * np.arange(44) / 44))
    degrees = np.concatenate([np.zeros(15), *[np.concatenate([raise_deg, np.zeros(15)])] * 5])
    arm = ("right_wrist", "right_pinky", "right_index", "right_thumb")
    seq = to_sequence(
        *(rotate(body, arm, rot_z(d), body["right_shoulder"]) for d in degrees)
    )  # fmt: skip
    angles = counted_angles(seq)
    column = {n: np.degrees(angles[:, i]) for i, n in enumerate(COUNTED_ANGLES)}
    lean = np.degrees(np.arctan(0.05 / 0.5))
    raised = 15 + 22 + 59 * np.arange(5)
    np.testing.assert_allclose(column["right_arm_line"][raised], 90 + lean, atol=1e-6)
    np.testing.assert_allclose(column["right_arm_line"][degrees == 0], lean, atol=1e-6)
    for name in ("right_armpit", "right_elbow", "left_arm_line", "left_leg_line"):
        assert np.isnan(column[name]).all(), name
    result = count_repetitions(seq)
    assert result.count == 5
    assert [r.peak_frame for r in result.repetitions] == list(raised)
    assert result.moving[0] == "right_arm_line"


def test_no_limb_line_with_every_joint_seen() -> None:
    """With the elbows and knees seen, each limb's own angles are read and its line takes no
    part (a line counted beside them would weigh the limb twice)."""
    seq = to_sequence(*[standing()] * 30)
    angles = counted_angles(seq)
    for name in ("left_arm_line", "right_arm_line", "left_leg_line", "right_leg_line"):
        assert np.isnan(angles[:, COUNTED_ANGLES.index(name)]).all(), name
    assert np.isfinite(angles[:, COUNTED_ANGLES.index("right_armpit")]).all()


def _bend(n: int, depth: float) -> np.ndarray:
    """An angle straight (pi) at rest bending by ``depth`` radians and back over ``n``
    samples (one cosine cycle)."""
    return np.pi - 0.5 * depth * (1 - np.cos(2 * np.pi * np.arange(n) / n))


def test_steps_alternate_with_one_arms_joint_unseen() -> None:
    """Knees bending in turn, left, right, three times each (1.2 rad), the right arm swinging
    forward (its armpit opening, its elbow bending by 1 rad) with each left step, as in a
    jog; the left arm's angles are missing (its elbow unseen): six steps, sides in turn.
    Before, the right arm's angles, whose left twins are missing, counted on the right side
    alone, so the left and right limbs did not seem to move about equally: 3 repetitions,
    not alternating."""
    still = np.full(40, np.pi)
    left = np.concatenate([_bend(40, 1.2), still] * 3)
    right = np.concatenate([still, _bend(40, 1.2)] * 3)
    swing = np.concatenate([_bend(40, 1.0), still] * 3)
    names = ("left_knee", "right_knee", "right_elbow", "right_armpit")
    values = np.stack([left, right, swing, np.pi - swing], axis=1)
    result = count_in_signals(MovementSignals(values, names, FPS, 1), len(left), FPS)
    assert result.alternating
    assert result.count == 6
    assert [r.side for r in result.repetitions] == ["left", "right"] * 3
    assert [r.peak_frame for r in result.repetitions] == [20, 60, 100, 140, 180, 220]


def test_a_real_lunge_with_a_knee_unseen_is_one_repetition(lunge_poses: PoseSequence) -> None:
    """The reverse-lunge video (one slow lunge by hand; a side view that never shows the right
    arm) with the left knee missing in every frame: the left knee and hip angles are gone,
    the right knee's and hip's have no twin, and no limb is seen on both sides; the trunk's
    twist, which the pose model reads from the depth of a side view, wobbles by 25 degrees.
    Before, that wobble alone was taken for the left and right turns of an alternating
    movement: 5 repetitions. One, not alternating."""
    hand = next(
        c for c in json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
        if c["source"].endswith("fit_reverse_lunge_pexels8233047.mp4")
    )  # fmt: skip
    (without_knee,) = unseen(lunge_poses, ("left_knee",))
    result = count_repetitions(without_knee)
    assert result.count == hand["count"] == 1
    assert not result.alternating


def _knee_raised(body: dict[str, np.ndarray], side: str, degrees: float) -> dict[str, np.ndarray]:
    """``body`` with ``side``'s thigh raised forward by ``degrees`` about the hip, the shank
    and foot hanging straight down under the knee."""
    hip, knee = body[f"{side}_hip"], body[f"{side}_knee"]
    raised = rot_x(-degrees) @ (knee - hip) + hip
    out = dict(body)
    for j in ("ankle", "heel", "foot_index"):
        out[f"{side}_{j}"] = body[f"{side}_{j}"] - knee + raised
    out[f"{side}_knee"] = raised
    return out


@pytest.mark.parametrize("unseen_as", ["missing", "confidence 0", "faint"])
def test_knee_raises_with_a_knee_unseen_alternate(unseen_as: str) -> None:
    """Knee raises, left then right, three times each (the thigh 0.45 m raised forward to the
    horizontal and back over 30 frames at 30 fps, the shank hanging under the knee; the figure
    of tests/bodies.py), the right knee missing in every frame (NaN, or written as (0, 0, 0)
    with confidence 0 as OpenPose writes a joint it did not see, or guessed where it stands
    at rest, 0.45 m under the hip, with confidence 0.3, as a pose model guesses a joint it
    does not see: "faint"). The right knee is placed
    from the right hip and ankle, with the left leg's thigh and shank (0.45 m each): the
    right knee's angle is 180 degrees less the raise, and the right hip's, between the thigh
    and the line to the shoulder (0.05 m out, 0.5 m up), arccos(-0.5 cos(raise) /
    sqrt(0.05^2 + 0.5^2)); the right leg's line takes no part. Six raises, sides in turn,
    at the top of each (frame 15 + 30 k), as with the knee seen. Before, the right leg was
    read along its line from hip to ankle alone, with no twin: 3 repetitions (the left
    raises), not alternating; faint, the right knee's and hip's angles were missing (below
    the 0.5 that reads a joint as seen) and the knee was not placed: 3, not alternating."""
    body = standing()
    raise_deg = 45.0 * (1 - np.cos(2 * np.pi * np.arange(30) / 30))
    still = np.zeros(30)
    left = np.concatenate([raise_deg, still] * 3)
    right = np.concatenate([still, raise_deg] * 3)
    pairs = zip(left, right, strict=True)
    seq = to_sequence(*(_knee_raised(_knee_raised(body, "left", a), "right", b) for a, b in pairs))
    knee = JOINT_INDEX["right_knee"]
    positions = seq.positions.copy()
    if unseen_as == "missing":
        positions[:, knee] = np.nan
        seq = dataclasses.replace(seq, positions=positions)
    else:
        faint = unseen_as == "faint"
        positions[:, knee] = body["right_knee"] if faint else 0.0
        confidence = np.ones(positions.shape[:2])
        confidence[:, knee] = 0.3 if faint else 0.0
        seq = dataclasses.replace(seq, positions=positions, confidence=confidence)
    angles = counted_angles(seq)
    column = {n: np.degrees(angles[:, i]) for i, n in enumerate(COUNTED_ANGLES)}
    np.testing.assert_allclose(column["right_knee"], 180.0 - right, atol=1e-4)
    hip = np.degrees(np.arccos(-0.5 * np.cos(np.radians(right)) / np.hypot(0.05, 0.5)))
    np.testing.assert_allclose(column["right_hip"], hip, atol=1e-4)
    assert np.isnan(column["right_leg_line"]).all()
    result = count_repetitions(seq)
    assert result.alternating
    assert [r.peak_frame for r in result.repetitions] == [15 + 30 * k for k in range(6)]
    assert [r.side for r in result.repetitions] == ["left", "right"] * 3


def test_a_still_straight_leg_whose_length_wobbles_is_placed_straight() -> None:
    """A body standing still for 6 s at 30 fps (the figure of tests/bodies.py: thigh and shank
    0.45 m), its legs' length wobbling as a pose model's does from frame to frame: the left
    ankle, heel and toes 0.03 sin(2 pi t / 1.5 s) m lower, the right ones as much higher, so
    the left shank is 0.45 + that long and the right hip-ankle distance 0.9 less that; the
    right knee missing in every frame. The seen leg's length has a median absolute deviation
    of 0.03 sin(pi / 4) = 0.0212 m over whole periods, twice the standard deviation it
    estimates (x 1.4826) is 0.063 m, more than the 0.03 m the right leg ever falls short of
    the thigh and shank's 0.9 m: the placed right knee is straight (180 degrees) in every
    frame, and nothing repeats (the mean height of the ankles, the hips' height above them,
    stays put). Before, the 0.03 m were read as a bend of arccos((2 0.45^2 - 0.87^2) /
    (2 0.45^2)) = 150.3 degrees at the knee every 1.5 s: 4 repetitions of a body standing
    still."""
    body = standing()
    del body["right_knee"]
    t = np.arange(180) / FPS
    wobble = 0.03 * np.sin(2 * np.pi * t / 1.5)
    feet = ("ankle", "heel", "foot_index")

    def frame(d: float) -> dict[str, np.ndarray]:
        out = dict(body)
        for j in feet:
            out[f"left_{j}"] = body[f"left_{j}"] - np.array([0.0, d, 0.0])
            out[f"right_{j}"] = body[f"right_{j}"] + np.array([0.0, d, 0.0])
        return out

    seq = to_sequence(*(frame(d) for d in wobble))
    knee = np.degrees(counted_angles(seq)[:, COUNTED_ANGLES.index("right_knee")])
    np.testing.assert_allclose(knee, 180.0, atol=1e-6)
    assert count_repetitions(seq).count == 0


def test_a_knee_missing_in_most_frames_is_placed_in_every_one() -> None:
    """A body standing still for 6 s at 30 fps (the figure of tests/bodies.py), its right knee
    seen in the first second of every three, 0.08 m ahead of where it stands (as a pose model
    may see it, a little bent: thigh and shank sqrt(0.45^2 + 0.08^2) = 0.457 m, the knee's
    angle 180 - 2 atan(0.08 / 0.45) = 159.8 degrees), and missing in the rest. The left leg is
    straight, 0.45 m a bone; the medians over both legs (the left's 180 frames against the
    right's 60) are 0.45 and the legs' length has no spread, so the knee's hinge, 0.9 m from
    hip to ankle, puts the knee straight: 180 degrees, in every frame, the seen ones too
    (missing in most frames, the knee is read from its hinge alone); nothing repeats. Placed
    only where missing, the knee stepped from 159.8 to 180 degrees and back every 3 s: 2
    repetitions of a body standing still."""
    body = standing()
    body["right_knee"] = body["right_knee"] + np.array([0.0, 0.0, 0.08])
    gone = dict(body)
    del gone["right_knee"]
    missing = np.arange(180) % 90 >= 30
    seq = to_sequence(*(gone if m else body for m in missing))
    knee = np.degrees(counted_angles(seq)[:, COUNTED_ANGLES.index("right_knee")])
    np.testing.assert_allclose(knee, 180.0, atol=1e-6)
    assert count_repetitions(seq).count == 0


def test_a_knee_seen_in_most_frames_is_placed_where_missing() -> None:
    """12 s standing still, then knee raises, left then right, three times each (as in
    test_knee_raises_with_a_knee_unseen_alternate: 30 frames up and down, 30 still, at 30
    fps), the right knee missing through the raises only, as when a person turns for one
    exercise of a recording: seen in two thirds of the frames. Where missing it is placed
    from the right hip and ankle (thigh and shank 0.45 m, as seen): the right knee's angle is
    180 degrees less the raise there, and the six raises alternate, at the top of each (frame
    360 + 15 + 30 k). Left out where missing (the knee read from one source, the pose model's,
    where seen in most frames), the right knee's and hip's angles were gone through the
    raises: 3 repetitions, not alternating (a recording's jog with a knee missing through it
    counted 1 of 7)."""
    body = standing()
    raise_deg = 45.0 * (1 - np.cos(2 * np.pi * np.arange(30) / 30))
    still = np.zeros(30)
    left = np.concatenate([np.zeros(360), *[np.concatenate([raise_deg, still])] * 3])
    right = np.concatenate([np.zeros(360), *[np.concatenate([still, raise_deg])] * 3])
    pairs = zip(left, right, strict=True)
    seq = to_sequence(*(_knee_raised(_knee_raised(body, "left", a), "right", b) for a, b in pairs))
    positions = seq.positions.copy()
    positions[360:, JOINT_INDEX["right_knee"]] = np.nan
    seq = dataclasses.replace(seq, positions=positions)
    knee = np.degrees(counted_angles(seq)[:, COUNTED_ANGLES.index("right_knee")])
    np.testing.assert_allclose(knee, 180.0 - right, atol=1e-4)
    result = count_repetitions(seq)
    assert result.alternating
    assert [r.peak_frame for r in result.repetitions] == [375 + 30 * k for k in range(6)]
    assert [r.side for r in result.repetitions] == ["left", "right"] * 3
