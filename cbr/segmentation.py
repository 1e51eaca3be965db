"""Segmentation of a long recording into activities of a case base, or unknown, with the
repetitions of each segment and a short explanation.

How (the fitted :class:`~cbr.estimator.CaseBaseClassifier` does the classifying, through its
``solve``, exactly as ``classify`` does):

1. what every frame yields (fluents, state signals, mirror image) is computed once for the
   whole recording, or for a recording longer than :data:`cbr.long_clip.CHUNK_FRAMES` once
   per piece of it (each with the history its motion states read); windows share it
   (:func:`features.derived.stretch`);
2. the windows (:func:`windows_of`): one of :data:`DEFAULT_WINDOW_S` every :data:`HOP_S`
   seconds (cut as ``train --split windows`` cuts cases), and every period of the movement
   found in the spans of :data:`PERIOD_SPAN_S` seconds around
   (:func:`features.repetitions.count_in_signals`: a repetition, or two neighbouring ones of
   a movement that alternates sides);
3. every window is a clip to solve and votes for the activity of its nearest case, unless
   it is like none (the judge of step 6 calls it unlike every activity: across a change of
   movement, or of one the case base lacks) or it is a repetition window whose period
   disagrees with its neighbours' (:func:`period_outliers`: found across a change, or a
   multiple of the period);
4. each :data:`BLOCK_S` block gets the mean vote of the voting windows over it, and the
   labels are decoded over all blocks at once (Viterbi): a change of activity must be
   supported by at least :data:`MIN_SEGMENT_S` of evidence at odds of :data:`SWITCH_ODDS` to
   1 (:func:`decode_activities`);
5. each change of activity is then moved to where the two activities' distances cross
   (:func:`place_changes`): the windows around it are split at the change, and the frames of
   each before it are charged the log distance to the activity before, those after it the
   log distance to the one after; the change goes where the charge is least. The votes say
   which activities follow one another; a window's distances say how much of it is which
   (a vote is all or nothing: a window over a change votes for one side whole);
6. stretches unlike every activity of the case base become unknown (:func:`unknown_blocks`):
   every window but the period outliers is judged (:mod:`cbr.unknown`; by default the margin
   between its two nearest activities against the nearest one's own threshold, calibrated on
   the case base; graded between the budget's threshold and the judge's own,
   :func:`cbr.unknown.unknown_evidence`; with one person's case base, of the distances less
   how much farther the recording's person lies from every case, :func:`cbr.unknown.for_person`),
   and known/unknown is
   decoded from the windows that lie within one decoded activity (a window across a change
   of activity is like neither side, whether both are known or not; a block none of them
   covers takes its nearest covered neighbours' evidence, :func:`block_evidence`), every
   change of the label seen costing the same (:func:`decode_unknown`: no sliver of an
   activity left between an unknown stretch and the next change); a stretch of at least
   :data:`MIN_SEGMENT_S` in which no frame shows the person (a glitch of the pose model
   aside, :func:`sighting_width`) is an unknown segment of its own, "nobody in view"
   (:func:`nobody_blocks`);
7. each segment is counted (:func:`features.repetitions.count_repetitions`), each
   repetition in the one segment that holds where its movement turns (:func:`keep_whole`,
   :func:`unclaimed`), and explained by its most confident window.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

import numpy as np

from features.body import (
    arms_alone,
    check_person,
    long_runs,
    majority,
    shown_rows,
    torso_share,
)
from features.derived import forget, movement_signals_of, stretch
from features.errors import DataError, InputError, ParameterError
from features.fluents import DEFAULT_TABLE, history_frames
from features.jitter import MAD_TO_SD
from features.nanstats import over_seen
from features.poses import PoseSequence, expect_sequence, gap_rows
from features.progress import progress
from features.repetitions import (
    MIN_PERIOD_S,
    WINDOW_HOP_S,
    WINDOW_S,
    MovementSignals,
    Repetition,
    RepetitionCount,
    count_in_signals,
    median_width,
    person_jumps,
)
from features.text import shown
from features.values import is_number

from . import long_clip
from .estimator_protocol import check_case_base_classifier
from .explain import Explanation
from .problem import FeatureConfig, warm
from .retrieve import query_distances
from .reuse import class_balance, vote
from .unknown import default_judge, for_person, tell_unknown, unknown_evidence
from .unknown_held_out import activity_codes, per_activity
from .unknown_judges import Familiarity, HeldOut, Judge, Margin

BLOCK_S = 0.1
"""Labels are given per block of this many seconds (the resolution of the label files)."""
HOP_S = WINDOW_HOP_S
"""A default window starts every this many seconds (as ``train --split windows`` cuts)."""
SPAN_HOP_S = 1.0
"""Repetitions are looked for in spans starting every this many seconds (spans overlap by
all but this, so every repetition up to MAX_WINDOW_S lies whole in one)."""
MIN_WINDOW_S = 1.0
MAX_WINDOW_S = 5.0
DEFAULT_WINDOW_S = WINDOW_S
"""Repetition windows span one local period within these bounds; the default windows last
DEFAULT_WINDOW_S (as ``train --split windows`` cuts them)."""
PERIOD_SPAN_S = 6.0
"""The local period is read from this many seconds around a window (periods up to 60 %)."""
PERIOD_OUTLIER_Z = 3.0
"""A repetition window whose log length lies more than this many robust standard deviations
(1.4826 median absolute deviations of such differences over the recording) from the median
of the repetition windows it overlaps is no clean period of one movement (the conventional
cut for an outlier): it does not vote (:func:`period_outliers`)."""
MIN_SEGMENT_S = 1.0
NOBODY = "nobody in view"  # the explanation of a stretch in which no frame shows the person
NO_FRAMES = "no frames in the video"
"""The explanation of a stretch with nobody in view that is mostly a gap in the video's frames
(no frame there at all, :func:`features.poses.gap_rows`: its poses left missing), not frames
that show nobody."""
SWITCH_ODDS = 2.0
"""A change of activity needs MIN_SEGMENT_S of blocks voting SWITCH_ODDS to 1 for it."""


def span_fields(start_frame: int, end_frame: int, label: str | None, confidence: float,
                fps: float) -> dict[str, Any]:  # fmt: skip
    """The JSON fields every labelled stretch has (``segment --json``, ``watch``'s lines):
    start and end in seconds and frames, the label (None: unknown) and its confidence.
    ``fps`` other than a finite number > 0 is refused (InputError) naming it."""
    if not (is_number(fps) and math.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be the frame rate, a number > 0, got {fps!r}", "to_dict")
    return {
        "start_s": round(start_frame / fps, 3),
        "end_s": round(end_frame / fps, 3),
        "start_frame": start_frame,
        "end_frame": end_frame,
        "label": label,
        "confidence": round(confidence, 3),
    }


UNLIKE = "unlike every activity"  # why a stretch in which the person is seen is unknown
STILL_TEXT = (
    "still: its joint angles vary less than half as much as in the least-moving case of the"
    " case base"
)  # why a stretch of windows that each move too little to be any activity is unknown


def unknown_reason(label: str | None, explanation: str) -> str | None:
    """Why a stretch is unknown, for machines: :data:`NOBODY` (no frame shows the person),
    :data:`NO_FRAMES` (the video has no frames there) or :data:`UNLIKE` (seen, but like no
    activity of the case base); None when it has a label."""
    if label is not None:
        return None
    return explanation if explanation in (NOBODY, NO_FRAMES) else UNLIKE


def nobody_explanation(absent: np.ndarray) -> str:
    """Why a stretch with nobody in view is unknown, ``absent`` ``(frames,)`` bool its frames
    inside a gap of the video (:func:`features.poses.gap_rows`): :data:`NO_FRAMES` when most
    of them are, :data:`NOBODY` otherwise."""
    return NO_FRAMES if 2 * int(np.count_nonzero(absent)) > len(absent) else NOBODY


@dataclass(frozen=True)
class Segment:
    """Frames ``start_frame`` to ``end_frame`` (exclusive) labelled ``label`` (None: unlike
    every activity of the case base) with ``confidence`` (the mean vote for it over the
    segment), its repetitions and a short explanation."""

    start_frame: int
    end_frame: int
    label: str | None
    confidence: float
    repetitions: tuple[Repetition, ...]
    explanation: str
    novelty: float

    def to_dict(self, fps: float) -> dict[str, Any]:
        """The segment as ``segment --json`` gives it; ``fps``: the recording's frames per
        second (``start_s``, ``end_s``; :attr:`Segmentation.fps`)."""
        return {
            **span_fields(self.start_frame, self.end_frame, self.label, self.confidence, fps),
            "unknown": unknown_reason(self.label, self.explanation),
            "repetitions": len(self.repetitions),  # the count: kept (reps: the list)
            "explanation": self.explanation,
            "novelty": round(self.novelty, 3) if math.isfinite(self.novelty) else None,
            "repetition_frames": [[r.start_frame, r.end_frame] for r in self.repetitions],
            "count": len(self.repetitions),  # as reps --json names its count
        }


@dataclass(frozen=True)
class Segmentation:
    """A recording's segments in order, covering every frame; ``blocks``: the label of every
    :data:`BLOCK_S` block (None = unknown)."""

    recording: str
    fps: float
    n_frames: int
    segments: tuple[Segment, ...]
    blocks: tuple[str | None, ...]
    windows: int = 0
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "recording": self.recording,
            "fps": self.fps,
            "frames": self.n_frames,
            "segments": [s.to_dict(self.fps) for s in self.segments],
        }


@dataclass(frozen=True)
class _Solved:
    """One window: frames [start, stop), its vote over the classes, its distance to the
    nearest case of every activity ``(n_classes,)`` and what solve gave (problem, retrieval,
    solution)."""

    start: int
    stop: int
    vote: np.ndarray
    nearest: np.ndarray
    solved: Any  # the classifier's Solved: problem, retrieval, solution, novelty, ...
    repetition: bool = False
    piece: tuple[int, int] | None = None  # in pieces: solved is None, solved again from these
    still: bool = False  # moves too little to be any activity of the case base (too_still)

    @property
    def centre(self) -> float:
        return 0.5 * (self.start + self.stop)


@dataclass(frozen=True)
class Window:
    """Frames [start, stop) of the recording to classify; ``repetition``: one period of the
    movement (else a fixed-length window)."""

    start: int
    stop: int
    repetition: bool


def windows_of(sig: MovementSignals, n_frames: int, fps: float, where: str = "") -> list[Window]:
    """The windows to classify: one of :data:`DEFAULT_WINDOW_S` every :data:`HOP_S` seconds
    (whatever is done there, repeated or not), and every period of the movement found whole
    in spans of :data:`PERIOD_SPAN_S` seconds starting every :data:`SPAN_HOP_S` seconds."""
    duration = _check_duration(n_frames, fps, where)
    # at least two frames (as live windows are): at a low frame rate the window's seconds
    # may hold less than one
    length = min(n_frames, max(2, int(round(min(DEFAULT_WINDOW_S, duration) * fps))))
    out = []
    for centre in np.arange(HOP_S / 2, duration, HOP_S):
        start = min(max(0, int(centre * fps) - length // 2), n_frames - length)
        out.append(Window(start, start + length, False))
    return out + [Window(a, b, True) for a, b in _repetition_bounds(sig, n_frames, fps)]


def _check_duration(n_frames: int, fps: float, where: str = "") -> float:
    """The recording's duration in seconds; DataError when shorter than one window."""
    duration = n_frames / fps
    if duration < MIN_WINDOW_S:
        raise DataError(
            f"the recording lasts {duration:.2f} s, shorter than the shortest window"
            f" ({MIN_WINDOW_S:g} s) of movement to classify",
            where or "recording",
        )
    return duration


def _repetition_bounds(sig: MovementSignals, n_frames: int, fps: float) -> list[tuple[int, int]]:
    """Frame ranges of the periods found whole in the spans, each once: a repetition, or for a
    movement that alternates sides two neighbouring ones (a step with each leg). Each span on
    the angles a clip of its frames alone takes (:meth:`MovementSignals.alone`), as ``watch``
    reads its spans: an arm joint missing throughout a jog but seen elsewhere in the
    recording, filled in across it as an arm held still, made windows of two to four strides."""
    span = int(PERIOD_SPAN_S * sig.fps)
    hop = max(1, int(SPAN_HOP_S * sig.fps))
    found: set[tuple[int, int]] = set()
    starts = range(0, max(1, len(sig.values) - span + hop), hop)
    for a in progress(starts, "finding repetitions", len(starts), "span", leave=False):
        part = sig.alone(a, a + span)
        if part is None:  # no angle followed in enough of its frames
            continue
        for first, last in periods_in_span(part, fps):
            found.add((a * sig.step + first, min(n_frames, a * sig.step + last)))
    return sorted(found)


def periods_in_span(part: MovementSignals, fps: float) -> list[tuple[int, int]]:
    """Frames [start, stop) of the periods found whole in one span's signals ``part`` (of a
    clip at ``fps``; :func:`_periods`), each between :data:`MIN_WINDOW_S` / 2 and
    :data:`MAX_WINDOW_S` long; one cut by the span's edge is left out (whole in a
    neighbouring span)."""
    if len(part.values) < 4:
        return []
    span_frames = len(part.values) * part.step
    out = []
    found = count_in_signals(part, span_frames, fps, recording_edges=False, clear_alternation=True)
    for first, last in _periods(found):
        if first == 0 or last >= span_frames - part.step:
            continue
        if MIN_WINDOW_S * fps / 2 <= last - first <= MAX_WINDOW_S * fps:
            out.append((first, last))
    return out


def _periods(count: RepetitionCount) -> list[tuple[int, int]]:
    """Frames [start, end) of every full period of the movement: each repetition, or for an
    alternating movement each two neighbouring repetitions (one per side)."""
    reps = count.repetitions
    if not count.alternating:
        return [(r.start_frame, r.end_frame) for r in reps]
    return [(a.start_frame, b.end_frame) for a, b in zip(reps[:-1], reps[1:], strict=True)]


def _nearest_votes(clf: Any, solved: Sequence[Any], codes: np.ndarray, k: int) -> np.ndarray:
    """Vote shares of each solved window's ``k`` nearest retrieved cases, ``(windows,
    n_classes)``, as ``clf`` votes (:func:`votes_as`); ``codes``: every case's activity
    (:func:`activity_codes`)."""
    distances = np.stack([s.retrieval.distances[:k] for s in solved])
    nearest = np.stack([s.retrieval.indices[:k] for s in solved])
    return votes_as(clf, distances, codes[nearest])


def votes_as(clf: Any, distances: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """Vote shares ``(q, n_classes)`` of ``q`` rows of nearest cases (their ``distances`` and
    activity ``codes``, ``(q, k)``) as the fitted classifier ``clf`` votes over a clip: by its
    ``weights`` (1/distance, the default) and its class balance (``class_weight``). So a
    window's k nearest cases (``segment -k``, ``watch -k``) vote as ``classify -k`` lets a
    clip's; they voted by 1/distance whatever the classifier's weights, without its balance
    (a case base of ``train --target correct``)."""
    classes = clf.classes_
    balance = None
    if clf.class_weight == "balanced":
        balance = class_balance(clf.case_base_.labels, classes)
    return vote(distances, codes, len(classes), clf.weights, balance)


def activity_distances(clf: Any, solved: Any, codes: np.ndarray | None = None) -> np.ndarray:
    """The distance from a clip solved by ``clf`` (its ``Solved``) to the nearest case of
    every activity of ``clf.classes_``, ``(n_classes,)`` (one scan of the case base: the
    nearest case of the second activity need not be among the retrieved ones). ``codes``:
    :func:`cbr.unknown.activity_codes` of the case base, when already at hand."""
    cb = clf.case_base_
    if codes is None:
        codes = activity_codes(cb.labels, clf.classes_)
    d = query_distances(cb, solved.problem)  # the fills of columns never shown left out
    return per_activity(d, codes, len(clf.classes_))


STILL_MOVEMENT_SHARE = 0.5
"""A window moves too little to be any activity of the case base when its joint angles vary less
than this share of what they vary in the least-moving of its cases (:func:`too_still`): a person
standing still is not doing an exercise when every stored window moves, whatever its nearest
case (a case base that holds windows of a jog ending standing took standing still for the jog:
docs/measurements.md, "Figures behind the code's rules: Still windows"). A share of the case
base's own least movement, not a distance: a case base holding an activity that is itself still
(a plank held, standing) keeps still windows, and the nearest case tells which activity they
are."""
STILL_CASE_MOVEMENT = 0.02
"""A case that moves less than this (:func:`movement_of`, pi radians: a mean standard
deviation of 3.6 degrees) is itself still, a posture held: a case base holding one keeps
still windows, whatever its other cases move (:func:`least_movement`), since the sensor's
jitter alone sets how little a still window moves (a posture held in motion capture well
under 0.02, one held through a video pose model near it) and a person holding a stored
posture may jitter less than its case did (a frozen frame not at all). Exercises move more
(docs/measurements.md, "Figures behind the code's rules: Still windows")."""
MOVEMENT_COLUMNS = ("angle:", "@std")
"""The problem columns :func:`movement_of` reads: each joint angle's standard deviation over
the window (a fluent summary with ``angles``, the default ``train`` problem)."""


def movement_columns(names: Sequence[str]) -> np.ndarray:
    """The indices of the columns of a problem with column ``names`` that
    :func:`movement_of` reads (:data:`MOVEMENT_COLUMNS`; empty: the problem has none, a QMP
    or fluent-sequence case base, whose windows are never too still)."""
    head, tail = MOVEMENT_COLUMNS
    return np.array(
        [i for i, n in enumerate(names) if n.startswith(head) and n.endswith(tail)], dtype=np.int64
    )


def movement_of(values: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """How much a clip moves: the mean of its joint angles' standard deviations over it (the
    problem ``values`` ``(F,)`` or ``(n, F)`` at ``columns``, :func:`movement_columns`), in
    units of pi radians; ``()`` or ``(n,)`` (NaN where none is defined)."""
    # none defined: NaN
    return over_seen(np.nanmean, np.asarray(values, dtype=np.float64)[..., columns], -1)


def least_movement(clf: Any) -> tuple[np.ndarray, float]:
    """The columns :func:`movement_of` reads of ``clf``'s problems
    (:func:`movement_columns`) and how much the least-moving case of its case base moves
    (0 when no case tells, the problem has no such columns, or the case base holds a case
    that is itself still, :data:`STILL_CASE_MOVEMENT`: no window is then too still)."""
    columns = movement_columns(getattr(clf.case_base_, "names", ()))
    problems = np.asarray(clf.case_base_.problems) if len(columns) else np.zeros((0, 0, 0))
    if problems.ndim != 2:  # none such, or sequences (DTW): not summaries of the clip
        return columns[:0], 0.0
    moved = movement_of(problems, columns)
    moved = moved[np.isfinite(moved)]
    least = float(moved.min()) if len(moved) else 0.0
    return columns, least if least >= STILL_CASE_MOVEMENT else 0.0


def window_still(solved: Any, columns: np.ndarray, least: float) -> bool:
    """Whether a window the classifier solved (its ``Solved``) moves too little to be any
    activity of a case base whose least-moving case moves ``least`` (:func:`least_movement`,
    with its ``columns``): measured over the whole window only (every frame showing the
    person: where nobody is seen the angles are held, not still), on a summary problem."""
    values = np.asarray(solved.problem.values)
    if least <= 0 or values.ndim != 1 or solved.torso_share < 1.0:
        return False
    return too_still(float(movement_of(values, columns)), least)


def too_still(moved: float, least: float) -> bool:
    """Whether a window that moves ``moved`` (:func:`movement_of`) moves too little to be any
    activity of a case base whose least-moving case moves ``least``
    (:func:`least_movement`): less than :data:`STILL_MOVEMENT_SHARE` of it."""
    return bool(np.isfinite(moved) and moved < STILL_MOVEMENT_SHARE * least)


BATCH = 32
"""Windows solved together (one batched search of the case base): enough to share the
search's set-up, few enough that a piece's windows are solved before the piece is dropped."""


def _solve_windows(
    clf: Any, rec: PoseSequence, windows: list[Window], k: int, chunk: int = 0
) -> list[_Solved]:
    """Each window solved by the classifier (:func:`_solve_distinct`), in the windows' order,
    windows in which no frame shows the person left out (nothing to solve). Windows of the
    same frames are solved once and share the answer (the same frames give the same one): at
    a low frame rate many hops fall within one frame (at 0.01 fps, 200 windows of the same two
    frames a frame: 60 frames were 12,000 windows solved, 14 s CPU and 417 MB)."""
    index: dict[tuple[int, int], int] = {}
    for w in windows:
        index.setdefault((w.start, w.stop), len(index))
    distinct = [Window(a, b, False) for a, b in index]
    found = _solve_distinct(clf, rec, distinct, k, chunk)
    return [
        replace(s, repetition=w.repetition)
        for w in windows
        if (s := found.get(index[(w.start, w.stop)])) is not None
    ]


def _solve_distinct(
    clf: Any, rec: PoseSequence, windows: list[Window], k: int, chunk: int = 0
) -> dict[int, _Solved]:
    """``{i: window i solved}`` by the classifier, :data:`BATCH` at a time, without the clip
    flag (the recording's stretches have their own judge, :mod:`cbr.unknown`); its vote is
    that of its ``k`` nearest cases. Windows in which no frame shows the person are left out
    (nothing to solve). With ``chunk``, the windows are cut from pieces of the recording
    (:func:`_cut_in_pieces`) and keep only their votes and distances (their ``solved`` is
    None)."""
    classes = np.array([str(c) for c in clf.classes_], dtype=object)
    codes = activity_codes(clf.case_base_.labels, classes)
    columns, least = least_movement(clf)
    alone = shoulders_up(rec)
    cuts = _cut_in_pieces(rec, windows, chunk, clf.feature_config_) if chunk else (
        (i, stretch(rec, w.start, w.stop), None) for i, w in enumerate(windows)
    )  # fmt: skip
    found: list[tuple[int, _Solved]] = []
    batch: list[tuple[int, PoseSequence, tuple[int, int] | None]] = []

    def flush() -> None:
        solved = clf.solve([b[1] for b in batch], flag=False)
        shares = _nearest_votes(clf, solved, codes, k)
        for (i, _, piece), one, votes in zip(batch, solved, shares, strict=True):
            w = windows[i]
            nearest = activity_distances(clf, one, codes)
            still = window_still(one, columns, least)
            found.append((i, _Solved(w.start, w.stop, votes, nearest, None if chunk else one,
                                     w.repetition, piece, still)))  # fmt: skip
        batch.clear()

    for i, part, piece in progress(cuts, "classifying windows", len(windows), "window"):
        if batch and (len(batch) == BATCH or batch[0][2] != piece):
            flush()  # a piece's windows together: the piece is dropped once they are cut
        if torso_share(part) > 0.0 or (alone and arms_alone(part)):
            batch.append((i, part, piece))
    if batch:
        flush()
    return dict(found)


def _cut_in_pieces(
    rec: PoseSequence, windows: list[Window], chunk: int, config: FeatureConfig
) -> Iterator[tuple[int, PoseSequence, tuple[int, int]]]:
    """``(i, window i as a clip, its piece)`` for the ``windows``, grouped by the piece of
    ``chunk`` frames their start lies in: each piece (frames ``lo`` to ``hi``, from the
    history its motion states look back on to the end of its last window) has what every
    frame yields computed once and shared by its windows (:func:`features.derived.stretch`),
    as the whole recording's would be; then it is dropped."""
    groups: dict[int, list[int]] = {}
    for i, w in enumerate(windows):
        groups.setdefault(w.start // chunk, []).append(i)
    history = history_frames(DEFAULT_TABLE, rec.fps)
    for p in sorted(groups):
        lo = max(0, p * chunk - history)
        bounds = (lo, max(windows[i].stop for i in groups[p]))
        piece = _piece(rec, bounds, config)
        for i in groups[p]:
            yield i, stretch(piece, windows[i].start - lo, windows[i].stop - lo), bounds
        forget(piece)


def _piece(rec: PoseSequence, bounds: tuple[int, int], config: FeatureConfig) -> PoseSequence:
    """Frames ``bounds`` of the recording with what its windows share computed (nothing for
    QMPs: a window's QMPs are fitted on it alone)."""
    piece = rec.slice_frames(*bounds)
    if config.level == "fluents":
        warm(piece, config.level, mirror=config.side == "canonical")
    return piece


class _LastPiece:
    """The piece (:func:`_piece`) last computed again to explain a window, kept for the next
    window of the same piece: the segments of a long recording come in order, so a piece of
    :data:`cbr.long_clip.CHUNK_FRAMES` frames is computed once for all the segments its
    windows explain, not once a segment (before: 143 segments of a 503-s recording at 120
    fps computed a 20,000-frame piece 143 times, three quarters of the run). One piece at a
    time: the memory of one piece, as when the windows were solved."""

    def __init__(self) -> None:
        self.bounds: tuple[int, int] | None = None
        self.piece: PoseSequence | None = None

    def get(
        self, rec: PoseSequence, bounds: tuple[int, int], config: FeatureConfig
    ) -> PoseSequence:
        if self.piece is None or bounds != self.bounds:
            self.drop()
            self.bounds, self.piece = bounds, _piece(rec, bounds, config)
        return self.piece

    def drop(self) -> None:
        if self.piece is not None:
            forget(self.piece)
        self.bounds, self.piece = None, None


def _solved(clf: Any, rec: PoseSequence, w: _Solved, pieces: _LastPiece | None = None) -> Any:
    """What solve gave for window ``w``: kept, or (cut from a piece) solved again from the
    same piece, so with the same numbers (the piece kept in ``pieces`` for the next window
    of it, when given)."""
    if w.solved is not None or w.piece is None:
        return w.solved
    lo = w.piece[0]
    config = clf.feature_config_
    piece = pieces.get(rec, w.piece, config) if pieces else _piece(rec, w.piece, config)
    return clf.solve([stretch(piece, w.start - lo, w.stop - lo)], flag=False)[0]


def period_outliers(spans: np.ndarray, repetition: np.ndarray, step: int) -> np.ndarray:
    """``(n_windows,)`` bool: the repetition windows (``repetition``) whose period disagrees
    with their neighbours': the log length of window ``spans[i]`` (frames [start, stop))
    differs from the median log length of the other repetition windows it overlaps by more
    than :data:`PERIOD_OUTLIER_Z` robust standard deviations of those differences over the
    recording (their scale, not a constant: a recording of steady repetitions is held to
    steady periods, one of irregular ones is not), the scale at least one sample of the
    counter's signals (``step`` frames) over the median period.

    A period found in a span across a change of movement, or read as a multiple of the
    true one, is half one movement and half another, or two repetitions: like neither
    side, its vote for one activity or for unknown is noise. Nothing is flagged without
    three repetition windows that overlap others."""
    out = np.zeros(len(spans), dtype=bool)
    idx = np.flatnonzero(repetition)
    if len(idx) < 3:
        return out
    start, stop = spans[idx, 0].astype(np.float64), spans[idx, 1].astype(np.float64)
    length = np.log(np.maximum(stop - start, 1.0))
    diff = np.full(len(idx), np.nan)
    for j in range(len(idx)):  # over repetition windows: the neighbours of each
        near = (start < stop[j]) & (stop > start[j])
        near[j] = False
        if near.any():
            diff[j] = length[j] - np.median(length[near])
    found = diff[np.isfinite(diff)]
    if len(found) < 3:
        return out
    mad = float(np.median(np.abs(found - np.median(found))))
    scale = max(MAD_TO_SD * mad, step / float(np.median(stop - start)))
    out[idx] = np.abs(np.nan_to_num(diff)) > PERIOD_OUTLIER_Z * scale
    return out


def block_votes(
    solved: Sequence[_Solved], n_frames: int, fps: float, n_states: int | None = None
) -> np.ndarray:
    """``(n_blocks, n_states)``: the mean vote of the windows over each block's centre (no
    window: every state alike; ``n_states`` when ``solved`` may be empty)."""
    n_blocks = int(math.ceil(n_frames / (fps * BLOCK_S) - 1e-9))
    if not solved:
        return np.full((n_blocks, n_states or 1), 1.0 / (n_states or 1))
    n_states = len(solved[0].vote)
    votes, counts = _block_sums(solved, np.stack([w.vote for w in solved]), n_blocks, fps)
    uniform = np.full(n_states, 1.0 / n_states)
    return np.where(counts[:, None] > 0, votes / np.maximum(counts, 1)[:, None], uniform)


def _block_sums(
    solved: Sequence[_Solved], values: np.ndarray, n_blocks: int, fps: float
) -> tuple[np.ndarray, np.ndarray]:
    """The sum of the windows' ``values`` ``(n_windows, ...)`` over each block's centre
    ``(n_blocks, ...)``, and how many windows cover it ``(n_blocks,)``. A window covers a
    run of blocks, [first, end) (a blocks x windows matrix would take 64 GB for a recording
    of 10^6 frames): one (window, block) pair per block it covers, in the windows' order,
    summed per block by ``np.bincount``, which adds them in that order, as a loop over the
    windows adding each to its run did (the same sums to the last bit: a difference array
    summed by ``cumsum`` adds and takes away in another order, and a tie between two
    activities' votes could fall the other way). 3-5x faster than that loop on a 2-minute mocap
    recording's windows, 2-7x on an hour of them."""
    centres = (np.arange(n_blocks) + 0.5) * BLOCK_S * fps  # in frames
    first = np.searchsorted(centres, [w.start for w in solved], side="left")
    end = np.searchsorted(centres, [w.stop for w in solved], side="left")
    runs = end - first  # how many blocks each window covers
    window = np.repeat(np.arange(len(runs)), runs)  # the window of each pair
    block = np.arange(len(window)) - np.repeat(np.cumsum(runs) - runs, runs) + first[window]
    counts: np.ndarray = np.bincount(block, minlength=n_blocks)
    flat = np.asarray(values, dtype=float).reshape(len(values), -1)
    width = flat.shape[1]
    bins = (block[:, None] * width + np.arange(width)).ravel()  # (block, column), row-major
    total = np.bincount(bins, weights=flat[window].ravel(), minlength=n_blocks * width)
    return total.reshape(n_blocks, *values.shape[1:]), counts


def block_evidence(
    solved: Sequence[_Solved], evidence: np.ndarray, n_frames: int, fps: float
) -> np.ndarray:
    """``(n_blocks,)``: the mean ``evidence`` ``(n_windows,)`` (0 to 1) of the windows over
    each block's centre; a block no window covers takes that of the nearest covered blocks
    on either side, linearly interpolated between them (the nearest one's beyond the
    first or the last; 0.5 when no block is covered). A gap in the evidence, where a change of
    activity leaves blocks that no window within one activity covers, is split between
    the sides by nearness instead of going whole to whichever side wins a tie."""
    n_blocks = int(math.ceil(n_frames / (fps * BLOCK_S) - 1e-9))
    if not solved:
        return np.full(n_blocks, 0.5)
    total, counts = _block_sums(solved, evidence, n_blocks, fps)
    covered = np.flatnonzero(counts > 0)
    if not len(covered):
        return np.full(n_blocks, 0.5)
    out: np.ndarray = np.interp(np.arange(n_blocks), covered, total[covered] / counts[covered])
    return out


TIE = 1e-6
"""Log-odds this close are a tie (sums of the same logs added in another order differ)."""


def switch_penalty() -> float:
    """The log-odds a change of label costs: :data:`MIN_SEGMENT_S` of blocks at
    :data:`SWITCH_ODDS` to 1."""
    return (MIN_SEGMENT_S / BLOCK_S) * math.log(SWITCH_ODDS)


def log_votes(votes: np.ndarray) -> np.ndarray:
    """Log votes, a zero share clipped to 1e-3 (a block no window votes for is unlikely,
    not impossible)."""
    out: np.ndarray = np.log(np.clip(votes, 1e-3, None))
    return out


def _backtrack(back: np.ndarray, last: int) -> np.ndarray:
    """The best path ending in state ``last``, followed back through ``back`` ``(n, k)`` (the
    state before each block's, for every state it may be in), a run at a time: the path
    stays in a state back to the latest block whose pointer leaves it."""
    n, k = back.shape
    leaves = np.where(back != np.arange(k), np.arange(n)[:, None], 0)
    latest = np.maximum.accumulate(leaves, axis=0)  # the latest block at or before t leaving s
    path = np.empty(n, dtype=np.int64)
    t, state = n - 1, last
    while True:  # over the path's runs
        first = int(latest[t, state])
        path[first : t + 1] = state
        if first == 0:
            return path
        t, state = first - 1, int(back[first, state])


FORWARD_CHUNK = 16
"""Blocks the forward pass first takes at once (:func:`_forward`); doubled while every block
of a chunk keeps the choices of its first."""


def _forward(score: np.ndarray, penalty: float, charged: np.ndarray | None = None) -> np.ndarray:
    """``(n, k)``: the Viterbi forward totals of ``score`` ``(n, k)`` (log votes) under a
    constant ``penalty`` per change of state: ``total[t, s] = max(total[t-1, s], max(total[t-1])
    - penalty) + score[t, s]``; at the blocks ``charged`` ``(n,)`` staying in state 0 costs
    ``penalty`` too (``total[t-1, 0] - penalty``).

    Computed a chunk of blocks at a time rather than block by block, with the same floating
    point operations in the same order (so the same totals, bit for bit, ties included): each
    state keeps through the chunk the choice it makes at its first block (stay, its own total
    summed on, ``np.add.accumulate``; or change from the best state, whose total it takes
    less ``penalty``), and the chunk is kept up to the first block at which a state would
    choose otherwise or the best state would no longer be best; the next chunk starts there.
    A recording's votes hold still for many blocks, so chunks are long (a 2.5 x 10^5-block
    recording: about 15)."""
    n, k = score.shape
    total = np.empty_like(score)
    total[0] = score[0]
    at_charge = np.flatnonzero(charged) if charged is not None else np.empty(0, dtype=np.int64)
    stay_cost = np.zeros(k)
    stay_cost[0] = penalty
    t, length = 1, FORWARD_CHUNK
    while t < n:
        prev = total[t - 1]
        upcoming = at_charge[np.searchsorted(at_charge, t) :]
        if len(upcoming) and upcoming[0] == t:  # one block on its own
            total[t] = np.maximum(prev - stay_cost, prev.max() - penalty) + score[t]
            t += 1
            continue
        stop = min(n, t + length, int(upcoming[0]) if len(upcoming) else n)
        best = int(np.argmax(prev))
        stay = prev >= prev[best] - penalty
        chunk = score[t:stop]
        own = chunk.copy()
        own[0] += prev
        np.add.accumulate(own, axis=0, out=own)
        switch = np.empty(len(chunk))
        switch[0], switch[1:] = prev[best], own[:-1, best]
        guess = np.where(stay, own, (switch - penalty)[:, None] + chunk)
        rows = guess[:-1]  # each block's choices are made on the totals of the one before
        kept = (rows.max(axis=1) == rows[:, best]) & (
            (rows >= (rows[:, best] - penalty)[:, None]) == stay
        ).all(axis=1)
        took = len(chunk) if kept.all() else int(np.argmin(kept)) + 1
        total[t : t + took] = guess[:took]
        length = 2 * length if took == len(chunk) else max(FORWARD_CHUNK, 2 * took)
        t += took
    return total


def decode(votes: np.ndarray) -> np.ndarray:
    """The most likely state of every block (Viterbi) under a constant cost per change of
    state (:func:`switch_penalty`). ``(n_blocks,)``."""
    penalty = switch_penalty()
    score = log_votes(votes)
    n, k = score.shape
    total = _forward(score, penalty)
    prev = total[:-1]  # a block's way in is chosen on the totals of the block before
    best = np.argmax(prev, axis=1)
    switch = prev[np.arange(n - 1), best] - penalty
    back = np.zeros((n, k), dtype=np.int64)
    back[1:] = np.where(prev >= switch[:, None], np.arange(k), best[:, None])
    return _backtrack(back, int(np.argmax(total[-1])))


def decode_unknown(votes: np.ndarray, path: np.ndarray) -> np.ndarray:
    """``(n_blocks,)`` bool: the most likely known (False) / unknown (True) state of every
    block given ``votes`` ``(n_blocks, 2)`` (shares known, unknown) and the decoded
    activities ``path`` ``(n_blocks,)``, where every change of the label a user sees costs
    :func:`switch_penalty` once: known to unknown and back, and a change of activity between
    two known blocks; a change of activity under unknown is not seen and costs nothing.

    Decoding known/unknown on its own would charge only its own changes: an unknown stretch
    ending 0.5 s before a change of activity would leave a 0.5-s segment of the activity
    before, a change nobody paid for (segments that flicker). Where known and unknown are
    equally likely (within :data:`TIE`, rounding), the block is known: calling a stretch
    unlike every activity takes evidence."""
    penalty = switch_penalty()
    score = log_votes(votes)
    moved = np.r_[False, path[1:] != path[:-1]]  # the activity changes at this block
    total = _forward(score, penalty, moved)
    known, unknown = total[:-1, 0], total[:-1, 1]
    stay_known = np.where(moved[1:], known - penalty, known)
    back = np.zeros((len(score), 2), dtype=np.int64)
    back[1:, 0] = np.where(stay_known >= unknown - penalty - TIE, 0, 1)
    back[1:, 1] = np.where(unknown > known - penalty + TIE, 1, 0)
    return np.asarray(_backtrack(back, int(total[-1, 1] > total[-1, 0] + TIE)) == 1)


def _log_distances(solved: Sequence[_Solved]) -> np.ndarray:
    """``(n_windows, n_classes)``: the log distance from every window to the nearest case of
    every activity (0 and inf clipped to the finite range: a window that is a case, or an
    activity out of reach)."""
    d = np.stack([w.nearest for w in solved]).astype(np.float64)
    return np.log(np.clip(d, np.finfo(np.float64).tiny, np.finfo(np.float64).max))


def _change_cost(
    bounds: np.ndarray, spans: np.ndarray, before: np.ndarray, after: np.ndarray
) -> np.ndarray:
    """``(n_candidates,)``: the charge of a change at each frame of ``bounds`` ``(n,)``: each
    window (``spans`` ``(n_windows, 2)`` frames [start, stop)) pays its log distance to the
    activity before (``before`` ``(n_windows,)``) for its share of frames before the change
    and that to the activity after (``after``) for the rest."""
    length = (spans[:, 1] - spans[:, 0]).astype(np.float64)
    share = np.clip((bounds[:, None] - spans[None, :, 0]) / length[None, :], 0.0, 1.0)
    cost: np.ndarray = share @ before + (1.0 - share) @ after
    return cost


def place_changes(solved: Sequence[_Solved], fps: float, path: np.ndarray) -> np.ndarray:
    """``path`` ``(n_blocks,)`` with each change of state moved, within the two runs it
    separates (each keeps a block), to the block boundary of least :func:`_change_cost` over
    the windows that overlap those runs: where the two activities' distances cross, read
    from how much of each window lies on either side. States past the case base's activities
    (unknown) are left where they are."""
    if not solved:
        return path
    out = path.copy()
    logs = _log_distances(solved)
    n_classes = logs.shape[1]
    spans = np.array([(w.start, w.stop) for w in solved], dtype=np.float64)
    per_block = fps * BLOCK_S
    runs = _runs(path)
    floor = 0  # the previous change as placed: a run keeps at least one block
    for (a0, a1, before), (_, b1, after) in zip(runs[:-1], runs[1:], strict=True):
        lo, hi = max(a0, floor) + 1, b1 - 1
        if before >= n_classes or after >= n_classes or hi < lo:
            floor = a1
            continue
        near = (spans[:, 1] > lo * per_block - per_block) & (spans[:, 0] < hi * per_block)
        candidates = np.arange(lo, hi + 1)
        cost = _change_cost(
            candidates * per_block, spans[near], logs[near, before], logs[near, after]
        )
        floor = int(candidates[int(np.argmin(cost))])
        out[lo - 1 : floor] = before
        out[floor:b1] = after
    return out


def sighting_width(fps: float) -> int:
    """How many frames (odd) at ``fps`` decide whether a frame shows the person
    (:func:`features.body.majority` of the frames showing the torso): the running median
    the movement signals read for a pose model's poses
    (:func:`features.repetitions.median_width`: 0.2 s, at least three frames). The person
    "seen" for a glitch of the pose model shorter than half of it in a stretch with nobody
    in view (a false detection) is not, nor is the person missed for one lost from view."""
    return median_width(fps, True)


def shoulders_up(rec: PoseSequence) -> bool:
    """Whether ``rec`` shows its person from the shoulders up only: no frame shows the torso
    and its arms are seen (:func:`features.body.arms_alone`, the hips out of view). Its
    windows that show the arms are labelled from them (:data:`features.signals.HIPLESS`),
    and a stretch is nobody in view where the shoulders are not seen."""
    return torso_share(rec) == 0.0 and arms_alone(rec)


def nobody_blocks(rec: PoseSequence, n_blocks: int) -> np.ndarray:
    """``(n_blocks,)`` bool: the :data:`BLOCK_S` blocks of ``rec`` whose centre lies in a
    stretch of at least :data:`MIN_SEGMENT_S` in which no frame shows the person
    (:func:`sighting_width`: nor a glitch of the pose model; a segment of its own, and a
    shorter dropout of the pose model is not). Before, the person "seen" for two frames
    1/3 s into 3 s with nobody in view left the 1/3 s before them unknown."""
    seen = majority(shown_rows(rec, shoulders_up(rec)), sighting_width(rec.fps))
    nobody = long_runs(~seen, MIN_SEGMENT_S * rec.fps)
    centres = ((np.arange(n_blocks) + 0.5) * rec.fps * BLOCK_S).astype(int)
    return np.asarray(nobody[np.minimum(centres, rec.n_frames - 1)])


def _runs(path: np.ndarray) -> list[tuple[int, int, int]]:
    """Runs of one state: (first block, end block exclusive, state)."""
    change = np.flatnonzero(path[1:] != path[:-1]) + 1
    starts = np.r_[0, change]
    ends = np.r_[change, len(path)]
    return [(int(a), int(b), int(path[a])) for a, b in zip(starts, ends, strict=True)]


def within_runs(solved: Sequence[_Solved], fps: float, path: np.ndarray) -> np.ndarray:
    """``(n_windows,)`` bool: the windows that lie within one run of the decoded activity
    ``path`` ``(n_blocks,)``; one across a change of activity is half one movement and half
    another, like neither, whether both are known or not."""
    run = np.r_[0, np.cumsum(path[1:] != path[:-1])]
    per_block, last = fps * BLOCK_S, len(path) - 1
    first = np.array([min(last, int(w.start // per_block)) for w in solved], dtype=np.int64)
    end = np.array(
        [min(last, int(math.ceil(w.stop / per_block - 1e-9)) - 1) for w in solved], dtype=np.int64
    )
    return np.asarray(run[first] == run[np.maximum(first, end)])


def unknown_shares(
    solved: Sequence[_Solved], n_frames: int, fps: float, judge: Judge, path: np.ndarray
) -> np.ndarray:
    """``(n_blocks,)``: every block's evidence (0 to 1) that it is unlike every activity of
    the case base. The windows within one run of the decoded activity ``path``
    ``(n_blocks,)`` (:func:`within_runs`) are judged (:func:`cbr.unknown.unknown_evidence`:
    graded between the budget's threshold and the judge's own by the default judge, else all
    or nothing); a block's evidence is the mean of those over it, a block none covers takes
    its nearest covered neighbours' (:func:`block_evidence`); 0 everywhere when no window is
    judged."""
    inside = within_runs(solved, fps, path)
    judged = [w for w, keep in zip(solved, inside.tolist(), strict=True) if keep]
    if not judged:
        return np.zeros(len(path))
    evidence = np.array(
        [1.0 if w.still else unknown_evidence(judge, w.nearest) for w in judged], dtype=np.float64
    )
    return block_evidence(judged, evidence, n_frames, fps)


def unknown_blocks(
    solved: Sequence[_Solved], n_frames: int, fps: float, judge: Judge, path: np.ndarray
) -> np.ndarray:
    """``(n_blocks,)`` bool: blocks unlike every activity of the case base: their evidence
    (:func:`unknown_shares`) decoded with the activities (:func:`decode_unknown`: every
    change of label a user sees needs :data:`MIN_SEGMENT_S` of evidence)."""
    unknown = unknown_shares(solved, n_frames, fps, judge, path)
    return decode_unknown(np.stack([1.0 - unknown, unknown], axis=1), path)


def _explain_segment(
    clf: Any,
    rec: PoseSequence,
    inside: list[_Solved],
    state: int,
    judge: Judge,
    pieces: _LastPiece | None = None,
) -> tuple[str, float]:
    """A short explanation from the segment's most telling window (unknown:
    :func:`cbr.unknown.tell_unknown`), and the segment's novelty (the judge's ratio, median
    over its windows)."""
    n_classes = len(clf.classes_)
    if not inside:
        return "", float("nan")
    ratio = float(np.median([judge.ratio(w.nearest) for w in inside]))
    if state == n_classes and sum(w.still for w in inside) > len(inside) / 2:
        return STILL_TEXT, ratio
    if state == n_classes:
        return tell_unknown(
            [(judge, w.nearest) for w in inside], [str(c) for c in clf.classes_]
        ), ratio
    w = max(inside, key=lambda s: s.vote[state])
    return told(clf, _solved(clf, rec, w, pieces), str(clf.classes_[state])), ratio


def told(clf: Any, solved: Any, label: str) -> str:
    """Why a window that ``clf`` solved (``solved``) tells of activity ``label``, in a line:
    how many of its most similar cases are of it, and the fluents it matched them on."""
    e: Explanation = clf.explain_solved(solved, counterfactual=False)
    agree = sum(str(n["label"]) == label for n in e.neighbours)
    verb = "is" if agree == 1 else "are"  # "1 of the 5 most similar cases is lunge"
    text = f"{agree} of the {len(e.neighbours)} most similar cases {verb} {label}"
    if e.matched:
        text += "; matched: " + ", ".join(e.matched[:3])
    return text


def count_in_segment(
    sig: MovementSignals,
    n_frames: int,
    fps: float,
    edges: tuple[bool, bool],
    settled: tuple[bool, bool] = (False, False),
) -> RepetitionCount:
    """The repetitions of a segment, of ``n_frames`` frames at ``fps``, whose movement signals
    are ``sig``: :func:`features.repetitions.count_in_signals` read past a period of noise
    (``past_noise``: hunt 38c), the rule of a segment's count, not of the windows classified
    nor of ``reps``; ``edges``, ``settled`` as there. ``segment`` counts each segment with it
    (:func:`_repetitions`) and ``watch`` each of its own (:mod:`cbr.live`), so that the two,
    cut alike, count alike."""
    return count_in_signals(sig, n_frames, fps, edges, settled=settled, past_noise=True)


class Counter(Protocol):
    """What counts the repetitions of a recording's frames other than its movement signals
    (:func:`_repetitions`): :class:`_Apart` (a recording cut where the pose jumped to another
    person) and the frames of ``watch``'s stream still kept (:class:`cbr.live.LiveSegmenter`),
    which :func:`unclaimed` reads as it reads a recording's."""

    @property
    def step(self) -> int:
        """Frames per sample of the counter's signals."""
        ...

    def repetitions(
        self, start: int, end: int, n_frames: int | None, settled: tuple[bool, bool]
    ) -> tuple[Repetition, ...]:
        """:func:`_repetitions` of frames [start, end)."""
        ...


def _repetitions(
    sig: MovementSignals | Counter,
    start: int,
    end: int,
    n_frames: int | None = None,
    settled: tuple[bool, bool] = (False, False),
) -> tuple[Repetition, ...]:
    """The repetitions within frames [start, end) of the recording whose signals are ``sig``
    (counted on the recording's own smoothed signals: no edge effects at the cut; each side
    of a jump of the pose to another person on its own side's, :class:`_Apart`). Given the
    recording's ``n_frames``, a segment at its start or end has no repetition there that is
    only part of one when none of its repetitions is whole (the way down of a squat as the
    recording ends: :func:`features.repetitions.count_in_signals`); one at a cut is left to
    :func:`keep_whole`. ``settled``: whether the segment's start, and its end, are cuts at
    which no movement turns (:func:`counted_segments`)."""
    if not isinstance(sig, MovementSignals):
        return sig.repetitions(start, end, n_frames, settled)
    last = n_frames is not None and end >= n_frames
    edges = (start == 0 and n_frames is not None, last)
    return repetitions_in(sig, start, end, last, edges, settled)


def repetitions_in(
    sig: MovementSignals,
    start: int,
    end: int,
    to_end: bool,
    edges: tuple[bool, bool],
    settled: tuple[bool, bool],
) -> tuple[Repetition, ...]:
    """:func:`_repetitions` of frames [start, end) of the frames ``sig`` are the signals of,
    read to their last sample when ``to_end``; ``edges``: whether the start, and the end,
    are the recording's. Counted on the angles a clip of those frames alone is counted on
    (:meth:`features.repetitions.MovementSignals.alone`; none followed: no repetition):
    before, an arm joint missing throughout a jog but seen elsewhere in the recording was
    filled in across it, an arm held still, and the jog's steps were undercounted."""
    a, b = start // sig.step, max(start // sig.step + 1, end // sig.step)
    if to_end:  # to the recording's last sample, as reps reads it (a far point there counts)
        b = max(b, len(sig.values))
    if (b - a) / sig.fps < MIN_PERIOD_S:
        return ()
    part = sig.alone(a, b)
    if part is None:
        return ()
    found = count_in_segment(
        part, min((b - a) * sig.step, end - a * sig.step), sig.fps * sig.step, edges, settled
    ).repetitions
    off = a * sig.step
    return tuple(  # the first sample may begin up to a step before ``start``: cut there
        Repetition(
            max(start, r.start_frame + off),
            min(end, r.end_frame + off),
            max(start, r.peak_frame + off),
            r.side,
            r.held,
            r.unreturned,
        )
        for r in found
    )


@dataclass(frozen=True)
class _Apart:
    """The movement signals of a recording computed apart on either side of each frame
    where the pose jumped to another person (:func:`counted_apart`): ``cuts``, 0, the jumps
    and the recording's frame count; ``sides``, the signals of the frames between each two
    (None: too short for a repetition, or nobody in view); ``step``, the recording's frames
    per sample. The running median and smoothing of one person's angles do not read the
    other's, as they read nothing beyond a recording's ends."""

    cuts: tuple[int, ...]
    sides: tuple[MovementSignals | None, ...]
    step: int

    def repetitions(
        self, start: int, end: int, n_frames: int | None, settled: tuple[bool, bool]
    ) -> tuple[Repetition, ...]:
        """:func:`_repetitions` of frames [start, end), each side's frames on its own side's
        signals (a jump is a cut, not the recording's start or end)."""
        out: tuple[Repetition, ...] = ()
        for p, q, side in zip(self.cuts[:-1], self.cuts[1:], self.sides, strict=True):
            a, b = max(start, p), min(end, q)
            if a >= b or side is None:
                continue
            edges = (a == 0 and n_frames is not None, n_frames is not None and b >= n_frames)
            still = (settled[0] and a == start, settled[1] and b == end)
            found = repetitions_in(side, a - p, b - p, b >= q, edges, still)
            out += tuple(_shifted(r, p) for r in found)
        return out


def _shifted(r: Repetition, by: int) -> Repetition:
    return Repetition(
        r.start_frame + by, r.end_frame + by, r.peak_frame + by, r.side, r.held, r.unreturned
    )


def _side_signals(rec: PoseSequence, start: int, end: int) -> MovementSignals | None:
    """The movement signals of frames [start, end) of ``rec`` alone, as of a recording of
    their own (None: too short for a repetition, or nobody in view)."""
    piece = rec.slice_frames(start, end)
    if piece.duration_s < MIN_PERIOD_S:
        return None
    chunk = long_clip.chunk_for(piece, None)
    try:
        return long_clip.movement_signals(piece, chunk) if chunk else movement_signals_of(piece)
    except DataError:  # nobody in view
        return None


def at_cut(reps: Sequence[Repetition], start: int, end: int, tolerance: int) -> tuple[bool, bool]:
    """Whether the first of ``reps`` (of frames [start, end)) has its far point at ``start``
    and whether the last has it at ``end``, within ``tolerance`` frames (one sample of the
    counter's signals)."""
    if not reps:
        return False, False
    return reps[0].peak_frame < start + tolerance, reps[-1].peak_frame >= end - tolerance


def keep_whole(
    reps: Sequence[Repetition],
    start: int,
    end: int,
    tolerance: int,
    after_turn: bool,
    cut_end: bool,
    held: bool = False,
) -> tuple[Repetition, ...]:
    """``reps`` of a segment, frames [start, end), with those whose far point is only where the
    recording was cut into segments left out: a repetition counts for the one segment that
    holds where its movement turns.

    Counted on a segment alone, a movement cut mid-way has its far point at the cut (the
    signal is largest there because it goes on beyond): half a squat each side of a change
    would count in both segments, and a fragment shorter than one repetition would count
    the movement at both its ends. So a far point at the segment's end (``cut_end``: the
    end is a change, not the end of the recording) is left out: the movement turns beyond,
    where the next segment counts it; one at the start is kept only when the segment before
    had one at that same cut (``after_turn``: the movement turns at the cut itself: one
    repetition, counted once, by the segment after). ``tolerance``: frames per sample of the
    counter's signals. ``held``: the last far point is held up to the cut, and on beyond it
    in the next segment (:func:`counted_segments`): it is at the cut, wherever along the hold
    its peak sample lies."""
    first, last = at_cut(reps, start, end, tolerance)
    last = last or held
    out = list(reps)
    if cut_end and last:
        out = out[:-1]
    if first and not after_turn and start > 0 and out and out[0] is reps[0]:
        out = out[1:]
    return tuple(out)


def counted_apart(
    sig: MovementSignals,
    bounds: Sequence[tuple[int, int]],
    n_frames: int,
    unseen: Sequence[bool],
    jumps: Sequence[int],
    rec: PoseSequence,
    states: Sequence[int] = (),
) -> list[tuple[Repetition, ...]]:
    """:func:`counted_segments` with every segment also cut at the frames ``jumps`` (where
    the pose jumped to another person, :func:`features.repetitions.person_jumps`), as at a
    change of segment, and each segment's pieces' repetitions joined back into it: the jump
    from one person's posture to the other's is no movement, as ``reps`` counts it. Before, a
    repetition ran on across the jump (a jumping jack of one person ending in another's).

    ``sig``: the movement signals of the recording ``rec`` (of ``n_frames``), read where it
    has no jump; with one, each side's are computed from its own frames of ``rec``
    (:class:`_Apart`), as ``watch`` counts each (:meth:`cbr.live.LiveSegmenter._count_apart`).
    Before, they were the whole recording's, whose running median and smoothing read across
    the jump and mixed the two people's postures: the jumping jacks cut with the first
    person's arms still rising and taken on with the second's coming down counted one more
    in ``segment`` than in ``watch``, ``reps`` and by hand."""
    cuts = [0, *sorted({j for j in jumps if 0 < j < n_frames}), n_frames]
    if len(cuts) == 2:
        return counted_segments(sig, bounds, n_frames, unseen, states)
    sides = tuple(_side_signals(rec, p, q) for p, q in zip(cuts[:-1], cuts[1:], strict=True))
    apart = _Apart(tuple(cuts), sides, sig.step)
    pieces: list[tuple[int, int]] = []
    owner: list[int] = []
    blind: list[bool] = []
    for k, ((a, b), u) in enumerate(zip(bounds, unseen, strict=True)):
        inside = [a, *(j for j in cuts[1:-1] if a < j < b), b]
        for x, y in zip(inside[:-1], inside[1:], strict=True):
            pieces.append((x, y))
            owner.append(k)
            blind.append(u)
    out: list[tuple[Repetition, ...]] = [() for _ in bounds]
    for k, found in zip(owner, counted_segments(apart, pieces, n_frames, blind), strict=True):
        out[k] += found
    return out


def counted_segments(
    sig: MovementSignals | _Apart,
    bounds: Sequence[tuple[int, int]],
    n_frames: int,
    unseen: Sequence[bool] = (),
    states: Sequence[int] = (),
) -> list[tuple[Repetition, ...]]:
    """The repetitions of every segment, frames ``bounds`` [start, end) in order covering the
    recording's ``n_frames``, each counted on its own frames (:func:`_repetitions`), each
    repetition in one segment (:func:`keep_whole`); a far point cut off at a cut that the
    segment across it does not take is kept where the movement turns within the segment
    (:func:`unclaimed`), as a clip of the segment's frames keeps it.

    A cut next to a segment with no far point at all is, for a posture got into and held
    still up to it, as the recording's end: nothing comes back beyond it, the posture is held
    on (a side plank held through a change of label the classifier saw in the hold), and the
    segment has no repetition, as ``reps`` on the whole recording has none
    (:func:`features.repetitions.count_in_signals`' ``settled``); before, the way into the
    plank counted 1 in the segment, 0 in ``reps``.

    A far point held on across a cut (a squat held at the bottom through a change of label
    the classifier saw in the hold; :func:`_held_across`), through any segments between that
    find no far point at all (a fragment all hold), is at the cut: counted once, by the
    segment where the movement comes back, and no segment beside the hold is settled. Before,
    each segment's far point lay mid-way along its part of the hold, neither at the cut, and
    the squat counted in both (a fragment all hold between them: in neither). So is a
    shallow dip across a cut between two far points of one repetition, neither side come
    back to rest by it (:attr:`features.repetitions.Repetition.unreturned`; a squat that
    rises 20 degrees at the knees before the cut and sinks again after it): before, counted
    in both segments when either side turned back by :data:`MIN_EXCURSION_RAD` or more.

    ``unseen``: per segment, whether nobody is in view in it (counted 0). The segments are
    then counted as ``reps`` counts the recording (:func:`_counted_seen`): from where the
    person is first seen to where they are last seen, as a recording of its own (the view of
    the movement ends where the person is lost for good, as at the recording's end: the way
    down of a squat, the person then lost, is no repetition; before, the segment kept it as
    one), and a stretch with nobody in view between two segments of the same activity
    (``states``: each segment's, as decoded; none given: all alike) is part of the segment
    before it (the activity goes on out of sight, filled in across the stretch: a squat
    whose person is lost on the way down and seen again on the way up is one repetition;
    before, it counted in both); between two of different activities, it ends the one
    before and starts the one after as a recording's end and start do (the first 0.5 s of
    a squat, 3 s with nobody in view, then knee raises: the squat's way down is none, as at
    a recording's end; before, it counted 1). Counted across a jump of the pose to another
    person (``sig`` of the pieces either side), the segment before a stretch with nobody
    in view keeps a far point at its cut, as before."""
    blind = [bool(u) for u in unseen] + [False] * (len(bounds) - len(unseen))
    if isinstance(sig, MovementSignals) and any(blind) and not all(blind):
        return _counted_seen(sig, bounds, blind, states)
    raw = [
        () if b else _repetitions(sig, start, end, n_frames)
        for (start, end), b in zip(bounds, blind, strict=True)
    ]
    raw = [_beside_whole(sig, raw, bounds, blind, i, n_frames) for i in range(len(raw))]
    # whether the last far point of each segment is held on, through any segments with none
    # (all hold), to the first of the next segment that has one (:func:`_held_across`); not
    # through a stretch with nobody in view
    after = [
        next((j for j in range(i + 1, len(raw)) if raw[j] or blind[j]), None)
        for i in range(len(raw))
    ]
    after = [None if j is None or blind[j] else j for j in after]
    held_on = [
        j is not None and _held_across(raw[i], raw[j], bounds[j], sig) for i, j in enumerate(after)
    ]
    mine = unclaimed(sig, raw, bounds, blind, held_on, n_frames)
    out = []
    turn = False  # the segment before had a far point at its end (the cut)
    holding = False  # a far point held on from a segment before, through this one
    for i, (start, end) in enumerate(bounds):
        reps = raw[i]
        lost = i + 1 < len(bounds) and blind[i + 1]  # the person goes out of view at the end
        settled = (
            i > 0 and not raw[i - 1] and not holding,
            i + 1 < len(bounds) and not raw[i + 1] and not held_on[i] and not lost,
        )
        if len(reps) == 1 and any(settled):
            reps = _repetitions(sig, start, end, n_frames, settled)
        cut = end < n_frames and not lost and not mine[i][1]
        out.append(keep_whole(reps, start, end, sig.step, turn or mine[i][0], cut, held_on[i]))
        if raw[i]:
            turn = at_cut(raw[i], start, end, sig.step)[1] or held_on[i]
            holding = held_on[i]
        elif not holding:
            turn = False
    out = _held_into_the_end(sig, out, raw, bounds, held_on, after, n_frames)
    return _held_to_the_end(out, raw, bounds, blind)


def _counted_seen(
    sig: MovementSignals,
    bounds: Sequence[tuple[int, int]],
    blind: Sequence[bool],
    states: Sequence[int],
) -> list[tuple[Repetition, ...]]:
    """:func:`counted_segments` of segments ``bounds`` some of which (``blind``, not all)
    show nobody: the segments that show the person, in runs that a stretch with nobody in
    view between two different activities (``states``) ends, each run counted as a recording
    of its own (its start and end the recording's, as ``reps`` counts a recording whose
    person is first seen late or lost for good early,
    :func:`features.repetitions.seen_frames`), each of its segments with the segments with
    nobody in view after it up to the next in the run (the movement filled in across them,
    as ``reps`` fills it in); the repetitions so counted are the segment's, cut to its
    frames, and a segment with nobody in view counts none."""
    seen = [k for k, b in enumerate(blind) if not b]
    runs = [[seen[0]]]
    for k, q in zip(seen[:-1], seen[1:], strict=True):
        alike = q == k + 1 or len(states) <= q or states[k] == states[q]
        if alike:
            runs[-1].append(q)
        else:
            runs.append([q])
    out: list[tuple[Repetition, ...]] = [() for _ in bounds]
    for run in runs:
        for k, reps in zip(run, _counted_run(sig, bounds, run), strict=True):
            out[k] = reps
    return out


def _counted_run(
    sig: MovementSignals, bounds: Sequence[tuple[int, int]], run: Sequence[int]
) -> list[tuple[Repetition, ...]]:
    """The repetitions of segments ``run`` (indices of ``bounds``, ascending, all showing
    the person) counted as a recording of their own from the first's start to the last's
    end, each with the frames after it up to the next (:func:`_counted_seen`), in the
    recording's frames, cut to each segment's own."""
    nxt = [*run[1:], None]
    groups = [(bounds[k][0], bounds[q][0] if q is not None else bounds[k][1]) for k, q in
              zip(run, nxt, strict=True)]  # fmt: skip
    step = sig.step
    a0, b0 = groups[0][0] // step, -(-groups[-1][1] // step)
    off = a0 * step
    # the run starts as a recording does: from its first sample (up to a step of frames
    # with nobody in view before the first segment, filled in)
    inner = [(0 if i == 0 else a - off, b - off) for i, (a, b) in enumerate(groups)]
    found = counted_segments(sig.part(a0, b0), inner, groups[-1][1] - off)
    out = []
    for k, reps in zip(run, found, strict=True):
        start, end = bounds[k]
        out.append(tuple(
            Repetition(
                max(start, r.start_frame + off),
                min(end, r.end_frame + off),
                min(end - 1, max(start, r.peak_frame + off)),
                r.side,
                r.held,
                r.unreturned,
            )
            for r in reps
        ))  # fmt: skip
    return out


def unclaimed(
    sig: MovementSignals | Counter,
    raw: Sequence[tuple[Repetition, ...]],
    bounds: Sequence[tuple[int, int]],
    blind: Sequence[bool],
    held_on: Sequence[bool],
    n_frames: int,
) -> list[tuple[bool, bool]]:
    """Per segment of ``bounds``, whether its first far point at its start, and its last at
    its end, is a cut off far point that the segment across that cut does not take (has
    none at the cut; neither is nobody in view nor is the far point held on across it) and
    that is where the movement turns within the segment (:func:`_turns_inside`): the
    segment keeps it, as a clip of its frames keeps a far point cut off at its edge beside
    its whole ones (:func:`features.repetitions.count_in_signals`). ``raw``: each segment's
    repetitions counted alone; ``held_on``: whether its last far point is held on across
    its end (:func:`_held_across`).

    :func:`keep_whole` hands a far point at a cut to the segment that has one at the same
    cut; each segment's count reads its own movement, and the next exercise's rarely shows
    the last one's. Before, a far point at a cut that only one side showed was dropped: a
    last repetition turning just before the cut, or a first just after it, counted in
    neither segment, though a clip of the segment's frames counts it. ``watch`` asks the same
    of each segment it finishes, ``sig`` its stream's frames (:class:`Counter`), the
    segment after being the frames pushed beyond the cut (:meth:`cbr.live.LiveSegmenter._mine`)."""
    step = sig.step
    cuts = [at_cut(r, a, b, step) for r, (a, b) in zip(raw, bounds, strict=True)]
    out = []
    for i, (reps, (first, last)) in enumerate(zip(raw, cuts, strict=True)):
        before = i > 0 and not blind[i - 1] and not (cuts[i - 1][1] or held_on[i - 1])
        after = i + 1 < len(raw) and not blind[i + 1] and not cuts[i + 1][0] and not held_on[i]
        out.append((
            before and first and _turns_inside(sig, reps, bounds[i], False, n_frames),
            after and last and _turns_inside(sig, reps, bounds[i], True, n_frames),
        ))  # fmt: skip
    return out


def _turns_inside(
    sig: MovementSignals | Counter,
    reps: Sequence[Repetition],
    bounds: tuple[int, int],
    at_end: bool,
    n_frames: int,
) -> bool:
    """Whether the far point of ``reps`` (a segment's repetitions, frames ``bounds``) at the
    segment's end (``at_end``) or start is where the movement turns within the segment: the
    segment's frames counted on across that cut by the median length of its whole
    repetitions (:func:`whole_in`; none: False), as one stretch, hold the far point
    nearest it (nearer it than any other of ``reps``) before the end, or at the start or
    after, within one sample (the frames the segment before calls at the cut,
    :func:`at_cut`). Beyond the cut, the line of a movement still going out to its far
    point rises on; one that turned comes back."""
    whole = [r for r in reps if not any(r.held)]
    if not whole:
        return False
    reach = int(np.median([r.end_frame - r.start_frame for r in whole]))
    start, end = bounds
    cut = reps[-1] if at_end else reps[0]
    a, b = (start, min(n_frames, end + reach)) if at_end else (max(0, start - reach), end)
    peaks = [r.peak_frame for r in _repetitions(sig, a, b, n_frames)]
    if not peaks:
        return False
    peak = min(peaks, key=lambda p: abs(p - cut.peak_frame))
    if any(abs(peak - r.peak_frame) <= abs(peak - cut.peak_frame) for r in reps if r is not cut):
        return False
    return peak < end if at_end else peak >= start - sig.step


def _held_into_the_end(
    sig: MovementSignals | _Apart,
    out: list[tuple[Repetition, ...]],
    raw: Sequence[tuple[Repetition, ...]],
    bounds: Sequence[tuple[int, int]],
    held_on: Sequence[bool],
    after: Sequence[int | None],
    n_frames: int,
) -> list[tuple[Repetition, ...]]:
    """:func:`counted_segments`' ``out`` without the far point held across a cut into the
    last segment (the way into a posture in one segment, the hold in the last, to the
    recording's end) when the frames from the first repetition of the segment it was got
    into in to the recording's end, counted as one stretch, hold no repetition: a posture
    got into and held (:func:`features.repetitions.count_in_signals`), no repetition, as
    ``reps`` counts the recording. Neither segment alone holds both the way in and the
    still end that rule reads, and the last counted the far point it was handed wherever
    its line sagged by :data:`features.repetitions.MIN_EXCURSION_RAD` in the hold (a side
    plank whose supporting shoulder sinks as it is held; docs/measurements.md, "Figures behind
    the code's rules: A posture held across a cut")."""
    last = len(bounds) - 1
    if bounds[-1][1] < n_frames or not out[last]:
        return out
    for k in range(last):
        if held_on[k] and after[k] == last:
            if not _repetitions(sig, raw[k][0].start_frame, n_frames, n_frames):
                return [*out[:last], out[last][1:]]
    return out


def _beside_whole(
    sig: MovementSignals | _Apart,
    raw: Sequence[tuple[Repetition, ...]],
    bounds: Sequence[tuple[int, int]],
    blind: Sequence[bool],
    i: int,
    n_frames: int,
) -> tuple[Repetition, ...]:
    """Segment ``i``'s repetitions counted alone (``raw[i]``), with a far point cut off at
    the recording's start or end judged beside the repetitions of the segment across its
    cut, as ``reps`` judges it beside the recording's whole ones: a far point cut off there
    counts only beside a whole one, when it got nearly as far
    (:func:`features.repetitions.count_in_signals`). A segment at the recording's edge with
    no whole repetition of its own (the last jumping jack of a recording, caught mid-way,
    cut from the jacks before it; the first bridge, held as the recording starts, cut from
    the bridges after it) had nothing to measure it against and dropped it, which the
    recording counted whole keeps: the count depended on where the cut fell. So the frames
    from the nearest repetition of the segment across the cut to the recording's edge are
    counted as one stretch (each segment's own movement line barely shows the other's), and
    the far point that stretch keeps cut off at the edge (:attr:`Repetition.held` there: the
    line falls back from it by less than :data:`features.repetitions.MIN_EXCURSION_RAD`),
    lying in this segment past its cut and in none of its own repetitions, is added.
    Nothing for a segment with a whole repetition of its own (it was judged beside that),
    nor beside a segment with none or with nobody in view."""
    start, end = bounds[i]
    own = raw[i]
    if blind[i] or whole_in(own):
        return own
    at_end = end >= n_frames and i > 0 and bool(raw[i - 1]) and not blind[i - 1]
    at_start = start == 0 and i + 1 < len(bounds) and bool(raw[i + 1]) and not blind[i + 1]
    if at_end:
        found = _repetitions(sig, raw[i - 1][-1].start_frame, n_frames, n_frames)
    elif at_start:
        found = _repetitions(sig, 0, raw[i + 1][0].end_frame, n_frames)
    else:
        return own
    return cut_off_beside(own, found, (start, end), sig.step, at_end)


def whole_in(reps: Sequence[Repetition]) -> bool:
    """Whether any of ``reps`` (of one stretch) is whole: its far point held up to neither
    end of the stretch (:attr:`Repetition.held`). Beside one, a far point cut off at the
    recording's start or end counts when it got nearly as far
    (:func:`features.repetitions.count_in_signals`)."""
    return any(not any(r.held) for r in reps)


def cut_off_beside(
    own: Sequence[Repetition],
    found: Sequence[Repetition],
    bounds: tuple[int, int],
    step: int,
    at_end: bool,
) -> tuple[Repetition, ...]:
    """``own``, the repetitions of a segment, frames ``bounds`` [start, end), at the
    recording's end (``at_end``) or start, with the far point cut off there that ``found``
    keeps (the repetitions of the frames from the nearest repetition of the segment across
    its cut to that edge, counted as one stretch; :attr:`Repetition.held` at the edge),
    when it lies in this segment, past its cut by ``step`` frames (one sample of the
    counter's signals), and in none of ``own``: the part of it in the segment added.
    :func:`_beside_whole` (``segment``), :meth:`cbr.live.LiveSegmenter._beside_whole`
    (``watch``, at the stream's end) and :meth:`cbr.live.LiveSegmenter._judge_held` (at its
    start) judge it so."""
    start, end = bounds
    if at_end:
        edge = [r for r in found if r.held[1] and r.peak_frame >= start + step][-1:]
    else:
        edge = [r for r in found if r.held[0] and r.peak_frame < end - step][:1]
    if not edge or any(r.start_frame <= edge[0].peak_frame < r.end_frame for r in own):
        return tuple(own)
    clipped = replace(edge[0], start_frame=max(start, edge[0].start_frame),
                      end_frame=min(end, edge[0].end_frame))  # fmt: skip
    return tuple(sorted((*own, clipped), key=lambda r: r.peak_frame))


def _held_to_the_end(
    out: list[tuple[Repetition, ...]],
    raw: Sequence[tuple[Repetition, ...]],
    bounds: Sequence[tuple[int, int]],
    blind: Sequence[bool],
) -> list[tuple[Repetition, ...]]:
    """:func:`counted_segments`' ``out`` with a segment's last far point held up to its end
    (:attr:`features.repetitions.Repetition.held`) and on to the recording's end, nothing
    come back (no far point in any segment after it, nobody in view in none), that the
    segment keeps as a repetition (beside whole ones: one got into and held alone is none),
    counted by the last segment, where the recording ends in the hold, as a far point held
    across a cut is counted by the segment where the body comes back: two squats and a
    third held at the bottom to the end, the label changing in the hold, count 2 and 1
    (were 3 and 0; ``watch``, which finishes the first segment while the hold goes on,
    counted 2 and 1). ``raw``: each segment's repetitions counted alone; ``blind``: nobody in
    view in it."""
    for i in range(len(bounds) - 1):
        if any(raw[j] or blind[j] for j in range(i + 1, len(bounds))):
            continue
        if not (raw[i] and raw[i][-1].held[1] and out[i]):
            break
        kept = out[i][-1]
        if kept.peak_frame != raw[i][-1].peak_frame:  # left out: a posture got into
            break
        start = bounds[-1][0]
        at = replace(kept, start_frame=max(kept.start_frame, start),
                     peak_frame=max(kept.peak_frame, start), end_frame=bounds[-1][1])  # fmt: skip
        out = [*out[:i], out[i][:-1], *out[i + 1 : -1], (*out[-1], at)]
        break
    return out


def _held_across(
    before: Sequence[Repetition],
    after: Sequence[Repetition],
    second: tuple[int, int],
    sig: MovementSignals | _Apart,
) -> bool:
    """Whether the last of ``before`` (the repetitions of one segment) and the first of
    ``after`` (of the next segment that has any, frames ``second``; those between found no
    far point) are one far point held across the cut
    between them: the movement falls back from the one by less than
    :data:`features.repetitions.MIN_EXCURSION_RAD` up to the cut, and rises to the other by
    less than that from it (:attr:`features.repetitions.Repetition.held`; or has its far
    point at the cut, :func:`at_cut`). A squat held at the bottom, or an arm held raised,
    through a change of label the classifier saw in the hold: each segment's far point lies
    mid-way along its part of the hold, neither at the cut, and the repetition counted in
    both. Both sides must hold it: the line dips by less than that between the two, no far
    point of its own on either side.

    Or a shallow dip between them: neither side comes back by the cut
    (:attr:`features.repetitions.Repetition.unreturned`), the one after rises to a far point
    of its own (not at the cut), and the two repetitions' frames together, counted as one
    stretch of the recording (each segment's movement line is its own: the next exercise's
    may barely show the last one's return), hold one far point, not two."""
    if not before or not after:
        return False
    last, first = before[-1], after[0]
    at_start = at_cut(after, *second, sig.step)[0]
    if last.unreturned[1] and first.unreturned[0] and not at_start:
        return len(_repetitions(sig, last.start_frame, first.end_frame)) == 1
    return last.held[1] and (first.held[0] or at_start)


def _frames_of(a: int, b: int, fps: float, n_frames: int) -> tuple[int, int]:
    """Frames [start, end) of blocks [a, b): a block's first frame is the first whose time
    lies in it, as a label file's blocks are read (:func:`features.label_tracks.frame_labels`)."""
    per_block = fps * BLOCK_S
    return _first_frame(a, per_block), min(n_frames, _first_frame(b, per_block))


def _first_frame(block: int, per_block: float) -> int:
    """The first frame of ``block`` at ``per_block`` frames a block."""
    return int(math.ceil(block * per_block - 1e-9 * per_block))


def _segment_of(
    clf: Any,
    rec: PoseSequence,
    run: tuple[int, int, int],
    solved: Sequence[_Solved],
    votes: np.ndarray,
    judge: Judge,
    evidence: Sequence[bool],
    reps: tuple[Repetition, ...],
    pieces: _LastPiece | None = None,
) -> Segment:
    """One decoded run as a segment: frames, label, confidence (the mean over its blocks of
    ``votes`` ``(n_blocks, n_classes + 1)`` for its state: a known activity's share of the
    votes, unknown's evidence, :func:`unknown_shares`), ``reps`` (its repetitions,
    :func:`counted_segments`), explanation."""
    a, b, state = run
    n_classes = len(clf.classes_)
    start, end = _frames_of(a, b, rec.fps, rec.n_frames)
    # told by the windows centred in it that were evidence (none across a change of activity);
    # a segment too short for any window's centre, by the windows over it
    pairs = list(zip(solved, evidence, strict=True))
    centred = [(w, e) for w, e in pairs if start <= w.centre < end]
    if not centred:
        centred = [(w, e) for w, e in pairs if w.start < end and w.stop > start]
    inside = [w for w, e in centred if e] or [w for w, _ in centred]
    text, ratio = _explain_segment(clf, rec, inside, state, judge, pieces)
    label = None if state == n_classes else str(clf.classes_[state])
    return Segment(start, end, label, float(votes[a:b, state].mean()), reps, text, ratio)


def _slivers_beside_nobody(path: np.ndarray, n_classes: int) -> np.ndarray:
    """``path`` with each run shorter than :data:`MIN_SEGMENT_S` after a run of nobody in
    view (state ``n_classes + 1``), which the decoders left where nobody in view cut a
    longer one short, given to what follows it: nobody in view when it is unknown and lies
    between two such runs (the person seen for a flicker), else the segment after it (its
    windows, half empty, are like no activity, or like the one before: the segment starts
    where the person is seen again; before, a sliver of an activity stayed, 3 to 6 frames of
    knee raises between nobody in view and squats). Nobody in view holds only frames without
    the person; any other sliver stays (an unknown one before nobody in view too: its frames
    show the person, unlike every activity as they leave, as ``watch`` gives it,
    :class:`cbr.live.LiveSegmenter`)."""
    nobody = n_classes + 1
    runs = _runs(path)
    for i, (a, b, state) in enumerate(runs[1:-1], start=1):
        before, after = runs[i - 1][2], runs[i + 1][2]
        short = (b - a) * BLOCK_S < MIN_SEGMENT_S
        if short and before == nobody and (after != nobody or state == n_classes):
            path[a:b] = after
    return path


def _nobody_segment(rec: PoseSequence, a: int, b: int) -> Segment:
    """Blocks [a, b), in which nobody is in view, as an unknown segment that says so (or,
    mostly a gap in the video's frames, that it has no frames there)."""
    start, end = _frames_of(a, b, rec.fps, rec.n_frames)
    why = nobody_explanation(gap_rows(rec)[start:end])
    return Segment(start, end, None, 1.0, (), why, float("nan"))


@dataclass(frozen=True)
class SolvedRecording:
    """A recording with its windows solved, before any judge of unknown has looked at it
    (:func:`solve_recording`); :func:`finish` decodes and finishes it. Several judges can
    finish one (the windows are solved once)."""

    rec: PoseSequence
    sig: MovementSignals
    windows: tuple[_Solved, ...]
    outliers: np.ndarray  # (n_windows,) bool: :func:`period_outliers`, which do not vote


def _check_call(clf: Any, recording: Any, chunk_frames: Any) -> None:
    """Refuse an unfitted ``clf`` (NotFittedError, as its ``predict`` does) or one that is no
    case base classifier (InputError), a ``recording`` that is not a PoseSequence and a
    ``chunk_frames`` that is not None or a whole number >= 0."""
    check_case_base_classifier(clf, "call 'fit' with appropriate arguments before using it")
    clf.case_base_.check_not_empty("case_base_")
    expect_sequence(recording, "recording")
    if chunk_frames is not None and (
        isinstance(chunk_frames, bool)
        or not isinstance(chunk_frames, int | np.integer)
        or chunk_frames < 0
    ):
        raise ParameterError(
            f"must be None or a whole number >= 0, got {chunk_frames!r}",
            "chunk_frames",
        )


def check_judge(judge: Any, classes: Sequence[Any] | None = None) -> None:
    """Refuse a judge given by its name (:func:`cbr.unknown.judge_of` makes the judge of a
    name): it would be found not to be one only when the first window is judged; and a judge
    with a threshold per activity calibrated on a case base of another number of activities
    than ``classes`` (the classifier's: another classifier's judge), which would fail deep
    in the first window judged (or read another activity's threshold), or, when the judge
    names its activities (:attr:`cbr.unknown.ActivityMargin.activities`), on others than
    ``classes`` or in another order (as many: each window judged against another
    activity's threshold); and a number (a ``k`` or a threshold given in its place), found
    otherwise to be no judge in the first window judged."""
    if isinstance(judge, str):
        raise InputError(
            f"must be None or a judge of cbr.unknown (judge_of(clf, {judge!r})), not its name",
            "judge",
        )
    if isinstance(judge, numbers.Number | np.bool_):  # k or a threshold in its place
        raise InputError(
            "must be None or a judge of cbr.unknown (judge_of(clf, 'spread-margin')),"
            f" got {type(judge).__name__}",
            "judge",
        )
    per = getattr(judge, "thresholds", None)
    if classes is not None and isinstance(per, tuple) and len(per) != len(classes):
        raise InputError(
            f"the judge was calibrated on a case base of {len(per)} activities, the classifier"
            f" has {len(classes)}: another classifier's judge (judge_of(clf, name) makes this"
            " classifier's)",
            "judge",
        )
    names = getattr(judge, "activities", None)
    mine = [str(c) for c in classes] if classes is not None else []
    if classes is not None and isinstance(names, tuple) and names and list(names) != mine:
        raise InputError(
            f"the judge was calibrated on the activities {_activity_list(names)}, the"
            f" classifier's are {_activity_list(mine)}: another classifier's judge"
            " (judge_of(clf, name) makes this classifier's)",
            "judge",
        )


ACTIVITIES_SHOWN = 6
"""Activities named in :func:`check_judge`'s refusal, then "and N more"."""


def _activity_list(names: Sequence[str]) -> str:
    """``a, b, c`` of the activities ``names`` in their order, at most
    :data:`ACTIVITIES_SHOWN` of them, then "and N more"."""
    listed = ", ".join(shown(n) for n in names[:ACTIVITIES_SHOWN])
    more = len(names) - ACTIVITIES_SHOWN
    return listed + (f" and {more} more" if more > 0 else "")


def check_segmentable(recording: PoseSequence) -> None:
    """Refuse, with the DataError :func:`segment` would raise, a recording it cannot segment
    (shorter than the shortest window, no frame showing the person, no person in enough
    frames to follow a movement), from its torso and movement signals alone: cheap, and
    cached for the segmenting when the recording is not cut in pieces. A command given
    several recordings refuses a bad one so before it segments any."""
    rec = recording.to_canonical()
    _check_duration(rec.n_frames, rec.fps, rec.source)
    check_person(rec, "segment", arms=True)  # every stretch would be nobody in view
    chunk = long_clip.chunk_for(rec, None)
    if chunk:
        long_clip.movement_signals(rec, chunk)
    else:
        movement_signals_of(rec)
    # the windows are not cut here: finding the periods in them took 3 s of a long recording's
    # run, done again when it is segmented


def check_k(clf: Any, k: Any) -> None:
    """Refuse, with ParameterError (a ConfigError, and the ValueError a Python caller
    catches) naming the argument ``k``, a ``k`` (a window's nearest cases that vote) the
    fitted classifier ``clf`` does not retrieve: a whole number from 1 to its own k. A
    command checks it before it reads any recording (before, a video's poses were estimated
    first) and says it of its option, ``-k`` (before, a Python caller read that too)."""
    if isinstance(k, bool) or not isinstance(k, int | np.integer) or not 1 <= k <= int(clf.k):
        raise ParameterError(
            f"must be from 1 to the case base's k ({int(clf.k)}, the nearest cases a window"
            f" retrieves), a whole number, got {k!r}",
            "k",
        )


def solve_recording(
    clf: Any, recording: PoseSequence, k: int = 1, chunk_frames: int | None = None
) -> SolvedRecording:
    """Steps 1-3 of the module docstring for ``recording`` (positions ``(frames, joints,
    3)``): its windows solved by the fitted classifier ``clf``, and the repetition windows
    whose period disagrees with their neighbours' found (:func:`period_outliers`); ``k`` and
    ``chunk_frames`` as :func:`segment` takes them. Raises DataError for a recording shorter
    than one window or without a person, ConfigError for a ``k`` the classifier does not
    retrieve (more than its own k)."""
    _check_call(clf, recording, chunk_frames)
    check_k(clf, k)
    rec = recording.to_canonical()
    check_person(rec, "segment", arms=True)  # every stretch would be nobody in view
    chunk = long_clip.chunk_for(rec, chunk_frames)
    sig = long_clip.movement_signals(rec, chunk) if chunk else movement_signals_of(rec)
    windows = windows_of(sig, rec.n_frames, rec.fps, rec.source)
    config = clf.feature_config_
    if not chunk:
        warm(rec, config.level, mirror=config.side == "canonical")
    solved = _solve_windows(clf, rec, windows, k, chunk)
    spans = np.array([(w.start, w.stop) for w in solved], dtype=np.int64).reshape(-1, 2)
    repetition = np.array([w.repetition for w in solved], dtype=bool)
    return SolvedRecording(rec, sig, tuple(solved), period_outliers(spans, repetition, sig.step))


def decode_activities(
    solved: Sequence[_Solved], outliers: np.ndarray, unlike: np.ndarray, n_frames: int,
    fps: float, n_classes: int,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The block votes ``(n_blocks, n_classes)`` and the decoded activity of every block
    ``(n_blocks,)`` (steps 4-5 of the module docstring). Only the windows that are neither
    ``outliers`` (:func:`period_outliers`) nor ``unlike`` every activity (by the judge) vote:
    a window like no activity, across a change of movement or of one the case base lacks,
    says nothing of which activity a block is (its nearest is whichever lies least far).
    Every window still tells :func:`place_changes` how much of it is which."""
    voting = [w for w, out, far in zip(solved, outliers, unlike, strict=True) if not (out or far)]
    votes = block_votes(voting, n_frames, fps, n_classes)
    return votes, place_changes(solved, fps, decode(votes))


def finish(clf: Any, done: SolvedRecording, judge: Judge) -> Segmentation:
    """Steps 4-7 of the module docstring: the activities of ``done`` (:func:`solve_recording`
    with ``clf``) decoded from the windows ``judge`` finds like an activity
    (:func:`decode_activities`), the stretches unlike every activity of the case base made
    unknown, and every segment counted and explained. The judge sees the recording's person
    (:func:`cbr.unknown.for_person`, from the windows but the period outliers)."""
    rec, solved, n_classes = done.rec, list(done.windows), len(clf.classes_)
    counted = [w for w, out in zip(solved, done.outliers.tolist(), strict=True) if not out]
    judge = for_person(judge, np.array([np.min(w.nearest) for w in counted]))
    unlike = np.array([w.still or judge.unlike(w.nearest) for w in solved], dtype=bool)
    votes, path = decode_activities(solved, done.outliers, unlike, rec.n_frames, rec.fps,
                                    n_classes)  # fmt: skip
    evidence = within_runs(solved, rec.fps, path).tolist()
    unknown = unknown_shares(counted, rec.n_frames, rec.fps, judge, path)
    path[decode_unknown(np.stack([1.0 - unknown, unknown], axis=1), path)] = n_classes
    votes = np.column_stack([votes, unknown])  # an unknown segment's: its evidence of unknown
    # nobody in view: unknown, whatever the neighbours', and a segment of its own
    path[nobody_blocks(rec, len(path))] = n_classes + 1
    runs = _runs(_slivers_beside_nobody(path, n_classes))
    bounds = [_frames_of(a, b, rec.fps, rec.n_frames) for a, b, _ in runs]
    unseen = [s > n_classes for *_, s in runs]
    states = [s for *_, s in runs]
    reps = counted_apart(done.sig, bounds, rec.n_frames, unseen, person_jumps(rec), rec, states)
    pieces = _LastPiece()
    segments = tuple(
        _nobody_segment(rec, a, b)
        if state > n_classes
        else _segment_of(clf, rec, (a, b, state), solved, votes, judge, evidence, r, pieces)
        for (a, b, state), r in progress(
            zip(runs, reps, strict=True), "explaining segments", len(runs), "segment", False
        )
    )
    pieces.drop()
    blocks: list[str | None] = []
    for a, b, state in runs:
        blocks += [None if state >= n_classes else str(clf.classes_[state])] * (b - a)
    return Segmentation(rec.source, rec.fps, rec.n_frames, segments, tuple(blocks), len(solved))


def segment(
    clf: Any,
    recording: PoseSequence,
    judge: Judge | None = None,
    k: int = 1,
    chunk_frames: int | None = None,
) -> Segmentation:
    """Segment ``recording`` (positions ``(frames, joints, 3)``) with the fitted classifier
    ``clf`` (a :class:`~cbr.estimator.CaseBaseClassifier`); see the module docstring.

    ``judge``: what makes a stretch unknown (:mod:`cbr.unknown`): the margin between the two
    nearest activities times how far the window lies in the nearest one's own spread,
    against that activity's own threshold (``spread-margin``), calibrated on
    ``clf.case_base_``, when None; ``k``: a window's k nearest cases vote, as ``clf`` votes
    over a clip with k = ``k`` (:func:`votes_as`; 1: its nearest; the votes of successive
    windows are pooled over time); ``chunk_frames``: what the frames yield is computed that
    many frames at a time (:func:`_cut_in_pieces`; the same segments in bounded memory), 0:
    for the whole recording at once; None: in pieces of :data:`cbr.long_clip.CHUNK_FRAMES`
    for a longer recording.
    Raises DataError for a recording shorter than one window or without a person, and for a
    case base the judge cannot be calibrated on; InputError for a ``recording`` that is not a
    PoseSequence, a ``judge`` given by its name (:func:`cbr.unknown.judge_of` makes the
    judge) or as a number, or one of another classifier (other activities, or theirs in
    another order), ParameterError (a ConfigError and a ValueError) for a negative
    ``chunk_frames`` or a ``k`` that is not a whole number from 1 to the classifier's,
    NotFittedError for an unfitted ``clf``."""
    _check_call(clf, recording, chunk_frames)
    check_k(clf, k)  # before the default judge is calibrated (it may refuse the case base)
    check_judge(judge, clf.classes_)
    judge = judge or default_judge(clf)
    return finish(clf, solve_recording(clf, recording, k, chunk_frames), judge)


__all__ = [
    "BLOCK_S",
    "Familiarity",
    "HeldOut",
    "Judge",
    "Margin",
    "activity_distances",
    "check_judge",
    "check_k",
    "check_segmentable",
    "count_in_segment",
    "cut_off_beside",
    "whole_in",
    "Segment",
    "Segmentation",
    "SolvedRecording",
    "Window",
    "block_evidence",
    "block_votes",
    "decode_activities",
    "period_outliers",
    "periods_in_span",
    "unknown_blocks",
    "within_runs",
    "windows_of",
    "decode",
    "decode_unknown",
    "keep_whole",
    "least_movement",
    "movement_columns",
    "movement_of",
    "too_still",
    "votes_as",
    "window_still",
    "STILL_MOVEMENT_SHARE",
    "STILL_CASE_MOVEMENT",
    "STILL_TEXT",
    "at_cut",
    "counted_segments",
    "log_votes",
    "place_changes",
    "finish",
    "nobody_blocks",
    "sighting_width",
    "nobody_explanation",
    "NO_FRAMES",
    "segment",
    "solve_recording",
]
