"""``posecbr demo``: the main job on the bundled UI-PRMD subset, end to end.

describe one clip -> train a case base on two subjects -> classify the third subject's clips
with explanations -> compare similarity measures, feature levels and DAD by leave-one-subject-
out cross-validation -> write the HTML report. Every step is the same command a user runs.

The data ships inside the package (``posecbr/demo_data/uiprmd``, found with
:mod:`importlib.resources`), so the demo runs wherever posecbr is installed.
"""

from __future__ import annotations

import argparse
import shutil
import time
from importlib import resources
from pathlib import Path

from features.errors import DataError, PosecbrError

# --quick: one configuration, no DAD or peers, one explanation and no pictures that need the
# clips again (the report draws the accuracy and confusion pictures from the results).
QUICK_COMPARE = ("--similarities", "euclidean", "--features", "fluents", "--no-dad",
                 "--peers", "none", "--explain", "1")  # fmt: skip


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help="train, classify, compare and report on the bundled UI-PRMD subset",
        description="Runs describe -> train -> classify -> compare -> report on the bundled "
        "UI-PRMD subset (3 subjects x 10 movements x 6 repetitions) and says where the report is.",
    )
    p.add_argument(
        "--data",
        type=Path,
        default=None,
        help="folder with the demo's labels.csv (default: the subset bundled with posecbr)",
    )
    p.add_argument("--out", type=Path, default=Path("demo-output"), help="output folder")
    p.add_argument(
        "--features",
        default="qmp",
        choices=["fluents", "qmp"],
        help="feature level of the demo case base (default qmp)",
    )
    p.add_argument("--similarity", default="euclidean", help="similarity of the demo case base")
    p.add_argument(
        "--quick",
        action="store_true",
        help="compare one configuration (fluents/euclidean) without DAD, peers or the "
        "per-activity pictures: seconds instead of about a minute",
    )
    p.set_defaults(func=run)


def _step(title: str) -> float:
    print(f"\n== {title} ==", flush=True)
    return time.perf_counter()


def _check_out(out: Path, data: Path) -> None:
    """The output folder: created if needed, never a file, never the demo data (the demo
    clears its own earlier outputs there)."""
    if out.exists() and not out.is_dir():
        raise DataError("exists and is not a folder", out)
    if out.resolve() == data.resolve() or data.resolve() in out.resolve().parents:
        raise DataError("is the demo data folder or inside it: choose another --out", out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DataError(f"cannot create: {exc.strerror or exc}", out) from None


def run(args: argparse.Namespace) -> int:
    if args.data is not None:
        return _run(args, args.data)
    with resources.as_file(resources.files("posecbr") / "demo_data" / "uiprmd") as bundled:
        return _run(args, bundled)


def _run(args: argparse.Namespace, data: Path) -> int:
    from posecbr.cli import main

    labels = data / "labels.csv"
    if not labels.is_file():
        raise PosecbrError("demo data not found (expected labels.csv)", data)
    out: Path = args.out
    _check_out(out, data)
    db = out / "casebase.sqlite"
    for stale in (db, db.with_name(db.name + "-wal"), db.with_name(db.name + "-shm")):
        stale.unlink(missing_ok=True)
    shutil.rmtree(out / "compare", ignore_errors=True)

    t = _step("1. describe: a deep squat in words (posecbr describe)")
    clip = data / "m01_s01_e01.npz"
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

    t = _step("4. compare: leave-one-subject-out cross-validation (posecbr compare)")
    results = out / "compare"
    compare = ["compare", str(labels)]
    if args.quick:
        results.mkdir()  # compare --json writes into an existing folder only
        results = results / "results.json"
        compare += [*QUICK_COMPARE, "--json", str(results)]
    else:
        compare += ["--out", str(results)]
    code = main(compare)
    if code:
        return code
    print(f"({time.perf_counter() - t:.1f} s)")

    t = _step("5. report (posecbr report)")
    report = out / "report.html"
    code = main(["report", str(results), "--out", str(report)])
    if code:
        return code
    print(f"({time.perf_counter() - t:.1f} s)")
    print(f"\nDone. Case base: {db}\nReport: {report.resolve()}")
    return 0
