"""Segmenting a live stream as it arrives: the causal half of :mod:`cbr.segmentation`.

Frames are pushed one at a time (world landmarks ``(33, 3)``). Every :data:`HOP_S` seconds
the last :data:`~cbr.segmentation.DEFAULT_WINDOW_S` seconds are a window, and every
:data:`~cbr.segmentation.SPAN_HOP_S` the periods of the movement found whole in the last
:data:`~cbr.segmentation.PERIOD_SPAN_S` seconds are windows too (a repetition each, as
offline); each is solved by the fitted classifier and judged, and the same two passes as
offline decode them, each made online (:class:`LiveSegmenter`): the activities, then known
or unknown within each stretch of one activity. A segment is finished once the decoders'
best paths into every state agree on where it ends (online Viterbi: what later frames cannot
change), not whenever the rolling label turns (the label of a stream whose windows waver
between two activities turns often; the best path through them does not), and a change is
placed where the evidence of the hops on either side is of (the mean centre of the windows
each averages), not where the window that decided it ends. Its repetitions are counted on
its frames as ``segment`` counts a segment cut there (the signals read the frames kept either
side too, :meth:`LiveSegmenter._in_context`), each repetition in the one segment that holds
where its movement turns (:func:`cbr.segmentation.keep_whole`,
:func:`cbr.segmentation.unclaimed`). A window whose frames show the shoulders and arms but
neither hip (the hips out of view: a camera close up, a patient seated) is judged on the arms
(:func:`_shown`), as ``segment`` judges a recording shown from the shoulders up, and its
frames show the person; a window where a hip is seen is judged as before.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from features.body import TORSO_JOINTS, arms_alone, shoulders_only, torso_seen, torso_share
from features.derived import stretch
from features.errors import DataError, InputError, PoseFileError
from features.poses import MAX_FPS, MIN_FPS, PoseSequence
from features.repetitions import (
    ANALYSIS_FPS,
    MIN_PERIOD_S,
    Repetition,
    movement_signals,
)
from features.skeleton import BLAZEPOSE_33
from features.values import is_number

from .estimator_protocol import check_case_base_classifier
from .problem import warm
from .segmentation import (
    DEFAULT_WINDOW_S,
    MAX_WINDOW_S,
    MIN_SEGMENT_S,
    MIN_WINDOW_S,
    PERIOD_SPAN_S,
    SPAN_HOP_S,
    STILL_TEXT,
    SWITCH_ODDS,
    activity_distances,
    at_cut,
    check_judge,
    check_k,
    cut_off_beside,
    keep_whole,
    least_movement,
    log_votes,
    nobody_explanation,
    period_outliers,
    periods_in_span,
    repetitions_in,
    segment,
    sighting_width,
    span_fields,
    told,
    unclaimed,
    unknown_reason,
    votes_as,
    whole_in,
    window_still,
)
from .unknown import (
    Judge,
    activity_codes,
    default_judge,
    for_person,
    tell_unknown,
    unknown_evidence,
)

HOP_S = 0.5
"""The rolling label is decided every this many seconds of stream."""
MAX_SEGMENT_S = 120.0
"""Frames are kept for at most the last this many seconds of the segment in progress (and of
the stretches its decisions read)."""
TALLY_S = 30.0
"""The repetitions of the segment in progress that end more than this many seconds before
the latest frame, before any frame a cut of it can still fall on, are tallied once the
frames it is counted on run to twice as many seconds (:meth:`LiveSegmenter._tally`): their
count is kept and their frames are not counted again. A segment of any length counts every
repetition (before, those of its last :data:`MAX_SEGMENT_S` seconds: 58 squats in one
141-s segment counted 46), and what is counted at each hop, for the segment drawn and for
the next tally, is at most :data:`TALLY_S` twice over, however long the segment has
run."""
PERSON_WINDOWS = 1200
"""How far the stream's person lies from every case (:func:`cbr.unknown.for_person`) is read
from at most this many of the latest windows (10 minutes of fixed windows)."""
CONTEXT_S = 1.0
"""Repetitions of stream frames are counted on movement signals computed over up to this many
seconds of the frames kept either side of them as well (:meth:`LiveSegmenter._in_context`):
more than the signals' filters read (:func:`features.repetitions.movement_signals`: a running
median 0.1 s either side, a pose model's glitch up to 0.2 s long, a Gaussian of 0.08 s to
four sigma, 0.32 s), so that inside the frames each sample is what the whole stream's signals
give there, as ``segment`` counts a segment on the whole recording's."""
MAX_UNSETTLED_S = 30.0
"""A hop the decoder has not settled after this many seconds of stream is settled on the path
best now (the best paths into the states may never agree: when every state is equally
likely, as with nobody in view, each stays in itself); bounds the delay and the memory."""


@dataclass(frozen=True)
class LiveSegment:
    """A finished (or the current) stretch of the stream: frames [start_frame, end_frame),
    label (None: unknown), mean vote for it, repetitions counted in it; a finished one also a
    short explanation and its novelty, as ``segment`` gives them (the current one: "" and
    NaN)."""

    start_frame: int
    end_frame: int
    label: str | None
    confidence: float
    repetitions: int
    explanation: str = ""
    novelty: float = math.nan

    def to_dict(self, fps: float) -> dict[str, Any]:
        """The segment as one of ``watch``'s JSON lines; ``fps``: the stream's frames per
        second (``start_s``, ``end_s``)."""
        fields = span_fields(self.start_frame, self.end_frame, self.label, self.confidence, fps)
        novelty = round(self.novelty, 3) if math.isfinite(self.novelty) else None
        return {
            **fields,
            "unknown": unknown_reason(self.label, self.explanation),
            "repetitions": self.repetitions,  # the count: kept (reps: the list)
            "explanation": self.explanation,
            "novelty": novelty,
            "count": self.repetitions,  # as reps --json names its count
        }


@dataclass(frozen=True)
class LiveProgress:
    """The segment in progress as it stands (:meth:`LiveSegmenter.progress`): frames
    [start_frame, frame) pushed so far; its label as the decoders have settled it (None:
    unknown), the one its line carries when it finishes; its confidence so far; the
    repetitions counted in it that end by ``settled_frame``, the earliest frame a cut of it
    can still fall on, less the longest window (those its finished line counts too); why it
    is unknown (``unknown``, as :func:`cbr.segmentation.unknown_reason` says it);
    ``still_frame``: while the person holds still, the first frame of the latest windows
    that are each too still for any activity, in a row (None while they move:
    :attr:`LiveSegmenter.still_from`)."""

    start_frame: int
    frame: int
    label: str | None
    confidence: float
    repetitions: int
    settled_frame: int
    unknown: str | None
    still_frame: int | None = None

    def to_dict(self, fps: float) -> dict[str, Any]:
        """One of ``watch --progress``'s lines: ``"event": "progress"``; ``t_s`` and
        ``frame``, the stream's time and frames pushed so far (the segment's end so far, as
        ``end_s`` and ``end_frame`` are a finished one's); ``since_s``, how long it has gone
        on; the finished line's fields by the same names (``start_s``, ``start_frame``,
        ``label``, ``confidence``, ``unknown``, ``repetitions`` and ``count``) as they stand;
        ``settled_s``, the time up to which it is settled (``settled_frame``); while the
        person holds still, ``still_s``, since when (``still_frame``; the key is left out
        while they move: those lines are as before). ``fps``: the stream's frames per second
        (InputError naming it when not a number > 0)."""
        fields = span_fields(self.start_frame, self.frame, self.label, self.confidence, fps)
        still = {} if self.still_frame is None else {"still_s": round(self.still_frame / fps, 3)}
        return {
            "event": "progress",
            "t_s": fields["end_s"],
            "frame": self.frame,
            "since_s": round((self.frame - self.start_frame) / fps, 3),
            "start_s": fields["start_s"],
            "start_frame": self.start_frame,
            "label": self.label,
            "confidence": fields["confidence"],
            "unknown": self.unknown,
            "repetitions": self.repetitions,
            "count": self.repetitions,  # as a finished segment's line names it too
            "settled_s": round(self.settled_frame / fps, 3),
            **still,
        }


@dataclass(frozen=True)
class _Judged:
    """A window the segmenter solved: frames [start, stop), its nearest activity, the
    judge's ratio, its distance to the nearest case of every activity and the judge it was
    judged by (that of the person as seen by then: :func:`cbr.unknown.for_person`); still:
    it moves too little to be any activity (:func:`cbr.segmentation.too_still`)."""

    start: int
    stop: int
    activity: int
    ratio: float
    nearest: np.ndarray
    judge: Judge
    still: bool = False

    @property
    def centre(self) -> float:
        return 0.5 * (self.start + self.stop)


_Window = tuple[int, int, float, "_Judged | None"]
"""A window over the stretch in progress: frames [start, stop), its evidence of unknown as
judged when it was solved, and the window as judged (None: it showed nobody)."""


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

    def step(self, score: np.ndarray, cost: np.ndarray | None = None) -> int:
        """Take one hop's log evidence ``score`` ``(n_states,)`` (``cost``: of reaching it,
        when not the usual); the state best supported now."""
        if self.started:
            reach = self.total[:, None] - (self.cost if cost is None else cost)  # (from, to)
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

    def settle(self, final: bool = False, most: int | None = None) -> list[int]:
        """The states of the hops now settled, in order, forgotten here: the leading hops on
        which the best paths into every state agree (whatever comes next, the best path
        keeps them: they are what the offline decoder would give); ``final``: the stream has
        ended, every hop is settled on the best path; ``most``: at most this many hops are
        left unsettled (the oldest beyond are settled on the path best now)."""
        if not self.back:
            return []
        paths = self.paths()
        best = paths[int(np.argmax(self.total))]
        if final:
            settled = best.tolist()
        else:
            same = (paths == paths[0]).all(axis=0)
            agree = len(same) if same.all() else int(np.argmin(same))
            if most is not None and len(same) - agree > most:
                settled = [*paths[0, :agree].tolist(), *best[agree : len(same) - most].tolist()]
            else:
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


@dataclass(frozen=True)
class _HeldBack:
    """The stream's first segment, finished and held back (:meth:`LiveSegmenter._hold`):
    ``segment`` as it would be given now, ``own`` its repetitions counted alone (none whole),
    ``held`` its last far point left to the segment after (:func:`cbr.segmentation.keep_whole`)."""

    segment: LiveSegment
    own: tuple[Repetition, ...]
    held: bool


class _Cut(NamedTuple):
    """The last segment finished at a cut, as :func:`cbr.segmentation.unclaimed` reads the
    segment before: its repetitions counted alone (``raw``), frames [start, end) they were
    counted on, whether nobody is in view in it (``blind``) and whether its last far point
    is held on across its end (``held``)."""

    raw: tuple[Repetition, ...]
    bounds: tuple[int, int]
    blind: bool
    held: bool


class _Tally(NamedTuple):
    """The repetitions of the segment that begins at frame ``start`` tallied
    (:meth:`LiveSegmenter._tally`): ``counted`` of them end by frame ``upto``, where the rest
    of the segment is counted from (a frame between two repetitions)."""

    start: int
    upto: int
    counted: int


class _Shown(NamedTuple):
    """The segment in progress as :meth:`LiveSegmenter.current` counted it at the hop, the
    start and the label of ``key``: the segment, and the repetitions it counted on the frames
    after its tally (:meth:`LiveSegmenter._counted`)."""

    key: tuple[int, int, int]
    segment: LiveSegment
    kept: tuple[Repetition, ...]


@dataclass(frozen=True)
class _Kept:
    """The stream's frames still kept, counted as :func:`cbr.segmentation.unclaimed` counts
    a recording's frames (:class:`cbr.segmentation.Counter`): ``count`` gives the
    repetitions of frames [start, end) with ``settled`` (:meth:`LiveSegmenter._count_kept`)."""

    step: int
    count: Callable[[int, int, tuple[bool, bool]], tuple[Repetition, ...]]

    def repetitions(
        self,
        start: int,
        end: int,
        n_frames: int | None,  # noqa: ARG002 (the stream's end: once it has ended)
        settled: tuple[bool, bool],
    ) -> tuple[Repetition, ...]:
        """The repetitions of stream frames [start, end) (of those still kept; the stream's
        end is the recording's once it has ended, whatever ``n_frames``)."""
        return self.count(start, end, settled)


@dataclass(frozen=True)
class _Hop:
    """A settled hop whose evidence of unknown is final, for the known/unknown decoder: the
    frame its evidence is of (``centre``), its ``activity``, the share of its windows voting
    for it (``vote``), the mean evidence of unknown of the windows inside its stretch over its
    centre (``unlike``), and its stretch's first frame when it is the stretch's first hop
    after a change of activity (``change``, else None)."""

    centre: float
    activity: int
    vote: float
    unlike: float
    change: int | None


class LiveSegmenter:
    """Push frames, read the rolling label; finished segments come out of :meth:`push`.

    ``clf``: a fitted :class:`~cbr.estimator.CaseBaseClassifier` (unfitted: NotFittedError;
    anything else, ``load_classifier``'s ``StoredClassifier`` holding one: InputError); ``fps``:
    the stream's frame rate, frames per second (segments are in frames counted from the first
    pushed, 0; ``to_dict(fps)`` adds seconds); ``judge``: what says a window is unlike the case
    base (:mod:`cbr.unknown`; the margin between the two nearest activities times how far the
    window lies in the nearest one's own spread, against that activity's own threshold,
    ``spread-margin``, calibrated on the case base, when None); ``source``: the stream's name in
    errors (a camera, a URL, a file); ``k``: a window's k nearest cases vote, as the classifier
    votes (:func:`cbr.segmentation.votes_as`; 1, the default: its nearest), as ``segment -k``
    votes offline (:func:`cbr.segmentation.segment`'s ``k``: from 1 to the classifier's own k,
    else ParameterError); the judge of unknown reads each activity's nearest case whatever
    ``k``.

    As offline, in two passes, each an online Viterbi (:class:`_Forward`: a hop is settled
    when the best paths into every state agree on it, so the settled hops are those the
    offline decoder gives over the same evidence, not every turn of the rolling label; or
    after :data:`MAX_UNSETTLED_S` on the path best then):

    1. the activities (:func:`cbr.segmentation.decode`): a hop's evidence is the mean vote of
       the latest fixed windows and of the repetition windows over it, each window not
       unlike every activity voting for its nearest; a change costs :data:`MIN_SEGMENT_S` of
       hops at :data:`SWITCH_ODDS` to 1; a settled change ends a stretch of one activity;
    2. known or unknown (:func:`cbr.segmentation.decode_unknown`), over the settled hops once
       no window can still change their evidence (:meth:`_final_until`): a hop's evidence is
       the mean evidence of unknown (:func:`cbr.unknown.unknown_evidence`, graded by the
       default judge; with one person's case base, of the distances less how much farther
       the person lies from every case, as the windows up to then tell,
       :func:`cbr.unknown.for_person`: each window judged again when the hop is passed, not
       as the first windows of the stream told, which took a movement the case base lacks
       for a far person) of the windows inside its stretch over it (fixed and
       repetition windows, those whose period disagrees with their neighbours' left out:
       :func:`cbr.segmentation.period_outliers`; a window across a change of activity is like
       neither side, whether both are known or not; over none, the last evidence carries
       on); every change of the label seen costs the same, and a change of activity under
       unknown is not seen and costs nothing.

    A segment is finished when the label seen (an activity, or unknown) settles on a change;
    the stream's first, when it has no whole repetition of its own, is given once the first
    repetition of the segment after it is known (:meth:`_judge_early`, :meth:`_judge_held`:
    a far point cut off by the stream's start is judged beside it, as offline), still before
    every later segment. Memory is bounded: windows, hops and frames are kept only while a
    segment or a decision can still need them.
    """

    def __init__(
        self,
        clf: Any,
        fps: float,
        judge: Judge | None = None,
        source: str = "stream",
        k: int = 1,
    ) -> None:
        check_case_base_classifier(clf, "fit it (or load a stored one) before streaming to it")
        if not (type(k) is int and k == 1):  # 1, the default, any classifier retrieves
            check_k(clf, k)
        self.k = int(k)
        if not (is_number(fps) and math.isfinite(fps) and fps > 0):
            raise InputError(f"the stream needs a frame rate > 0, got {fps!r}", source)
        if not MIN_FPS <= fps <= MAX_FPS:  # as a pose file's: every frame would be refused
            raise InputError(
                f"the stream needs a frame rate between {MIN_FPS:g} and {MAX_FPS:g} frames per"
                f" second, got {fps:g}",
                source,
            )
        check_judge(judge, clf.classes_)
        self.clf, self.source = clf, source
        self.fps = float(fps)
        self.judge = judge if judge is not None else default_judge(clf)
        self.classes = [str(c) for c in clf.classes_]
        self.codes = activity_codes(clf.case_base_.labels, self.classes)
        self.movement, self.least = least_movement(clf)  # as offline: too still for any
        self.unknown = len(self.classes)
        self.hop = max(1, int(round(HOP_S * fps)))
        self.window = max(2, int(round(DEFAULT_WINDOW_S * fps)))
        self.step = max(1, int(round(fps / ANALYSIS_FPS)))  # frames per counted sample
        self.span = int(round(PERIOD_SPAN_S * fps))
        self.span_every = max(1, int(round(SPAN_HOP_S / HOP_S)))  # hops between two spans
        self.longest = max(self.window, int(round(MAX_WINDOW_S * fps)))  # of any window
        self.most = max(1, int(round(MAX_UNSETTLED_S / HOP_S)))  # hops left unsettled
        self.frames: list[np.ndarray] = []
        self.seen_by: list[np.ndarray | None] = []  # each kept frame's joints' confidence
        self.offset = 0  # the stream frame that frames[0] is (older frames are dropped)
        self.n = 0  # frames pushed
        self.hops = 0  # hops decided
        self.cover = max(1, math.ceil(self.window / self.hop))  # windows over one stretch
        self.latest_votes: list[tuple[np.ndarray, float]] = []
        self.windows: list[_Window] = []  # (start, stop, evidence of unknown as judged then,
        # the window as judged: None when it shows nobody) of the windows that start in the
        # stretch in progress and may still count
        self.periods: list[_Window] = []  # the same of its repetition windows
        self.period_votes: list[tuple[int, int, np.ndarray]] = []  # (start, stop, vote) of
        # the recent repetition windows not unlike every activity
        self.found: set[tuple[int, int]] = set()  # the recent periods (each solved once)
        # pass 1, the activities:
        self.forward = _Forward(self._penalty() * (1.0 - np.eye(self.unknown)))
        self.votes: list[np.ndarray] = []  # of the hops not yet passed to pass 2 (and the
        # last settled one): the share of the windows over each nearest each activity
        self.hop_centres: list[float] = []  # the frame each of those hops' evidence is of:
        # the mean centre of the fixed windows it averages (:meth:`_decide`)
        self.state: int | None = None  # the rolling activity
        self.settled: int | None = None  # the activity of the stretch in progress
        self.stretch_start = 0
        self.passed = -math.inf  # the centre of the last hop passed to pass 2
        self.stretch_passed = False  # a hop of the stretch in progress was passed
        # pass 2, known or unknown:
        pen = self._penalty()
        self.known = _Forward(np.array([[0.0, pen], [pen, 0.0]]))
        self.pending: list[_Hop] = []  # the hops pass 2 has not settled
        self.carried = 0.0  # the last evidence of unknown of a hop some window covered
        self.seen: int | None = None  # the label seen of the segment in progress (an
        # activity, or n_classes: unknown)
        self.seen_start = 0
        self.seen_sum: list[float] = [0.0, 0.0]  # its settled hops' votes for it (unknown:
        # their evidence of unknown), and how many
        self.last_centre = 0.0  # of the last hop pass 2 settled
        self.turn = False  # the last finished segment had a far point at its end
        self.holding = False  # and held it up to its end: the segment after counts it
        self.passed_on = 0  # a far point held on past the end of the segments finished,
        # nothing come back yet, that counts if the stream ends still in the hold (0: a
        # posture got into and held, :meth:`_still_beyond`)
        self.held_from = 0  # the first repetition's first frame of the segment that held it
        self.last_cut: _Cut | None = None  # the last segment finished (:meth:`_mine`)
        self.tally: _Tally | None = None  # the repetitions of the segment in progress
        # tallied (:meth:`_tally`)
        self.beside: int | None = None  # the last repetition's first frame of the last
        # segment finished (None: it had none, or nobody was in view): what the stream's last
        # segment is judged beside when the stream ends (:meth:`_beside_whole`)
        self.lost_from: tuple[int, int] | None = None  # the first frame of the repetition
        # whose far point the person was lost at, left to the segment seen after if it is of
        # the same activity (the label: the second), :meth:`_segment`
        self.waiting: _HeldBack | None = None  # the stream's first segment, held back until
        # the first repetition of the segment after it is known (:meth:`_hold`)
        self.released: list[LiveSegment] = []  # it, judged, not yet given
        self.ended = False  # the stream has ended (finish)
        self.shown: _Shown | None = None  # current()'s, counted once a hop
        self.judged: list[_Judged] = []  # the windows over the segments not yet finished
        # whose frames are kept: what explains a finished segment
        self.near: deque[float] = deque(maxlen=PERSON_WINDOWS)  # the latest windows'
        # distances to their nearest case: how far the person lies
        # nobody in view (a segment of its own, as offline: cbr.segmentation.nobody_blocks):
        self.nobody = self.unknown + 1  # its label seen
        self.torso = [BLAZEPOSE_33.index(j) for j in TORSO_JOINTS]
        self.hips = self.torso[2:]  # blanked in the context of a window without them
        self.least_blind = MIN_SEGMENT_S * self.fps  # frames: a shorter dropout is not one
        # whether a frame shows the person: the majority of the frames around it that show
        # the torso (as offline, sighting_width: a glitch of the pose model is not), known
        # once the frames after it are pushed
        self.glitch = sighting_width(self.fps) // 2  # frames either side of it
        self.sightings: deque[bool] = deque(maxlen=2 * self.glitch + 1)  # the torso seen in
        # the last frames pushed
        self.looked = 0  # the frames whose sighting is known
        self.blind: list[tuple[int, int]] = []  # the recent runs of at least that many
        # frames without the torso: [first, end)
        self.blind_from: int | None = None  # the first frame of the run in progress
        self.blind_hop = 0.0  # the centre of the last hop seen as nobody
        self.absent: list[list[int]] = []  # the runs [first, end) of frames in a gap of
        # the video (push's absent): a stretch with nobody in view mostly of them has no frames
        self.held: list[float] = []  # the evidence of unknown of the unknown hops after a
        # stretch with nobody in view, not yet a second long (they join it, or the
        # activity after it)
        # the pose jumping to another person (push's image landmarks):
        self.image_before: np.ndarray | None = None  # the last frame's hip and torso (px)
        self.jumps: list[int] = []  # the frames, still kept, where the pose jumped
        self.jumped = False  # the pose jumped at the last frame pushed
        self.still_from: int | None = None  # the first frame of the latest fixed windows
        # that are each too still for any activity, in a row (the person holds still since
        # about then: :meth:`progress`); None when the latest moves or shows nobody

    def _penalty(self) -> float:
        """The log-odds a change costs: :data:`MIN_SEGMENT_S` of hops at :data:`SWITCH_ODDS`."""
        return (MIN_SEGMENT_S / (self.hop / self.fps)) * math.log(SWITCH_ODDS)

    @property
    def label(self) -> str | None:
        """The rolling label (None: unknown or not decided yet): the rolling activity, unless
        the latest windows show nobody or are more unlike every activity than not."""
        if self.state is None or self._unlike_now() > 0.5 or self._nobody_now():
            return None
        return self.classes[int(self.state)]

    @property
    def nobody_in_view(self) -> bool:
        """Nobody has been seen for the last :data:`MIN_SEGMENT_S` or more (a stretch that
        will be a segment of its own, "nobody in view"; a glitch of the pose model aside:
        known :attr:`glitch` frames late, :meth:`_sighted`)."""
        return self.blind_from is not None and self.looked - self.blind_from >= self.least_blind

    @property
    def nobody_reason(self) -> str:
        """What the stretch with nobody in view in progress (:attr:`nobody_in_view`) is
        called, as its segment will be: "no frames in the video" when most of its frames lie
        in a gap of the video (push's ``absent``), "nobody in view" otherwise."""
        start = self.n if self.blind_from is None else self.blind_from
        return nobody_explanation(self._absent_in(start, self.n))

    def _absent_in(self, start: int, end: int) -> np.ndarray:
        """``(end - start,)`` bool: which of frames [start, end) lie in a gap of the video."""
        absent = np.zeros(end - start, dtype=bool)
        for first, stop in self.absent:
            absent[max(first, start) - start : max(min(stop, end), start) - start] = True
        return absent

    def _unlike_now(self) -> float:
        """The mean evidence of unknown of the latest windows that lie in the stretch in
        progress (all the latest when none does)."""
        latest = [w[2] for w in self.windows[-self.cover :]] or [v[1] for v in self.latest_votes]
        return float(np.mean(latest)) if latest else 0.0

    def _nobody_now(self) -> bool:
        """Every one of the latest windows votes every activity alike (nobody in view)."""
        return all(np.ptp(v) == 0.0 for v, _ in self.latest_votes)

    def push(
        self,
        world: np.ndarray,
        confidence: np.ndarray | None = None,
        absent: bool = False,
        image: np.ndarray | None = None,
    ) -> list[LiveSegment]:
        """Add one frame ``(33, 3)`` (NaN where the person is not seen) and, from a pose
        model, its joints' confidence ``(33,)`` (visibility: the repetitions leave out a joint
        below 0.5 as ``segment`` does, :func:`features.repetitions.counted_angles`); ``absent``:
        the frame lies in a gap of the video, no frame there at all (its joints missing: a
        stretch with nobody in view that is mostly such frames says "no frames in the video",
        as ``segment`` says it); ``image``: the frame's image landmarks ``(33, >=2)`` (x, y in
        px, NaN where nobody is seen, as a pose model gives them): where the hip centre moves
        farther from the frame before's than a torso length (or 8 a second at low rates:
        :func:`features.pose_estimation.video.person_jumps`, as ``extract`` records it), the
        pose jumped to another person (:attr:`jumped`), and repetitions are counted apart on
        either side of that frame, as ``segment`` counts them (the segment goes on across
        it); without ``image`` no jump is seen.

        ``world`` is a :class:`~features.poses.PoseSequence`'s positions for one frame: the
        joints of :data:`features.skeleton.BLAZEPOSE_33` in that order, in metres, in a
        right-handed frame with y up (gravity along -y). Another tracker's joints are put in
        that order by ``PoseSequence(xyz, names, fps).to_canonical()`` (a Kinect v2's by its
        SDK's names with ``skeleton="kinect_v2"``); a z-up frame (ROS's)
        must be turned first, ``(x, y, z)`` to ``(x, z, -y)``: read as it is, an upright torso
        is one tilted forward. Frames are taken as evenly spaced at the ``fps`` given: push
        every one. Returns the segments that this frame settled as finished (usually none). A
        copy is kept; a frame that is not one (another skeleton's joints, an infinite
        coordinate) is refused with :class:`features.errors.InputError`, nothing kept; so is
        any frame after :meth:`finish` (the stream has ended: a new one needs a new
        segmenter), and an ``absent`` that is not True or False."""
        if self.ended:
            raise InputError(
                f"frame {self.n}: the stream has ended (finish() was called): a new stream "
                "needs a new LiveSegmenter",
                self.source,
            )
        if not isinstance(absent, bool | np.bool_):  # "no" was taken as True
            raise InputError(
                f"frame {self.n}: absent must be True or False, got {absent!r}", self.source
            )
        frame, seen = self._checked(world, confidence)
        hips = self._hips(image)
        self._follow_person(hips)
        if absent:  # runs [first, end) of frames in a gap
            if self.absent and self.absent[-1][1] == self.n:
                self.absent[-1][1] += 1
            else:
                self.absent.append([self.n, self.n + 1])
        self.frames.append(frame)
        self.seen_by.append(seen)
        self._look(frame)
        self.n += 1
        if self.n < self.window or (self.n - self.window) % self.hop:
            return []
        return self._decide(self.n)

    def _checked(self, world: Any, confidence: Any) -> tuple[np.ndarray, np.ndarray | None]:
        """Frame :attr:`n` as it is kept: ``world`` ``(33, 3)`` and ``confidence`` ``(33,)``
        (or None) as read-only copies (a caller may refill its buffer for the next frame),
        checked as a pose file's are. InputError naming the stream and the frame for one that
        is not, before anything is kept: a window would read it seconds later, and every
        window after it."""
        joints = len(BLAZEPOSE_33)
        if world is None:  # a tracker's "nobody found", or a dropped frame
            raise InputError(
                f"frame {self.n}: world is None: push a frame of NaN "
                "(np.full((33, 3), np.nan)) where nobody is seen, absent=True where no frame came",
                self.source,
            )
        for value, shape, what in ((world, (joints, 3), "world"),
                                   (confidence, (joints,), "confidence")):  # fmt: skip
            got: object
            try:
                got = None if value is None else np.shape(value)
            except ValueError:  # rows of different lengths
                got = "rows of different lengths"
            if got is not None and got != shape:
                raise InputError(
                    f"frame {self.n}: {what} must have shape {shape}, got {got}",
                    self.source,
                )
        conf = None if confidence is None else np.asarray(confidence)[None]
        try:
            one = PoseSequence(np.asarray(world)[None], BLAZEPOSE_33, self.fps, confidence=conf)
        except PoseFileError as exc:  # said of the positions: push's argument is world
            said = re.sub(r"^positions( contain| reach)?\b", _of_world, exc.message)
            raise InputError(f"frame {self.n}: {said}", self.source) from None
        return one.positions[0], None if one.confidence is None else one.confidence[0]

    def _hips(self, image: Any) -> np.ndarray | None:
        """``image``, push's image landmarks of frame :attr:`n`, as a float array ``(33, 2)``
        (x, y), or None; InputError naming the stream and the frame for one that is not,
        before anything is kept."""
        if image is None:
            return None
        try:
            xy = np.array(image, dtype=float)
        except (TypeError, ValueError):  # rows of different lengths, or not numbers
            xy = np.empty(0)
        if xy.ndim != 2 or xy.shape[0] != len(BLAZEPOSE_33) or xy.shape[1] < 2:
            got = xy.shape if xy.size else "no array of numbers"
            raise InputError(
                f"frame {self.n}: image landmarks must have shape (33, 2) or more columns"
                f" (x, y in px), got {got}",
                self.source,
            )
        return xy[:, :2]

    def _follow_person(self, hips: np.ndarray | None) -> None:
        """Whether the pose jumped to another person at frame :attr:`n` (image landmarks
        ``hips``, or None: no jump seen), by
        :func:`features.pose_estimation.video.person_jumps` over it and the frame before."""
        before, self.image_before = self.image_before, hips
        self.jumped = False
        if before is not None and hips is not None:
            from features.pose_estimation.video import person_jumps

            self.jumped = bool(person_jumps(np.stack([before, hips]), self.fps))
        if self.jumped:
            self.jumps.append(self.n)

    def _look(self, frame: np.ndarray) -> None:
        """Follow the runs of frames without the person with frame :attr:`n`, ``frame``: the
        sighting of the frame :attr:`glitch` frames back is known now (of the stream's first
        :attr:`glitch` frames, when twice as many are pushed: each is read over the first
        frames of the stream, as offline)."""
        torso = frame[self.torso]  # the person: the torso, or the shoulders without the hips
        self.sightings.append(bool(torso_seen(torso) or shoulders_only(torso)))
        end = self.n + 1
        while end > 2 * self.glitch and end - self.looked > self.glitch:
            self._sighted(end)

    def _sighted(self, end: int) -> None:
        """Whether frame :attr:`looked` shows the person, the frames up to ``end``
        (exclusive) pushed: the majority of the frames within :attr:`glitch` of it that show
        the torso, or both shoulders and neither hip (the hips out of view), as
        :func:`cbr.segmentation.nobody_blocks` reads it
        (:func:`features.body.majority`: nearer the stream's ends, of as many frames nearest
        that end); and the runs of frames without the person followed with it."""
        i, first = self.looked, end - len(self.sightings)  # first: the frame sightings[0] is
        half = min(self.glitch, (end - 1) // 2)
        centre = min(max(i, half), end - 1 - half)
        window = list(self.sightings)[centre - half - first : centre + half + 1 - first]
        seen = 2 * sum(window) > len(window)
        if not seen and self.blind_from is None:
            self.blind_from = i
        elif seen and self.blind_from is not None:
            if i - self.blind_from >= self.least_blind:
                self.blind.append((self.blind_from, i))
            self.blind_from = None
        self.looked += 1

    def _blind_run(self, frame: float) -> tuple[int, int] | None:
        """The run of at least :data:`MIN_SEGMENT_S` with nobody in view that holds ``frame``
        (the run in progress ends, so far, at the last frame whose sighting is known), or
        None."""
        runs = list(self.blind)
        if self.blind_from is not None and self.looked - self.blind_from >= self.least_blind:
            runs.append((self.blind_from, self.looked))
        return next(((a, b) for a, b in runs if a <= frame < b), None)

    def _decide(self, n: int) -> list[LiveSegment]:
        vote = self._vote(n)
        self.latest_votes = [*self.latest_votes[1 - self.cover :], vote]
        judged = self._last_judged(n - self.window, n)
        self.windows.append((n - self.window, n, vote[1], judged))
        if judged is None or not judged.still:
            self.still_from = None
        elif self.still_from is None:
            self.still_from = n - self.window
        if self.hops % self.span_every == 0:  # spans end where offline's do: a window, then
            self._repetition_windows(n)  # every SPAN_HOP_S
        self.hops += 1
        # the evidence for the latest stretch: the mean vote of the windows over it that are
        # not unlike every activity, as each block of the offline decoder gets
        centre = n - self.window / 2 - (len(self.latest_votes) - 1) * self.hop / 2
        periods = [v for b, c, v in self.period_votes if b <= centre < c]
        fixed = [v for v, far in self.latest_votes if far < 1.0]
        nearest = _mean_vote(fixed + periods, self.unknown)
        self.votes.append(nearest)
        self.hop_centres.append(centre)
        self.state = self.forward.step(log_votes(nearest))
        states = self.forward.settle(most=self.most)
        finished = self._settle(np.array(states, dtype=np.int64))
        finished += self._judge_early()
        self._trim()
        return finished

    def _settle(self, states: np.ndarray) -> list[LiveSegment]:
        """Follow the newly settled hops' activity ``states`` (the oldest hops not settled
        before): each change ends the stretch in progress between the last hop of the old
        activity and the first of the new (:meth:`_between`), and passes its remaining hops
        to pass 2 (:meth:`_pass`); then the hops of the stretch in progress whose evidence
        no window can change any more are passed too (:meth:`_final_until`)."""
        first = len(self.hop_centres) - len(self.forward.back) - len(states)
        finished = []
        for i, state in enumerate(states.tolist(), start=first):
            if self.settled is None:
                self.settled = state
            if state == self.settled:
                continue
            boundary = max(self.stretch_start + 1, self._between(i))
            finished += self._pass(boundary, boundary)
            self.stretch_start, self.settled, self.stretch_passed = boundary, state, False
            self.windows = [w for w in self.windows if w[0] >= boundary]
            self.periods = [w for w in self.periods if w[0] >= boundary]
        if self.settled is not None:
            last = self.hop_centres[len(self.hop_centres) - len(self.forward.back) - 1]
            finished += self._pass(self._final_until(last), int(last))
        return finished

    def _final_until(self, last: float) -> float:
        """The latest hop centre whose evidence of unknown is final when the last settled hop
        lies at ``last``: the stretch in progress ends after ``last``, so a window that stops
        by then lies inside it; every window over a hop stops within :attr:`longest` frames
        of it, and the repetition windows over it are found within a span of it."""
        return min(last - self.longest, self.n - self.span)

    def _between(self, i: int) -> int:
        """The frame where a change from hop ``i - 1``'s state to hop ``i``'s lies (``i`` > 0:
        the hop before a change is kept): midway between what their evidence is of (the mean
        centre of the fixed windows each averages), not the end of hop ``i``'s window nor
        its middle: the evidence of the stretch just decided is that of the last few windows,
        centred 1 to 1.75 s back."""
        return int(round((self.hop_centres[i - 1] + self.hop_centres[i]) / 2))

    def _evidence(self, centres: np.ndarray, start: int, end: int) -> np.ndarray:
        """For hops at ``centres`` (in order): the mean evidence of unknown of the windows
        inside frames [start, end) over each; a hop none covers carries the last covered
        one's (the first: that of the hop before, :attr:`carried`)."""
        spans = np.array([w[:2] for w in self.periods], dtype=np.int64).reshape(-1, 2)
        odd = period_outliers(spans, np.ones(len(spans), dtype=bool), self.step)
        periods = [w for w, out in zip(self.periods, odd.tolist(), strict=True) if not out]
        # each window judged by the person as the windows by now show them, as offline
        # judges every window by the whole recording's (cbr.segmentation.finish)
        judge = for_person(self.judge, np.array(self.near))
        inside = np.array(
            [
                (w[0], w[1], self._rejudged(w, judge))
                for w in self.windows + periods
                if w[0] >= start and w[1] <= end
            ]
        ).reshape(-1, 3)
        over = (inside[None, :, 0] <= centres[:, None]) & (centres[:, None] < inside[None, :, 1])
        n_over = over.sum(axis=1)
        mean = (over * inside[None, :, 2]).sum(axis=1) / np.maximum(n_over, 1)
        out = np.empty(len(centres))
        for k in range(len(centres)):  # over the hops passed (a few): carry the last evidence
            if n_over[k]:
                self.carried = float(mean[k])
            out[k] = self.carried
        return out

    @staticmethod
    def _rejudged(window: _Window, judge: Judge) -> float:
        """``window``'s evidence of unknown by ``judge`` (:func:`cbr.unknown.unknown_evidence`;
        1.0 when too still for any activity); as judged then when it showed nobody."""
        one = window[3]
        if one is None:
            return window[2]
        return 1.0 if one.still else unknown_evidence(judge, one.nearest)

    def _pass(self, until: float, end: int, final: bool = False) -> list[LiveSegment]:
        """Pass the settled hops of the stretch in progress not passed yet, up to centre
        ``until``, to pass 2, judged by the windows that stop by ``end``; finish the segments
        that settles (``final``: the stream has ended: every hop)."""
        centres = np.array(self.hop_centres)
        settled = len(centres) if final else len(centres) - len(self.forward.back)
        hops = np.flatnonzero(
            (centres[:settled] > self.passed)
            & (centres[:settled] >= self.stretch_start)
            & (centres[:settled] <= until)
        )
        if len(hops):
            assert self.settled is not None
            activity = self.settled
            shares = self._evidence(centres[hops], self.stretch_start, end)
            pen = self._penalty()
            moved = np.array([[pen, pen], [pen, 0.0]])  # a change under unknown is free
            for i, share in zip(hops.tolist(), shares.tolist(), strict=True):
                change = None
                if not self.stretch_passed and self.known.started:
                    change = self.stretch_start
                self.stretch_passed = True
                self.pending.append(_Hop(centres[i], activity, float(self.votes[i][activity]),
                                         share, change))  # fmt: skip
                score = log_votes(np.array([1.0 - share, share]))
                self.known.step(score, moved if change is not None else None)
            self.passed = float(centres[hops[-1]])
            self.windows = [w for w in self.windows if w[1] > self.passed]
            self.periods = [w for w in self.periods if w[1] > self.passed - self.span]
        return self._follow(self.known.settle(final=final, most=self.most))

    def _follow(self, unknown: list[int]) -> list[LiveSegment]:
        """Follow the hops pass 2 newly settled (``unknown``: 1 where unknown, in order, the
        oldest of :attr:`pending`): each change of the label seen finishes the segment in
        progress, at the change of activity when one lies there, else midway between the
        two hops. A hop within a stretch of :data:`MIN_SEGMENT_S` or more with nobody in view
        is seen as nobody, whatever its evidence, and such a stretch is a segment of its own
        from the frame the person is lost to the frame they are seen again (as offline); an
        unknown stretch of less than :data:`MIN_SEGMENT_S` after it joins the activity that
        follows (its windows, half empty, are like no activity), or the stretch when nobody is
        in view again after it (the person seen for a flicker): :meth:`_after_nobody`."""
        finished = []
        for hop, far in zip(self.pending[: len(unknown)], unknown, strict=True):
            seen = self.unknown if far else hop.activity
            run = self._blind_run(hop.centre)
            if run is not None:
                seen = self.nobody
            if self.seen is None:
                own = self.unknown if far else hop.activity
                self.seen = self._first_seen(hop.centre, seen, run, own)
            if self.seen == self.nobody and seen == self.unknown:
                finished += self._after_nobody(hop)
            elif seen != self.seen:
                if run is not None:  # nobody from the frame the person was lost
                    boundary = run[0]
                elif self.seen == self.nobody:  # to where they are seen (held hops: after)
                    boundary = self._blind_end()
                else:
                    mid = int(round((self.last_centre + hop.centre) / 2))
                    boundary = hop.change if hop.change is not None else mid
                finished += self._change(max(self.seen_start + 1, boundary), seen)
            if run is not None:
                self.blind_hop, self.held = hop.centre, []
            elif self.seen != self.nobody:
                self.seen_sum[0] += hop.unlike if far else hop.vote
                self.seen_sum[1] += 1.0
            self.last_centre = hop.centre
        del self.pending[: len(unknown)]
        return finished

    def _first_seen(self, centre: float, seen: int, run: tuple[int, int] | None, own: int) -> int:
        """The label seen of the stream's first segment, its first hop (at ``centre``) seen
        as ``seen``: nobody in view when a stretch of :data:`MIN_SEGMENT_S` or more with
        nobody in view opens the stream and ends by that hop (which no hop then lies in: the
        first hop's evidence is of the middle of the first window, a second in, so a lead-in
        of exactly a second), the hop then following it as one after such a stretch does, as
        offline (:func:`cbr.segmentation.nobody_blocks`: every block from the first). Before,
        the lead-in joined the first segment, unknown by its half-empty windows, where
        ``segment`` gave it as nobody in view. When the hop lies in such a stretch (``run``)
        that begins after the stream's first frame, the frames before it show the person:
        the first segment is theirs, seen as the hop's own label ``own`` (its activity, or
        unknown), as offline the decoder's path gives them, and nobody in view begins where
        the person is lost (hunt 50c: before, the person's first 0.5 s joined the stretch)."""
        if run is not None and run[0] > self.seen_start:
            return own
        lead = next((run for run in self.blind if run[1] <= centre), None)
        if lead is None:
            return seen
        self.blind_hop = float(lead[0])  # where the stretch lies (:meth:`_blind_end`)
        return self.nobody

    def _change(self, boundary: int, seen: int) -> list[LiveSegment]:
        """The label seen changes to ``seen`` at frame ``boundary``: the segment in progress
        is finished there (an unknown one before nobody in view too, however short: its
        frames show the person, as offline, :func:`cbr.segmentation.finish`)."""
        assert self.seen is not None
        lost = seen == self.nobody
        done = self._given(self._segment(self.seen_start, boundary, self.seen, True, lost=lost))
        self.seen, self.seen_start, self.seen_sum, self.held = seen, boundary, [0.0, 0.0], []
        return done

    def _given(self, segment: LiveSegment) -> list[LiveSegment]:
        """The segments to give now that ``segment`` is finished: the stream's first segment,
        held back and judged since (:attr:`released`), then ``segment``, unless it is that
        first segment, held back (:meth:`_segment`)."""
        out, self.released = self.released, []
        if self.waiting is not None and self.waiting.segment is segment:
            return out
        return [*out, segment]

    def _judge_early(self) -> list[LiveSegment]:
        """The stream's first segment, held back, judged and given once the first repetition
        of the segment after it has come back (counted on the frames pushed since its cut:
        its end known), or once that segment has gone on :data:`MAX_UNSETTLED_S` (on what
        it holds then: the delay is bounded); else nothing yet. The segment after it being
        finished, or the stream ending, judges it too (:meth:`_segment`)."""
        if self.waiting is None:
            return []
        cut = self.waiting.segment.end_frame
        try:
            after = self._count_apart(cut, self.n, (False, False))
        except DataError:  # too short yet, or nobody in view
            after = ()
        back = bool(after) and not (after[0].held[1] or after[0].unreturned[1])
        if not back and self.n - cut < MAX_UNSETTLED_S * self.fps:
            return []
        self._judge_held(after)
        out, self.released = self.released, []
        return out

    def _judge_held(self, after: tuple[Repetition, ...]) -> None:
        """Judge the stream's first segment, held back (:attr:`waiting`; no whole repetition
        of its own), beside ``after``, the repetitions of the segment after it, and release
        it (:attr:`released`): as :func:`cbr.segmentation.counted_segments` judges a far
        point cut off at the recording's start (its ``_beside_whole``), the stream frames
        from the start to the end of the first of ``after`` are counted as one stretch, and
        the far point they keep cut off at the start, lying in the first segment, counts
        there (:func:`cbr.segmentation.cut_off_beside`). Before, dropped: ``watch`` finished
        the first segment before it saw the next, and a glute bridge held as the stream
        starts counted none there where ``segment`` and a count by hand found one
        (docs/measurements.md, "Figures behind the code's rules: watch against segment")."""
        held, self.waiting = self.waiting, None
        assert held is not None
        segment, end = held.segment, held.segment.end_frame
        found: tuple[Repetition, ...] = ()
        if after and self.offset == 0:
            try:
                found = self._count_apart(0, after[0].end_frame, (True, False))
            except DataError:  # too short, or nobody in view
                found = ()
        reps = cut_off_beside(held.own, found, (0, end), self.step, at_end=False)
        if len(reps) > len(held.own):
            kept = keep_whole(reps, 0, end, self.step, False, True, held.held)
            segment = dataclasses.replace(segment, repetitions=len(kept))
        self.released.append(segment)

    def _after_nobody(self, hop: _Hop) -> list[LiveSegment]:
        """An unknown hop after nobody in view: held (:attr:`held`) while the unknown stretch
        is shorter than :data:`MIN_SEGMENT_S` (nobody in view again then: it was a flicker,
        and the stretch goes on; an activity: it begins where the person is seen again,
        :meth:`_follow`), then the nobody segment is finished where the person is seen again
        and the unknown one begins there with the held hops."""
        self.held.append(hop.unlike)
        end = self._blind_end()
        if hop.centre - end < self.least_blind:
            return []
        held = self.held
        finished = self._change(max(self.seen_start + 1, end), self.unknown)
        self.seen_sum = [sum(held[:-1]), float(len(held) - 1)]  # the hop itself: by _follow
        return finished

    def _blind_end(self) -> int:
        """Where the stretch with nobody in view of the segment in progress ends: the end of
        the run that holds its last hop seen as nobody."""
        run = self._blind_run(self.blind_hop)
        return run[1] if run is not None else int(round(self.blind_hop))

    def _repetition_windows(self, n: int) -> None:
        """The periods of the movement found whole in the last :data:`PERIOD_SPAN_S` seconds,
        as offline (:func:`cbr.segmentation.periods_in_span`; spans every
        :data:`SPAN_HOP_S`), each new one solved and judged once: windows of one repetition
        that vote in pass 1 and are evidence in pass 2 (a stretch shorter than a fixed window
        holds none of those)."""
        a = max(self.offset, n - self.span)
        try:
            sig = movement_signals(self._sequence(a, n))
        except DataError:  # nobody in view
            return
        new = [
            (a + first, a + last)
            for first, last in periods_in_span(sig, self.fps)
            if (a + first, a + last) not in self.found
        ]
        self.found = {f for f in self.found if f[1] > n - 2 * self.span} | set(new)
        self.period_votes = [w for w in self.period_votes if w[1] > n - 2 * self.span]
        clips = [self._with_context(b, c) for b, c in new]
        shown = [(w, clip) for w, clip in zip(new, clips, strict=True) if _shown(clip)]
        if not shown:
            return
        solved = self.clf.solve([clip for _, clip in shown], flag=False)
        for ((b, c), _), one in zip(shown, solved, strict=True):
            vote, far = self._judged(one, b, c)
            self.periods.append((b, c, far, self.judged[-1]))
            if far < 1.0:
                self.period_votes.append((b, c, vote))

    def _trim(self) -> None:
        """Forget frames and hops no segment in progress or decision can need (nor the
        stream's end: the frames from the last repetition of the segment finished last,
        :meth:`_beside_whole`), the repetitions of the segment in progress tallied first
        (:meth:`_tally`)."""
        self._tally()
        begun = min(self.seen_start, self.stretch_start)
        if self.waiting is not None:  # the first segment, held back: from the stream's start
            begun = 0
        if self.beside is not None:
            begun = min(begun, self.beside)
        keep_from = max(begun, self.n - int(MAX_SEGMENT_S * self.fps)) - self.window
        keep_from = min(keep_from, self.n - self.span)  # the next span's frames
        drop = keep_from - self.offset
        if drop > self.window:
            del self.frames[:drop], self.seen_by[:drop]
            self.offset += drop
            self.jumps = [j for j in self.jumps if j > self.offset]
        settled = len(self.hop_centres) - len(self.forward.back)
        old = sum(f <= self.passed for f in self.hop_centres[: max(0, settled - 1)])
        if old:  # hops passed to pass 2 (the last settled kept: _between)
            del self.votes[:old], self.hop_centres[:old]
        kept = [w for w in self.judged if w.stop > self.seen_start and w.start >= self.offset]
        self.judged = kept  # of the segments not finished, over frames still kept
        followed = self.blind_hop if self.seen == self.nobody else self.last_centre
        self.blind = [run for run in self.blind if run[1] > followed]  # hops still to follow
        # the gaps of the video: read only for a segment with nobody in view, which begins
        # no earlier than the segment in progress, the run without the torso in progress or
        # one still to follow, or the frames still kept (every later change lies after those)
        starts = [self.offset, *(a for a, _ in self.blind)]
        if self.seen == self.nobody:
            starts.append(self.seen_start)
        if self.blind_from is not None:
            starts.append(self.blind_from)
        needed = min(starts) - self.longest
        while self.absent and self.absent[0][1] <= needed:
            del self.absent[0]

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        """The last window's vote over the activities ``(n_classes,)`` (its nearest case's)
        and how much it says it is unlike every activity (:func:`cbr.unknown.unknown_evidence`:
        1.0 when unlike; 0.5 when it shows nobody, whose vote is every activity alike). Only a
        window not unlike every activity votes for one (:func:`_mean_vote`), as offline
        (:func:`cbr.segmentation.decode_activities`): one like none, across a change of
        movement or of one the case base lacks, is nearest to whichever lies least far."""
        window = self._with_context(n - self.window, n)
        if not _shown(window):  # no person: no evidence either way
            return np.full(self.unknown, 1.0 / self.unknown), 0.5
        solved = self.clf.solve([window], flag=False)[0]
        return self._judged(solved, n - self.window, n)  # the judge: unknown

    def _last_judged(self, start: int, stop: int) -> _Judged | None:
        """The window of frames [start, stop) just judged (:meth:`_judged`), or None: it
        showed nobody, and was not."""
        last = self.judged[-1] if self.judged else None
        return last if last is not None and (last.start, last.stop) == (start, stop) else None

    def _with_context(self, a: int, b: int) -> PoseSequence:
        """Stream frames [a, b) as a clip whose motion states keep up to a window of the
        frames before ``a`` as context (:func:`features.derived.stretch`), as a window cut
        from a recording (``segment``) or a training clip (``train --split windows``) keeps
        them: cut cold, a window that begins part-way through a movement read its first
        frames as still."""
        first = max(self.offset, a - self.window)
        if first == a:
            return self._sequence(a, b)
        # a window without the hips is judged on its arms, its context read without them too
        whole = self._sequence(first, b, hipless=arms_alone(self._sequence(a, b)))
        config = self.clf.feature_config_
        warm(whole, config.level, mirror=config.side == "canonical")
        return stretch(whole, a - first, b - first)

    def _judged(self, solved: Any, start: int, stop: int) -> tuple[np.ndarray, float]:
        """A solved window's (frames [start, stop)) vote for its nearest case's activity
        ``(n_classes,)`` and its evidence of unknown (:func:`cbr.unknown.unknown_evidence`, by
        the judge of the person as the windows so far show them:
        :func:`cbr.unknown.for_person`); kept to explain the segment it lies in
        (:meth:`_explain`)."""
        # its k nearest cases' votes, as the classifier votes and as offline
        # (cbr.segmentation.votes_as); k = 1: its nearest case's activity alone
        nearest_k = np.asarray(solved.retrieval.indices[: self.k])
        distances = np.asarray(solved.retrieval.distances[: self.k], dtype=float)
        vote = np.asarray(votes_as(self.clf, distances[None], self.codes[nearest_k][None])[0])
        activity = int(np.argmax(vote))
        nearest = activity_distances(self.clf, solved, self.codes)
        if np.isfinite(np.min(nearest)):
            self.near.append(float(np.min(nearest)))
        judge = for_person(self.judge, np.array(self.near))
        # as offline (cbr.segmentation._solve_distinct): too still for any activity, unknown
        still = window_still(solved, self.movement, self.least)
        self.judged.append(
            _Judged(start, stop, activity, judge.ratio(nearest), nearest, judge, still)
        )
        return vote, 1.0 if still else unknown_evidence(judge, nearest)

    def _explain(self, start: int, end: int, state: int) -> tuple[str, float]:
        """A finished segment's explanation and novelty (the judge's ratio, median over its
        windows), as ``segment`` gives them (:func:`cbr.segmentation.told`), from the windows
        centred in frames [start, end) (those over it when none is): unknown, told by
        :func:`cbr.unknown.tell_unknown`; an activity, by the window whose nearest activity
        it is most clearly (the least ratio), solved again from its frames, or when none of
        them is nearest to it (a segment the decoders' evidence around it gave, a hop or two
        long), by the one that lies least far from it, as ``segment`` tells such a segment by
        one of its windows (:func:`cbr.segmentation._explain_segment`). Before, "": a squat
        streamed after seconds of nobody had a short segment of another activity explained by
        nothing (docs/measurements.md, "Figures behind the code's rules: watch against segment")."""
        inside = [w for w in self.judged if start <= w.centre < end]
        inside = inside or [w for w in self.judged if w.start < end and w.stop > start]
        if not inside:
            return "", math.nan
        novelty = float(np.median([w.ratio for w in inside]))
        if state == self.unknown and sum(w.still for w in inside) > len(inside) / 2:
            return STILL_TEXT, novelty
        if state == self.unknown:
            return tell_unknown([(w.judge, w.nearest) for w in inside], self.classes), novelty
        kept = [w for w in inside if w.start >= self.offset]  # its frames kept: solved again
        telling = [w for w in kept if w.activity == state]
        if telling:
            w = min(telling, key=lambda t: t.ratio)
        elif kept:  # none nearest to it: the window that lies least far from it
            w = min(kept, key=lambda t: float(t.nearest[state]))
        else:
            return "", novelty
        solved = self.clf.solve([self._sequence(w.start, w.stop)], flag=False)[0]
        return told(self.clf, solved, self.classes[state]), novelty

    def recent(self, frames: int) -> PoseSequence:
        """The last ``frames`` frames pushed, as a clip (fewer when the older ones are no
        longer kept). ``frames`` not a whole number > 0, or no frame pushed yet, is refused
        (InputError) saying so."""
        if not (
            is_number(frames) and math.isfinite(frames) and frames == int(frames) and frames > 0
        ):
            raise InputError(f"recent needs a number of frames > 0, got {frames!r}", self.source)
        if not self.n:
            raise InputError("recent: no frame has been pushed yet", self.source)
        return self._sequence(max(self.offset, self.n - int(frames)), self.n)

    def clip(self, start: int, end: int) -> PoseSequence:
        """Stream frames [start, end) as a clip cut from the stream, as ``classify --split
        repetitions`` cuts a piece of a recording (its ``frame_offset`` ``start``): a
        repetition of :meth:`repetitions_from` to judge. Frames no longer kept, or an empty
        range, are refused (DataError)."""
        return self._sequence(start, end).with_metadata(frame_offset=int(start))

    def repetitions_from(self, start: int) -> tuple[tuple[int, int], ...]:
        """The frames [start, end) of each repetition counted in the stream frames from
        ``start`` (those still kept) to the last pushed, counted as ``segment`` counts a
        stretch cut there (:meth:`_in_context`: with the frames either side as context, the
        stream's start and, once it has ended, its end as a recording's), whatever the
        segments: the count ``watch --split repetitions`` judges, as ``classify --split
        repetitions`` counts a whole recording. The last may be one still in progress
        (its end where the frames end). ``start`` not a whole number >= 0 (True and False
        too: not frame numbers, though Python counts them as ints): InputError."""
        if isinstance(start, bool) or not (isinstance(start, int | np.integer) and start >= 0):
            raise InputError(f"start must be a frame number >= 0, got {start!r}", self.source)
        reps = self._count_kept(int(start), self.n, (False, False))
        return tuple((int(r.start_frame), int(r.end_frame)) for r in reps)

    def _sequence(self, a: int, b: int, hipless: bool = False) -> PoseSequence:
        """Stream frames [a, b) as a clip (``a`` >= :attr:`offset`: frames not yet dropped);
        ``hipless``: with the hips missing in every frame (the frames kept are not changed)."""
        if a < self.offset or b <= a:
            raise DataError(f"stream frames {a}-{b} are no longer kept (from {self.offset})",
                            self.source)  # fmt: skip
        rows = self.frames[a - self.offset : b - self.offset]
        seen = self.seen_by[a - self.offset : b - self.offset]
        confidence = None
        if any(c is not None for c in seen):  # a frame without stays unknown (NaN)
            confidence = np.stack([np.full(len(BLAZEPOSE_33), np.nan) if c is None else c
                                   for c in seen])  # fmt: skip
        positions = np.stack(rows)  # a copy
        if hipless:
            positions[:, self.hips] = np.nan
        return PoseSequence(
            positions, BLAZEPOSE_33, self.fps, confidence=confidence, source=self.source
        )

    def _confidence(self, state: int) -> float:
        """Of the segment in progress labelled ``state``: the mean over the hops pass 2 has
        settled in it of their vote for its activity, or of their evidence of unknown; the
        latest windows' while it has none, or when ``state`` is the rolling label and not the
        one pass 2 has settled."""
        total, count = self.seen_sum
        if count and state == self.seen:
            return float(total) / count
        if state == self.unknown:
            return self._unlike_now()
        return float(self.votes[-1][state]) if self.votes else 0.0

    def _segment(
        self,
        start: int,
        end: int,
        state: int,
        cut: bool,
        explained: bool = True,
        lost: bool = False,
    ) -> LiveSegment:
        """:meth:`_counted`'s segment."""
        return self._counted(start, end, state, cut, explained, lost)[0]

    def _counted(
        self,
        start: int,
        end: int,
        state: int,
        cut: bool,
        explained: bool = True,
        lost: bool = False,
    ) -> tuple[LiveSegment, tuple[Repetition, ...]]:
        """Frames [start, end) as a segment of ``state`` (an activity, or n_classes: unknown;
        :meth:`_confidence`); ``cut``: it ends where another begins (a finished segment: its
        repetitions are counted as :func:`cbr.segmentation.keep_whole` says, and the next one
        learns whether the movement turned at the cut; a last far point held up to the cut,
        the movement within :data:`features.repetitions.MIN_EXCURSION_RAD` of it, and on in
        the frames already pushed beyond it (:meth:`_held_beyond`), is left to the next
        segment, where the movement comes back: a squat held at the bottom through a change
        of label counts once, as :func:`cbr.segmentation.counted_segments` counts it, though
        the segment is finished before the next one is). Repetitions are counted over at most
        its last :data:`MAX_SEGMENT_S` seconds, of the frames still kept; a segment whose
        frames never show anybody is unknown, whatever the tie between its windows' evidence
        (every activity alike, known as likely as not) fell to. Nobody in view (``state``
        n_classes + 1): unknown, told so, counted 0, as offline; ``lost``: the segment after
        this one is nobody in view: a far point at the cut (the person lost from view on the
        way out to it, or held there) is left to the segment where the person is seen again,
        as at a cut: that segment is counted from the far point's repetition on, through the
        stretch with nobody in view (filled in, :attr:`lost_from`), as
        :func:`cbr.segmentation.counted_segments` counts the movement on across it (down
        into a squat, lost, seen again on the way up or standing: one repetition); where the
        person is not seen again, no repetition was seen finished, and it counts none (the
        way down of a squat, the person then lost). Before, this segment kept it: the way
        down of a squat, the person then lost, counted 1, and seen again on the way up,
        2. A segment that has run longer than :data:`TALLY_S` twice over adds the
        repetitions tallied before the frames it is counted on (:meth:`_tally`). Returns the
        segment and the repetitions it counts on those frames."""
        if state == self.nobody:
            if cut:  # no movement turns at its end
                self.turn = self.holding = False
                self.beside = None
                self.last_cut = _Cut((), (start, end), True, False)
            told = nobody_explanation(self._absent_in(start, end))
            return LiveSegment(start, end, None, 1.0, 0, told), ()
        first, tallied = self._first_counted(start, end, state)
        reps: tuple[Repetition, ...] = ()
        # the stream's own start and (once finished) end are the recording's, as offline
        # (cbr.segmentation._repetitions): part of one repetition there is none
        edges = (first == 0, not cut and explained)
        if end > first:
            clip = self._sequence(first, end)
            if not _shown(clip):
                state = self.unknown
            try:
                reps = self._count_apart(first, end, edges)
            except DataError:  # too short, or nobody in view
                pass
        self._judge_after(start, reps, cut or explained)
        if not cut and explained:  # the stream's last segment, the stream ended
            reps = self._beside_whole(start, end, reps)
        confidence = self._confidence(state)
        turn = self.turn and first == start
        # the last far point held up to the cut (a squat held at the bottom through a change
        # of label): the movement comes back beyond it, where the next segment counts it
        held = cut and not lost and bool(reps) and self._held_beyond(end, reps[-1])
        passed_on = 0
        if cut and not lost and reps and not held and self._still_beyond(end, reps[-1]):
            reps, held, passed_on = self._held_on(first, end, edges, reps)
        mine = self._mine(start, first, end, reps, held, cut and not lost)
        counted = self._after_still(start, first, end, edges, reps)
        kept = keep_whole(counted, first, end, self.step, turn or mine[0], cut and not mine[1],
                          held)  # fmt: skip
        left = self._left_when_lost(lost, counted, kept, end)
        self.lost_from = None if left is None else (left, state)
        if cut:
            self._finished(reps, first, end, held, passed_on)
        kept = self._unless_got_into(kept, end, not cut and explained)
        count = tallied + len(kept)
        if not cut and explained and self.holding and not reps and not tallied:
            # the stream ended still in a hold passed on from a segment before: its far
            # point counts here, as it would have there had the stream ended sooner
            count += self.passed_on
        label = None if state == self.unknown else self.classes[state]
        text, novelty = self._explain(start, end, state) if explained else ("", math.nan)
        out = LiveSegment(start, end, label, float(confidence), count, text, novelty)
        self._hold(out, first, reps, held, cut and not lost)
        return out, kept

    def _first_counted(self, start: int, end: int, state: int) -> tuple[int, int]:
        """The first frame the repetitions of the segment of frames [start, end), labelled
        ``state``, are counted from, and how many of its repetitions before it are tallied
        (:meth:`_tally`: from where the tally ends); at most its last :data:`MAX_SEGMENT_S`
        seconds of the frames still kept; right after a segment with nobody in view
        (:attr:`last_cut`) that took over from one of the same activity whose far point the
        person was lost at, from that far point's repetition on (:attr:`lost_from`), across
        the stretch, as offline (:func:`cbr.segmentation.counted_segments`: another activity
        after the stretch does not finish it)."""
        first = max(start, end - int(MAX_SEGMENT_S * self.fps), self.offset)
        lost_from, self.lost_from = self.lost_from, None
        tally = self.tally
        if tally is not None and tally.start == start and tally.upto < end:
            return max(first, tally.upto), tally.counted
        prior = self.last_cut
        if lost_from is None or lost_from[1] != state:
            return first, 0
        if prior is None or not prior.blind or prior.bounds[1] != start:
            return first, 0
        first = max(min(first, lost_from[0]), end - int(MAX_SEGMENT_S * self.fps), self.offset)
        return first, 0

    def _tally(self) -> None:
        """Tally the repetitions of the segment in progress once more than :data:`TALLY_S`
        of the frames it is counted on (from its start, or from where the last tally ended)
        lie :data:`TALLY_S` before the latest frame and before any frame a cut of the
        segment can still fall on (:meth:`_settled_until`): counted as :meth:`current`
        counts them, those that end by then are added to the tally, and the segment is
        counted from the end of the last of them on (the movement back at rest, between two
        repetitions); with none, from the first that runs on past that frame, or from that
        frame when none does (the frames before it hold no repetition). While the decoders
        leave the cut open further back, nothing is tallied, and the segment is counted over
        the frames kept (:data:`MAX_SEGMENT_S`), as before."""
        if self.seen is None or self.seen == self.nobody or self.ended:
            return
        start, tally = self.seen_start, self.tally
        if tally is None or tally.start != start:
            tally = _Tally(start, start, 0)
        until = min(self._settled_until(), self.n - TALLY_S * self.fps)
        if until - max(tally.upto, self.offset) <= TALLY_S * self.fps:
            return
        lost_from = self.lost_from  # as current(): asking changes nothing
        try:
            _, reps = self._counted(start, self.n, self.seen, False, False)
        finally:
            self.lost_from = lost_from
        done = [r for r in reps if r.end_frame <= until]
        if done:
            upto = done[-1].end_frame
        else:
            across = [r.start_frame for r in reps if r.start_frame < until < r.end_frame]
            upto = int(min([until, *across]))
        self.tally = _Tally(start, max(tally.upto, upto), tally.counted + len(done))

    def _settled_until(self) -> float:
        """The earliest frame a cut of the segment in progress can still fall on, less the
        longest window: no earlier than the last hop pass 2 settled (a later change falls
        after it) nor than a stretch with nobody in view still to be followed, or in
        progress, begins (where the person was lost)."""
        lost = [a for a, _ in self.blind]
        if self.blind_from is not None:
            lost.append(self.blind_from)
        return min([self.last_centre, *lost]) - self.longest

    def _left_when_lost(
        self, lost: bool, counted: tuple[Repetition, ...], kept: tuple[Repetition, ...], end: int
    ) -> int | None:
        """Of a segment finished at frame ``end`` where the person is lost from view
        (``lost``; its repetitions ``counted``, ``kept`` by
        :func:`cbr.segmentation.keep_whole`), the first frame of the repetition whose far
        point, at the cut, it left to the segment where the person is seen again
        (:attr:`lost_from`); None when it left none, or the person is not lost there."""
        if lost and len(kept) < len(counted) and counted[-1].peak_frame >= end - self.step:
            return counted[-1].start_frame
        return None

    def _hold(
        self,
        segment: LiveSegment,
        first: int,
        reps: tuple[Repetition, ...],
        held: bool,
        finished: bool,
    ) -> None:
        """Hold ``segment`` back (:attr:`waiting`) when it is the stream's first, being
        ``finished`` at a cut with a segment after it that shows somebody, counted from the
        stream's first frame (``first``), and none of ``reps``, its repetitions, is whole: a
        far point cut off by the start is judged beside the segment after it
        (:meth:`_judge_held`); ``held``: its last far point is left to that segment."""
        if finished and first == 0 and not whole_in(reps):
            self.waiting = _HeldBack(segment, reps, held)

    def _judge_after(self, start: int, reps: tuple[Repetition, ...], given: bool) -> None:
        """When the segment starting at ``start`` (its repetitions ``reps``) is the one after
        the stream's first, held back, and is being given (``given``: finished, or the
        stream's last once it has ended), judge that first one beside it
        (:meth:`_judge_held`)."""
        if given and self.waiting is not None and start == self.waiting.segment.end_frame:
            self._judge_held(reps)

    def _finished(
        self, reps: tuple[Repetition, ...], first: int, end: int, held: bool, passed_on: int
    ) -> None:
        """What a segment finished at the cut ``end`` (its repetitions ``reps``, counted on
        frames [first, end); ``held``, ``passed_on``: its last far point left to the segment
        after, and what that counts if the stream ends in the hold, :meth:`_held_on`) leaves
        the segments after it: whether the movement turned at the cut and the far point is
        held on, the frames the one that holds it was got into from, and the last
        repetition the stream's last segment is judged beside (:meth:`_beside_whole`)."""
        self.beside = reps[-1].start_frame if reps else None
        self.last_cut = _Cut(reps, (first, end), False, held)
        if reps:
            self.turn = at_cut(reps, first, end, self.step)[1] or held
            self.holding = held
            self.passed_on = passed_on
            self.held_from = reps[0].start_frame
        elif not self.holding:  # held on through a segment all hold, else no turn
            self.turn = False

    def _after_still(
        self,
        start: int,
        first: int,
        end: int,
        edges: tuple[bool, bool],
        reps: tuple[Repetition, ...],
    ) -> tuple[Repetition, ...]:
        """``reps``, the one repetition of the segment of frames [start, end) (counted on
        frames [first, end) with ``edges``), counted again with its start settled when the
        segment finished before it (:attr:`last_cut`) has no far point at all and none is held
        on through it: that cut is as the recording's start, nothing turns there, and one far
        point got into and held is no repetition
        (:func:`features.repetitions.count_in_signals`' ``settled``), as
        :func:`cbr.segmentation.counted_segments` counts a segment after one with none.
        Before, counted: a side plank whose label changes before the plank is got into
        counted a repetition in ``watch``'s segment after the change, none in ``segment``'s
        and by ``reps`` (docs/measurements.md, "Figures behind the code's rules: watch
        against segment"). Other ``reps`` as they are."""
        prior = self.last_cut
        if len(reps) != 1 or first != start or prior is None or prior.bounds[1] != start:
            return reps
        if prior.raw or self.holding:
            return reps
        try:
            return self._count_apart(first, end, edges, (True, False))
        except DataError:  # too short, or nobody in view
            return reps

    def _mine(
        self,
        start: int,
        first: int,
        end: int,
        reps: tuple[Repetition, ...],
        held: bool,
        cut: bool,
    ) -> tuple[bool, bool]:
        """Whether the segment of frames [start, end) (its repetitions ``reps``, counted on
        frames [first, end); ``held``: its last far point is left to the segment after;
        ``cut``: it is finished at a cut the person stays in view across) keeps a far point
        at its start, and one at its end, that the segment across that cut does not take, as
        ``segment`` keeps it (:func:`cbr.segmentation.unclaimed`, asked of the segment
        finished before, :attr:`last_cut`, and of the frames pushed beyond the cut, counted
        alone, as the segment after as far as it has come). Before, dropped by both: the
        last repetition of an exercise turning just before the label changed counted in
        neither segment."""
        if not reps:
            return False, False
        at_start, at_end = at_cut(reps, first, end, self.step)
        prior = self.last_cut
        before = at_start and first == start and prior is not None and prior.bounds[1] == start
        after = at_end and cut and self.n > end
        if not (before or after):
            return False, False
        kept = _Kept(self.step, self._count_kept)
        raw, bounds, blind, held_on = [reps], [(first, end)], [False], [held]
        if before:
            assert prior is not None
            raw, bounds = [prior.raw, *raw], [prior.bounds, *bounds]
            blind, held_on = [prior.blind, *blind], [prior.held, *held_on]
        if after:
            raw.append(self._count_kept(end, self.n, (False, False)))
            bounds.append((end, self.n))
            blind.append(False)
            held_on.append(False)
        return unclaimed(kept, raw, bounds, blind, held_on, self.n)[int(before)]

    def _count_kept(
        self, start: int, end: int, settled: tuple[bool, bool]
    ) -> tuple[Repetition, ...]:
        """:meth:`_count_apart` of the stream frames [start, end) still kept (none: no
        repetition), the stream's start and, once it has ended, its end as a recording's."""
        first, stop = max(start, self.offset), min(end, self.n)
        if stop <= first:
            return ()
        try:
            return self._count_apart(first, stop, (first == 0, self.ended and stop >= self.n),
                                     settled)  # fmt: skip
        except DataError:  # too short, or nobody in view
            return ()

    def _count_apart(
        self,
        first: int,
        end: int,
        edges: tuple[bool, bool],
        settled: tuple[bool, bool] = (False, False),
    ) -> tuple[Repetition, ...]:
        """The repetitions of stream frames [first, end) (:meth:`_in_context`, ``edges`` and
        ``settled`` of those frames' start and end), in stream frames, counted apart on
        either side of each frame where the pose jumped to another person (:attr:`jumps`), as
        :func:`cbr.segmentation.counted_apart` counts a segment across one: each piece as a
        segment of its own (DataError: none), a far point at the jump left to the piece after
        unless the movement turns there on both sides (:func:`cbr.segmentation.keep_whole`),
        a piece beside one with no far point settled at that jump; the jump from one
        person's posture to the other's is no movement. Before, a repetition ran on across
        it. Without a jump in them: :meth:`_in_context` of the frames (DataError raised)."""
        cuts = [first, *(j for j in self.jumps if first < j < end), end]
        if len(cuts) == 2:
            return self._in_context(first, end, edges, settled)
        pieces = list(zip(cuts[:-1], cuts[1:], strict=True))
        last = len(pieces) - 1

        def count(k: int, inner: tuple[bool, bool]) -> tuple[Repetition, ...]:
            a, b = pieces[k]
            outer = (edges[0] and k == 0, edges[1] and k == last)
            still = (settled[0] if k == 0 else inner[0], settled[1] if k == last else inner[1])
            try:
                return self._in_context(a, b, outer, still)
            except DataError:  # too short, or nobody in view
                return ()

        raw = [count(k, (False, False)) for k in range(len(pieces))]
        out: list[Repetition] = []
        turn = False  # the piece before had a far point at the jump
        for k, (a, b) in enumerate(pieces):
            reps = raw[k]
            inner = (k > 0 and not raw[k - 1], k < last and not raw[k + 1])
            if len(reps) == 1 and any(inner):
                reps = count(k, inner)
            # the frames' own start and end: as the segment's (_segment's keep_whole)
            out += keep_whole(reps, a, b, self.step, turn or k == 0, k < last)
            turn = bool(raw[k]) and at_cut(raw[k], a, b, self.step)[1]
        return tuple(out)

    def _in_context(
        self, first: int, end: int, edges: tuple[bool, bool], settled: tuple[bool, bool]
    ) -> tuple[Repetition, ...]:
        """The repetitions of stream frames [first, end), in stream frames, counted as
        ``segment`` counts a segment (:func:`cbr.segmentation.repetitions_in`; ``edges``,
        ``settled`` as there): on the movement signals of those frames and of up to
        :data:`CONTEXT_S` of the frames kept either side (none across a frame where the pose
        jumped to another person), which the running median and smoothing read across the
        frames' ends as a whole recording's signals do at a cut (none beyond an end that is
        the recording's: where the person was lost for good). Before, on the frames' own
        signals, which bend at their ends: a far point at a cut lay a sample off where
        ``segment`` found it, and the two gave it to different segments. DataError: the
        frames are shorter than one repetition can be (:data:`MIN_PERIOD_S`), or show
        nobody."""
        if end - first < MIN_PERIOD_S * self.fps:
            raise DataError(f"stream frames {first}-{end} are shorter than one repetition can be"
                            f" ({MIN_PERIOD_S:g} s)", self.source)  # fmt: skip
        reach = int(math.ceil(CONTEXT_S * self.fps))
        lo = max([self.offset, first - reach, *(j for j in self.jumps if j <= first)])
        lo = min(first, -(-lo // self.step) * self.step)  # on the stream's samples
        hi = min([self.n, end + reach, *(j for j in self.jumps if j >= end)])
        if edges[1]:  # nothing beyond a recording's end (the person lost there for good)
            hi = end
        sig = movement_signals(self._sequence(lo, hi))
        to_end = self.ended and end >= self.n
        found = repetitions_in(sig, first - lo, end - lo, to_end, edges, settled)
        return tuple(_shifted(r, lo) for r in found)

    def _beyond(self, cut: int) -> tuple[Repetition, ...]:
        """The repetitions of the frames pushed after ``cut`` (up to :data:`MAX_SEGMENT_S` of
        them), up to the next frame where the pose jumped to another person (another
        person's are not the movement's going on), counted as the segment after the cut
        (:meth:`_in_context`; the stream's end as a recording's once it has ended)."""
        stop = min(
            [self.n, cut + int(MAX_SEGMENT_S * self.fps), *(j for j in self.jumps if j > cut)]
        )
        return self._in_context(cut, stop, (False, self.ended), (False, False))

    def _held_beyond(self, cut: int, last: Repetition) -> bool:
        """Whether the frames pushed after ``cut`` (the end of a segment being finished: the
        stream runs on past it by the decoders' delay) begin in the hold of ``last``, the
        segment's last far point, held up to the cut
        (:attr:`features.repetitions.Repetition.held`): the first repetition counted on them
        has its far point at their start, or the movement rises to it by less than
        :data:`features.repetitions.MIN_EXCURSION_RAD` from there; or whether, ``last`` not
        come back by the cut (:attr:`features.repetitions.Repetition.unreturned`), they rise
        to a far point of their own without coming back from the cut either, and the two
        repetitions' frames together hold one far point (a shallow dip across the cut, one
        repetition); as :func:`cbr.segmentation.counted_segments` asks of
        the segment after. None counted (the body still in the hold): :meth:`_still_beyond`
        and :meth:`_held_on` say what the segment keeps."""
        if self.n - cut < 2 or not (last.held[1] or last.unreturned[1]):
            return False
        try:
            after = self._beyond(cut)
        except DataError:  # too short, or nobody in view
            return False
        if not after:
            return False
        at_start = after[0].peak_frame < cut + self.step
        if last.unreturned[1] and after[0].unreturned[0] and not at_start:
            # a shallow dip: the two repetitions' frames together hold one far point
            try:
                both = self._count_apart(last.start_frame, after[0].end_frame, (False, False))
            except DataError:
                return False
            return len(both) == 1
        return last.held[1] and (after[0].held[0] or at_start)

    def _still_beyond(self, cut: int, last: Repetition) -> bool:
        """Whether ``last``, the last far point of a segment being finished at ``cut``, is
        held up to the cut (:attr:`features.repetitions.Repetition.held`) and the frames
        pushed beyond it hold no far point: nothing has come back from it yet (a squat held
        at the bottom through a change of label, on to the frames pushed; to the stream's
        end once it has ended)."""
        if self.n - cut < 2 or not last.held[1]:
            return False
        try:
            return not self._beyond(cut)
        except DataError:  # too short, or nobody in view
            return False

    def _beside_whole(
        self, start: int, end: int, reps: tuple[Repetition, ...]
    ) -> tuple[Repetition, ...]:
        """``reps``, the repetitions of the stream's last segment, frames [start, end), the
        stream ended, with a far point cut off by the end judged beside the last repetition
        of the segment finished before (:attr:`beside`, while kept), as
        :func:`cbr.segmentation.counted_segments` judges one cut off by the recording's end
        (its ``_beside_whole``): a segment with no whole repetition of its own has nothing to
        measure a far point cut off at its end against and drops it, so the stream frames
        from that repetition to the end are counted as one stretch, and the far point they
        keep cut off at the end, lying in this segment, is added
        (:func:`cbr.segmentation.cut_off_beside`).
        Before, dropped: squats, a change of label in the standing after them, and the
        stream ending on the way down of one more, counted 2 and 0 where ``segment`` counts
        2 and 1. Nothing beside a segment with none or with nobody in view, nor for a
        segment with a whole repetition of its own."""
        before = self.beside
        if before is None or before < self.offset or whole_in(reps):
            return reps
        try:
            found = self._count_apart(before, end, (before == 0, True))
        except DataError:  # too short, or nobody in view
            return reps
        return cut_off_beside(reps, found, (start, end), self.step, at_end=True)

    def _unless_got_into(
        self, kept: tuple[Repetition, ...], end: int, last: bool
    ) -> tuple[Repetition, ...]:
        """``kept``, the repetitions of a segment ending at ``end`` (``last``: the stream's
        last, the stream ended), without the far point held on into it when that was a
        posture got into and held: the stream frames from the first repetition of the
        segment that held it (:attr:`held_from`, while kept) to the end, counted as one
        stretch, hold none, as :func:`cbr.segmentation.counted_segments` judges it
        (:func:`cbr.segmentation._held_into_the_end`: a side plank cut in its hold counted a
        repetition where the stream as a whole counts none; docs/measurements.md, "Figures
        behind the code's rules: A posture held across a cut")."""
        if not (last and self.holding and kept) or self.held_from < self.offset:
            return kept
        try:
            found = self._count_apart(self.held_from, end, (self.held_from == 0, True))
        except DataError:  # too short, or nobody in view
            return kept
        return kept if found else kept[1:]

    def _held_on(
        self,
        first: int,
        end: int,
        edges: tuple[bool, bool],
        reps: tuple[Repetition, ...],
    ) -> tuple[tuple[Repetition, ...], bool, int]:
        """A segment being finished, frames [first, end) (counted with ``edges``: ``reps``,
        :meth:`_count_apart`), whose last far point is held on past its end and nothing has
        come back in the frames pushed beyond (:meth:`_still_beyond`): as
        :func:`cbr.segmentation.counted_segments` counts a segment beside one with no far
        point, the cut is as a recording's end beyond which nothing turns, and one far point
        got into and held still up to it is no repetition. The far point is left to the
        segment after, which counts it where the movement comes back or, the stream ending
        still in the hold, counts what this one would have, as ``segment`` counts it
        (:func:`cbr.segmentation.counted_segments`); so too once the stream has ended (before,
        the segment then kept it: two squats and a third held 8 s at the bottom to the end,
        cut in the hold, counted 3 and 0 where a longer hold counted 2 and 1). Returns the
        segment's repetitions, whether its last far point is left to the segment after, and
        how many that counts if the stream ends in the hold."""
        settled = self._count_apart(first, end, edges, settled=(False, True))
        return reps, True, len(settled) - len(reps) + 1

    def current(self) -> LiveSegment | None:
        """The segment in progress, labelled with the rolling label; its confidence and
        repetitions as of the last hop (counted once a hop, not on every frame drawn: a
        count over up to :data:`MAX_SEGMENT_S` of frames takes longer than a frame lasts).
        Asking changes nothing the segments given count by: where a repetition the person was
        lost from view in began (:attr:`lost_from`) is left to the segment when it finishes
        (before, asked for on every frame ``watch --out`` or ``--show`` draws, it cleared
        that, and the segment seen again after the stretch with nobody in view counted the
        repetition no more)."""
        if self.state is None:
            return None
        state = self.unknown if self.label is None else int(self.state)
        key = (self.hops, self.seen_start, state)
        if self.shown is None or self.shown.key != key:
            lost_from = self.lost_from
            try:
                counted = self._counted(self.seen_start, self.n, state, False, False)
            finally:
                self.lost_from = lost_from
            self.shown = _Shown(key, *counted)
        return dataclasses.replace(self.shown.segment, end_frame=self.n)

    def progress(self) -> LiveProgress | None:
        """The segment in progress as the decoders have settled it so far (``watch
        --progress``'s lines): frames [start, latest pushed); the label its line will carry
        when it finishes (the label seen, not the rolling label, which may be a change not
        settled yet that would end the segment before the latest frame); its confidence as
        that line's is reckoned, so far; and, of the repetitions :meth:`current` counts (the
        same count, not counted again: its tally and the repetitions after it), those that
        end by the earliest frame a cut of the segment can still fall on, less the longest
        window (:meth:`_settled_until`, what the tally takes as final): the frames after it
        may yet be cut off into another segment, so its finished line counts at least as
        many; while the person holds still, since when (``still_frame``): the decoders
        settle nothing over a hold (no window of it votes for any activity), so neither the
        label nor the count moves on until the movement comes back (or
        :data:`MAX_UNSETTLED_S` has passed), and the line says why. None before the
        decoders have settled the stream's first hops (some 9 s of stream: no segment's
        label is known yet), and once the stream has ended (:meth:`finish` gave the last
        segment)."""
        if self.ended:
            return None
        now = self.current()
        if now is None or self.seen is None or self.shown is None:
            return None
        start = self.seen_start
        settled = int(min(max(start, self._settled_until()), self.n))
        if self.seen == self.nobody:
            told = nobody_explanation(self._absent_in(start, self.n))
            return LiveProgress(start, self.n, None, 1.0, 0, settled, told)
        label = None if self.seen == self.unknown else self.classes[self.seen]
        later = sum(r.end_frame > settled for r in self.shown.kept)
        count = max(0, now.repetitions - later)
        confidence = self._confidence(self.seen)
        return LiveProgress(start, self.n, label, confidence, count, settled,
                            unknown_reason(label, ""), self.still_from)  # fmt: skip

    def finish(self) -> list[LiveSegment]:
        """The segments not yet finished, at the end of the stream (the last one ends there);
        a stream that ended before its first window (:data:`DEFAULT_WINDOW_S`) but lasted
        the shortest window :func:`cbr.segmentation.segment` takes (:data:`MIN_WINDOW_S`) is
        segmented as that segments such a recording (DataError where it refuses one), but
        one that shows nobody in any frame is a segment with nobody in view, as a longer one
        is (:meth:`_short_stream`). Called again, it returns none: the stream's segments have
        all been given."""
        if self.ended:
            return []
        self.ended = True
        while self.looked < self.n:  # the last frames' sightings, by the frames there are
            self._sighted(self.n)
        if self.state is None:
            return self._short_stream()
        out = self._settle(np.array(self.forward.settle(final=True), dtype=np.int64))
        assert self.settled is not None
        out += self._pass(math.inf, self.n, final=True)
        out += self._lost_at_end()
        assert self.seen is not None
        held = self.held  # seen after nobody in view, no hop followed of it
        tail = self.unknown if self.label is None else int(self.state)  # it: as now
        end = self._blind_end()
        if self.seen == self.nobody and end < self.n:
            # seen again, however briefly: nobody in view holds only frames without the
            # person (as offline, an unknown sliver at the end stays unknown)
            out += self._change(end, tail)
            self.seen_sum = [sum(held), float(len(held))] if tail == self.unknown else [0.0, 0.0]
        return [*out, *self._given(self._segment(self.seen_start, self.n, self.seen, False))]

    def _lost_at_end(self) -> list[LiveSegment]:
        """At the end of the stream, a stretch of :data:`MIN_SEGMENT_S` or more with nobody in
        view that began in the segment in progress and no hop reached (a hop's evidence is
        of the middle of its windows, a second behind the stream: the person lost for the
        last second or two): the segment is finished where the person was lost, keeping a
        far point there (the stretch is a segment of its own, counted 0), as offline
        (:func:`cbr.segmentation.nobody_blocks`). Before, the stretch stayed in the segment,
        and a squat lost from view at the bottom as the stream ended counted none."""
        runs = list(self.blind)
        if self.blind_from is not None and self.looked - self.blind_from >= self.least_blind:
            runs.append((self.blind_from, self.looked))
        late = [r for r in runs if r[0] > self.seen_start]
        if self.seen is None or self.seen == self.nobody or not late:
            return []
        first = late[0][0]
        self.blind_hop = float(first)  # where the stretch lies (:meth:`_blind_end`)
        if len(late) > 1 or late[0][1] < self.n:  # seen again before the stream's end
            return self._change(first, self.nobody)
        # lost for good: the segment ends as the stream would have there, as offline
        # (cbr.segmentation._counted_seen): a far point cut off where the person was lost
        # counts only beside a whole repetition
        done = self._given(self._segment(self.seen_start, first, self.seen, False))
        self.seen, self.seen_start, self.seen_sum, self.held = self.nobody, first, [0.0, 0.0], []
        return done

    def _short_stream(self) -> list[LiveSegment]:
        """The segments of a stream that ended before its first window (:meth:`finish`): as
        :func:`cbr.segmentation.segment` segments such a recording, but one in which no frame
        shows the person is a segment with nobody in view, as such a stretch of a longer
        stream is (before, refused as ``segment`` refuses a recording without a person: "no
        person in view in enough frames to follow a movement (joint angles missing)")."""
        if self.offset or not self.n or self.n < MIN_WINDOW_S * self.fps:
            return []
        if not _shown(self._sequence(0, self.n)):
            return [self._segment(0, self.n, self.nobody, False)]
        jumps = {"frames": list(self.jumps)}  # counted apart, as segment reads a pose file's
        found = segment(self.clf, self._sequence(0, self.n).with_metadata(person_jumps=jumps),
                        self.judge)  # fmt: skip
        return [
            LiveSegment(s.start_frame, s.end_frame, s.label, s.confidence, len(s.repetitions),
                        s.explanation, s.novelty)
            for s in found.segments
        ]  # fmt: skip


def _shown(clip: PoseSequence) -> bool:
    """Whether stream frames ``clip`` (a window, a repetition's, a segment's) show the
    person: the torso in some frame, judged whole as before; or, the hips out of view, the
    arms without a hip in any frame (:func:`features.body.arms_alone`), judged on the arms as
    ``segment`` judges a recording shown from the shoulders up
    (:func:`cbr.segmentation.shoulders_up`; the stream's windows each tell, a stream having
    no whole-recording fact)."""
    return torso_share(clip) > 0.0 or arms_alone(clip)


def _of_world(said: re.Match[str]) -> str:
    """A pose check's words of the positions said of ``push``'s argument, ``world`` (one
    frame: "world contains", where the positions "contain")."""
    verb = {" contain": " contains", " reach": " reaches"}.get(said.group(1) or "", "")
    return "world" + verb


def warm_up(clf: Any, judge: Judge | None = None, fps: float = 30.0, k: int = 1) -> None:
    """Stream a made-up figure moving to and fro through a segmenter of ``clf`` that is then
    dropped: a stream's first decisions (solving and judging a window, finding its periods,
    counting repetitions) load compiled kernels, about 0.4 s, which would otherwise hold up
    the first frames of the real stream and those queued behind them."""
    rng = np.random.default_rng(0)
    figure, sway = rng.normal(size=(2, len(BLAZEPOSE_33), 3))
    seg = LiveSegmenter(clf, fps, judge, k=k)
    t = np.arange(seg.window + seg.span) / fps
    for phase in np.sin(2.0 * np.pi * t / 2.0):  # one repetition every 2 s
        seg.push(figure + 0.1 * phase * sway)
    seg.finish()


__all__ = ["HOP_S", "LiveSegment", "LiveSegmenter", "warm_up"]
