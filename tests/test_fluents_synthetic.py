"""Fluents on synthetic bodies with hand-set geometry: every state means what its words say."""

from __future__ import annotations

import math

import numpy as np
import pytest

from features.fluents import evaluate, state_signals
from tests.bodies import (
    UPPER_BODY,
    rot_x,
    rot_y,
    rot_z,
    rotate,
    standing,
    to_sequence,
)

PI = math.pi


def conf(body: dict[str, np.ndarray]) -> dict[str, float]:
    result = evaluate(to_sequence(body))
    return dict(zip(result.state_names, result.confidence[0], strict=True))


def signal(body: dict[str, np.ndarray], name: str) -> float:
    return float(state_signals(to_sequence(body)).column(name)[0])


def test_standing_reads_upright_straight_and_lowered() -> None:
    c = conf(standing())
    for side in ("left", "right"):
        assert c[f"{side}_arm_bent.straight"] > 0.99
        assert c[f"{side}_leg_bent.straight"] > 0.99
        assert c[f"{side}_arm_raised.lowered"] > 0.99
        assert c[f"{side}_leg_raised.lowered"] > 0.99
        assert c[f"{side}_arm_in_front.centered"] > 0.99
        assert c[f"{side}_arm_outward.at_side"] > 0.99
        assert c[f"{side}_leg_outward.at_side"] > 0.99
    assert c["head_tilted_forward.upright"] > 0.99
    assert c["torso_tilted_forward.upright"] > 0.99
    assert c["head_twisted.centered"] > 0.99
    assert c["torso_twisted.centered"] > 0.99


def test_hand_computed_angles_of_standing_body() -> None:
    body = standing()
    # Elbow: shoulder, elbow, wrist collinear -> pi. Armpit: arm straight down, shoulder->hip
    # vector (-0.05, -0.5, 0): angle = atan(0.05 / 0.5).
    assert signal(body, "left_elbow") == pytest.approx(PI)
    assert signal(body, "left_armpit") == pytest.approx(math.atan2(0.05, 0.5))
    # Hip: knee straight below, shoulder at (+0.05, +0.5): pi - atan(0.05/0.5).
    assert signal(body, "left_hip") == pytest.approx(PI - math.atan2(0.05, 0.5))
    assert signal(body, "left_upper_arm_sagittal") == pytest.approx(PI / 2)


def test_t_pose_arms_outward_and_chest_level() -> None:
    body = standing()
    for side, x in (("left", 1.0), ("right", -1.0)):
        body[f"{side}_elbow"] = np.array([0.50 * x, 1.50, 0.0])
        body[f"{side}_wrist"] = np.array([0.75 * x, 1.50, 0.0])
        body[f"{side}_index"] = np.array([0.85 * x, 1.50, 0.0])
    c = conf(body)
    for side in ("left", "right"):
        assert c[f"{side}_arm_outward.outward"] > 0.999
        assert c[f"{side}_arm_bent.straight"] > 0.999
        assert c[f"{side}_arm_raised.chest_level"] > 0.9
    # armpit angle by hand: (1,0,0) against (-0.05,-0.5,0) -> pi/2 + atan(0.05/0.5)
    assert signal(body, "left_armpit") == pytest.approx(PI / 2 + math.atan2(0.05, 0.5))


def test_arms_straight_up_raised() -> None:
    body = standing()
    for side, x in (("left", 0.20), ("right", -0.20)):
        body[f"{side}_elbow"] = np.array([x, 1.80, 0.0])
        body[f"{side}_wrist"] = np.array([x, 2.05, 0.0])
    c = conf(body)
    assert c["left_arm_raised.raised"] > 0.999
    assert c["right_arm_raised.raised"] > 0.999
    assert c["left_arm_in_front.centered"] > 0.99  # straight up is neither in front nor behind


def test_arm_forward_in_front_and_arm_back_behind() -> None:
    body = standing()
    body["left_elbow"] = np.array([0.20, 1.50, 0.30])
    body["left_wrist"] = np.array([0.20, 1.50, 0.55])
    body["right_elbow"] = np.array([-0.20, 1.30, -0.20])  # 45 degrees behind
    c = conf(body)
    assert c["left_arm_in_front.in_front"] > 0.999
    assert c["right_arm_in_front.behind"] > 0.999
    assert signal(body, "right_upper_arm_sagittal") == pytest.approx(3 * PI / 4)


def test_arm_across_body_inward() -> None:
    body = standing()
    body["left_elbow"] = np.array([-0.05, 1.35, 0.05])  # upper arm points to the right side
    c = conf(body)
    assert c["left_arm_outward.inward"] > 0.99


def test_squat_knees_bent_thighs_in_front() -> None:
    body = standing()
    for side, x in (("left", 0.15), ("right", -0.15)):
        body[f"{side}_knee"] = np.array([x, 0.55, 0.45])
        body[f"{side}_ankle"] = np.array([x, 0.10, 0.35])
    c = conf(body)
    for side in ("left", "right"):
        assert c[f"{side}_leg_bent.bent"] > 0.999
        assert c[f"{side}_leg_in_front.in_front"] > 0.999
    # knee angle by hand: K->H (0, 0.45, -0.45), K->A (0, -0.45, -0.10)
    u, v = np.array([0, 0.45, -0.45]), np.array([0, -0.45, -0.10])
    expected = math.acos(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)))
    assert signal(body, "left_knee") == pytest.approx(expected)


def test_leg_raised_forward_and_leg_outward() -> None:
    body = standing()
    body["left_knee"] = np.array([0.15, 1.00, 0.45])  # thigh horizontal, forward
    body["left_ankle"] = np.array([0.15, 0.55, 0.45])
    s45 = 0.45 * math.sin(PI / 4)
    body["right_knee"] = np.array([-0.15 - s45, 1.0 - s45, 0.0])  # right leg 45 deg outward
    body["right_ankle"] = np.array([-0.15 - 2 * s45, 1.0 - 2 * s45, 0.0])
    c = conf(body)
    assert c["left_leg_raised.raised"] > 0.999
    assert c["left_leg_in_front.in_front"] > 0.999
    assert c["right_leg_outward.outward"] > 0.999
    # the hip angle is not projected, so a leg lifted 45 degrees sideways is raised too:
    # knee direction (-sin 45, -cos 45) against shoulder direction (-0.05, 0.5)
    u, v = np.array([-s45, -s45, 0]), np.array([-0.05, 0.5, 0])
    assert signal(body, "right_hip") == pytest.approx(
        math.acos(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)))
    )
    assert c["right_leg_raised.raised"] > 0.999
    assert signal(body, "right_upper_leg_frontal") == pytest.approx(PI / 4)


def test_head_turned_left_reads_head_twisted_left() -> None:
    body = rotate(standing(), ("nose", "left_eye", "right_eye", "mouth_left", "mouth_right"),
                  rot_y(45), np.array([0.0, 1.5, 0.0]))  # fmt: skip
    c = conf(body)
    assert c["head_twisted.twisted_left"] > 0.999
    body = rotate(standing(), ("nose",), rot_y(-45), np.array([0.0, 1.5, 0.0]))
    assert conf(body)["head_twisted.twisted_right"] > 0.999


def test_shoulders_turned_left_over_fixed_hips_read_torso_twisted_left() -> None:
    body = rotate(standing(), UPPER_BODY, rot_y(30), np.array([0.0, 1.0, 0.0]))
    c = conf(body)
    assert c["torso_twisted.twisted_left"] > 0.999
    # the angle by hand: mid-hip -> left hip is +x, forward is (sin 30, 0, cos 30) -> 60 deg
    assert signal(body, "torso_transverse") == pytest.approx(PI / 3)
    body = rotate(standing(), UPPER_BODY, rot_y(-30), np.array([0.0, 1.0, 0.0]))
    assert conf(body)["torso_twisted.twisted_right"] > 0.999


def test_head_tilts_forward_and_left() -> None:
    neck = np.array([0.0, 1.5, 0.0])
    fwd = conf(rotate(standing(), ("left_ear", "right_ear", "nose"), rot_x(30), neck))
    assert fwd["head_tilted_forward.tilted_forward"] > 0.999
    assert fwd["head_tilted_forward.upright"] < 0.01
    left = conf(rotate(standing(), ("left_ear", "right_ear", "nose"), rot_z(30), neck))
    assert left["head_tilted_left.tilted_left"] > 0.999
    right = conf(rotate(standing(), ("left_ear", "right_ear", "nose"), rot_z(-30), neck))
    assert right["head_tilted_left.tilted_right"] > 0.999
    back = conf(rotate(standing(), ("left_ear", "right_ear", "nose"), rot_x(-30), neck))
    assert back["head_tilted_forward.tilted_backward"] > 0.999


def test_bending_forward_at_hips_tilts_torso_not_head() -> None:
    hips = np.array([0.0, 1.0, 0.0])
    body = rotate(standing(), UPPER_BODY, rot_x(45), hips)
    c = conf(body)
    assert c["torso_tilted_forward.tilted_forward"] > 0.999
    assert c["head_tilted_forward.upright"] > 0.99  # the head moved with the torso
    assert signal(body, "torso_sagittal") == pytest.approx(PI / 4)
    lean_left = conf(rotate(standing(), UPPER_BODY, rot_z(30), hips))
    assert lean_left["torso_tilted_left.tilted_left"] > 0.999


def test_left_and_right_are_not_swapped_when_the_person_turns_around() -> None:
    # Facing -z: the whole body turned 180 degrees. Raising the person's left arm sideways must
    # still read "left arm outward" although it is now on the viewer's left (-x).
    body = standing()
    body["left_elbow"] = np.array([0.50, 1.50, 0.0])
    body["left_wrist"] = np.array([0.75, 1.50, 0.0])
    turned = rotate(body, tuple(body), rot_y(180), np.zeros(3))
    assert turned["left_elbow"][0] < 0
    c = conf(turned)
    assert c["left_arm_outward.outward"] > 0.999
    assert c["right_arm_outward.at_side"] > 0.99


def test_hand_touching_nose_is_near_and_touching() -> None:
    body = standing()
    body["right_index"] = body["nose"] + np.array([0.0, 0.0, 0.05])
    c = conf(body)
    assert c["near:right_index~nose.near"] > 0.999
    assert c["near:right_index~nose.touching"] == 1.0
    assert c["near:left_index~nose.far_from"] > 0.999
    assert c["near:left_index~nose.touching"] == 0.0
    sig = state_signals(to_sequence(body))
    # 0.05 m over one head-length of 2 * 0.15 m
    assert sig.column("right_index~nose")[0] == pytest.approx(0.05 / 0.30)


def test_confidences_of_two_state_fluents_sum_to_one_and_three_state_use_middle_rule() -> None:
    rng = np.random.default_rng(0)
    frames = []
    for _ in range(20):
        body = standing()
        for j in body:
            body[j] = body[j] + rng.normal(0, 0.08, 3)
        frames.append(body)
    result = evaluate(to_sequence(*frames))
    c = dict(zip(result.state_names, result.confidence.T, strict=True))
    for side in ("left", "right"):
        np.testing.assert_allclose(c[f"{side}_arm_bent.bent"] + c[f"{side}_arm_bent.straight"], 1)
        raised, lowered = c[f"{side}_leg_raised.raised"], c[f"{side}_leg_raised.lowered"]
        np.testing.assert_allclose(raised + lowered, 1)
        lo, mid, hi = (c[f"{side}_arm_outward.{s}"] for s in ("outward", "at_side", "inward"))
        np.testing.assert_allclose(mid, (1 - lo) * (1 - hi))
    # the tilt pair shares one upright state built from both directions (paper, "Tilted")
    f, b = c["head_tilted_forward.tilted_forward"], c["head_tilted_forward.tilted_backward"]
    left, right = c["head_tilted_left.tilted_left"], c["head_tilted_left.tilted_right"]
    np.testing.assert_allclose(
        c["head_tilted_forward.upright"], (1 - f) * (1 - b) * (1 - left) * (1 - right)
    )
    assert "head_tilted_left.upright" not in c


def test_near_pairs_follow_the_paper() -> None:
    from features.signals import near_pairs

    pairs = near_pairs()
    # 4 sources x (23 targets - itself - 2 same-side tautologies) = 80 ordered, minus the 6
    # pairs counted twice among the sources themselves.
    assert len(pairs) == 74
    keys = {frozenset(p) for p in pairs}
    assert frozenset(("left_index", "left_wrist")) not in keys
    assert frozenset(("left_index", "right_wrist")) in keys
    assert frozenset(("right_heel", "right_foot_index")) not in keys
    assert frozenset(("right_heel", "left_foot_index")) in keys
    assert frozenset(("left_heel", "left_knee")) not in keys
