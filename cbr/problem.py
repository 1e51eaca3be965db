"""The problem side of a case: the feature configuration and :func:`extract_problem`.

Fluent level: the per-frame confidences of the selected fluent states
(:func:`features.fluents.evaluate`), with NaN handled consistently, resampled to ``length``
frames: a ``(length, n_states)`` array. Euclidean compares it flattened; DTW and signatures
compare it as a sequence. QMP level: the QMP feature vector (:func:`features.qmp.qmp_features`),
binary by default (plain Euclidean then counts mismatched QMPs; with learned feature weights,
which ``CaseBaseClassifier``'s ``feature_weights="auto"`` mostly chooses, each mismatch counts
by its QMP's weight).

Options of the fluent level: ``angles`` adds the named joint angles of the state signals
(:func:`features.fluents.state_signals`, "left knee angle", divided by pi so they lie in [0, 1]
like the confidences) as further columns ``"angle:left_knee"``; ``summary`` describes the clip by
per-column statistics instead of the sequence: the mean (for a fluent state, about the share of
the clip it holds), the lowest and highest value and the standard deviation, a
``(4 * n_columns,)`` vector (statistic-major) for vector measures such as euclidean; with
``velocity`` the same four statistics of every column's rate of change follow (its change
from one resampled frame to the next, per clip length: a 2-s window's change per window).
:func:`mirrored` gives the left-right mirror image of a clip (for mirror-augmented case bases).

Which states are used is decided once, when the case base is built (:func:`resolve_config`):
states unavailable in too many training clips are dropped, and the explicit list is part of
the stored configuration, so every later clip is described by the same columns.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Literal

import numpy as np

from features.body import (
    ARM_PLANE_SIGNALS,
    arm_planes,
    body_positions,
    frame_rows,
    mirrored,
    moves_left_more,
    position_names,
    position_word,
    torso_rows,
)
from features.derived import fluents_of, qmp_of, signals_of
from features.errors import ConfigError, DataError
from features.fluents import state_columns
from features.poses import PoseSequence
from features.qmp import QMPFeatures
from features.signals import ANGLE_SIGNALS
from features.text import dataclass_line, did_you_mean

from . import long_clip

Level = Literal["fluents", "qmp"]
STATE_GROUPS = ("angles", "instantaneous", "all")
ANGLE_PREFIX = "angle:"
SUMMARY_STATS = ("mean", "min", "max", "std")
_STAT_WORDS = {"mean": "", "min": " (lowest)", "max": " (highest)", "std": " (variation)"}
RATE_PREFIX = "rate_"
"""The statistics of a column's rate of change are named ``@rate_mean``, ``@rate_min``, ..."""
# options added after the first stored case bases: left out of to_dict() while off, so the
# configuration hash of every existing case base stays the same
_LATER_OPTIONS = {
    "angles": False,
    "summary": False,
    "side": "as_recorded",
    "phases": 0,
    "positions": False,
    "velocity": False,
}
POSITION_PREFIX = "pos:"
SIDE_MODES = ("as_recorded", "canonical")
#: the longest resampled sequence (frames): far beyond any useful length, short of memory trouble
MAX_LENGTH = 4096


@dataclass(frozen=True, repr=False)  # its repr: one line
class FeatureConfig:
    """How a clip becomes a problem.

    level: ``"fluents"`` or ``"qmp"``.
    length: frames the fluent confidence sequence is resampled to (fluent level).
    states: a group (``"angles"``: angle fluents with their motion states, no near/touching
      pairs; ``"instantaneous"``: angle fluents without motion states; ``"all"``) or an explicit
      tuple of machine state names (``"left_leg_bent.bent"``); explicit after
      :func:`resolve_config`.
    min_available: at build time, keep a state when it is available (not all-NaN) in at least
      this fraction of the training clips.
    fill: confidence given to a selected state that is unavailable in a whole clip (a fill,
      not a measurement: left out of the clip's distances, :meth:`Problem.measured`).
    qmp_part: ``"binary"`` (detected / not) or ``"values"`` (scored QMPs) at the QMP level.
    angles: also use the named joint angles (``"angle:left_knee"`` columns, radians / pi).
    summary: per-column statistics (mean, lowest, highest, variation) instead of the sequence.
    phases: with ``summary``, also the mean of every column over each of this many equal
      stretches of the clip ("left knee angle (middle third)"); 0: none.
    positions: also use the positions of the limb joints in the person's own frame at the
      start of the clip (:func:`body_positions`: "left wrist height", in torso lengths).
    velocity: with ``summary``, also the statistics of every column's rate of change
      ("left knee angle rate of change (highest)"), before the phase means.
    side: ``"as_recorded"``, or ``"canonical"``: a clip that moves its left limbs more than its
      right ones is described by its mirror image (:func:`mirrored`), so a movement done with
      the left arm is compared with the right-arm cases (:func:`moves_left_more`).
    """

    level: Level = "fluents"
    length: int = 32
    states: str | tuple[str, ...] = "angles"
    min_available: float = 0.5
    fill: float = 0.0
    qmp_part: Literal["binary", "values"] = "binary"
    angles: bool = False
    summary: bool = False
    side: str = "as_recorded"
    phases: int = 0
    positions: bool = False
    velocity: bool = False

    def __repr__(self) -> str:
        """Its fields in one line, the states once resolved (:func:`resolve_config`: a hundred
        names and more) by their count (:func:`features.text.dataclass_line`: they ran to
        thousands of characters)."""
        return dataclass_line(self)

    def __post_init__(self) -> None:
        if self.level not in ("fluents", "qmp"):
            raise ConfigError(f"must be 'fluents' or 'qmp', got {self.level!r}", "features")
        if (
            isinstance(self.length, bool)
            or not isinstance(self.length, int | np.integer)
            or not 2 <= int(self.length) <= MAX_LENGTH
        ):
            raise ConfigError(
                f"must be a whole number of frames from 2 to {MAX_LENGTH}, got {self.length!r}",
                "length",
            )
        if isinstance(self.states, str):
            if self.states not in STATE_GROUPS:
                raise ConfigError(
                    f"must be one of {', '.join(STATE_GROUPS)} or a list of state names,"
                    f" got {self.states!r}{did_you_mean(self.states, STATE_GROUPS)}",
                    "states",
                )
        else:
            object.__setattr__(self, "states", tuple(str(s) for s in self.states))
        if not 0.0 <= float(self.min_available) <= 1.0:
            raise ConfigError(f"min_available must be in [0, 1], got {self.min_available!r}")
        if self.qmp_part not in ("binary", "values"):
            raise ConfigError(f"qmp_part must be 'binary' or 'values', got {self.qmp_part!r}")
        if not isinstance(self.phases, int | np.integer) or not 0 <= int(self.phases) <= int(
            self.length
        ):
            raise ConfigError(
                f"must be a whole number from 0 to length ({self.length}), got {self.phases!r}",
                "phases",
            )
        self._check_velocity()
        if self.side not in SIDE_MODES:
            raise ConfigError(f"must be one of {', '.join(SIDE_MODES)}, got {self.side!r}", "side")

    def _check_velocity(self) -> None:
        if not isinstance(self.velocity, bool | np.bool_):
            raise ConfigError(f"must be true or false, got {self.velocity!r}", "velocity")
        if self.velocity and not (self.summary and self.level == "fluents"):
            raise ConfigError(
                "rates of change need fluent-level clip summaries (summary=True)",
                "velocity",
            )

    @property
    def resolved(self) -> bool:
        return self.level == "qmp" or not isinstance(self.states, str)

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["states"] = self.states if isinstance(self.states, str) else list(self.states)
        for key, off in _LATER_OPTIONS.items():
            if d[key] == off:
                del d[key]
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> FeatureConfig:
        known = {f.name for f in dataclasses.fields(cls)}
        bad = sorted(set(d) - known)
        if bad:
            raise ConfigError(f"unknown feature configuration keys: {', '.join(bad)}", "features")
        d = dict(d)
        if isinstance(d.get("states"), list):
            d["states"] = tuple(d["states"])
        return cls(**d)

    def describe(self) -> str:
        side = ", left-side clips mirrored" if self.side == "canonical" else ""
        if self.level == "qmp":
            return f"qmp ({self.qmp_part}{side})"
        n = self.states if isinstance(self.states, str) else f"{len(self.states)} states"
        extra = (
            (" with joint angles" if self.angles else "")
            + (" and positions" if self.positions else "")
            + side
        )
        if self.summary:
            ph = f" and {self.phases} phases" if self.phases else ""
            rate = " with rates of change" if self.velocity else ""
            return f"fluents ({n}{extra}, summarised{rate} over {self.length} frames{ph})"
        return f"fluents ({n}{extra}, resampled to {self.length} frames)"


@dataclass(frozen=True, eq=False)
class Problem:
    """A case's problem: ``values`` ``(length, n_features)`` (fluent sequence) or
    ``(n_features,)`` (QMP vector); ``names`` machine names and ``words`` human words of the
    feature columns (so explanations can cite them); ``unseen``: the features (names before
    any ``@`` statistic) the clip never showed, whose values are fills, not measurements
    (explanations cite no value of them, and retrieval leaves them out of the distance:
    :meth:`measured`)."""

    values: np.ndarray
    names: tuple[str, ...]
    words: tuple[str, ...]
    level: Level
    mirrored: bool = False
    unseen: frozenset[str] = frozenset()

    def measured(self) -> np.ndarray | None:
        """``(values.size,)`` bool over the flattened values (a sequence frame after frame):
        False where the value is the fill of a feature the clip never showed (``unseen``);
        None when every value is measured, or none is (nothing to compare but the fills)."""
        if not self.unseen:
            return None
        cols = _measured_columns(self.names, self.unseen)
        if cols.all() or not cols.any():
            return None
        values = np.asarray(self.values)
        if values.ndim == 2 and values.shape[1] == len(cols):
            return np.tile(cols, values.shape[0])
        if values.size != len(cols):
            raise ConfigError(
                f"the problem has {values.size} values but {len(cols)} column names", "problem"
            )
        return cols


@lru_cache(maxsize=64)
def _measured_columns(names: tuple[str, ...], unseen: frozenset[str]) -> np.ndarray:
    """``(len(names),)`` bool, read-only: the columns ``names`` (``feature@statistic`` or
    ``feature``) whose feature is not ``unseen``. Kept per pair: a recording's windows that
    miss a column miss the same few."""
    cols = np.array([n.split("@", 1)[0] not in unseen for n in names], dtype=bool)
    cols.setflags(write=False)
    return cols


def warm(seq: PoseSequence, level: Level = "fluents", mirror: bool = True) -> None:
    """Compute and cache what :func:`extract_problem` needs for ``seq`` (and, with ``mirror``,
    for its mirror image), so a caller can show progress over the expensive part."""
    if mirror:
        moves_left_more(seq)
    for s in (seq, mirrored(seq)) if mirror else (seq,):
        if level == "qmp":
            qmp_of(s)
        else:
            fluents_of(s)
            signals_of(s)
            arm_planes(s)
            frame_rows(s)
            torso_rows(s)
            body_positions(s)


def _group_mask(state_names: Sequence[str], temporal: np.ndarray, group: str) -> np.ndarray:
    is_near = np.array([n.startswith("near:") for n in state_names])
    if group == "all":
        return np.ones(len(state_names), dtype=bool)
    if group == "angles":
        return ~is_near
    instantaneous: np.ndarray = ~is_near & ~np.asarray(temporal, dtype=bool)
    return instantaneous


def candidate_config(config: FeatureConfig) -> FeatureConfig:
    """``config`` with every column it may use: the fluent states of its group, the joint
    angles and arm planes (``angles``) and the positions (``positions``), before
    :func:`resolve_config` drops those unavailable in too many training clips. A resolved
    configuration is its own candidate set."""
    if config.resolved:
        return config
    state_names, _, temporal = state_columns()
    keep = _group_mask(state_names, temporal, str(config.states))
    names = tuple(n for n, k in zip(state_names, keep, strict=True) if k)
    if config.angles:
        names += tuple(ANGLE_PREFIX + a for a in ANGLE_SIGNALS)
        names += tuple(ANGLE_PREFIX + a for a in ARM_PLANE_SIGNALS)
    if config.positions:
        names += tuple(POSITION_PREFIX + n for n in position_names())
    return dataclasses.replace(config, states=names)


def check_state_names(states: Sequence[str]) -> None:
    """Refuse, naming ``states`` (the estimator's parameter), an explicit list of columns that
    is empty or names a column none has (a fluent state, ``angle:`` a joint angle or arm
    plane, ``pos:`` a joint position; :func:`candidate_config`'s names), before any clip is
    read: it was found only when the first clip was described, said of ``features`` as a
    stored case base's state the fluent table "no longer has"."""
    if len(states) == 0:
        raise ConfigError(
            f"must be one of {', '.join(STATE_GROUPS)} or a list of state names, got none",
            "states",
        )
    every = candidate_config(FeatureConfig(states="all", angles=True, positions=True)).states
    unknown = [s for s in states if s not in set(every)]
    if unknown:
        raise ConfigError(
            "no column of that name: "
            + ", ".join(repr(s) for s in unknown[:5])
            + did_you_mean(unknown[0], every),
            "states",
        )


def availability(
    seq: PoseSequence, candidates: FeatureConfig, chunk_frames: int | None = None
) -> np.ndarray:
    """``(n_columns,)`` bool: which columns of ``candidates`` (:func:`candidate_config`) the
    clip ``seq`` ``(frames, joints, 3)`` has (a fluent state or angle defined in some frame; the
    arm planes whenever the arm joints are there at all). ``chunk_frames`` as for
    :func:`extract_problem`: a long clip is looked at a piece at a time."""
    states = tuple(candidates.states)
    chunk = long_clip.chunk_for(seq, chunk_frames)
    if chunk:
        return long_clip.availability(seq, states, chunk)
    fluent, angles, positions = column_kinds(states)
    res = fluents_of(seq) if fluent.any() else None
    sig = signals_of(seq) if angles.any() else None
    return defined_columns(
        states,
        (res.confidence, res.state_names) if res is not None else None,
        (sig.values[:, : len(sig.angle_names)], sig.angle_names) if sig is not None else None,
        body_positions(seq) if positions.any() else None,
    )


def column_kinds(states: Sequence[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which of the columns ``states`` are fluent states, joint angles and positions, ``(n,)``
    bool each."""
    angles = np.array([n.startswith(ANGLE_PREFIX) for n in states], dtype=bool)
    positions = np.array([n.startswith(POSITION_PREFIX) for n in states], dtype=bool)
    return ~angles & ~positions, angles, positions


def defined_columns(
    states: Sequence[str],
    fluents: tuple[np.ndarray, Sequence[str]] | None,
    angles: tuple[np.ndarray, Sequence[str]] | None,
    positions: np.ndarray | None,
) -> np.ndarray:
    """``(n_columns,)`` bool: which columns ``states`` are defined in some frame of the fluent
    confidences ``(frames, n_states)`` with their state names, the joint angles
    ``(frames, n_angles)`` with their names and the body positions ``(frames, n_position
    columns)`` of a clip (or of a piece of it: a clip has a column when a piece has it). Each
    is None when no column needs it."""
    out = np.zeros(len(states), dtype=bool)
    kinds = column_kinds(states)
    fluent, ang, pos = (np.flatnonzero(k).tolist() for k in kinds)
    if len(fluent) and fluents is not None:
        index = {n: i for i, n in enumerate(fluents[1])}
        defined = ~np.all(np.isnan(fluents[0]), axis=0)
        out[fluent] = defined[[index[states[i]] for i in fluent]]
    if len(ang) and angles is not None:
        values, names = angles
        seen = dict(zip(names, ~np.all(np.isnan(values), axis=0), strict=True))
        arms = bool(np.isfinite(values[:, :4]).any())
        for i in ang:
            a = states[i][len(ANGLE_PREFIX) :]
            out[i] = arms if a in ARM_PLANE_SIGNALS else bool(seen.get(a, False))
    if len(pos) and positions is not None:
        seen_pos = dict(zip(position_names(), ~np.all(np.isnan(positions), axis=0),
                            strict=True))  # fmt: skip
        out[pos] = [bool(seen_pos[states[i][len(POSITION_PREFIX) :]]) for i in pos]
    return out


def resolve_counts(config: FeatureConfig, available: np.ndarray, n_clips: int) -> FeatureConfig:
    """The resolved configuration from ``available`` ``(n_columns,)``: in how many of the
    ``n_clips`` training clips each column of :func:`candidate_config` is available."""
    if config.resolved:
        return config
    if n_clips == 0:
        raise DataError("no training clips to choose the fluent states from", "training set")
    candidates = tuple(candidate_config(config).states)
    keep = np.asarray(available) >= config.min_available * n_clips
    fluent = np.array([not n.startswith((ANGLE_PREFIX, POSITION_PREFIX)) for n in candidates])
    if not (keep & fluent).any():
        raise DataError(
            "no fluent state is available in enough training clips (are the skeletons empty?)",
            "training set",
        )
    return dataclasses.replace(
        config, states=tuple(n for n, k in zip(candidates, keep, strict=True) if k)
    )


def resolve_config(config: FeatureConfig, clips: Sequence[PoseSequence]) -> FeatureConfig:
    """The configuration with an explicit state list, chosen from the training ``clips``."""
    if config.resolved:
        return config
    candidates = candidate_config(config)
    counts = np.zeros(len(candidates.states), dtype=np.int64)
    for seq in clips:
        counts += availability(seq, candidates)
    return resolve_counts(config, counts, len(clips))


def column_index(config: FeatureConfig, candidates: FeatureConfig) -> np.ndarray:
    """Where the problem values of resolved ``config`` lie in those of ``candidates`` (its
    :func:`candidate_config`), along the last axis: a clip described once over the candidate
    columns gives its problem under ``config`` as ``values[..., column_index(...)]``."""
    position = {n: i for i, n in enumerate(candidates.states)}
    cols = np.array([position[n] for n in config.states], dtype=np.intp)
    if not config.summary:
        return cols
    n = len(candidates.states)
    blocks = len(SUMMARY_STATS) * (2 if config.velocity else 1) + int(config.phases)
    return np.concatenate([b * n + cols for b in range(blocks)])


def fill_nan_time(x: np.ndarray, fill: float | np.ndarray) -> np.ndarray:
    """Fill NaN along time (axis 0) of ``(frames, n)`` by linear interpolation, holding the
    edge values; a column NaN in every frame becomes ``fill`` (one value, or ``(n,)``: one a
    column)."""
    x = np.array(x, dtype=np.float64, copy=True)
    nan = np.isnan(x)
    if not nan.any():
        return x
    gappy = nan.any(axis=0)
    fills = np.broadcast_to(np.asarray(fill, dtype=np.float64), (x.shape[1],))[gappy]
    x[:, gappy] = _filled(x[:, gappy], ~nan[:, gappy], fills)
    return x


def _filled(x: np.ndarray, ok: np.ndarray, fills: np.ndarray) -> np.ndarray:
    """:func:`fill_nan_time` of the columns ``x`` ``(frames, n)`` that have a gap (``ok``:
    where they have a value; ``fills`` ``(n,)``), all at once, as ``np.interp`` fills each."""
    frames, cols = x.shape
    t = np.arange(frames)[:, None]
    # every frame's last valid frame at or before it and first at or after it; before the
    # first valid frame and after the last, that one (the edge value held)
    before = np.maximum.accumulate(np.where(ok, t, -1), axis=0)
    after = np.minimum.accumulate(np.where(ok, t, frames)[::-1], axis=0)[::-1]
    first, last = ok.argmax(axis=0), frames - 1 - ok[::-1].argmax(axis=0)
    lo = np.where(before < 0, first, before)
    hi = np.where(after >= frames, last, after)
    at = np.arange(cols)
    y_lo, y_hi = x[lo, at], x[hi, at]
    # np.interp's arithmetic: the slope between the valid frames around, from the lower one
    gap = np.where(hi > lo, hi - lo, 1).astype(np.float64)
    inside = np.where(hi > lo, (y_hi - y_lo) / gap * (t - lo) + y_lo, y_lo)
    out = np.where(ok, x, inside)
    empty = ~ok.any(axis=0)
    out[:, empty] = fills[empty]
    return out


def resample(x: np.ndarray, length: int) -> np.ndarray:
    """Linear resampling of ``(frames, n)`` to ``(length, n)`` over normalised time."""
    frames = x.shape[0]
    if frames == 1:
        return np.repeat(x, length, axis=0)
    i, w = resample_points(frames, length)
    out: np.ndarray = x[i] * (1.0 - w) + x[i + 1] * w
    return out


@lru_cache(maxsize=256)
def resample_points(frames: int, length: int) -> tuple[np.ndarray, np.ndarray]:
    """Where :func:`resample` reads a clip of ``frames`` (at least 2) frames: output row ``r``
    is ``x[i[r]] * (1 - w[r]) + x[i[r] + 1] * w[r]``; ``i`` ``(length,)``, ``w``
    ``(length, 1)``. Kept per size (read-only): a recording's windows share a few sizes."""
    src = np.linspace(0.0, 1.0, frames)
    dst = np.linspace(0.0, 1.0, length)
    i = np.clip(np.searchsorted(src, dst, side="right") - 1, 0, frames - 2)
    w = ((dst - src[i]) / (src[i + 1] - src[i]))[:, None]
    i.setflags(write=False)
    w.setflags(write=False)
    return i, w


@dataclass(frozen=True)
class _ColumnPlan:
    """Where a configuration's columns come from (the same for every clip, so worked out
    once): fluent state columns, the angle and position columns, the words of them all."""

    fluent_cols: np.ndarray
    angle_states: tuple[str, ...]
    arm_planes: bool
    position_cols: np.ndarray
    words: tuple[str, ...]


@lru_cache(maxsize=32)
def _column_plan(
    states: tuple[str, ...], state_names: tuple[str, ...], state_words: tuple[str, ...]
) -> _ColumnPlan:
    index = {n: i for i, n in enumerate(state_names)}
    fluent_states = [s for s in states if not s.startswith((ANGLE_PREFIX, POSITION_PREFIX))]
    angle_states = tuple(s[len(ANGLE_PREFIX) :] for s in states if s.startswith(ANGLE_PREFIX))
    position_states = [s[len(POSITION_PREFIX) :] for s in states if s.startswith(POSITION_PREFIX)]
    missing = [s for s in fluent_states if s not in index]
    if missing:
        raise ConfigError(
            "the fluent table no longer has states " + ", ".join(missing[:5]), "features"
        )
    pos_index = {n: i for i, n in enumerate(position_names())}
    unknown = [n for n in position_states if n not in pos_index]
    if unknown:
        raise ConfigError("no joint position " + ", ".join(unknown[:5]), "features")
    cols = np.array([index[s] for s in fluent_states], dtype=np.int64)
    words = [state_words[i] for i in cols]
    words += [a.replace("_", " ") + " angle" for a in angle_states]
    words += [position_word(n) for n in position_states]
    return _ColumnPlan(
        cols,
        angle_states,
        any(a in ARM_PLANE_SIGNALS for a in angle_states),
        np.array([pos_index[n] for n in position_states], dtype=np.int64),
        tuple(words),
    )


@lru_cache(maxsize=32)
def _signal_cols(angle_states: tuple[str, ...], signal_names: tuple[str, ...]) -> tuple[int, ...]:
    """Column of every angle in the state signals (-1 for the arm planes, kept elsewhere)."""
    sig_index = {n: i for i, n in enumerate(signal_names)}
    unknown = [a for a in angle_states if a not in sig_index and a not in ARM_PLANE_SIGNALS]
    if unknown:
        raise ConfigError("no state signal " + ", ".join(unknown[:5]), "features")
    return tuple(sig_index.get(a, -1) for a in angle_states)


def extract_problem(
    seq: PoseSequence, config: FeatureConfig, chunk_frames: int | None = None
) -> Problem:
    """The problem representation of one clip under a resolved ``config``.

    seq: a pose sequence ``(frames, joints, 3)``. Returns a :class:`Problem` whose values are
    ``(config.length, n_states)`` in [0, 1] (fluents) or ``(n_features,)`` (QMP). With
    ``config.side == "canonical"`` a clip that moves its left side more is described by its
    mirror image (``Problem.mirrored`` is then True). ``chunk_frames``: compute the fluent
    columns (the QMP state signals and fit) that many frames at a time (:mod:`cbr.long_clip`;
    the same values in bounded memory), 0 the whole clip at once; None: pieces for a clip
    longer than :data:`cbr.long_clip.CHUNK_FRAMES` whose fluents (QMPs) are not computed yet.
    """
    chunk = long_clip.chunk_for(seq, chunk_frames, "qmp" if config.level == "qmp" else "fluents")
    mirror = config.side == "canonical" and (
        long_clip.moves_left_more(seq, chunk) if chunk else moves_left_more(seq)
    )
    if config.level == "qmp":
        q = (
            long_clip.qmp_features(seq, chunk, mirror)
            if chunk
            else qmp_of(mirrored(seq) if mirror else seq)
        )
        problem = _qmp_problem(q, config)
    elif chunk:
        problem = _fluent_problem(seq, config, chunk, mirror)
    else:
        problem = _fluent_problem(mirrored(seq) if mirror else seq, config, 0, False)
    return dataclasses.replace(problem, mirrored=True) if mirror else problem


def mirror_problem(
    seq: PoseSequence, config: FeatureConfig, chunk_frames: int | None = None
) -> Problem:
    """``extract_problem(mirrored(seq), config)`` under an as-recorded ``config``: the problem
    of the clip's mirror image, for a long clip computed a piece at a time from mirrored
    pieces (the mirror image of the whole clip is never held)."""
    if config.side != "as_recorded":
        raise ConfigError("the mirror image's problem is taken as recorded", "side")
    chunk = long_clip.chunk_for(seq, chunk_frames, "qmp" if config.level == "qmp" else "fluents")
    if not chunk:
        return extract_problem(mirrored(seq), config, 0)
    if config.level == "qmp":
        return _qmp_problem(long_clip.qmp_features(seq, chunk, True), config)
    return _fluent_problem(seq, config, chunk, True)


def _qmp_problem(q: QMPFeatures, config: FeatureConfig) -> Problem:
    """The QMP-level problem from a clip's QMP features ``q``."""
    if config.qmp_part == "binary":
        tested = q.values[: len(q.binary_names)]
        return Problem(
            np.asarray(q.binary, dtype=np.float64),
            tuple(q.binary_names),
            tuple(str(n).replace("_", " ") for n in q.binary_names),
            "qmp",
            unseen=frozenset(
                str(n) for n, v in zip(q.binary_names, tested, strict=True) if np.isnan(v)
            ),
        )
    # parameters not observable in this clip (NaN) get the configured fill value (unseen:
    # left out of its distances)
    raw = np.asarray(q.values, dtype=np.float64)
    vals = np.nan_to_num(raw, nan=float(config.fill))
    unseen = frozenset(str(n) for n, v in zip(q.names, raw, strict=True) if np.isnan(v))
    words = tuple(str(n).replace("_", " ") for n in q.names)
    return Problem(vals, tuple(q.names), words, "qmp", unseen=unseen)


def _fluent_problem(seq: PoseSequence, config: FeatureConfig, chunk: int, mirror: bool) -> Problem:
    """The fluent-level problem of ``seq`` (of its mirror image with ``mirror``, which only
    the piecewise path takes: the whole-clip path is given the mirrored clip), computed
    ``chunk`` frames at a time (0: at once)."""
    if not config.resolved:
        raise ConfigError(
            "the feature configuration has no explicit state list yet (call resolve_config "
            "with the training clips first)",
            "features",
        )
    states = tuple(config.states)
    if not states:
        raise ConfigError("the feature configuration selects no columns", "features")
    names, words, _ = state_columns()
    plan = _column_plan(states, names, words)
    fills = _column_fills(plan, float(config.fill))
    if chunk:
        values, never = long_clip.resampled_columns(
            seq, plan, fills, int(config.length), chunk, mirror
        )
    else:
        planes = arm_planes(seq) if plan.arm_planes else None
        positions = body_positions(seq) if len(plan.position_cols) else None
        sig = signals_of(seq) if plan.angle_states else None
        columns = raw_columns(
            plan,
            fluents_of(seq).confidence,
            sig.names if sig is not None else (),
            sig.values if sig is not None else None,
            planes,
            positions,
        )
        values = resample(fill_nan_time(columns, fills), int(config.length))
        never = np.isnan(columns).all(axis=0) if len(columns) else np.zeros(len(states), bool)
    unseen = frozenset(s for s, n in zip(states, never, strict=True) if n)
    if config.summary:
        problem = summarise(values, states, plan.words, int(config.phases), bool(config.velocity))
        return dataclasses.replace(problem, unseen=unseen)
    return Problem(values, states, plan.words, "fluents", unseen=unseen)


def _column_fills(plan: _ColumnPlan, fill: float) -> np.ndarray:
    """``(n_columns,)`` the value of each column in a clip that never has it: ``fill`` for a
    fluent state, 90 degrees (0.5) for an angle, 0 for a position."""
    return np.concatenate([
        np.full(len(plan.fluent_cols), fill),
        np.full(len(plan.angle_states), 0.5),
        np.zeros(len(plan.position_cols)),
    ])  # fmt: skip


def raw_columns(
    plan: _ColumnPlan,
    confidence: np.ndarray,
    signal_names: tuple[str, ...],
    signals: np.ndarray | None,
    planes: np.ndarray | None,
    positions: np.ndarray | None,
) -> np.ndarray:
    """The columns of ``plan`` ``(frames, n_columns)``, gaps not filled yet, from a clip's (or
    a piece's) fluent ``confidence`` ``(frames, n_states)``, state ``signals``
    ``(frames, n_signals)`` named ``signal_names``, arm ``planes`` ``(frames, 2)`` and body
    ``positions`` ``(frames, 3 * n_joints)`` (each None when the plan uses none of it)."""
    blocks = [confidence[:, plan.fluent_cols]]
    if plan.angle_states:
        assert signals is not None
        ang_cols = [
            planes[:, ARM_PLANE_SIGNALS.index(a)]
            if planes is not None and a in ARM_PLANE_SIGNALS
            else signals[:, i]
            for a, i in zip(
                plan.angle_states, _signal_cols(plan.angle_states, signal_names), strict=True
            )
        ]
        # radians / pi: in [0, 1] like the confidences
        blocks.append(np.stack(ang_cols, axis=1) / np.pi)
    if len(plan.position_cols):
        assert positions is not None
        blocks.append(positions[:, plan.position_cols])
    return np.concatenate(blocks, axis=1) if len(blocks) > 1 else blocks[0]


def phase_words(phases: int) -> tuple[str, ...]:
    """How the ``phases`` stretches of a clip are named in explanations."""
    if phases == 3:
        return ("first third", "middle third", "last third")
    if phases == 2:
        return ("first half", "second half")
    return tuple(f"phase {i + 1} of {phases}" for i in range(phases))


@lru_cache(maxsize=64)
def summary_columns(
    names: tuple[str, ...], words: tuple[str, ...], phases: int = 0, velocity: bool = False
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Names and words of the columns :func:`summarise` gives (the same for every clip of a
    case base, so built once)."""
    out_names = [f"{n}@{st}" for st in SUMMARY_STATS for n in names]
    # a fluent's lowest/highest value is a confidence; an angle's (position's) is the value itself
    out_words = [
        f"{w}{_STAT_WORDS[st]}"
        if st in ("mean", "std") or n.startswith((ANGLE_PREFIX, POSITION_PREFIX))
        else f"{w}{_STAT_WORDS[st][:-1]} confidence)"
        for st in SUMMARY_STATS
        for n, w in zip(names, words, strict=True)
    ]
    if velocity:
        out_names += [f"{n}@{RATE_PREFIX}{st}" for st in SUMMARY_STATS for n in names]
        out_words += [
            f"{w} rate of change{_STAT_WORDS[st] or ' (mean)'}"
            for st in SUMMARY_STATS
            for w in words
        ]
    for i, said in enumerate(phase_words(phases) if phases else ()):
        out_names += [f"{n}@phase{i + 1}" for n in names]
        out_words += [f"{w} ({said})" for w in words]
    return tuple(out_names), tuple(out_words)


def summarise(
    values: np.ndarray,
    names: tuple[str, ...],
    words: tuple[str, ...],
    phases: int = 0,
    velocity: bool = False,
) -> Problem:
    """Per-column statistics of a ``(frames, n)`` sequence: a ``(4 * n,)`` vector, statistic-
    major (all means, then lowest, highest, standard deviation); with ``velocity`` the same
    four of the rate of change ``(frames - 1) * diff(values)`` (the change per clip length of
    each step of the resampled frames; ``4 * n`` more, ``@rate_mean``...); then with ``phases``
    > 0 the mean over each of that many equal stretches of the frames (``phases * n`` more).
    Column names get ``@mean``, ``@min``, ..., ``@phase1``...; the words of the means are the
    plain feature words (for a fluent state the mean confidence is about the share of the clip
    it holds)."""
    stats = [values.mean(axis=0), values.min(axis=0), values.max(axis=0), values.std(axis=0)]
    if velocity:
        if len(values) < 2:
            raise DataError("a rate of change needs at least two frames", "velocity")
        rate = np.diff(values, axis=0) * (len(values) - 1)
        stats += [rate.mean(axis=0), rate.min(axis=0), rate.max(axis=0), rate.std(axis=0)]
    stats += (
        [part.mean(axis=0) for part in np.array_split(values, phases, axis=0)] if phases else []
    )
    out_names, out_words = summary_columns(names, words, phases, velocity)
    return Problem(np.concatenate(stats), out_names, out_words, "fluents")


def problem_columns(config: FeatureConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Names and words of the columns :func:`extract_problem` gives under a resolved
    fluent-level ``config`` (known without a clip)."""
    if not config.resolved or config.level != "fluents":
        raise ConfigError("problem columns need a resolved fluent-level configuration", "features")
    states = tuple(config.states)
    names, words, _ = state_columns()
    plan_words = _column_plan(states, tuple(names), tuple(words)).words
    if config.summary:
        return summary_columns(states, plan_words, int(config.phases), bool(config.velocity))
    return states, plan_words
