"""The fluent-level problem of a long clip in bounded memory, a piece of the clip at a time.

A clip's fluent-level problem is its feature columns (fluent confidences, joint angles, body
positions: :func:`cbr.problem.extract_problem`), gaps filled along time, resampled to
``length`` frames; clip summaries are statistics of that resampled sequence. Held whole, the
columns of a clip of 10^6 frames take about 10 GB (every fluent state's confidence is 566
float64 a frame, the state signals 171 more). Yet resampling reads at most ``2 * length``
frames of them, and filling a gap at such a frame needs only the nearest defined frames either
side. So :func:`resampled_columns` computes the columns ``CHUNK_FRAMES`` frames at a time (each
piece with the history its motion states look back on, as
:func:`features.fluents.evaluate_chunks` does) and keeps, per column, the values at the frames
resampling reads and the last defined value seen (:class:`SampledColumns`): the same numbers
as the whole-clip computation, in the memory of the poses plus one piece.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np

from features.body import (
    arm_planes,
    left_moves_more,
    mid_hips,
    mirrored,
    neck_to_hip,
    position_frame,
    positions_in_frame,
    start_frames,
    start_rows,
)
from features.derived import derived, is_cached
from features.fluents import DEFAULT_TABLE, evaluate, history_frames
from features.geometry import body_frame
from features.progress import progress
from features.qmp import QMPFeatures, load_add, qmp_from_signals
from features.repetitions import MovementSignals
from features.repetitions import movement_signals as count_signals
from features.signals import ANGLE_SIGNALS, StateSignals, state_signals

if TYPE_CHECKING:
    from features.poses import PoseSequence

    from .problem import _ColumnPlan

#: frames computed at once for a long clip (about 90 MB of fluent confidences); a clip with
#: more frames than this goes through :func:`resampled_columns` unless its fluents are cached
CHUNK_FRAMES = 20_000

PositionFrame = tuple[np.ndarray, np.ndarray, float] | None


def chunk_for(seq: PoseSequence, chunk_frames: int | None, kind: str = "fluents") -> int:
    """The piece size for ``seq``: ``chunk_frames`` when given (0: the whole clip at once),
    else :data:`CHUNK_FRAMES` for a clip longer than that whose ``kind`` (``"fluents"``,
    ``"qmp"``) is not computed yet, 0 otherwise (and for a clip of one frame)."""
    if seq.n_frames < 2:  # nothing to resample between
        return 0
    if chunk_frames is not None:
        return max(0, int(chunk_frames))
    if seq.n_frames > CHUNK_FRAMES and not is_cached(seq, kind):
        return CHUNK_FRAMES
    return 0


def _pieces(seq: PoseSequence, chunk: int, history: int) -> Iterator[tuple[int, PoseSequence]]:
    """``(start, piece)``: canonical frames ``start - history`` (clipped at 0) to
    ``start + chunk`` of ``seq``, for start = 0, chunk, 2 chunk, ..."""
    for start in range(0, seq.n_frames, chunk):
        read_from = max(0, start - history)
        stop = min(seq.n_frames, start + chunk)
        yield start - read_from, seq.slice_frames(read_from, stop).to_canonical()


def moves_left_more(seq: PoseSequence, chunk: int) -> bool:
    """:func:`features.body.moves_left_more` of ``seq`` ``(frames, joints, 3)`` computed
    ``chunk`` frames at a time: only the angle signals ``(frames, 22)`` are kept whole."""
    angles: np.ndarray | None = None
    names: tuple[str, ...] = ()
    for start in range(0, seq.n_frames, chunk):
        sig = state_signals(seq.slice_frames(start, start + chunk))
        names = sig.angle_names
        if angles is None:
            angles = np.empty((seq.n_frames, len(names)))
        angles[start : start + sig.values.shape[0]] = sig.values[:, : len(names)]
    assert angles is not None  # a clip has frames
    return left_moves_more(angles, names)


def qmp_features(seq: PoseSequence, chunk: int, mirror: bool = False) -> QMPFeatures:
    """:func:`features.qmp.qmp_features` of ``seq`` ``(frames, joints, 3)`` (of its mirror
    image with ``mirror``), its state signals computed ``chunk`` frames at a time and its fit's
    normal equations summed ``chunk`` frames at a time. The QMP fit is defined over every frame
    of the clip, so the signals the ADD reads are kept whole, ``(frames, 16)``; the other 80
    state signals and the fit's basis never are."""
    add = load_add()
    values = np.empty((seq.n_frames, len(add.signals)))
    for start in range(0, seq.n_frames, chunk):
        piece = seq.slice_frames(start, start + chunk).to_canonical()
        sig = state_signals(mirrored(piece) if mirror else piece)
        values[start : start + piece.n_frames] = sig.values[:, _columns(sig.names, add.signals)]
    return qmp_from_signals(values, seq.fps, add, frame_block=chunk)


def movement_signals(seq: PoseSequence, chunk: int) -> MovementSignals:
    """:func:`features.repetitions.movement_signals` of ``seq`` ``(frames, joints, 3)`` with
    its state signals computed ``chunk`` frames at a time (they are per frame): only the
    joint angles ``(frames, 22)`` are kept whole, which is all the counted angles read, not
    the near distances ``(frames, 148)``. They are handed over as the signals of a
    stand-in for ``seq`` (a new object: what is cached for it goes with it). Cached for
    ``seq`` and ``chunk``: a command checks a recording can be segmented before segmenting it
    (:func:`cbr.segmentation.check_segmentable`), and both read these."""
    return derived(seq, f"movement_signals/{chunk}", lambda s: _movement_signals(s, chunk))


def _movement_signals(seq: PoseSequence, chunk: int) -> MovementSignals:
    n = seq.n_frames
    angles = np.empty((n, len(ANGLE_SIGNALS)))
    head = np.empty(n)
    starts = range(0, n, chunk)
    for start in progress(starts, "joint angles", len(starts), "piece", leave=False):
        sig = state_signals(seq.slice_frames(start, start + chunk))
        angles[start : start + len(sig.values)] = sig.values[:, : len(ANGLE_SIGNALS)]
        head[start : start + len(sig.values)] = sig.head_length_m
    angle_signals = StateSignals(ANGLE_SIGNALS, angles, seq.fps, head, np.empty((n, 0)))
    stand_in = dataclasses.replace(seq)
    derived(stand_in, "signals", lambda _: angle_signals)
    return count_signals(stand_in)


def availability(seq: PoseSequence, states: tuple[str, ...], chunk: int) -> np.ndarray:
    """:func:`cbr.problem.availability` of ``seq`` over the columns ``states``, ``chunk``
    frames at a time: a column is there when some piece has it ``(n_columns,)``."""
    from .problem import column_kinds, defined_columns

    fluent, angles, positions = (bool(k.any()) for k in column_kinds(states))
    frame = _position_frame(seq, chunk, False) if positions else None
    history = history_frames(DEFAULT_TABLE, seq.fps) if fluent else 0
    out = np.zeros(len(states), dtype=bool)
    for skip, piece in _pieces(seq, chunk, history):
        sig = state_signals(piece)
        res = evaluate(piece, signals=sig) if fluent else None
        core = piece.slice_frames(skip, piece.n_frames)
        out |= defined_columns(
            states,
            (res.confidence[skip:], res.state_names) if res is not None else None,
            (sig.values[skip:, : len(sig.angle_names)], sig.angle_names) if angles else None,
            positions_in_frame(core.positions, frame) if positions else None,
        )
    return out


def _columns(names: tuple[str, ...], wanted: tuple[str, ...]) -> list[int]:
    index = {n: i for i, n in enumerate(names)}
    return [index[n] for n in wanted]


def _position_frame(seq: PoseSequence, chunk: int, mirror: bool) -> PositionFrame:
    """:func:`features.body.position_frame` of the (mirrored) clip, ``chunk`` frames at a
    time."""

    def canonical(start: int, stop: int) -> np.ndarray:
        part = seq.slice_frames(start, stop).to_canonical()
        return (mirrored(part) if mirror else part).positions

    n = seq.n_frames
    lengths, hips = [], []
    for s in range(0, n, chunk):
        part = canonical(s, s + chunk)
        lengths.append(neck_to_hip(part))
        hips.append(mid_hips(part))
    at = start_rows(np.concatenate(hips), start_frames(n))

    def level_left() -> np.ndarray:
        return np.concatenate(
            [body_frame(canonical(s, s + chunk)).level_left for s in range(0, n, chunk)]
        )  # fmt: skip

    return position_frame(canonical(at.start, at.stop), np.concatenate(lengths), level_left)


def _piece_columns(
    piece: PoseSequence, skip: int, plan: _ColumnPlan, frame: PositionFrame
) -> np.ndarray:
    """The unfilled columns of ``plan`` for the frames of ``piece`` after its first ``skip``
    (the history its motion states read), ``(frames, n_columns)``."""
    from .problem import raw_columns

    sig = state_signals(piece)
    conf = evaluate(piece, signals=sig).confidence[skip:]
    core = piece.slice_frames(skip, piece.n_frames)
    planes = arm_planes(core) if plan.arm_planes else None
    positions = positions_in_frame(core.positions, frame) if len(plan.position_cols) else None
    return raw_columns(plan, conf, sig.names, sig.values[skip:], planes, positions)


def resampled_columns(
    seq: PoseSequence,
    plan: _ColumnPlan,
    fills: np.ndarray,
    length: int,
    chunk: int,
    mirror: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """``(length, n_columns)``: the columns of ``plan`` for ``seq`` (its mirror image with
    ``mirror``), gaps filled along time (a column never defined: ``fills``), resampled to
    ``length`` frames; computed ``chunk`` frames at a time. Equal to
    ``resample(fill_nan_time(columns), length)`` of the whole clip's columns. With it,
    ``(n_columns,)`` bool: the columns never defined in any frame (their values are fills)."""
    from .problem import resample_points

    i, w = resample_points(seq.n_frames, length)
    at = np.unique(np.concatenate([i, i + 1]))
    sampled = SampledColumns(at, fills)
    frame = _position_frame(seq, chunk, mirror) if len(plan.position_cols) else None
    start = 0
    for skip, piece in _pieces(seq, chunk, history_frames(DEFAULT_TABLE, seq.fps)):
        cols = _piece_columns(mirrored(piece) if mirror else piece, skip, plan, frame)
        sampled.feed(start, cols)
        start += cols.shape[0]
    x = sampled.values()
    lo, hi = x[np.searchsorted(at, i)], x[np.searchsorted(at, i + 1)]
    out: np.ndarray = lo * (1.0 - w) + hi * w
    return out, sampled.never


class SampledColumns:
    """The values at frames ``at`` of ``(frames, n)`` columns whose gaps are filled along time
    as :func:`cbr.problem.fill_nan_time` fills them (linear between the defined frames either
    side, the edge value held beyond the first or last, ``fills[j]`` in a column never
    defined), from consecutive pieces of the columns fed in order: memory ``(len(at), n)``.

    at: sorted distinct frame indices ``(k,)``; fills: ``(n,)``.
    """

    def __init__(self, at: np.ndarray, fills: np.ndarray) -> None:
        self.at = np.asarray(at, dtype=np.int64)
        self.fills = np.asarray(fills, dtype=np.float64)
        k, n = len(self.at), len(self.fills)
        self.value = np.full((k, n), np.nan)
        self.waiting = np.zeros((k, n), dtype=bool)  # a gap waiting for its next defined frame
        self.prev_t = np.full((k, n), -1, dtype=np.int64)  # the gap's last defined frame
        self.prev_v = np.full((k, n), np.nan)
        self.last_t = np.full(n, -1, dtype=np.int64)  # the last defined frame fed so far
        self.last_v = np.full(n, np.nan)

    def feed(self, start: int, x: np.ndarray) -> None:
        """The next piece: frames ``start`` .. ``start + len(x)`` of the columns, ``(m, n)``."""
        valid = ~np.isnan(x)
        has = valid.any(axis=0)
        if self.waiting.any():
            first = np.argmax(valid, axis=0)
            rows, cols = np.nonzero(self.waiting & has)
            self._between(rows, cols, start + first[cols], x[first[cols], cols])
        inside = np.flatnonzero((self.at >= start) & (self.at < start + x.shape[0]))
        if len(inside):
            self._sample(start, x, valid, inside)
        last = x.shape[0] - 1 - np.argmax(valid[::-1], axis=0)
        self.last_t = np.where(has, start + last, self.last_t)
        self.last_v = np.where(has, x[last, np.arange(x.shape[1])], self.last_v)

    def _sample(self, start: int, x: np.ndarray, valid: np.ndarray, inside: np.ndarray) -> None:
        """The frames of ``at`` in this piece: their values, and their gaps filled from the
        defined frames around them (the next one may come in a later piece)."""
        rows = self.at[inside] - start
        self.value[inside] = x[rows]
        gap_r, gap_c = np.nonzero(np.isnan(x[rows]))
        if not len(gap_r):
            return
        cols = np.unique(gap_c)  # the few gappy columns only
        idx = np.arange(x.shape[0])[:, None]
        v = valid[:, cols]
        before = np.maximum.accumulate(np.where(v, idx, -1), axis=0)
        after = np.minimum.accumulate(np.where(v, idx, x.shape[0])[::-1], axis=0)[::-1]
        where = np.searchsorted(cols, gap_c)
        p, q = before[rows[gap_r], where], after[rows[gap_r], where]
        at_r = inside[gap_r]
        self.prev_t[at_r, gap_c] = np.where(p >= 0, start + p, self.last_t[gap_c])
        self.prev_v[at_r, gap_c] = np.where(p >= 0, x[np.maximum(p, 0), gap_c],
                                            self.last_v[gap_c])  # fmt: skip
        now = q < x.shape[0]
        self.waiting[at_r[~now], gap_c[~now]] = True
        self._between(at_r[now], gap_c[now], start + q[now], x[q[now], gap_c[now]])

    def _between(self, rows: np.ndarray, cols: np.ndarray, q: np.ndarray, qv: np.ndarray) -> None:
        """Fill the gaps (rows, cols) from their last defined frame before and the next one,
        ``q`` with value ``qv`` (np.interp's arithmetic; no frame before: ``qv`` held)."""
        pt, pv = self.prev_t[rows, cols], self.prev_v[rows, cols]
        with np.errstate(invalid="ignore", divide="ignore"):
            slope = (qv - pv) / (q - pt)
            filled = slope * (self.at[rows] - pt) + pv
        self.value[rows, cols] = np.where(pt >= 0, filled, qv)
        self.waiting[rows, cols] = False

    def values(self) -> np.ndarray:
        """``(len(at), n)`` once every piece is fed: gaps with no defined frame after them
        hold the last defined value; a column never defined is its fill."""
        rows, cols = np.nonzero(self.waiting)
        self.value[rows, cols] = self.prev_v[rows, cols]
        never = self.never
        self.value[:, never] = self.fills[never]
        return self.value

    @property
    def never(self) -> np.ndarray:
        """``(n,)`` bool: the columns no frame fed so far defines."""
        never: np.ndarray = self.last_t < 0
        return never
