"""Synthetic stick figures with hand-set geometry for fluent tests.

The person stands facing +z (toward the viewer) in a right-handed frame with y up, so the
person's left is +x. Proportions (metres): shoulders ±0.20 at 1.50, hips ±0.15 at 1.00,
ears ±0.08 at 1.65 (mid-ear 0.15 above the neck: one head-length = 0.30 m).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from features.poses import PoseSequence
from features.skeleton import BLAZEPOSE_33, JOINT_INDEX


def standing() -> dict[str, np.ndarray]:
    """Upright, arms hanging straight down, legs straight, looking ahead."""
    p = {
        "nose": (0.0, 1.63, 0.10),
        "left_eye_inner": (0.015, 1.67, 0.09),
        "left_eye": (0.03, 1.67, 0.08),
        "left_eye_outer": (0.045, 1.67, 0.07),
        "right_eye_inner": (-0.015, 1.67, 0.09),
        "right_eye": (-0.03, 1.67, 0.08),
        "right_eye_outer": (-0.045, 1.67, 0.07),
        "left_ear": (0.08, 1.65, 0.0),
        "right_ear": (-0.08, 1.65, 0.0),
        "mouth_left": (0.03, 1.58, 0.09),
        "mouth_right": (-0.03, 1.58, 0.09),
        "left_shoulder": (0.20, 1.50, 0.0),
        "right_shoulder": (-0.20, 1.50, 0.0),
        "left_elbow": (0.20, 1.20, 0.0),
        "right_elbow": (-0.20, 1.20, 0.0),
        "left_wrist": (0.20, 0.95, 0.0),
        "right_wrist": (-0.20, 0.95, 0.0),
        "left_pinky": (0.21, 0.87, 0.0),
        "right_pinky": (-0.21, 0.87, 0.0),
        "left_index": (0.20, 0.86, 0.02),
        "right_index": (-0.20, 0.86, 0.02),
        "left_thumb": (0.19, 0.90, 0.03),
        "right_thumb": (-0.19, 0.90, 0.03),
        "left_hip": (0.15, 1.00, 0.0),
        "right_hip": (-0.15, 1.00, 0.0),
        "left_knee": (0.15, 0.55, 0.0),
        "right_knee": (-0.15, 0.55, 0.0),
        "left_ankle": (0.15, 0.10, 0.0),
        "right_ankle": (-0.15, 0.10, 0.0),
        "left_heel": (0.15, 0.05, -0.05),
        "right_heel": (-0.15, 0.05, -0.05),
        "left_foot_index": (0.15, 0.02, 0.15),
        "right_foot_index": (-0.15, 0.02, 0.15),
    }
    return {k: np.array(v, dtype=float) for k, v in p.items()}


def rot_y(deg: float) -> np.ndarray:
    """Rotation about the vertical axis; positive turns the person (facing +z) to their left."""
    a = np.radians(deg)
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def rot_x(deg: float) -> np.ndarray:
    """Rotation about the person's left-right axis; positive pitches the top forward (+z)."""
    a = np.radians(deg)
    return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])


def rot_z(deg: float) -> np.ndarray:
    """Rotation about the forward axis; positive moves the top toward the person's left (+x)."""
    a = np.radians(deg)
    return np.array([[np.cos(a), np.sin(a), 0], [-np.sin(a), np.cos(a), 0], [0, 0, 1]])


HEAD = ("nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye",
        "right_eye_outer", "left_ear", "right_ear", "mouth_left", "mouth_right")  # fmt: skip
UPPER_BODY = HEAD + tuple(
    f"{s}_{j}" for s in ("left", "right")
    for j in ("shoulder", "elbow", "wrist", "pinky", "index", "thumb")
)  # fmt: skip


def rotate(body: dict[str, np.ndarray], joints: tuple[str, ...], r: np.ndarray,
           about: np.ndarray) -> dict[str, np.ndarray]:  # fmt: skip
    out = dict(body)
    for j in joints:
        out[j] = r @ (body[j] - about) + about
    return out


def to_sequence(*frames: dict[str, np.ndarray], fps: float = 30.0) -> PoseSequence:
    """Pose sequence ``(len(frames), 33, 3)`` from joint dictionaries (missing joints NaN)."""
    pos = np.full((len(frames), len(BLAZEPOSE_33), 3), np.nan)
    for f, body in enumerate(frames):
        for name, xyz in body.items():
            pos[f, JOINT_INDEX[name]] = xyz
    return PoseSequence(pos, BLAZEPOSE_33, fps, source="synthetic")


def squat_pose(
    depth: float, lean_deg: float = 40.0, arms_deg: float = 0.0
) -> dict[str, np.ndarray]:
    """A squat at ``depth`` in [0, 1] of the way down: feet planted, the shins tip 35 degrees
    forward and the thighs reach 95 degrees from vertical at depth 1, the torso leans
    ``lean_deg`` forward over the hips; ``arms_deg`` raises both straight arms forward.

    The knee angle is the angle between the thigh and the shin at the knee: standing, 180
    degrees; at depth ``a`` it is ``180 - 35 a - 95 a`` degrees (shin forward, thigh back)."""
    b = standing()
    out = dict(b)
    shin, thigh = np.radians(35 * depth), np.radians(95 * depth)
    for side in ("left", "right"):
        knee = b[f"{side}_ankle"] + 0.45 * np.array([0.0, np.cos(shin), np.sin(shin)])
        out[f"{side}_knee"] = knee
        out[f"{side}_hip"] = knee + 0.45 * np.array([0.0, np.cos(thigh), -np.sin(thigh)])
    arms = tuple(f"{s}_{j}" for s in ("left", "right")
                 for j in ("elbow", "wrist", "pinky", "index", "thumb"))  # fmt: skip
    for side in ("left", "right"):
        out = rotate(out, tuple(a for a in arms if a.startswith(side)), rot_x(-arms_deg),
                     b[f"{side}_shoulder"])  # fmt: skip
    mid_old = 0.5 * (b["left_hip"] + b["right_hip"])
    mid_new = 0.5 * (out["left_hip"] + out["right_hip"])
    upper = UPPER_BODY
    return {j: (rot_x(lean_deg * depth) @ (out[j] - mid_old) + mid_new if j in upper else p)
            for j, p in out.items()}  # fmt: skip


def squat_clip(
    depth: float,
    frames: int = 45,
    lean_deg: float = 40.0,
    arms_deg: float = 0.0,
    source: str = "synthetic squat",
) -> PoseSequence:
    """One squat repetition down to ``depth`` and back up over ``frames`` frames (30 fps)."""
    phase = 0.5 * (1.0 - np.cos(np.linspace(0.0, 2.0 * np.pi, frames)))
    seq = to_sequence(*[squat_pose(depth * a, lean_deg, arms_deg) for a in phase])
    return replace(seq, source=source)
