"""Hunt 52w: a review of the day's changes.

- ``watch --split repetitions``' end listed every verdict's times at the rate the stream
  was last watched at: a verdict given before the stream was watched again at the rate it
  rose to (:meth:`posecbr.commands.watch.Watcher._remake`), its frames counted at the first
  rate, was said at half its time after a rise from 15 to 30 fps. Each verdict now keeps the
  rate its frames count at (:class:`cbr.live_verdicts.Verdict`); the count after the
  first verdict at the new rate went on from the frame before the last at the old rate's
  frame number (half as far into the stream from 15 to 30 fps).
- ``extract``'s line of the body's parts out of view rounded a part missing in 99.5 % of
  the frames with a person or more to "100 %", which it says of a part no frame shows:
  now ">99 %".
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import cbr.live_verdicts as live_verdicts
from cbr.live_verdicts import RepetitionVerdicts
from features.skeleton import JOINT_INDEX
from posecbr.commands.extract import out_of_view
from posecbr.commands.watch import _print_verdicts


def _judged(*args: Any) -> SimpleNamespace:
    """``classify_clip``'s stand-in: an incorrect repetition, explained."""
    text = "an incorrect repetition, confidence 0.78\nwhy: ..."
    explanation = SimpleNamespace(text=text)
    return SimpleNamespace(label="incorrect", explanation=explanation, to_dict=lambda: {})


def test_a_verdict_before_a_rise_of_the_rate_keeps_its_times(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A repetition of stream frames 15-29 at 15 fps (1.0-2.0 s) judged, then the stream
    watched again at 30 fps, where frames 90-119 (3.0-4.0 s) are judged: its line says
    1.0-2.0 s, and the end lists it at 1.0-2.0 s (frames 15-29, as its line gave them) and
    the second at 3.0-4.0 s; the count goes on from the first's start, frame 30 at 30 fps.
    Before, the end read every verdict's frames at 30 fps: the first at 0.5-1.0 s; and the
    count after the second went on from frame 15 (0.5 s)."""
    monkeypatch.setattr(live_verdicts, "classify_clip", _judged)
    stored = SimpleNamespace(target="correct")
    slow = SimpleNamespace(fps=15.0, clip=lambda a, b: None)
    first = RepetitionVerdicts(stored, slow)  # type: ignore[arg-type]
    first._ask((15, 30))
    first.ready()  # given, as watch reads it
    line = first.given[0].to_dict()
    assert (line["repetition"], line["start_s"], line["end_s"]) == (1, 1.0, 2.0)
    fast = SimpleNamespace(fps=30.0, clip=lambda a, b: None)
    again = RepetitionVerdicts(stored, fast, first)  # type: ignore[arg-type]
    assert again.judged_to == 60  # the first's end, frame 30 at 15 fps, at 30 fps
    again._ask((90, 120))
    again.ready()
    # the count goes on from the start of the one before the last judged: the first's frame
    # 15 at 15 fps, frame 30 at 30 fps
    assert again.anchor == 30
    assert (again.given[1].to_dict()["start_s"], again.given[1].to_dict()["end_s"]) == (3.0, 4.0)
    _print_verdicts(again.given, "correct")
    assert capsys.readouterr().err.splitlines()[:2] == [
        "repetition 1, frames 15-29 (1.0-2.0 s): an incorrect repetition, confidence 0.78",
        "repetition 2, frames 90-119 (3.0-4.0 s): an incorrect repetition, confidence 0.78",
    ]


def test_extract_says_100_percent_only_of_a_part_out_of_view_in_every_frame() -> None:
    """``extract``'s line of a close-up whose hips are out of view in 399 of its 400 frames
    with a person and whose left wrist is in 1: the hips ">99 %", not 100 % (a frame shows
    them), the wrists "<1 %"; the knees, in none of them, 100 %. Before, the hips' 99.75 %
    was rounded to "100 %", as if no frame showed them."""
    positions = np.zeros((400, 33, 3))
    for name in ("left_knee", "right_knee"):
        positions[:, JOINT_INDEX[name]] = np.nan
    positions[1:, JOINT_INDEX["left_hip"]] = np.nan
    positions[0, JOINT_INDEX["left_wrist"]] = np.nan
    seq = SimpleNamespace(positions=positions)
    assert out_of_view(seq, np.zeros(400, dtype=bool)) == (  # type: ignore[arg-type]
        "; out of view in the frames with a person: wrists <1 %, hips >99 %, knees 100 %"
    )
