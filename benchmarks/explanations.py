"""Explanations a person can check, measured on held-out subjects.

Train a case base on some subjects, explain the clips of the others (every clip of a dataset is
held out once: UI-PRMD in four folds of two subjects, HDM05 leaving one actor out), and report
per dataset:

- counterfactual **validity** (the changed clip, run through the same retrieve and reuse, gets
  the label wanted: the label of the nearest case of another label), **sparsity** (features
  changed; a feature is one signal with what is computed from it) and **plausibility** (the
  changed clip's distance to its nearest case of that label over that label's usual
  nearest-case distance; Native Guide, Delaney et al. 2021);
- the default text's **length** (lines and characters per clip);
- **contradictions** found by :func:`cbr.consistency.contradictions` over every clip;
- accuracy and the **expected calibration error** (ECE, 10 bins) of the confidences;
- the "unlike the stored cases" flag: **false alarms** on the held-out clips (trained
  activities, new people) and **detection** of clips from the other dataset, by the distance
  alone and with the sensor rule (a skeleton no training clip was recorded with), for
  fluents/euclidean, fluents/dtw, fluents/signature and qmp/euclidean;
- the ECE of the repetition check (UI-PRMD correct vs incorrect, one case base per movement).

    python -m benchmarks.explanations             # both datasets from ../shared/data (~1 h)
    python -m benchmarks.explanations --train DATA --test DATA [--train-subjects s01,s02]
        [--test-subjects s03] [--other DATA]      # one split of your own
    python -m benchmarks.explanations --quick     # the bundled demo subset (~1 min)
    python -m benchmarks.explanations --datasets hdm05,repetitions --out FILE  # some of them

The figures of each fold are printed as it finishes, and the JSON is written after each
dataset (``"partial": true`` until the run ends).

Writes ``benchmarks/results/explanations.json`` with the machine, the versions and the load
average.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import write_json

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = Path(__file__).resolve().parent / "results" / "explanations.json"
DATASETS = {
    "ui-prmd": (SHARED / "ui-prmd", (("s01", "s02"), ("s03", "s04"), ("s05", "s06"),
                                     ("s07", "s08"))),
    "hdm05": (SHARED / "hdm05", (("bd",), ("bk",), ("dg",))),
}  # fmt: skip
FLAG_CONFIGS = (
    ("fluents", "euclidean"),
    ("fluents", "dtw"),
    ("fluents", "signature"),
    ("qmp", "euclidean"),
)
#: clips of the other dataset each fold's flag is tried on (a seeded sample)
OTHER_SAMPLE = 200
#: UI-PRMD's repetition check (correct vs incorrect) in --datasets
REPETITIONS = "repetitions"


def _clips(path: Path, subjects: Sequence[str] | None = None) -> list[Any]:
    from features.datasets import load_dataset

    return load_dataset(path, subjects=set(subjects) if subjects else None)


def _sample(items: list[Any], n: int, seed: int = 0) -> list[Any]:
    if len(items) <= n:
        return items
    pick = np.sort(np.random.default_rng(seed).choice(len(items), n, replace=False))
    return [items[i] for i in pick]


def explain_fold(train: list[Any], test: list[Any], target: str = "label") -> dict[str, Any]:
    """Fit the default case base on ``train`` and explain every clip of ``test``: per clip, the
    counterfactual's validity, size and plausibility, the text's length, the contradictions,
    whether the answer was right and its confidence."""
    from cbr.consistency import contradictions
    from cbr.estimator import CaseBaseClassifier
    from features.datasets import clip_target

    y = [clip_target(c, target) for c in train]
    clf = CaseBaseClassifier().fit([c.seq for c in train], y)
    rows = []
    for clip, solved in zip(test, clf.solve([c.seq for c in test]), strict=True):
        exp = clf.explain_solved(solved, target)
        c = exp.contrast
        found = contradictions(exp, clf.case_base_, solved.problem)
        rows.append(
            {
                "valid": bool(c is not None and c.valid),
                "changes": len(c.changes) if c is not None and c.valid else None,
                "plausibility": c.plausibility if c is not None and c.valid else None,
                "chars": len(exp.text),
                "lines": len(exp.text.splitlines()),
                "contradictions": found,
                "right": solved.solution.label == clip_target(clip, target),
                "confidence": solved.solution.confidence,
                "vote_share": solved.solution.vote_share,
            }
        )
    from cbr.profiles import view_of

    return {"rows": rows, "features": len(view_of(clf.case_base_).features)}


def summarise_rows(rows: list[dict[str, Any]], features: int) -> dict[str, Any]:
    from cbr.calibration import expected_calibration_error

    valid = [r for r in rows if r["valid"]]
    changes = [r["changes"] for r in valid]
    plaus = [r["plausibility"] for r in valid]
    right = np.array([r["right"] for r in rows], dtype=bool)
    conf = np.array([r["confidence"] for r in rows])
    share = np.array([r["vote_share"] for r in rows])
    found = [f for r in rows for f in r["contradictions"]]
    return {
        "clips": len(rows),
        "validity": len(valid) / len(rows) if rows else float("nan"),
        "mean_changes": float(np.mean(changes)) if changes else float("nan"),
        "changes_histogram": np.bincount(changes).tolist() if changes else [],
        "sparsity_share": float(np.mean(changes)) / features if changes else float("nan"),
        "features": features,
        "plausibility_median": float(np.median(plaus)) if plaus else float("nan"),
        "max_chars": max(r["chars"] for r in rows),
        "mean_chars": float(np.mean([r["chars"] for r in rows])),
        "max_lines": max(r["lines"] for r in rows),
        "contradictions": len(found),
        "contradiction_examples": found[:5],
        "accuracy": float(right.mean()),
        "ece": expected_calibration_error(conf, right),
        "ece_vote_share": expected_calibration_error(share, right),
        "mean_confidence": float(conf.mean()),
    }


def flag_fold(
    features: str, similarity: str, train: list[Any], test: list[Any], other: list[Any]
) -> dict[str, Any]:
    """False alarms on the held-out clips and detection of the other dataset's clips."""
    from cbr.estimator import CaseBaseClassifier

    clf = CaseBaseClassifier(features=features, similarity=similarity)
    clf.fit([c.seq for c in train], [c.label for c in train])
    held = clf.solve([c.seq for c in test])
    away = clf.solve([c.seq for c in other])
    return {
        "false_alarm": [s.unlike_cases for s in held],
        "false_alarm_distance": [s.unlike_reason == "distance" for s in held],
        "detected": [s.unlike_cases for s in away],
        "detected_distance": [
            clf.novelty_.ratio(float(s.retrieval.distances[0])) > clf.novelty_.unlike_ratio
            for s in away
        ],  # fmt: skip
        "other_label": [c.label for c in other],
        "right": [s.solution.label == c.label for s, c in zip(held, test, strict=True)],
        "confidence": [s.solution.confidence for s in held],
    }


def _by_activity(labels: list[str], hit: list[bool]) -> dict[str, float]:
    """The share of ``hit`` among the other dataset's clips of each activity: which of its
    movements the distance alone tells apart from the stored cases."""
    return {lab: _rate([h for la, h in zip(labels, hit, strict=True) if la == lab])
            for lab in sorted(set(labels))}  # fmt: skip


def _rate(values: list[bool]) -> float:
    return float(np.mean(values)) if values else float("nan")


def run_dataset(
    name: str, path: Path, folds: Sequence[Sequence[str]], other: list[Any], flags: bool
) -> dict[str, Any]:
    """Every clip of one dataset explained held out; the flags of every configuration."""

    clips = _clips(path)
    rows: list[dict[str, Any]] = []
    features = 0
    flag_rows: dict[str, dict[str, list[Any]]] = {}
    for held in folds:
        train = [c for c in clips if c.subject not in held]
        test = [c for c in clips if c.subject in held]
        t0 = time.perf_counter()
        fold = explain_fold(train, test)
        rows += fold["rows"]
        features = fold["features"]
        print(f"  {name} held out {','.join(held)}: {len(test)} clips explained "
              f"({time.perf_counter() - t0:.0f} s)", flush=True)  # fmt: skip
        _print_fold(summarise_rows(fold["rows"], features))
        if not flags:
            continue
        for feats, sim in FLAG_CONFIGS:
            t0 = time.perf_counter()
            got = flag_fold(feats, sim, train, test, _sample(other, OTHER_SAMPLE))
            acc = flag_rows.setdefault(f"{feats}/{sim}", {})
            for k, v in got.items():
                acc.setdefault(k, []).extend(v)
            print(f"    flag {feats}/{sim}: {time.perf_counter() - t0:.0f} s; false alarms "
                  f"{100 * _rate(got['false_alarm']):.1f} %, detection "
                  f"{100 * _rate(got['detected']):.1f} % (by distance "
                  f"{100 * _rate(got['detected_distance']):.1f} %)", flush=True)  # fmt: skip
    out: dict[str, Any] = {"explanations": summarise_rows(rows, features)}
    if flags:
        out["flags"] = {cfg: _flag_summary(r) for cfg, r in flag_rows.items()}
    return out


def run_repetitions(path: Path, folds: Sequence[Sequence[str]]) -> dict[str, Any]:
    """UI-PRMD correct vs incorrect: one case base per movement, each clip held out once; the
    ECE of the confidences and the explanations' figures."""
    clips = _clips(path)
    rows: list[dict[str, Any]] = []
    features = 0
    for movement in sorted({c.label for c in clips}):
        mine = [c for c in clips if c.label == movement]
        for held in folds:
            train = [c for c in mine if c.subject not in held]
            test = [c for c in mine if c.subject in held]
            fold = explain_fold(train, test, target="correct")
            for r in fold["rows"]:
                r["movement"] = movement
            rows += fold["rows"]
            features = fold["features"]
        print(f"  correct vs incorrect, {movement}: done", flush=True)
        _print_fold(summarise_rows([r for r in rows if r["movement"] == movement], features))
    return summarise_rows(rows, features)


def _print_fold(s: dict[str, Any]) -> None:
    """One fold's figures as it finishes (a long run shows its progress in figures)."""
    print(f"    validity {100 * s['validity']:.1f} % with {s['mean_changes']:.2f} changes, "
          f"{s['contradictions']} contradictions, at most {s['max_lines']} lines and "
          f"{s['max_chars']} chars, accuracy {100 * s['accuracy']:.1f} %, ECE {s['ece']:.3f}",
          flush=True)  # fmt: skip


def _print_explanations(name: str, s: dict[str, Any]) -> None:
    print(
        f"{name:<28} {s['clips']:>5} {100 * s['validity']:8.1f} % {s['mean_changes']:8.2f} "
        f"{s['plausibility_median']:8.2f} {s['max_lines']:6d} {s['max_chars']:6d} "
        f"{s['mean_chars']:6.0f} {s['contradictions']:6d} {100 * s['accuracy']:6.1f} % "
        f"{s['ece']:6.3f}"
    )


def _print_flags(name: str, flags: dict[str, Any]) -> None:
    for cfg, f in flags.items():
        print(
            f"{name + ' ' + cfg:<36} {100 * f['false_alarm']:6.1f} % "
            f"{100 * f['false_alarm_distance']:6.1f} % {100 * f['detection']:6.1f} % "
            f"{100 * f['detection_distance']:6.1f} % {100 * f['accuracy']:6.1f} % "
            f"{f['ece']:6.3f}"
        )


def _header() -> None:
    print(
        f"\n{'dataset':<28} {'clips':>5} {'validity':>10} {'changes':>8} {'plausib.':>8} "
        f"{'lines':>6} {'chars':>6} {'mean':>6} {'contra':>6} {'acc':>8} {'ECE':>6}"
    )


def _flag_summary(r: dict[str, Any]) -> dict[str, Any]:
    """One flag configuration's figures from its per-clip outcomes ``r`` (:func:`flag_fold`)."""
    from cbr.calibration import expected_calibration_error

    return {
        "false_alarm": _rate(r["false_alarm"]),
        "false_alarm_distance": _rate(r["false_alarm_distance"]),
        "detection": _rate(r["detected"]),
        "detection_distance": _rate(r["detected_distance"]),
        "accuracy": _rate(r["right"]),
        "ece": expected_calibration_error(
            np.array(r["confidence"]), np.array(r["right"], dtype=bool)
        ),
        "held_out_clips": len(r["false_alarm"]),
        "other_clips": len(r["detected"]),
        "detection_distance_by_activity": _by_activity(r["other_label"], r["detected_distance"]),
    }


def _run_split(args: argparse.Namespace) -> dict[str, Any]:
    """One training/test split (--quick or --train): explanations and, with --other, flags."""

    datasets: dict[str, Any] = {}
    if args.quick:
        with resources.as_file(resources.files("posecbr") / "demo_data" / "uiprmd") as d:
            data = d / "labels.csv"
            train = _clips(data, ("s01", "s02"))
            test = _clips(data, ("s03",))
    else:
        split = lambda v: [s.strip() for s in v.split(",")] if v else None  # noqa: E731
        train = _clips(args.train, split(args.train_subjects))
        test = _clips(args.test or args.train, split(args.test_subjects))
    fold = explain_fold(train, test)
    s = summarise_rows(fold["rows"], fold["features"])
    datasets["split"] = {"explanations": s}
    if args.other is not None and not args.no_flags:
        other = _sample(_clips(args.other), OTHER_SAMPLE)
        flags = {}
        for feats, sim in FLAG_CONFIGS:
            r = flag_fold(feats, sim, train, test, other)
            flags[f"{feats}/{sim}"] = _flag_summary(r)
        datasets["split"]["flags"] = flags
    return datasets


def _run_shared(args: argparse.Namespace, done: Callable[[dict[str, Any]], None]) -> dict[str, Any]:
    """Both shared datasets held out by subject, and UI-PRMD's repetition check (those of
    ``args.datasets``); ``done`` is given the figures so far after each."""
    datasets: dict[str, Any] = {}
    for name, (path, folds) in DATASETS.items():
        if name not in args.datasets:
            continue
        if not path.exists():
            print(f"{name}: skipped, {path} is not on this machine")
            continue
        other_name = "hdm05" if name == "ui-prmd" else "ui-prmd"
        other_path = DATASETS[other_name][0]
        other = _clips(other_path) if other_path.exists() and not args.no_flags else []
        print(f"{name}:", flush=True)
        datasets[name] = run_dataset(name, path, folds, other, bool(other))
        done(datasets)
    path, folds = DATASETS["ui-prmd"]
    if path.exists() and REPETITIONS in args.datasets:
        print("ui-prmd correct vs incorrect:", flush=True)
        datasets["ui-prmd correct vs incorrect"] = {"explanations": run_repetitions(path, folds)}
    return datasets


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.explanations")
    p.add_argument("--train", type=Path, help="training data (default: both shared datasets)")
    p.add_argument("--test", type=Path, help="data whose clips are explained")
    p.add_argument("--train-subjects", help="with --train: only these subjects")
    p.add_argument("--test-subjects", help="with --test: only these subjects")
    p.add_argument("--other", type=Path, help="another dataset's clips for the flag")
    p.add_argument("--quick", action="store_true", help="the bundled demo subset only")
    p.add_argument("--no-flags", action="store_true", help="explanations only")
    p.add_argument(
        "--datasets",
        default=",".join((*DATASETS, REPETITIONS)),
        help=f"of the shared data, these only (default: {','.join((*DATASETS, REPETITIONS))})",
    )
    p.add_argument("--out", type=Path, default=RESULTS, help=f"results JSON (default {RESULTS})")
    args = p.parse_args(argv if argv is not None else sys.argv[1:])
    os.environ.setdefault("POSECBR_NO_PROGRESS", "1")
    from cbr.evaluation.machine import machine_info

    t_start = time.perf_counter()
    out: dict[str, Any] = {"benchmark": "explanations", "machine": machine_info(),
                           "load_average_start": os.getloadavg(), "datasets": {}}  # fmt: skip
    args.datasets = {d.strip() for d in args.datasets.split(",")}

    def done(datasets: dict[str, Any]) -> None:  # partial figures survive an interrupted run
        write_json({**out, "datasets": datasets, "partial": True}, args.out)

    if args.quick or args.train is not None:
        out["datasets"] = _run_split(args)
    else:
        out["datasets"] = _run_shared(args, done)
    _header()
    for name, d in out["datasets"].items():
        _print_explanations(name, d["explanations"])
    if any("flags" in d for d in out["datasets"].values()):
        print(
            f"\n{'flag: dataset configuration':<36} {'f.alarm':>8} {'(dist.)':>8} "
            f"{'detect':>8} {'(dist.)':>8} {'acc':>8} {'ECE':>6}"
        )
        for name, d in out["datasets"].items():
            if "flags" in d:
                _print_flags(name, d["flags"])
    out["seconds"] = round(time.perf_counter() - t_start, 1)
    out["load_average_end"] = os.getloadavg()
    write_json(out, args.out)
    print(f"\nwritten {args.out} ({out['seconds']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
