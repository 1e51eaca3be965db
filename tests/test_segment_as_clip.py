"""A segment's repetitions counted as a clip of its frames is counted: on the movement signals
of its own frames (:class:`cbr.segmentation._Own`), and with a far point cut off at a cut
that only this side of the cut shows kept where the movement turns within the segment
(:func:`cbr.segmentation._unclaimed`). CMU subject 13, cut at its labelled changes, against
the hand counts of tests/fixtures/repetition_counts.json."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cbr.segmentation import count_in_segment, counted_segments
from features.poses import PoseSequence
from features.repetitions import count_repetitions, movement_signals
from tests.test_segment import recordings  # noqa: F401 (fixture)

FIXTURE = Path(__file__).parent / "fixtures" / "repetition_counts.json"


def _hand(recording: str) -> list[dict]:
    """The stretches of ``recording`` counted by hand, in order."""
    clips = json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
    return [c for c in clips if c["source"].endswith(f"{recording}.amc")]


@pytest.mark.parametrize(("recording", "first"), [("13_29", 0), ("13_31", 3)])
def test_two_exercises_cut_at_their_change_count_as_their_clips(
    recordings: dict[str, PoseSequence],  # noqa: F811 (fixture)
    recording: str,
    first: int,
) -> None:
    """Two neighbouring hand-counted stretches as a recording of their own, cut into two
    segments at the labelled change: 13_29's four jumping jacks (the last arms-up 0.1 s
    before the change) then three twists; 13_31's twist then seven jogging steps (the
    first far point the steps' frames hold is at the change). Each segment counts what its
    frames count as a clip, and the hand count. Before, the jacks counted 3: their last far
    point, in the segment's last sample, was handed to the twists, whose own movement has
    none at the change, and counted nowhere (the jog, smoothed over its own frames, lost its
    first step so too, until the far point at its start was judged across the change)."""
    one, two = _hand(recording)[first : first + 2]
    a, cut, b = one["start_frame"], one["end_frame"], two["end_frame"]
    assert two["start_frame"] == cut
    seq = recordings[recording].slice_frames(a, b).to_canonical()
    bounds = [(0, cut - a), (cut - a, b - a)]
    counts = [len(r) for r in counted_segments(seq, bounds, seq.n_frames)]
    assert counts == [one["count"], two["count"]]
    assert counts == [count_repetitions(seq.slice_frames(p, q)).count for p, q in bounds]


def test_a_segment_is_counted_on_its_own_frames(
    recordings: dict[str, PoseSequence],  # noqa: F811 (fixture)
) -> None:
    """13_31's first knee raises (4 by hand) as the one segment cut out of the recording's
    first 12 s: counted exactly as the same frames counted alone at a cut at either end
    (far points, their frames and their sides), not on the recording's signals smoothed
    across the cuts."""
    raises = _hand("13_31")[1]
    a, b = raises["start_frame"], raises["end_frame"]
    seq = recordings["13_31"].slice_frames(0, int(12 * 120)).to_canonical()
    bounds = [(0, a), (a, b), (b, seq.n_frames)]
    piece = counted_segments(seq, bounds, seq.n_frames)[1]
    clip = seq.slice_frames(a, b)
    alone = count_in_segment(movement_signals(clip), clip.n_frames, clip.fps, (False, False))
    assert len(piece) == raises["count"] == 4
    shifted = [
        (r.start_frame + a, r.peak_frame + a, r.end_frame + a, r.side) for r in alone.repetitions
    ]
    assert [(r.start_frame, r.peak_frame, r.end_frame, r.side) for r in piece] == shifted
