"""Does a clip's repetition count go down as its end moves on?

Run: ``python -m benchmarks.repetition_growth [--per-group N] [--no-videos]`` (about 15
minutes at load 2; the videos are read by the pose model first). Writes
``benchmarks/results/repetition_growth.json``.

Every recording is counted (:func:`features.repetitions.count_repetitions`, as ``posecbr
reps`` counts a clip) from its start to an end moved on in steps of 0.25 s, from 0.5 s to
its last frame; a step whose count is lower than the step before is a decrease: a person
watching the count (``watch``'s rolling count) sees a repetition taken back. Reported per
source: the share of steps that decrease and of recordings with at least one.

- the joined recordings of ``python -m benchmarks.repetitions`` (UI-PRMD Kinect and Vicon, all
  eight subjects, and HDM05; ``--per-group`` per person and movement, seed 0: the first of
  that benchmark's draws);
- CMU subject 13's stretches counted by hand (``tests/fixtures/repetition_counts.json``), each
  from its own start to an end moved within it;
- the fixture's videos, as the pose model reads them.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from collections.abc import Iterator  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
from benchmarks._common import one_thread_machine, versions  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "repetition_growth.json"
STEP_S = 0.25
FIRST_S = 0.5


def ends(n_frames: int, fps: float) -> list[int]:
    """Frames at which a clip of ``n_frames`` is cut: every :data:`STEP_S` from
    :data:`FIRST_S`, and its last frame."""
    out = [int(round(t * fps)) for t in np.arange(FIRST_S, n_frames / fps, STEP_S)]
    return [e for e in out if e < n_frames] + [n_frames]


def counts(seq: Any) -> list[int]:
    """The count of ``seq`` cut at every one of :func:`ends` (0 when too short to count)."""
    from features.errors import DataError
    from features.repetitions import count_repetitions

    out = []
    for e in ends(seq.n_frames, seq.fps):
        try:
            out.append(count_repetitions(seq.slice_frames(0, e)).count)
        except DataError:
            out.append(0)
    return out


def recordings(per_group: int, videos: bool) -> Iterator[tuple[str, str, Any]]:
    from benchmarks.repetitions import hdm05_groups, joined_sequences, uiprmd_groups
    from benchmarks.segment import DATA, FIXTURE
    from features.clips import load_clip
    from features.readers.asfamc import read_asf_amc

    groups = uiprmd_groups("Kinect") + uiprmd_groups("Vicon") + hdm05_groups()
    for j in joined_sequences(groups, per_group, 0):
        g = j.group
        yield f"{g.dataset}/{g.person}/{g.movement} k={j.k}", g.dataset, j.seq
    cache: dict[str, Any] = {}
    for c in json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]:
        source = c["source"]
        if not source.endswith(".amc"):
            if videos:
                yield source, "videos", load_clip(DATA / source)
            continue
        if source not in cache:
            cache[source] = read_asf_amc(DATA / c["asf"], DATA / source)
        name = f"{source}[{c['start_frame']}:{c['end_frame']}] {c['activity']}"
        yield name, "cmu", cache[source].slice_frames(c["start_frame"], c["end_frame"])


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    out = {}
    for kind in [*sorted({r["kind"] for r in rows}), "all"]:
        mine = [r for r in rows if kind in ("all", r["kind"])]
        steps = sum(r["steps"] for r in mine)
        down = sum(r["decreases"] for r in mine)
        out[kind] = {
            "recordings": len(mine),
            "recordings_with_a_decrease": sum(r["decreases"] > 0 for r in mine),
            "steps": steps,
            "decreasing_steps": down,
            "decreasing_share": down / max(1, steps),
        }
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.repetition_growth", description=__doc__
    )
    parser.add_argument("--per-group", type=int, default=1, help="joined recordings per group")
    parser.add_argument("--no-videos", action="store_true", help="skip the videos")
    args = parser.parse_args(argv)
    rows = []
    t0 = time.process_time()
    for name, kind, seq in recordings(args.per_group, not args.no_videos):
        c = counts(seq)
        down = int((np.diff(c) < 0).sum())
        rows.append({"name": name, "kind": kind, "counts": c, "steps": len(c) - 1,
                     "decreases": down})  # fmt: skip
        if down:
            print(f"{name}: {c}", flush=True)
    summary = summarise(rows)
    print(f"\n{'source':<16} {'recordings':>10} {'with a decrease':>16} {'steps':>6} {'down':>5}")
    for kind, s in summary.items():
        share = f"{s['decreasing_share']:.2%}"
        print(f"{kind:<16} {s['recordings']:>10} {s['recordings_with_a_decrease']:>16}"
              f" {s['steps']:>6} {s['decreasing_steps']:>5} ({share})")  # fmt: skip
    write_json(
        {
            "benchmark": "repetition_growth",
            "command": "python -m benchmarks.repetition_growth"
            + f" --per-group {args.per_group}"
            + (" --no-videos" if args.no_videos else ""),
            "step_s": STEP_S,
            "machine": one_thread_machine(),
            "versions": versions("posecbr", "numpy", "scipy"),
            "cpu_seconds": time.process_time() - t0,
            "summary": summary,
            "recordings": rows,
        },
        RESULTS,
    )
    print(f"\nwrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
