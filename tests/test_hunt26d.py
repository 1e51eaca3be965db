"""The numbers of ``segment``, ``reps``, ``describe`` and ``train --frame-labels/--split``
(hunt 26d) at frame rates other than 30 and 120 fps (the same recording resampled to 5, 24,
25 or 60 fps), for recordings cut to odd lengths and for pose files whose first frames show
nobody: seconds against frames, segments tiling the recording, repetitions within their
segment, counts that do not change with the frame rate, and label blocks on the right frames.
Each test says what happened before its fix.
"""

from __future__ import annotations

import pytest

from cbr.segmentation import Segment, Segmentation
from features.datasets import Clip
from features.repetitions import WINDOW_HOP_S, WINDOW_S, Repetition, split_windows
from posecbr.commands.segment import frame_words
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


def _segment(start: int, end: int, label: str, reps: list[tuple[int, int]]) -> Segment:
    return Segment(start, end, label, 1.0, tuple(Repetition(a, b, a) for a, b in reps), "", 0.5)


def test_the_overlay_counts_a_segments_last_repetition_by_its_last_frame() -> None:
    """Frames [0, 100) squats with repetitions [0, 40) and [40, 100), frames [100, 150) knee
    raises with one [100, 150) (ends exclusive): the overlay's count should reach 1 at frame
    39, 2 at frame 99 (the squats' last frame) and 1 at frame 149, the counts ``segment``
    prints. Before, a repetition was counted from the frame after its end, which for one
    that runs to its segment's end is the next segment's first frame: the squats were shown
    done 1 to their end and the knee raise 0 (CMU 13_30 at 25 fps: its second knee-raise
    segment, 5 repetitions, drawn ending at 4)."""
    result = Segmentation(
        "r", 25.0, 150,
        (_segment(0, 100, "squat", [(0, 40), (40, 100)]),
         _segment(100, 150, "knee", [(100, 150)])),
        (),
    )  # fmt: skip
    words = frame_words(result)
    counts = [int(w[1].split(": ")[1]) for w in words]
    assert counts[38] == 0 and counts[39] == 1 and counts[98] == 1
    assert counts[99] == 2 and counts[100] == 0 and counts[148] == 0 and counts[149] == 1
    assert [w[0] for w in (words[99], words[100])] == ["squat", "knee"]
