"""``run_compare``: every similarity x feature level, DAD and peer classifiers cross-validated
on the same folds of a labelled dataset, with confidence intervals and a paired test.

Protocol
--------
- Folds: leave-one-subject-out (the default, ``cv=None``; ``cv="loso"`` by name) or stratified
  k-fold over clips (``cv="kfold"``). LOSO needs a subject for every clip and at least two
  subjects (of the clips left once those showing no person, too short or of a class of a
  single clip are left out); otherwise the default falls back to stratified k-fold and says so
  in ``notes`` (scores are then optimistic, because the same person is in training and test),
  and ``cv="loso"`` is refused.
- Classes with a single clip are left out (a held-out single clip can never be predicted right,
  and stratification is impossible); the note names them.
- Target: the activity label (default) or any column of the clip metadata (``correct``,
  ``sensor``, ...). For a target other than the label, one model per activity is trained
  (``within="label"``): e.g. ``target="correct"`` on UI-PRMD predicts correct/incorrect within
  each movement from that movement's training clips, so chance is ~50 % and the movement itself
  is never confused with correctness.
- The work unit is one (method, fold) task (:mod:`cbr.evaluation.tasks`), run by a
  :mod:`cbr.evaluation.runner`: in this process for ``jobs=1``, else in spawned workers that
  each receive the clips once and compute their features once, before their first task.
- Statistics (:mod:`cbr.evaluation.stats`): accuracy with a Wilson 95 % interval; macro-F1 with
  a percentile bootstrap, under leave-one-subject-out over subjects and then the clips of each
  drawn subject (one person's clips share the errors made on that person), else over clips;
  under leave-one-subject-out the accuracy on every subject held out, with its mean, sample
  standard deviation and minimum over the subjects (none under k-fold, whose folds are not
  people); per-class recall with Wilson intervals; McNemar's exact (binomial) test of every method
  against the best one on the same clips.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np

from features.clips import Clip

from ..similarity import get_measure
from .data import Prepared, prepare
from .folds import check_k, check_within, make_folds, unseen_class_notes
from .machine import machine_info
from .methods import Method, add_covers, methods_for, why_unavailable
from .results import ClipInfo, CompareResults, CVSummary, DatasetSummary, MethodResult
from .runner import make_runner
from .scoring import best_methods, score, with_tests
from .settings import CompareSettings
from .tasks import FoldResult, FoldTask, RunContext, missing_levels, prepare_worker, run_fold


@dataclass
class CompareRun:
    """A finished comparison: its results, and the clips and folds (``(n,)``) they came from,
    which explanations and pictures need."""

    results: CompareResults
    data: Prepared
    folds: np.ndarray


def _folds(
    data: Prepared, settings: CompareSettings, given: np.ndarray | None, source: str
) -> tuple[str, np.ndarray, list[str]]:
    """Scheme, fold of every clip ``(n,)`` and notes (``given`` overrides the scheme;
    ``source`` is named by a refusal)."""
    if given is not None:
        return "given", np.asarray(given, dtype=np.int64), []
    scheme, folds, notes = make_folds(data, settings, source)
    if scheme == "loso":
        notes += unseen_class_notes(data, folds)
    return scheme, folds, notes


def _fallback_notes(rows: list[MethodResult]) -> list[str]:
    """Where a model had fewer than two classes to learn from and answered one class for
    its test clips (the same for every method): the figures count those answers."""
    seen = sorted({note for m in rows if m.scores for note in m.scores.fold_notes})
    return [f"{note} (no model trained there; the figures count that answer)" for note in seen]


def _qmp_note(settings: CompareSettings) -> list[str]:
    if "qmp" in settings.features and all(
        get_measure(s).compares_sequences for s in settings.similarities
    ):
        return [
            "qmp features are one vector per clip, compared by euclidean only, which "
            "--similarities leaves out: not compared"
        ]
    if "qmp" in settings.features and any(
        get_measure(s).compares_sequences for s in settings.similarities
    ):
        return [
            "qmp features are one vector per clip: compared by euclidean only (dtw and "
            "signature compare sequences)"
        ]
    return []


def _dad_note(data: Prepared) -> list[str]:
    covered = add_covers(data.classes)
    uncovered = [c for c in data.classes if c not in covered]
    if not uncovered:
        return []
    return [
        f"the ADD has no activity for {', '.join(uncovered)}: DAD cannot recognise those clips "
        "(it answers the best-scoring described activity instead)"
    ]


def _skipped(
    methods: list[Method], data: Prepared, settings: CompareSettings
) -> tuple[dict[int, str], list[str]]:
    """Methods that cannot run here, by index, with the reason; and notes on those that can."""
    skipped: dict[int, str] = {}
    notes: list[str] = []
    for mi, m in enumerate(methods):
        why = why_unavailable(m, data.classes, settings.target)
        if why:
            skipped[mi] = why
        elif m.kind == "dad":
            notes += _dad_note(data)
    runnable = [m for mi, m in enumerate(methods) if mi not in skipped]
    for level, why in missing_levels(data, runnable).items():
        for mi, m in enumerate(methods):
            if m.kind == "cbr" and m.params["features"] == level and mi not in skipped:
                skipped[mi] = why
    return skipped, notes


def _run_tasks(ctx: RunContext, jobs: int, scheduler: str | None = None) -> list[FoldResult]:
    """Every (method, fold) task of the methods that can run (``ctx.active``)."""
    folds = sorted(set(ctx.folds.tolist()))
    tasks = [FoldTask(mi, f) for mi in ctx.active for f in folds]
    runner = make_runner(ctx, prepare_worker, min(jobs, max(1, len(tasks))), scheduler)
    return list(runner.map(run_fold, tasks, "folds", "fold"))


def _method_result(
    mi: int,
    m: Method,
    data: Prepared,
    skipped: dict[int, str],
    fold_results: list[FoldResult],
    settings: CompareSettings,
    subjects: np.ndarray | None = None,
) -> MethodResult:
    """Method ``mi``'s row: skipped, failed (the first fold's error), or scored (``subjects``
    ``(n,)``: every clip's subject under leave-one-subject-out, else None)."""
    head = (m.name, m.kind, m.interpretable, dict(m.params))
    if mi in skipped:
        return MethodResult(*head, "skipped", skipped[mi])
    mine = [r for r in fold_results if r.method == mi]
    errors = [r.error for r in mine if r.error]
    if errors:
        return MethodResult(*head, "failed", errors[0])
    pred = np.empty(len(data.y), dtype=object)
    for r in mine:
        pred[r.test] = r.pred
    return MethodResult(*head, "ok", "", score(data, pred, mine, settings, subjects))


def _status_notes(rows: list[MethodResult]) -> list[str]:
    return [f"{m.name} {m.status}: {m.message}" for m in rows if m.status in ("skipped", "failed")]


def _dataset(data: Prepared, source: str) -> DatasetSummary:
    return DatasetSummary(
        source=source,
        n_clips=len(data.y),
        subjects=sorted({s for s in data.subjects if s is not None}),
        classes=list(data.classes),
        class_counts={c: int((data.y == c).sum()) for c in data.classes},
        activities=sorted(set(data.labels.tolist())),
    )


def _clips(data: Prepared) -> list[ClipInfo]:
    return [
        ClipInfo(
            data.ids[i], str(data.labels[i]), data.subjects[i], str(data.y[i]), data.frames_of(i)
        )
        for i in range(len(data.y))
    ]


def run_compare(
    clips: Sequence[Clip],
    settings: CompareSettings,
    source: str = "dataset",
    fold_indices: np.ndarray | None = None,
) -> CompareRun:
    """Cross-validate every configuration of ``settings`` on ``clips``.

    Returns the results (dataset summary, settings, notes, folds, per-method metrics and
    predictions, the best method and McNemar p-values against it; explanations and pictures
    are added afterwards) with the clips and folds they came from. ``fold_indices``
    ``(n_clips,)`` overrides the fold assignment (tests, fixed splits).
    """
    data = prepare(clips, settings, source)
    scheme, folds, fold_notes = _folds(data, settings, fold_indices, source)
    check_k(settings, folds)
    check_within(data.within, folds, settings.within_column)
    methods = methods_for(settings)
    skipped, method_notes = _skipped(methods, data, settings)
    active = tuple(mi for mi in range(len(methods)) if mi not in skipped)
    ctx = RunContext(data, tuple(methods), folds, active, int(settings.peer_length))
    fold_results = _run_tasks(ctx, int(settings.jobs), settings.scheduler)
    # leave one subject out: a fold is a subject, the bootstrap draws subjects whole and the
    # accuracy is given per subject
    subjects = np.array([str(s) for s in data.subjects]) if scheme == "loso" else None
    rows = [
        _method_result(mi, m, data, skipped, fold_results, settings, subjects)
        for mi, m in enumerate(methods)
    ]
    best, best_interpretable = best_methods(rows)
    results = CompareResults(
        created_utc=datetime.now(UTC).isoformat(timespec="seconds"),
        machine=machine_info(),
        dataset=_dataset(data, source),
        settings=settings.to_dict(),
        cv=CVSummary(
            scheme,
            len(set(folds.tolist())),
            folds.tolist(),
            "clips" if subjects is None else "subjects",
        ),
        notes=data.notes
        + fold_notes
        + _qmp_note(settings)
        + method_notes
        + _fallback_notes(rows)
        + _status_notes(rows),
        clips=_clips(data),
        methods=with_tests(rows, best, int(settings.seed)),
        best=best,
        best_interpretable=best_interpretable,
    )
    return CompareRun(results, data, folds)
