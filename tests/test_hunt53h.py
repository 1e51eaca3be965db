"""Session 53, task H: ``watch`` of a person whose hips are out of view. A window of the
stream whose frames show the shoulders and arms but neither hip is judged on the arms, as
``segment`` judges a recording shown from the shoulders up (hunt 53g), where every such
window was nobody in view; a window where the hips come back is judged whole as before."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from features.poses import PoseSequence
from tests.test_hunt52g import TWO_PEOPLE, _hips_out
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows


@pytest.fixture(scope="module")
def clf(case_base: Path) -> Any:  # noqa: F811
    from posecbr.commands.segment import load_stored

    return load_stored(str(case_base), None)


def _streamed(clf: Any, seq: PoseSequence) -> list[Any]:
    """The segments ``watch``'s segmenter gives of ``seq`` pushed frame by frame."""
    from cbr.live import LiveSegmenter

    live = LiveSegmenter(clf, seq.fps)
    got = []
    for i in range(seq.n_frames):
        conf = None if seq.confidence is None else seq.confidence[i]
        got += live.push(seq.positions[i], conf)
    return got + live.finish()


def test_a_stream_without_hips_is_labelled_from_its_arms(
    clf: Any, bundled_poses: Callable[[str], PoseSequence]
) -> None:
    """The two-people jumping-jack video's tracked person (10 s at 25 fps, six jumping jacks
    by hand: tests/fixtures/repetition_counts.json) with the hips and legs missing in every
    frame, streamed against CMU 13_29's windows: the person is in view throughout, so no
    stretch is nobody in view; what is labelled is an activity whose arms are those of a
    jumping jack (JumpJack, or ArmCircle: the arms swing up over the head and down again in
    both), JumpJack for most of the stream, and the six are counted, as ``segment`` counts
    them on the same poses. On main's code the whole stream was one segment, nobody in view,
    counted 0."""
    seq = _hips_out(bundled_poses(TWO_PEOPLE).to_canonical())
    got = _streamed(clf, seq)
    assert got[-1].end_frame == seq.n_frames
    assert all(s.explanation != "nobody in view" for s in got), got
    assert {s.label for s in got} - {None} <= {"JumpJack", "ArmCircle"}, got
    jacks = sum(s.end_frame - s.start_frame for s in got if s.label == "JumpJack")
    assert jacks > seq.n_frames / 2, got
    assert sum(s.repetitions for s in got) == 6, got


def test_the_hips_going_out_of_view_the_stream_goes_on_from_the_arms(
    clf: Any, bundled_poses: Callable[[str], PoseSequence]
) -> None:
    """The same person's first 6 s, the whole body for the first 2 s (50 frames) and the hips
    and legs out of view after: three jumping jacks by hand (arms up at 1.25, 2.9 and 4.65
    s). The stretch without the hips is no nobody in view and is labelled JumpJack for most
    of it (a jumping jack it is), and the three are counted. Its first windows' context shows
    the hips: read with them, every arm angle of those windows was unavailable (the frame of
    the hips, no hips in the window) and the stretch was unknown to its end; the context is
    read without the hips, as the window is. On main's code the stretch was nobody in view."""
    whole = bundled_poses(TWO_PEOPLE).to_canonical().slice_frames(0, 150)
    out = _hips_out(whole)
    seq = dataclasses.replace(
        whole, positions=np.concatenate([whole.positions[:50], out.positions[50:]])
    )
    got = _streamed(clf, seq)
    assert all(s.explanation != "nobody in view" for s in got), got
    jacks = sum(
        min(s.end_frame, 150) - max(s.start_frame, 50) for s in got if s.label == "JumpJack"
    )
    assert jacks > 50, got
    assert sum(s.repetitions for s in got) == 3, got
