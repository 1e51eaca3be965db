"""Every QMP phrase and fluent state says what it computes: each is checked on synthetic
bodies that do what the words say and on bodies that do not (tests.moves: the geometry of
each movement is set by hand, so what it does is known without running the code under test).
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from features.fluents import evaluate
from features.qmp import qmp_features
from features.qmp.add import load_add
from tests.moves import clip

# criterion: (movements that do what its words say, movements that do not)
QMP_PHRASES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    # lower body
    "knee_oscillation": (("squat", "jog"), ("still", "straight_leg_raise", "arm_abduction")),
    "hip_oscillation": (("squat", "torso_bend"), ("still", "knee_lift", "arm_abduction")),
    "knees_in_phase": (("squat",), ("jog", "knee_lift", "still")),
    "consistent_leg_distance": (("still", "squat", "arm_abduction"),
                                ("leg_out_and_in", "jumping_jack", "knee_lift")),
    "squat_depth": (("squat_hold",), ("still", "arm_abduction")),
    "torso_upright": (("still", "squat", "lean_back"), ("torso_bend",)),
    "hips_steady": (("still", "arm_abduction"), ("squat", "torso_bend")),
    "legs_split": (("lunge", "knee_lift"), ("still", "squat")),
    "one_knee_oscillation": (("knee_lift", "kick"), ("squat", "still")),
    "one_hip_flexion": (("knee_lift", "straight_leg_raise", "kick"), ("squat", "still")),
    "knee_lifts_with_hip": (("knee_lift", "squat"), ("straight_leg_raise", "still")),
    "raised_leg_straight": (("straight_leg_raise", "torso_bend"), ("knee_lift", "still")),
    "one_leg_still": (("still", "knee_lift", "arm_abduction"), ("squat", "jog")),
    "legs_steady": (("still", "arm_abduction"), ("squat", "jog", "knee_lift")),
    "legs_wide": (("side_step",), ("still", "squat", "lunge")),
    "legs_out_and_in": (("leg_out_and_in", "jumping_jack"), ("still", "side_step")),
    "hip_hinge_soft_knee": (("straight_leg_raise", "torso_bend"), ("knee_lift", "still")),
    "free_leg_in_line_with_torso": (("still", "arm_abduction"), ("squat", "torso_bend")),
    "torso_tilt_oscillation": (("torso_bend", "squat", "lean_back"), ("still", "arm_abduction")),
    "legs_alternating": (("jog",), ("squat", "still", "leg_out_and_in")),
    # a knee lifting with the hip swings the thigh up in front (the words say thigh, not leg)
    "kick_forward": (("kick", "left_kick", "knee_lift"), ("squat", "torso_bend", "still")),
    # upper body
    "arms_steady": (("still", "squat", "arms_overhead"), ("arm_abduction", "jumping_jack")),
    "arms_overhead": (("arms_overhead",), ("still", "squat_arms_forward")),
    "arms_below_shoulders": (("still", "squat_arms_forward"), ("arms_overhead",)),
    "arm_raise_oscillation": (("arm_abduction", "arm_flexion"), ("still", "arms_overhead")),
    "other_arm_still": (("arm_abduction", "reach"), ("jumping_jack", "still")),
    "arm_in_frontal_plane": (("arm_abduction", "arm_extension"), ("arm_flexion", "still")),
    "arm_in_scapular_plane": (("arm_flexion", "reach"), ("arm_abduction", "still")),
    "arm_extension_backward": (("arm_extension",), ("arm_flexion", "still")),
    "arm_out_elbow_bent": (("arm_out_elbow_bent",), ("elbows_bent", "still")),
    "arms_raised_both_in_phase": (("jumping_jack", "throw"), ("arm_abduction", "still")),
    "arms_in_phase_with_legs": (("jumping_jack",), ("arm_abduction", "leg_out_and_in")),
    "shoulder_translation_synchronised": (("push_up", "throw"), ("still", "arm_abduction")),
    "torso_horizontal": (("push_up",), ("still", "torso_bend")),
    "body_straight": (("still", "push_up"), ("squat", "torso_bend")),
    "arms_swinging": (("push_up", "throw"), ("still", "arm_abduction")),
    "arm_reaching_high": (("arm_abduction", "arm_flexion"), ("still", "arms_overhead")),
    # HDM05 actions
    "torso_bends_forward": (("torso_bend", "push_up"), ("still", "squat", "lean_back")),
    "arms_low": (("still", "squat"), ("arms_overhead", "squat_arms_forward")),
    "torso_lies_back": (("lean_back",), ("still", "torso_bend")),
    "right_knee_lifts": (("knee_lift", "straight_leg_raise", "kick"), ("squat", "left_kick")),
    "left_elbow_bent": (("elbows_bent",), ("still",)),
    "left_leg_kicks_front": (("left_kick",), ("kick", "still")),
    "right_arm_reaches": (("reach",), ("still", "arm_abduction")),
    "both_arms_throw": (("throw",), ("jumping_jack", "still")),
    "elbows_bent": (("elbows_bent", "jog"), ("still",)),
    "arms_hanging_straight": (("still", "arms_overhead", "squat_arms_forward"),
                              ("arm_abduction", "elbows_bent")),
}  # fmt: skip


@cache
def _detected(move: str) -> dict[str, bool]:
    q = qmp_features(clip(move))
    return dict(zip(q.criteria, (bool(b) for b in q.binary), strict=True))


def test_every_qmp_phrase_is_checked() -> None:
    assert set(QMP_PHRASES) == set(load_add().criteria)


@pytest.mark.parametrize("criterion", sorted(QMP_PHRASES))
def test_qmp_phrase_holds_on_bodies_that_do_it_and_not_on_others(criterion: str) -> None:
    words = load_add().criteria[criterion].words
    does, does_not = QMP_PHRASES[criterion]
    for move in does:
        assert _detected(move)[criterion], f"{move} does {words!r} but it is not detected"
    for move in does_not:
        assert not _detected(move)[criterion], f"{move} does not {words!r} but it is detected"


# fluent state (machine name): (movements that hold it for most of the clip, movements that
# hold it for none of it)
FLUENT_STATES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "right_arm_bent.bent": (("elbows_bent",), ("still", "arms_overhead")),
    "right_arm_bent.straight": (("still", "arms_overhead"), ("elbows_bent",)),
    "right_leg_bent.bent": (("squat_hold",), ("still", "side_step")),
    "right_leg_bent.straight": (("still", "side_step"), ("squat_hold",)),
    "right_arm_raised.lowered": (("still", "elbows_bent"), ("arms_overhead",)),
    "right_arm_raised.raised": (("arms_overhead",), ("still",)),
    "right_arm_raised.chest_level": (("arm_out_elbow_bent",), ("still", "arms_overhead")),
    "right_leg_raised.lowered": (("still", "elbows_bent"), ("squat_hold", "side_step")),
    # the hip angle is not projected: a thigh lifted in front or out to the side is raised
    "right_leg_raised.raised": (("squat_hold", "side_step"), ("still",)),
    "right_leg_in_front.in_front": (("squat_hold", "lunge"), ("still",)),
    "left_leg_in_front.behind": (("lunge",), ("still", "squat_hold")),
    "right_leg_in_front.centered": (("still",), ("squat_hold", "lunge")),
    "right_leg_outward.outward": (("side_step",), ("still",)),
    "right_leg_outward.at_side": (("still",), ("side_step",)),
    "right_arm_outward.outward": (("arm_out_elbow_bent",), ("still",)),
    "right_arm_outward.at_side": (("still",), ("arm_out_elbow_bent",)),
    "torso_tilted_forward.upright": (("still", "side_step"), ("squat_hold",)),
    "torso_tilted_forward.tilted_forward": (("squat_hold",), ("still",)),
    "right_leg_bent.bend_steady": (("still", "squat_hold"), ()),
    "torso_tilted_forward.tilt_steady": (("still", "side_step"), ()),
}  # fmt: skip


@cache
def _held(move: str) -> dict[str, float]:
    """The share of the clip each fluent state holds with confidence >= 0.5."""
    res = evaluate(clip(move, seconds=2.0))
    held = np.nanmean(res.confidence >= 0.5, axis=0)
    return dict(zip(res.state_names, held.tolist(), strict=True))


@pytest.mark.parametrize("state", sorted(FLUENT_STATES))
def test_fluent_state_holds_on_postures_that_show_it_and_not_on_others(state: str) -> None:
    does, does_not = FLUENT_STATES[state]
    for move in does:
        assert _held(move)[state] > 0.9, f"{move} shows {state} but it holds too little"
    for move in does_not:
        assert _held(move)[state] < 0.1, f"{move} does not show {state} but it holds"
