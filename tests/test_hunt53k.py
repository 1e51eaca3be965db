"""Hunt 53k: ``watch --split repetitions`` judged each repetition in the frame loop, every
frame behind it waiting for the verdict's solve and explanation (13-30 ms of CPU; 125 ms at
load 16 before the counterfactual's search was sped up). The verdicts are now judged on a
thread of their own (:class:`cbr.live_verdicts.RepetitionVerdicts`'s ``background``): the
frames go on meanwhile, each verdict is given once judged, in the order asked for, and
``watch`` prints its line before any line after it (the lines as before, in the same order).
"""

from __future__ import annotations

import json
import threading
from types import SimpleNamespace
from typing import Any

import pytest

import cbr.live_verdicts as live_verdicts
from cbr.live_verdicts import RepetitionVerdicts
from posecbr.commands.watch import Watcher

SPANS = ((10, 40), (40, 70), (70, 100))  # three repetitions counted, the last long finished


def _slow_first(release: threading.Event, threads: list[int]) -> Any:
    """``classify_clip``'s stand-in: judges a piece (its frames, as the live stand-in cuts
    it) on whatever thread calls it, the first repetition only once ``release`` is set."""

    def judged(stored: Any, piece: tuple[int, int], truth: Any, target: str) -> Any:
        threads.append(threading.get_ident())
        if piece == SPANS[0]:
            assert release.wait(10)
        return SimpleNamespace(label=f"{piece}", to_dict=lambda: {"label": f"{piece}"})

    return judged


def _live() -> SimpleNamespace:
    """A live segmenter's stand-in at 30 fps, 200 frames pushed, counting :data:`SPANS`."""
    return SimpleNamespace(
        fps=30.0, hops=0, n=200, clip=lambda a, b: (a, b), repetitions_from=lambda start: SPANS
    )


def test_verdicts_judged_on_their_own_thread_are_given_in_order(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Three repetitions finished at one hop, the first slow to judge: ``update`` returns at
    once with none given (the frame loop goes on), the count going on as before from the
    start of the one before the last (40) after the last's end (100); the next hop's count
    asks for none again and gives none while the first is judged; once it is, all three in
    the order asked for, numbered 1-3, each judged on one thread that is not the caller's."""
    release, threads = threading.Event(), []
    monkeypatch.setattr(live_verdicts, "classify_clip", _slow_first(release, threads))
    live = _live()
    verdicts = RepetitionVerdicts(SimpleNamespace(target="correct"), live, background=True)  # type: ignore[arg-type]
    try:
        assert verdicts.update() == []
        assert (verdicts.anchor, verdicts.judged_to) == (40, 100)
        live.hops = 1
        assert verdicts.update() == [] and verdicts.given == []
        release.set()
        given = verdicts.ready(wait=True)
    finally:
        release.set()
        verdicts.close()
    assert [(v.number, v.start_frame, v.end_frame, v.label) for v in given] == [
        (1, 10, 40, "(10, 40)"),
        (2, 40, 70, "(40, 70)"),
        (3, 70, 100, "(70, 100)"),
    ]
    assert verdicts.given == given and not verdicts.asked
    assert len(threads) == 3 and set(threads) != {threading.get_ident()}
    assert len(set(threads)) == 1


def test_watch_prints_verdicts_being_judged_before_a_later_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch``'s segment line finished while the three verdicts asked for before it are
    still being judged: the three repetition lines first, in order, then the segment's, as
    when each verdict held up the frame loop until judged."""
    release, threads = threading.Event(), []
    monkeypatch.setattr(live_verdicts, "classify_clip", _slow_first(release, threads))
    args = SimpleNamespace(progress=None, source="0", out=None, show=False)
    watcher = Watcher(None, None, args, 30.0)  # type: ignore[arg-type]
    watcher.verdicts = RepetitionVerdicts(
        SimpleNamespace(target="correct"), _live(), background=True
    )  # type: ignore[arg-type]
    timer = threading.Timer(0.1, release.set)
    try:
        watcher._verdict_lines(watcher.verdicts.update())
        assert capsys.readouterr().out == ""  # none judged yet: none printed
        timer.start()
        watcher._print_line({"label": "squat"}, "segment")
    finally:
        release.set()
        timer.cancel()
        watcher.verdicts.close()
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert lines == [
        {"repetition": 1, "start_s": 0.333, "end_s": 1.333, "label": "(10, 40)"},
        {"repetition": 2, "start_s": 1.333, "end_s": 2.333, "label": "(40, 70)"},
        {"repetition": 3, "start_s": 2.333, "end_s": 3.333, "label": "(70, 100)"},
        {"label": "squat"},
    ]
