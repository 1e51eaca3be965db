"""Dynamic Action Detection (DAD): the expert-system baseline (paper section "DAD").

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

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.validation import check_is_fitted

from features.errors import ConfigError
from features.fluents import state_signals
from features.poses import PoseSequence
from features.qmp import QMPConfig, fit_signals
from features.qmp.add import ADD, Activity, CriteriaResult, evaluate_criteria, load_add

NOT_ENOUGH_DATA = "not enough data"


@dataclass(frozen=True)
class QMPOutcome:
    """One step of an activity: met in order, seen but out of order, not met, or not
    observable. ``window_s``: [start, end] seconds of the window that satisfied it (met)."""

    qmp: str
    words: str
    weight: int
    status: str  # "met" | "out of order" | "not met" | "not observable"
    window_s: tuple[float, float] | None = None
    reasons: tuple[str, ...] = ()

    @property
    def met(self) -> bool:
        return self.status == "met"


@dataclass(frozen=True)
class ActivityScore:
    """An activity's score (weighted ratio of its QMPs met in order; NaN if none observable)."""

    activity: str
    words: str
    labels: tuple[str, ...]
    score: float
    met_weight: int
    observable_weight: int
    qmps: tuple[QMPOutcome, ...]

    @property
    def met(self) -> tuple[QMPOutcome, ...]:
        return tuple(q for q in self.qmps if q.met)

    @property
    def not_met(self) -> tuple[QMPOutcome, ...]:
        return tuple(q for q in self.qmps if q.status in ("not met", "out of order"))


@dataclass(frozen=True)
class DADResult:
    """DAD's answer for one clip.

    status: "ok" or "not enough data" (then ``activities`` is empty and ``message`` says why);
    windows_s ``(W, 2)`` seconds; detected: per window, the QMP names that held; activities:
    ranked best first.
    """

    source: str
    status: str
    message: str
    fps: float
    duration_s: float
    windows_s: tuple[tuple[float, float], ...]
    detected: tuple[tuple[str, ...], ...]
    activities: tuple[ActivityScore, ...]
    add_source: str = ""
    qmp_words: dict[str, str] = field(default_factory=dict)

    @property
    def best(self) -> ActivityScore | None:
        return self.activities[0] if self.activities else None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (NaN scores become None)."""
        out = asdict(self)
        for act in out["activities"]:
            if not np.isfinite(act["score"]):
                act["score"] = None
        return out


@dataclass(frozen=True)
class DADConfig:
    """Windowing of DAD: ``window_s`` long windows every ``step_s``; a clip shorter than one
    window is judged as a single window if it lasts at least ``min_duration_s``."""

    window_s: float = 4.0
    step_s: float = 1.0
    min_duration_s: float = 0.5
    qmp: QMPConfig = field(default_factory=QMPConfig)

    def __post_init__(self) -> None:
        for name in ("window_s", "step_s", "min_duration_s"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(f"{name} must be > 0, got {v!r}", "DAD")


def ordered_match(
    met: np.ndarray, weights: Sequence[int] | np.ndarray
) -> tuple[int, list[int | None]]:
    """Heaviest in-order subsequence of steps whose detections fall in non-decreasing windows.

    met: ``(steps, W)`` bool, step i detected in window w; weights: ``(steps,)``. Returns
    (matched weight, the window chosen for each step or None). Dynamic programme: f_i[w] is
    the heaviest chain over steps < i whose last window is <= w; QMPs in the same window may
    chain (several QMPs hold at once).
    """
    n_steps, n_win = met.shape
    f = [np.zeros(n_win, dtype=np.int64)]
    for i in range(n_steps):
        take = f[i] + np.where(met[i], int(weights[i]), 0)
        f.append(np.maximum.accumulate(np.maximum(f[i], take)))
    chosen: list[int | None] = [None] * n_steps
    if n_win == 0:
        return 0, chosen
    limit = n_win - 1
    total = int(f[n_steps][limit])
    target = total
    for i in range(n_steps - 1, -1, -1):
        # Take step i at the latest window <= limit that realises the target, if any.
        ok = np.flatnonzero(met[i, : limit + 1] & (f[i][: limit + 1] + int(weights[i]) == target))
        if len(ok):
            w = int(ok[-1])
            chosen[i] = w
            target -= int(weights[i])
            limit = w
    return total, chosen


def _score_activity(
    act: Activity, add: ADD, crit: CriteriaResult, windows_s: np.ndarray
) -> ActivityScore:
    q_index = {n: i for i, n in enumerate(crit.names)}
    cols = [q_index[step.qmp] for step in act.sequence]
    weights = np.array([step.weight for step in act.sequence])
    observable = np.asarray(crit.observable[:, cols].any(axis=0))  # (steps,)
    met = (crit.met[:, cols] & crit.observable[:, cols]).T  # (steps, W)
    matched, chosen = ordered_match(met[observable], weights[observable])
    chosen_full: list[int | None] = [None] * len(cols)
    for jj, c in zip(np.flatnonzero(observable).tolist(), chosen, strict=True):
        chosen_full[jj] = c

    outcomes = []
    for j, step in enumerate(act.sequence):
        words = add.criteria[step.qmp].words
        w = chosen_full[j]
        if not observable[j]:
            outcomes.append(QMPOutcome(step.qmp, words, step.weight, "not observable"))
        elif w is not None:
            span = (float(windows_s[w, 0]), float(windows_s[w, 1]))
            outcomes.append(QMPOutcome(step.qmp, words, step.weight, "met", span))
        elif met[j].any():
            outcomes.append(
                QMPOutcome(
                    step.qmp,
                    words,
                    step.weight,
                    "out of order",
                    reasons=("detected, but not in the expected order",),
                )
            )
        else:
            # The reasons come from the window where the QMP came closest.
            outcomes.append(
                QMPOutcome(step.qmp, words, step.weight, "not met", reasons=crit.failed[cols[j]])
            )
    obs_weight = int(weights[observable].sum())
    score = matched / obs_weight if obs_weight > 0 else float("nan")
    return ActivityScore(
        act.name, act.words, act.labels, float(score), int(matched), obs_weight, tuple(outcomes)
    )


def _rank_key(a: ActivityScore) -> tuple[float, int, str]:
    score = a.score if np.isfinite(a.score) else -1.0
    return (-score, -a.met_weight, a.activity)


def detect(
    seq: PoseSequence,
    add: ADD | str | Path | None = None,
    config: DADConfig | None = None,
) -> DADResult:
    """Run DAD on one pose sequence ``(frames, joints, 3)``; see :class:`DADResult`.

    add: a loaded :class:`ADD`, a path to an ADD file, or None for the shipped database.
    """
    cfg = config or DADConfig()
    db = add if isinstance(add, ADD) else load_add(add)
    duration = seq.positions.shape[0] / seq.fps
    if duration < cfg.min_duration_s:
        return _too_short(seq.source, seq.fps, duration, db, cfg)
    signals = state_signals(seq)
    return detect_signals(signals.values, signals.names, seq.fps, db, cfg, source=seq.source)


def _too_short(source: str, fps: float, duration: float, db: ADD, cfg: DADConfig) -> DADResult:
    return DADResult(
        source,
        NOT_ENOUGH_DATA,
        f"clip lasts {duration:.2f} s; DAD needs at least {cfg.min_duration_s:g} s",
        fps,
        duration,
        (),
        (),
        (),
        db.source,
        {n: c.words for n, c in db.criteria.items()},
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
    words = {n: c.words for n, c in db.criteria.items()}
    if duration < cfg.min_duration_s:
        return _too_short(source, fps, duration, db, cfg)
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
        return DADResult(
            source,
            NOT_ENOUGH_DATA,
            "no QMP could be observed (joints missing, or gaps too long)",
            fps,
            duration,
            spans,
            detected,
            (),
            db.source,
            words,
        )
    scores = [_score_activity(a, db, crit, windows_s) for a in db.activities.values()]
    ranked = tuple(sorted(scores, key=_rank_key))
    return DADResult(source, "ok", "", fps, duration, spans, detected, ranked, db.source, words)


class DADClassifier(ClassifierMixin, BaseEstimator):
    """DAD with the scikit-learn classifier contract (X: a sequence of PoseSequence).

    ``fit`` learns nothing but ``classes_`` (DAD needs no training data); ``predict`` maps the
    top-ranked ADD activity among those standing for a known class to that class (activities
    for other datasets' labels are ignored); a clip DAD cannot judge ("not enough data") gets
    the first class. ``decision_function`` gives each class its best activity's score;
    ``predict_proba`` normalises those scores.

    add: an :class:`ADD`, a path to an ADD file, or None for the shipped one; window_s and
    step_s: the sliding windows (see :class:`DADConfig`).
    """

    def __init__(
        self, add: ADD | str | Path | None = None, window_s: float = 4.0, step_s: float = 1.0
    ) -> None:
        self.add = add
        self.window_s = window_s
        self.step_s = step_s

    def fit(self, X: Sequence[PoseSequence], y: Sequence[Any] | np.ndarray) -> DADClassifier:
        labels = np.asarray(list(y))
        if len(labels) != len(X):
            raise ValueError(f"X has {len(X)} clips but y has {len(labels)} labels")
        self.classes_ = np.unique(labels)
        self.add_ = self.add if isinstance(self.add, ADD) else load_add(self.add)
        self.config_ = DADConfig(window_s=self.window_s, step_s=self.step_s)
        return self

    def _class_scores(self, seq: PoseSequence) -> np.ndarray:
        result = detect(seq, self.add_, self.config_)
        classes = [str(c) for c in self.classes_]
        scores = np.full(len(classes), -1.0)
        for rank, act in enumerate(result.activities):
            if not np.isfinite(act.score):
                continue
            # The rank breaks ties between equal ratios (more matched weight ranks first).
            key = act.score - 1e-6 * rank
            for label in act.labels:
                if label in classes:
                    i = classes.index(label)
                    scores[i] = max(scores[i], key)
        return scores

    def decision_function(self, X: Sequence[PoseSequence]) -> np.ndarray:
        """Best activity score per class, ``(n_clips, n_classes)``; -1 where no activity."""
        check_is_fitted(self, "classes_")
        if len(X) == 0:
            return np.zeros((0, len(self.classes_)))
        return np.stack([self._class_scores(seq) for seq in X])

    def predict(self, X: Sequence[PoseSequence]) -> np.ndarray:
        scores = self.decision_function(X)  # checks fitted before classes_ is read
        return self.classes_[np.argmax(scores, axis=1)]

    def predict_proba(self, X: Sequence[PoseSequence]) -> np.ndarray:
        scores = np.clip(self.decision_function(X), 0.0, None) + 1e-9
        return scores / scores.sum(axis=1, keepdims=True)
