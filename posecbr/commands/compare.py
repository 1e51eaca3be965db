"""``posecbr compare DATA``: cross-validate every similarity x feature level, DAD and peer
classifiers on a labelled dataset and print the table (JSON, CSV and pictures on request)."""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from pathlib import Path
from typing import Any

from features.errors import ConfigError, DataError


def _names(text: str) -> tuple[str, ...]:
    return tuple(s.strip() for s in text.split(",") if s.strip())


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "compare",
        help="cross-validate similarity measures x feature levels, DAD and peers on a dataset",
        description="Cross-validation by subject (leave-one-subject-out by default) of every "
        "case-base configuration (similarity x feature level), the DAD expert system and "
        "peer classifiers on the same folds. Prints accuracy and macro-F1 with 95 % "
        "intervals, times, case-base sizes and McNemar's exact test against the best method. "
        "With --target other than label (e.g. correct), one model is trained per activity.",
    )
    p.add_argument(
        "data",
        type=Path,
        help="dataset: UI-PRMD or HDM05 folder, labels CSV, folder per class, ...",
    )
    p.add_argument(
        "--target",
        default="label",
        help="what to predict: label (default), correct, or another metadata column",
    )
    p.add_argument(
        "--within",
        default="auto",
        metavar="COLUMN",
        help="train one model per value of COLUMN (default: per activity label when "
        "--target is not label); 'none' for one model over all clips",
    )
    p.add_argument(
        "--cv",
        choices=("loso", "kfold"),
        default="loso",
        help="leave-one-subject-out (default; falls back to stratified k-fold, with a "
        "note, when there is a single subject) or stratified k-fold over clips",
    )
    p.add_argument("--folds", type=int, default=5, metavar="K", help="folds for kfold (5)")
    p.add_argument(
        "--similarities",
        default="euclidean,dtw,signature",
        metavar="LIST",
        help="comma-separated similarity measures (default: all three)",
    )
    p.add_argument(
        "--features",
        default="fluents,qmp",
        metavar="LIST",
        help="comma-separated feature levels (default: fluents,qmp)",
    )
    p.add_argument("--no-dad", action="store_true", help="leave out the DAD baseline")
    p.add_argument(
        "--peers",
        default="dtw-knn,minirocket",
        metavar="LIST",
        help="peer classifiers: dtw-knn (tslearn), minirocket (needs sktime or "
        "aeon; skipped with a note otherwise); 'none' for no peers",
    )
    p.add_argument("--k", type=int, default=5, help="cases retrieved by the case-base classifier")
    p.add_argument(
        "--trim",
        type=float,
        default=None,
        metavar="F",
        help="keep fraction F of each activity's cases (novelty/benefit trimming) in "
        "every fold (default: keep all)",
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a further CaseBaseClassifier parameter for every case-base configuration "
        "(repeatable; VALUE is JSON or a plain string), e.g. --param states=all --param length=48",
    )
    p.add_argument("--sensor", default="kinect", help="UI-PRMD sensor: kinect or vicon")
    p.add_argument("--labels", default=None, metavar="LIST", help="only these activity labels")
    p.add_argument("--subjects", default=None, metavar="LIST", help="only these subjects")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="folds run in parallel (1)")
    p.add_argument("--seed", type=int, default=0, help="seed for k-fold, bootstrap, MiniRocket")
    p.add_argument(
        "--explain",
        type=int,
        default=5,
        metavar="N",
        help="explain N misclassified clips of the best case-base configuration",
    )
    p.add_argument("--json", type=Path, metavar="FILE", help="write all results as JSON")
    p.add_argument("--csv", type=Path, metavar="FILE", help="write one row per method as CSV")
    p.add_argument(
        "--out",
        type=Path,
        metavar="DIR",
        help="write results.json, results.csv and the pictures to DIR "
        "(then `posecbr report DIR --out report.html`)",
    )
    p.set_defaults(func=run)


def write_json(obj: Any, path: Path) -> None:
    """JSON to ``path`` atomically (temp file in the same folder, then rename)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        json.dump(obj, fh, indent=1, allow_nan=True)
    os.replace(tmp, path)


def write_csv(rows: list[dict[str, Any]], path: Path) -> None:
    """CSV rows to ``path`` atomically (columns: union of the rows' keys, first seen first)."""
    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w", encoding="utf-8", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, path)


def parse_params(items: list[str]) -> dict[str, Any]:
    """``KEY=VALUE`` pairs; VALUE read as JSON when it parses (numbers, lists), else a string."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"expected KEY=VALUE, got {item!r}", "--param")
        try:
            out[key.strip()] = json.loads(raw)
        except json.JSONDecodeError:
            out[key.strip()] = raw
    return out


def _load(args: argparse.Namespace) -> list[Any]:
    from features.datasets import load_dataset

    if not args.data.exists():
        raise DataError("no such dataset (file or folder)", args.data)
    kw: dict[str, Any] = {"sensor": args.sensor, "progress_desc": "loading"}
    if args.labels:
        kw["labels"] = set(_names(args.labels))
    if args.subjects:
        kw["subjects"] = set(_names(args.subjects))
    return load_dataset(args.data, **kw)


def pictures_with_data(results: dict[str, Any], out: Path, trim: float | None) -> dict[str, Any]:
    """Pictures that need the clips and an estimator: feature prevalence (initial vs trimmed
    case base) and one fluent timeline per activity."""
    from cbr.compare import example_clips, prevalence
    from cbr.report import plot_prevalence
    from features.fluents import evaluate
    from features.progress import progress
    from features.timeline import plot_timeline

    pics: dict[str, Any] = {}
    prev = prevalence(results, trim=trim if trim is not None and trim < 1.0 else 0.5)
    if prev is not None:
        plot_prevalence(prev, out / "prevalence.png")
        pics["prevalence"] = "prevalence.png"
        results["prevalence"] = prev
    timelines = []
    examples = example_clips(results)
    for i, (act, seq) in enumerate(
        progress(examples.items(), "timelines", total=len(examples), unit="clip")
    ):
        name = f"timeline_{i:02d}.png"
        clip = Path(seq.source).name if seq.source else act
        plot_timeline(evaluate(seq.to_canonical()), out / name, title=f"{act}: {clip}")
        timelines.append({"activity": act, "clip": clip, "file": name})
    pics["timelines"] = timelines
    return pics


def run(args: argparse.Namespace) -> int:
    from cbr.compare import (
        CompareSettings,
        csv_rows,
        explain_dad_errors,
        explain_errors,
        format_table,
        public,
    )
    from cbr.compare import run_compare as run_engine

    peers = () if args.peers.strip().lower() == "none" else _names(args.peers)
    within = None if args.within.lower() == "none" else args.within
    settings = CompareSettings(
        target=args.target,
        cv=args.cv,
        folds=args.folds,
        similarities=_names(args.similarities),
        features=_names(args.features),
        dad=not args.no_dad,
        peers=peers,
        k=args.k,
        trim=args.trim,
        cbr_params=parse_params(args.param),
        within=within,
        jobs=args.jobs,
        seed=args.seed,
        explain=args.explain,
    )
    clips = _load(args)
    results = run_engine(clips, settings, source=str(args.data))
    results["explanations"] = explain_errors(results, settings.explain)
    results["explanations"] += explain_dad_errors(results, min(settings.explain, 3))
    for note in results["notes"]:
        print(f"note: {note}", file=sys.stderr)
    print(format_table(results))
    if results["best"]:
        print(f"best: {results['best']}; best interpretable (*): {results['best_interpretable']}")
    if args.out:
        from cbr.report import make_pictures

        args.out.mkdir(parents=True, exist_ok=True)
        pics = make_pictures(results, args.out)
        pics.update(pictures_with_data(results, args.out, args.trim))
        results["pictures"] = pics
    data = public(results)
    if args.out:
        write_json(data, args.out / "results.json")
        write_csv(csv_rows(data), args.out / "results.csv")
        print(
            f"results and pictures in {args.out}; report: posecbr report {args.out} "
            f"--out {args.out / 'report.html'}"
        )
    if args.json:
        write_json(data, args.json)
    if args.csv:
        write_csv(csv_rows(data), args.csv)
    return 0
