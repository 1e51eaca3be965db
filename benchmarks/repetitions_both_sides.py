"""Repetition counts of movements that go out to both sides of rest, one side at a time.

Run: ``python -m benchmarks.repetitions_both_sides [--per-group N] [--seed S]`` (about a
minute). Writes ``benchmarks/results/repetitions_both_sides.json``.

The data sets hold single repetitions of one side only (HDM05's elbow to knee is the left
elbow to the right knee, its front kick the left leg; UI-PRMD's one-leg and one-arm
movements the subject's one side). A movement that alternates sides is made of them as
:mod:`benchmarks.repetitions` joins repetitions (:func:`features.joining.join_repetitions`):
K real repetitions (K drawn from 2..12) of one person and one movement, every second one
replaced by its mirror image (:func:`features.body.mirrored`: the same movement on the other
side), so the sides take turns, left, right, left, ... The count is K by construction, one
repetition per side, as :mod:`features.repetitions` counts an alternating movement and a
coach counts "5 each side" (ten). A mirror image keeps the person's own asymmetry mirrored
too: a take that starts in a stance with the kicking leg back starts its mirror with the
other leg back, as a person who kicks with each leg in turn does.

Every count is held out: no choice of the counting method looked at these recordings.
Reported per data set and movement: mean absolute error of the count (MAE), off-by-one
accuracy (|error| <= 1, OBO), the share counted exactly, the signed mean error and the share
of recordings counted as alternating.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
from collections import defaultdict  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
from benchmarks._common import one_thread_machine, versions  # noqa: E402
from benchmarks.repetitions import (  # noqa: E402
    HDM05,
    K_RANGE,
    ROOT,
    UIPRMD,
    Group,
    hdm05_groups,
    read_one,
    take_name,
    uiprmd_groups,
)

RESULTS = ROOT / "benchmarks" / "results" / "repetitions_both_sides.json"
HDM05_ONE_SIDE = ("elbowToKnee1RepsLelbowStart", "kickLFront1Reps")
"""HDM05's one-repetition clips of one side of a movement done on either side."""
UIPRMD_ONE_SIDE = ("m02", "m04", "m06", "m07", "m08", "m10")
"""UI-PRMD's movements of one side: hurdle step, side lunge, standing leg raise, shoulder
abduction, extension and scaption."""


def groups() -> list[Group]:
    """The groups of one-side repetitions: HDM05 (:data:`HDM05_ONE_SIDE`) and UI-PRMD Kinect's
    and Vicon's correct repetitions (:data:`UIPRMD_ONE_SIDE`)."""
    found = hdm05_groups(HDM05_ONE_SIDE)
    for sensor in ("Kinect", "Vicon"):
        found += [
            Group(
                g.dataset, g.person, g.movement, tuple(f for f in g.files if "_inc" not in f.name)
            )
            for g in uiprmd_groups(sensor)
            if g.movement in UIPRMD_ONE_SIDE
        ]
    return found


def run(per_group: int, seed: int) -> list[dict[str, Any]]:
    from features.body import mirrored
    from features.joining import join_repetitions
    from features.progress import progress
    from features.repetitions import count_repetitions

    rng = np.random.default_rng(seed)
    found = groups()
    rows = []
    for group in progress(found, total=len(found), desc="count"):
        cache: dict[Any, Any] = {}
        for _ in range(per_group):
            k = min(int(rng.integers(K_RANGE[0], K_RANGE[1] + 1)), len(group.files))
            picks = rng.choice(len(group.files), size=k, replace=False)
            reps, names = [], []
            for turn, i in enumerate(picks):
                path = group.files[int(i)]
                if path not in cache:
                    cache[path] = read_one(group, path).to_canonical()
                reps.append(cache[path] if turn % 2 == 0 else mirrored(cache[path]))
                names.append(take_name(path) + ("" if turn % 2 == 0 else " (mirrored)"))
            seq = join_repetitions(reps).seq
            t0 = time.process_time()
            counted = count_repetitions(seq)
            rows.append(
                {
                    "dataset": group.dataset,
                    "person": group.person,
                    "movement": group.movement,
                    "k": k,
                    "frames": seq.n_frames,
                    "takes": names,
                    "count": counted.count,
                    "alternating": counted.alternating,
                    "sides": [r.side for r in counted.repetitions],
                    "cpu_s": round(time.process_time() - t0, 4),
                }
            )
    return rows


def scores(rows: list[dict[str, Any]]) -> dict[str, float]:
    """MAE, off-by-one accuracy, exact share and signed mean error of ``rows``' counts, and
    the share counted as alternating."""
    errors = np.array([r["count"] - r["k"] for r in rows])
    err = np.abs(errors)
    return {
        "n": int(len(err)),
        "mae": float(err.mean()),
        "obo": float((err <= 1).mean()),
        "exact": float((err == 0).mean()),
        "mean_signed_error": float(errors.mean()),
        "alternating": float(np.mean([r["alternating"] for r in rows])),
    }


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    by: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        by[f"{r['dataset']} {r['movement']}"].append(r)
    return {"by_movement": {k: scores(v) for k, v in sorted(by.items())}, "all": scores(rows)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.repetitions_both_sides", description=__doc__
    )
    parser.add_argument("--per-group", type=int, default=2, help="recordings per group")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if not UIPRMD.is_dir() or not HDM05.is_dir():
        print(f"no ui-prmd or hdm05 data under {UIPRMD.parents[1]}: nothing to measure")
        return 1
    rows = run(args.per_group, args.seed)
    summary = summarise(rows)
    print(f"\n{'alternating sides, count known':<44} {'n':>4} {'MAE':>6} {'OBO':>6} {'exact':>6}"
          f" {'signed':>7} {'alt':>5}")  # fmt: skip
    for name, s in [*summary["by_movement"].items(), ("all", summary["all"])]:
        print(f"{name:<44} {s['n']:>4} {s['mae']:>6.2f} {s['obo']:>6.1%} {s['exact']:>6.1%}"
              f" {s['mean_signed_error']:>+7.2f} {s['alternating']:>5.0%}")  # fmt: skip
    write_json(
        {
            "benchmark": "repetitions_both_sides",
            "command": "python -m benchmarks.repetitions_both_sides"
            f" --per-group {args.per_group} --seed {args.seed}",
            "k_range": list(K_RANGE),
            "machine": one_thread_machine(),
            "versions": versions("posecbr", "numpy", "scipy"),
            "summary": summary,
            "recordings": rows,
        },
        RESULTS,
    )
    print(f"\nwrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
