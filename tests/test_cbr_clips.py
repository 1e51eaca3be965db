"""Synthetic labelled clips for the CBR tests: three arm movements on the hand-set stick figure
of ``tests/bodies.py`` (activity known by construction), and tests that each clip moves as its
label says, checked by hand geometry (the angle of the upper arm from straight down).
"""

from __future__ import annotations

import numpy as np
import pytest

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


# --- the helper's clips are what their labels say ---------------------------------------------

DOWN = np.array([0.0, -1.0, 0.0])


def _upper_arm(seq: PoseSequence, side: str) -> tuple[np.ndarray, np.ndarray]:
    """Per frame: the angle (degrees) of shoulder -> elbow from straight down, and that vector."""
    arm = seq.joint(f"{side}_elbow") - seq.joint(f"{side}_shoulder")
    unit = arm / np.linalg.norm(arm, axis=1, keepdims=True)
    return np.degrees(np.arccos(np.clip(unit @ DOWN, -1.0, 1.0))), unit


@pytest.mark.parametrize(
    ("activity", "moving", "direction"),
    [
        (ACTIVITIES[0], ("left",), np.array([1.0, 0.0, 0.0])),  # the person's left is +x
        (ACTIVITIES[1], ("right",), np.array([-1.0, 0.0, 0.0])),
        (ACTIVITIES[2], ("left", "right"), np.array([0.0, 0.0, 1.0])),  # facing +z
    ],
)
def test_arm_clip_moves_the_arms_its_label_names(
    activity: str, moving: tuple[str, ...], direction: np.ndarray
) -> None:
    rng = np.random.default_rng(7)
    for _ in range(5):
        seq = arm_clip(activity, rng)
        assert seq.label == activity
        assert 30 <= seq.n_frames <= 42  # 36 frames, give or take 6
        for side in ("left", "right"):
            angle, unit = _upper_arm(seq, side)
            assert angle[0] < 8 and angle[-1] < 8  # hanging at the start and the end
            if side not in moving:
                assert angle.max() < 8  # the other arm stays down
                continue
            peak = int(np.argmax(angle))
            assert 115 < angle[peak] < 165  # up to 120-160 degrees, 5 mm joint noise
            assert 0 < peak < seq.n_frames - 1
            # lifted in the named direction: sideways (abduction) or forward (flexion)
            horizontal = unit[peak] - (unit[peak] @ DOWN) * DOWN
            horizontal /= np.linalg.norm(horizontal)
            assert horizontal @ direction > 0.95


def test_arm_dataset_is_balanced_and_reproducible() -> None:
    X, y = arm_dataset(4, seed=3)
    assert len(X) == len(y) == 12
    assert {a: int((y == a).sum()) for a in ACTIVITIES} == {a: 4 for a in ACTIVITIES}
    assert [s.label for s in X] == list(y)
    again, _ = arm_dataset(4, seed=3)
    other, _ = arm_dataset(4, seed=4)
    for a, b in zip(X, again, strict=True):
        assert np.array_equal(a.positions, b.positions, equal_nan=True)
    assert not np.array_equal(X[0].positions, other[0].positions, equal_nan=True)
