"""Does a clip whose person is lost from view count as the clip ending there?

Run: ``python -m benchmarks.lost_view`` (about a minute). Writes
``benchmarks/results/lost_view.json``.

Each single squat of HDM05 (actors bd, bk, dg) and of UI-PRMD's deep squats (``m01``, Vicon and
Kinect, episodes 1-3 of the eight subjects) that ``posecbr reps`` counts as one repetition
(start, far point, end): none or one copy of the whole take, then its frames up to a cut (half
way from the start to the far point, or 0.1 s before the far point), counted as it is and with
1 s in which nobody is seen after it (every joint NaN; a video's confidence 0). A person
watching says the same of both: the view of the movement ends where the person is lost, as it
ends where the clip does. With no whole copy before it, the way down alone is no repetition:
0. Counted as ``posecbr reps`` counts a clip (:func:`posecbr.commands.reps._count`).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import time  # noqa: E402
from collections.abc import Iterator  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
from benchmarks._common import DATA, one_thread_machine, versions  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "lost_view.json"
LOST_S = 1.0  # nobody in view after the cut


def takes() -> Iterator[Path]:
    """The single squats read: HDM05's, then UI-PRMD's deep squats (Vicon, Kinect)."""
    yield from sorted(DATA.glob("hdm05/train/*/HDM_*_squat1Reps_*.amc"))
    ui = DATA / "ui-prmd" / "data" / "Segmented Movements"
    yield from sorted(ui.glob("Vicon/Positions/m01_s0*_e0[1-3]*"))
    yield from sorted(ui.glob("Kinect/Positions/m01_s0*_e0[1-3]_positions*"))


def _counted(seq: Any, positions: np.ndarray, confidence: np.ndarray | None) -> int | None:
    from features.errors import DataError
    from posecbr.commands.reps import _count

    clip = dataclasses.replace(seq, positions=positions, confidence=confidence, metadata={})
    try:
        return int(_count(clip).count)
    except DataError:  # shorter than a repetition can be
        return None


def cases(path: Path) -> list[dict[str, Any]]:
    """Each cut of the take at ``path``: its count ending there and with the person lost."""
    from posecbr.recordings import load_recording

    seq = load_recording(path, None, None).to_canonical()
    whole = _counted(seq, seq.positions, seq.confidence)
    if whole != 1:
        return []
    from posecbr.commands.reps import _count

    rep = _count(seq).repetitions[0]
    a, p = rep.start_frame, rep.peak_frame
    out = []
    for copies in (0, 1):
        for cut in ((a + p) // 2, p - max(1, int(0.1 * seq.fps))):
            pos = np.concatenate([seq.positions] * copies + [seq.positions[:cut]])
            nan = np.full((int(LOST_S * seq.fps), *pos.shape[1:]), np.nan)
            conf = None
            if seq.confidence is not None:
                conf = np.concatenate([seq.confidence] * copies + [seq.confidence[:cut]])
            ended = _counted(seq, pos, conf)
            lost_conf = None if conf is None else np.concatenate([conf, np.zeros(nan.shape[:2])])
            lost = _counted(seq, np.concatenate([pos, nan]), lost_conf)
            if ended is None or lost is None:
                continue
            out.append({"take": path.name, "whole_before": copies, "cut_frame": cut,
                        "ended": ended, "lost": lost})  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.lost_view", description=__doc__)
    parser.parse_args(argv)
    t0 = time.process_time()
    rows = [row for path in takes() for row in cases(path)]
    alone = [r for r in rows if r["whole_before"] == 0]
    summary = {
        "clips": len(rows),
        "lost_as_ended": sum(r["lost"] == r["ended"] for r in rows),
        "way_down_alone": len(alone),
        "way_down_alone_lost_counted_0": sum(r["lost"] == 0 for r in alone),
    }
    for r in rows:
        if r["lost"] != r["ended"]:
            print(f"{r['take']} after {r['whole_before']} whole, cut at frame {r['cut_frame']}:"
                  f" ended {r['ended']}, lost {r['lost']}")  # fmt: skip
    same, zero = summary["lost_as_ended"], summary["way_down_alone_lost_counted_0"]
    print(f"lost for {LOST_S:g} s counted as the clip ending there: {same} of {len(rows)};"
          f" the way down alone, then lost, 0: {zero} of {len(alone)}")  # fmt: skip
    write_json(
        {
            "benchmark": "lost_view",
            "command": "python -m benchmarks.lost_view",
            "machine": one_thread_machine(),
            "versions": versions("posecbr", "numpy", "scipy"),
            "cpu_seconds": time.process_time() - t0,
            "summary": summary,
            "clips": rows,
        },
        RESULTS,
    )
    print(f"wrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
