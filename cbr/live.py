"""Segmenting a live stream as it arrives: the causal half of :mod:`cbr.segmentation`.

Frames are pushed one at a time (world landmarks ``(33, 3)``). Every :data:`HOP_S` seconds
the last :data:`~cbr.segmentation.DEFAULT_WINDOW_S` seconds are solved by the fitted
classifier and vote (an activity, or unknown when unlike the case base); the mean vote of the
windows over the latest stretch goes through the forward pass of the same decoder (a change
needs :data:`~cbr.segmentation.MIN_SEGMENT_S` of evidence at
:data:`~cbr.segmentation.SWITCH_ODDS` to 1), whose best state is the rolling label. When the
label changes, the segment before it is finished: its start is where the new label's path
began (followed back through the decoder), its repetitions are counted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from features.body import torso_share
from features.errors import DataError
from features.poses import PoseSequence
from features.repetitions import count_repetitions
from features.skeleton import BLAZEPOSE_33

from .segmentation import (
    DEFAULT_WINDOW_S,
    MIN_SEGMENT_S,
    SWITCH_ODDS,
    activity_distances,
    span_fields,
)
from .unknown import Judge, activity_codes, judge_of

HOP_S = 0.5
"""The rolling label is decided every this many seconds of stream."""
MAX_SEGMENT_S = 120.0
"""Repetitions are counted over at most the last this many seconds of a segment."""


@dataclass(frozen=True)
class LiveSegment:
    """A finished (or the current) stretch of the stream: frames [start_frame, end_frame),
    label (None: unknown), mean vote for it, repetitions counted in it."""

    start_frame: int
    end_frame: int
    label: str | None
    confidence: float
    repetitions: int

    def to_dict(self, fps: float) -> dict[str, Any]:
        fields = span_fields(self.start_frame, self.end_frame, self.label, self.confidence, fps)
        return {**fields, "repetitions": self.repetitions}


@dataclass
class _Forward:
    """The decoder's forward pass over hops, with back pointers to find where a state began."""

    n_states: int
    penalty: float
    total: np.ndarray = field(init=False)
    back: list[np.ndarray] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.total = np.zeros(self.n_states)

    def step(self, vote: np.ndarray) -> int:
        score = np.log(np.clip(vote, 1e-3, None))
        if self.back or self.total.any():
            best = int(np.argmax(self.total))
            switch = self.total[best] - self.penalty
            stay = self.total >= switch
            self.back.append(np.where(stay, np.arange(self.n_states), best))
            self.total = np.where(stay, self.total, switch) + score
        else:
            self.back.append(np.arange(self.n_states))
            self.total = score.copy()
        self.total -= self.total.max()  # keep the numbers small; only differences matter
        return int(np.argmax(self.total))

    def began(self, state: int) -> int:
        """The hop at which the best path ending in ``state`` entered it (0: at the first)."""
        hop = len(self.back) - 1
        while hop > 0 and self.back[hop][state] == state:
            hop -= 1
        return hop

    def forget(self, hops: int) -> None:
        """Drop the back pointers of the first ``hops`` hops (they are no longer needed)."""
        del self.back[:hops]


class LiveSegmenter:
    """Push frames, read the rolling label; finished segments come out of :meth:`push`.

    ``clf``: a fitted :class:`~cbr.estimator.CaseBaseClassifier`; ``fps``: the stream's frame
    rate; ``judge``: what says a window is unlike the case base (:mod:`cbr.unknown`; the margin
    between the two nearest activities, calibrated on the case base, when None).
    """

    def __init__(self, clf: Any, fps: float, judge: Judge | None = None) -> None:
        if not (math.isfinite(fps) and fps > 0):
            raise DataError(f"the stream needs a frame rate > 0, got {fps!r}", "stream")
        self.clf = clf
        self.fps = float(fps)
        self.judge = judge if judge is not None else judge_of(clf, "margin")
        self.classes = [str(c) for c in clf.classes_]
        self.codes = activity_codes(clf.case_base_.labels, self.classes)
        self.unknown = len(self.classes)
        self.hop = max(1, int(round(HOP_S * fps)))
        self.window = max(2, int(round(DEFAULT_WINDOW_S * fps)))
        self.frames: list[np.ndarray] = []
        self.offset = 0  # the stream frame that frames[0] is (older frames are dropped)
        self.n = 0  # frames pushed
        self.forward = _Forward(self.unknown + 1, (MIN_SEGMENT_S / HOP_S) * math.log(SWITCH_ODDS))
        self.votes: list[np.ndarray] = []
        self.cover = max(1, math.ceil(self.window / self.hop))  # windows over one stretch
        self.latest_votes: list[np.ndarray] = []
        self.hop_frames: list[int] = []  # the frame at which each hop was decided
        self.state: int | None = None
        self.segment_start = 0

    @property
    def label(self) -> str | None:
        """The rolling label (None: unknown or not decided yet)."""
        return None if self.state in (None, self.unknown) else self.classes[int(self.state)]

    def push(self, world: np.ndarray) -> LiveSegment | None:
        """Add one frame ``(33, 3)`` (NaN where the person is not seen). Returns the segment
        that just finished, if the rolling label changed."""
        self.frames.append(np.asarray(world, dtype=np.float64))
        self.n += 1
        if self.n < self.window or (self.n - self.window) % self.hop:
            return None
        return self._decide(self.n)

    def _decide(self, n: int) -> LiveSegment | None:
        self.latest_votes = [*self.latest_votes[1 - self.cover :], self._vote(n)]
        # the evidence for the latest stretch: the mean vote of the windows over it, as each
        # block of the offline decoder gets
        vote = np.mean(self.latest_votes, axis=0)
        self.votes.append(vote)
        self.hop_frames.append(n)
        state = self.forward.step(vote)
        if self.state is None:
            self.state = state
            return None
        if state == self.state:
            self._trim()
            return None
        start_hop = self.forward.began(state)
        boundary = self.hop_frames[start_hop] - self.window // 2
        finished = None
        if boundary >= self.segment_start + self.hop:
            finished = self._segment(self.segment_start, boundary, int(self.state))
            self.segment_start = boundary
        # else the new label's path began before this segment did: the segment is relabelled
        self.state = state
        self._trim()
        return finished

    def _trim(self) -> None:
        """Forget frames and hops no segment in progress can need (bounded memory)."""
        keep_from = max(self.segment_start, self.n - int(MAX_SEGMENT_S * self.fps)) - self.window
        drop = keep_from - self.offset
        if drop > self.window:
            del self.frames[:drop]
            self.offset += drop
        old = sum(f < keep_from for f in self.hop_frames[:-1])
        if old:
            del self.votes[:old], self.hop_frames[:old]
            self.forward.forget(old)

    def _vote(self, n: int) -> np.ndarray:
        """The last window's vote over the activities and unknown ``(n_classes + 1,)``."""
        window = self._sequence(n - self.window, n)
        vote = np.zeros(self.unknown + 1)
        if torso_share(window) == 0.0:
            vote[:] = 1.0 / len(vote)  # no person: no evidence either way
            return vote
        solved = self.clf.solve([window])[0]
        if self.judge.unlike(activity_distances(self.clf, solved, self.codes)):
            vote[-1] = 1.0
        else:
            vote[self.classes.index(str(solved.retrieval.labels[0]))] = 1.0
        return vote

    def recent(self, frames: int) -> PoseSequence:
        """The last ``frames`` frames pushed, as a clip."""
        return self._sequence(max(self.offset, self.n - frames), self.n)

    def _sequence(self, a: int, b: int) -> PoseSequence:
        """Stream frames [a, b) as a clip."""
        rows = self.frames[max(0, a - self.offset) : b - self.offset]
        return PoseSequence(np.stack(rows), BLAZEPOSE_33, self.fps, source="stream")

    def _segment(self, start: int, end: int, state: int) -> LiveSegment:
        hops = [v for v, f in zip(self.votes, self.hop_frames, strict=True) if start < f <= end]
        confidence = float(np.mean([v[state] for v in hops])) if hops else 0.0
        first = max(start, end - int(MAX_SEGMENT_S * self.fps))
        try:
            reps = count_repetitions(self._sequence(first, end)).count
        except DataError:
            reps = 0
        label = None if state == self.unknown else self.classes[state]
        return LiveSegment(start, end, label, confidence, reps)

    def current(self) -> LiveSegment | None:
        """The segment in progress (its repetitions so far)."""
        if self.state is None:
            return None
        return self._segment(self.segment_start, self.n, int(self.state))

    def finish(self) -> LiveSegment | None:
        """The last segment, at the end of the stream."""
        return self.current()


__all__ = ["HOP_S", "LiveSegment", "LiveSegmenter"]
