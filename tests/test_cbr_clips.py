"""Helper module (no tests): synthetic labelled clips for the CBR tests, three arm
movements on the hand-set stick figure of ``tests/bodies.py`` (activity known by construction).
"""

from __future__ import annotations

import numpy as np

from features.poses import PoseSequence
from tests.bodies import rot_x, rot_z, rotate, standing, to_sequence

ARM = ("elbow", "wrist", "pinky", "index", "thumb")
ACTIVITIES = ('left arm "raise"', "右腕 raise", "l'avant – both arms")


def arm_clip(activity: str, rng: np.random.Generator, frames: int = 36) -> PoseSequence:
    """One repetition: the arm(s) go up to ~140 degrees and back, with jitter and noise."""
    body = standing()
    peak = rng.uniform(120, 160)
    n = frames + int(rng.integers(-6, 7))
    angles = peak * np.sin(np.linspace(0, np.pi, n)) ** rng.uniform(0.8, 1.5)
    out = []
    for a in angles:
        b = body
        if activity == ACTIVITIES[0]:  # left arm sideways (abduction: -z rotation on the left)
            b = rotate(b, tuple(f"left_{j}" for j in ARM), rot_z(-a), b["left_shoulder"])
        elif activity == ACTIVITIES[1]:
            b = rotate(b, tuple(f"right_{j}" for j in ARM), rot_z(a), b["right_shoulder"])
        else:  # both arms forward (flexion: the hand moves toward +z)
            for s in ("left", "right"):
                b = rotate(b, tuple(f"{s}_{j}" for j in ARM), rot_x(-a), b[f"{s}_shoulder"])
        out.append({k: v + rng.normal(scale=0.005, size=3) for k, v in b.items()})
    return to_sequence(*out).with_metadata(label=activity)


def arm_dataset(n_per_class: int, seed: int) -> tuple[list[PoseSequence], np.ndarray]:
    rng = np.random.default_rng(seed)
    X, y = [], []
    for i in range(n_per_class * len(ACTIVITIES)):
        act = ACTIVITIES[i % len(ACTIVITIES)]
        X.append(arm_clip(act, rng))
        y.append(act)
    return X, np.array(y, dtype=object)
