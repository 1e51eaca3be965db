"""Does the default unknown judge's held-out scan, corrected for the one person fewer it
measures against, catch more left-out movements on people not in the case base? (Issue 14.)

The judges are calibrated on the case base's held-out scan (:func:`cbr.unknown.
held_out_activities`): each training person's cases against the case base without that
person, so against ONE PERSON FEWER than a new person meets; their cases lie farther from
the rest than a new person's known windows lie from the case base (``benchmarks.
unknown_bounds``). Here the scan is also taken per other person (:func:`people_scan`): how
near each held-out case lies to every activity of each other training person, from which a
scan leaving out a second person too is read, and the change from that one (P-2 people) to
the ordinary one (P-1) is carried on to P (:func:`extrapolated`, :func:`median_scaled`).

Run: ``python -m benchmarks.unknown_extrapolate [--datasets ...] [--train-people 1] [--cache
DIR]``; writes ``benchmarks/results/unknown_extrapolate.json`` (``unknown_extrapolate_1.json``
with ``--train-people 1``, where every rule is the default judge: a case base of one person
has no second person to leave out). The folds, windows and tallies are those of
:mod:`benchmarks.unknown_bounds` (known windows kept / left-out windows unknown, pooled over
the left-out movements). The rules, each fixed before its figures on the test windows were
looked at, each a corrected scan the default judge (``spread-margin``: rate, prior, power,
spreads and thresholds) is calibrated on as it is on the ordinary one:

- ``jackknife``: every held-out case's distance to every activity, ``X1`` (the nearest
  other person's), moved as ``log D = log X1 - gamma * delta``: ``delta = (log X2 - log X1)
  / n`` is how much leaving out one more of the ``n`` other people who did the activity
  raises ``log X1`` on average (``X2`` the second-nearest person's), ``gamma = (n - 1) / (n
  + 1)`` carries it on to one person more if ``E[log d]`` goes as ``c + b / n``;
- ``same step``: ``gamma = 1``, the change from P-2 to P-1 people taken as the change from
  P-1 to P;
- ``median ratio``: every distance times the ratio of the held-out known cases' median
  nearest distance to their median nearest distance with a second person left out (each in
  turn, pooled): the margins stay, the spreads shrink;
- ``one more person``: each person's distance to an activity taken as an independent draw
  from one distribution per activity and kind (the activity's own held-out cases, the
  others'), an entry of the scan the least of ``n`` people's, moved to where the least of
  ``n + 1`` would lie at the same survival (:func:`one_more_person`): defined with one other
  person too, as in HDM05's folds of two training people, where the three above change
  nothing (``n`` 1: no second person to leave out);
- ``chosen``: the correction (or none) the case base itself picks, each training person in
  turn standing in for a new person against the case base of the others
  (:func:`choose_correction`; fixed after the four above were seen, before its own figures);
- each also with ``spread-far``'s far bound read from the corrected scan (``... + far``);
  ``spread-far`` (uncorrected) for comparison.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

from pathlib import Path  # noqa: E402
from types import SimpleNamespace  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import unknown_bounds  # noqa: E402
from benchmarks.repetitions import Group  # noqa: E402
from benchmarks.segment_people import Fold  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "unknown_extrapolate.json"
CORRECTIONS = ("jackknife", "same step", "median ratio", "one more person")
RULES = ("spread-margin", "spread-far",
         *(f"{c}{far}" for far in ("", " + far") for c in (*CORRECTIONS, "chosen")))  # fmt: skip
CHOICE_SLACK = 0.01
"""How many fewer of the stand-in new people's known cases (a share) a correction may keep
than the uncorrected judge when :func:`choose_correction` chooses it."""


# ---------------------------------------------------------------- the scan per person


def people_scan(cb: Any, sample: int | None = None, seed: int = 0) -> tuple[Any, np.ndarray]:
    """The held-out scan :func:`cbr.unknown.held_out_activities` makes (the same cases) and,
    for each held-out case, its distance to the nearest case of every activity done by each
    person ``(n, n_people, n_classes)``: inf for the case's own person (held out) and where
    the person did not do the activity. People are the case base's subjects, in sorted
    order; the second array is empty ``(n, 0, n_classes)`` when the scan does not hold out
    people (basis not "subject"). Its minimum over people is the scan's own distances."""
    from cbr.unknown_held_out import (
        MARGIN_SAMPLE,
        activity_codes,
        held_out_activities,
        held_out_rows,
        per_activity,
    )

    sample = MARGIN_SAMPLE if sample is None else sample
    held = held_out_activities(cb, sample, seed)
    seen, codes, basis, groups = held
    if basis != "subject":
        return held, np.zeros((len(seen), 0, seen.shape[1]))
    everyone = np.array([s or "" for s in cb.subjects], dtype=object)
    people = sorted(set(everyone.tolist()))
    labels = np.asarray(cb.labels).astype(str)
    classes = sorted(set(labels.tolist()))
    all_codes = activity_codes(labels, classes)
    index, reps = cb.index, cb.reps
    real = held_out_rows(cb, sample, seed)
    out = np.full((len(real), len(people), len(classes)), np.inf)
    for row, i in enumerate(real.tolist()):
        d = cb.measure.distances(reps[i], index)
        for k, p in enumerate(people):
            if p != everyone[i]:
                out[row, k] = per_activity(np.where(everyone == p, d, np.inf), all_codes,
                                           len(classes))  # fmt: skip
    return held, out


def _steps(people: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(X1, delta, n)`` each ``(n_cases, n_classes)`` of a per-person scan ``(n_cases,
    n_people, n_classes)``: the nearest person's distance, the mean rise of ``log X1`` when
    one of the ``n`` people who did the activity is left out too (``(log X2 - log X1) / n``;
    0 where ``n < 2``, ``X1`` is 0 or ``X2`` inf) and ``n``."""
    ranked = np.sort(people, axis=1)
    x1, x2 = ranked[:, 0, :], ranked[:, 1, :]
    n = np.isfinite(people).sum(axis=1)
    ok = (n >= 2) & (x1 > 0.0) & np.isfinite(x2)
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = np.where(ok, (np.log(np.where(ok, x2, 1.0)) - np.log(np.where(ok, x1, 1.0)))
                         / np.maximum(n, 1), 0.0)  # fmt: skip
    return x1, delta, n


def extrapolated(people: np.ndarray, correction: str) -> np.ndarray:
    """The scan's distances ``(n_cases, n_classes)`` carried on to one person more, from the
    per-person scan ``people`` (:func:`people_scan`): ``X1 * exp(-gamma * delta)``
    (:func:`_steps`), ``gamma`` ``(n - 1) / (n + 1)`` for "jackknife", 1 for "same step"."""
    x1, delta, n = _steps(people)
    if correction == "jackknife":
        gamma = (n - 1.0) / np.maximum(n + 1.0, 1.0)
    elif correction == "same step":
        gamma = np.ones_like(delta)
    else:
        raise ValueError(f"unknown correction {correction!r}")
    return np.asarray(x1 * np.exp(-gamma * delta))


def second_left_out(rows: np.ndarray) -> np.ndarray:
    """The nearest distance of every held-out case of the per-person scan ``rows``
    ``(n_cases, n_people, n_classes)`` with each other person (one the case is measured
    against) left out too, in turn, pooled (the finite ones)."""
    fewer = []
    for k in range(rows.shape[1]):
        there = np.isfinite(rows[:, k, :]).any(axis=1)
        others = np.delete(rows, k, axis=1).min(axis=(1, 2))
        fewer.append(others[there & np.isfinite(others)])
    return np.concatenate(fewer) if fewer else np.zeros(0)


def median_ratio(people: np.ndarray, codes: np.ndarray) -> float:
    """The held-out known cases' (:func:`cbr.unknown.known_rows` of the scan, the minimum of
    ``people`` over people) median nearest distance over their median nearest distance with
    each other person left out in turn too (pooled; a person whose leaving leaves a case no
    activity is not counted); 1 when either is not positive or there is no such case."""
    from cbr.unknown_held_out import known_rows

    seen = people.min(axis=1) if people.shape[1] else np.zeros((len(people), 0))
    if not people.shape[1] or not len(people):
        return 1.0
    keep = known_rows(seen, codes)
    d1 = seen[keep].min(axis=1)
    pooled = second_left_out(people[keep])
    if not len(d1) or not len(pooled):
        return 1.0
    a, b = float(np.median(d1)), float(np.median(pooled))
    return a / b if a > 0.0 and b > 0.0 else 1.0


def one_more_person(seen: np.ndarray, codes: np.ndarray, people: np.ndarray) -> np.ndarray:
    """The scan's distances ``seen`` ``(n_cases, n_classes)`` (held-out cases of activities
    ``codes``) as the least of one person more: each person's distance to an activity taken
    as an independent draw from one distribution per column and kind (own: the column's
    activity's held-out cases; cross: the others'), an entry the least of its ``n`` people's
    (``people``, :func:`people_scan`), whose survival ``S ** n`` becomes ``S ** (n + 1)`` for
    one person more. Each finite entry at ``F = (rank - 0.5) / m`` in its pool of ``m`` is
    moved to the pool's quantile ``1 - (1 - F) ** (n / (n + 1))``. Works with one other
    person (``n`` 1); an entry without a person (``n`` 0) stays."""
    out = seen.astype(np.float64, copy=True)
    n = np.isfinite(people).sum(axis=1)
    for a in range(seen.shape[1]):
        for kind in (codes == a, codes != a):
            rows = kind & np.isfinite(seen[:, a]) & (n[:, a] >= 1)
            pool = seen[rows, a]
            if not len(pool):
                continue
            order = np.argsort(pool, kind="stable")
            f = np.empty(len(pool))
            f[order] = (np.arange(len(pool)) + 0.5) / len(pool)
            e = n[rows, a] / (n[rows, a] + 1.0)
            out[rows, a] = np.quantile(pool, 1.0 - (1.0 - f) ** e)
    return out


def corrected(held: Any, people: np.ndarray, correction: str) -> Any:
    """The held-out scan ``held`` with its distances corrected by ``correction`` (of
    :data:`CORRECTIONS`); ``held`` itself when it does not hold out people."""
    seen, codes, basis, groups = held
    if basis != "subject" or not people.shape[1] or correction == "none":
        return held
    if correction == "median ratio":
        fixed = seen * median_ratio(people, codes)
    elif correction == "one more person":
        fixed = one_more_person(seen, codes, people)
    else:
        fixed = extrapolated(people, correction)
    return fixed, codes, basis, groups


def choose_correction(labels: Any, held: Any, people: np.ndarray) -> tuple[str, dict[str, Any]]:
    """The correction (of ``none`` and :data:`CORRECTIONS`) the case base itself says to use,
    and each one's tally ``[known kept, known, novel unknown, novel]``: each training person
    in turn stands in for a new person, the case base without them calibrated on its own
    scan (the other rows without that person's column: one person fewer still) so corrected,
    their held-out cases (their rows of the scan) judged, known (:func:`cbr.unknown.
    known_rows`) and novel (their own activity gone, :func:`cbr.unknown.known_and_novel`),
    pooled. The one that calls most novel cases unknown while keeping known ones within
    :data:`CHOICE_SLACK` of ``none``'s (a tie: the first, ``none`` first). ``none`` without
    three people to stand in for (or when a stand-in's case base cannot be calibrated)."""
    from cbr.unknown_held_out import known_and_novel
    from cbr.unknown_judges import SpreadMargin
    from features.errors import DataError

    seen, codes, basis, groups = held
    names = sorted(set(groups.tolist()))
    candidates = ("none", *CORRECTIONS)
    tally = {c: np.zeros(4, dtype=np.int64) for c in candidates}
    if basis != "subject" or people.shape[1] < 3 or len(names) != people.shape[1]:
        return "none", {}
    cb = SimpleNamespace(labels=labels)
    for k, name in enumerate(names):
        mine = groups == name
        rest = np.delete(people[~mine], k, axis=1)
        sub = (rest.min(axis=1), codes[~mine], "subject", groups[~mine])
        known, novel = known_and_novel(seen[mine], codes[mine])
        try:
            made = {c: SpreadMargin.of(cb, held=sub if c == "none" else corrected(sub, rest, c))  # type: ignore[arg-type]
                    for c in candidates}  # fmt: skip
        except DataError:
            return "none", {}
        for c, j in made.items():
            unknown_known = sum(bool(j.unlike(r)) for r in known)
            tally[c] += [len(known) - unknown_known, len(known),
                         sum(bool(j.unlike(r)) for r in novel), len(novel)]  # fmt: skip
    share = {c: (t[0] / max(t[1], 1), t[2] / max(t[3], 1)) for c, t in tally.items()}
    within = [c for c in candidates if share[c][0] >= share["none"][0] - CHOICE_SLACK - 1e-12]
    best = max(within, key=lambda c: (share[c][1], -candidates.index(c)))
    return best, {c: t.tolist() for c, t in tally.items()}


def judges(labels: Any, held: Any, people: np.ndarray) -> dict[str, Any]:
    """Every rule of :data:`RULES` but the first two's judge, calibrated on its corrected
    scan; ``labels`` the case base's (the margin judges need three activities)."""
    from cbr.unknown_judges import SpreadFar, SpreadMargin

    cb = SimpleNamespace(labels=labels)
    out: dict[str, Any] = {}
    chosen, _ = choose_correction(labels, held, people)
    for c in (*CORRECTIONS, "chosen"):
        fixed = corrected(held, people, chosen) if c == "chosen" else corrected(held, people, c)
        inner = SpreadMargin.of(cb, held=fixed)  # type: ignore[arg-type]
        out[c] = inner
        out[f"{c} + far"] = SpreadFar.bounding(inner, fixed)
    return out


# ---------------------------------------------------------------- measuring


def measure(fold: Fold, joined: list[tuple[Any, Group]], movement: str) -> dict[str, Any]:
    """:func:`benchmarks.unknown_bounds.measure` (made here: the case base is needed) and the
    per-person scan of the case base (:func:`people_scan`) with its labels."""
    from benchmarks.segment import judge_named
    from benchmarks.segment_people import fit, training_clips
    from benchmarks.unknown_bounds import JUDGE, recordings_measured

    clf = fit(training_clips(joined, leave_out=movement))
    recs = recordings_measured(clf, fold)
    judge = judge_named(clf, JUDGE)
    held, people = people_scan(clf.case_base_)
    labels = np.asarray(clf.case_base_.labels).astype(str)
    return {"cases": len(clf.case_base_), "judge": judge, "held": held, "people": people,
            "labels": labels, "recordings": recs}  # fmt: skip


def decide(movement: str, measured: dict[str, Any]) -> dict[str, np.ndarray]:
    """Per rule of :data:`RULES`: the tally ``[known kept, known, novel unknown, novel]`` of
    one left-out movement's case base (``measured``: :func:`measure`)."""
    from cbr.unknown import for_person
    from cbr.unknown_judges import SpreadFar

    judge, held = measured["judge"], measured["held"]
    rules: dict[str, Any] = {"spread-margin": judge,
                             "spread-far": SpreadFar.bounding(judge, held)}  # fmt: skip
    rules.update(judges(measured["labels"], held, measured["people"]))
    out = {rule: np.zeros(4, dtype=np.int64) for rule in RULES}
    for r in measured["recordings"].values():
        is_novel = np.array([m == movement for m in r["movements"]], dtype=bool)
        is_known = np.array([m is not None and m != movement for m in r["movements"]], dtype=bool)
        for rule, j in rules.items():
            mine = for_person(j, r["counted_d1"])
            pairs = zip(r["still"], r["nearest"], strict=True)
            u = np.array([s or mine.unlike(n) for s, n in pairs], dtype=bool)
            out[rule] += [int(np.sum(~u[is_known])), int(is_known.sum()),
                          int(np.sum(u[is_novel])), int(is_novel.sum())]  # fmt: skip
    return out


def quantiles(measured: dict[str, Any], movement: str) -> dict[str, float]:
    """The diagnostic: the 95 % quantile of the nearest distance of the held-out known cases
    with a second person left out too (pooled), of the scan's (P-1), of each correction's,
    and of the test people's known windows (P)."""
    from cbr.unknown_held_out import known_rows
    from cbr.unknown_thresholds import false_unknown_threshold

    held, people = measured["held"], measured["people"]
    seen, codes = held[0], held[1]
    keep = known_rows(seen, codes)
    out = {"scan": false_unknown_threshold(seen[keep].min(axis=1))}
    if people.shape[1]:
        pooled = second_left_out(people[keep])
        if len(pooled):
            out["second person left out"] = false_unknown_threshold(pooled)
        for c in CORRECTIONS:
            fixed = corrected(held, people, c)[0]
            out[c] = false_unknown_threshold(fixed[keep].min(axis=1))
    d1 = [r["nearest"].min(axis=1)[np.array([m is not None and m != movement
                                             for m in r["movements"]], dtype=bool)]
          for r in measured["recordings"].values()]  # fmt: skip
    out["test known windows"] = false_unknown_threshold(np.concatenate(d1))
    return out


def run_dataset(
    dataset: str, cache: Path | None, train_people: int | None = None
) -> list[tuple[str, str, dict[str, Any]]]:
    """``(fold, movement, measured)`` for every fold of ``dataset`` and each movement left
    out (``train_people``: case bases of that many people, each in turn)."""
    return unknown_bounds.run_dataset(dataset, cache, train_people, measure, "people")


def summarise(measured: list[tuple[str, str, dict[str, Any]]]) -> dict[str, Any]:
    """Per rule, pooled over the left-out movements: known windows kept, novel ones unknown;
    and per case base the diagnostic quantiles (:func:`quantiles`) and the median ratio."""
    tally = {rule: np.zeros(4, dtype=np.int64) for rule in RULES}
    cases = []
    for fold, movement, m in measured:
        for rule, t in decide(movement, m).items():
            tally[rule] += t
        cases.append({"fold": fold, "left_out": movement, "cases": m["cases"],
                      "basis": m["held"][2], "people": int(m["people"].shape[1]),
                      "median_ratio": median_ratio(m["people"], m["held"][1]),
                      "chosen": choose_correction(m["labels"], m["held"], m["people"]),
                      "d1_q95": quantiles(m, movement)})  # fmt: skip
    return {"rules": unknown_bounds.rule_shares(tally), "case_bases": cases}


def main(argv: list[str] | None = None) -> int:
    return unknown_bounds.rules_main(
        argv,
        "unknown_extrapolate",
        __doc__ or "",
        "window level, people not in the case base; the default judge calibrated on its "
        "held-out scan corrected for the one person fewer it measures against",
        run_dataset,
        summarise,
        RESULTS,
    )


if __name__ == "__main__":
    raise SystemExit(main())
