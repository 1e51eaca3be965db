"""Hunt 42w: ``watch`` judges a repetition cut off by the stream's end beside the last
repetition of the segment finished before, as ``segment`` judges one cut off by the
recording's end since hunt 41r (:func:`cbr.segmentation._beside_whole`;
:meth:`cbr.live.LiveSegmenter._beside_whole`): the two agree on the last segment's count."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from cbr.segmentation import counted_segments
from features.poses import PoseSequence
from features.repetitions import count_repetitions, movement_signals
from tests.bodies import squat_pose, to_sequence
from tests.test_hunt36j import MOVE_S, REST_S, _eased
from tests.test_hunt36l import _live_segments
from tests.test_hunt38b import _both
from tests.test_repetitions import FPS


def _squats_then_down(squats: int, stand_s: float, depth: float) -> tuple[PoseSequence, int]:
    """Standing 0.6 s, ``squats`` squats (down over 0.8 s to knees at 50 degrees, up over
    0.8 s, standing 0.6 s between them), standing ``stand_s`` s after the last, then down
    over 0.8 s to ``depth`` of the way (knees at 180 - 130 ``depth`` degrees) and held there
    0.5 s to the end. Returns it and the first frame of the standing after the squats."""
    rest, move = int(REST_S * FPS), int(MOVE_S * FPS)
    parts = [np.zeros(rest)]
    for k in range(squats):
        parts += [_eased(move), _eased(move)[::-1]]
        if k < squats - 1:
            parts.append(np.zeros(rest))
    standing_from = sum(len(p) for p in parts)
    parts += [np.zeros(int(stand_s * FPS)), depth * _eased(move), np.full(int(0.5 * FPS), depth)]
    return to_sequence(*(squat_pose(d) for d in np.concatenate(parts)), fps=FPS), standing_from


@pytest.mark.parametrize("squats", [2, 3])
@pytest.mark.parametrize(("stand_s", "into_s"), [(2.0, 0.3), (3.0, 1.0), (8.0, 0.3)])
def test_watch_counts_the_squat_cut_off_by_the_end_as_segment(
    squats: int, stand_s: float, into_s: float
) -> None:
    """By construction ``squats`` whole squats and, after ``stand_s`` s of standing, one
    more down the whole way (knees 180 -> 50 degrees) that the stream ends in: cut off by
    the end as deep as the whole ones, which ``reps`` counts beside them (README, "a far
    point cut off by the end counts beside whole ones": at three quarters of their depth or
    more): ``squats`` + 1. The label changing ``into_s`` s into the standing, ``watch``
    counts ``squats`` and 1, as ``segment`` cut where ``watch`` cut. Before: ``squats`` and
    0, the last segment holding no whole repetition to measure it against (checked: fails
    on the code before). 8 s of standing can outlast the frames ``watch`` keeps from
    before the segment began (with two squats: 2 and 0 unless it keeps those from the last
    squat on; checked)."""
    seq, standing_from = _squats_then_down(squats, stand_s, 1.0)
    assert count_repetitions(seq).count == squats + 1
    watched, offline = _both(seq, standing_from + int(into_s * FPS), 0.0)
    assert len(watched) == 2
    assert watched == offline == [squats, 1]


def test_watch_leaves_out_a_way_down_half_as_deep_as_segment() -> None:
    """The same with the last way down only half as deep (knees to 115 degrees, half the
    whole squats' 130-degree bend, less than the three quarters a cut-off far point must
    reach to count beside whole ones): ``reps`` counts 2, and ``watch`` and ``segment``
    2 and 0: the stretch judged beside the segment before keeps no far point at the end."""
    seq, standing_from = _squats_then_down(2, 3.0, 0.5)
    assert count_repetitions(seq).count == 2
    watched, offline = _both(seq, standing_from + int(0.3 * FPS), 0.0)
    assert watched == offline == [2, 0]


@pytest.fixture(scope="module")
def bridges(bundled_poses: Callable[[str], PoseSequence]) -> PoseSequence:
    """The bundled glute bridge video's poses (BlazePose, as ``extract`` reads them)."""
    return bundled_poses("glute_bridge/fit_glute_bridge_pexels6525487.mp4").to_canonical()


@pytest.mark.parametrize("end", [153, 163])
def test_watch_counts_a_real_bridge_cut_off_by_the_end_as_segment(
    bridges: PoseSequence, end: int
) -> None:
    """The bundled glute bridge (25 fps), three bridges by hand, the hips up 0.0-1.1, 2.8-3.9
    and 5.9-6.6 s (tests/test_repetitions.py), streamed to ``watch`` up to frame ``end``
    (6.12 or 6.52 s: the stream ends with the hips up in the third), the label changing at
    frame 70 (2.8 s). ``watch`` cuts where the hips are on their way up into the second
    bridge, between the first hips-up stretch and the second: the last segment holds the
    second bridge's top and the third's, cut off by the end, 2 by hand, and 2 as
    ``segment`` counts it cut where ``watch`` cut (the second bridge cut off at the
    segment's start by the cut, the third judged beside the first segment's repetition).
    Before: 1, the third dropped (checked: fails on the code before). The first segment,
    the first bridge held as the stream starts, 1 by hand, ``watch`` counts 1 as ``segment``
    does since hunt 44w (before: 0, finished before the next segment was seen)."""
    assert bridges.fps == 25.0
    streamed = _live_segments(bridges.positions[:end], bridges.fps, (70,), bridges.confidence[:end])
    assert len(streamed) == 2
    cut = streamed[0].end_frame
    assert 1.1 * 25 < cut < 2.8 * 25
    piece = bridges.slice_frames(0, end)
    offline = counted_segments(movement_signals(piece), [(0, cut), (cut, end)], end)
    assert streamed[-1].repetitions == len(offline[-1]) == 2
    assert streamed[0].repetitions == len(offline[0]) == 1
