"""Session 53, task M: a review of the day's merged work (hunts 53d, 53e, 53j).

- ``train --split repetitions``' line of the pieces it skips called every piece that shows
  no person (or no torso) a clip, as a clip with no repetition is kept whole; but a clip with
  the hips out of view is cut into repetitions counted from the arms (hunt 52g), each piece
  then showing no torso: a hips-out recording of three shoulder abductions was "skipped 3
  clips that show no torso ...: nohips.npz (3)".
- ``compare`` of clips every one of which is left out (the hips out of view, no joint at
  all, too short) said "no clip shows a person for as long as one movement can last",
  though the notes name clips with the hips out of view as showing no torso (hunt 53j).
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
