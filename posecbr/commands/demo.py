"""``posecbr demo``: the main job on the bundled UI-PRMD subset, end to end.

describe one clip -> train a case base on two subjects -> classify the third subject's clips
with explanations -> compare similarity measures, feature levels and DAD by leave-one-subject-
out cross-validation -> write the HTML report. Every step is the same command a user runs.
"""

from __future__ import annotations

import argparse
import shutil
import time
from pathlib import Path

from features.errors import PosecbrError

DEMO_DATA = Path(__file__).resolve().parents[2] / "data" / "demo" / "uiprmd"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help="train, classify, compare and report on the bundled UI-PRMD subset",
        description="Runs describe -> train -> classify -> compare -> report on the bundled "
        "UI-PRMD subset (3 subjects x 10 movements x 6 repetitions) and says where the report is.",
    )
    p.add_argument("--data", type=Path, default=DEMO_DATA, help="labels CSV folder of the demo")
    p.add_argument("--out", type=Path, default=Path("demo-output"), help="output folder")
    p.add_argument(
        "--features",
        default="qmp",
        choices=["fluents", "qmp"],
        help="feature level of the demo case base (default qmp)",
    )
    p.add_argument("--similarity", default="euclidean", help="similarity of the demo case base")
    p.add_argument(
        "--quick", action="store_true", help="compare only a few configurations (faster)"
    )
    p.set_defaults(func=run)


def _step(title: str) -> float:
    print(f"\n== {title} ==", flush=True)
    return time.perf_counter()


def run(args: argparse.Namespace) -> int:
    from posecbr.cli import main

    labels = args.data / "labels.csv"
    if not labels.is_file():
        raise PosecbrError("demo data not found (expected labels.csv)", args.data)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    db = out / "casebase.sqlite"
    for stale in (db, db.with_name(db.name + "-wal"), db.with_name(db.name + "-shm")):
        stale.unlink(missing_ok=True)
    shutil.rmtree(out / "compare", ignore_errors=True)

    t = _step("1. describe: a deep squat in words (posecbr describe)")
    clip = args.data / "m01_s01_e01.npz"
    code = main(["describe", str(clip), "--plot", str(out / "timeline_deep_squat.png")])
    if code:
        return code
    print(f"({time.perf_counter() - t:.1f} s)")

    t = _step("2. train: case base from subjects s01 and s02 (posecbr train)")
    code = main(["train", str(labels), "--db", str(db), "--subjects", "s01,s02",
                 "--features", args.features, "--similarity", args.similarity])  # fmt: skip
    if code:
        return code
    print(f"({time.perf_counter() - t:.1f} s)")

    t = _step("3. classify: subject s03, unseen in training (posecbr classify)")
    code = main(["classify", str(labels), "--db", str(db), "--subjects", "s03", "--top", "2"])
    if code:
        return code
    print(f"({time.perf_counter() - t:.1f} s)")

    t = _step("4. compare: leave-one-subject-out over every configuration (posecbr compare)")
    compare = ["compare", str(labels), "--out", str(out / "compare")]
    if args.quick:
        compare += ["--similarities", "euclidean,dtw", "--features", "fluents,qmp"]
    code = main(compare)
    if code:
        return code
    print(f"({time.perf_counter() - t:.1f} s)")

    t = _step("5. report (posecbr report)")
    report = out / "report.html"
    code = main(["report", str(out / "compare"), "--out", str(report)])
    if code:
        return code
    print(f"({time.perf_counter() - t:.1f} s)")
    print(f"\nDone. Case base: {db}\nReport: {report.resolve()}")
    return 0
