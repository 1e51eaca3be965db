"""Hunt 51r: a review of the session's changes. ``watch --out`` (or ``--show``) counted a
squat the person was lost from view in at its bottom and seen again on the way up no more,
where ``watch`` without them counted it (the segment in progress, drawn with its count,
cleared where the repetition began); ``watch`` left the latency of a frame held after a
pause uncounted when the frame after it was held too; a HEIF grid whose layout item holds
bytes after its fields was read as a picture millions of pixels high."""

from __future__ import annotations

import numpy as np

from cbr.estimator import CaseBaseClassifier
from cbr.live import LiveSegmenter
from features.pose_estimation.containers import _grid_layout
from features.poses import PoseSequence
from tests.test_hunt51e import _watched
from tests.test_segment import classifier, names, recordings  # noqa: F401 - the fixtures


def _drawn(clf: CaseBaseClassifier, positions: np.ndarray) -> list:
    """The segments ``watch``'s live segmenter gives the frames pushed one by one at 30 fps,
    the segment in progress asked for after every frame, as ``watch`` asks it for every frame
    it draws (``--out``, ``--show``)."""
    live = LiveSegmenter(clf, 30.0)
    out = []
    for frame in positions:
        out += live.push(frame)
        live.current()
    return out + live.finish()


def test_watch_counts_a_squat_lost_at_its_bottom_alike_whether_it_draws_or_not(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
    classifier: CaseBaseClassifier,  # noqa: F811
) -> None:
    """CMU 13_30's squats (11.8-16.1 s, two squats: the hips lowest at frames 36-39 and
    105-108 of 30 fps) cut at frame 40, just after the first squat's bottom, 1 s with every
    joint missing, the rest, and the two squats again. By hand: 4 squats, the first lost from
    view on its way up and seen again (one repetition, as ``segment`` counts it). Drawn, the
    segment after the stretch counted 3: the segment in progress, asked for to be drawn with
    its count, took and cleared the frame the lost squat began at (LiveSegmenter.lost_from)."""
    rec = recordings["13_30"]
    squats = rec.positions[int(11.8 * 120) : int(16.1 * 120)][::4]
    nobody = np.full((30, *squats.shape[1:]), np.nan)
    positions = np.concatenate([squats[:40], nobody, squats[40:], squats])
    drawn = _drawn(classifier, positions)
    assert [(s.start_frame, s.label, s.repetitions) for s in drawn] == [
        (0, "Squat", 0),  # down to the bottom: the repetition goes on out of sight
        (40, None, 0),  # nobody in view
        (70, "Squat", 4),  # seen again: the lost squat, and three more
    ]


def test_each_frame_held_after_a_pause_has_its_latency_counted() -> None:
    """A live stream at 30 fps for 2 s, then five frames each 0.3 s after the one before (a
    drop-out before each: each held until the next frame tells it from a burst's), then 30
    fps again for 1 s: 95 frames, each watched and each with its latency counted once. The
    first four of the five were held, then given with the next, itself held: their
    latencies were not counted (91 of 95), and those are the frames that waited longest."""
    times = [*(np.arange(60) / 30.0)]
    times += [times[-1] + 0.3 * k for k in range(1, 6)]
    times += [times[-1] + k / 30.0 for k in range(1, 31)]
    _, latencies = _watched(times, "the stream ended after")
    assert len(times) == 95
    assert len(latencies) == 95


def test_a_heif_grid_layout_is_read_from_its_fields_alone() -> None:
    """ISO/IEC 23008-12 ImageGrid: version 0, flags (bit 0: 32-bit sizes), rows - 1,
    columns - 1, output width, output height. An iPhone's 4032x3024 photo: 6 rows, 8 columns
    of 512x512 tiles. Bytes after the fields (a writer's padding) are no part of the height:
    two zero bytes more made it 3024 * 65536, and the photo was refused as a part."""
    layout16 = bytes([0, 0, 5, 7]) + (4032).to_bytes(2, "big") + (3024).to_bytes(2, "big")
    layout32 = bytes([0, 1, 5, 7]) + (4032).to_bytes(4, "big") + (3024).to_bytes(4, "big")
    for layout in (layout16, layout32):
        assert _grid_layout(layout) == (6, 8, 4032, 3024)
        assert _grid_layout(layout + b"\0\0") == (6, 8, 4032, 3024)
    assert _grid_layout(layout16[:7]) is None
    assert _grid_layout(layout32[:11]) is None
