"""The statistics of a comparison: Wilson interval and McNemar's exact test from scipy,
macro-F1 from scikit-learn, and a percentile bootstrap of macro-F1 over clips, or over the
subjects they come from and their clips; with the person as the unit, a bootstrap of the
accuracy over the same people and clips and Wilcoxon's signed-rank test on their
accuracies."""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import PermutationMethod, binomtest, wilcoxon
from sklearn.metrics import f1_score


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval for ``successes / n`` (``(nan, nan)`` if ``n == 0``).

    From ``scipy.stats.binomtest(...).proportion_ci(method="wilson")``, clipped to [0, 1] and
    made to hold the proportion itself: rounding can put a bound a hair past it (an upper bound
    of 0.9999999999999999 at 100 %), which plots as a negative error bar.
    """
    if n <= 0:
        return (math.nan, math.nan)
    ci = binomtest(int(successes), int(n)).proportion_ci(
        confidence_level=confidence, method="wilson"
    )
    p = successes / n
    return (min(max(float(ci.low), 0.0), p), max(min(float(ci.high), 1.0), p))


def mcnemar_exact(b: int, c: int) -> float:
    """Two-sided exact McNemar p-value from the discordant counts ``b`` (only the first method
    right) and ``c`` (only the second right): binomial test of min(b, c) in b + c at 1/2."""
    if b + c == 0:
        return 1.0
    return float(binomtest(min(b, c), b + c, 0.5).pvalue)


#: Wilcoxon's test is exact (every sign pattern) up to this many people whose accuracies differ
EXACT_PEOPLE = 16


def signed_rank(differences: np.ndarray, seed: int = 0) -> tuple[int, float, float]:
    """Wilcoxon's signed-rank test of paired differences ``(m,)`` (one per person: this
    method's accuracy on them less the other's): the people whose accuracies differ, the
    smaller of the two rank sums ``W`` and the two-sided p-value.

    Equal accuracies are left out (Wilcoxon's own rule) and tied absolute differences share
    their mid-rank; the p-value is the share of the ``2 ** n`` ways of signing the ranks
    whose rank sum lies at least as far from its mean as the one seen
    (``scipy.stats.wilcoxon`` with a ``PermutationMethod`` that enumerates them all), so it
    is exact with ties too, up to :data:`EXACT_PEOPLE` people; beyond, ``2 ** 16`` random
    signings drawn with ``seed``. With ``n`` people the smallest p-value is
    ``2 / 2 ** n``: 0.25 for 3, 0.0625 for 5. The differences are rounded to 12 decimals
    so that accuracies that are the same fraction tie. No difference at all: ``(0, 0, 1)``.
    """
    d = np.round(np.asarray(differences, dtype=float), 12)
    d = d[d != 0]
    if len(d) == 0:
        return 0, 0.0, 1.0
    method = PermutationMethod(n_resamples=2**EXACT_PEOPLE, rng=np.random.default_rng(seed))
    res = wilcoxon(d, method=method)
    return len(d), float(res.statistic), min(1.0, float(res.pvalue))


def bootstrap_accuracy(
    correct: np.ndarray,
    groups: np.ndarray,
    n_boot: int = 1000,
    confidence: float = 0.95,
    seed: int = 0,
) -> tuple[float, float]:
    """Percentile bootstrap interval of the accuracy over people and their clips.

    correct: ``(n,)`` every clip right or not; groups: ``(n,)`` its person (subject held
    out). The resamples are :func:`bootstrap_macro_f1`'s with the same ``groups`` and
    ``seed``, clip for clip: the ``g`` people drawn with replacement, then each drawn
    person's ``m`` clips drawn ``m`` times; each resample's accuracy is its clips' share
    right. Drawing people alone (each with all their clips) leaves the bootstrap variance
    ``(g - 1) / g`` of the true one and, with 3 to 8 people, a percentile interval near
    the range of the people's accuracies: simulated with a known spread between people it
    held the population's accuracy 70-90 % of the time for a nominal 95 %; drawing their
    clips too counts the noise within a person twice (Davison and Hinkley 1997, section
    3.8) and held it 75-99.5 % of the time, never less often (docs/measurements.md, hunt
    53w). With three people who differ much it still holds it only about 75 % of the time;
    ``(nan, nan)`` without clips.
    """
    correct = np.asarray(correct, dtype=float)
    if len(correct) == 0:
        return (math.nan, math.nan)
    idx, boot = _two_stage(np.random.default_rng(seed), np.asarray(groups), n_boot)
    acc = np.bincount(boot, weights=correct[idx], minlength=n_boot) / np.bincount(
        boot, minlength=n_boot
    )
    alpha = (1.0 - confidence) / 2.0
    lo, hi = np.quantile(acc, [alpha, 1.0 - alpha])
    return (float(lo), float(hi))


def macro_f1(y_true: np.ndarray, y_pred: np.ndarray) -> float:
    """Macro-F1 of labels ``(n,)`` over the classes present in truth or prediction
    (``sklearn.metrics.f1_score(average="macro")``)."""
    return float(f1_score(y_true, y_pred, average="macro", zero_division=0))


def _f1_from_counts(tp: np.ndarray, fp: np.ndarray, fn: np.ndarray) -> np.ndarray:
    """Macro-F1 over the last axis; classes never seen in truth or prediction are left out."""
    denom = 2 * tp + fp + fn
    with np.errstate(invalid="ignore", divide="ignore"):
        f1 = np.where(denom > 0, 2 * tp / np.where(denom > 0, denom, 1), np.nan)
    return np.asarray(np.nanmean(f1, axis=-1))


def _two_stage(
    rng: np.random.Generator, groups: np.ndarray, n_boot: int
) -> tuple[np.ndarray, np.ndarray]:
    """The clips of :func:`bootstrap_macro_f1`'s two-stage resamples, flat, and the resample
    each belongs to, both ``(total,)``: ``g`` groups drawn with replacement per resample,
    then, in each drawn group, as many of its clips as it has, drawn with replacement."""
    _, code, n_of = np.unique(np.asarray(groups), return_inverse=True, return_counts=True)
    code = code.ravel()
    members = np.argsort(code, kind="stable")  # the clips of group 0, then of group 1, ...
    start = np.concatenate([[0], np.cumsum(n_of)[:-1]])
    draws = rng.integers(0, len(n_of), size=(n_boot, len(n_of)))
    sizes = n_of[draws]
    group = np.repeat(draws.ravel(), sizes.ravel())
    pos = np.floor(rng.random(len(group)) * n_of[group]).astype(np.int64)
    return members[start[group] + pos], np.repeat(np.arange(n_boot), sizes.sum(axis=1))


def bootstrap_macro_f1(
    y_true: np.ndarray,
    y_pred: np.ndarray,
    n_classes: int,
    n_boot: int = 1000,
    confidence: float = 0.95,
    seed: int = 0,
    groups: np.ndarray | None = None,
) -> tuple[float, float]:
    """Percentile bootstrap interval of macro-F1, resampling clips, or groups and then clips
    within them.

    y_true, y_pred: ``(n,)`` integer class codes below ``n_classes``. groups None: the clips
    are resampled, ``default_rng(seed).integers(0, n, (n_boot, n))``. groups ``(n,)``: the
    clips' groups (their subjects under leave-one-subject-out, where one person's clips share
    what the model gets wrong about that person), resampled in two stages with
    ``rng = default_rng(seed)``: the ``g`` distinct groups, sorted, drawn ``g`` times per
    resample (``rng.integers(0, g, (n_boot, g))``); then every drawn group's ``m`` clips
    drawn ``m`` times, its ``j``-th clip in dataset order where ``j = floor(u * m)`` and the
    ``u`` are ``rng.random(total)`` taken in order, resample by resample and drawn group by
    drawn group. Clips alone leave out how people differ; groups alone leave out the noise
    within a person and, with 3 to 8 people, cover too seldom (:func:`bootstrap_accuracy`,
    which draws the same resamples).

    Every resample is counted at once as ``(n_boot, n_classes)`` true-positive, false-positive
    and false-negative tables: the same figures as ``f1_score`` per resample (tested), in a
    tenth of the time or less: 1000 ``f1_score`` calls on 1600 clips take about 3 s, for
    every method of a comparison.
    """
    n = len(y_true)
    if n == 0:
        return (math.nan, math.nan)
    rng = np.random.default_rng(seed)
    if groups is None:
        idx = rng.integers(0, n, size=(n_boot, n)).ravel()
        boot = np.repeat(np.arange(n_boot), n)
    else:
        idx, boot = _two_stage(rng, groups, n_boot)
    t = y_true[idx] + boot * n_classes
    p = y_pred[idx] + boot * n_classes
    size = n_boot * n_classes
    hit = y_true[idx] == y_pred[idx]
    tp = np.bincount(t[hit], minlength=size).reshape(n_boot, n_classes)
    n_pred = np.bincount(p, minlength=size).reshape(n_boot, n_classes)
    n_true = np.bincount(t, minlength=size).reshape(n_boot, n_classes)
    f1 = _f1_from_counts(tp.astype(float), (n_pred - tp).astype(float), (n_true - tp).astype(float))
    alpha = (1.0 - confidence) / 2.0
    lo, hi = np.quantile(f1, [alpha, 1.0 - alpha])
    return (float(lo), float(hi))
