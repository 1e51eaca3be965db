"""A library of synthetic movements whose geometry is set by hand (tests.bodies): what each
does is known by construction, so every fluent and QMP phrase can be checked against bodies
that do and do not do what it says.

Each movement is a function of time (seconds) returning a body; :func:`clip` samples it at
30 fps. Repetitions follow :func:`phase` (0 at rest, 1 at the far point).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from features.poses import PoseSequence
from tests.bodies import (
    UPPER_BODY,
    rot_x,
    rot_y,
    rot_z,
    rotate,
    squat_pose,
    standing,
    to_sequence,
)

Body = dict[str, np.ndarray]


def phase(t: float, period: float) -> float:
    """0 at rest, 1 at the far point of the movement, smoothly (one repetition per period)."""
    return float(0.5 * (1.0 - np.cos(2.0 * np.pi * t / period)))


def arm(side: str) -> tuple[str, ...]:
    return tuple(f"{side}_{j}" for j in ("elbow", "wrist", "pinky", "index", "thumb"))


def forearm(side: str) -> tuple[str, ...]:
    return tuple(f"{side}_{j}" for j in ("wrist", "pinky", "index", "thumb"))


def leg(side: str) -> tuple[str, ...]:
    return tuple(f"{side}_{j}" for j in ("knee", "ankle", "heel", "foot_index"))


def shin(side: str) -> tuple[str, ...]:
    return tuple(f"{side}_{j}" for j in ("ankle", "heel", "foot_index"))


def _out(side: str, deg: float) -> np.ndarray:
    """Rotation that swings a limb of ``side`` out to that side by ``deg`` (frontal plane)."""
    return rot_z(-deg if side == "left" else deg)


def still(t: float) -> Body:
    """Standing upright, arms hanging straight, not moving."""
    return standing()


def squat(t: float) -> Body:
    """Deep squats (knees to 50 degrees), arms hanging, 2.5 s per repetition."""
    return squat_pose(phase(t, 2.5), lean_deg=40.0)


def squat_arms_forward(t: float) -> Body:
    """Deep squats with both straight arms held forward at shoulder height."""
    return squat_pose(phase(t, 2.5), lean_deg=40.0, arms_deg=90.0)


def knee_lift(t: float) -> Body:
    """The right thigh lifts to horizontal in front while the knee bends to a right angle
    (a hurdle step), the left leg stands straight, 2.5 s per repetition."""
    b, a = standing(), phase(t, 2.5)
    b = rotate(b, leg("right"), rot_x(-90 * a), b["right_hip"])
    return rotate(b, shin("right"), rot_x(90 * a), b["right_knee"])


def straight_leg_raise(t: float) -> Body:
    """The straight right leg lifts 60 degrees in front, the left leg stands, 3 s per rep."""
    b, a = standing(), phase(t, 3.0)
    return rotate(b, leg("right"), rot_x(-60 * a), b["right_hip"])


def kick(t: float) -> Body:
    """The right leg swings up 70 degrees in front with the knee bent on the way and
    straight at the top (a front kick), the left leg stands, 1.5 s per repetition."""
    b, a = standing(), phase(t, 1.5)
    b = rotate(b, leg("right"), rot_x(-70 * a), b["right_hip"])
    bend = 60.0 * np.sin(np.pi * a)  # bent half way up, straight at the top and at rest
    return rotate(b, shin("right"), rot_x(bend), b["right_knee"])


def side_step(t: float) -> Body:
    """The straight right leg held out 35 degrees to the side (a wide stance), still."""
    b = standing()
    return rotate(b, leg("right"), _out("right", 35.0), b["right_hip"])


def leg_out_and_in(t: float) -> Body:
    """Both straight legs swing out 20 degrees to the sides and back, 2 s per repetition."""
    b, a = standing(), phase(t, 2.0)
    for side in ("left", "right"):
        b = rotate(b, leg(side), _out(side, 20.0 * a), b[f"{side}_hip"])
    return b


def lunge(t: float) -> Body:
    """A split stance, still: the right thigh 40 degrees in front, the left 30 behind."""
    b = standing()
    b = rotate(b, leg("right"), rot_x(-40.0), b["right_hip"])
    return rotate(b, leg("left"), rot_x(30.0), b["left_hip"])


def arm_abduction(t: float) -> Body:
    """The straight right arm swings up sideways to 150 degrees and back (shoulder
    abduction), the left arm hangs still, 3 s per repetition."""
    b, a = standing(), phase(t, 3.0)
    return rotate(b, arm("right"), _out("right", 150.0 * a), b["right_shoulder"])


def arm_flexion(t: float) -> Body:
    """The straight right arm swings up in front to 150 degrees and back, 3 s per rep."""
    b, a = standing(), phase(t, 3.0)
    return rotate(b, arm("right"), rot_x(-150.0 * a), b["right_shoulder"])


def arms_overhead(t: float) -> Body:
    """Both straight arms held straight up, still."""
    b = standing()
    for side in ("left", "right"):
        b = rotate(b, arm(side), _out(side, 175.0), b[f"{side}_shoulder"])
    return b


def arm_extension(t: float) -> Body:
    """The straight right arm swings 50 degrees backward and returns, 3 s per repetition."""
    b, a = standing(), phase(t, 3.0)
    return rotate(b, arm("right"), rot_x(50.0 * a), b["right_shoulder"])


def elbows_bent(t: float) -> Body:
    """Upper arms hanging, both elbows held bent at a right angle (forearms forward), still."""
    b = standing()
    for side in ("left", "right"):
        b = rotate(b, forearm(side), rot_x(-90.0), b[f"{side}_elbow"])
    return b


def torso_bend(t: float) -> Body:
    """Bending forward 80 degrees at the hips with straight legs and back, 4 s per rep."""
    b, a = standing(), phase(t, 4.0)
    mid = 0.5 * (b["left_hip"] + b["right_hip"])
    return rotate(b, UPPER_BODY, rot_x(80.0 * a), mid)


def jog(t: float) -> Body:
    """Thighs swinging 30 degrees forward and back in turn (anti-phase), knees bending as
    they swing forward, elbows held bent, 1 s per stride."""
    b = elbows_bent(t)
    swing = np.sin(2.0 * np.pi * t / 1.0)
    for side, sign in (("left", 1.0), ("right", -1.0)):
        deg = 30.0 * sign * swing
        b = rotate(b, leg(side), rot_x(-deg), b[f"{side}_hip"])
        b = rotate(b, shin(side), rot_x(max(deg, 0.0) * 1.5), b[f"{side}_knee"])
    return b


def jumping_jack(t: float) -> Body:
    """Arms swing up sideways to 150 degrees while the legs open 20 degrees, 1 s per rep."""
    b, a = standing(), phase(t, 1.0)
    for side in ("left", "right"):
        b = rotate(b, arm(side), _out(side, 150.0 * a), b[f"{side}_shoulder"])
        b = rotate(b, leg(side), _out(side, 20.0 * a), b[f"{side}_hip"])
    return b


def squat_hold(t: float) -> Body:
    """Held at the bottom of a deep squat (knees at 180 - 130 x 0.9 = 63 degrees), still."""
    return squat_pose(0.9, lean_deg=40.0)


def arm_out_elbow_bent(t: float) -> Body:
    """The right upper arm held out sideways at shoulder height, the elbow bent at a right
    angle with the forearm pointing forward, still (a shoulder rotation's start)."""
    b = standing()
    b = rotate(b, arm("right"), _out("right", 90.0), b["right_shoulder"])
    return rotate(b, forearm("right"), rot_y(90.0), b["right_elbow"])


def push_up(t: float) -> Body:
    """Plank facing down with straight arms under the shoulders; the body lowers 25 cm while
    the hands stay put and the elbows bend out to the sides, 2 s per repetition."""
    b = standing()
    for side in ("left", "right"):
        b = rotate(b, arm(side), rot_x(-90), b[f"{side}_shoulder"])  # arms straight ahead
    b = rotate(b, tuple(b), rot_x(90), np.array([0.0, 0.1, 0.0]))  # tip over: face down
    hands = {f"{s}_{j}" for s in ("left", "right") for j in ("wrist", "pinky", "index", "thumb")}
    drop = np.array([0.0, 0.25 * phase(t, 2.0), 0.0])
    out = {j: (p if j in hands else p - drop) for j, p in b.items()}
    upper, fore = 0.30, 0.25  # the standing body's arm links
    for side, out_x in (("left", 1.0), ("right", -1.0)):
        sh, wr = out[f"{side}_shoulder"], out[f"{side}_wrist"]
        dist = float(np.linalg.norm(wr - sh))
        along = (upper**2 - fore**2 + dist**2) / (2 * dist)  # elbow: two-link triangle
        aside = np.sqrt(max(upper**2 - along**2, 0.0))
        out[f"{side}_elbow"] = sh + along * (wr - sh) / dist + aside * np.array([out_x, 0, 0])
    return out


def lean_back(t: float) -> Body:
    """Leaning the straight body back 60 degrees at the hips and up again, 4 s per rep."""
    b, a = standing(), phase(t, 4.0)
    mid = 0.5 * (b["left_hip"] + b["right_hip"])
    return rotate(b, UPPER_BODY, rot_x(-60.0 * a), mid)


def left_kick(t: float) -> Body:
    """The kick with the left leg (the mirror image of :func:`kick`: x negated, sides
    swapped)."""
    b = kick(t)
    out = {}
    for j, p in b.items():
        other = j.replace("left", "\0").replace("right", "left").replace("\0", "right")
        out[other] = p * np.array([-1.0, 1.0, 1.0])
    return out


def reach(t: float) -> Body:
    """The right arm lifts 80 degrees in front while its elbow straightens from a right angle
    (reaching out) and back, the left arm hangs still, 3 s per repetition."""
    b, a = standing(), phase(t, 3.0)
    b = rotate(b, forearm("right"), rot_x(-90.0 * (1.0 - a)), b["right_elbow"])
    return rotate(b, arm("right"), rot_x(-80.0 * a), b["right_shoulder"])


def throw(t: float) -> Body:
    """Both arms lift 120 degrees in front together while both elbows bend and straighten
    (a two-handed throw), 2 s per repetition."""
    b, a = standing(), phase(t, 2.0)
    bend = 90.0 * np.sin(np.pi * a)
    for side in ("left", "right"):
        b = rotate(b, forearm(side), rot_x(-bend), b[f"{side}_elbow"])
        b = rotate(b, arm(side), rot_x(-120.0 * a), b[f"{side}_shoulder"])
    return b


MOVES: dict[str, Callable[[float], Body]] = {
    f.__name__: f
    for f in (still, squat, squat_arms_forward, knee_lift, straight_leg_raise, kick, side_step,
              leg_out_and_in, lunge, arm_abduction, arm_flexion, arms_overhead, arm_extension,
              elbows_bent, torso_bend, jog, jumping_jack, squat_hold, arm_out_elbow_bent,
              push_up, lean_back, left_kick, reach, throw)
}  # fmt: skip


def clip(name: str, seconds: float = 7.5, fps: float = 30.0) -> PoseSequence:
    """Movement ``name`` sampled over ``seconds`` at ``fps``."""
    move = MOVES[name]
    seq = to_sequence(*[move(i / fps) for i in range(int(seconds * fps))], fps=fps)
    return seq.with_metadata(movement=name)
