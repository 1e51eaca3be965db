"""What storing the unknown judges with the model saves ``segment`` and ``watch`` at start, and
what it costs ``train`` (issue 14).

Run: ``python -m benchmarks.stored_judges [--repeats N]``. Writes
``benchmarks/results/stored_judges.json``.

The case base is the UI-PRMD Kinect one of ``benchmarks.segment_people`` (subjects s01-s04,
each person's repetitions of a movement joined and cut into the windows ``train --split
windows`` makes), stored as ``train`` stores it. Measured in this process, CPU and wall
seconds (median of ``--repeats``): the fit; calibrating the judges stored at fit
(:data:`cbr.unknown.AT_FIT`); loading the stored model; readying each judge with the stored
calibration (what ``segment`` and ``watch`` do now) and calibrating it on the loaded case base
(what they did at every start before, and still do for a model stored without judges). Each
stored judge is checked to equal the fresh one. The load average before and after says how
busy the machine was.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from benchmarks import write_json

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "stored_judges.json"


def _timed(f: Callable[[], Any]) -> tuple[Any, float, float]:
    """``f()`` with its wall and CPU seconds."""
    wall, cpu = time.perf_counter(), time.process_time()
    out = f()
    return out, time.perf_counter() - wall, time.process_time() - cpu


def _median(f: Callable[[], Any], repeats: int) -> tuple[Any, dict[str, float]]:
    """``f()`` run ``repeats`` times: its last result and the median wall and CPU seconds."""
    runs = [_timed(f) for _ in range(repeats)]
    return runs[-1][0], {
        "wall_s": round(statistics.median(r[1] for r in runs), 3),
        "cpu_s": round(statistics.median(r[2] for r in runs), 3),
    }


def build(db: Path) -> dict[str, Any]:
    """Fit and store the Kinect case base in ``db``: the seconds of each stage."""
    from benchmarks.segment_people import Reader, fit, folds, joined_training, training_clips
    from cbr.stored import calibrate_stored_judges
    from cbr.training import store_fitted

    read = Reader()
    fold = next(folds("ui-prmd-kinect", 1, 0, read))
    clips = training_clips(joined_training(fold.train, read))
    clf, fit_s = _median(lambda: fit(clips), 1)
    _, judges_s = _median(lambda: calibrate_stored_judges(clf), 1)
    _, store_s = _median(lambda: store_fitted(db, "default", clf, [c.label for c in clips]), 1)
    return {"cases": len(clf.case_base_), "fit": fit_s, "judges_at_fit": judges_s,
            "store_fitted_with_judges": store_s}  # fmt: skip


def start_up(db: Path, repeats: int) -> dict[str, Any]:
    """Loading the stored model and readying every judge, stored and fresh."""
    from cbr.judges import JUDGES
    from cbr.unknown import judge_of
    from posecbr.commands.segment import load_stored

    clf, load_s = _median(lambda: load_stored(str(db), None), repeats)
    stored = dict(clf.judges_)
    judges: dict[str, Any] = {}
    for name in JUDGES:
        clf.judges_ = stored
        kept, with_stored = _median(lambda: judge_of(clf, name), repeats)  # noqa: B023
        clf.judges_ = {}
        fresh, calibrated = _median(lambda: judge_of(clf, name), repeats)  # noqa: B023
        judges[name] = {"stored": name in stored, "with_stored": with_stored,
                        "calibrated_now": calibrated, "equal": kept == fresh}  # fmt: skip
    return {"load_model": load_s, "judges": judges}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    os.environ["POSECBR_NO_PROGRESS"] = "1"
    doc: dict[str, Any] = {"load_average_start": list(os.getloadavg()),
                           "cpus": os.cpu_count(), "repeats": args.repeats}  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "kinect.sqlite"
        doc["train"] = build(db)
        doc["start_up"] = start_up(db, args.repeats)
    doc["load_average_end"] = list(os.getloadavg())
    write_json(doc, RESULTS)
    t, s = doc["train"], doc["start_up"]
    print(f"UI-PRMD Kinect s01-s04, {t['cases']} cases: fit {t['fit']['cpu_s']:.1f} s CPU, "
          f"judges at fit {t['judges_at_fit']['cpu_s']:.1f} s CPU; load the model "
          f"{s['load_model']['cpu_s']:.2f} s CPU")  # fmt: skip
    for name, j in s["judges"].items():
        print(f"  {name:16s} stored {j['stored']!s:5s} ready from the model "
              f"{j['with_stored']['cpu_s']:.3f} s CPU, calibrated now "
              f"{j['calibrated_now']['cpu_s']:.3f} s CPU (wall {j['with_stored']['wall_s']:.3f} "
              f"/ {j['calibrated_now']['wall_s']:.3f} s); same judge: {j['equal']}")  # fmt: skip
    print(f"load average {doc['load_average_start'][0]:.1f} -> {doc['load_average_end'][0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
