"""Frame-rate dependence: do the same clips get the same answers at a lower frame rate?

A case base is trained at the recordings' own rate, and its held-out clips are classified at
that rate and again at a half and a quarter of it (every 2nd / 4th frame kept, the frame rate
divided accordingly: what a camera at that rate would have recorded). Counted: how many
answers change against the native rate's, and the accuracy at each rate.

- UI-PRMD Vicon (100 Hz; correct repetitions only), movement, subjects s03, s07, s08 held out;
- UI-PRMD Kinect (30 Hz), movement, the same subjects held out;
- UI-PRMD Kinect, correct vs incorrect, one case base per movement (class-balanced vote, as
  ``train --target correct``), the same subjects held out;
- HDM05 (120 Hz), actions, each actor held out once.

Configurations: fluents under euclidean (clip summaries) and dtw (sequences), QMPs under
euclidean (``--quick``: HDM05 alone).

First run (2026-12-06, ``benchmarks/results/frame_rate.json``): answers changed at 1/2 and 1/4
rate, of 600 Kinect clips: movement fluents/euclidean 7 and 14, dtw 3 and 10, QMPs 25 and 86;
correct vs incorrect 47 and 64, 23 and 40, 32 and 115; Vicon (290) and HDM05 (189) none for
fluents/euclidean and dtw, QMPs 0 and 1, 3 and 5. Resampling each clip's columns by area
(each of the 32 frames the mean of its stretch of the clip, instead of the clip read at 32
instants) did not lower the fluent counts (Kinect movement 9 and 19, 9 and 13; correct 40 and
70, 25 and 41): at a lower rate the motion states' confidences differ (a clip's fluent summary
moved about 3 times as far as without the motion states), not what resampling reads.

Why the motion states differ (issue 36h): eq. 5 multiplies the confidences of five Δs, so one
small Δ pulls "moving" down, and a lower rate has smaller jitter in its Δs. An angle moving
1.5·π/72 a frame at 30 fps with ±0.5·π/72 of jitter alternating frame by frame has Δs of 2.5
and 0.5·π/72 (confidences 1 and 0.031; "moving" 0.073 and 0.005, frame by frame); every 2nd
(or 4th) frame carries the same jitter, so at 15 and 7.5 fps each Δ (a reference interval's
share of a frame's change) is 1.5·π/72 (0.969) and "moving" 0.931. White jitter of σ a frame
gives Δ a spread of σ√2 at the reference rate, σ√2/2 at a half and σ√2/4 at a quarter. The
53-frame s07 scaption clip (m10 e07) is this case: its left upper arm's Δs at 30 fps run
-2.3, -0.56, -2.6, -1.76, -1.32, -3.48, -0.26, -1.92 (·π/72), at 15 fps -1.1 to -2.5;
"moving outward" peaks at 0.51 at 30 fps, 1.0 at 15 fps. SPEC fixes Δθ_t = θ_t − θ_{t−1} at
the reference rate and leaves open only how Δ is taken at another rate, where no choice puts
the jitter back (interpolating and rescaling give the same Δs), so it is not changed. Tried
outside SPEC in a scratch copy (``results/frame_rate_motion_baseline2.json``): Δ over two
reference intervals, halved ((θ_t − θ_{t−2})/2 at 30 fps, the same spread as at 15 fps). Kinect
clip summaries moved by RMS 0.027 / 0.043 between native and 1/2 / 1/4 rate (0.035 / 0.050
with SPEC's Δ); answers changed at 1/2, 1/4: movement euclidean 7, 14 -> 4, 10, dtw 3, 10 -> 9,
14, correct 47, 64 -> 14, 32 and 23, 40 -> 14, 29; native accuracy 96.5 -> 96.3, 82.7 -> 84.7,
81.0 -> 82.3, 66.7 -> 68.0 %; Vicon and HDM05 none changed, accuracy the same (Vicon dtw
85.5 -> 85.9). Not adopted: outside SPEC, and dtw's movement answers changed more.

Prints the table and writes ``benchmarks/results/frame_rate.json`` with machine and versions.

    python -m benchmarks.frame_rate           # 653 s on 2 cores at load 4-10 (longer loaded)
    python -m benchmarks.frame_rate --quick
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import write_json

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = Path(__file__).resolve().parent / "results" / "frame_rate.json"

HELD_OUT = ("s03", "s07", "s08")
RATES = (1, 2, 4)  # keep every k-th frame
CONFIGS = (
    ("fluents", "euclidean"),
    ("fluents", "dtw"),
    ("qmp", "euclidean"),
)
#: (task, dataset folder, sensor, target)
TASKS = (
    ("ui-prmd vicon movement", "ui-prmd", "vicon", "label"),
    ("ui-prmd kinect movement", "ui-prmd", "kinect", "label"),
    ("ui-prmd kinect correct", "ui-prmd", "kinect", "correct"),
    ("hdm05 action", "hdm05", "", "label"),
)
QUICK_TASKS = (TASKS[3],)


def decimated(seq: Any, k: int) -> Any:
    """``seq`` with every ``k``-th frame, at a ``k``-th of its frame rate."""
    if k == 1:
        return seq
    conf = None if seq.confidence is None else seq.confidence[::k]
    return dataclasses.replace(seq, positions=seq.positions[::k], confidence=conf,
                               fps=seq.fps / k)  # fmt: skip


def _folds(clips: list[Any], folder: str) -> list[tuple[str, ...]]:
    if folder == "hdm05":  # three actors: each held out once
        return [(s,) for s in sorted({str(c.subject) for c in clips})]
    return [HELD_OUT]


def run_task(
    clips: list[Any], folder: str, target: str, level: str, similarity: str
) -> dict[str, Any]:
    """Train at the native rate on all but the held-out subjects, classify the held-out
    clips at every rate of :data:`RATES`: accuracy per rate and answers changed."""
    from cbr.estimator import CaseBaseClassifier

    truth: list[str] = []
    answers: dict[int, list[str]] = {k: [] for k in RATES}
    per_movement = target != "label"
    groups = sorted({c.label for c in clips}) if per_movement else [None]

    def solution(c: Any) -> str:
        return str(c.extras[target]) if per_movement else str(c.label)

    for held in _folds(clips, folder):
        for group in groups:
            mine = [c for c in clips if group in (None, c.label)]
            train = [c for c in mine if c.subject not in held]
            test = [c for c in mine if c.subject in held]
            est = CaseBaseClassifier(
                features=level,
                similarity=similarity,
                class_weight="balanced" if per_movement else "none",
            )
            est.fit([c.seq for c in train], [solution(c) for c in train])
            truth += [solution(c) for c in test]
            for k in RATES:
                answers[k] += [str(a) for a in est.predict([decimated(c.seq, k) for c in test])]
    y = np.array(truth)
    got = {k: np.array(v) for k, v in answers.items()}
    return {
        "clips": len(y),
        "accuracy": {str(k): float((got[k] == y).mean()) for k in RATES},
        "changed": {str(k): int((got[k] != got[1]).sum()) for k in RATES[1:]},
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks.frame_rate",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--quick", action="store_true", help="HDM05 alone")
    args = ap.parse_args(argv)
    from cbr.evaluation.machine import machine_info
    from features.datasets import load_dataset

    start = time.perf_counter()
    rows = []
    print("| task | configuration | clips | accuracy 1 / 1/2 / 1/4 rate | answers changed at 1/2, "
          "1/4 |")  # fmt: skip
    print("| --- | --- | ---: | --- | --- |")
    for task, folder, sensor, target in QUICK_TASKS if args.quick else TASKS:
        kwargs = {"sensor": sensor} if sensor else {}
        clips = load_dataset(SHARED / folder, **kwargs)
        for level, similarity in CONFIGS:
            row = run_task(clips, folder, target, level, similarity)
            row.update(task=task, configuration=f"{level}/{similarity}")
            rows.append(row)
            acc = " / ".join(f"{100 * row['accuracy'][str(k)]:.1f}" for k in RATES)
            changed = ", ".join(str(row["changed"][str(k)]) for k in RATES[1:])
            print(f"| {task} | {level}/{similarity} | {row['clips']} | {acc} % | {changed} |",
                  flush=True)  # fmt: skip
    doc = {
        "benchmark": "frame_rate",
        "machine": machine_info(),
        "protocol": {
            "rates": "native, every 2nd frame at half the rate, every 4th at a quarter",
            "held_out_subjects": list(HELD_OUT),
            "hdm05": "each actor held out once",
            "quick": bool(args.quick),
        },
        "rows": rows,
        "seconds": round(time.perf_counter() - start, 1),
        "load_average": list(os.getloadavg()),
    }
    out = RESULTS.with_name("frame_rate_quick.json") if args.quick else RESULTS
    write_json(doc, out)
    print(f"\nwritten to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
