"""``watch`` and ``segment`` judge whether a stretch is unlike every activity by one rule for
how far the person lies from every case (hunt 39f, hunt 40a).

With a case base of one person, each window's distances are taken less how much farther
this person lies from every case (:func:`cbr.unknown.person_judges`): read from the fixed
windows that end by the window's own end, what a stream has seen when the window is solved,
in both commands. Before, ``segment`` read it from the whole recording and ``watch`` judged
each window again by the windows seen when its hop was decided known or unknown (and, before
that, by the windows so far, fixed and repetition windows alike, which took a movement the
case base lacks at the stream's start for a far person): a recording's first windows could
be known to one and unknown to the other.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from benchmarks.segment import fit, load_recordings, training_clips
from benchmarks.segment_live import block_labels, watch
from cbr.segmentation import segment
from features.poses import PoseSequence
from features.skeleton import BLAZEPOSE_33

STEP = 4  # 120 fps streamed at 30, as benchmarks.segment_live streams it


@pytest.fixture(scope="module")
def both() -> tuple[Any, list[Any], list[Any], float]:
    """CMU 13_30 at 30 fps (every 4th frame), its first exercise (jumping jacks, 0-1.8 s)
    left out of a case base of 13_29 and 13_31 (``benchmarks.segment_live``'s case):
    the recording, and its segments streamed to ``watch``'s decoder and by ``segment``."""
    recs = load_recordings()
    rec = recs["13_30"]
    clf = fit(training_clips([recs["13_29"], recs["13_31"]], leave_out="JumpJack"))
    fps = rec.seq.fps / STEP
    world = rec.seq.positions[::STEP]
    live = watch(clf, world, fps)
    offline = list(segment(clf, PoseSequence(world, BLAZEPOSE_33, fps, source="13_30")).segments)
    return rec, live, offline, fps


def test_an_exercise_the_case_base_lacks_at_the_stream_start_is_unknown(
    both: tuple[Any, list[Any], list[Any], float],
) -> None:
    """``watch`` called none of the left-out jumping jacks' blocks unknown, then (hunt 39f) 8
    in 9; ``segment`` all of them. Now both: most (more than half), and the exercises the
    case base has are named rightly in 9 blocks in 10 or more."""
    rec, live, _, fps = both
    pred = block_labels(live, len(rec.blocks), fps)
    mine = rec.blocks == "JumpJack"
    assert mine[0] and mine.sum() >= 10  # the stream starts with them
    called_unknown = float(np.mean([p is None for p in pred[mine]]))
    assert called_unknown > 0.5, called_unknown
    seen = ~mine
    assert np.mean(pred[seen] == rec.blocks[seen]) > 0.9


def test_watch_and_segment_judge_the_stream_start_alike(
    both: tuple[Any, list[Any], list[Any], float],
) -> None:
    """The same recording, segmented and streamed: the left-out jumping jacks' blocks called
    unknown block for block alike (``watch`` had left 2 of their 18 known, ``segment`` none),
    the same labels in the same order, and every boundary within one hop of the live decoder
    (0.5 s, 15 frames: it decides every hop, ``segment`` every 0.1-s block)."""
    rec, live, offline, fps = both
    mine = rec.blocks == "JumpJack"
    watched = block_labels(live, len(rec.blocks), fps)
    segmented = block_labels(offline, len(rec.blocks), fps)
    assert [p is None for p in watched[mine]] == [p is None for p in segmented[mine]]
    assert [s.label for s in live] == [s.label for s in offline]
    for a, b in zip(live, offline, strict=True):
        assert abs(a.start_frame - b.start_frame) <= 15, (a, b)
        assert abs(a.end_frame - b.end_frame) <= 15, (a, b)


if __name__ == "__main__":  # pragma: no cover
    pytest.main([__file__])
