"""Session 53, task G: a clip whose hips are out of view (a patient filmed seated or close up)
has its arms and head stated in the frame of its shoulders and the world's up, where every
fluent that needs the body frame was unavailable; what needs the hips stays unavailable."""

from __future__ import annotations

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.segmentation import solve_recording
from features.fluents import evaluate
from features.poses import PoseSequence
from features.signals import ANGLE_SIGNALS, state_signals
from features.skeleton import JOINT_INDEX
from tests.bodies import UPPER_BODY, rot_y, rotate, standing, to_sequence
from tests.test_cbr_clips import ACTIVITIES, arm_clip

BELOW_THE_WAIST = tuple(
    f"{side}_{part}"
    for side in ("left", "right")
    for part in ("hip", "knee", "ankle", "heel", "foot_index")
)

SHOULDER = np.array([0.20, 1.50, 0.0])


def _arms_up_without_hips(turn: float) -> dict[str, np.ndarray]:
    """The stick figure of :func:`tests.bodies.standing` from the shoulders up, turned
    ``turn`` degrees to its left about the vertical: the left upper arm raised 135 degrees
    from straight down in the frontal plane (up and out to the side), the right one 120
    degrees in the sagittal plane (forward, 30 degrees above the horizontal), both elbows
    straight (0.30 m upper arms, 0.25 m forearms)."""
    body = {j: xyz for j, xyz in standing().items() if j in UPPER_BODY}
    up_out = np.array([np.sin(np.radians(135)), -np.cos(np.radians(135)), 0.0])
    forward_up = np.array([0.0, np.sin(np.radians(30)), np.cos(np.radians(30))])
    right = SHOULDER * [-1, 1, 1]
    body["left_elbow"] = SHOULDER + 0.30 * up_out
    body["left_wrist"] = SHOULDER + 0.55 * up_out
    body["right_elbow"] = right + 0.30 * forward_up
    body["right_wrist"] = right + 0.55 * forward_up
    return rotate(body, tuple(body), rot_y(turn), np.zeros(3))


@pytest.mark.parametrize("backend", ["numba", "numpy"])
@pytest.mark.parametrize("turn", [0.0, 40.0])
def test_arm_angles_of_a_pose_without_hips(backend: str, turn: float) -> None:
    """Worked out by hand from the pose: the armpit angle is the upper arm's angle from
    straight down (135 and 120 degrees), the left arm 45 degrees from the outward axis in the
    frontal plane, the right 30 degrees from the forward axis in the sagittal plane, the
    elbows straight, the head neither twisted (the nose 90 degrees from the left shoulder
    about the neck) nor tilted sideways (the mid-ear straight above the neck, 90 degrees from
    the left axis); turned 40 degrees, the same (the frame follows the shoulders). Every angle
    that needs a hip stays unavailable. On main's code every body-frame angle was NaN."""
    seq = to_sequence(*[_arms_up_without_hips(turn)] * 3)
    got = dict(zip(ANGLE_SIGNALS, np.degrees(state_signals(seq, backend).values[0]), strict=False))
    want = {
        "left_armpit": 135.0,
        "right_armpit": 120.0,
        "left_upper_arm_frontal": 45.0,
        "right_upper_arm_sagittal": 30.0,
        "left_elbow": 180.0,
        "right_elbow": 180.0,
        "neck_transverse": 90.0,
        "neck_frontal": 90.0,
    }
    for name, deg in want.items():
        assert got[name] == pytest.approx(deg, abs=1e-6), name
    hips = [n for n in ANGLE_SIGNALS if "leg" in n or "knee" in n or "torso" in n or "_hip" in n]
    assert len(hips) == 11 and all(np.isnan(got[n]) for n in hips)
    from features.signals import HIPLESS  # the angles the module says it states

    assert set(want) - {"left_elbow", "right_elbow"} <= set(HIPLESS)


def test_fluents_of_a_pose_without_hips() -> None:
    """The states of that pose with their confidences, from the paper's table: 135 and 120
    degrees lie above the arm's raised boundary's 10pi/16 (raised 1, lowered 0); 45 degrees
    below the outward boundary's 6pi/16 (outward 1, inward 0), 30 degrees below the in-front
    one (in front 1, behind 0). The legs, the hips' angles and the trunk's tilts and twist
    are unavailable (NaN) in every frame, not stated."""
    res = evaluate(to_sequence(*[_arms_up_without_hips(0.0)] * 3), backend="numpy")
    ones = ("left_arm_raised.raised", "right_arm_raised.raised", "left_arm_outward.outward",
            "right_arm_in_front.in_front", "left_arm_bent.straight")  # fmt: skip
    zeros = ("left_arm_raised.lowered", "left_arm_outward.inward", "right_arm_in_front.behind")
    for name in ones:
        assert res.column(name)[1] == pytest.approx(1.0, abs=1e-9), name
    for name in zeros:
        assert res.column(name)[1] == pytest.approx(0.0, abs=1e-9), name
    for family in ("leg_bent", "leg_raised", "leg_in_front", "leg_outward", "torso_tilted",
                   "torso_twisted"):  # fmt: skip
        cols = [i for i, n in enumerate(res.state_names) if family in n.split(".")[0]]
        assert cols and np.isnan(res.confidence[:, cols]).all(), family


def test_a_recording_without_hips_is_segmented_from_its_arms(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
) -> None:
    """Four left-arm raises out to the side, then four raises of both arms forward (the
    synthetic arm movements of the case base, whole bodies), with the hips and legs missing
    in every frame: every window of the recording that lies within one of the two movements
    is solved as that movement, from the arms, and says it was judged on them. On main's
    code the recording was refused ("shows no torso: nothing to segment")."""
    clf, _, _ = arm_k3
    rng = np.random.default_rng(11)
    clips = [arm_clip(ACTIVITIES[0], rng) for _ in range(4)]
    clips += [arm_clip(ACTIVITIES[2], rng) for _ in range(4)]
    p = np.concatenate([c.positions for c in clips])
    p[:, [JOINT_INDEX[j] for j in BELOW_THE_WAIST]] = np.nan
    change = sum(c.n_frames for c in clips[:4])
    windows = solve_recording(clf, PoseSequence(p, clips[0].joint_names, 30.0)).windows
    classes = [str(c) for c in clf.classes_]
    within = [w for w in windows if w.stop <= change or w.start >= change]
    assert len(within) >= 10
    for w in within:
        truth = ACTIVITIES[0] if w.stop <= change else ACTIVITIES[2]
        assert classes[int(np.argmax(w.vote))] == truth, (w.start, w.stop)
    assert all(w.solved.arms_alone for w in windows)
