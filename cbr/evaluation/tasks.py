"""One unit of work of a comparison: fit one method on every fold but one and predict that
fold; and the warming each worker does before its first task."""

from __future__ import annotations

import contextlib
import time
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from features.errors import ConfigError, PosecbrError
from features.poses import PoseSequence
from features.progress import progress
from features.text import counted

from .data import Prepared
from .methods import Method, make_estimator
from .peers import angle_series


@dataclass(frozen=True)
class RunContext:
    """What every task reads: the clips, the methods, the fold of every clip ``(n,)``, and
    which methods run (indices into ``methods``; the others were skipped)."""

    data: Prepared
    methods: tuple[Method, ...]
    folds: np.ndarray
    active: tuple[int, ...]
    peer_length: int = 64

    def running(self) -> list[Method]:
        return [self.methods[i] for i in self.active]


@dataclass(frozen=True)
class FoldTask:
    """Method ``method`` (an index into ``RunContext.methods``) on fold ``fold``."""

    method: int
    fold: int


@dataclass
class FoldResult:
    """One task's predictions for the clips of its fold ``test`` ``(n_test,)`` and its
    costs; ``error`` is set (and the predictions partial) when the method failed."""

    method: int
    fold: int
    test: np.ndarray
    pred: np.ndarray
    fit_s: float = 0.0
    predict_s: float = 0.0
    case_base_size: int | None = None
    training_size: int = 0
    error: str | None = None
    notes: list[str] = field(default_factory=list)


class TrimmedBelowK(PosecbrError):
    """A fold's trimming kept fewer cases than the case base votes with (k): the method is
    not scored (``train --trim`` refuses such a case base)."""


def _check_trimmed(est: object, where: str) -> None:
    """Refuse a case base that its trimming (``--trim``, an ``editor``) left with fewer cases
    than k, as ``train`` refuses it: every answer would be the vote of all its cases, and the
    figures those of another k."""
    report = getattr(est, "maintenance_", None)
    k = int(getattr(est, "k", 0))
    if report is not None and report.size_after < k:
        raise TrimmedBelowK(
            f"{where}: trimming kept {report.size_after} of {report.size_before} cases, fewer"
            f" than the {k} the case base votes with (k): not scored (keep more with --trim,"
            " or give a smaller --k)"
        )


def _fit_predict(
    method: Method,
    X_train: list[PoseSequence],
    y_train: np.ndarray,
    X_test: list[PoseSequence],
    where: str = "fold",
) -> tuple[np.ndarray, float, float, int | None]:
    """Predictions ``(n_test,)`` as str, fit and predict seconds, and the case-base size.
    ``where``: the fold (and model group), as a refusal names it."""
    est = make_estimator(method)
    t0 = time.perf_counter()
    est.fit(X_train, y_train)
    _check_trimmed(est, where)
    t1 = time.perf_counter()
    pred = np.asarray(est.predict(X_test), dtype=object)
    t2 = time.perf_counter()
    cb = getattr(est, "case_base_", None)
    size = None if cb is None else len(cb)
    return np.array([str(p) for p in pred], dtype=object), t1 - t0, t2 - t1, size


def _one_class_note(group: object, present: list[str], fallback: str, n_test: int) -> str:
    lead = "" if group is None else f"{group}: "
    has = "only " + repr(present[0]) if present else "no clips"
    tested = counted(n_test, "test clip")
    return f"{lead}training fold has {has}; predicted {fallback!r} for its {tested}"


def _run_group(
    ctx: RunContext, out: FoldResult, train: np.ndarray, test: np.ndarray, group: object
) -> None:
    """Fit on ``train`` and predict ``test`` (clip indices of one model group) into ``out``."""
    data = ctx.data
    where = np.isin(out.test, test)
    y_train = data.y[train]
    present = sorted(set(y_train))
    if len(present) < 2:
        # One class (or none) to learn from: every prediction is that class.
        everyone = data.y[np.flatnonzero(ctx.folds != out.fold)]
        fallback = present[0] if present else Counter(everyone).most_common(1)[0][0]
        out.pred[where] = fallback
        out.notes.append(_one_class_note(group, present, fallback, len(test)))
        return
    pred, fit_s, predict_s, size = _fit_predict(
        ctx.methods[out.method],
        [data.seqs[i] for i in train],
        y_train,
        [data.seqs[i] for i in test],
        fold_name(ctx, out.fold) + ("" if group is None else f", {group}"),
    )
    out.pred[where] = pred
    out.fit_s += fit_s
    out.predict_s += predict_s
    if size is not None:
        out.case_base_size = (out.case_base_size or 0) + size


def fold_name(ctx: RunContext, fold: int) -> str:
    """A fold in words: its number as the results' ``fold_of_clip`` gives it, and the subject
    it holds out when it holds out one (leave one subject out: every clip of one subject,
    none of whose clips is trained on; not k folds of a one-subject dataset)."""
    subjects = np.array(ctx.data.subjects, dtype=object)
    held = set(subjects[ctx.folds == fold].tolist())
    subject = next(iter(held)) if len(held) == 1 else None
    if subject is None or subject in set(subjects[ctx.folds != fold].tolist()):
        return f"fold {fold}"
    return f"fold {fold} (subject {subject} held out)"


def run_fold(ctx: RunContext, task: FoldTask) -> FoldResult:
    """Train method ``task.method`` on every fold but ``task.fold`` and predict that fold (per
    group when the comparison trains one model per activity)."""
    test = np.flatnonzero(ctx.folds == task.fold)
    train = np.flatnonzero(ctx.folds != task.fold)
    out = FoldResult(
        task.method, task.fold, test, np.empty(len(test), dtype=object), training_size=len(train)
    )
    within = ctx.data.within
    groups = [None] if within is None else sorted(set(within[test]))
    try:
        for g in groups:
            te = test if within is None else test[within[test] == g]
            tr = train if within is None else train[within[train] == g]
            _run_group(ctx, out, tr, te, g)
    except PosecbrError as exc:
        out.error = str(exc)
    return out


def missing_levels(data: Prepared, methods: list[Method]) -> dict[str, str]:
    """The feature levels this build cannot compute at all, each with the reason (tried on the
    first clip; a single clip's own problem is left to the folds)."""
    from ..problem import FeatureConfig, extract_problem

    levels = {m.params["features"] for m in methods if m.kind == "cbr"}
    missing = {}
    if "qmp" in levels:
        try:
            extract_problem(data.seqs[0], FeatureConfig(level="qmp"))
        except ConfigError as exc:
            missing["qmp"] = exc.message
        except PosecbrError:
            pass
    return missing


def warm_features(ctx: RunContext) -> None:
    """Compute every clip's features once (fluents, QMPs, peer angle series) so that no fold
    recomputes them and no fit is billed for them. Best effort: a clip that fails is left to
    the folds, which report the method as failed with the clip's error."""
    from ..problem import FeatureConfig, extract_problem, resolve_config

    methods = ctx.running()
    fluents = any(m.kind == "cbr" and m.params["features"] == "fluents" for m in methods)
    qmp = any(m.kind == "cbr" and m.params["features"] == "qmp" for m in methods)
    angles = any(m.kind == "peer" for m in methods)
    seqs = ctx.data.seqs
    for seq in progress(seqs, "features", total=len(seqs), unit="clip"):
        with contextlib.suppress(PosecbrError):
            if fluents:
                resolve_config(FeatureConfig(level="fluents"), [seq])  # fills the fluent cache
        with contextlib.suppress(PosecbrError):
            if qmp:
                extract_problem(seq, FeatureConfig(level="qmp"))  # fills the QMP cache
        with contextlib.suppress(PosecbrError):
            if angles:
                angle_series(seq, ctx.peer_length)


def warm_compilers(ctx: RunContext) -> None:
    """Fit and predict every method once on two clips of different classes, untimed, so that
    just-in-time compilation (numba in tslearn, sktime and the DTW measure: up to tens of
    seconds) is not billed to the first fold's training or prediction time. Best effort: any
    error here is left for the folds to report."""
    data = ctx.data
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
    methods = ctx.running()
    for m in progress(methods, "compiling", total=len(methods), unit="method"):
        with contextlib.suppress(Exception):
            make_estimator(m).fit(X, y).predict(X[:1])


def prepare_worker(ctx: RunContext) -> None:
    """What a worker does before its first task: features, then compilers."""
    warm_features(ctx)
    warm_compilers(ctx)
