"""A segment's repetitions counted as a clip of its frames is counted: a far point cut off at a
cut that only this side of the cut shows is kept where the movement turns within the segment
(:func:`cbr.segmentation.unclaimed`). CMU subject 13, cut at its labelled changes, against
the hand counts of tests/fixtures/repetition_counts.json."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cbr.segmentation import counted_segments
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
    none at the change, and counted nowhere."""
    one, two = _hand(recording)[first : first + 2]
    a, cut, b = one["start_frame"], one["end_frame"], two["end_frame"]
    assert two["start_frame"] == cut
    seq = recordings[recording].slice_frames(a, b).to_canonical()
    bounds = [(0, cut - a), (cut - a, b - a)]
    counts = [len(r) for r in counted_segments(movement_signals(seq), bounds, seq.n_frames)]
    assert counts == [one["count"], two["count"]]
    assert counts == [count_repetitions(seq.slice_frames(p, q)).count for p, q in bounds]
