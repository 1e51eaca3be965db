"""Can the nearest-case distance d1, calibrated on the case base alone, make the default
unknown judge (``spread-margin``) catch more left-out movements on people not in the case
base without calling more known windows unknown? (Issue 14; ``benchmarks.unknown_ceiling``
found d1 separates HDM05's left-out windows almost perfectly, AUROC 0.998, while its
threshold held out by person caught only 65.9 %.)

Run: ``python -m benchmarks.unknown_bounds [--datasets ...] [--train-people 1] [--cache
DIR]`` (at load 12-16 on 2 cores: HDM05 under a minute, its one-actor case bases about 3
minutes, UI-PRMD Vicon and Kinect 1-3 minutes per left-out movement; ``--cache
DIR`` keeps each left-out movement's measurements, so a rerun resumes). Writes
``benchmarks/results/unknown_bounds.json`` (``unknown_bounds_1.json`` with
``--train-people 1``: case bases of one person, each in turn, as ``segment_people
--train-people 1 --rotate``).

The folds, recordings and case bases are :mod:`benchmarks.segment_people`'s (seed 0, one
recording per held-out person), each movement of the test recordings left out of the case
base in turn, as :mod:`benchmarks.unknown_ceiling` does: the 2-s windows the judges see,
whole within one labelled movement; *known* windows (a movement in the case base) kept
known and *novel* ones (the left-out movement) called unknown, pooled over the left-out
movements. Every rule below is calibrated on the case base's own held-out scan
(:func:`cbr.unknown.held_out_activities`: training cases held out by person, their distances
to every activity) and was stated before its figures on the test windows were looked at:

- ``spread-margin``: the default judge's own decisions (:meth:`unlike`, through
  :func:`cbr.unknown.for_person`; a window too still for every case is unknown);
- ``bounded`` (:class:`Bounded`): the default judge between two bounds on d1: never unknown
  at or below ``near``, always beyond ``far``. ``far`` is the distance that 5 % of the
  held-out known cases lie beyond; ``near`` the highest quantile of their distances (0.9,
  0.8, ... 0.1) at or below which the judge calls at most 1 % of the held-out novel cases
  (their activity left out) unknown (:func:`near_bound`). With one person's case base the
  distances are those less the person offset, as the judge's are. Also each bound alone
  (``near only``, ``far only``);
- ``fisher, person-scaled``: Fisher's ``-2 sum log p`` of the judge's score (over its
  nearest activity's threshold) and d1, each p its upper tail among the held-out known
  cases (:func:`benchmarks.unknown_ceiling.tail_p`), d1 first multiplied by how much nearer
  the held-out known cases' nearest tenth lies than the recording's windows' (shrunk by 8
  windows, as :func:`cbr.unknown.person_offset`); unknown above the 95 % quantile of the
  held-out known cases' own;
- ``fisher, weight chosen``: ``-2 log p_judge - 2 w log p_d1``, the weight w (0, 0.25, 0.5,
  1, 2) that calls most held-out novel cases unknown at the 95 % quantile of the held-out
  known ones (a tie: the smaller; 0: the judge's own decisions).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from functools import partial  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import json_out, write_json  # noqa: E402
from benchmarks._common import one_thread_machine, versions  # noqa: E402
from benchmarks.repetitions import HDM05, UIPRMD, Group  # noqa: E402
from benchmarks.segment_people import (  # noqa: E402
    DATASETS,
    Fold,
    Reader,
    fit,
    folds,
    joined_training,
    training_clips,
)
from benchmarks.unknown_ceiling import _cached, oracle_threshold, pure_windows, tail_p  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "unknown_bounds.json"
JUDGE = "spread-margin"
NEAR_QUANTILES = (0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1)
"""The quantiles of the held-out known cases' d1 :func:`near_bound` tries, highest first."""
NEAR_COST = 0.01
"""The share of the held-out novel cases the judge calls unknown that the near bound may give
up."""
FAR_RATE = 0.05
"""The share of held-out known cases that lie beyond the far bound."""
WEIGHTS = (0.0, 0.25, 0.5, 1.0, 2.0)
"""The weights of d1 against the judge's score tried by ``fisher, weight chosen``."""
RULES = ("spread-margin", "bounded", "near only", "far only", "fisher, person-scaled",
         "fisher, weight chosen")  # fmt: skip


# ---------------------------------------------------------------- the rules


def near_bound(judge: Any, known: np.ndarray, novel: np.ndarray) -> float:
    """The near bound: the highest quantile (of :data:`NEAR_QUANTILES`, read at a sample
    value, :func:`cbr.unknown.false_unknown_threshold` at ``1 - q``) of the held-out known
    cases' d1 (``known`` ``(k, n_classes)``: distances to every activity) such that at most
    :data:`NEAR_COST` of the held-out novel cases ``novel`` ``(m, n_classes)`` are both
    called unknown by ``judge`` and no farther than it; 0 (no bound) when none is, or either
    is empty."""
    from cbr.unknown_thresholds import false_unknown_threshold

    if not len(known) or not len(novel):
        return 0.0
    d_known, d_novel = np.min(known, axis=1), np.min(novel, axis=1)
    caught = np.array([judge.unlike(n) for n in novel], dtype=bool)
    for q in NEAR_QUANTILES:
        near = false_unknown_threshold(d_known, round(1.0 - q, 12))
        if np.sum(caught & (d_novel <= near)) <= NEAR_COST * len(novel) + 1e-9:
            return near
    return 0.0


@dataclass(frozen=True)
class Bounded:
    """``judge`` (a window's distances to every activity ``(n_classes,)`` in) between two
    bounds on the nearest distance d1, both in the distances less ``offset`` (one person's
    case base: :func:`cbr.unknown.person_offset`; 0 otherwise): unknown beyond ``far``,
    never at or below ``near``, as ``judge`` says between."""

    judge: Any
    near: float = 0.0
    far: float = math.inf
    offset: float = 0.0

    def unlike(self, nearest: np.ndarray) -> bool:
        d1 = max(float(np.min(nearest)) - self.offset, 0.0)
        if d1 > self.far:
            return True
        return d1 > self.near and bool(self.judge.unlike(nearest))


def bounds(judge: Any, held: Any) -> tuple[float, float]:
    """``(near, far)`` of :class:`Bounded` from the case base's held-out scan ``held``
    (:func:`cbr.unknown.held_out_activities`) and its calibrated ``judge``."""
    from cbr.unknown_held_out import known_and_novel
    from cbr.unknown_thresholds import false_unknown_threshold

    known, novel = known_and_novel(held[0], held[1])
    far = false_unknown_threshold(np.min(known, axis=1), FAR_RATE) if len(known) else math.inf
    return near_bound(judge, known, novel), far


def fisher(
    held_known: dict[str, np.ndarray], scores: dict[str, np.ndarray], w: float
) -> np.ndarray:
    """``-2 log p_judge - 2 w log p_d1`` of the windows' ``scores`` (``judge``, ``d1``; each
    ``(m,)``), each p the upper tail among the held-out known cases' own."""
    lj = np.log(tail_p(held_known["judge"], scores["judge"]))
    ld = np.log(tail_p(held_known["d1"], scores["d1"]))
    return np.asarray(-2.0 * lj - 2.0 * w * ld)


def person_scale(held_d1: np.ndarray, d1: np.ndarray) -> float:
    """How much nearer the held-out known cases' nearest tenth (their d1 ``held_d1``) lies
    than a recording's windows' (``d1``): the ratio of the two 10 % quantiles, shrunk
    towards 1 by 8 windows (:data:`cbr.unknown.PERSON_PRIOR`); 1 without a finite one."""
    from cbr.unknown_person import PERSON_PRIOR, PERSON_QUANTILE

    d = np.asarray(d1, dtype=np.float64)
    d = d[np.isfinite(d)]
    mine = float(np.quantile(d, PERSON_QUANTILE)) if len(d) else 0.0
    if mine <= 0.0:
        return 1.0
    raw = float(np.quantile(held_d1, PERSON_QUANTILE)) / mine
    return 1.0 + (raw - 1.0) * len(d) / (len(d) + PERSON_PRIOR)


def choose_fisher_weight(held: dict[str, dict[str, np.ndarray]]) -> float:
    """The weight of :data:`WEIGHTS` under which most held-out novel cases lie above the 95 %
    quantile of the held-out known cases' own scores (a tie: the smaller)."""
    best, caught = 0.0, -1.0
    for w in WEIGHTS:
        t = oracle_threshold(fisher(held["known"], held["known"], w))
        c = float(np.mean(fisher(held["known"], held["novel"], w) > t))
        if c > caught + 1e-12:
            best, caught = w, c
    return best


# ---------------------------------------------------------------- measuring


def measure(fold: Fold, joined: list[tuple[Any, Group]], movement: str) -> dict[str, Any]:
    """With ``movement`` left out of the fold's case base: the default judge, the case base's
    held-out scan and, per test recording, every non-repetition window's distances to every
    activity, stillness and movement, and every counted window's d1 (the person offset's)."""
    from benchmarks.segment import judge_named
    from cbr.unknown_held_out import held_out_activities

    clf = fit(training_clips(joined, leave_out=movement))
    recs = recordings_measured(clf, fold)
    judge = judge_named(clf, JUDGE)
    held = held_out_activities(clf.case_base_)
    return {"cases": len(clf.case_base_), "judge": judge, "held": held, "recordings": recs}


def recordings_measured(clf: Any, fold: Fold) -> dict[str, dict[str, np.ndarray]]:
    """Per test recording of ``fold``, segmented by ``clf``: every non-repetition window's
    distances to every activity (``nearest``), whether it is still, the movements it holds,
    and every counted window's d1 (``counted_d1``)."""
    from cbr.segmentation import solve_recording

    recs = {}
    for rec in fold.recordings:
        done = solve_recording(clf, rec.seq, chunk_frames=0)
        counted = [float(np.min(w.nearest)) for w, out in
                   zip(done.windows, done.outliers.tolist(), strict=True) if not out]  # fmt: skip
        windows = [w for w in done.windows if not w.repetition]
        spans = np.array([(w.start, w.stop) for w in windows], dtype=np.int64)
        recs[rec.name] = {
            "nearest": np.stack([w.nearest for w in windows]),
            "still": np.array([w.still for w in windows], dtype=bool),
            "movements": pure_windows(rec, spans, rec.seq.fps),
            "counted_d1": np.array(counted),
        }
    return recs


def judge_scores(judge: Any, rows: np.ndarray) -> np.ndarray:
    """The judge's score over its nearest activity's threshold of every row ``(n,
    n_classes)`` (a :class:`cbr.unknown.Offset`'s: its judge's, of the distances less the
    offset)."""
    inner = getattr(judge, "judge", judge)
    less = getattr(judge, "less", lambda r: r)
    return np.array([inner.ratio(less(r)) / inner.threshold(less(r)) for r in rows])


def decide(movement: str, measured: dict[str, Any]) -> dict[str, np.ndarray]:
    """Per rule of :data:`RULES`: the tally ``[known kept, known, novel unknown, novel]`` of
    one left-out movement's case base (``measured``: :func:`measure`)."""
    from cbr.unknown import for_person
    from cbr.unknown_held_out import known_and_novel
    from cbr.unknown_person import person_offset

    judge, held = measured["judge"], measured["held"]
    near, far = bounds(judge, held)
    known, novel = known_and_novel(held[0], held[1])
    scan = {k: {"judge": judge_scores(judge, r), "d1": r.min(axis=1)}
            for k, r in (("known", known), ("novel", novel))}  # fmt: skip
    w = choose_fisher_weight(scan)
    t_person = oracle_threshold(fisher(scan["known"], scan["known"], 1.0))
    t_weight = oracle_threshold(fisher(scan["known"], scan["known"], w))
    out = {rule: np.zeros(4, dtype=np.int64) for rule in RULES}
    for r in measured["recordings"].values():
        is_novel = np.array([m == movement for m in r["movements"]], dtype=bool)
        is_known = np.array([m is not None and m != movement for m in r["movements"]], dtype=bool)
        offset = person_offset(r["counted_d1"], getattr(judge, "reach", math.inf))
        mine = for_person(judge, r["counted_d1"])
        rows, still = r["nearest"], r["still"]
        d1 = rows.min(axis=1)
        score = np.where(still, np.inf, judge_scores(mine, rows))
        scaled = {"judge": score, "d1": d1 * person_scale(scan["known"]["d1"], r["counted_d1"])}
        plain = {"judge": score, "d1": d1}
        unknown = {
            "spread-margin": [s or mine.unlike(n) for s, n in zip(still, rows, strict=True)],
            "fisher, person-scaled": fisher(scan["known"], scaled, 1.0) > t_person,
            "fisher, weight chosen": (
                fisher(scan["known"], plain, w) > t_weight
                if w
                else [s or mine.unlike(n) for s, n in zip(still, rows, strict=True)]
            ),
        }
        for rule, (lo, hi) in (("bounded", (near, far)), ("near only", (near, math.inf)),
                               ("far only", (0.0, far))):  # fmt: skip
            b = Bounded(mine, lo, hi, offset)
            unknown[rule] = [s or b.unlike(n) for s, n in zip(still, rows, strict=True)]
        for rule, u in unknown.items():
            u = np.asarray(u, dtype=bool)
            out[rule] += [int(np.sum(~u[is_known])), int(is_known.sum()),
                          int(np.sum(u[is_novel])), int(is_novel.sum())]  # fmt: skip
    return out


def run_dataset(
    dataset: str,
    cache: Path | None,
    train_people: int | None = None,
    measure: Callable[[Fold, list[tuple[Any, Group]], str], dict[str, Any]] = measure,
    tag: str = "full",
) -> list[tuple[str, str, dict[str, Any]]]:
    """``(fold, movement, measure(fold, joined, movement))`` for every fold of ``dataset`` and
    each movement left out (``train_people``: case bases of that many people, each in turn),
    kept in ``cache`` under ``tag``."""
    from features.progress import progress

    read = Reader()
    out = []
    for fold in folds(dataset, 1, 0, read, train_people, bool(train_people)):
        key = f"{tag}-{dataset}-{fold.name.replace(' ', '_').replace(',', '')}"
        joined = joined_training(fold.train, read)
        movements = sorted({m for r in fold.recordings for m in r.movements})
        for m in progress(movements, f"{dataset} {fold.name}: left out", unit="movement"):
            out.append((fold.name, m, _cached(cache, f"{key}-{m}",
                                              partial(measure, fold, joined, m))))  # fmt: skip
    return out


def summarise(measured: list[tuple[str, str, dict[str, Any]]]) -> dict[str, Any]:
    """Per rule, pooled over the left-out movements: known windows kept, novel ones unknown;
    and each case base's bounds."""
    tally = {rule: np.zeros(4, dtype=np.int64) for rule in RULES}
    cases = []
    for fold, movement, m in measured:
        for rule, t in decide(movement, m).items():
            tally[rule] += t
        near, far = bounds(m["judge"], m["held"])
        cases.append({"fold": fold, "left_out": movement, "cases": m["cases"],
                      "basis": m["held"][2], "near": near, "far": far})  # fmt: skip
    return {"rules": rule_shares(tally), "case_bases": cases}


def rule_shares(tally: dict[str, np.ndarray]) -> dict[str, dict[str, Any]]:
    """Per rule, from its ``(known kept, known, novel unknown, novel)`` window counts: the
    counts and the two shares."""
    return {rule: {"known_windows": int(t[1]), "novel_windows": int(t[3]),
                   "known_kept": float(t[0]) / max(1, int(t[1])),
                   "novel_unknown": float(t[2]) / max(1, int(t[3]))}
            for rule, t in tally.items()}  # fmt: skip


def rules_main(
    argv: list[str] | None,
    name: str,
    doc: str,
    note: str,
    run: Callable[[str, Path | None, int | None], list[tuple[str, str, dict[str, Any]]]],
    summarise: Callable[[list[tuple[str, str, dict[str, Any]]]], dict[str, Any]],
    results: Path,
) -> int:
    """The command of a window-level benchmark of unknown rules (``python -m benchmarks.NAME``,
    described by the first paragraph of ``doc``): ``run`` measures each dataset, ``summarise``
    gives each rule's shares; the table is printed and the JSON written to ``results``
    (``NAME_N.json`` with ``--train-people N``)."""
    parser = argparse.ArgumentParser(prog=f"python -m benchmarks.{name}",
                                     description=doc.split("\n\n")[0])  # fmt: skip
    parser.add_argument("--datasets", nargs="+", choices=DATASETS, default=list(DATASETS))
    parser.add_argument("--train-people", type=int, default=None, metavar="N",
                        help="case bases of N training people, each in turn")  # fmt: skip
    parser.add_argument("--cache", type=Path, default=None, metavar="DIR",
                        help="keep each left-out movement's measurements here")  # fmt: skip
    parser.add_argument("--out", type=json_out, default=None, metavar="JSON",
                        help="write here instead of benchmarks/results/")  # fmt: skip
    args = parser.parse_args(argv)
    if args.train_people is not None and args.train_people < 1:
        parser.error(f"--train-people must be at least 1, got {args.train_people}")
    if not UIPRMD.is_dir() or not HDM05.is_dir():
        print(f"no ui-prmd or hdm05 data under {UIPRMD.parents[1]}: nothing to measure")
        return 1
    import numba

    numba.set_num_threads(1)
    load_at_start = [round(x, 2) for x in os.getloadavg()]
    summary: dict[str, Any] = {}
    for dataset in args.datasets:
        t0 = time.perf_counter()
        summary[dataset] = summarise(run(dataset, args.cache, args.train_people))
        summary[dataset]["wall_s"] = time.perf_counter() - t0
        print(f"\n{dataset}: known windows kept / left-out windows unknown")
        for rule, r in summary[dataset]["rules"].items():
            counts = f"({r['known_windows']} known, {r['novel_windows']} left-out windows)"
            print(f"  {rule:24s}{r['known_kept']:8.1%}{r['novel_unknown']:8.1%}   {counts}")
    result = {
        "benchmark": name,
        "command": f"python -m benchmarks.{name} --datasets "
        + " ".join(args.datasets)
        + (f" --train-people {args.train_people}" if args.train_people else ""),
        "note": note,
        "machine": one_thread_machine(),
        "load_average_at_start": load_at_start,
        "versions": versions("posecbr", "numpy", "scipy", "scikit-learn", "numba"),
        "summary": summary,
    }
    if args.cache is not None:
        result["cache"] = (
            "measurements read from --cache where a run had made them: wall_s is this run's"
        )
    out = args.out or results
    if args.train_people and args.out is None:
        out = results.with_name(f"{name}_{args.train_people}.json")
    write_json(result, out)
    print(f"\nwrote {out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    return rules_main(
        argv,
        "unknown_bounds",
        __doc__ or "",
        "window level, people not in the case base; every rule calibrated on the case "
        "base's held-out scan alone",
        run_dataset,
        summarise,
        RESULTS,
    )


if __name__ == "__main__":
    raise SystemExit(main())
