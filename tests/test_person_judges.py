"""One rule for how far a recording's person lies from every case, which ``segment`` and
``watch`` share (:func:`cbr.unknown.person_judges`, hunt 40a): every window is judged by the
person as the fixed windows that end by its own end show them, what a stream has seen when
the window is solved. Before, ``segment`` read the whole recording and ``watch`` judged each
window again by the windows seen when its hop was decided, so a recording's first windows
could be known to one and unknown to the other."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr import unknown
from cbr.unknown import ActivityMargin, Offset, person_judges
from posecbr.cli import main
from tests.test_person_jump import _leave_video
from tests.test_watch import case_base  # noqa: F401 (a fixture)


def _judge(reach: float) -> ActivityMargin:
    """A margin judge of two activities whose held-out cases' nearest tenth lies ``reach``
    from their nearest case (inf: a case base that holds out people)."""
    return ActivityMargin(
        thresholds=(0.8, 0.8),
        pooled=0.8,
        basis="time" if math.isfinite(reach) else "subject",
        known=20,
        reach=reach,
    )


def test_each_window_is_judged_by_the_fixed_windows_that_end_by_its_end() -> None:
    """Fixed windows ending at frames 90, 60 and 75 (given out of order) lie 2 (an activity
    out of reach: inf), 5 and 3 from their nearest case; the case base's own held-out cases
    1 (reach). By hand (the tenth quantile less the reach, times n / (n + 8)):
    - a window ending at 50: no fixed window yet, no offset: 0;
    - at 60: {5}: (5 - 1) * 1 / 9 = 4 / 9;
    - at 75 and at 80: {5, 3}: the tenth quantile 3 + 0.1 * (5 - 3) = 3.2, (3.2 - 1) * 2 / 10
      = 0.44;
    - at 90: the same (an infinite distance says nothing of the person)."""
    judge = _judge(1.0)
    nearest = np.array([math.inf, 5.0, 3.0])
    ends = np.array([90, 60, 75])
    got = person_judges(judge, nearest, ends, np.array([50, 60, 75, 80, 90]))
    assert all(isinstance(j, Offset) and j.judge is judge for j in got)
    offsets = [j.offset for j in got]  # type: ignore[attr-defined]
    assert offsets == pytest.approx([0.0, 4 / 9, 0.44, 0.44, 0.44])


def test_the_person_is_read_from_the_latest_windows_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """At most the latest PERSON_WINDOWS fixed windows at a finite distance (here 2): by the
    window ending at 40, of {3, 1} (the one at 5 forgotten; the infinite one not counted):
    the tenth quantile 1.2, (1.2 - 1) * 2 / 10 = 0.04; by 20, of {5, 3}: 0.44 as above."""
    monkeypatch.setattr(unknown, "PERSON_WINDOWS", 2)
    got = person_judges(
        _judge(1.0),
        np.array([5.0, 3.0, math.inf, 1.0]),
        np.array([10, 20, 30, 40]),
        np.array([40, 20]),
    )
    assert [j.offset for j in got] == pytest.approx([0.04, 0.44])  # type: ignore[attr-defined]


def test_a_case_base_of_several_people_takes_no_offset() -> None:
    """A case base that holds out people (reach inf): its held-out cases already lie as far
    as a new person's, every window is judged by the judge as it is."""
    judge = _judge(math.inf)
    got = person_judges(judge, np.array([5.0]), np.array([60]), np.array([60, 90]))
    assert got == [judge, judge]


def test_segment_and_watch_segment_a_video_of_movements_the_case_base_lacks_alike(
    shared_data: Path,
    case_base: Path,  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """tests/test_person_jump.py's video (a reverse lunge at half size, then a side-lying leg
    raise beside it, the pose jumping to it at 5.00 s), to a case base of CMU 13_29, which
    holds neither movement: unknown throughout, in both commands, the same segments and
    repetitions. ``segment`` gave KneeRaise for the first 1.2 s (0 repetitions), then
    unknown (1), judging its first windows by the person as the whole recording showed them;
    ``watch`` unknown throughout (2), by the windows seen by then."""
    video = _leave_video(shared_data, tmp_path / "leaves.avi")
    capsys.readouterr()
    assert main(["segment", str(video), "--db", str(case_base), "--json"]) == 0
    offline = json.loads(capsys.readouterr().out)["segments"]
    assert main(["watch", str(video), "--db", str(case_base), "--speed", "0"]) == 0
    watched = [json.loads(line) for line in capsys.readouterr().out.splitlines()]

    def spans(segments: list[dict[str, Any]]) -> list[tuple[Any, ...]]:
        keys = ("start_frame", "end_frame", "label", "repetitions")
        return [tuple(d[k] for k in keys) for d in segments]

    assert {d["label"] for d in offline} == {None}, spans(offline)
    assert spans(watched) == spans(offline)
