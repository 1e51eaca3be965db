"""features.jitter: each joint smoothed as much as its own measured jitter asks (issue 14's
Kinect study), on hand-computed signals."""

from __future__ import annotations

import numpy as np
import pytest

from features.jitter import MIN_FRAMES, joint_jitter, smooth_jitter, smoothing_frames
from features.poses import BLAZEPOSE_33, PoseSequence
from features.skeleton import JOINT_INDEX

WRIST = JOINT_INDEX["left_wrist"]
KNEE = JOINT_INDEX["left_knee"]


def _still(frames: int = 60) -> np.ndarray:
    """Every joint at its own fixed place ``(frames, 33, 3)``."""
    base = np.arange(33 * 3, dtype=np.float64).reshape(33, 3) / 100.0
    return np.repeat(base[None], frames, axis=0)


def test_alternating_jitter_measured_from_its_second_differences() -> None:
    # x alternates +a, -a: every second difference is +-4a, so the estimate is
    # 1.4826 * 4a / sqrt(6) on that axis and 0 on the others
    a = 0.002
    pos = _still()
    pos[:, WRIST, 0] += a * (-1.0) ** np.arange(60)
    got = joint_jitter(pos)
    assert got[WRIST] == pytest.approx(1.4826 * 4 * a / np.sqrt(6))
    assert got[KNEE] == 0.0


def test_steady_movement_is_no_jitter() -> None:
    # constant velocity: second differences all 0
    pos = _still()
    pos[:, KNEE, 1] += 0.01 * np.arange(60)
    assert joint_jitter(pos)[KNEE] == pytest.approx(0.0, abs=1e-12)


def test_missing_frames_skipped_and_a_joint_never_seen_is_nan() -> None:
    a = 0.002
    pos = _still()
    pos[:, WRIST, 0] += a * (-1.0) ** np.arange(60)
    pos[10:13, WRIST] = np.nan  # the second differences touching these are left out
    pos[:, KNEE] = np.nan
    got = joint_jitter(pos)
    assert got[WRIST] == pytest.approx(1.4826 * 4 * a / np.sqrt(6))
    assert np.isnan(got[KNEE])


def test_smoothing_frames_bring_white_noise_to_the_target() -> None:
    # (j / target)^2 / (2 sqrt(pi)): 6 mm to 3 mm: 4 / 3.5449 = 1.128 frames; 30 mm asks
    # 28.2, capped at 0.1 s of 30 fps = 3 frames; 3 mm asks 0.282 < MIN_FRAMES: none
    got = smoothing_frames(np.array([0.006, 0.03, 0.003, np.nan]), 30.0, 0.003, 0.1)
    assert got == pytest.approx([4 / (2 * np.sqrt(np.pi)), 3.0, 0.0, 0.0])
    assert 1 / (2 * np.sqrt(np.pi)) < MIN_FRAMES


def test_clean_recording_comes_back_unchanged() -> None:
    pos = _still()
    pos[:, KNEE, 1] += 0.01 * np.arange(60)
    seq = PoseSequence(pos, BLAZEPOSE_33, 100.0)
    assert smooth_jitter(seq) is seq


def test_jittery_joint_smoothed_others_untouched_missing_kept_missing() -> None:
    # 1 cm alternating jitter on the wrist at 30 fps: asks far above the cap, so a Gaussian of
    # 3 frames, whose response at the alternation's frequency is exp(-(3 pi)^2 / 2) ~ 5e-20
    # (scipy cuts it at 4 sigma, 12 frames: ~2e-5 left): more than 12 frames from the ends and
    # the missing frame the wrist is back at its place; the knee is not touched at all
    a = 0.01
    pos = _still()
    place = pos[0, WRIST].copy()
    pos[:, WRIST, 0] += a * (-1.0) ** np.arange(60)
    pos[30, WRIST] = np.nan
    seq = PoseSequence(pos, BLAZEPOSE_33, 30.0)
    out = smooth_jitter(seq)
    wrist = out.positions[:, WRIST]
    assert np.isnan(wrist[30]).all()
    inside = np.r_[12:18, 43:48]
    assert np.abs(wrist[inside] - place).max() < 1e-4 * a
    # nearer, a held end or the missing frame unbalances the alternation: still a sixth of it
    assert np.abs(wrist[np.r_[4:30, 31:56]] - place).max() < 0.15 * a
    assert np.isfinite(np.delete(wrist, 30, axis=0)).all()
    others = np.delete(np.arange(33), WRIST)
    assert np.array_equal(out.positions[:, others], seq.positions[:, others])
    assert out.fps == seq.fps and out.joint_names == seq.joint_names
