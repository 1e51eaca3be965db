"""DAD's detection: QMPs fitted over sliding windows, checked against the ADD, and every
activity scored by the weighted share of its QMPs met in order (paper section "DAD").

DAD needs no training data. Over sliding windows it fits QMPs to the state signals, detects
every ADD criterion that holds (several may hold at once), and scores each ADD activity by the
weighted ratio of its QMPs detected *in order*: the heaviest subsequence of the activity's QMPs
whose detections fall in non-decreasing windows (QMPs in the same window satisfy any order).
Activities are ranked by that ratio (ties: more matched weight first), and for each one DAD
lists which QMPs were executed as expected and which were not, with the reason.

A QMP whose signals are unavailable in the clip (e.g. no heels on a Kinect skeleton) is listed
as "not observable" and left out of that activity's ratio, rather than counted as failed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import ConfigError
from features.fluents import Backend, state_signals
from features.poses import PoseSequence, expect_sequence
from features.qmp import QMPConfig, fit_signals, sliding_windows
from features.qmp.add import ADD, Activity, CriteriaResult, evaluate_criteria, load_add
from features.text import percent
from features.values import is_number

from .matching import ordered_match
from .outcome import NOT_ENOUGH_DATA, ActivityScore, DADResult, QMPOutcome

DEFAULT_STEP_S = 1.0
"""How far apart DAD's windows start, unless the window is shorter: then end to end."""


def default_step(window_s: float) -> float:
    """The step of windows ``window_s`` long when none is given: :data:`DEFAULT_STEP_S`, or
    the window's length when that is shorter (no part of a clip between two windows; a
    ``window_s`` that is no length: :data:`DEFAULT_STEP_S`, for :class:`DADConfig` to refuse
    the length)."""
    return min(DEFAULT_STEP_S, window_s) if _positive(window_s) else DEFAULT_STEP_S


def _positive(value: Any) -> bool:
    """Whether ``value`` is a finite number > 0 (a bool is no length of time)."""
    return is_number(value) and math.isfinite(float(value)) and float(value) > 0


@dataclass(frozen=True)
class DADConfig:
    """Windowing of DAD: ``window_s`` long windows every ``step_s``; a clip shorter than one
    window is judged as a single window if it lasts at least ``min_duration_s``."""

    window_s: float = 4.0
    step_s: float = DEFAULT_STEP_S
    min_duration_s: float = 0.5
    qmp: QMPConfig = field(default_factory=QMPConfig)
    min_observable_share: float = 0.5
    """An activity is scored only when at least this share of its QMPs' weight is observable
    (on a whole skeleton every shipped activity has far more: docs/measurements.md, "Figures
    behind the code's rules: Observable QMPs"; a clip with a knee missing throughout would
    otherwise crown a kick from its arms alone)."""

    def __post_init__(self) -> None:
        for name in ("window_s", "step_s", "min_duration_s"):
            v = getattr(self, name)
            if not _positive(v):
                raise ConfigError(f"{name} must be a number > 0, got {v!r}", "DAD")
        share = self.min_observable_share
        if not (_positive(share) and float(share) <= 1.0):
            raise ConfigError(f"min_observable_share must be in (0, 1], got {share!r}", "DAD")
        if self.step_s > self.window_s:
            raise ConfigError(
                f"step_s ({self.step_s:g} s) is longer than window_s ({self.window_s:g} s): "
                "the clip between two windows would be judged by none",
                "DAD",
            )


def _step_outcome(
    qmp: str,
    words: str,
    weight: int,
    observable: bool,
    window: int | None,
    seen: bool,
    reasons: tuple[str, ...],
    windows_s: np.ndarray,
) -> QMPOutcome:
    """One step's outcome from where (if anywhere) the in-order chain placed it."""
    if not observable:
        return QMPOutcome(qmp, words, weight, "not observable")
    if window is not None:
        span = (float(windows_s[window, 0]), float(windows_s[window, 1]))
        return QMPOutcome(qmp, words, weight, "met", span)
    if seen:
        why = ("detected, but not in the expected order",)
        return QMPOutcome(qmp, words, weight, "out of order", reasons=why)
    # The reasons come from the window where the QMP came closest.
    return QMPOutcome(qmp, words, weight, "not met", reasons=reasons)


def _score_activity(
    act: Activity, add: ADD, crit: CriteriaResult, windows_s: np.ndarray, min_share: float = 0.5
) -> ActivityScore:
    """Score ``act``: its observable steps chained in order over the windows ``(W, 2)``; NaN
    when less than ``min_share`` of its weight is observable."""
    q_index = {n: i for i, n in enumerate(crit.names)}
    cols = [q_index[step.qmp] for step in act.sequence]
    weights = np.array([step.weight for step in act.sequence])
    observable = np.asarray(crit.observable[:, cols].any(axis=0))  # (steps,)
    met = (crit.met[:, cols] & crit.observable[:, cols]).T  # (steps, W)
    matched, chosen = ordered_match(met[observable], weights[observable])
    window: list[int | None] = [None] * len(cols)
    for j, w in zip(np.flatnonzero(observable).tolist(), chosen, strict=True):
        window[j] = w
    outcomes = tuple(
        _step_outcome(
            step.qmp,
            add.criteria[step.qmp].words,
            step.weight,
            bool(observable[j]),
            window[j],
            bool(met[j].any()),
            crit.failed[cols[j]],
            windows_s,
        )
        for j, step in enumerate(act.sequence)
    )
    obs_weight = int(weights[observable].sum())
    total = int(weights.sum())
    judged = obs_weight > 0 and obs_weight >= min_share * total
    score = matched / obs_weight if judged else float("nan")
    return ActivityScore(
        act.name, act.words, act.labels, float(score), int(matched), obs_weight, outcomes, total
    )


def _rank_key(a: ActivityScore) -> tuple[float, int, str]:
    score = a.score if np.isfinite(a.score) else -1.0
    return (-score, -a.met_weight, a.activity)


def detect(
    seq: PoseSequence,
    add: ADD | str | Path | None = None,
    config: DADConfig | None = None,
    backend: Backend = "numba",
) -> DADResult:
    """Run DAD on one pose sequence ``(frames, joints, 3)``; see :class:`DADResult`.

    add: a loaded :class:`ADD`, a path to an ADD file, or None for the shipped database.
    backend: how the state signals are computed (:func:`features.signals.state_signals`):
    numba's compiled pass (the default) or the numpy reference, which a short clip in a new
    process gets sooner than numba loads its kernels (the same signals within 1e-15).
    """
    expect_sequence(seq)
    cfg = config or DADConfig()
    db = add if isinstance(add, ADD) else load_add(add)
    duration = seq.positions.shape[0] / seq.fps
    if duration < cfg.min_duration_s:
        return _unjudged(seq.source, seq.fps, duration, db, _too_short(duration, cfg))
    # the ADD's QMPs are written for the whole body: a clip without hips is not read in
    # the upright frame of its shoulders (an arms-hanging sneak crowned from the arms)
    signals = state_signals(seq, backend=backend, shoulders=False)
    return detect_signals(signals.values, signals.names, seq.fps, db, cfg, source=seq.source)


def _too_short(duration: float, cfg: DADConfig) -> str:
    return f"clip lasts {duration:.2f} s; DAD needs at least {cfg.min_duration_s:g} s"


def _too_few_frames(n_frames: int, fps: float, cfg: DADConfig) -> str:
    """Why the windows of a clip of ``n_frames`` at ``fps`` are too short to fit QMPs in (a
    5-fps video's 2-s window is 10 frames; the fit needs 12), or "" when they are not."""
    windows = sliding_windows(n_frames, fps, cfg.window_s, cfg.step_s)
    frames = int(windows[0, 1] - windows[0, 0])
    need = cfg.qmp.min_frames(fps)
    if frames >= need:
        return ""
    what = (
        f"the clip is {frames} frames"
        if len(windows) == 1 and frames == n_frames
        else f"a window of {cfg.window_s:g} s is {frames} frames"
    )
    return (
        f"{what} at {fps:g} fps; fitting QMPs needs at least {need} frames "
        f"({need / fps:.2g} s at this rate)"
    )


def _unjudged(
    source: str,
    fps: float,
    duration: float,
    db: ADD,
    message: str,
    windows_s: tuple[tuple[float, float], ...] = (),
    detected: tuple[tuple[str, ...], ...] = (),
) -> DADResult:
    """The answer for a clip DAD cannot judge ("not enough data", with ``message``)."""
    words = {n: c.words for n, c in db.criteria.items()}
    return DADResult(
        source, NOT_ENOUGH_DATA, message, fps, duration, windows_s, detected, (), db.source, words
    )


def detect_signals(
    values: np.ndarray,
    names: Sequence[str],
    fps: float,
    add: ADD | str | Path | None = None,
    config: DADConfig | None = None,
    source: str = "",
) -> DADResult:
    """DAD on precomputed state signals: values ``(frames, len(names))`` (see
    :func:`features.fluents.state_signals`)."""
    cfg = config or DADConfig()
    db = add if isinstance(add, ADD) else load_add(add)
    duration = values.shape[0] / fps
    if duration < cfg.min_duration_s:
        return _unjudged(source, fps, duration, db, _too_short(duration, cfg))
    short = _too_few_frames(values.shape[0], fps, cfg)
    if short:  # every window would be "not enough data", as if joints were missing
        return _unjudged(source, fps, duration, db, short)
    used = db.signals
    names = list(names)
    missing = [s for s in used if s not in names]
    if missing:
        raise ConfigError(f"state signals lack {missing}", db.source)
    cols = [names.index(s) for s in used]
    fits = fit_signals(
        np.asarray(values, dtype=np.float64)[:, cols],
        fps,
        used,
        config=cfg.qmp,
        window_s=cfg.window_s,
        step_s=cfg.step_s,
    )
    windows_s = fits.windows / fps
    crit = evaluate_criteria(db, fits)
    spans = tuple((float(a), float(b)) for a, b in windows_s)
    detected = tuple(
        tuple(n for n, m in zip(crit.names, row, strict=True) if m) for row in crit.met
    )
    if not crit.observable.any():
        why = "no QMP could be observed (joints missing, or gaps too long)"
        return _unjudged(source, fps, duration, db, why, spans, detected)
    share = cfg.min_observable_share
    scores = [_score_activity(a, db, crit, windows_s, share) for a in db.activities.values()]
    if not any(s.observable_weight for s in scores):  # QMPs seen, but none an activity uses
        why = "no activity's QMPs could be observed (joints missing, or gaps too long)"
        return _unjudged(source, fps, duration, db, why, spans, detected)
    if not any(np.isfinite(s.score) for s in scores):  # each seen too little to judge
        why = (
            f"no activity has {percent(share, 0)} of its QMPs' weight observable (joints missing, "
            "or gaps too long)"
        )
        return _unjudged(source, fps, duration, db, why, spans, detected)
    ranked = tuple(sorted(scores, key=_rank_key))
    words = {n: c.words for n, c in db.criteria.items()}
    return DADResult(source, "ok", "", fps, duration, spans, detected, ranked, db.source, words)
