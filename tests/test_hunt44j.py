"""Hunt 44j: ``train --split repetitions`` of a movement that alternates sides.

``reps`` counts such a movement one repetition per side's turn, so a jogging step lasts
0.3-0.4 s; every case must last the shortest period (``MIN_PERIOD_S``, 0.4 s), and the
steps were cut one per case and then skipped as too short: CMU subject 13's jog stretches
(13_29 and 13_30 as training recordings) kept 3 of their 10 steps. Now an alternating
movement whose turns are shorter than a repetition can be (their median) is cut in whole
left-and-right cycles (``features.repetitions.case_spans``): a turn and the next together,
a short turn left over at the end joined to the cycle before. Slower ones (knee raises,
twists) keep a case per turn.

The jog here is built by hand: one knee lifted at a time, the thigh 70 degrees forward at
its height, each turn 9 frames at 30 fps (0.3 s) starting where the other leg is back down,
so turn k runs over frames 9k to 9k + 9 and cycle c (turns 2c and 2c + 1) over frames 18c
to 18c + 18.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.poses import PoseSequence
from features.repetitions import MIN_PERIOD_S, Repetition, RepetitionCount, case_spans
from tests.bodies import rot_x, rotate, standing, to_sequence
from tests.moves import leg, shin

FPS = 30.0
TURN = 9
"""Frames of one side's turn (0.3 s at 30 fps, shorter than MIN_PERIOD_S)."""


def _jog(turns: int) -> PoseSequence:
    """``turns`` knee lifts, left and right in turn, each over ``TURN`` frames (the thigh up
    to 70 degrees and back, the knee bending 1.3 times as far), plus the frame after the
    last, both feet down."""
    frames = []
    for f in range(turns * TURN + 1):
        b = standing()
        k, u = divmod(f, TURN)
        side = ("left", "right")[k % 2]
        deg = 70.0 * np.sin(np.pi * u / TURN)
        b = rotate(b, leg(side), rot_x(-deg), b[f"{side}_hip"])
        b = rotate(b, shin(side), rot_x(1.3 * deg), b[f"{side}_knee"])
        frames.append(b)
    return to_sequence(*frames, fps=FPS)


def _frames(seq: PoseSequence) -> tuple[int, int]:
    a = int(seq.metadata.get("frame_offset", 0))
    return a, a + seq.n_frames


@pytest.mark.parametrize(
    ("turns", "expected"),
    [
        # eight turns: four cycles; the last ends with the clip (frame 72 is its last)
        (8, [(0, 18), (18, 36), (36, 54), (54, 73)]),
        # nine: the ninth turn (0.3 s) joins the cycle before it
        (9, [(0, 18), (18, 36), (36, 54), (54, 82)]),
    ],
)
def test_split_repetitions_of_a_jog_cuts_one_case_per_left_and_right_cycle(
    turns: int, expected: list[tuple[int, int]]
) -> None:
    """Before, the cut gave one piece per turn, 9 frames each, all shorter than a case may
    be (``train`` skipped every one)."""
    from cbr.training import cut

    assert TURN / FPS < MIN_PERIOD_S  # one turn alone could be no case
    pieces, labels = cut([_jog(turns)], ["jog"], "repetitions")
    assert [_frames(p) for p in pieces] == expected
    assert labels == ["jog"] * len(expected)
    assert all(p.n_frames >= MIN_PERIOD_S * FPS for p in pieces)


def _count(spans: list[tuple[int, int]], alternating: bool) -> RepetitionCount:
    reps = tuple(Repetition(a, b, (a + b) // 2) for a, b in spans)
    return RepetitionCount(reps, FPS, 100, 0.6, 0.9, alternating, ("left_knee",))


def test_case_spans_pair_turns_only_where_they_follow_one_another() -> None:
    """Turns of 10 frames (0.33 s at 30 fps, under 12 frames = MIN_PERIOD_S): a run of three,
    then, after a gap (a stretch that shows nobody), a run of two. The third of the first
    run joins the cycle before it; the run after the gap is a cycle of its own."""
    turns = [(0, 10), (10, 20), (20, 30), (40, 50), (50, 60)]
    assert case_spans(_count(turns, True)) == [(0, 30, 3), (40, 60, 2)]


def test_a_turn_left_over_that_lasts_a_period_is_a_case_of_its_own() -> None:
    """The leftover turn of 15 frames (0.5 s) is as long as a case may be: it stays alone."""
    turns = [(0, 10), (10, 20), (20, 35)]
    assert case_spans(_count(turns, True)) == [(0, 20, 2), (20, 35, 1)]


def test_case_spans_keep_the_slower_turns_of_an_alternating_movement_one_per_turn() -> None:
    """Knee raises of 30 frames a side (1 s), the first cut short by the clip's start (10
    frames): the median turn lasts a repetition, each turn is a case of its own, as before
    (the short one too, which ``train`` skips as it did)."""
    turns = [(0, 10), (10, 40), (40, 70), (70, 100)]
    assert case_spans(_count(turns, True)) == [(0, 10, 1), (10, 40, 1), (40, 70, 1), (70, 100, 1)]


def test_case_spans_keep_a_movement_that_does_not_alternate_one_per_repetition() -> None:
    """Squats of 10 frames each (too short to be cases, as before): each stays one piece."""
    reps = [(0, 10), (10, 20), (20, 30)]
    assert case_spans(_count(reps, False)) == [(0, 10, 1), (10, 20, 1), (20, 30, 1)]


def test_train_and_classify_a_jog_cut_into_cycles(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train --split repetitions`` of the eight-turn jog beside a squat clip: the jog gives
    its 4 cycles, none skipped (before: 8 steps of 0.30 s, every one skipped, and ``train``
    refused: "only one activity ('squat') is left to learn from"). ``classify`` of one
    cycle (2 turns, frames 0-17) says nothing of "several repetitions": it is one case's
    worth."""
    from features.poses import save_pose
    from posecbr.cli import main
    from tests.moves import clip

    save_pose(_jog(8), tmp_path / "jog.npz")
    save_pose(clip("squat", seconds=6.0), tmp_path / "squat.npz")
    (tmp_path / "train.csv").write_text(
        "path,label\njog.npz,jog\nsquat.npz,squat\n", encoding="utf-8"
    )
    db = tmp_path / "cb.sqlite"
    capsys.readouterr()
    assert main(["train", str(tmp_path / "train.csv"), "--split", "repetitions",
                 "--db", str(db)]) == 0  # fmt: skip
    out = capsys.readouterr()
    assert "4 left-and-right cycles of a movement that alternates sides" in out.err
    assert "skipped" not in out.out + out.err
    assert [line.split() for line in out.out.splitlines() if line.strip().endswith("jog")] == [
        ["4", "jog"]
    ]
    (tmp_path / "one.csv").write_text("path,label,start,end\njog.npz,jog,0,18\n", encoding="utf-8")
    assert main(["classify", str(tmp_path / "one.csv"), "--db", str(db)]) == 0
    out = capsys.readouterr()
    assert "several" not in out.err
    assert "jog.npz frames 0-17" in out.out
