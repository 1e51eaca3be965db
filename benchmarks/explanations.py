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
- the **time** of an explanation (``explain_ms``: milliseconds per clip of
  ``explain_solved``, the counterfactual search most of it; median and maximum);
- **contradictions** found by :func:`cbr.consistency.contradictions` over every clip;
- accuracy and the **expected calibration error** (ECE, 10 bins) of the confidences, with its
  bootstrap 95 % interval (clips resampled: what of it is noise at a few hundred clips) and
  what a perfectly calibrated confidence would score at the same confidences ("if
  calibrated": median and 95th percentile, answers drawn right with their confidence);
- the "unlike the stored cases" flag: **false alarms** on the held-out clips (trained
  activities, new people) and **detection** of clips from the other dataset, with the sensor
  rule (a skeleton no training clip was recorded with), without it (``measured``: the
  nearest-case distance or the summary features, :mod:`cbr.novelty`) and by each of the two
  scores alone (per activity of the other dataset too), for fluents/euclidean, fluents/dtw,
  fluents/signature and qmp/euclidean;
- the ECE of the repetition check (UI-PRMD correct vs incorrect, one case base per movement),
  overall and per movement.

    python -m benchmarks.explanations [--jobs 2]  # both datasets from ../shared/data
    python -m benchmarks.explanations --train DATA --test DATA [--train-subjects s01,s02]
        [--test-subjects s03] [--other DATA]      # one split of your own
    python -m benchmarks.explanations --quick     # the bundled demo subset (about 10 s)
    python -m benchmarks.explanations --datasets hdm05,repetitions --out FILE  # some of them

The shared run is a list of tasks (a fold of a dataset with its four flag configurations, or one
movement's repetition check) run ``--jobs`` at a time in worker processes that each read the
datasets once; the figures do not depend on ``--jobs`` (each task is a function of its clips
alone, gathered in task order). Within a fold the flag reuses the explanations' default case
base (fluents/euclidean is that configuration) and describes the training clips once for dtw
and signature (the same problems). The figures of each task are printed as it finishes, and the
JSON is written after each dataset (``"partial": true`` until the run ends), with each task's
seconds.

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

from benchmarks import json_out, write_json

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


def fit_classifier(
    train: list[Any],
    target: str = "label",
    described: dict[Any, list[Any]] | None = None,
    **params: Any,
) -> Any:
    """A :class:`cbr.estimator.CaseBaseClassifier` with ``params`` fitted on ``train``.
    ``described``: the training clips already described, by describe plan (filled here), so
    configurations that describe clips alike (dtw and signature) read each clip once; the
    same model as ``fit``, which is these two steps."""
    from cbr.described import describe_clips
    from cbr.estimator import CaseBaseClassifier
    from features.targets import clip_target

    clf = CaseBaseClassifier(**params)
    y = [clip_target(c, target) for c in train]
    if described is None:
        clf.fit([c.seq for c in train], y)
    else:
        plan = clf.describe_plan()
        if plan not in described:
            described[plan] = list(describe_clips([c.seq for c in train], *plan))
        clf.fit_described(described[plan], y)
    clf.target_ = target  # the column it predicts, which explain_solved's target may name
    return clf


def explain_rows(
    clf: Any, test: list[Any], solved: list[Any], target: str, explain: bool = True
) -> dict[str, Any]:
    """Every clip of ``test`` (``solved`` by ``clf``) explained: per clip, the
    counterfactual's validity, size and plausibility, the text's length, the contradictions,
    whether the answer was right and its confidence (``explain`` False: the last two only)."""
    from cbr.consistency import contradictions
    from cbr.profiles import view_of
    from features.targets import clip_target

    rows = []
    for clip, one in zip(test, solved, strict=True):
        if not explain:
            rows.append({"right": one.solution.label == clip_target(clip, target),
                         "confidence": one.solution.confidence,
                         "vote_share": one.solution.vote_share})  # fmt: skip
            continue
        t0 = time.perf_counter()
        exp = clf.explain_solved(one, target)
        ms = 1e3 * (time.perf_counter() - t0)
        c = exp.contrast
        found = contradictions(exp, clf.case_base_, one.problem)
        rows.append(
            {
                "valid": bool(c is not None and c.valid),
                "changes": len(c.changes) if c is not None and c.valid else None,
                "plausibility": c.plausibility if c is not None and c.valid else None,
                "chars": len(exp.text),
                "lines": len(exp.text.splitlines()),
                "explain_ms": ms,
                "contradictions": found,
                "right": one.solution.label == clip_target(clip, target),
                "confidence": one.solution.confidence,
                "vote_share": one.solution.vote_share,
            }
        )
    return {"rows": rows, "features": len(view_of(clf.case_base_).features)}


def explain_fold(
    train: list[Any], test: list[Any], target: str = "label", explain: bool = True
) -> dict[str, Any]:
    """Fit the default case base on ``train`` and explain every clip of ``test``
    (:func:`explain_rows`)."""
    clf = fit_classifier(train, target)
    return explain_rows(clf, test, clf.solve([c.seq for c in test]), target, explain)


def summarise_rows(rows: list[dict[str, Any]], features: int) -> dict[str, Any]:
    from cbr.calibration import ece_if_calibrated, ece_interval, expected_calibration_error

    if rows and "valid" not in rows[0]:  # not explained (--no-explain): the confidences only
        return {**_calibration(rows), "explained": False}
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
        "explain_ms_median": float(np.median([r["explain_ms"] for r in rows])),
        "explain_ms_max": float(max(r["explain_ms"] for r in rows)),
        "max_lines": max(r["lines"] for r in rows),
        "contradictions": len(found),
        "contradiction_examples": found[:5],
        "accuracy": float(right.mean()),
        "ece": expected_calibration_error(conf, right),
        "ece_interval": ece_interval(conf, right),
        "ece_if_calibrated": ece_if_calibrated(conf),
        "ece_vote_share": expected_calibration_error(share, right),
        "mean_confidence": float(conf.mean()),
    }


def flag_fold(
    features: str,
    similarity: str,
    train: list[Any],
    test: list[Any],
    other: list[Any],
    fitted: tuple[Any, list[Any]] | None = None,
    described: dict[Any, list[Any]] | None = None,
) -> dict[str, Any]:
    """False alarms on the held-out clips and detection of the other dataset's clips.
    ``fitted``: this configuration's classifier already fitted on ``train`` and its solutions
    of ``test`` (the explanations' default case base); ``described``: see
    :func:`fit_classifier`."""
    if fitted is None:
        clf = fit_classifier(train, described=described, features=features,
                             similarity=similarity)  # fmt: skip
        held = clf.solve([c.seq for c in test])
    else:
        clf, held = fitted
    away = clf.solve([c.seq for c in other])
    held_scores, away_scores = _scores(clf, held), _scores(clf, away)
    return {
        "false_alarm": [s.unlike_cases for s in held],
        "false_alarm_measured": [bool(d or f) for d, f in held_scores],
        "false_alarm_distance": [d for d, _ in held_scores],
        "false_alarm_features": [f for _, f in held_scores],
        "detected": [s.unlike_cases for s in away],
        "detected_measured": [bool(d or f) for d, f in away_scores],
        "detected_distance": [d for d, _ in away_scores],
        "detected_features": [f for _, f in away_scores],
        "other_label": [c.label for c in other],
        "right": [s.solution.label == c.label for s, c in zip(held, test, strict=True)],
        "confidence": [s.solution.confidence for s in held],
    }


def _scores(clf: Any, solved: list[Any]) -> list[tuple[bool, bool]]:
    """Per clip, the sensor rule aside: whether the nearest-case distance flags it and whether
    the summary features do (:mod:`cbr.novelty`: the clip's fluent summary in every
    configuration)."""
    nov = clf.novelty_
    return [nov.scores(float(s.retrieval.distances[0]), s.description, s.solution.label)
            for s in solved]  # fmt: skip


def _by_activity(labels: list[str], hit: list[bool]) -> dict[str, float]:
    """The share of ``hit`` among the other dataset's clips of each activity: which of its
    movements the distance alone tells apart from the stored cases."""
    return {lab: _rate([h for la, h in zip(labels, hit, strict=True) if la == lab])
            for lab in sorted(set(labels))}  # fmt: skip


def _rate(values: list[bool]) -> float:
    return float(np.mean(values)) if values else float("nan")


#: the shared datasets' clips in this process, read once per worker by :func:`_load`
_LOADED: dict[str, list[Any]] = {}
#: the dataset whose clips each dataset's flag is tried on
_OTHER = {"ui-prmd": "hdm05", "hdm05": "ui-prmd"}
#: the explanations' case base (the classifier's defaults), whose fit the flag reuses
DEFAULT_CONFIG = ("fluents", "euclidean")


def _load(paths: dict[str, Path]) -> None:
    """Every worker's set-up: read the datasets the tasks need, once."""
    for name, path in paths.items():
        if name not in _LOADED:
            _LOADED[name] = _clips(path)


def _task(paths: dict[str, Path], task: tuple[Any, ...]) -> dict[str, Any]:
    """One unit of the shared run (in this process or a worker): ``("fold", dataset,
    held-out subjects, flags, explain)`` or ``("movement", movement, explain)``; its rows,
    figures and the lines to print, with the task itself."""
    _load(paths)
    out = _fold(*task[1:]) if task[0] == "fold" else _movement(*task[1:])
    return {**out, "task": task}


def _fold(name: str, held: tuple[str, ...], flags: bool, explain: bool) -> dict[str, Any]:
    """One fold of a dataset: the held-out subjects' clips explained by the default case base
    of the others, and (``flags``) every flag configuration fitted on the same clips: the
    default one reused, dtw and signature from one description of the clips."""
    clips = _LOADED[name]
    train = [c for c in clips if c.subject not in held]
    test = [c for c in clips if c.subject in held]
    t0 = time.perf_counter()
    clf = fit_classifier(train)
    solved = clf.solve([c.seq for c in test])
    fold = explain_rows(clf, test, solved, "label", explain)
    seconds: dict[str, Any] = {"held_out": list(held), "explain": round(time.perf_counter() - t0)}
    lines = [
        f"  {name} held out {','.join(held)}: {len(test)} clips explained ({seconds['explain']} s)",
        _fold_line(summarise_rows(fold["rows"], fold["features"])),
    ]
    fold["flags"] = {}
    if flags:
        other = _sample(_LOADED[_OTHER[name]], OTHER_SAMPLE)
        described: dict[Any, list[Any]] = {}
        for feats, sim in FLAG_CONFIGS:
            t0 = time.perf_counter()
            fitted = (clf, solved) if (feats, sim) == DEFAULT_CONFIG else None
            got = flag_fold(feats, sim, train, test, other, fitted, described)
            fold["flags"][f"{feats}/{sim}"] = got
            seconds[f"{feats}/{sim}"] = round(time.perf_counter() - t0)
            cal = _calibration(
                [
                    {"right": h, "confidence": c}
                    for h, c in zip(got["right"], got["confidence"], strict=True)
                ]
            )
            lo, hi = cal["ece_interval"]
            lines.append(f"    flag {feats}/{sim}: {seconds[f'{feats}/{sim}']} s; false alarms "
                         f"{100 * _rate(got['false_alarm']):.1f} %, detection "
                         f"{100 * _rate(got['detected']):.1f} % (without the sensor rule "
                         f"{100 * _rate(got['detected_measured']):.1f} %: distance "
                         f"{100 * _rate(got['detected_distance']):.1f} %, features "
                         f"{100 * _rate(got['detected_features']):.1f} %; false alarms "
                         f"{100 * _rate(got['false_alarm_distance']):.1f} %, "
                         f"{100 * _rate(got['false_alarm_features']):.1f} %); accuracy "
                         f"{100 * cal['accuracy']:.1f} %, ECE {cal['ece']:.3f} "
                         f"[{lo:.3f}, {hi:.3f}], if calibrated {_if_calibrated(cal)}")  # fmt: skip
    return {**fold, "lines": lines, "seconds": seconds}


def _movement(movement: str, explain: bool) -> dict[str, Any]:
    """UI-PRMD correct vs incorrect for one movement: its own case base per fold, each of its
    clips held out once."""
    mine = [c for c in _LOADED["ui-prmd"] if c.label == movement]
    rows: list[dict[str, Any]] = []
    features = 0
    t0 = time.perf_counter()
    for held in DATASETS["ui-prmd"][1]:
        train = [c for c in mine if c.subject not in held]
        test = [c for c in mine if c.subject in held]
        fold = explain_fold(train, test, target="correct", explain=explain)
        for r in fold["rows"]:
            r["movement"] = movement
        rows += fold["rows"]
        features = fold["features"]
    seconds = round(time.perf_counter() - t0)
    lines = [f"  correct vs incorrect, {movement}: done ({seconds} s)",
             _fold_line(summarise_rows(rows, features))]  # fmt: skip
    return {"rows": rows, "features": features, "lines": lines,
            "seconds": {"movement": movement, "explain": seconds}}  # fmt: skip


def _dataset(folds: list[dict[str, Any]]) -> dict[str, Any]:
    """A dataset's figures from its folds' outcomes (in fold order)."""
    rows = [r for f in folds for r in f["rows"]]
    out: dict[str, Any] = {"explanations": summarise_rows(rows, folds[-1]["features"])}
    merged: dict[str, dict[str, list[Any]]] = {}
    for f in folds:
        for cfg, got in f.get("flags", {}).items():
            acc = merged.setdefault(cfg, {})
            for k, v in got.items():
                acc.setdefault(k, []).extend(v)
    if merged:
        out["flags"] = {cfg: _flag_summary(r) for cfg, r in merged.items()}
        for cfg, summary in out["flags"].items():
            summary["by_fold"] = _by_fold(folds, cfg)
    out["seconds"] = [f["seconds"] for f in folds]
    return out


def _repetitions(folds: list[dict[str, Any]]) -> dict[str, Any]:
    """The repetition check's figures, overall and per movement (the ECE with its interval)."""
    out = _dataset(folds)
    out["per_movement"] = {f["seconds"]["movement"]: _calibration(f["rows"]) for f in folds}
    return out


def _fold_line(s: dict[str, Any]) -> str:
    """One fold's figures as it finishes (a long run shows its progress in figures)."""
    lo, hi = s["ece_interval"]
    if s.get("explained") is False:
        return f"    accuracy {100 * s['accuracy']:.1f} %, ECE {s['ece']:.3f} [{lo:.3f}, {hi:.3f}]"
    return (f"    validity {100 * s['validity']:.1f} % with {s['mean_changes']:.2f} changes, "
            f"{s['contradictions']} contradictions, at most {s['max_lines']} lines and "
            f"{s['max_chars']} chars, accuracy {100 * s['accuracy']:.1f} %, ECE {s['ece']:.3f} "
            f"[{lo:.3f}, {hi:.3f}], {s['explain_ms_median']:.0f} ms an explanation "
            "(median)")  # fmt: skip


def _print_explanations(name: str, s: dict[str, Any]) -> None:
    lo, hi = s["ece_interval"]
    if s.get("explained") is False:
        print(f"{name:<28} {s['clips']:>5} {'(not explained)':>70} {100 * s['accuracy']:6.1f} % "
              f"{s['ece']:6.3f} [{lo:.3f}, {hi:.3f}] {_if_calibrated(s)}")  # fmt: skip
        return
    print(
        f"{name:<28} {s['clips']:>5} {100 * s['validity']:8.1f} % {s['mean_changes']:8.2f} "
        f"{s['plausibility_median']:8.2f} {s['max_lines']:6d} {s['max_chars']:6d} "
        f"{s['mean_chars']:6.0f} {s['contradictions']:6d} {100 * s['accuracy']:6.1f} % "
        f"{s['ece']:6.3f} [{lo:.3f}, {hi:.3f}] {_if_calibrated(s)} "
        f"{s['explain_ms_median']:8.0f} {s['explain_ms_max']:8.0f}"
    )


def _print_flags(name: str, flags: dict[str, Any]) -> None:
    for cfg, f in flags.items():
        lo, hi = f["ece_interval"]
        print(
            f"{name + ' ' + cfg:<36} {100 * f['false_alarm']:6.1f} % "
            f"{100 * f['false_alarm_distance']:6.1f} % {100 * f['false_alarm_features']:6.1f} % "
            f"{100 * f['detection']:6.1f} % {100 * f['detection_measured']:6.1f} % "
            f"{100 * f['detection_distance']:6.1f} % {100 * f['detection_features']:6.1f} % "
            f"{100 * f['accuracy']:6.1f} % "
            f"{f['ece']:6.3f} [{lo:.3f}, {hi:.3f}] {_if_calibrated(f)}"
        )


def _if_calibrated(s: dict[str, Any]) -> str:
    """What a perfectly calibrated confidence scores at these confidences: median (95th
    percentile), :func:`cbr.calibration.ece_if_calibrated`."""
    mid, high = s["ece_if_calibrated"]
    return f"{mid:.3f} ({high:.3f})"


def _print_movements(per_movement: dict[str, Any]) -> None:
    print(f"\n{'correct vs incorrect: movement':<46} {'clips':>5} {'acc':>8} {'conf.':>6} "
          f"{'ECE':>6} {'95 % interval':>16} {'if calibrated':>15}")  # fmt: skip
    for movement, m in per_movement.items():
        lo, hi = m["ece_interval"]
        print(f"{movement:<46} {m['clips']:>5} {100 * m['accuracy']:6.1f} % "
              f"{m['mean_confidence']:6.3f} {m['ece']:6.3f} [{lo:.3f}, {hi:.3f}] "
              f"{_if_calibrated(m)}")  # fmt: skip


def _header() -> None:
    print(
        f"\n{'dataset':<28} {'clips':>5} {'validity':>10} {'changes':>8} {'plausib.':>8} "
        f"{'lines':>6} {'chars':>6} {'mean':>6} {'contra':>6} {'acc':>8} {'ECE':>6} "
        f"{'(95 % interval)':>16} {'if calibrated':>15} {'ms/expl.':>8} {'(max)':>8}"
    )


def _flag_summary(r: dict[str, Any]) -> dict[str, Any]:
    """One flag configuration's figures from its per-clip outcomes ``r`` (:func:`flag_fold`)."""
    return {
        "false_alarm": _rate(r["false_alarm"]),
        "false_alarm_measured": _rate(r["false_alarm_measured"]),
        "false_alarm_distance": _rate(r["false_alarm_distance"]),
        "false_alarm_features": _rate(r["false_alarm_features"]),
        "detection": _rate(r["detected"]),
        "detection_measured": _rate(r["detected_measured"]),
        "detection_distance": _rate(r["detected_distance"]),
        "detection_features": _rate(r["detected_features"]),
        **_calibration(
            [
                {"right": h, "confidence": c}
                for h, c in zip(r["right"], r["confidence"], strict=True)
            ]
        ),  # fmt: skip
        "held_out_clips": len(r["false_alarm"]),
        "other_clips": len(r["detected"]),
        "detection_measured_by_activity": _by_activity(r["other_label"], r["detected_measured"]),
        "detection_distance_by_activity": _by_activity(r["other_label"], r["detected_distance"]),
        "detection_features_by_activity": _by_activity(r["other_label"], r["detected_features"]),
    }


def _by_fold(folds: list[dict[str, Any]], cfg: str) -> list[dict[str, Any]]:
    """Each fold's false alarms and detection (without the sensor rule) under ``cfg``: how
    evenly the flag treats new people (a held-out person unlike the training ones raises its
    fold's false alarms however well the flag is calibrated on average)."""
    return [{"held_out": f["seconds"]["held_out"],
             "false_alarm": _rate(f["flags"][cfg]["false_alarm"]),
             "detection_measured": _rate(f["flags"][cfg]["detected_measured"])}
            for f in folds if cfg in f.get("flags", {})]  # fmt: skip


def _calibration(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Accuracy and ECE of clips' ``right`` and ``confidence``, with the ECE's bootstrap 95 %
    interval (clips resampled): what is noise at a few hundred clips."""
    from cbr.calibration import ece_if_calibrated, ece_interval, expected_calibration_error

    right = np.array([r["right"] for r in rows], dtype=bool)
    conf = np.array([r["confidence"] for r in rows], dtype=np.float64)
    return {
        "clips": len(rows),
        "accuracy": _rate(right.tolist()),
        "mean_confidence": float(conf.mean()) if len(conf) else float("nan"),
        "ece": expected_calibration_error(conf, right),
        "ece_interval": ece_interval(conf, right),
        "ece_if_calibrated": ece_if_calibrated(conf),
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


def _tasks(args: argparse.Namespace) -> tuple[dict[str, Path], list[tuple[Any, ...]]]:
    """The datasets the shared run reads and its tasks, the longest first: the folds of both
    datasets (with the flags when the other dataset is here too), then UI-PRMD's movements."""
    paths: dict[str, Path] = {}
    tasks: list[tuple[Any, ...]] = []
    for name, (path, folds) in DATASETS.items():
        if name not in args.datasets:
            continue
        if not path.exists():
            print(f"{name}: skipped, {path} is not on this machine")
            continue
        other = DATASETS[_OTHER[name]][0]
        flags = other.exists() and not args.no_flags
        paths[name] = path
        if flags:
            paths[_OTHER[name]] = other
        tasks += [("fold", name, tuple(held), flags, not args.no_explain) for held in folds]
    path = DATASETS["ui-prmd"][0]
    if path.exists() and REPETITIONS in args.datasets:
        paths["ui-prmd"] = path
        _load({"ui-prmd": path})
        movements = sorted({c.label for c in _LOADED["ui-prmd"]})
        tasks += [("movement", m, not args.no_explain) for m in movements]
    return paths, tasks


def _run_shared(args: argparse.Namespace, done: Callable[[dict[str, Any]], None]) -> dict[str, Any]:
    """Both shared datasets held out by subject, and UI-PRMD's repetition check (those of
    ``args.datasets``), ``args.jobs`` tasks at a time; ``done`` is given the figures of the
    datasets finished so far after each task."""
    from cbr.evaluation.runner import ProcessRunner, Runner, SerialRunner

    paths, tasks = _tasks(args)
    runner: Runner[dict[str, Path]] = (
        ProcessRunner(paths, _load, args.jobs) if args.jobs > 1 else SerialRunner(paths, _load)
    )
    finished: dict[tuple[Any, ...], dict[str, Any]] = {}
    datasets: dict[str, Any] = {}
    for result in runner.map(_task, tasks, desc="folds", unit="fold"):
        print("\n".join(result["lines"]), flush=True)
        finished[result["task"]] = result
        _gather(tasks, finished, datasets)
        done({**datasets, **_so_far(tasks, finished, datasets)})
    return datasets


def _so_far(
    tasks: list[tuple[Any, ...]],
    finished: dict[tuple[Any, ...], dict[str, Any]],
    datasets: dict[str, Any],
) -> dict[str, Any]:
    """The figures of the datasets not finished yet over the tasks that are (a run stopped
    early keeps them), each with ``"partial"``: the tasks they cover."""
    out: dict[str, Any] = {}
    for name in DATASETS:
        mine = [t for t in tasks if t[:2] == ("fold", name) and t in finished]
        if name not in datasets and mine:
            out[name] = {**_dataset([finished[t] for t in mine]),
                         "partial": [list(t[2]) for t in mine]}  # fmt: skip
    moves = [t for t in tasks if t[0] == "movement" and t in finished]
    if "ui-prmd correct vs incorrect" not in datasets and moves:
        out["ui-prmd correct vs incorrect"] = {
            **_repetitions([finished[t] for t in moves]),
            "partial": [t[1] for t in moves],
        }
    return out


def _gather(
    tasks: list[tuple[Any, ...]],
    finished: dict[tuple[Any, ...], dict[str, Any]],
    datasets: dict[str, Any],
) -> None:
    """Put the figures of every dataset whose tasks have all ``finished`` in ``datasets`` (in
    the order of ``DATASETS``, the repetition check last)."""
    for name in (*DATASETS, REPETITIONS):
        rep = name == REPETITIONS
        mine = [t for t in tasks if (t[0] == "movement" if rep else t[:2] == ("fold", name))]
        key = "ui-prmd correct vs incorrect" if rep else name
        if key in datasets or not mine or any(t not in finished for t in mine):
            continue
        outcomes = [finished[t] for t in mine]  # in task order: the same figures as serial
        datasets[key] = _repetitions(outcomes) if rep else _dataset(outcomes)
    order = [*DATASETS, "ui-prmd correct vs incorrect"]
    ordered = {k: datasets[k] for k in order if k in datasets}
    datasets.clear()
    datasets.update(ordered)


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
        "--no-explain",
        action="store_true",
        help="the shared run's accuracy, ECE and flags only (no explanations: minutes, not hours)",
    )
    p.add_argument(
        "--datasets",
        default=",".join((*DATASETS, REPETITIONS)),
        help=f"of the shared data, these only (default: {','.join((*DATASETS, REPETITIONS))})",
    )
    p.add_argument(
        "--out",
        type=json_out,
        default=None,
        help=f"results JSON (default {RESULTS}; with --quick, explanations_quick.json beside it)",
    )
    p.add_argument(
        "--jobs", type=int, default=1, help="tasks of the shared run in parallel processes"
    )
    args = p.parse_args(argv if argv is not None else sys.argv[1:])
    if args.out is None:  # the demo subset's figures never replace the shared data's
        args.out = RESULTS.with_name("explanations_quick.json") if args.quick else RESULTS
    os.environ.setdefault("POSECBR_NO_PROGRESS", "1")
    from cbr.evaluation.machine import machine_info

    t_start = time.perf_counter()
    out: dict[str, Any] = {"benchmark": "explanations", "machine": machine_info(),
                           "load_average_start": os.getloadavg(), "jobs": args.jobs,
                           "datasets": {}}  # fmt: skip
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
            f"\n{'flag: dataset configuration':<36} {'f.alarm':>8} {'(dist.)':>8} {'(feat.)':>8} "
            f"{'detect':>8} {'(no sensor)':>8} {'(dist.)':>8} {'(feat.)':>8} {'acc':>8} {'ECE':>6} "
            f"{'(95 % interval)':>16} "
            f"{'if calibrated':>15}"
        )
        for name, d in out["datasets"].items():
            if "flags" in d:
                _print_flags(name, d["flags"])
    for d in out["datasets"].values():
        if "per_movement" in d:
            _print_movements(d["per_movement"])
    out["seconds"] = round(time.perf_counter() - t_start, 1)
    out["load_average_end"] = os.getloadavg()
    write_json(out, args.out)
    print(f"\nwritten {args.out} ({out['seconds']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
