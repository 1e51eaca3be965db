"""Session 53, task M: a review of the day's merged work (hunts 53d, 53e, 53j).

- ``train --split repetitions``' line of the pieces it skips called every piece that shows
  no person (or no torso) a clip, as a clip with no repetition is kept whole; but a clip with
  the hips out of view is cut into repetitions counted from the arms (hunt 52g), each piece
  then showing no torso: a hips-out recording of three shoulder abductions was "skipped 3
  clips that show no torso ...: nohips.npz (3)".
"""

from __future__ import annotations

from posecbr.commands.train import _skipped

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
