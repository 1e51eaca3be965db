"""Smoothing each joint as much as its own measured jitter asks, and no more.

A joint's jitter is the per-frame size of the white noise on its positions, read from its
second differences: for noise of standard deviation ``s`` on each axis, the second difference
``x[t+1] - 2 x[t] + x[t-1]`` has standard deviation ``sqrt(6) s``, and its median absolute
value (robust to the movement's own accelerations, which are small between frames most of
the time) is ``0.6745 sqrt(6) s`` (:func:`joint_jitter`). A Gaussian of ``g`` frames
(``g`` about 1 or more) divides white noise by ``sqrt(2 sqrt(pi) g)``, so bringing a jitter
``j`` down to ``target`` takes ``g = (j / target)^2 / (2 sqrt(pi))`` frames
(:func:`smoothing_frames`), at most ``max_s`` seconds; a joint that asks for less than
:data:`MIN_FRAMES` is left as it is (:func:`smooth_jitter`). Nothing here knows a sensor or
a data set: a clean motion-capture recording (jitter well under a millimetre) comes back
unchanged, a depth camera's ankles and feet (several millimetres a frame) are smoothed.

Measured on issue 14's windows (``benchmarks.unknown_ceiling --smooth-jitter``; README "How
far any threshold could go"): not a default.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .poses import PoseSequence

TARGET_M = 0.003
"""The jitter (metres a frame) :func:`smooth_jitter` brings a joint down to by default."""
MAX_S = 0.1
"""The widest Gaussian (its standard deviation, seconds) :func:`smooth_jitter` uses by default."""
MIN_FRAMES = 0.3
"""A joint asking for a Gaussian narrower than this many frames is not smoothed."""

MAD_TO_SD = 1.4826
"""A normal variable's standard deviation over its median absolute deviation (1 / 0.6745):
the robust standard deviation the counter, the segmenter and :func:`joint_jitter` take."""


def joint_jitter(positions: np.ndarray) -> np.ndarray:
    """Each joint's jitter ``(joints,)``, metres a frame, of ``positions`` ``(frames, joints,
    3)``: per axis ``1.4826 median|second difference| / sqrt(6)`` (the standard deviation of
    white noise with that median), over the frames where three in a row are present; the
    Euclidean norm over the axes. NaN for a joint never present three frames in a row."""
    x = np.asarray(positions, dtype=np.float64)
    out = np.full(x.shape[1], np.nan)
    if x.shape[0] < 3:
        return out
    d2 = np.abs(np.diff(x, 2, axis=0))  # (frames - 2, joints, 3); NaN where a frame is missing
    for j in range(x.shape[1]):
        ok = np.all(np.isfinite(d2[:, j]), axis=1)
        if ok.any():
            out[j] = float(np.linalg.norm(MAD_TO_SD * np.median(d2[ok, j], axis=0) / np.sqrt(6)))
    return out


def smoothing_frames(
    jitter: np.ndarray, fps: float, target_m: float = TARGET_M, max_s: float = MAX_S
) -> np.ndarray:
    """The Gaussian's standard deviation in frames ``(joints,)`` that brings each ``jitter``
    (metres a frame) down to ``target_m``: ``(jitter / target_m)^2 / (2 sqrt(pi))``, at most
    ``max_s * fps``; 0 where it would be under :data:`MIN_FRAMES` or the jitter is NaN."""
    j = np.asarray(jitter, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        g = np.minimum((j / target_m) ** 2 / (2.0 * np.sqrt(np.pi)), max_s * fps)
        return np.where(np.isfinite(g) & (g >= MIN_FRAMES), g, 0.0)


def smooth_jitter(
    seq: PoseSequence, target_m: float = TARGET_M, max_s: float = MAX_S
) -> PoseSequence:
    """``seq`` with every joint smoothed over time by a Gaussian of :func:`smoothing_frames`
    of its own :func:`joint_jitter` (ends held at their values; a missing frame is left
    missing and does not count in its neighbours' averages); ``seq`` itself when no joint
    asks for smoothing."""
    g = smoothing_frames(joint_jitter(seq.positions), seq.fps, target_m, max_s)
    if not g.any():
        return seq
    from scipy.ndimage import gaussian_filter1d

    x = np.array(seq.positions, dtype=np.float64)
    for j in np.flatnonzero(g):
        col = x[:, j]  # (frames, 3)
        present: np.ndarray = np.asarray(np.isfinite(col).all(axis=1))
        weight = gaussian_filter1d(present.astype(np.float64), g[j], mode="nearest")
        total = gaussian_filter1d(np.where(present[:, None], col, 0.0), g[j], axis=0,
                                  mode="nearest")  # fmt: skip
        with np.errstate(invalid="ignore", divide="ignore"):
            x[:, j] = np.where(present[:, None], total / weight[:, None], np.nan)
    return dataclasses.replace(seq, positions=x)
