"""DAD on synthetic people performing the paper's activities, posed from the movements'
descriptions (not from the ADD's thresholds): each is recognised with every QMP met."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from cbr.dad import detect
from tests.bodies import UPPER_BODY, rot_x, rot_z, rotate, standing, to_sequence
from tests.moves import arm, phase, push_up

Body = dict[str, np.ndarray]


def _leg(side: str) -> tuple[str, ...]:
    return tuple(f"{side}_{j}" for j in ("knee", "ankle", "heel", "foot_index"))


def jumping_jack(t: float) -> Body:
    """Arms swing up sideways to 150 degrees while the legs open 20 degrees, 1 rep/s."""
    b, a = standing(), phase(t, 1.0)
    b = rotate(b, arm("left"), rot_z(-150 * a), b["left_shoulder"])
    b = rotate(b, arm("right"), rot_z(150 * a), b["right_shoulder"])
    b = rotate(b, _leg("left"), rot_z(-20 * a), b["left_hip"])
    return rotate(b, _leg("right"), rot_z(20 * a), b["right_hip"])


def single_leg_rdl(t: float) -> Body:
    """Hinge 80 degrees at the right hip; torso and left leg tip as one line, 3 s per rep."""
    b, a = standing(), phase(t, 3.0)
    moving = UPPER_BODY + ("left_hip",) + _leg("left")
    return rotate(b, moving, rot_x(80 * a), b["right_hip"])


def squat(t: float) -> Body:
    """Feet planted; shins tip 35 degrees forward, thighs reach 95 degrees from vertical, the
    torso leans 40 degrees forward over the hips, 2.5 s per rep."""
    b, a = standing(), phase(t, 2.5)
    out = dict(b)
    shin, thigh = np.radians(35 * a), np.radians(95 * a)
    for side in ("left", "right"):
        knee = b[f"{side}_ankle"] + 0.45 * np.array([0.0, np.cos(shin), np.sin(shin)])
        out[f"{side}_knee"] = knee
        out[f"{side}_hip"] = knee + 0.45 * np.array([0.0, np.cos(thigh), -np.sin(thigh)])
    mid_old = 0.5 * (b["left_hip"] + b["right_hip"])
    mid_new = 0.5 * (out["left_hip"] + out["right_hip"])
    for j in UPPER_BODY:
        out[j] = rot_x(40 * a) @ (b[j] - mid_old) + mid_new
    return out


@pytest.mark.parametrize(
    ("pose", "seconds", "activity"),
    [
        (jumping_jack, 4.0, "jumping_jack"),
        (single_leg_rdl, 6.0, "single_leg_romanian_deadlift"),
        (squat, 7.5, "squat"),
        (push_up, 6.0, "push_up"),
    ],
)
def test_synthetic_activity_is_ranked_first_with_every_qmp_met(
    pose: Callable[[float], Body], seconds: float, activity: str
) -> None:
    seq = to_sequence(*[pose(i / 30.0) for i in range(int(seconds * 30))])
    result = detect(seq)
    best = result.activities[0]
    assert best.activity == activity
    assert best.score == 1.0 and all(q.met for q in best.qmps)
    paper = {"squat", "push_up", "jumping_jack", "single_leg_romanian_deadlift"} - {activity}
    others = [a for a in result.activities if a.activity in paper]
    assert all(a.score < 0.5 for a in others)
