"""Hunt 44w: ``watch`` judges a repetition cut off by the stream's start beside the first
repetition of the segment after the first, as ``segment`` judges one cut off by the
recording's start (:func:`cbr.segmentation._beside_whole`;
:meth:`cbr.live.LiveSegmenter._judge_held`): the first segment's line is held back until
that repetition is known, and the two agree on the first segment's count. Also: the
windows' sums over each block, made without a loop over the windows, are the sums added in
the windows' order, to the last bit (:func:`cbr.segmentation._block_sums`)."""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace

import numpy as np
import pytest

from cbr.segmentation import _block_sums, _Solved, block_votes
from features.poses import PoseSequence
from features.repetitions import count_repetitions
from tests.bodies import squat_pose, to_sequence
from tests.test_hunt36j import MOVE_S, REST_S, _counts, _eased
from tests.test_hunt36l import LABELS, _Changing
from tests.test_hunt38b import _both
from tests.test_hunt45w import _streamed
from tests.test_repetitions import FPS


def _up_then_squats(depth: float, stand_s: float, squats: int) -> tuple[PoseSequence, int]:
    """The stream starting at the bottom of a squat ``depth`` of the way down (knees at
    180 - 130 ``depth`` degrees), held there 0.5 s, up over 0.8 s, standing ``stand_s`` s,
    then ``squats`` squats (down over 0.8 s to knees at 50 degrees, up over 0.8 s, standing
    0.6 s after each). Returns it and the first frame of the standing after the way up."""
    rest, move = int(REST_S * FPS), int(MOVE_S * FPS)
    parts = [np.full(int(0.5 * FPS), depth), depth * _eased(move)[::-1]]
    standing_from = sum(len(p) for p in parts)
    parts.append(np.zeros(int(stand_s * FPS)))
    for _ in range(squats):
        parts += [_eased(move), _eased(move)[::-1], np.zeros(rest)]
    return to_sequence(*(squat_pose(d) for d in np.concatenate(parts)), fps=FPS), standing_from


@pytest.mark.parametrize("squats", [2, 3])
@pytest.mark.parametrize(("stand_s", "into_s"), [(2.0, 0.3), (3.0, 1.0)])
def test_watch_counts_the_squat_cut_off_by_the_start_as_segment(
    squats: int, stand_s: float, into_s: float
) -> None:
    """By construction the stream starts at the bottom of a squat as deep as the ``squats``
    whole ones after it: cut off by the start, it counts beside them (README, "a far point
    cut off by the clip's start or end counts beside a whole one": three quarters of their
    depth or more), and ``reps`` counts ``squats`` + 1. The label changing ``into_s`` s into
    the standing after the way up, ``watch`` counts 1 and ``squats``, as ``segment`` cut
    where ``watch`` cut. Before: 0 and ``squats``, the first segment finished before the
    next was seen, with no whole repetition to measure its far point against (checked:
    fails on the code before)."""
    seq, standing_from = _up_then_squats(1.0, stand_s, squats)
    assert count_repetitions(seq).count == squats + 1
    watched, offline = _both(seq, standing_from + int(into_s * FPS), 2.0)
    assert len(watched) == 2
    assert watched == offline == [1, squats]


def test_watch_leaves_out_a_way_up_from_less_than_half_as_deep_as_segment() -> None:
    """The same starting at 0.4 of the whole squats' depth (knees at 128 degrees: 52 of
    their 130 degrees of bend, less than half): ``reps`` counts the 2 whole squats alone, and
    ``watch`` and ``segment`` 0 and 2: the stretch judged beside the segment after keeps no
    far point at the start."""
    seq, standing_from = _up_then_squats(0.4, 3.0, 2)
    assert count_repetitions(seq).count == 2
    watched, offline = _both(seq, standing_from + int(1.0 * FPS), 2.0)
    assert watched == offline == [0, 2]


def test_the_first_line_waits_for_the_next_segments_first_repetition() -> None:
    """8 s of standing after the way up, the label changing 0.3 s into it: ``watch``
    finishes the first segment while the standing goes on (about 9.5 s into the stream),
    before any repetition of the segment after it. Its line is held back until the first
    squat after the standing has come back (by construction at frame 39 + 240 + 48 = 327,
    10.9 s), then given while the stream goes on (not at its end), counting 1 as ``segment``
    does (before: given at once, counting 0; checked)."""
    seq, standing_from = _up_then_squats(1.0, 8.0, 2)
    back = standing_from + int(8.0 * FPS) + 2 * int(MOVE_S * FPS)
    frames = np.concatenate([seq.positions, np.repeat(seq.positions[-1:], int(2.0 * FPS), 0)])
    clf = SimpleNamespace(classes_=LABELS, case_base_=SimpleNamespace(labels=LABELS))
    live = _Changing(clf, FPS, judge=SimpleNamespace())
    live.changes = (standing_from + int(0.3 * FPS),)
    given = []
    for i, frame in enumerate(frames):
        given += [(i + 1, s) for s in live.push(frame)]
    assert given, "the first segment is given before the stream ends"
    at, first = given[0]
    assert first.start_frame == 0
    assert back <= at < len(frames)
    offline = _counts(PoseSequence(frames, seq.joint_names, FPS), [first.end_frame / FPS])
    assert first.repetitions == offline[0] == 1


@pytest.fixture(scope="module")
def squats(bundled_poses: Callable[[str], PoseSequence]) -> PoseSequence:
    """The bundled squat video's poses (BlazePose, as ``extract`` reads them; 65 frames at
    5 fps)."""
    return bundled_poses("squat/tfjs_pose_squats_pexels4838220.mp4").to_canonical()


@pytest.mark.parametrize("into_s", [1.5, 2.5])
def test_watch_counts_a_real_squat_cut_off_by_the_start_as_segment(
    squats: PoseSequence, into_s: float
) -> None:
    """The bundled squat video, three squats by hand, their bottoms at 2.0, 6.8 and
    12.0-12.8 s (tests/test_repetitions.py), streamed from frame 10 (2.0 s: the stream starts
    at the bottom of the first), the label changing ``into_s`` s in (before the second
    squat's way down): the first segment holds the first squat's way up, cut off by the
    start, 1 by hand, and 1 as ``segment`` counts it cut where ``watch`` cut; the stream 3,
    as ``reps`` and the hand count it. Before: 0 (checked: fails on the code before)."""
    assert squats.fps == 5.0
    start = 10
    stream = squats.slice_frames(start, squats.n_frames)
    assert count_repetitions(stream).count == 3
    streamed = _streamed(stream, into_s)
    assert len(streamed) == 2
    cut = streamed[0][1]
    assert cut < (5.2 - 2.0) * squats.fps  # before the second squat's way down
    offline = _counts(stream, [cut / squats.fps])
    assert [r for *_, r in streamed] == offline == [1, 2]


def test_block_votes_are_the_mean_of_the_windows_over_each_block() -> None:
    """10 fps, 0.1-s blocks (one frame each, centred at frames 0.5, 1.5, ...): a window of
    frames 0-3 voting [1, 0] and one of 1-3 voting [0, 1]. Block 0: the first alone, [1, 0];
    blocks 1 and 2: both, [0.5, 0.5]; blocks 3 and 4: none, every activity alike."""
    windows = [
        _Solved(0, 3, np.array([1.0, 0.0]), np.ones(2), None),
        _Solved(1, 3, np.array([0.0, 1.0]), np.ones(2), None),
    ]
    got = block_votes(windows, 5, 10.0)
    assert got.tolist() == [[1.0, 0.0], [0.5, 0.5], [0.5, 0.5], [0.5, 0.5], [0.5, 0.5]]


@pytest.mark.parametrize("columns", [(), (7,)])
def test_block_sums_add_each_blocks_windows_in_their_order(columns: tuple[int, ...]) -> None:
    """Each block's sum is its windows' values added one by one in the windows' order, to
    the last bit (as a loop over the windows added them before it was vectorised; a sum in
    another order, a difference array's running sum, differs in the last bits and can turn
    a tie between two activities' votes): 300 windows of 0.3-5 s at random over 60 s at 30
    fps, values of magnitudes 1e-3 to 1e3, summed here float by float."""
    rng = np.random.default_rng(44)
    fps, n_blocks = 30.0, 600
    starts = np.sort(rng.integers(0, 1790, 300))
    stops = np.minimum(1800, starts + rng.integers(9, 150, 300))
    spans = zip(starts.tolist(), stops.tolist(), strict=True)
    windows = [_Solved(a, b, np.ones(1), np.ones(1), None) for a, b in spans]
    values = rng.normal(size=(300, *columns)) * 10.0 ** rng.uniform(-3, 3, (300, *columns))
    total, counts = _block_sums(windows, values, n_blocks, fps)
    centres = (np.arange(n_blocks) + 0.5) * 0.1 * fps
    want = np.zeros((n_blocks, *columns))
    want_counts = np.zeros(n_blocks, dtype=np.int64)
    for k, centre in enumerate(centres):
        for w, v in zip(windows, values, strict=True):
            if w.start <= centre < w.stop:
                want[k] = want[k] + v
                want_counts[k] += 1
    assert np.array_equal(counts, want_counts)
    assert np.array_equal(total, want)  # bit for bit, not approximately
