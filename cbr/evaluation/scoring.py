"""From a method's predictions to its figures (``Scores``), the best methods, and McNemar's test
of every method against the best on the same clips, with Wilcoxon's over the subjects held
out."""

from __future__ import annotations

import dataclasses

import numpy as np

from .data import Prepared
from .results import McNemar, MethodResult, Rate, Scores, SignedRank
from .settings import CompareSettings
from .stats import (
    bootstrap_accuracy,
    bootstrap_macro_f1,
    macro_f1,
    mcnemar_exact,
    signed_rank,
    wilson_interval,
)
from .tasks import FoldResult


def _rate(hits: np.ndarray) -> Rate:
    """Share of True in ``hits`` ``(n,)`` with its Wilson interval."""
    n, k = len(hits), int(hits.sum())
    return Rate(n, k / max(1, n), wilson_interval(k, n))


def _per_group(data: Prepared, correct: np.ndarray) -> dict[str, Rate]:
    """Accuracy per model group (one model per movement, say); empty without groups."""
    if data.within is None:
        return {}
    return {str(g): _rate(correct[data.within == g]) for g in sorted(set(data.within.tolist()))}


def _per_subject(subjects: np.ndarray | None, correct: np.ndarray) -> dict[str, Rate]:
    """Accuracy on every subject held out (sorted); empty when subjects were not held out
    one by one."""
    if subjects is None:
        return {}
    return {str(p): _rate(correct[subjects == p]) for p in sorted(set(subjects.tolist()))}


def _people_ci(
    subjects: np.ndarray | None, correct: np.ndarray, settings: CompareSettings
) -> tuple[float, float] | None:
    """The accuracy's bootstrap interval over the subjects held out and their clips (the
    resamples of macro-F1's interval); None without them."""
    if subjects is None:
        return None
    return bootstrap_accuracy(correct, subjects, int(settings.bootstrap), seed=int(settings.seed))


def _mean_case_base(results: list[FoldResult]) -> float | None:
    """Cases kept after trimming, mean over the folds that built a case base."""
    sizes = [r.case_base_size for r in results if r.case_base_size is not None]
    return float(np.mean(sizes)) if sizes else None


def score(
    data: Prepared,
    pred: np.ndarray,
    results: list[FoldResult],
    settings: CompareSettings,
    subjects: np.ndarray | None = None,
) -> Scores:
    """The figures of one method from its predictions ``(n,)`` of every clip's target.

    subjects: ``(n,)`` every clip's subject under leave-one-subject-out: macro-F1's bootstrap
    resamples them, then their clips, the accuracy is given per subject and with a bootstrap
    interval over the same resamples; None (k-fold) to resample clips, with neither.

    A prediction outside the target classes (e.g. DAD's answer for an activity the target
    does not name) counts as wrong and is kept in ``unassigned``.
    """
    classes = data.classes
    code = {c: i for i, c in enumerate(classes)}
    other = len(classes)
    t = np.array([code[v] for v in data.y])
    p = np.array([code.get(str(v), other) for v in pred])
    correct = t == p
    confusion = np.zeros((len(classes), len(classes) + 1), dtype=np.int64)
    np.add.at(confusion, (t, p), 1)
    n = len(t)
    predict_s = sum(r.predict_s for r in results)
    return Scores(
        accuracy=float(correct.mean()),
        accuracy_ci=wilson_interval(int(correct.sum()), n),
        macro_f1=macro_f1(t, p),
        macro_f1_ci=bootstrap_macro_f1(
            t, p, other + 1, int(settings.bootstrap), seed=int(settings.seed), groups=subjects
        ),
        per_class={c: _rate(correct[t == i]) for c, i in code.items()},
        per_group=_per_group(data, correct),
        confusion=confusion[:, :other].tolist(),
        unassigned=confusion[:, other].tolist(),
        fit_s=sum(r.fit_s for r in results),
        predict_s=predict_s,
        predict_ms_per_clip=1000.0 * predict_s / max(1, n),
        case_base_size=_mean_case_base(results),
        training_size=float(np.mean([r.training_size for r in results])),
        predictions=[str(v) for v in pred],
        correct=correct.tolist(),
        fold_notes=sorted({note for r in results for note in r.notes}),
        per_subject=_per_subject(subjects, correct),
        accuracy_ci_people=_people_ci(subjects, correct, settings),
    )


def _key(ms: tuple[MethodResult, Scores]) -> tuple[float, float]:
    return (ms[1].accuracy, ms[1].macro_f1)


def best_methods(methods: list[MethodResult]) -> tuple[str | None, str | None]:
    """The most accurate method and the most accurate interpretable one (ties: macro-F1)."""
    ok = [(m, m.scores) for m in methods if m.scores is not None]
    if not ok:
        return None, None
    interp = [ms for ms in ok if ms[0].interpretable]
    return max(ok, key=_key)[0].name, max(interp, key=_key)[0].name if interp else None


def _signed_rank(ref: Scores, cur: Scores, versus: str, seed: int) -> SignedRank | None:
    """Wilcoxon's test of ``cur`` against ``ref`` over the subjects held out; None without."""
    if not cur.per_subject or set(cur.per_subject) != set(ref.per_subject):
        return None
    d = [cur.per_subject[p].value - ref.per_subject[p].value for p in cur.per_subject]
    n, w, p = signed_rank(np.array(d), seed)
    return SignedRank(versus, n, w, p)


def with_tests(methods: list[MethodResult], best: str | None, seed: int = 0) -> list[MethodResult]:
    """Every method that ran, tested against ``best``: on the same clips (exact McNemar)
    and, under leave-one-subject-out, on the same people (Wilcoxon's signed-rank test of
    their accuracies, ``seed`` for its random signings past 16 people)."""
    ref = next((m.scores for m in methods if m.name == best), None)
    if ref is None:
        return methods
    right = np.array(ref.correct)
    out = []
    for m in methods:
        if m.scores is not None:
            cur = np.array(m.scores.correct)
            b, c = int((right & ~cur).sum()), int((~right & cur).sum())
            test = McNemar(str(best), b, c, mcnemar_exact(b, c))
            people = _signed_rank(ref, m.scores, str(best), seed)
            scores = dataclasses.replace(m.scores, mcnemar=test, wilcoxon=people)
            m = dataclasses.replace(m, scores=scores)
        out.append(m)
    return out
