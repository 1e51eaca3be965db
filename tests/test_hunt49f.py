"""A person found only in the finer tiles counts when found again (hunt 49f).

The tiles of a quarter of the frame (hunt 48p) look at 35 windows of a 640 x 480 frame where
the whole frame and the tiles of half look at 7: each a chance for a pattern in noise to
look like a person to the detector and then to the landmark model. On frames of coloured
noise the finer search "found" people where there were none. A find of the finer tiles now
counts only when the detector finds the same person again in a window of the tiles' size
centred on them, and the landmark model sees a person there.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from features.pose_estimation import PoseEstimator
from tests.test_hunt48p import _player


def _noise(seed: int, width: int = 640, height: int = 480) -> np.ndarray:
    """A frame of seeded coloured noise (random colours in square cells 2-16 pixels wide,
    blurred), boxes and lines: nobody in it."""
    rng = np.random.default_rng(seed)
    cell = int(rng.integers(2, 17))
    small = rng.integers(0, 256, (height // cell + 1, width // cell + 1, 3)).astype(np.uint8)
    frame = cv2.resize(small, (width, height), interpolation=cv2.INTER_NEAREST)
    frame = cv2.GaussianBlur(frame, (0, 0), float(rng.uniform(0.5, 3)))
    for _ in range(int(rng.integers(5, 20))):
        x0, y0 = int(rng.integers(0, width)), int(rng.integers(0, height))
        x1, y1 = x0 + int(rng.integers(5, width // 3)), y0 + int(rng.integers(5, height // 3))
        colour = tuple(int(c) for c in rng.integers(0, 256, 3))
        cv2.rectangle(frame, (x0, y0), (x1, y1), colour, -1 if rng.random() < 0.5 else 2)
    for _ in range(int(rng.integers(5, 20))):
        p0 = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        p1 = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        colour = tuple(int(c) for c in rng.integers(0, 256, 3))
        cv2.line(frame, p0, p1, colour, int(rng.integers(1, 6)))
    return frame


def test_noise_is_nobody_and_a_small_person_on_it_is_found(shared_data: Path) -> None:
    """Two seeded frames of coloured noise: nobody in either (before, the finer tiles found
    a person in each). The basketball player shrunk to 0.15 of the frame's height (72
    pixels, under the some 0.2 the tiles of half reach) and put near the centre of the
    first, where the finer tiles find him (at the very centre the detector finds him in no
    window, before as now): found, his hips within his picture."""
    est = PoseEstimator(tracking=False, smoothing=False)
    assert not est.process(_noise(1049)).person
    assert not est.process(_noise(1059)).person
    player = _player(shared_data)
    scale = 72 / player.shape[0]
    small = cv2.resize(player, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    frame = _noise(1049)
    x, y = 310, 200
    frame[y : y + small.shape[0], x : x + small.shape[1]] = small
    pose = est.process(frame)
    assert pose.person
    hips = pose.image[[23, 24], :2].mean(axis=0)
    assert x < hips[0] < x + small.shape[1] and y < hips[1] < y + small.shape[0]
