"""Accuracy comparison: every similarity x feature level, DAD and peer classifiers, run on the
same cross-validation folds of a labelled dataset, with confidence intervals and a paired test.

Protocol
--------
- Folds: leave-one-subject-out (``cv="loso"``, default) or stratified k-fold over clips
  (``cv="kfold"``). LOSO needs a subject for every clip and at least two subjects; otherwise the
  run falls back to stratified k-fold and says so in ``notes`` (scores are then optimistic,
  because the same person is in training and test).
- Classes with a single clip are left out (a held-out single clip can never be predicted right,
  and stratification is impossible); the note names them.
- Target: the activity label (default) or any column of the clip metadata (``correct``,
  ``sensor``, ...). For a target other than the label, one model per activity is trained
  (``within="label"``): e.g. ``target="correct"`` on UI-PRMD predicts correct/incorrect within
  each movement from that movement's training clips, so chance is ~50 % and the movement itself
  is never confused with correctness.
- Features are computed once per clip before the folds run (fluents and QMPs through the
  estimator's per-sequence cache, joint-angle series for the peers here), so no fold recomputes
  them; with ``jobs > 1`` the folds run in forked workers that inherit the warm caches.
- Statistics: accuracy with a Wilson 95 % interval; macro-F1 with a percentile bootstrap over
  clips; per-class recall with Wilson intervals; McNemar's exact (binomial) test of every method
  against the best one on the same clips.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import importlib.metadata
import math
import multiprocessing
import os
import platform
import time
import warnings
import weakref
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import binomtest, norm
from sklearn.base import BaseEstimator, ClassifierMixin

from features.datasets import clip_column, clip_target
from features.errors import ConfigError, DataError, PosecbrError
from features.poses import PoseSequence
from features.progress import progress

from .similarity import get_measure

SIMILARITIES = ("euclidean", "dtw", "signature")
FEATURE_LEVELS = ("fluents", "qmp")
PEERS = ("dtw-knn", "minirocket")
CV_SCHEMES = ("loso", "kfold")
# The eight limb angles the peers see (elbows, knees, armpits, hips): raw joint angles in
# radians from the same state signals the fluents are computed from.
LIMB_ANGLES = (
    "left_elbow",
    "right_elbow",
    "left_knee",
    "right_knee",
    "left_armpit",
    "right_armpit",
    "left_hip",
    "right_hip",
)


# ---------------------------------------------------------------------------- statistics


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion ``successes / n`` (``(nan, nan)`` if
    ``n == 0``)."""
    if n <= 0:
        return (math.nan, math.nan)
    z = float(norm.ppf(0.5 + confidence / 2.0))
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


def mcnemar_exact(b: int, c: int) -> float:
    """Two-sided exact McNemar p-value from the discordant counts ``b`` (only the first method
    right) and ``c`` (only the second right): binomial test of min(b, c) in b + c at 1/2."""
    if b + c == 0:
        return 1.0
    return float(binomtest(min(b, c), b + c, 0.5).pvalue)


def _f1_from_counts(tp: np.ndarray, fp: np.ndarray, fn: np.ndarray) -> np.ndarray:
    """Macro-F1 over the last axis; classes never seen in truth or prediction are left out."""
    denom = 2 * tp + fp + fn
    with np.errstate(invalid="ignore", divide="ignore"):
        f1 = np.where(denom > 0, 2 * tp / np.where(denom > 0, denom, 1), np.nan)
    return np.asarray(np.nanmean(f1, axis=-1))


def macro_f1(y_true: np.ndarray, y_pred: np.ndarray, n_classes: int) -> float:
    """Macro-F1 of integer-coded labels ``(n,)`` over the classes present in truth or
    prediction (as ``sklearn.metrics.f1_score(average="macro")``)."""
    tp = np.bincount(y_true[y_true == y_pred], minlength=n_classes).astype(float)
    fp = np.bincount(y_pred, minlength=n_classes) - tp
    fn = np.bincount(y_true, minlength=n_classes) - tp
    return float(_f1_from_counts(tp, fp, fn))


def bootstrap_macro_f1(
    y_true: np.ndarray,
    y_pred: np.ndarray,
    n_classes: int,
    n_boot: int = 1000,
    confidence: float = 0.95,
    seed: int = 0,
) -> tuple[float, float]:
    """Percentile bootstrap interval of macro-F1, resampling clips with replacement.

    y_true, y_pred: ``(n,)`` integer class codes. All resamples are counted at once:
    ``(n_boot, n_classes)`` true-positive, false-positive and false-negative tables.
    """
    n = len(y_true)
    if n == 0:
        return (math.nan, math.nan)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, n, size=(n_boot, n))
    t = y_true[idx]
    p = y_pred[idx]
    offs = (np.arange(n_boot) * n_classes)[:, None]
    size = n_boot * n_classes
    hit = (t == p).ravel()
    tp = np.bincount((t + offs).ravel()[hit], minlength=size).reshape(n_boot, n_classes)
    n_pred = np.bincount((p + offs).ravel(), minlength=size).reshape(n_boot, n_classes)
    n_true = np.bincount((t + offs).ravel(), minlength=size).reshape(n_boot, n_classes)
    f1 = _f1_from_counts(tp.astype(float), (n_pred - tp).astype(float), (n_true - tp).astype(float))
    alpha = (1.0 - confidence) / 2.0
    lo, hi = np.quantile(f1, [alpha, 1.0 - alpha])
    return (float(lo), float(hi))


# ---------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class CompareSettings:
    """What ``compare`` runs.

    target: ``"label"`` or a metadata column; within: train one model per value of this column
    (``"label"`` by default when the target is not the label; ``None``: one model for all).
    k: neighbours of the case-base classifiers; trim: fraction of cases kept by novelty/benefit
    trimming (None: keep all); cbr_params: further ``CaseBaseClassifier`` parameters given to
    every case-base configuration (e.g. ``{"states": "all", "length": 48}``); peer_length:
    frames the peers' angle series are resampled to; bootstrap: resamples for the F1
    interval; explain: misclassified clips to explain.
    """

    target: str = "label"
    cv: str = "loso"
    folds: int = 5
    similarities: tuple[str, ...] = SIMILARITIES
    features: tuple[str, ...] = FEATURE_LEVELS
    dad: bool = True
    peers: tuple[str, ...] = PEERS
    k: int = 5
    trim: float | None = None
    cbr_params: dict[str, Any] = field(default_factory=dict)
    within: str | None = "auto"
    peer_length: int = 64
    jobs: int = 1
    seed: int = 0
    bootstrap: int = 1000
    explain: int = 5

    def __post_init__(self) -> None:
        if self.cv not in CV_SCHEMES:
            raise ConfigError(f"cv must be one of {', '.join(CV_SCHEMES)}, got {self.cv!r}", "--cv")
        if int(self.folds) < 2:
            raise ConfigError(f"folds must be at least 2, got {self.folds}", "--folds")
        for s in self.similarities:
            if s not in SIMILARITIES:
                raise ConfigError(
                    f"unknown similarity {s!r} (choose from {', '.join(SIMILARITIES)})",
                    "--similarities",
                )
        for f in self.features:
            if f not in FEATURE_LEVELS:
                raise ConfigError(
                    f"unknown feature level {f!r} (choose from {', '.join(FEATURE_LEVELS)})",
                    "--features",
                )
        for p in self.peers:
            if p not in PEERS:
                raise ConfigError(f"unknown peer {p!r} (choose from {', '.join(PEERS)})", "--peers")
        if int(self.k) < 1:
            raise ConfigError(f"k must be a positive integer, got {self.k}", "--k")
        if self.trim is not None and not 0.0 < float(self.trim) <= 1.0:
            raise ConfigError(f"trim must be in (0, 1], got {self.trim}", "--trim")
        from .estimator import CaseBaseClassifier

        known = set(CaseBaseClassifier().get_params()) - {"features", "similarity", "k", "trim"}
        bad = sorted(set(self.cbr_params) - known)
        if bad:
            raise ConfigError(
                f"unknown case-base parameter(s) {', '.join(bad)} "
                f"(known: {', '.join(sorted(known))})",
                "--param",
            )
        if int(self.jobs) < 1:
            raise ConfigError(f"jobs must be at least 1, got {self.jobs}", "--jobs")
        if int(self.peer_length) < 9:
            raise ConfigError("peer_length must be at least 9 frames", "peer_length")

    @property
    def within_column(self) -> str | None:
        if self.within == "auto":
            return None if self.target == "label" else "label"
        return self.within or None

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["within"] = self.within_column
        return d


@dataclass(frozen=True)
class Method:
    """One row of the comparison: ``kind`` is "cbr", "dad" or "peer"."""

    name: str
    kind: str
    interpretable: bool
    params: dict[str, Any] = field(default_factory=dict)


def methods_for(settings: CompareSettings) -> list[Method]:
    """Every configuration ``settings`` asks for, interpretable ones first."""
    out = [
        Method(
            f"cbr {level}/{sim}",
            "cbr",
            True,
            {
                "features": level,
                "similarity": sim,
                "k": int(settings.k),
                "trim": settings.trim,
                **settings.cbr_params,
            },
        )
        for level in settings.features
        for sim in settings.similarities
        # a QMP description is one vector per clip: sequence measures have nothing to align
        if level != "qmp" or not get_measure(sim).compares_sequences
    ]
    if settings.dad:
        out.append(Method("dad", "dad", True, {}))
    for peer in settings.peers:
        params: dict[str, Any] = {"length": int(settings.peer_length)}
        if peer == "dtw-knn":
            params["n_neighbors"] = 1
        else:
            params["random_state"] = int(settings.seed)
        out.append(Method(peer, "peer", False, params))
    return out


# ---------------------------------------------------------------------------- peers

_ANGLE_CACHE: weakref.WeakKeyDictionary[PoseSequence, np.ndarray] = weakref.WeakKeyDictionary()


def angle_series(seq: PoseSequence, length: int) -> np.ndarray:
    """The eight limb angles of ``seq`` (radians), gaps interpolated, resampled to ``length``
    frames: ``(length, 8)``. Cached per sequence object (all folds share one computation)."""
    cached = _ANGLE_CACHE.get(seq)
    if cached is not None and cached.shape[0] == length:
        return cached
    from features.fluents import state_signals

    from .problem import fill_nan_time, resample

    sig = state_signals(seq)
    index = {n: i for i, n in enumerate(sig.names)}
    missing = [a for a in LIMB_ANGLES if a not in index]
    if missing:
        raise DataError(f"state signals lack {', '.join(missing)}", seq.source or "clip")
    values = sig.values[:, [index[a] for a in LIMB_ANGLES]]
    out = resample(fill_nan_time(values, 0.0), int(length))
    _ANGLE_CACHE[seq] = out
    return out


class DTWKNNPeer(ClassifierMixin, BaseEstimator):
    """k-NN with DTW from tslearn (``KNeighborsTimeSeriesClassifier``) on the eight limb
    angles resampled to ``length`` frames: the plain peer a user would reach for."""

    def __init__(self, length: int = 64, n_neighbors: int = 1) -> None:
        self.length = length
        self.n_neighbors = n_neighbors

    def _series(self, X: Sequence[PoseSequence]) -> np.ndarray:
        return np.stack([angle_series(s, int(self.length)) for s in X])

    def fit(self, X: Sequence[PoseSequence], y: Any) -> DTWKNNPeer:
        with warnings.catch_warnings():  # tslearn warns that optional h5py is missing
            warnings.simplefilter("ignore", UserWarning)
            from tslearn.neighbors import KNeighborsTimeSeriesClassifier

        self.model_ = KNeighborsTimeSeriesClassifier(
            n_neighbors=int(self.n_neighbors), metric="dtw"
        )
        self.model_.fit(self._series(X), np.asarray(y))
        self.classes_ = self.model_.classes_
        return self

    def predict(self, X: Sequence[PoseSequence]) -> np.ndarray:
        return np.asarray(self.model_.predict(self._series(X)))


def minirocket_backend() -> str | None:
    """``"sktime"`` or ``"aeon"`` when one of them is installed, else None."""
    for name in ("sktime", "aeon"):
        if importlib.util.find_spec(name) is not None:
            return name
    return None


class MiniRocketPeer(ClassifierMixin, BaseEstimator):
    """MiniRocket features (sktime or aeon) + ridge regression with built-in cross-validated
    regularisation, on the eight limb angles: a strong, non-interpretable peer."""

    def __init__(self, length: int = 64, random_state: int = 0) -> None:
        self.length = length
        self.random_state = random_state

    def _panel(self, X: Sequence[PoseSequence]) -> np.ndarray:
        # (n, channels, time), the layout both libraries take.
        return np.stack([angle_series(s, int(self.length)).T for s in X])

    def fit(self, X: Sequence[PoseSequence], y: Any) -> MiniRocketPeer:
        from sklearn.linear_model import RidgeClassifierCV
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        backend = minirocket_backend()
        if backend == "sktime":
            from sktime.transformations.panel.rocket import MiniRocketMultivariate

            transform: Any = MiniRocketMultivariate(random_state=self.random_state, n_jobs=1)
        elif backend == "aeon":
            from aeon.transformations.collection.convolution_based import MiniRocket

            transform = MiniRocket(random_state=self.random_state, n_jobs=1)
        else:
            raise ConfigError(
                "MiniRocket needs sktime or aeon (pip install sktime); the peer is skipped",
                "minirocket",
            )
        self.transform_ = transform.fit(self._panel(X))
        feats = np.asarray(self.transform_.transform(self._panel(X)), dtype=np.float64)
        self.ridge_ = make_pipeline(
            StandardScaler(), RidgeClassifierCV(alphas=np.logspace(-3, 3, 10))
        ).fit(feats, np.asarray(y))
        self.classes_ = self.ridge_.classes_
        return self

    def predict(self, X: Sequence[PoseSequence]) -> np.ndarray:
        feats = np.asarray(self.transform_.transform(self._panel(X)), dtype=np.float64)
        return np.asarray(self.ridge_.predict(feats))


def make_estimator(method: Method) -> Any:
    """A fresh, unfitted estimator for ``method`` (all share fit(X, y)/predict(X))."""
    if method.kind == "cbr":
        from .estimator import CaseBaseClassifier

        return CaseBaseClassifier(**method.params)
    if method.kind == "dad":
        from .dad import DADClassifier

        return DADClassifier()
    if method.name == "dtw-knn":
        return DTWKNNPeer(**method.params)
    if method.name == "minirocket":
        return MiniRocketPeer(**method.params)
    raise ConfigError(f"unknown method {method.name!r}", "compare")


# ---------------------------------------------------------------------------- data


@dataclass
class Prepared:
    """The clips of one comparison and what is predicted for each.

    seqs ``(n,)`` pose sequences; ids ``(n,)`` clip names; y ``(n,)`` target values (str);
    subjects ``(n,)`` (None when unknown); labels ``(n,)`` activity labels; within ``(n,)``
    the per-model group (or None); classes: sorted target values.
    """

    seqs: list[PoseSequence]
    ids: list[str]
    y: np.ndarray
    subjects: list[str | None]
    labels: np.ndarray
    within: np.ndarray | None
    classes: list[str]
    notes: list[str] = field(default_factory=list)


def prepare(clips: Sequence[Any], settings: CompareSettings, source: str = "dataset") -> Prepared:
    """Targets, subjects and groups of ``clips`` (``features.datasets.Clip``); classes with a
    single clip are dropped with a note."""
    if not clips:
        raise DataError("no clips found", source)
    notes: list[str] = []
    values = [clip_target(c, settings.target) for c in clips]
    missing = [i for i, v in enumerate(values) if v is None]
    if missing:
        cols = sorted({"label", "subject"} | {k for c in clips for k in c.extras})
        raise DataError(
            f"{len(missing)} of {len(clips)} clips have no value for target "
            f"{settings.target!r} (e.g. {_clip_id(clips[missing[0]], missing[0])}); "
            f"columns available: {', '.join(cols)}",
            source,
        )
    y = np.array(values, dtype=object)
    within_col = settings.within_column
    within = None
    if within_col is not None:
        wv = [clip_column(c, within_col) for c in clips]
        if any(v is None for v in wv):
            raise DataError(f"some clips have no {within_col!r} to group the models by", source)
        within = np.array([str(v) for v in wv], dtype=object)
    counts = Counter(y)
    single = sorted(c for c, n in counts.items() if n < 2)
    keep = np.array([counts[v] >= 2 for v in y])
    if single:
        notes.append(
            f"class{'es' if len(single) > 1 else ''} {', '.join(single)} ha"
            f"{'ve' if len(single) > 1 else 's'} a single clip and cannot be cross-validated "
            "(a held-out single clip is never in training); left out of the comparison"
        )
    idx = [int(i) for i in np.flatnonzero(keep)]
    classes = sorted({str(v) for v in y[idx]})
    if len(classes) < 2:
        raise DataError(
            f"need at least two classes of {settings.target!r} with two or more clips each; "
            f"found {dict(counts)}",
            source,
        )
    return Prepared(
        seqs=[clips[i].seq for i in idx],
        ids=[_clip_id(clips[i], i) for i in idx],
        y=y[idx],
        subjects=[clips[i].subject for i in idx],
        labels=np.array([str(clips[i].label) for i in idx], dtype=object),
        within=None if within is None else within[idx],
        classes=classes,
        notes=notes,
    )


def _clip_id(clip: Any, i: int) -> str:
    src = clip.seq.source or clip.extras.get("origin") or ""
    return Path(str(src)).name if src else f"clip {i}"


# ---------------------------------------------------------------------------- folds


def make_folds(data: Prepared, settings: CompareSettings) -> tuple[str, np.ndarray, list[str]]:
    """Fold number of every clip ``(n,)`` and the scheme actually used, with notes.

    LOSO: one fold per subject. Stratified k-fold (shuffled, seeded) is used when asked for, or
    as the fallback when LOSO is impossible (a clip without subject, or a single subject).
    """
    notes: list[str] = []
    n = len(data.y)
    scheme = settings.cv
    if scheme == "loso":
        subjects = data.subjects
        unknown = sum(s is None for s in subjects)
        distinct = sorted({s for s in subjects if s is not None})
        if unknown:
            notes.append(
                f"{unknown} clip(s) have no subject, so leave-one-subject-out is impossible; "
                f"falling back to stratified {settings.folds}-fold cross-validation over clips "
                "(optimistic: a person can be in training and test)"
            )
            scheme = "kfold"
        elif len(distinct) < 2:
            notes.append(
                f"only one subject ({distinct[0]}), so leave-one-subject-out is impossible; "
                f"falling back to stratified {settings.folds}-fold cross-validation over clips "
                "(optimistic: the same person is in training and test)"
            )
            scheme = "kfold"
        else:
            index = {s: i for i, s in enumerate(distinct)}
            fold = np.array([index[str(s)] for s in subjects], dtype=np.int64)
            return "loso", fold, notes
    from sklearn.model_selection import StratifiedKFold

    strat = (
        data.y
        if data.within is None
        else np.array([f"{w}|{v}" for w, v in zip(data.within, data.y, strict=True)])
    )
    smallest = min(Counter(strat).values())
    k = int(settings.folds)
    if smallest < k:
        if smallest < 2:
            raise DataError(
                "a class has a single clip in some group; stratified k-fold is impossible",
                "--cv kfold",
            )
        notes.append(f"the smallest class has {smallest} clips: using {smallest} folds, not {k}")
        k = smallest
    fold = np.zeros(n, dtype=np.int64)
    skf = StratifiedKFold(n_splits=k, shuffle=True, random_state=int(settings.seed))
    for i, (_, test) in enumerate(skf.split(np.zeros((n, 1)), strat)):
        fold[test] = i
    return "kfold", fold, notes


# ---------------------------------------------------------------------------- running


@dataclass
class FoldResult:
    method: int
    fold: int
    test: np.ndarray  # (n_test,) clip indices
    pred: np.ndarray  # (n_test,) predicted target values
    fit_s: float
    predict_s: float
    case_base_size: int | None
    training_size: int
    error: str | None = None
    notes: tuple[str, ...] = ()


# The running comparison, set before workers fork so they inherit data and warm caches.
_RUN: dict[str, Any] = {}


def _case_base_size(est: Any) -> int | None:
    cb = getattr(est, "case_base_", None)
    return None if cb is None else len(cb)


def _fit_predict(
    method: Method, X_train: list[PoseSequence], y_train: np.ndarray, X_test: list[PoseSequence]
) -> tuple[np.ndarray, float, float, int | None]:
    est = make_estimator(method)
    t0 = time.perf_counter()
    est.fit(X_train, y_train)
    t1 = time.perf_counter()
    pred = np.asarray(est.predict(X_test), dtype=object)
    t2 = time.perf_counter()
    return np.array([str(p) for p in pred], dtype=object), t1 - t0, t2 - t1, _case_base_size(est)


def run_fold(mi: int, fold: int) -> FoldResult:
    """Train method ``mi`` on every fold but ``fold`` and predict ``fold`` (per group when the
    comparison trains one model per activity)."""
    data: Prepared = _RUN["data"]
    method: Method = _RUN["methods"][mi]
    folds: np.ndarray = _RUN["folds"]
    test = np.flatnonzero(folds == fold)
    train = np.flatnonzero(folds != fold)
    pred = np.empty(len(test), dtype=object)
    fit_s = predict_s = 0.0
    size: int | None = None
    notes: list[str] = []
    within = data.within
    groups = [None] if within is None else sorted(set(within[test]))
    try:
        for g in groups:
            te = test if within is None else test[within[test] == g]
            tr = train if within is None else train[within[train] == g]
            where = np.isin(test, te)
            y_tr = data.y[tr]
            present = sorted(set(y_tr))
            if len(present) < 2:
                # One class (or none) to learn from: every prediction is that class.
                fallback = present[0] if present else Counter(data.y[train]).most_common(1)[0][0]
                pred[where] = fallback
                notes.append(
                    f"{'' if g is None else f'{g}: '}training fold has "
                    f"{'only ' + repr(present[0]) if present else 'no clips'}; predicted "
                    f"{fallback!r} for its {len(te)} test clip(s)"
                )
                continue
            p, f_s, p_s, cb = _fit_predict(
                method, [data.seqs[i] for i in tr], y_tr, [data.seqs[i] for i in te]
            )
            pred[where] = p
            fit_s += f_s
            predict_s += p_s
            if cb is not None:
                size = (size or 0) + cb
    except PosecbrError as exc:
        return FoldResult(mi, fold, test, pred, fit_s, predict_s, size, len(train), str(exc))
    return FoldResult(mi, fold, test, pred, fit_s, predict_s, size, len(train), None, tuple(notes))


def _run_task(task: tuple[int, int]) -> FoldResult:
    return run_fold(*task)


def warm_features(data: Prepared, methods: list[Method], settings: CompareSettings) -> list[str]:
    """Compute every clip's features once (fluents, QMPs, peer angle series) so that no fold
    recomputes them; returns the feature levels that cannot be computed at all in this build,
    each with its reason ("qmp: ..."). A single clip that fails is left to the folds, which
    report the method as failed with the clip's error."""
    from .problem import FeatureConfig, extract_problem, resolve_config

    failed: list[str] = []
    need_fluents = any(m.kind == "cbr" and m.params["features"] == "fluents" for m in methods)
    need_qmp = any(m.kind == "cbr" and m.params["features"] == "qmp" for m in methods)
    need_angles = any(m.kind == "peer" for m in methods)
    qmp_config = FeatureConfig(level="qmp")
    for seq in progress(data.seqs, "features", total=len(data.seqs), unit="clip"):
        if need_fluents:
            with contextlib.suppress(PosecbrError):
                resolve_config(FeatureConfig(level="fluents"), [seq])  # fills the fluent cache
        if need_qmp:
            try:
                extract_problem(seq, qmp_config)  # fills the QMP cache
            except ConfigError as exc:  # the level is missing from this build
                failed.append(f"qmp: {exc.message}")
                need_qmp = False
            except PosecbrError:
                pass
        if need_angles:
            with contextlib.suppress(PosecbrError):
                angle_series(seq, int(settings.peer_length))
    return failed


def warm_compilers(data: Prepared, methods: list[Method]) -> None:
    """Fit and predict every method once on two clips of different classes, untimed, so that
    just-in-time compilation (numba in tslearn, sktime and the DTW measure: up to tens of
    seconds) is not billed to the first fold's training or prediction time. Best effort: any
    error here is left for the folds to report."""
    first: dict[str, int] = {}
    for i, v in enumerate(data.y):
        first.setdefault(str(v), i)
        if len(first) == 2:
            break
    if len(first) < 2:
        return
    idx = list(first.values())
    X = [data.seqs[i] for i in idx]
    y = data.y[idx]
    for m in progress(methods, "compiling", total=len(methods), unit="method"):
        with contextlib.suppress(Exception):
            make_estimator(m).fit(X, y).predict(X[:1])


def _method_unavailable(method: Method, data: Prepared, settings: CompareSettings) -> str | None:
    """Why ``method`` cannot run on this comparison (None if it can)."""
    if method.kind == "dad":
        if settings.target != "label":
            return (
                f"DAD recognises activities from its ADD rules; it does not predict "
                f"{settings.target!r}"
            )
        from features.qmp.add import load_add

        known = {lab for act in load_add().activities.values() for lab in act.labels}
        covered = [c for c in data.classes if c in known]
        if not covered:
            return "the ADD describes none of this dataset's activities"
    if method.name == "minirocket" and minirocket_backend() is None:
        return (
            "MiniRocket needs sktime or aeon, neither is installed "
            "(pip install -e '.[compare]' installs sktime)"
        )
    return None


def _per_method(
    method: Method,
    data: Prepared,
    pred: np.ndarray,
    results: list[FoldResult],
    settings: CompareSettings,
) -> dict[str, Any]:
    classes = data.classes
    code = {c: i for i, c in enumerate(classes)}
    n_cls = len(classes)
    other = n_cls  # predictions outside the target classes (e.g. DAD's first-class default)
    t = np.array([code[v] for v in data.y])
    p = np.array([code.get(str(v), other) for v in pred])
    correct = t == p
    n = len(t)
    acc = float(correct.mean())
    per_class: dict[str, Any] = {}
    for c, i in code.items():
        m = t == i
        k = int(correct[m].sum())
        per_class[c] = {
            "n": int(m.sum()),
            "recall": k / max(1, int(m.sum())),
            "ci": list(wilson_interval(k, int(m.sum()))),
        }
    per_group: dict[str, Any] = {}
    if data.within is not None:  # one model per group (e.g. per movement): how each fares
        for g in sorted(set(data.within.tolist())):
            m = data.within == g
            k = int(correct[m].sum())
            per_group[str(g)] = {
                "n": int(m.sum()),
                "accuracy": k / int(m.sum()),
                "ci": list(wilson_interval(k, int(m.sum()))),
            }
    confusion = np.zeros((n_cls, n_cls + 1), dtype=np.int64)
    np.add.at(confusion, (t, p), 1)
    sizes = [r.case_base_size for r in results if r.case_base_size is not None]
    fit_s = sum(r.fit_s for r in results)
    predict_s = sum(r.predict_s for r in results)
    notes = sorted({nt for r in results for nt in r.notes})
    return {
        "accuracy": acc,
        "accuracy_ci": list(wilson_interval(int(correct.sum()), n)),
        "macro_f1": macro_f1(t, p, n_cls + 1),
        "macro_f1_ci": list(
            bootstrap_macro_f1(t, p, n_cls + 1, int(settings.bootstrap), seed=int(settings.seed))
        ),
        "per_class": per_class,
        "per_group": per_group,
        "confusion": confusion[:, :n_cls].tolist(),
        "unassigned": confusion[:, n_cls].tolist(),
        "fit_s": fit_s,
        "predict_s": predict_s,
        "predict_ms_per_clip": 1000.0 * predict_s / max(1, n),
        "case_base_size": float(np.mean(sizes)) if sizes else None,
        "training_size": float(np.mean([r.training_size for r in results])),
        "predictions": [str(v) for v in pred],
        "correct": correct.tolist(),
        "fold_notes": notes,
    }


def machine_info(extra_packages: tuple[str, ...] = ()) -> dict[str, Any]:
    """Machine and library versions, recorded with every result (and every benchmark)."""
    versions: dict[str, str | None] = {}
    for pkg in extra_packages + (
        "posecbr",
        "numpy",
        "scipy",
        "scikit-learn",
        "tslearn",
        "iisignature",
        "pysindy",
        "numba",
        "sktime",
        "aeon",
        "matplotlib",
    ):
        try:
            versions[pkg] = importlib.metadata.version(pkg)
        except importlib.metadata.PackageNotFoundError:
            versions[pkg] = None
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "versions": versions,
    }


def _run_tasks(
    data: Prepared,
    methods: list[Method],
    folds: np.ndarray,
    tasks: list[tuple[int, int]],
    status: dict[int, tuple[str, str]],
    jobs: int,
) -> list[FoldResult]:
    """Every (method, fold) task, in ``jobs`` forked workers that inherit the warm caches.

    With workers, each one warms the compilers itself before its first task: the parent must
    not, because GNU OpenMP (scikit-learn's neighbour search under the tslearn peer) aborts a
    forked child once the parent has started its thread team.
    """
    active = [m for i, m in enumerate(methods) if i not in status]
    _RUN.update(data=data, methods=methods, folds=folds)
    try:
        if jobs > 1:
            ctx = multiprocessing.get_context("fork")
            with ctx.Pool(jobs, initializer=warm_compilers, initargs=(data, active)) as pool:
                it = pool.imap_unordered(_run_task, tasks)
                return list(progress(it, "folds", total=len(tasks), unit="fold"))
        warm_compilers(data, active)
        return [
            run_fold(mi, f) for mi, f in progress(tasks, "folds", total=len(tasks), unit="fold")
        ]
    finally:
        _RUN.clear()


def run_compare(
    clips: Sequence[Any],
    settings: CompareSettings,
    source: str = "dataset",
    fold_indices: np.ndarray | None = None,
) -> dict[str, Any]:
    """Cross-validate every configuration of ``settings`` on ``clips`` (``Clip`` objects).

    Returns the JSON-ready results (see :func:`cbr.report.render_html` for the reader):
    dataset summary, settings, notes, folds, per-method metrics and predictions, the best
    method and McNemar p-values against it, and explanations of misclassified clips.
    ``fold_indices`` ``(n_clips,)`` overrides the fold assignment (tests, fixed splits).
    """
    data = prepare(clips, settings, source)
    notes = list(data.notes)
    if fold_indices is not None:
        scheme, folds = "given", np.asarray(fold_indices, dtype=np.int64)
    else:
        scheme, folds, fold_notes = make_folds(data, settings)
        notes += fold_notes
    fold_ids = sorted(set(folds.tolist()))
    if scheme == "loso":
        for f in fold_ids:
            test = folds == f
            unseen = sorted(set(data.y[test]) - set(data.y[~test]))
            if unseen:
                notes.append(
                    f"subject {data.subjects[int(np.flatnonzero(test)[0])]}: class(es) "
                    f"{', '.join(unseen)} occur in no other subject, so they cannot be "
                    "predicted when that subject is held out"
                )
    methods = methods_for(settings)
    if "qmp" in settings.features and any(
        get_measure(s).compares_sequences for s in settings.similarities
    ):
        notes.append(
            "qmp features are one vector per clip: compared by euclidean only (dtw and "
            "signature compare sequences)"
        )
    status: dict[int, tuple[str, str]] = {}
    for mi, m in enumerate(methods):
        why = _method_unavailable(m, data, settings)
        if why:
            status[mi] = ("skipped", why)
        elif m.kind == "dad":
            from features.qmp.add import load_add

            known = {lab for act in load_add().activities.values() for lab in act.labels}
            uncovered = [c for c in data.classes if c not in known]
            if uncovered:
                notes.append(
                    f"the ADD has no activity for {', '.join(uncovered)}: DAD cannot recognise "
                    "those clips (it answers the best-scoring described activity instead)"
                )
    failed = warm_features(data, [m for i, m in enumerate(methods) if i not in status], settings)
    for msg in failed:
        level = msg.split(":", 1)[0]
        for mi, m in enumerate(methods):
            if m.kind == "cbr" and m.params["features"] == level and mi not in status:
                status[mi] = ("skipped", msg.split(":", 1)[1].strip())
    tasks = [(mi, f) for mi in range(len(methods)) if mi not in status for f in fold_ids]
    jobs = min(int(settings.jobs), max(1, len(tasks)))
    fold_results = _run_tasks(data, methods, folds, tasks, status, jobs)

    out_methods: list[dict[str, Any]] = []
    for mi, m in enumerate(methods):
        entry: dict[str, Any] = {
            "name": m.name,
            "kind": m.kind,
            "interpretable": m.interpretable,
            "params": m.params,
        }
        if mi in status:
            entry["status"], entry["message"] = status[mi]
            out_methods.append(entry)
            continue
        res = [r for r in fold_results if r.method == mi]
        errors = [r.error for r in res if r.error]
        if errors:
            entry["status"], entry["message"] = "failed", errors[0]
            out_methods.append(entry)
            continue
        pred = np.empty(len(data.y), dtype=object)
        for r in res:
            pred[r.test] = r.pred
        entry["status"], entry["message"] = "ok", ""
        entry.update(_per_method(m, data, pred, res, settings))
        out_methods.append(entry)

    ok = [e for e in out_methods if e["status"] == "ok"]
    best = best_interpretable = None
    if ok:
        best = max(ok, key=lambda e: (e["accuracy"], e["macro_f1"]))
        interp = [e for e in ok if e["interpretable"]]
        if interp:
            best_interpretable = max(interp, key=lambda e: (e["accuracy"], e["macro_f1"]))
        ref = np.array(best["correct"])
        for e in ok:
            cur = np.array(e["correct"])
            b = int((ref & ~cur).sum())
            c = int((~ref & cur).sum())
            e["mcnemar_vs"] = best["name"]
            e["mcnemar_b"], e["mcnemar_c"] = b, c
            e["mcnemar_p"] = mcnemar_exact(b, c)
    for e in out_methods:
        if e["status"] == "skipped":
            notes.append(f"{e['name']} skipped: {e['message']}")
        elif e["status"] == "failed":
            notes.append(f"{e['name']} failed: {e['message']}")

    subjects = sorted({s for s in data.subjects if s is not None})
    return {
        "kind": "posecbr-compare",
        "created_utc": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": machine_info(),
        "dataset": {
            "source": source,
            "n_clips": len(data.y),
            "subjects": subjects,
            "classes": data.classes,
            "class_counts": {c: int((data.y == c).sum()) for c in data.classes},
            "activities": sorted(set(data.labels.tolist())),
        },
        "settings": settings.to_dict(),
        "cv": {"scheme": scheme, "n_folds": len(fold_ids), "fold_of_clip": folds.tolist()},
        "notes": notes,
        "clips": [
            {
                "id": data.ids[i],
                "label": str(data.labels[i]),
                "subject": data.subjects[i],
                "target": str(data.y[i]),
            }
            for i in range(len(data.y))
        ],
        "methods": out_methods,
        "best": None if best is None else best["name"],
        "best_interpretable": None if best_interpretable is None else best_interpretable["name"],
        "explanations": [],
        "pictures": {},
        "_data": data,
        "_folds": folds,
    }


# ---------------------------------------------------------------------------- after the folds


def best_cbr(results: dict[str, Any]) -> dict[str, Any] | None:
    """The most accurate case-base configuration that ran."""
    cbr = [m for m in results["methods"] if m["kind"] == "cbr" and m["status"] == "ok"]
    return max(cbr, key=lambda e: (e["accuracy"], e["macro_f1"])) if cbr else None


def explain_errors(results: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """Explanations of up to ``n`` clips the best case-base configuration got wrong (one per
    true class first), from a model refitted on that clip's training fold."""
    m = best_cbr(results)
    if m is None or n <= 0:
        return []
    data: Prepared = results["_data"]
    folds: np.ndarray = results["_folds"]
    wrong = [i for i, ok in enumerate(m["correct"]) if not ok]
    picked: list[int] = []
    seen: set[str] = set()
    for i in wrong:  # one per true class first, then any
        if str(data.y[i]) not in seen:
            picked.append(i)
            seen.add(str(data.y[i]))
    picked += [i for i in wrong if i not in picked]
    picked = picked[:n]
    method = Method(m["name"], m["kind"], True, m["params"])
    out = []
    for i in progress(picked, "explanations", total=len(picked), unit="clip"):
        train = np.flatnonzero(folds != folds[i])
        if data.within is not None:
            train = train[data.within[train] == data.within[i]]
        if len(set(data.y[train])) < 2:
            continue
        est = make_estimator(method)
        est.fit([data.seqs[j] for j in train], data.y[train])
        exp = est.explain([data.seqs[i]])[0]
        out.append(
            {
                "clip": data.ids[i],
                "subject": data.subjects[i],
                "activity": str(data.labels[i]),
                "true": str(data.y[i]),
                "predicted": m["predictions"][i],
                "method": m["name"],
                "text": exp.text,
                "explanation": exp.to_dict(),
            }
        )
    return out


def _dad_words(act: Any) -> str:
    """One activity's DAD outcome in words: score, QMPs met and not met (with the reason)."""
    score = "no observable QMP" if not np.isfinite(act.score) else f"score {act.score:.2f}"
    met = ", ".join(q.words for q in act.met) or "none"
    missed = "; ".join(
        q.words + (f" ({q.status}: {q.reasons[0]})" if q.reasons else f" ({q.status})")
        for q in act.not_met
    )
    return f"{act.words} ({score}); met: {met}" + (f"; not met: {missed}" if missed else "")


def explain_dad_errors(results: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """For up to ``n`` clips DAD got wrong (one per true class first): what DAD saw for the
    activity it chose and for the true one, QMP by QMP, from :func:`cbr.dad.detect`."""
    m = next((x for x in results["methods"] if x["kind"] == "dad" and x["status"] == "ok"), None)
    if m is None or n <= 0:
        return []
    from features.qmp.add import load_add

    from .dad import detect

    data: Prepared = results["_data"]
    wrong = [i for i, ok in enumerate(m["correct"]) if not ok]
    picked: list[int] = []
    seen: set[str] = set()
    for i in wrong:
        if str(data.y[i]) not in seen:
            picked.append(i)
            seen.add(str(data.y[i]))
    picked = (picked + [i for i in wrong if i not in picked])[:n]
    add = load_add()
    out = []
    for i in progress(picked, "DAD explanations", total=len(picked), unit="clip"):
        res = detect(data.seqs[i], add)
        true, pred = str(data.y[i]), str(m["predictions"][i])
        chosen = next((a for a in res.activities if pred in a.labels), None)
        wanted = next((a for a in res.activities if true in a.labels), None)
        if res.status != "ok":
            text = f"DAD could not judge the clip: {res.message}"
        else:
            text = "DAD chose " + (_dad_words(chosen) if chosen else pred) + "."
            text += (
                f"\nThe true activity: {_dad_words(wanted)}."
                if wanted
                else f"\nThe ADD has no activity for {true}."
            )
        out.append(
            {
                "clip": data.ids[i],
                "subject": data.subjects[i],
                "activity": str(data.labels[i]),
                "true": true,
                "predicted": pred,
                "method": "dad",
                "text": text,
            }
        )
    return out


def prevalence(
    results: dict[str, Any], trim: float = 0.5, max_features: int = 40
) -> dict[str, Any] | None:
    """Feature prevalence per activity in the initial and the trimmed case base (paper fig. 4).

    Uses the best case-base configuration's feature level and similarity, built on every clip
    with the activity label as solution. Prevalence of a feature in an activity = mean over its
    cases of the share of (resampled) frames where the feature holds (confidence >= 0.5); for
    QMP vectors, the share of cases that show the QMP. Returns activities, feature words
    (the ``max_features`` that differ most between activities), ``initial`` and ``trimmed``
    ``(n_activities, n_features)`` and the case counts.
    """
    m = best_cbr(results)
    if m is None:
        return None
    from .estimator import CaseBaseClassifier
    from .explain import presence, state_columns

    data: Prepared = results["_data"]
    params = dict(m["params"])
    params["trim"] = None
    labels = data.labels
    if len(set(labels)) < 2:
        return None
    full = CaseBaseClassifier(**params).fit(data.seqs, labels)
    params["trim"] = float(trim)
    trimmed = CaseBaseClassifier(**params).fit(data.seqs, labels)

    def table(cb: Any) -> tuple[np.ndarray, list[int]]:
        v = np.asarray(cb.problems)
        pres = presence(v if v.ndim == 3 else v[:, None, :])  # (cases, features)
        acts = sorted(set(labels))
        lab = cb.labels.astype(str)
        rows = [
            pres[lab == a].mean(axis=0) if (lab == a).any() else np.full(pres.shape[1], np.nan)
            for a in acts
        ]
        return np.stack(rows), [int((lab == a).sum()) for a in acts]

    init, n_init = table(full.case_base_)
    trim_t, n_trim = table(trimmed.case_base_)
    spread = np.nanmax(init, axis=0) - np.nanmin(init, axis=0)
    # the fluent states only (for clip summaries: their means): a joint angle or position
    # above 0.5 is no feature being present
    picked = state_columns(tuple(full.case_base_.names))
    if picked is not None:
        keep = np.zeros(len(spread), dtype=bool)
        keep[picked[0]] = True
        spread = np.where(keep, spread, -np.inf)
        max_features = min(max_features, int(keep.sum()))
    cols = np.sort(np.argsort(-spread, kind="stable")[:max_features])
    words = list(full.case_base_.words)
    if len(words) != init.shape[1]:  # extra columns (e.g. a mirror-image flag) have no words
        words = [words[i] if i < len(words) else f"feature {i}" for i in range(init.shape[1])]
    return {
        "method": m["name"],
        "trim": float(trim),
        "activities": sorted(set(labels)),
        "features": [words[c] for c in cols],
        "initial": init[:, cols].tolist(),
        "trimmed": trim_t[:, cols].tolist(),
        "cases_initial": n_init,
        "cases_trimmed": n_trim,
    }


def example_clips(results: dict[str, Any]) -> dict[str, PoseSequence]:
    """One example clip per activity (the first in dataset order)."""
    data: Prepared = results["_data"]
    out: dict[str, PoseSequence] = {}
    for i, lab in enumerate(data.labels):
        out.setdefault(str(lab), data.seqs[i])
    return dict(sorted(out.items()))


def public(results: dict[str, Any]) -> dict[str, Any]:
    """``results`` without the in-memory parts (what is written as JSON)."""
    return {k: v for k, v in results.items() if not k.startswith("_")}


def format_table(results: dict[str, Any]) -> str:
    """The comparison as a plain-text table, best first within interpretable/peer groups."""
    head = (
        f"{'method':<22} {'accuracy [95% CI]':<22} {'macro-F1 [95% CI]':<22} "
        f"{'fit s':>8} {'ms/clip':>8} {'cases':>7} {'McNemar p':>10}"
    )
    lines = [head, "-" * len(head)]
    for m in results["methods"]:
        if m["status"] != "ok":
            lines.append(f"{m['name']:<22} {m['status']}: {m['message']}")
            continue
        acc = (
            f"{100 * m['accuracy']:5.1f} [{100 * m['accuracy_ci'][0]:4.1f}, "
            f"{100 * m['accuracy_ci'][1]:5.1f}]"
        )
        f1 = (
            f"{100 * m['macro_f1']:5.1f} [{100 * m['macro_f1_ci'][0]:4.1f}, "
            f"{100 * m['macro_f1_ci'][1]:5.1f}]"
        )
        cases = "" if m["case_base_size"] is None else f"{m['case_base_size']:.0f}"
        p = m["mcnemar_p"]
        pv = "best" if m["name"] == results["best"] else ("<1e-300" if p < 1e-300 else f"{p:.3g}")
        mark = " *" if m["name"] == results["best_interpretable"] else ""
        lines.append(
            f"{m['name'] + mark:<22} {acc:<22} {f1:<22} {m['fit_s']:8.2f} "
            f"{m['predict_ms_per_clip']:8.2f} {cases:>7} {pv:>10}"
        )
    lines += _group_table(results)
    return "\n".join(lines)


def _group_table(results: dict[str, Any]) -> list[str]:
    """Accuracy (%) of every method per model group (e.g. per movement), when there are
    groups: which activities the target is hard to tell in."""
    ok = [m for m in results["methods"] if m["status"] == "ok" and m.get("per_group")]
    if not ok:
        return []
    groups = list(ok[0]["per_group"])
    width = max(len(g) for g in groups) + 2
    within = results["settings"].get("within") or "group"
    names = [m["name"] for m in ok]
    lines = ["", f"accuracy % per {within} (one model each):"]
    cols = [len(n) + 2 for n in names]
    head = "".join(f"{n:>{w}}" for n, w in zip(names, cols, strict=True))
    lines.append(f"{within:<{width}}{head}")
    for g in groups:
        row = "".join(
            f"{100 * m['per_group'][g]['accuracy']:>{w}.1f}" for m, w in zip(ok, cols, strict=True)
        )
        lines.append(f"{g:<{width}}{row}")
    return lines


def csv_rows(results: dict[str, Any]) -> list[dict[str, Any]]:
    """One row per method: the table's figures plus per-class recall."""
    rows = []
    classes = results["dataset"]["classes"]
    for m in results["methods"]:
        row: dict[str, Any] = {
            "method": m["name"],
            "kind": m["kind"],
            "interpretable": m["interpretable"],
            "status": m["status"],
        }
        if m["status"] == "ok":
            row.update(
                {
                    "accuracy": round(m["accuracy"], 6),
                    "accuracy_lo": round(m["accuracy_ci"][0], 6),
                    "accuracy_hi": round(m["accuracy_ci"][1], 6),
                    "macro_f1": round(m["macro_f1"], 6),
                    "macro_f1_lo": round(m["macro_f1_ci"][0], 6),
                    "macro_f1_hi": round(m["macro_f1_ci"][1], 6),
                    "fit_s": round(m["fit_s"], 4),
                    "predict_s": round(m["predict_s"], 4),
                    "case_base_size": m["case_base_size"],
                    "mcnemar_p": m["mcnemar_p"],
                }
            )
            for c in classes:
                row[f"recall:{c}"] = round(m["per_class"][c]["recall"], 6)
        else:
            row["message"] = m["message"]
        rows.append(row)
    return rows


__all__ = [
    "CompareSettings",
    "DTWKNNPeer",
    "LIMB_ANGLES",
    "Method",
    "MiniRocketPeer",
    "Prepared",
    "angle_series",
    "best_cbr",
    "bootstrap_macro_f1",
    "csv_rows",
    "example_clips",
    "explain_dad_errors",
    "explain_errors",
    "format_table",
    "machine_info",
    "macro_f1",
    "make_folds",
    "mcnemar_exact",
    "methods_for",
    "prepare",
    "prevalence",
    "public",
    "run_compare",
    "wilson_interval",
]
