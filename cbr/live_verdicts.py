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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

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


class RepetitionVerdicts:
    """The verdicts of a stream's repetitions (module docstring): ``stored``, the case base
    that judges them (``load_classifier``'s; its ``target``: ``correct`` for a repetition
    check), ``live`` the segmenter whose frames are counted. Call :meth:`update` after every
    frame pushed, and with ``ended`` True after :meth:`LiveSegmenter.finish`; each returns
    the verdicts given then."""

    def __init__(
        self,
        stored: StoredClassifier,
        live: LiveSegmenter,
        before: RepetitionVerdicts | None = None,
    ) -> None:
        self.stored, self.live = stored, live
        self.given: list[Verdict] = []
        self.anchor = 0  # the count goes on from here: the start of the one before the last
        self.judged_to = 0  # the end of the last judged: a repetition is judged from there on
        self.hops = -1  # the hop at which the count was last read
        if before is not None:  # the stream watched again at another rate (watch's re-make):
            # its verdicts stand, numbered on, the count going on from the same time
            self.given = list(before.given)
            self.anchor = self._frame_of(before.anchor, before.live.fps)
            self.judged_to = self._frame_of(before.judged_to, before.live.fps)

    @property
    def last(self) -> Verdict | None:
        """The latest verdict given (drawn on the frames)."""
        return self.given[-1] if self.given else None

    def update(self, ended: bool = False) -> list[Verdict]:
        if not ended and self.live.hops == self.hops:  # the count is read once a hop
            return []
        self.hops = self.live.hops
        # a stretch without repetitions is not counted again without end
        self.anchor = max(self.anchor, self.live.n - int(REACH_S * self.live.fps))
        spans = tuple(s for s in self.live.repetitions_from(self.anchor) if self._new(s))
        out: list[Verdict] = []
        for span in spans if ended else self._finished(spans):
            out.append(self._judge(span))
            self.given.append(out[-1])
        return out

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

    def _judge(self, span: tuple[int, int]) -> Verdict:
        piece = self.live.clip(*span)
        judged = classify_clip(self.stored, piece, None, self.stored.target)
        # counted on from the start of the one before it: as in a count of the whole stream,
        # the next one begins where it ends (counted from its own start, 14 of 60 joined
        # repetitions were cut where classify --split repetitions cuts them; so, 20); one
        # judged before the stream was watched again at another rate, on this rate's frames
        last = self.given[-1] if self.given else None
        self.anchor = span[0] if last is None else self._frame_of(last.start_frame, last.fps)
        self.judged_to = span[1]
        return Verdict(len(self.given) + 1, span[0], span[1], judged, float(self.live.fps))

    def _frame_of(self, frame: int, fps: float) -> int:
        """The stream frame at :attr:`live`'s rate at the time of ``frame`` at ``fps`` (a
        verdict's start, or a count's frame, given before the stream was watched again at
        another rate)."""
        return int(round(frame * self.live.fps / fps))
