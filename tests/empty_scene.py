"""A video of a scene with nobody in it, lossless, for the tests of "nobody in view"."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.test_video_vfr import _write


def empty_scene(path: Path, frames: int, fps: int = 10) -> Path:
    """``frames`` frames at ``fps`` of a 320 x 240 still scene with nobody in it (a sky-to-
    ground gradient, a wall and a kerb: no shape of a person), FFV1 in Matroska, lossless, so
    that every run decodes the same pixels."""
    y = np.linspace(0.0, 1.0, 240)[:, None, None]
    rgb = np.array([150.0, 180.0, 220.0]) * (1 - y) + np.array([90.0, 110.0, 80.0]) * y
    still = np.broadcast_to(rgb, (240, 320, 3)).astype(np.uint8).copy()
    still[60:140, 200:300] = (150, 90, 70)  # a brick wall
    still[170:176, :] = (200, 200, 200)  # a kerb
    step = round(1000 / fps)
    return _write(path, [step * k for k in range(frames)], [still] * frames, rate=fps, codec="ffv1")
