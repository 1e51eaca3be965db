"""Hunt 37g: what a person sees in the pictures and overlays of the long-recording commands
(``segment --plot``, ``reps --plot``, ``segment --overlay``, ``watch --out``, ``extract
--overlay``)."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.mark.parametrize(("width", "height"), [(640, 480), (1920, 1080), (720, 1280)])
def test_overlay_text_outline_lies_around_its_letters(width: int, height: int) -> None:
    """The overlays wrote a word twice with OpenCV's font, a black outline 4 pixels thick and
    the white letters 1 pixel thick over it; that font advances its letters further the
    thicker the stroke, so the white letters fell behind the outline letter by letter:
    "repetitions: 1" read as a smudge, the white "1" some 17 pixels short of its outline at
    1920x1080. Now the outline is drawn around the letters: on the line of "repetitions: 1"
    the black reaches only a few pixels beyond the white on either side."""
    from features.pose_estimation.overlay import draw_pose

    frame = np.full((height, width, 3), 128, dtype=np.uint8)
    draw_pose(frame, np.full((33, 5), np.nan), ["repetitions: 1"])  # "no person" first
    scale = max(0.6, min(width, height) / 600)
    base1, base2 = 30 * scale, 60 * scale  # the baselines of the two lines
    rows = slice(int(base1 + 0.4 * (base2 - base1)), int(base2 + 0.35 * (base2 - base1)))
    line = frame[rows].astype(int).sum(axis=2)
    dark = np.flatnonzero((line < 3 * 40).any(axis=0))
    light = np.flatnonzero((line > 3 * 215).any(axis=0))
    assert dark.size and light.size
    stroke = max(1, round(19 * scale / 10))  # the outline's width
    assert 0 <= dark.max() - light.max() <= stroke + 2, (dark.max(), light.max())
    assert 0 <= light.min() - dark.min() <= stroke + 2, (dark.min(), light.min())
    assert frame[:, :, 0].shape == (height, width)  # drawn in place, nothing outside
