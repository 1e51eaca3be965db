"""Segmentation of a long recording into activities of a case base, or unknown, with the
repetitions of each segment and a short explanation.

How (the fitted :class:`~cbr.estimator.CaseBaseClassifier` does the classifying, through its
``solve``, exactly as ``classify`` does):

1. what every frame yields (fluents, state signals, mirror image) is computed once for the
   whole recording; windows share it (:func:`features.derived.stretch`);
2. the windows (:func:`windows_of`): one of :data:`DEFAULT_WINDOW_S` every :data:`HOP_S`
   seconds, and every repetition found in the spans of :data:`PERIOD_SPAN_S` seconds around
   (:func:`features.repetitions.count_in_signals`, cut as ``train --split repetitions`` cuts
   cases);
3. every window is a clip to solve and votes for the activity of its nearest case;
4. each :data:`BLOCK_S` block gets the mean vote of the windows over it, and the labels are
   decoded over all blocks at once (Viterbi): a change of activity must be supported by at
   least :data:`MIN_SEGMENT_S` of evidence at odds of :data:`SWITCH_ODDS` to 1;
   stretches whose repetitions lie as far from their nearest cases as the case base's
   activities lie from each other (:class:`Familiarity`, calibrated on the case base) are
   decoded the same way and become unknown (:func:`unknown_blocks`);
5. each segment is counted (:func:`features.repetitions.count_repetitions`) and explained by
   its most confident window.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from features.body import torso_share
from features.derived import stretch
from features.errors import DataError
from features.poses import PoseSequence
from features.progress import progress
from features.repetitions import (
    MIN_PERIOD_S,
    MovementSignals,
    Repetition,
    count_in_signals,
    movement_signals,
)

from .casebase import CaseBase
from .explain import Explanation
from .problem import warm
from .retrieve import Retrieval
from .reuse import reuse

BLOCK_S = 0.1
"""Labels are given per block of this many seconds (the resolution of the label files)."""
HOP_S = 0.5
"""Where nothing repeats, a default window starts every this many seconds."""
SPAN_HOP_S = 1.0
"""Repetitions are looked for in spans starting every this many seconds (spans overlap by
all but this, so every repetition up to MAX_WINDOW_S lies whole in one)."""
MIN_WINDOW_S = 1.0
MAX_WINDOW_S = 5.0
DEFAULT_WINDOW_S = 2.0
"""Windows span one local period within these bounds; the default where nothing repeats."""
PERIOD_SPAN_S = 6.0
"""The local period is read from this many seconds around a window (periods up to 60 %)."""
MIN_SEGMENT_S = 1.0
SWITCH_ODDS = 2.0
"""A change of activity needs MIN_SEGMENT_S of blocks voting SWITCH_ODDS to 1 for it."""


class Judge(Protocol):
    """What says how unlike the case base a clip is, from its nearest-case distance: the
    classifier's own stored calibration (:class:`cbr.novelty.NoveltyCalibration`, held-out
    nearest-case distances) or :class:`Familiarity` (how far the activities lie apart)."""

    def ratio(self, distance: float) -> float: ...

    def unlike(self, distance: float) -> bool: ...


@dataclass(frozen=True)
class Familiarity:
    """When a clip is unlike every activity of the case base, calibrated on the case base
    itself: a clip whose nearest case lies as far as different activities of the case base
    lie from each other is no more that case's activity than the others are.

    ``threshold``: the median, over the cases, of the distance to the nearest case of another
    activity; ``reference`` (the unit of the novelty ratio): the median distance from a case
    to its nearest case of the same activity from another source (another recording or video:
    what a new recording of a known activity is to the case base; cases cut from one
    recording are near copies), or, where no activity has two sources, to its nearest other
    case."""

    reference: float
    threshold: float

    @classmethod
    def of(cls, cb: CaseBase) -> Familiarity:
        if len(cb.classes) < 2:
            raise DataError("a case base of one activity cannot say what is unlike it", "case base")
        within, between = _neighbour_distances(cb)
        reference = float(np.median(within)) or float(np.mean(within)) or 1.0
        return cls(reference, float(np.median(between)))

    def ratio(self, distance: float) -> float:
        """Nearest-case distance in units of the case base's usual neighbour distance."""
        return distance / self.reference

    def unlike(self, distance: float) -> bool:
        return distance > self.threshold


def _neighbour_distances(cb: CaseBase) -> tuple[np.ndarray, np.ndarray]:
    """Per case: the distance to its nearest same-activity case from another source (``within``;
    every case's nearest other case when no activity has two sources) and to its nearest case
    of another activity (``between``)."""
    sources = np.array(cb.sources, dtype=object)
    labels = cb.labels
    index = cb.index
    assert cb.reps is not None
    within, nearest, between = [], [], []
    for i in range(len(cb)):  # one query against the whole case base per case
        d = cb.measure.distances(cb.reps[i], index)
        same = labels == labels[i]
        between.append(float(d[~same].min()))
        nearest.append(float(np.delete(d, i).min()))
        peers = same & (sources != sources[i])
        if peers.any():
            within.append(float(d[peers].min()))
    return np.asarray(within or nearest), np.asarray(between)


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
        return {
            "start_s": round(self.start_frame / fps, 3),
            "end_s": round(self.end_frame / fps, 3),
            "start_frame": self.start_frame,
            "end_frame": self.end_frame,
            "label": self.label,
            "confidence": round(self.confidence, 3),
            "repetitions": len(self.repetitions),
            "explanation": self.explanation,
            "novelty": round(self.novelty, 3),
            "repetition_frames": [[r.start_frame, r.end_frame] for r in self.repetitions],
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
    """One window: frames [start, stop), its vote over the classes, its nearest-case distance
    and what solve gave (problem, retrieval, solution)."""

    start: int
    stop: int
    vote: np.ndarray
    distance: float
    solved: Any  # the classifier's Solved: problem, retrieval, solution, novelty, ...
    repetition: bool = False

    @property
    def centre(self) -> float:
        return 0.5 * (self.start + self.stop)


@dataclass(frozen=True)
class Window:
    """Frames [start, stop) of the recording to classify; ``repetition``: one repetition, cut
    the way ``train --split repetitions`` cuts cases (else a fixed-length window)."""

    start: int
    stop: int
    repetition: bool


def windows_of(sig: MovementSignals, n_frames: int, fps: float, where: str = "") -> list[Window]:
    """The windows to classify: one of :data:`DEFAULT_WINDOW_S` every :data:`HOP_S` seconds
    (whatever is done there, repeated or not), and every repetition found whole in spans of
    :data:`PERIOD_SPAN_S` seconds starting every :data:`SPAN_HOP_S` seconds."""
    duration = n_frames / fps
    if duration < MIN_WINDOW_S:
        raise DataError(
            f"the recording lasts {duration:.2f} s, shorter than one window ({MIN_WINDOW_S:g} s)"
            " of movement to classify",
            where or "recording",
        )
    length = int(round(min(DEFAULT_WINDOW_S, duration) * fps))
    out = []
    for centre in np.arange(HOP_S / 2, duration, HOP_S):
        start = min(max(0, int(centre * fps) - length // 2), n_frames - length)
        out.append(Window(start, start + length, False))
    return out + [Window(a, b, True) for a, b in _repetition_bounds(sig, n_frames, fps)]


def _repetition_bounds(sig: MovementSignals, n_frames: int, fps: float) -> list[tuple[int, int]]:
    """Frame ranges of the repetitions found whole in the spans, each once."""
    span = int(PERIOD_SPAN_S * sig.fps)
    hop = max(1, int(SPAN_HOP_S * sig.fps))
    found: set[tuple[int, int]] = set()
    for a in range(0, max(1, len(sig.values) - span + hop), hop):
        part = MovementSignals(sig.values[a : a + span], sig.names, sig.fps, sig.step)
        if len(part.values) < 4:
            continue
        span_frames = len(part.values) * sig.step
        for r in count_in_signals(part, span_frames, fps).repetitions:
            if r.start_frame == 0 or r.end_frame >= span_frames - sig.step:
                continue  # cut by the span's edge: whole in a neighbouring span
            start, stop = a * sig.step + r.start_frame, a * sig.step + r.end_frame
            if MIN_WINDOW_S * fps / 2 <= stop - start <= MAX_WINDOW_S * fps:
                found.add((start, min(n_frames, stop)))
    return sorted(found)


def _nearest_vote(retrieval: Retrieval, classes: np.ndarray, k: int) -> np.ndarray:
    """Vote shares of the ``k`` nearest retrieved cases (distance-weighted), ``(n_classes,)``."""
    top = Retrieval(
        retrieval.indices[:k], retrieval.distances[:k], retrieval.labels[:k], retrieval.case_ids[:k]
    )
    return reuse(top, classes, "distance").proba


def _solve_windows(clf: Any, rec: PoseSequence, windows: list[Window], k: int) -> list[_Solved]:
    """Each window solved by the classifier; its vote is that of its ``k`` nearest cases.
    Windows in which no frame shows the person are left out (nothing to solve)."""
    classes = np.array([str(c) for c in clf.classes_], dtype=object)
    out = []
    for w in progress(windows, "classifying windows", unit="window"):
        part = stretch(rec, w.start, w.stop)
        if torso_share(part) == 0.0:
            continue
        solved = clf.solve([part])[0]
        vote = _nearest_vote(solved.retrieval, classes, k)
        distance = float(solved.retrieval.distances[0])
        out.append(_Solved(w.start, w.stop, vote, distance, solved, w.repetition))
    return out


def block_votes(solved: Sequence[_Solved], n_frames: int, fps: float) -> np.ndarray:
    """``(n_blocks, n_classes)``: the mean vote of the windows over each block's centre."""
    n_blocks = int(math.ceil(n_frames / (fps * BLOCK_S) - 1e-9))
    centres = (np.arange(n_blocks) + 0.5) * BLOCK_S * fps  # in frames
    starts = np.array([w.start for w in solved])
    stops = np.array([w.stop for w in solved])
    cover = (starts[None, :] <= centres[:, None]) & (centres[:, None] < stops[None, :])
    votes = cover.astype(np.float64) @ np.stack([w.vote for w in solved])
    counts = cover.sum(axis=1)
    n_states = votes.shape[1]
    uniform = np.full(n_states, 1.0 / n_states)
    return np.where(counts[:, None] > 0, votes / np.maximum(counts, 1)[:, None], uniform)


def decode(votes: np.ndarray) -> np.ndarray:
    """The most likely state of every block (Viterbi) under a constant cost per change of
    state: :data:`MIN_SEGMENT_S` of blocks at :data:`SWITCH_ODDS` to 1. ``(n_blocks,)``."""
    penalty = (MIN_SEGMENT_S / BLOCK_S) * math.log(SWITCH_ODDS)
    score = np.log(np.clip(votes, 1e-3, None))
    n, k = score.shape
    back = np.zeros((n, k), dtype=np.int64)
    total = score[0].copy()
    for t in range(1, n):  # over 0.1-s blocks, each step vectorised over the states
        best = int(np.argmax(total))
        switch = total[best] - penalty
        stay = total >= switch
        back[t] = np.where(stay, np.arange(k), best)
        total = np.where(stay, total, switch) + score[t]
    path = np.empty(n, dtype=np.int64)
    path[-1] = int(np.argmax(total))
    for t in range(n - 1, 0, -1):
        path[t - 1] = back[t, path[t]]
    return path


def _runs(path: np.ndarray) -> list[tuple[int, int, int]]:
    """Runs of one state: (first block, end block exclusive, state)."""
    change = np.flatnonzero(path[1:] != path[:-1]) + 1
    starts = np.r_[0, change]
    ends = np.r_[change, len(path)]
    return [(int(a), int(b), int(path[a])) for a, b in zip(starts, ends, strict=True)]


def unknown_blocks(
    solved: Sequence[_Solved], n_frames: int, fps: float, familiar: Judge
) -> np.ndarray:
    """``(n_blocks,)`` bool: blocks unlike the case base. A block's evidence is the share of
    the repetition windows over it whose nearest case lies beyond
    :attr:`Familiarity.threshold` (repetitions are cut the way the cases of a case base of
    repetitions are; a fixed window cut at another phase lies farther from every case for that
    alone), of all windows over it where no repetition was found; known/unknown is decoded like
    the activities (a change needs :data:`MIN_SEGMENT_S`)."""

    def flags(ws: Sequence[_Solved]) -> tuple[np.ndarray, np.ndarray]:
        marked = [
            dataclasses.replace(
                w, vote=np.array([0.0, 1.0] if familiar.unlike(w.distance) else [1.0, 0.0])
            )
            for w in ws
        ]
        if not marked:
            return np.zeros((n_blocks, 2)), np.zeros(n_blocks, dtype=bool)
        return block_votes(marked, n_frames, fps), _covered(marked, n_frames, fps)

    n_blocks = int(math.ceil(n_frames / (fps * BLOCK_S) - 1e-9))
    every, _ = flags(solved)
    reps, has_rep = flags([w for w in solved if w.repetition])
    return decode(np.where(has_rep[:, None], reps, every)) == 1


def _covered(solved: Sequence[_Solved], n_frames: int, fps: float) -> np.ndarray:
    """``(n_blocks,)`` bool: some window lies over the block's centre."""
    n_blocks = int(math.ceil(n_frames / (fps * BLOCK_S) - 1e-9))
    centres = (np.arange(n_blocks) + 0.5) * BLOCK_S * fps
    starts = np.array([w.start for w in solved])
    stops = np.array([w.stop for w in solved])
    return np.asarray(
        ((starts[None, :] <= centres[:, None]) & (centres[:, None] < stops[None, :])).any(axis=1)
    )


def _explain_segment(
    clf: Any, inside: list[_Solved], state: int, familiar: Judge
) -> tuple[str, float]:
    """A short explanation from the segment's most telling window, and the segment's novelty
    ratio (the median over its windows)."""
    n_classes = len(clf.classes_)
    if not inside:
        return "", float("nan")
    ratio = familiar.ratio(float(np.median([w.distance for w in inside])))
    if state == n_classes:  # unknown
        w = min(inside, key=lambda s: s.distance)
        nearest = str(w.solved.retrieval.labels[0])
        return (
            f"unlike every stored case: even the nearest ({nearest}) lies {ratio:.1f}x the case"
            " base's usual nearest-case distance away",
            ratio,
        )
    w = max(inside, key=lambda s: s.vote[state])
    e: Explanation = clf.explain_solved(w.solved, counterfactual=False)
    label = str(clf.classes_[state])
    agree = sum(str(n["label"]) == label for n in e.neighbours)
    text = f"{agree} of the {len(e.neighbours)} most similar cases are {label}"
    if e.matched:
        text += "; matched: " + ", ".join(e.matched[:3])
    return text, ratio


def _repetitions(sig: MovementSignals, start: int, end: int) -> tuple[Repetition, ...]:
    """The repetitions within frames [start, end) of the recording whose signals are ``sig``
    (counted on the recording's own smoothed signals: no edge effects at the cut)."""
    a, b = start // sig.step, max(start // sig.step + 1, end // sig.step)
    if (b - a) / sig.fps < MIN_PERIOD_S:
        return ()
    part = MovementSignals(sig.values[a:b], sig.names, sig.fps, sig.step)
    found = count_in_signals(part, (b - a) * sig.step, sig.fps * sig.step).repetitions
    off = a * sig.step
    return tuple(
        Repetition(r.start_frame + off, min(end, r.end_frame + off), r.peak_frame + off, r.side)
        for r in found
    )


def _segment_of(
    clf: Any,
    rec: PoseSequence,
    sig: MovementSignals,
    run: tuple[int, int, int],
    solved: Sequence[_Solved],
    votes: np.ndarray,
    familiar: Judge,
) -> Segment:
    """One decoded run as a segment: frames, label, confidence, repetitions, explanation."""
    a, b, state = run
    n_classes = len(clf.classes_)
    frames_per_block = rec.fps * BLOCK_S
    start = int(round(a * frames_per_block))
    end = min(rec.n_frames, int(round(b * frames_per_block)))
    inside = [w for w in solved if start <= w.centre < end]
    reps = _repetitions(sig, start, end)
    text, ratio = _explain_segment(clf, inside, state, familiar)
    label: str | None = None
    if state == n_classes:  # confidence: the share of its windows unlike every case
        share = [1.0 if familiar.unlike(w.distance) else 0.0 for w in inside]
        confidence = float(np.mean(share)) if share else 1.0
    else:
        label, confidence = str(clf.classes_[state]), float(votes[a:b, state].mean())
    return Segment(start, end, label, confidence, reps, text, ratio)


def segment(
    clf: Any, recording: PoseSequence, familiar: Judge | None = None, k: int = 1
) -> Segmentation:
    """Segment ``recording`` (positions ``(frames, joints, 3)``) with the fitted classifier
    ``clf`` (a :class:`~cbr.estimator.CaseBaseClassifier`); see the module docstring.

    ``familiar``: what judges a stretch unlike the case base: :class:`Familiarity` of
    ``clf.case_base_`` when None (how far its activities lie apart), or the classifier's own
    calibration ``clf.novelty_`` (how far held-out training clips lie from the cases);
    ``k``: a window votes with its k nearest cases (1: its nearest; the votes of successive
    windows are pooled over time). Raises DataError for a recording shorter than one window
    or without a person."""
    rec = recording.to_canonical()
    familiar = familiar or Familiarity.of(clf.case_base_)
    sig = movement_signals(rec)
    windows = windows_of(sig, rec.n_frames, rec.fps, rec.source)
    config = clf.feature_config_
    warm(rec, config.level, mirror=config.side == "canonical")
    solved = _solve_windows(clf, rec, windows, k)
    votes = block_votes(solved, rec.n_frames, rec.fps)
    n_classes = len(clf.classes_)
    path = decode(votes)
    path[unknown_blocks(solved, rec.n_frames, rec.fps, familiar)] = n_classes
    runs = _runs(path)
    segments = tuple(_segment_of(clf, rec, sig, run, solved, votes, familiar) for run in runs)
    blocks: list[str | None] = []
    for a, b, state in runs:
        blocks += [None if state == n_classes else str(clf.classes_[state])] * (b - a)
    return Segmentation(rec.source, rec.fps, rec.n_frames, segments, tuple(blocks), len(solved))


__all__ = [
    "BLOCK_S",
    "Familiarity",
    "Segment",
    "Segmentation",
    "Window",
    "block_votes",
    "unknown_blocks",
    "windows_of",
    "decode",
    "segment",
]
