"""A video of a scene with nobody in it, lossless, for the tests of "nobody in view"."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.test_video_vfr import _write


def still_scene(width: int = 320, height: int = 240) -> np.ndarray:
    """``(height, width, 3)`` RGB: a still scene with nobody in it (a sky-to-ground gradient,
    a wall and a kerb: no shape of a person), drawn at 320 x 240 by default and in proportion
    at other sizes (a bundled clip's frame size, to show it after nobody)."""
    y = np.linspace(0.0, 1.0, height)[:, None, None]
    rgb = np.array([150.0, 180.0, 220.0]) * (1 - y) + np.array([90.0, 110.0, 80.0]) * y
    still = np.broadcast_to(rgb, (height, width, 3)).astype(np.uint8).copy()
    h, w = height / 240, width / 320  # of the 320 x 240 drawing
    still[int(60 * h) : int(140 * h), int(200 * w) : int(300 * w)] = (150, 90, 70)  # a wall
    still[int(170 * h) : int(176 * h), :] = (200, 200, 200)  # a kerb
    return still


def empty_scene(path: Path, frames: int, fps: int = 10) -> Path:
    """``frames`` frames at ``fps`` of the 320 x 240 still scene with nobody in it
    (:func:`still_scene`), FFV1 in Matroska, lossless, so that every run decodes the same
    pixels."""
    still = still_scene()
    step = round(1000 / fps)
    return _write(path, [step * k for k in range(frames)], [still] * frames, rate=fps, codec="ffv1")
