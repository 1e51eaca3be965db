"""The numbers of ``segment``, ``reps``, ``describe`` and ``train --frame-labels/--split``
(hunt 26d) at frame rates other than 30 and 120 fps (the same recording resampled to 5, 24,
25 or 60 fps), for recordings cut to odd lengths and for pose files whose first frames show
nobody: seconds against frames, segments tiling the recording, repetitions within their
segment, counts that do not change with the frame rate, and label blocks on the right frames.
Each test says what happened before its fix.
"""

from __future__ import annotations

import pytest

from features.datasets import Clip
from features.repetitions import WINDOW_HOP_S, WINDOW_S, split_windows
from tests.moves import clip


@pytest.mark.parametrize("fps", [5.0, 15.0, 25.0, 30.0, 45.0])
def test_split_windows_start_every_half_second_at_any_frame_rate(fps: float) -> None:
    """30 s cut into 2-s windows every 0.5 s: windows starting at 0, 0.5, ..., 28 s, 57 of
    them, window k from frame k x 0.5 x fps rounded. Before, the hop was rounded to whole
    frames once: 12 frames at 25 fps (a window every 0.48 s, 59 windows), 2 at 5 fps (every
    0.4 s, 71), 8 at 15 fps (every 0.53 s, 53): the case base of ``train --split windows``
    held more or fewer cases of the same recording by its frame rate, each later window
    further from where ``segment`` cuts its own."""
    seq = clip("still", 30.0, fps)
    windows = split_windows([Clip(seq, "still", None, {})]).clips
    assert len(windows) == int((30.0 - WINDOW_S) / WINDOW_HOP_S) + 1 == 57
    for k, w in enumerate(windows):
        start = int(w.seq.metadata["frame_offset"])
        assert abs(start - k * WINDOW_HOP_S * fps) <= 0.5, (k, start)
        assert w.seq.n_frames == round(WINDOW_S * fps)
