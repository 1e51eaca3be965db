"""Segmenting a live stream as it arrives: the causal half of :mod:`cbr.segmentation`.

Frames are pushed one at a time (world landmarks ``(33, 3)``). Every :data:`HOP_S` seconds
the last :data:`~cbr.segmentation.DEFAULT_WINDOW_S` seconds are solved by the fitted
classifier and vote for the activity of their nearest case unless unlike the case base (then
for unknown); the mean vote of the last windows goes through the forward pass of the same
decoder (a change needs :data:`~cbr.segmentation.MIN_SEGMENT_S` of evidence at
:data:`~cbr.segmentation.SWITCH_ODDS` to 1), whose best state now is the rolling label. A
segment is finished once the decoder's best paths into every state agree on where it ends
(online Viterbi: what later frames cannot change), not whenever the rolling label turns (the
label of a stream whose windows waver between two activities turns often; the best path
through them does not), and placed where the evidence of the hops on either side is of (the
mean centre of the windows each averages), not where the window that decided it ends. Its
repetitions are counted on its frames, each repetition in the one segment that holds where
its movement turns (:func:`cbr.segmentation.keep_whole`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from features.body import torso_share
from features.errors import DataError
from features.poses import PoseSequence
from features.repetitions import ANALYSIS_FPS, Repetition, count_repetitions
from features.skeleton import BLAZEPOSE_33

from .segmentation import (
    DEFAULT_WINDOW_S,
    MIN_SEGMENT_S,
    SWITCH_ODDS,
    activity_distances,
    at_cut,
    keep_whole,
    log_votes,
    span_fields,
)
from .unknown import JUDGES, Judge, activity_codes, judge_of

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
    """The decoder's forward pass over hops (Viterbi; ``cost[i, j]``: of going from state i
    to state j), with the back pointers of the hops not yet settled: those on which the
    best paths into the states still disagree."""

    cost: np.ndarray
    total: np.ndarray = field(init=False)
    back: list[np.ndarray] = field(default_factory=list)
    started: bool = False

    @property
    def n_states(self) -> int:
        return len(self.cost)

    def __post_init__(self) -> None:
        self.total = np.zeros(self.n_states)

    def step(self, score: np.ndarray) -> int:
        """Take one hop's log evidence ``score`` ``(n_states,)``; the state best supported
        now."""
        if self.started:
            reach = self.total[:, None] - self.cost  # (from, to)
            best = np.argmax(reach, axis=0)
            self.back.append(best)
            self.total = reach[best, np.arange(self.n_states)] + score
        else:
            self.back.append(np.arange(self.n_states))
            self.total = score.copy()
            self.started = True
        self.total -= self.total.max()  # keep the numbers small; only differences matter
        return int(np.argmax(self.total))

    def paths(self) -> np.ndarray:
        """``(n_states, len(back))``: over the hops not yet settled, the best path ending in
        each state."""
        out = np.empty((self.n_states, len(self.back)), dtype=np.int64)
        out[:, -1] = np.arange(self.n_states)
        for i in range(len(self.back) - 1, 0, -1):  # over unsettled hops, vectorised over states
            out[:, i - 1] = self.back[i][out[:, i]]
        return out

    def settle(self, final: bool = False) -> list[int]:
        """The states of the hops now settled, in order, forgotten here: the leading hops on
        which the best paths into every state agree (whatever comes next, the best path
        keeps them: they are what the offline decoder would give); ``final``: the stream has
        ended, every hop is settled on the best path."""
        if not self.back:
            return []
        paths = self.paths()
        if final:
            settled = paths[int(np.argmax(self.total))].tolist()
        else:
            same = (paths == paths[0]).all(axis=0)
            agree = len(same) if same.all() else int(np.argmin(same))
            settled = paths[0, :agree].tolist()
        del self.back[: len(settled)]
        return [int(x) for x in settled]


def _mean_vote(votes: list[np.ndarray], n_classes: int) -> np.ndarray:
    """The mean of the voting windows' ``votes`` ``(n_classes,)`` each, every activity alike
    when no window votes."""
    if not votes:
        return np.full(n_classes, 1.0 / n_classes)
    out: np.ndarray = np.mean(votes, axis=0)
    return out


def _shifted(rep: Repetition, frames: int) -> Repetition:
    """``rep`` of a clip that starts ``frames`` into the stream, in stream frames."""
    return dataclasses.replace(
        rep,
        start_frame=rep.start_frame + frames,
        end_frame=rep.end_frame + frames,
        peak_frame=rep.peak_frame + frames,
    )


class LiveSegmenter:
    """Push frames, read the rolling label; finished segments come out of :meth:`push`.

    ``clf``: a fitted :class:`~cbr.estimator.CaseBaseClassifier`; ``fps``: the stream's frame
    rate; ``judge``: what says a window is unlike the case base (:mod:`cbr.unknown`; the margin
    between the two nearest activities against the nearest one's own threshold, calibrated on
    the case base, when None).

    The rolling label is the state best supported now (it may still change its mind); a
    segment is finished when the decoder's best paths into every state agree on where it
    ends (:meth:`_Forward.settle`), so the finished segments are those the offline decoder
    would give over the same votes, not every turn of the rolling label.
    """

    def __init__(self, clf: Any, fps: float, judge: Judge | None = None) -> None:
        if not (math.isfinite(fps) and fps > 0):
            raise DataError(f"the stream needs a frame rate > 0, got {fps!r}", "stream")
        self.clf = clf
        self.fps = float(fps)
        self.judge = judge if judge is not None else judge_of(clf, JUDGES[0])
        self.classes = [str(c) for c in clf.classes_]
        self.codes = activity_codes(clf.case_base_.labels, self.classes)
        self.unknown = len(self.classes)
        self.hop = max(1, int(round(HOP_S * fps)))
        self.window = max(2, int(round(DEFAULT_WINDOW_S * fps)))
        self.step = max(1, int(round(fps / ANALYSIS_FPS)))  # frames per counted sample
        self.frames: list[np.ndarray] = []
        self.offset = 0  # the stream frame that frames[0] is (older frames are dropped)
        self.n = 0  # frames pushed
        self.forward = _Forward(self._costs())
        self.cover = max(1, math.ceil(self.window / self.hop))  # windows over one stretch
        self.latest_votes: list[tuple[np.ndarray, float]] = []
        self.votes: list[np.ndarray] = []  # of the hops since the segment in progress began:
        # the share of windows nearest each activity, and the share unlike every one
        self.hop_centres: list[float] = []  # the frame each of those hops' evidence is of:
        # the mean centre of the windows it averages (:meth:`_decide`)
        self.state: int | None = None  # the rolling label's state
        self.settled: int | None = None  # the state of the segment in progress
        self.segment_start = 0
        self.turn = False  # the last finished segment had a far point at its end

    def _costs(self) -> np.ndarray:
        """``(2 n_classes, 2 n_classes)``: the cost of going from one state to another. A state
        is an activity and whether it is known (``2 a``) or unknown (``2 a + 1``): which
        activity the windows are nearest and whether they are unlike it are decoded
        together, as the offline decoder does in turn (:func:`cbr.segmentation.decode`, then
        :func:`cbr.segmentation.decode_unknown`): a change of activity costs the penalty
        (:data:`MIN_SEGMENT_S` of hops at :data:`SWITCH_ODDS` to 1), and so does a change of
        the label seen (an activity, or unknown). The share of windows unlike every activity
        is evidence of its own, not a vote taken from the activities (that would split their
        evidence, and the label would turn with every such window); those windows cast no
        vote for an activity (:meth:`_vote`)."""
        hop_s = self.hop / self.fps
        penalty = (MIN_SEGMENT_S / hop_s) * math.log(SWITCH_ODDS)
        activity = np.arange(2 * self.unknown) // 2
        seen = self._seen(np.arange(2 * self.unknown))
        moved = activity[:, None] != activity[None, :]
        turned = seen[:, None] != seen[None, :]
        cost: np.ndarray = penalty * (moved.astype(np.float64) + turned.astype(np.float64))
        return cost

    def _seen(self, states: np.ndarray) -> np.ndarray:
        """The label seen of decoder ``states``: the activity's index, or n_classes (unknown)."""
        return np.asarray(np.where(states % 2 == 1, self.unknown, states // 2))

    @property
    def label(self) -> str | None:
        """The rolling label (None: unknown or not decided yet)."""
        return None if self.state in (None, self.unknown) else self.classes[int(self.state)]

    def push(self, world: np.ndarray) -> list[LiveSegment]:
        """Add one frame ``(33, 3)`` (NaN where the person is not seen). Returns the segments
        that this frame settled as finished (usually none)."""
        self.frames.append(np.asarray(world, dtype=np.float64))
        self.n += 1
        if self.n < self.window or (self.n - self.window) % self.hop:
            return []
        return self._decide(self.n)

    def _decide(self, n: int) -> list[LiveSegment]:
        self.latest_votes = [*self.latest_votes[1 - self.cover :], self._vote(n)]
        # the evidence for the latest stretch: the mean vote of the windows over it, as each
        # block of the offline decoder gets
        nearest = _mean_vote([v for v, far in self.latest_votes if far == 0.0], self.unknown)
        unlike = np.mean([v[1] for v in self.latest_votes])
        self.votes.append(np.r_[nearest, unlike])
        self.hop_centres.append(n - self.window / 2 - (len(self.latest_votes) - 1) * self.hop / 2)
        score = np.add.outer(
            log_votes(nearest), log_votes(np.array([1.0 - unlike, unlike]))
        ).ravel()
        self.state = int(self._seen(np.array(self.forward.step(score))))
        finished = self._settle(self._seen(np.array(self.forward.settle(), dtype=np.int64)))
        self._trim()
        return finished

    def _settle(self, states: np.ndarray) -> list[LiveSegment]:
        """Follow the newly settled hops' ``states`` (the oldest hops not settled before):
        each change of state finishes the segment in progress, between the last hop of the old
        state and the first of the new (:meth:`_between`)."""
        first = len(self.hop_centres) - len(self.forward.back) - len(states)
        finished = []
        for i, state in enumerate(states.tolist(), start=first):
            if self.settled is None:
                self.settled = state
            if state == self.settled:
                continue
            boundary = max(self.segment_start + 1, self._between(i))
            finished.append(self._segment(self.segment_start, boundary, self.settled, True))
            self.segment_start, self.settled = boundary, state
        return finished

    def _between(self, i: int) -> int:
        """The frame where a change from hop ``i - 1``'s state to hop ``i``'s lies: midway
        between what their evidence is of (the mean centre of the windows each averages).
        Not the end of hop ``i``'s window, nor its middle: the evidence of the stretch just
        decided is that of the last few windows, centred a window and a half back."""
        if i == 0:
            return int(round(self.hop_centres[0] - self.hop / 2))
        return int(round((self.hop_centres[i - 1] + self.hop_centres[i]) / 2))

    def _trim(self) -> None:
        """Forget frames and hops no segment in progress can need (bounded memory)."""
        keep_from = max(self.segment_start, self.n - int(MAX_SEGMENT_S * self.fps)) - self.window
        drop = keep_from - self.offset
        if drop > self.window:
            del self.frames[:drop]
            self.offset += drop
        settled = len(self.hop_centres) - len(self.forward.back)
        old = sum(f < keep_from for f in self.hop_centres[: max(0, settled - 1)])
        if old:
            del self.votes[:old], self.hop_centres[:old]

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        """The last window's vote over the activities ``(n_classes,)`` (its nearest case's)
        and whether it is unlike every activity (1.0), not (0.0), or shows nobody (0.5).
        Only a window like an activity votes for one (:func:`_mean_vote`), as offline
        (:func:`cbr.segmentation.decode_activities`): one like none, across a change of
        movement or of one the case base lacks, is nearest to whichever lies least far."""
        window = self._sequence(n - self.window, n)
        if torso_share(window) == 0.0:  # no person: no evidence either way
            return np.full(self.unknown, 1.0 / self.unknown), 0.5
        solved = self.clf.solve([window], flag=False)[0]  # the judge decides unknown
        vote = np.zeros(self.unknown)
        vote[self.classes.index(str(solved.retrieval.labels[0]))] = 1.0
        unlike = self.judge.unlike(activity_distances(self.clf, solved, self.codes))
        return vote, 1.0 if unlike else 0.0

    def recent(self, frames: int) -> PoseSequence:
        """The last ``frames`` frames pushed, as a clip."""
        return self._sequence(max(self.offset, self.n - frames), self.n)

    def _sequence(self, a: int, b: int) -> PoseSequence:
        """Stream frames [a, b) as a clip."""
        rows = self.frames[max(0, a - self.offset) : b - self.offset]
        return PoseSequence(np.stack(rows), BLAZEPOSE_33, self.fps, source="stream")

    def _segment(self, start: int, end: int, state: int, cut: bool) -> LiveSegment:
        """Frames [start, end) as a segment of ``state``; ``cut``: it ends where another
        begins (a finished segment: its repetitions are counted as
        :func:`cbr.segmentation.keep_whole` says, and the next one learns whether the
        movement turned at the cut)."""
        hops = [v for v, f in zip(self.votes, self.hop_centres, strict=True) if start < f <= end]
        confidence = float(np.mean([v[state] for v in hops])) if hops else 0.0
        first = max(start, end - int(MAX_SEGMENT_S * self.fps))
        try:
            found = count_repetitions(self._sequence(first, end)).repetitions
        except DataError:
            found = ()
        reps = tuple(_shifted(r, first) for r in found)
        turn = self.turn and first == start
        kept = keep_whole(reps, first, end, self.step, turn, cut)
        if cut:
            self.turn = at_cut(reps, first, end, self.step)[1]
        label = None if state == self.unknown else self.classes[state]
        return LiveSegment(start, end, label, confidence, len(kept))

    def current(self) -> LiveSegment | None:
        """The segment in progress (its repetitions so far), labelled with the rolling label."""
        if self.state is None:
            return None
        return self._segment(self.segment_start, self.n, int(self.state), False)

    def finish(self) -> list[LiveSegment]:
        """The segments not yet finished, at the end of the stream (the last one ends there)."""
        if self.state is None:
            return []
        out = self._settle(self._seen(np.array(self.forward.settle(final=True), dtype=np.int64)))
        assert self.settled is not None
        return [*out, self._segment(self.segment_start, self.n, self.settled, False)]


__all__ = ["HOP_S", "LiveSegment", "LiveSegmenter"]
