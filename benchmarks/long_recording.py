"""What a user waits for on a long recording: ``posecbr segment``, ``reps`` and ``train
--frame-labels`` end to end, each in a process of its own, with the threads a user gets.

    python -m benchmarks.long_recording                 # 3 repeats, about 5 minutes idle
    python -m benchmarks.long_recording --repeats 5 --minutes 10

Unlike ``benchmarks.segment`` (segmentation alone after feature extraction, every library
pinned to one thread), each row here is a whole command as typed: reading the file, the
features, the case base, the answer, and BLAS, onnxruntime and numba with their default
threads. Inputs, made in a temporary folder:

- *mocap*: CMU subject 13's three recordings of ``cmu-mocap6`` (120 fps; ``posecbr convert``
  with HDM05's ``HDM_bd.asf``, as the README does) one after the other, repeated to
  ``--minutes`` (10: 72,000 frames); the case base: 13_29 and 13_30 labelled every 0.1 s
  (``train`` of a labels CSV: 2-s windows);
- *video*: the 25-fps videos of ``../shared/data/videos`` through ``posecbr extract``
  (BlazePose), their pose files one after the other, repeated to half of ``--minutes``; the
  case base: those pose files, a case per repetition (``train --split repetitions``).

Rows: ``segment`` of both, ``reps`` of the mocap, and ``train 13_29 --frame-labels`` (one
recording labelled over time). Per row the median over ``--repeats`` of the process's CPU
time (user + system, its own and its threads'), its wall time and its peak resident memory
(``ru_maxrss`` from ``wait4``), and times real time (the recording's length over the median
CPU time). The rows run in rounds, each round every row once (a slow spell of the shared
machine falls on all alike); the load average is recorded with each run. Every repeat of a
row must print the same output (checked). Results: ``benchmarks/results/long_recording.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks import json_out, write_json

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results" / "long_recording.json"
CMU = DATA / "cmu-mocap6"
ASF = DATA / "hdm05" / "train" / "3" / "HDM_bd.asf"
VIDEOS = DATA / "videos"
TAKES = ("13_29", "13_30", "13_31")
NAMES = ("JumpJack", "Jog", "Squat", "KneeRaise", "ArmCircle", "Twist", "SideReach", "Box",
         "UpDown", "ToeTouchOneHand", "SideBend", "ToeTouchTwoHands")  # fmt: skip


def _posecbr(*argv: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "posecbr", *argv], cwd=ROOT, capture_output=True, text=True
    )
    if done.returncode != 0:
        raise SystemExit(f"posecbr {' '.join(argv)} failed:\n{done.stderr[-2000:]}")


def _tiled(parts: list[Path], frames: int, fps: float, out: Path) -> Path:
    """The pose files ``parts`` one after the other, repeated to ``frames`` frames."""
    import dataclasses

    import numpy as np

    from features.poses import load_pose, save_pose

    seqs = [load_pose(p) for p in parts]
    pos, conf, n, i = [], [], 0, 0
    while n < frames:
        s = seqs[i % len(seqs)]
        pos.append(s.positions)
        conf.append(s.confidence if s.confidence is not None else np.ones(s.positions.shape[:2]))
        n, i = n + s.n_frames, i + 1
    long = dataclasses.replace(
        seqs[0],
        positions=np.concatenate(pos)[:frames],
        confidence=np.concatenate(conf)[:frames] if seqs[0].confidence is not None else None,
        fps=fps,
        source="tiled",
    )
    return save_pose(long, out)


def make_inputs(work: Path, minutes: float) -> dict[str, Path]:
    """The two recordings and their case bases (see the module docstring)."""
    for path in (CMU, ASF, VIDEOS):
        if not path.exists():
            raise SystemExit(f"python -m benchmarks.long_recording: missing {path}")
    cmu = work / "cmu"
    for take in TAKES:
        _posecbr("convert", str(CMU / "amc" / f"{take}.amc"), "--asf", str(ASF), "--out", str(cmu))
    (cmu / "names.txt").write_text(
        "".join(f"{i} {n}\n" for i, n in enumerate(NAMES, 1)), encoding="utf-8"
    )
    rows = [f"{t}.npz,{CMU / 'truelabels' / f'{t}.txt'},0.1,names.txt" for t in TAKES[:2]]
    (cmu / "train.csv").write_text(
        "path,label_file,label_block_s,label_names\n" + "\n".join(rows) + "\n", encoding="utf-8"
    )
    _posecbr("train", str(cmu / "train.csv"), "--db", str(work / "cmu.sqlite"))
    mocap = _tiled([cmu / f"{t}.npz" for t in TAKES], int(minutes * 60 * 120), 120.0,
                   work / "mocap.npz")  # fmt: skip
    poses = work / "poses"
    _posecbr("extract", str(VIDEOS), "--out", str(poses))
    import numpy as np

    at_25 = [p for p in sorted(poses.rglob("*.npz")) if float(np.load(p)["fps"]) == 25.0]
    video = _tiled(at_25, int(minutes * 30 * 25), 25.0, work / "video.npz")
    _posecbr("train", str(poses), "--db", str(work / "video.sqlite"), "--split", "repetitions")
    return {"mocap": mocap, "video": video, "cmu": cmu, "work": work}


def commands(inputs: dict[str, Path]) -> dict[str, tuple[list[str], float]]:
    """Each row's command line and the length (s) of what it reads."""
    work, cmu = inputs["work"], inputs["cmu"]
    mocap_s = _seconds(inputs["mocap"])
    return {
        "segment mocap": (
            ["segment", str(inputs["mocap"]), "--db", str(work / "cmu.sqlite"), "--json"],
            mocap_s,
        ),
        "segment video": (
            ["segment", str(inputs["video"]), "--db", str(work / "video.sqlite"), "--json"],
            _seconds(inputs["video"]),
        ),
        "reps mocap": (["reps", str(inputs["mocap"]), "--json"], mocap_s),
        "train --frame-labels 13_29": (
            [
                "train",
                str(cmu / "13_29.npz"),
                "--frame-labels",
                str(CMU / "truelabels" / "13_29.txt"),
                "--label-block",
                "0.1",
                "--label-names",
                str(cmu / "names.txt"),
                "--db",
                str(work / "fl.sqlite"),
                "--replace",
                "--json",
            ],
            _seconds(cmu / "13_29.npz"),
        ),  # fmt: skip
    }


def _seconds(path: Path) -> float:
    import numpy as np

    with np.load(path) as z:
        return float(len(z["positions"]) / float(z["fps"]))


def run_once(argv: list[str]) -> dict[str, Any]:
    """One command in a process of its own: CPU and wall seconds, peak memory, its output."""
    load = round(os.getloadavg()[0], 2)
    with tempfile.TemporaryFile() as out:
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            [sys.executable, "-m", "posecbr", *argv], cwd=ROOT, stdout=out,
            stderr=subprocess.DEVNULL,
        )  # fmt: skip
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        text = out.read().decode("utf-8", "replace")
    if proc.returncode != 0:
        raise SystemExit(f"posecbr {' '.join(argv)} failed (exit {proc.returncode})")
    return {"cpu_s": usage.ru_utime + usage.ru_stime, "wall_s": wall,
            "peak_mb": usage.ru_maxrss / 1024, "load": load, "output": text}  # fmt: skip


def _stable(label: str, text: str) -> str:
    """The output compared between repeats: train's JSON names its database's creation time."""
    if not label.startswith("train"):
        return text
    doc = json.loads(text)
    return json.dumps({k: v for k, v in doc.items() if "created" not in k}, sort_keys=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.long_recording",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--minutes", type=float, default=10.0, help="the mocap's length")
    parser.add_argument("--out", type=json_out, default=RESULTS)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="posecbr-long-recording-") as tmp:
        inputs = make_inputs(Path(tmp), args.minutes)
        rows = commands(inputs)
        runs: dict[str, list[dict[str, Any]]] = {name: [] for name in rows}
        for _ in range(args.repeats):
            for name, (cli, _) in rows.items():
                runs[name].append(run_once(cli))
    table = []
    print(f"{'command':<28} {'length s':>9} {'cpu s':>7} {'wall s':>7} {'x real':>7} "
          f"{'peak MB':>8}  loads")  # fmt: skip
    for name, (_, length) in rows.items():
        got = runs[name]
        same = len({_stable(name, r["output"]) for r in got}) == 1
        cpu = statistics.median(r["cpu_s"] for r in got)
        row = {
            "command": name,
            "recording_s": round(length, 2),
            "cpu_s_median": round(cpu, 2),
            "wall_s_median": round(statistics.median(r["wall_s"] for r in got), 2),
            "times_real_time_cpu": round(length / cpu, 1),
            "peak_mb_median": round(statistics.median(r["peak_mb"] for r in got), 1),
            "cpu_s": [round(r["cpu_s"], 2) for r in got],
            "wall_s": [round(r["wall_s"], 2) for r in got],
            "loads": [r["load"] for r in got],
            "same_output_every_repeat": same,
        }
        table.append(row)
        print(f"{name:<28} {length:>9.1f} {cpu:>7.2f} {row['wall_s_median']:>7.2f} "
              f"{row['times_real_time_cpu']:>7.1f} {row['peak_mb_median']:>8.1f}  "
              f"{row['loads']}{'' if same else '  OUTPUT DIFFERS'}")  # fmt: skip
    from cbr.evaluation.machine import machine_info

    doc = {
        "benchmark": "long_recording",
        "repeats": args.repeats,
        "minutes": args.minutes,
        "threads": "defaults (BLAS, onnxruntime, numba as a user runs them)",
        "machine": {**machine_info(), "platform": platform.platform(),
                    "cpu_count": os.cpu_count(), "load_at_end": list(os.getloadavg())},
        "rows": table,
    }  # fmt: skip
    write_json(doc, args.out)
    print(f"written {args.out}")
    return 0 if all(r["same_output_every_repeat"] for r in table) else 1


if __name__ == "__main__":
    raise SystemExit(main())
