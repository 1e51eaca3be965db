"""Session 53, task M: a review of the day's merged work (hunts 53d, 53e, 53j).

- ``train --split repetitions``' line of the pieces it skips called every piece that shows
  no person (or no torso) a clip, as a clip with no repetition is kept whole; but a clip with
  the hips out of view is cut into repetitions counted from the arms (hunt 52g), each piece
  then showing no torso: a hips-out recording of three shoulder abductions was "skipped 3
  clips that show no torso ...: nohips.npz (3)".
- ``compare`` of clips every one of which is left out (the hips out of view, no joint at
  all, too short) said "no clip shows a person for as long as one movement can last",
  though the notes name clips with the hips out of view as showing no torso (hunt 53j).
- ``watch``: a live source's rate measured with a drop-out left out (hunt 53d) left out a
  fall of the rate too: each slow interval was a "pause" after which the stream came on
  no faster than a quarter below the median (the lower bound alone), and a fall from 60
  to 15 fps was measured near 60, no change of rate, until the slow intervals took half
  the window's time.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cbr.evaluation.data import prepare
from cbr.evaluation.settings import CompareSettings
from features.clips import Clip
from features.errors import DataError
from posecbr.commands.train import _skipped
from posecbr.commands.watch import BURST_S, CHANGE_WINDOW_S, RATE_CHANGE, _frame_rate
from tests.test_hunt53j import _abduction, _hips_out

NO_HIPS = "shows no torso (no frame shows its left hip, right hip)"


def test_repetitions_cut_from_a_clip_with_the_hips_out_are_named_repetitions() -> None:
    """Three repetitions cut from one clip with the hips out of view (``posecbr reps`` of
    it counts 3, from the arms alone), and a clip with no joint at all, kept whole (it has no
    repetition): the three are repetitions, the one a clip, as the line saying how the clips
    were cut names them ("cut 7 clips into 9 repetitions; 1 clip without a repetition kept
    whole (blank.npz)")."""
    nobody = ["nohips.npz"] * 3 + ["blank.npz"]
    line = _skipped(nobody, [], "repetitions", {"blank.npz"}, [NO_HIPS] * 3 + [""])
    assert line == (
        "skipped 3 repetitions that show no torso (no frame shows its left hip, right hip):"
        " nohips.npz (3)\nskipped 1 clip that shows no person: blank.npz"
    )


def test_compare_of_clips_all_left_out_says_why_in_the_notes_words() -> None:
    """Four clips: two shoulder abductions with the hips out of view (shoulders and arms
    seen), one with no joint at all, one of its first 6 frames (0.2 s at 30 fps, shorter
    than one movement can be, 0.4 s): none is compared, and the refusal says why each is
    left out, in the words of the notes that name them when some are left (hunt 53j). It
    said "no clip shows a person for as long as one movement can last", of clips that show
    a person's shoulders and arms."""
    seq = _abduction("s01_e01")
    no_hips = [_hips_out(_abduction(f"s02_e0{e}"), f"nohips{e}.npz") for e in (1, 2)]
    blank = dataclasses.replace(
        seq, positions=np.full_like(seq.positions, np.nan), source="blank.npz"
    )
    short = dataclasses.replace(seq, positions=seq.positions[:6], source="short.npz")
    clips = [
        Clip(s, label, "s01") for s, label in zip([*no_hips, blank, short], "aabb", strict=True)
    ]
    with pytest.raises(DataError) as refused:
        prepare(clips, CompareSettings(), "data")
    assert str(refused.value) == (
        "data: no clip to compare: left out 2 clips that show no torso (no frame shows its"
        " left hip, right hip): nohips1.npz, nohips2.npz; left out 1 clip that shows no"
        " person: blank.npz; left out 1 clip shorter than one movement can be (0.4 s):"
        " short.npz"
    )


def test_a_fall_of_the_rate_is_no_drop_out() -> None:
    """60 fps for 0.4 s, then 15 fps for 0.2 s (the camera slowed down: no frame lost): the
    rate over the latest frames, as a change of rate is measured, is their count over their
    span (hand: 24 + 3 intervals in 0.6 s, 45 fps), a change of rate from 60 by more than
    RATE_CHANGE. Hunt 53d's rule took the first two slow intervals for drop-outs (the
    intervals after each as slow, no faster than the median) and measured 25 intervals in
    0.467 s, 53.6 fps: no change. A drop-out (60 fps, a 0.3-s pause, 60 fps: the frames
    after at the median pace) is still left out: 60 fps."""
    fell = np.concatenate([np.arange(25) / 60.0, 0.4 + np.arange(1, 4) / 15.0])
    rate = _frame_rate(fell.tolist(), CHANGE_WINDOW_S, BURST_S)
    assert rate == pytest.approx(27 / 0.6)
    assert abs(rate / 60.0 - 1.0) > RATE_CHANGE
    dropped = np.concatenate([np.arange(31) / 60.0, 0.8 + np.arange(19) / 60.0])
    assert _frame_rate(dropped.tolist(), CHANGE_WINDOW_S, BURST_S) == pytest.approx(60.0)
