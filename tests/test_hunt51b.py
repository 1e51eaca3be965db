"""Hunt 51b: a command line missing several required arguments names them all; a repetition
the person is lost from view in before it is finished.

``posecbr segment`` given nothing said only that ``--db`` was missing (its RECORDING is
optional to argparse, for ``--truth``, and was checked after ``--db``): the user added
``--db`` and was then told of RECORDING. Every command given nothing now names everything
its usage asks for, in one line, exit 2.

A squat's way down, then nobody in view, counted 1 in ``segment`` and ``watch`` (and, after
whole squats, one more in ``reps``) where a person says 0: no repetition was finished. The
person lost for good is now as the recording's end, and a stretch with nobody in view
between two that show the person is counted across (a squat lost on the way down and seen
again on the way up is one repetition, counted once), in ``reps``, ``segment`` and
``watch``; on a real HDM05 squat.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from features.poses import PoseSequence
from posecbr.cli import build_parser, main
from tests.test_empty_arguments import _commands
from tests.test_hunt50c import seen_lost_back
from tests.test_segment import classifier, names, recordings  # noqa: F401 - the fixtures


def _asked(usage: str, prog: str) -> set[str]:
    """What the usage line of command ``prog`` asks for, read from its text: the words
    outside brackets, an option by its name (its value's word after it dropped), an
    argument by its own word."""
    words = usage.split(":", 1)[1].split()[len(prog.split()) :]
    text = " ".join(words)
    while re.search(r"\[[^\[\]]*\]", text):  # innermost [optional] first: they nest
        text = re.sub(r"\[[^\[\]]*\]", "", text)
    out: set[str] = set()
    tokens = iter(t for t in text.split() if t != "...")
    for token in tokens:
        out.add(token)
        if token.startswith("-"):
            next(tokens, None)  # the option's value
    return out


def _said(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    capsys.readouterr()
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    return err.rstrip("\n")


def test_segment_given_nothing_names_the_recording_and_the_case_base(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Given nothing, or options that are neither (``--json``, a label file), ``segment``
    names both; given the one, the other."""
    both = (
        "posecbr segment: error: the following arguments are required: RECORDING, --db;"
        " see posecbr segment --help"
    )
    assert _said(["segment"], capsys) == both
    assert _said(["segment", "--json"], capsys) == both
    assert _said(["segment", "--truth", "labels.txt"], capsys) == both
    assert _said(["segment", "--db", "cb.sqlite"], capsys) == both.replace(", --db", "")
    assert _said(["segment", "walk.npz"], capsys) == both.replace("RECORDING, ", "")


def test_every_command_given_nothing_names_all_its_usage_asks_for(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Each command (and ``casebase`` action) whose usage asks for something, given nothing,
    names exactly what its usage line asks for (read from the usage's text, not from the
    parser's actions)."""
    checked = 0
    for words, sub in _commands(build_parser()):
        prog = "posecbr " + " ".join(words)
        asked = _asked(sub.format_usage(), prog)
        if not asked:  # demo, thresholds: nothing to give
            continue
        line = _said(list(words), capsys)
        head = f"{prog}: error: the following arguments are required: "
        assert line.startswith(head) and line.endswith(f"; see {prog} --help"), line
        named = line[len(head) : -len(f"; see {prog} --help")].split(", ")
        assert set(named) == asked and len(named) == len(asked), (words, named, asked)
        checked += 1
    assert checked >= 17  # 12 commands and 6 casebase actions ask for something


# --- the person lost from view part-way through a repetition (real motion capture) ---------

SQUAT = ("hdm05", "train", "10", "HDM_bd_squat1Reps_001_120.amc")
FPS = 30.0  # every 4th of the take's 120 fps frames: a webcam's rate, a quarter the frames
WHOLE = (0.0, 1.17)  # the whole take, in seconds
DOWN = (0.0, 0.5)  # its first 0.5 s: standing, then the way down, short of the bottom


@pytest.fixture(scope="module")
def squat(shared_data: Path) -> PoseSequence:
    """One real squat (HDM05, actor bd): standing, down to the bottom at 0.63 s, up, standing
    again at 1.1 s (140 frames at 120 fps; the bottom read from the hips' height, not from
    the counter), at 30 fps."""
    from features.datasets import load_clip

    seq = load_clip(shared_data.joinpath(*SQUAT)).to_canonical()
    out = PoseSequence(seq.positions[::4], seq.joint_names, FPS)
    # the take as the tests read it: the hips lowest at 0.6-0.7 s, 0.25 m or more below where
    # they stand at its start and end, and at 0.5 s on the way down, short of the bottom
    hips = np.nanmean(out.joints(["left_hip", "right_hip"])[:, :, 1], axis=1)
    assert 0.55 <= int(np.argmin(hips)) / FPS <= 0.7
    assert hips[0] - hips.min() > 0.25 and hips[-1] - hips.min() > 0.25
    assert hips[int(DOWN[1] * FPS) - 1] - hips.min() > 0.05
    return out


def _joined(squat: PoseSequence, *parts: tuple[float, float] | float) -> PoseSequence:
    """The squat's frames from ``a`` to ``b`` seconds for each pair ``(a, b)`` and, for each
    number, that many seconds in which nobody is seen (every joint NaN), one after another."""
    rows = []
    for part in parts:
        if isinstance(part, tuple):
            rows.append(squat.positions[int(round(part[0] * FPS)) : int(round(part[1] * FPS))])
        else:
            rows.append(np.full((int(round(part * FPS)), *squat.positions.shape[1:]), np.nan))
    return PoseSequence(np.concatenate(rows), squat.joint_names, FPS)


def test_reps_counts_no_more_when_the_person_is_lost_than_when_the_clip_ends(
    squat: PoseSequence,
) -> None:
    """Two squats, then the way down of a third, then nobody in view for 1 s: by hand two
    repetitions (the third is not finished), as the same frames without the 1 s of nobody
    count. Before: 3 (the posture last seen held through the 1 s and smoothed into it, the
    far point cut off there counted beside the whole ones)."""
    from posecbr.commands.reps import _count

    ended = _count(_joined(squat, WHOLE, WHOLE, DOWN))
    lost = _count(_joined(squat, WHOLE, WHOLE, DOWN, 1.0))
    assert ended.count == 2
    assert lost.count == 2
    assert [r.peak_frame for r in lost.repetitions] == [r.peak_frame for r in ended.repetitions]


def test_segment_counts_no_repetition_in_the_way_down_before_nobody_in_view(
    squat: PoseSequence,
) -> None:
    """The first 0.5 s of the squat (the way down), then nobody in view for 2 s: no
    repetition was finished, 0 (as ``reps`` counts it: "no whole repetition"). Counted as
    ``segment`` counts its segments (the squat's frames, then the stretch with nobody in
    view, :func:`cbr.segmentation.counted_segments`). Before: 1, the far point where the
    person was lost kept by the segment before the stretch."""
    from cbr.segmentation import counted_segments
    from features.repetitions import movement_signals

    seq = _joined(squat, DOWN, 2.0)
    cut = int(DOWN[1] * FPS)
    found = counted_segments(movement_signals(seq), [(0, cut), (cut, seq.n_frames)],
                             seq.n_frames, [False, True])  # fmt: skip
    assert [len(r) for r in found] == [0, 0]


def test_segment_counts_a_squat_seen_again_on_the_way_up_once(squat: PoseSequence) -> None:
    """The way down of the squat, nobody in view for 1 s, then the rest of the squat (on
    down to the bottom and up) and one more: by hand 2, one in the frames after the stretch
    (as ``reps`` counts it). Before: 3, the way down counted in the segment before the
    stretch and again after it."""
    from cbr.segmentation import counted_segments
    from features.repetitions import movement_signals

    seq = _joined(squat, DOWN, 1.0, (DOWN[1], WHOLE[1]), WHOLE)
    lost, back = int(DOWN[1] * FPS), int((DOWN[1] + 1.0) * FPS)
    bounds = [(0, lost), (lost, back), (back, seq.n_frames)]
    found = counted_segments(movement_signals(seq), bounds, seq.n_frames, [False, True, False])
    assert [len(r) for r in found] == [0, 0, 2]


@pytest.mark.parametrize(
    ("parts", "want"),
    [
        # the way down, then nobody for the last 4 s: 0 (was 1)
        ((DOWN, 4.0), 0),
        # two squats, the way down of a third, nobody for the last 2 s: 2 (was 3)
        ((WHOLE, WHOLE, DOWN, 2.0), 2),
        # two squats, the way down, nobody 1 s, the rest of that squat, one more: 4 (was 5)
        ((WHOLE, WHOLE, DOWN, 1.0, (DOWN[1], WHOLE[1]), WHOLE), 4),
    ],
)
def test_watch_counts_no_repetition_the_person_was_lost_in_before_it_was_finished(
    squat: PoseSequence, parts: tuple[tuple[float, float] | float, ...], want: int
) -> None:
    """Streamed through ``watch``'s live segmenter (one label throughout): the squats
    finished, by hand; a stretch with nobody in view a segment of its own, counted 0."""
    from tests.test_hunt36l import _live_segments

    seq = _joined(squat, *parts)
    out = _live_segments(seq.positions, FPS)
    assert sum(s.repetitions for s in out) == want
    assert all(s.repetitions == 0 for s in out if s.label is None)


def test_a_squats_way_down_lost_before_other_exercise_counts_none(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
    classifier: CaseBaseClassifier,  # noqa: F811
) -> None:
    """At 30 fps: CMU 13_30's squats' first 0.5 s (frames 0-15: the way down), 3 s with
    every joint missing (15-105), its knee raises (6.7-11.8 s: 105-258), as
    tests/test_hunt50c.py builds it. By hand: no squat finished, 0; the knee raises 4. The
    stretch with nobody in view between two activities is no squat going on out of sight:
    the squat's segment ends as at a recording's end. Before: 1 in ``segment`` and
    ``watch`` (the far point where the person was lost kept, or the return filled in across
    the 3 s)."""
    offline, watched = seen_lost_back(classifier, recordings["13_30"])
    assert [(s.start_frame, len(s.repetitions)) for s in offline] == [(0, 0), (15, 0), (105, 4)]
    assert [(s.start_frame, s.repetitions) for s in watched] == [(0, 0), (15, 0), (105, 4)]
