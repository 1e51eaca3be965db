"""Peak memory of ``posecbr classify`` and ``posecbr segment`` on one very long pose file,
read in pieces or whole.

    python -m benchmarks.long_clip                    # 10^6 frames, the three case bases
    python -m benchmarks.long_clip --frames 200000 --skip-whole

The clip is real BlazePose-33 output tiled: ``posecbr extract`` on the reverse-lunge video of
``../shared/data/videos`` (250 frames at 25 fps), repeated to ``--frames`` frames (10^6: 11 h)
and saved as float32. Three case bases are trained on the bundled UI-PRMD demo data
(``posecbr/demo_data/uiprmd/labels.csv``): the defaults (fluent clip summaries, euclidean),
``--features fluents --similarity dtw`` and ``--features qmp``. Each ``posecbr classify CLIP
--db CB --json`` runs in a process of its own whose peak resident memory is its VmHWM, twice:
as shipped (a long clip's fluents, signals and positions computed ``CHUNK_FRAMES`` frames at a
time, :mod:`cbr.long_clip`) and, as the peer, with the whole clip at once (the path every clip
took before; ``--skip-whole`` leaves it out: it needs 8-11 GB). Both must give the same answer
and the same distance to the nearest case. ``posecbr segment CLIP --db CB --json`` (the
defaults case base; ``--segment-frames`` of the clip, ``--skip-segment`` leaves it out) runs the
same two ways: its windows cut from pieces of the recording or from the whole one (as before);
both must give the same segments. The load average is recorded with every figure (the machine
is shared: wall seconds stretch under load, peak memory does not); the JSON is written after
every row. Results: ``benchmarks/results/long_clip.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks import json_out, write_json

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd" / "labels.csv"
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
VIDEO = DATA / "videos" / "lunge" / "fit_reverse_lunge_pexels8233047.mp4"
RESULTS = ROOT / "benchmarks" / "results" / "long_clip.json"
CASE_BASES = {
    "qmp": ["--features", "qmp"],
    "summary, euclidean (defaults)": [],
    "fluents, dtw": ["--features", "fluents", "--similarity", "dtw"],
}


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}


def _posecbr(*argv: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "posecbr", *argv], env=_env(), capture_output=True, text=True
    )
    if done.returncode != 0:
        raise SystemExit(f"posecbr {' '.join(argv)} failed:\n{done.stderr[-2000:]}")


def make_clip(work: Path, frames: int) -> Path:
    """The real clip tiled to ``frames`` frames, as a float32 pose file in ``work``."""
    import dataclasses

    import numpy as np

    from features.poses import load_pose, save_pose

    if not VIDEO.is_file():
        raise SystemExit(f"the lunge video is missing: {VIDEO}")
    _posecbr("extract", str(VIDEO), "--out", str(work / "real"))
    real = load_pose(work / "real" / f"{VIDEO.stem}.npz")
    reps = -(-frames // real.n_frames)
    pos = np.tile(real.positions, (reps, 1, 1))[:frames]
    conf = None
    if real.confidence is not None:
        conf = np.tile(real.confidence, (reps, 1))[:frames]
    long = dataclasses.replace(real, positions=pos, confidence=conf, source="tiled lunge")
    return save_pose(long, work / "long.npz", float32=True)


#: address space of the whole-clip peer (it needs 8-12 GB resident for 10^6 frames)
WHOLE_LIMIT_BYTES = 16 * 2**30


def _child(argv: list[str]) -> int:
    """In the measured process: ``classify`` with its JSON to a file, then this process's
    peak memory (VmHWM: unlike ru_maxrss it does not start at the parent's size)."""
    mode, out, *cli = argv
    if mode == "whole":  # the peer: every clip computed at once, as before cbr.long_clip
        import cbr.long_clip
        import features.qmp.fit

        # its address space capped, so that on a shared machine it fails with MemoryError
        # (recorded as a failed run) instead of waking the kernel's OOM killer
        resource.setrlimit(resource.RLIMIT_AS, (WHOLE_LIMIT_BYTES, WHOLE_LIMIT_BYTES))

        cbr.long_clip.CHUNK_FRAMES = 10**12
        features.qmp.fit.THETA_ROWS = 10**15  # the QMP fit's basis over all frames at once
    from posecbr.cli import main

    t0, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_SELF)
    with open(out, "w", encoding="utf-8") as fh:
        stdout, sys.stdout = sys.stdout, fh
        try:
            code = main(cli)
        finally:
            sys.stdout = stdout
    r1 = resource.getrusage(resource.RUSAGE_SELF)
    with open("/proc/self/status", encoding="ascii") as fh:
        hwm = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmHWM:"))
    cpu = r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime
    print(json.dumps({"exit": code, "peak_bytes": hwm, "wall_s": time.perf_counter() - t0,
                      "cpu_s": cpu}))  # fmt: skip
    return 0


def measure(
    mode: str, db: Path, clip: Path, work: Path, command: str = "classify"
) -> dict[str, Any]:
    """One ``classify`` (``segment``) in a process of its own: peak memory, times, the
    answer."""
    out = work / f"{command}-{mode}-{db.stem}-{clip.stem}.json"
    load = [round(v, 2) for v in os.getloadavg()]
    code = f"import sys, benchmarks.long_clip as b; sys.exit(b._child({[mode, str(out)]!r} + sys.argv[1:]))"  # noqa: E501
    done = subprocess.run(
        [sys.executable, "-c", code, command, str(clip), "--db", str(db), "--json"],
        env=_env(), capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    row: dict[str, Any] = {"mode": mode, "load_before": load}
    if done.returncode != 0:  # out of memory: MemoryError under the cap, or killed (-9)
        print(done.stderr[-2000:], file=sys.stderr)
        return {**row, "exit": done.returncode, "peak_bytes": None, "wall_s": None,
                "cpu_s": None, "label": None, "nearest_distance": None}  # fmt: skip
    row.update(json.loads(done.stdout.strip().splitlines()[-1]))
    if command == "segment":
        doc = json.loads(out.read_text(encoding="utf-8"))
        segments = doc["segments"]
        return {**row, "load_after": [round(v, 2) for v in os.getloadavg()],
                "frames": doc["frames"], "segments": len(segments),
                "label": ", ".join(sorted({str(s["label"]) for s in segments})),
                "nearest_distance": None, "segments_json": segments}  # fmt: skip
    result = json.loads(out.read_text(encoding="utf-8"))["results"][0]
    row.update(
        load_after=[round(v, 2) for v in os.getloadavg()],
        label=result.get("label"),
        confidence=result.get("confidence"),
        nearest_distance=(result.get("neighbours") or [{}])[0].get("distance"),
    )
    return row


def _print_row(row: dict[str, Any]) -> None:
    name, mode, load = row["case_base"], row["mode"], row["load_before"][0]
    if row["peak_bytes"] is None:
        print(f"{name:<32} {mode:<8} failed (exit {row['exit']}; -9: killed), load {load}")
        return
    print(
        f"{name:<32} {mode:<8} {row['peak_bytes'] / 1e9:>8.2f} {row['wall_s']:>8.1f} "
        f"{row['cpu_s']:>8.1f}  {row['label']} (nearest {row['nearest_distance']}, load {load})",
        flush=True,
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=1_000_000)
    parser.add_argument("--skip-whole", action="store_true", help="only the chunked path")
    parser.add_argument(
        "--segment-frames", type=int, default=None, help="frames segment reads (default --frames)"
    )
    parser.add_argument("--skip-segment", action="store_true", help="no posecbr segment rows")
    parser.add_argument("--skip-classify", action="store_true", help="only the segment rows")
    parser.add_argument("--out", type=json_out, default=RESULTS, help="the results JSON")
    parser.add_argument(
        "--segment-modes", nargs="+", choices=("chunked", "whole"), default=["chunked", "whole"]
    )
    args = parser.parse_args(argv)
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="posecbr-long-") as tmp:
        work = Path(tmp)
        clip = make_clip(work, args.frames)
        print(f"clip: {args.frames} frames, {clip.stat().st_size / 1e6:.0f} MB on disk")
        print(f"{'case base':<32} {'mode':<8} {'peak GB':>8} {'wall s':>8} {'cpu s':>8}  answer")
        modes = ("chunked",) if args.skip_whole else ("chunked", "whole")
        for name, extra in CASE_BASES.items():
            if args.skip_classify and extra:
                continue
            db = work / f"{len(rows)}-{len(extra)}.sqlite"
            _posecbr("train", str(DEMO), "--db", str(db), *extra)
            for mode in () if args.skip_classify else modes:
                row = {"case_base": name, "train_args": extra, **measure(mode, db, clip, work)}
                rows.append(row)
                _print_row(row)
                _write(args, rows)
            if extra == [] and not args.skip_segment:
                _segment_rows(args, db, clip, work, rows)
    return 0


def _segment_rows(
    args: argparse.Namespace, db: Path, clip: Path, work: Path, rows: list[dict[str, Any]]
) -> None:
    """``posecbr segment`` of the long recording in pieces and whole (as before), on the
    defaults case base ``db``; both must give the same segments."""
    frames = args.segment_frames or args.frames
    recording = clip if frames == args.frames else _cut(clip, work, frames)
    found = []
    for mode in args.segment_modes:
        row = {"case_base": "segment, defaults", "command": "posecbr segment LONG.npz --db CB "
               "--json", **measure(mode, db, recording, work, "segment")}  # fmt: skip
        found.append(row.pop("segments_json", None))
        rows.append(row)
        _print_row(row)
        _write(args, rows)
    if len(found) == 2 and all(f is not None for f in found):
        rows[-1]["same_segments_as_chunked"] = found[0] == found[1]
        _write(args, rows)


def _cut(clip: Path, work: Path, frames: int) -> Path:
    """The first ``frames`` frames of the long clip as a pose file of their own."""
    from features.poses import load_pose, save_pose

    return save_pose(load_pose(clip).slice_frames(0, frames), work / f"long-{frames}.npz",
                     float32=True)  # fmt: skip


def _write(args: argparse.Namespace, rows: list[dict[str, Any]]) -> None:
    from benchmarks.__main__ import machine
    from cbr.long_clip import CHUNK_FRAMES

    doc = {
        "kind": "posecbr-long-clip",
        "frames": args.frames,
        "segment_frames": args.segment_frames or args.frames,
        "chunk_frames": CHUNK_FRAMES,
        "command": "posecbr classify LONG.npz --db CB --json",
        "argv": sys.argv[1:],
        "machine": machine(),
        "load": [round(v, 2) for v in os.getloadavg()],
        "rows": rows,
    }
    write_json(doc, args.out)


if __name__ == "__main__":
    sys.exit(main())
