"""Accuracy benchmark: ``posecbr compare`` on the real data beside the project.

Every similarity x feature level, DAD, and the peers (tslearn DTW 1-NN on eight limb angles;
MiniRocket when sktime or aeon is installed), cross-validated leave-one-subject-out on
UI-PRMD movement type, UI-PRMD correct-versus-incorrect (one model per movement) and HDM05
actions. Prints one table per task and writes ``benchmarks/results/compare.json`` with the
figures, the best interpretable configuration's margin over each peer (accuracy difference,
McNemar p over the clips and Wilcoxon p over the subjects held out) and its prediction-time
ratio to them, plus machine and versions.

    python -m benchmarks.compare            # all three tasks on ../shared/data (~20 min)
    python -m benchmarks.compare --quick    # the bundled demo subset only (~1 min)
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

from benchmarks import write_json

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = Path(__file__).resolve().parent / "results" / "compare.json"

TASKS = (
    ("ui-prmd movement", SHARED / "ui-prmd", "label"),
    ("ui-prmd correct", SHARED / "ui-prmd", "correct"),
    ("hdm05 action", SHARED / "hdm05", "label"),
)
QUICK = (("demo ui-prmd movement", ROOT / "posecbr" / "demo_data" / "uiprmd", "label"),)


def summarise(results: dict[str, Any], seconds: float) -> dict[str, Any]:
    """The figures kept for one task (no per-clip predictions)."""
    keep = (
        "name",
        "kind",
        "interpretable",
        "status",
        "message",
        "accuracy",
        "accuracy_ci",
        "macro_f1",
        "macro_f1_ci",
        "fit_s",
        "predict_ms_per_clip",
        "case_base_size",
        "mcnemar_p",
        "accuracy_ci_people",
        "wilcoxon_p",
        "wilcoxon_n",
        "per_group",
    )
    methods = [{k: m[k] for k in keep if k in m and m[k] != {}} for m in results["methods"]]
    by_name = {m["name"]: m for m in results["methods"]}
    versus = []
    bi = by_name.get(results["best_interpretable"] or "")
    if bi is not None:
        import numpy as np

        from cbr.evaluation.stats import mcnemar_exact, signed_rank

        for m in results["methods"]:
            if m["kind"] != "peer" or m["status"] != "ok":
                continue
            a, b = np.array(bi["correct"]), np.array(m["correct"])
            ratio = bi["predict_ms_per_clip"] / max(m["predict_ms_per_clip"], 1e-9)
            people = bi.get("per_subject") or {}
            # over the subjects held out (leave-one-subject-out only): the person as the unit
            d = [people[p]["accuracy"] - m["per_subject"][p]["accuracy"] for p in people]
            versus.append(
                {
                    "interpretable": bi["name"],
                    "peer": m["name"],
                    "accuracy_difference": bi["accuracy"] - m["accuracy"],
                    "mcnemar_p": mcnemar_exact(int((a & ~b).sum()), int((~a & b).sum())),
                    "wilcoxon_p": signed_rank(np.array(d))[2] if d else None,
                    "predict_time_ratio": ratio,
                }
            )
    return {
        "dataset": results["dataset"]["source"],
        "n_clips": results["dataset"]["n_clips"],
        "subjects": results["dataset"]["subjects"],
        "classes": results["dataset"]["classes"],
        "cv": {k: v for k, v in results["cv"].items() if k != "fold_of_clip"},
        "notes": results["notes"],
        "best": results["best"],
        "best_interpretable": results["best_interpretable"],
        "methods": methods,
        "best_interpretable_vs_peers": versus,
        "seconds": round(seconds, 1),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.compare")
    parser.add_argument(
        "--quick", action="store_true", help="demo subset only (written to compare_quick.json)"
    )
    parser.add_argument("--jobs", type=int, default=1, help="folds in parallel")
    args = parser.parse_args(argv if argv is not None else sys.argv[1:])
    os.environ.setdefault("POSECBR_NO_PROGRESS", "1")

    from cbr.evaluation.compare import run_compare
    from cbr.evaluation.machine import machine_info
    from cbr.evaluation.settings import CompareSettings
    from cbr.evaluation.tables import format_table
    from features.datasets import load_dataset

    tasks = QUICK if args.quick else TASKS
    out: dict[str, Any] = {"benchmark": "compare", "machine": machine_info(), "tasks": {}}
    for name, path, target in tasks:
        if not path.exists():
            print(f"{name}: skipped, {path} is not on this machine")
            out["tasks"][name] = {"status": "skipped", "reason": f"{path} missing"}
            continue
        t0 = time.perf_counter()
        clips = load_dataset(path)
        settings = CompareSettings(target=target, jobs=args.jobs, explain=0)
        results = run_compare(clips, settings, source=str(path)).results
        seconds = time.perf_counter() - t0
        print(f"\n{name} ({len(clips)} clips, {seconds:.0f} s)")
        print(format_table(results))
        for note in results.notes:
            print(f"note: {note}")
        out["tasks"][name] = summarise(results.to_dict(), seconds)
    # the demo subset's figures never replace the shared data's (README quotes those)
    path = RESULTS.with_name(f"{RESULTS.stem}_quick.json") if args.quick else RESULTS
    write_json(out, path)
    print(f"\nwritten {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
