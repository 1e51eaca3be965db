"""Each repetition of a live stream judged as it finishes (``posecbr watch --split
repetitions``): the live counterpart of ``classify --split repetitions``.

The repetitions are counted over the stream as ``classify --split repetitions`` counts a
recording, whatever its segments (:meth:`cbr.live.LiveSegmenter.repetitions_from`: not cut
where the segments change, which with a repetition check are 2-s windows judged correct or
incorrect, and would cut a repetition in two), each judged alone by the stored classifier
on its own frames (:func:`cbr.classification.classify_clip`, the solve and explanation
``classify`` gives each piece it cuts): where the two cut a repetition at the same frames,
the verdict is the same.

A repetition is judged once it is finished and its frames are final: when the count holds
another repetition after it and :data:`SETTLE_S` of frames have come after its end (the
count reads the frames either side of a repetition, and its end moves by a frame or two as
the next one comes), or, with none after it, once as many frames as it lasts have come
after it (the person stopped), or when the stream ends. Each verdict is given once and
never revised: a repetition is judged from the end of the last one judged on (the count
going on from the start of the one before it, as context), so no later count judges its
frames again. (Judged as soon as the count first held it, 30 of 40
repetitions of two joined sessions were judged again on frames a frame or two off, and its
end was not yet known: the count's last repetition ends where the frames end.)

A verdict (a solve and an explanation: some 13-30 ms of CPU) can be judged on a thread of its
own (``background``): the frame loop goes on meanwhile, and :meth:`RepetitionVerdicts.update`
gives the verdicts whose judging has finished, in the order they were asked for
(:meth:`RepetitionVerdicts.ready`). Which repetitions are judged, and where the count goes on
from, do not depend on any verdict: only when each is given changes.
"""

from __future__ import annotations

from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, NamedTuple

from .classification import Classification, classify_clip
from .live import LiveSegmenter
from .stored import StoredClassifier

SETTLE_S = 0.5
"""A repetition with another counted after it is judged once this many seconds of frames have
come after its end."""

REACH_S = 30.0
"""The count goes back at most this many seconds (the end of the last repetition judged, else
this far): a count once a hop stays short however long no repetition is found."""


@dataclass(frozen=True)
class Verdict:
    """One repetition's verdict: ``number`` (1, 2, ... in the stream's order), its stream
    frames [start_frame, end_frame), counted at ``fps`` (the segmenter's that judged it: a
    stream watched again at another rate keeps the verdicts given before), and its
    classification (``judged``)."""

    number: int
    start_frame: int
    end_frame: int
    judged: Classification
    fps: float

    @property
    def label(self) -> str | None:
        return self.judged.label

    def to_dict(self) -> dict[str, Any]:
        """One of ``watch --split repetitions``' repetition lines: ``repetition`` (its
        number), ``start_s`` and ``end_s``, then the record ``classify --split repetitions
        --json`` gives the same piece (``start_frame``, ``end_frame``, ``label``,
        ``confidence``, ``text``, ...)."""
        return {
            "repetition": self.number,
            "start_s": round(self.start_frame / self.fps, 3),
            "end_s": round(self.end_frame / self.fps, 3),
            **self.judged.to_dict(),
        }


class _Asked(NamedTuple):
    """A verdict asked for: its number, stream frames [start, end), the rate they count at,
    and its classification, judged or being judged."""

    number: int
    start_frame: int
    end_frame: int
    fps: float
    judged: Future[Classification]


class RepetitionVerdicts:
    """The verdicts of a stream's repetitions (module docstring): ``stored``, the case base
    that judges them (``load_classifier``'s; its ``target``: ``correct`` for a repetition
    check), ``live`` the segmenter whose frames are counted. Call :meth:`update` after every
    frame pushed, and with ``ended`` True after :meth:`LiveSegmenter.finish`; each returns
    the verdicts given then. ``background``: each repetition is judged on a thread of its own
    (module docstring): :meth:`update` gives those judged by then, :meth:`ready` with
    ``wait`` every one asked for; :meth:`close` ends the thread (``update`` with ``ended``
    does)."""

    def __init__(
        self,
        stored: StoredClassifier,
        live: LiveSegmenter,
        before: RepetitionVerdicts | None = None,
        background: bool = False,
    ) -> None:
        self.stored, self.live = stored, live
        self.given: list[Verdict] = []
        self.asked: deque[_Asked] = deque()  # asked for and not yet given, in order
        self.last_asked: tuple[int, float] | None = None  # the latest's start frame and rate
        self.anchor = 0  # the count goes on from here: the start of the one before the last
        self.judged_to = 0  # the end of the last judged: a repetition is judged from there on
        self.hops = -1  # the hop at which the count was last read
        self.pool = ThreadPoolExecutor(1, "verdicts") if background else None
        if before is not None:  # the stream watched again at another rate (watch's re-make):
            # its verdicts stand, numbered on, the count going on from the same time; those
            # still being judged are given by this one
            self.given, self.asked = list(before.given), before.asked
            self.last_asked = before.last_asked
            self.anchor = self._frame_of(before.anchor, before.live.fps)
            self.judged_to = self._frame_of(before.judged_to, before.live.fps)
            before.close()

    @property
    def last(self) -> Verdict | None:
        """The latest verdict given (drawn on the frames)."""
        return self.given[-1] if self.given else None

    def update(self, ended: bool = False) -> list[Verdict]:
        if not ended and self.live.hops == self.hops:  # the count is read once a hop
            return self.ready()
        self.hops = self.live.hops
        # a stretch without repetitions is not counted again without end
        self.anchor = max(self.anchor, self.live.n - int(REACH_S * self.live.fps))
        spans = tuple(s for s in self.live.repetitions_from(self.anchor) if self._new(s))
        for span in spans if ended else self._finished(spans):
            self._ask(span)
        if not ended:
            return self.ready()
        given = self.ready(wait=True)
        self.close()  # the stream has ended: nothing more to judge
        return given

    def ready(self, wait: bool = False) -> list[Verdict]:
        """The verdicts asked for and not yet given whose judging has finished, in the order
        asked for (one still being judged holds back those after it); ``wait``: every one,
        waited for. A judging that failed raises its error here."""
        out: list[Verdict] = []
        while self.asked and (wait or self.asked[0].judged.done()):
            a = self.asked.popleft()
            out.append(Verdict(a.number, a.start_frame, a.end_frame, a.judged.result(), a.fps))
            self.given.append(out[-1])
        return out

    def close(self) -> None:
        """End the thread that judges (``background``) once it has judged what it was asked."""
        if self.pool is not None:
            self.pool.shutdown()
            self.pool = None

    def _ask(self, span: tuple[int, int]) -> None:
        """Have repetition ``span`` judged (on :attr:`pool`'s thread, if any); the count goes
        on after it (:meth:`_go_on`)."""
        piece = self.live.clip(*span)
        judged: Future[Classification]
        if self.pool is not None:
            judged = self.pool.submit(classify_clip, self.stored, piece, None, self.stored.target)
        else:
            judged = Future()
            judged.set_result(classify_clip(self.stored, piece, None, self.stored.target))
        number = len(self.given) + len(self.asked) + 1
        self.asked.append(_Asked(number, *span, float(self.live.fps), judged))
        self._go_on(span)

    def _new(self, span: tuple[int, int]) -> bool:
        """Whether ``span`` is a repetition not yet judged: at most half of it lies before
        the end of the last one judged (the count from that one's start finds it again, and
        may find the next beginning a frame or two before its end)."""
        return 2 * (self.judged_to - span[0]) < span[1] - span[0]

    def _finished(self, spans: tuple[tuple[int, int], ...]) -> tuple[tuple[int, int], ...]:
        """Of ``spans``, the count from :attr:`anchor`, those to judge now (module
        docstring)."""
        n = self.live.n
        settle = SETTLE_S * self.live.fps
        if spans and n - spans[-1][1] >= max(settle, spans[-1][1] - spans[-1][0]):
            return spans
        return tuple(s for s in spans[:-1] if n - s[1] >= settle)

    def _go_on(self, span: tuple[int, int]) -> None:
        """The count goes on after ``span``, the latest repetition asked for, from the start
        of the one asked for before it: as in a count of the whole stream, the next one
        begins where it ends (counted from its own start, 14 of 60 joined repetitions were
        cut where classify --split repetitions cuts them; so, 20); one asked for before the
        stream was watched again at another rate, on this rate's frames."""
        last, self.last_asked = self.last_asked, (span[0], float(self.live.fps))
        self.anchor = span[0] if last is None else self._frame_of(*last)
        self.judged_to = span[1]

    def _frame_of(self, frame: int, fps: float) -> int:
        """The stream frame at :attr:`live`'s rate at the time of ``frame`` at ``fps`` (a
        verdict's start, or a count's frame, given before the stream was watched again at
        another rate)."""
        return int(round(frame * self.live.fps / fps))
