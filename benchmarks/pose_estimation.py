"""Pose estimation speed and agreement: posecbr's BlazePose on onnxruntime vs MediaPipe 0.10.21.

Run: ``python -m benchmarks.pose_estimation [--mediapipe-python PATH] [--frames N]
[--repeats N]``. Writes ``benchmarks/results/pose_estimation.json``.

Input: real video (the reverse-lunge clip in ``../shared/data/videos``, centre-cropped to 4:3
and resized to 640 x 480), decoded once into memory so only pose estimation is timed. Both
pipelines run the same frames in the same run, in two modes:

- ``tracking``: the landmark model follows the previous frame's landmarks (the detector only
  when the track is lost), smoothing on; MediaPipe ``static_image_mode=False``.
  Timestamps are 1/30 s apart in both, as MediaPipe's Python solution always assumes.
- ``detect_every_frame``: the detector on every frame, no smoothing; MediaPipe
  ``static_image_mode=True``.

MediaPipe (``solutions.pose``, ``model_complexity=1`` = the full model, the one converted)
runs in its own environment (``pip install --no-deps mediapipe==0.10.21`` plus absl-py attrs
flatbuffers 'protobuf<5' matplotlib numpy opencv-python-headless), in a subprocess started
with ``--mediapipe-python`` (default: ``$POSECBR_MEDIAPIPE_PYTHON`` or
``/work/mp-venv/bin/python`` when present); without it only posecbr is measured.

Reported per mode: frames/s (median over rounds that alternate the two pipelines, each after
a warm-up pass), the speed ratio posecbr / MediaPipe (median of the per-round ratios: each
round runs both back to back, so load from other processes on a shared machine cancels
better than in a ratio of medians, which is recorded too), and the mean image-landmark
difference in pixels (33 landmarks, frames where both found the person).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from benchmarks import write_json

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
CLIP = DATA / "videos" / "lunge" / "fit_reverse_lunge_pexels8233047.mp4"
RESULTS = ROOT / "benchmarks" / "results" / "pose_estimation.json"
DEFAULT_MP_PYTHON = Path("/work/mp-venv/bin/python")
MODES = ("tracking", "detect_every_frame")

# Runs inside the MediaPipe environment: frames from an .npy file, landmarks and timings out.
MP_RUNNER = r"""
import json, sys, time
import numpy as np
import mediapipe as mp
frames = np.load(sys.argv[1])
repeats = int(sys.argv[2])
out = {"mediapipe": mp.__version__, "modes": {}}
h, w = frames.shape[1:3]
for mode, static in (("tracking", False), ("detect_every_frame", True)):
    times, cpu, lms = [], [], None
    for r in range(repeats + 1):  # first pass = warm-up
        pose = mp.solutions.pose.Pose(static_image_mode=static, model_complexity=1,
                                      smooth_landmarks=True, enable_segmentation=False)
        got = []
        t0, c0 = time.perf_counter(), time.process_time()
        for f in frames:
            res = pose.process(f)
            got.append(None if res.pose_landmarks is None else
                       [[p.x * w, p.y * h] for p in res.pose_landmarks.landmark])
        dt, dc = time.perf_counter() - t0, time.process_time() - c0
        pose.close()
        if r > 0:
            times.append(dt)
            cpu.append(dc)
        lms = got
    out["modes"][mode] = {"seconds": times, "cpu_seconds": cpu, "landmarks": lms}
json.dump(out, sys.stdout)
"""


def load_frames(n: int) -> np.ndarray:
    """``(n, 480, 640, 3)`` RGB uint8: centre 4:3 crop of the clip, resized to 640 x 480."""
    cap = cv2.VideoCapture(str(CLIP))
    frames: list[np.ndarray] = []
    while len(frames) < n:
        ok, bgr = cap.read()
        if not ok:
            break
        h, w = bgr.shape[:2]
        cw = min(w, h * 4 // 3)
        x0 = (w - cw) // 2
        crop = cv2.resize(bgr[:, x0 : x0 + cw], (640, 480), interpolation=cv2.INTER_AREA)
        frames.append(cv2.cvtColor(crop, cv2.COLOR_BGR2RGB))
    cap.release()
    if not frames:
        raise SystemExit(f"cannot read {CLIP}")
    return np.stack(frames)


def run_posecbr(frames: np.ndarray, estimators: dict[str, Any]) -> dict[str, Any]:
    """One timed pass per mode: seconds and per-frame landmarks ``(33, 2)`` px or None."""
    out: dict[str, Any] = {}
    for mode in MODES:
        est = estimators[mode]
        est.reset()
        got: list[np.ndarray | None] = []
        t0, c0 = time.perf_counter(), time.process_time()
        for i, f in enumerate(frames):
            pose = est.process(f, i / 30.0)
            got.append(pose.image[:, :2] if pose.person else None)
        out[mode] = {
            "seconds": time.perf_counter() - t0,
            "cpu_seconds": time.process_time() - c0,
            "landmarks": got,
        }
    return out


def run_mediapipe(python: Path, frames_path: Path) -> dict[str, Any] | None:
    """MediaPipe in its own environment: a warm-up pass, then one timed pass per mode."""
    proc = subprocess.run(
        [str(python), "-c", MP_RUNNER, str(frames_path), "1"],
        capture_output=True,
        text=True,
        timeout=3600,
    )
    if proc.returncode != 0:
        print(f"MediaPipe run failed:\n{proc.stderr[-2000:]}", file=sys.stderr)
        return None
    result: dict[str, Any] = json.loads(proc.stdout)
    return result


def mean_difference(ours: list[Any], theirs: list[Any]) -> tuple[float, int]:
    """Mean px distance over the 33 landmarks and the frames where both found a person."""
    diffs = [
        np.linalg.norm(np.asarray(a) - np.asarray(b), axis=1).mean()
        for a, b in zip(ours, theirs, strict=True)
        if a is not None and b is not None
    ]
    return (float(np.mean(diffs)) if diffs else float("nan")), len(diffs)


def machine() -> dict[str, Any]:
    from cbr.evaluation.machine import machine_info

    return machine_info(("onnxruntime", "opencv-python-headless"))


def main(argv: list[str] | None = None) -> int:
    args = _parse_args(argv)
    from features.pose_estimation import PoseEstimator, model_version

    frames = load_frames(args.frames)
    estimators = {
        mode: PoseEstimator(tracking=mode == "tracking", smoothing=mode == "tracking")
        for mode in MODES
    }
    mp_python: Path | None = args.mediapipe_python
    if not args.mediapipe_python.is_file():
        print(f"no MediaPipe environment at {args.mediapipe_python}: posecbr only")
        mp_python = None
    run_posecbr(frames, estimators)  # warm-up
    ours, theirs = run_rounds(frames, estimators, args.repeats, mp_python)
    n = len(frames)
    print(f"{n} frames 640x480 from {CLIP.name}, median of {args.repeats} alternating rounds")
    head = ("mode", "posecbr fps", "MediaPipe fps", "ratio", "CPU ms/frame", "CPU ratio", "diff px")
    print("{:<20} {:>12} {:>14} {:>7} {:>14} {:>10} {:>8}".format(*head))
    rows = {}
    for mode in MODES:
        rows[mode] = mode_row(n, ours[mode], None if theirs is None else theirs["modes"][mode])
        print_row(mode, rows[mode])
    result = {
        "benchmark": "pose_estimation",
        "input": {"clip": str(CLIP.relative_to(DATA)), "frames": n, "size": [640, 480]},
        "repeats": args.repeats,
        "pose_model": model_version(),
        "mediapipe": None if theirs is None else theirs["mediapipe"],
        "goal": {"fps_ratio": 1.2, "mean_difference_px": 1.0},
        "modes": rows,
        "machine": machine(),
        "command": "python -m benchmarks.pose_estimation",
    }
    write_json(result, RESULTS)
    print(f"wrote {RESULTS.relative_to(ROOT)}")
    return 0


def _parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    env_python = os.environ.get("POSECBR_MEDIAPIPE_PYTHON")
    default_python = Path(env_python) if env_python else DEFAULT_MP_PYTHON
    parser.add_argument("--mediapipe-python", type=Path, default=default_python)
    parser.add_argument("--frames", type=int, default=250)
    parser.add_argument("--repeats", type=int, default=3)
    return parser.parse_args(argv)


def run_rounds(
    frames: np.ndarray, estimators: dict[str, Any], repeats: int, mp_python: Path | None
) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """``repeats`` rounds of posecbr then MediaPipe (when ``mp_python`` is given and its
    runs succeed): per pipeline and mode the seconds and CPU seconds of every round and the
    last round's landmarks. Rounds alternate the two pipelines so that load from other
    processes on a shared machine falls on both alike."""
    ours: dict[str, Any] = {m: {"seconds": [], "cpu_seconds": []} for m in MODES}
    theirs: dict[str, Any] | None = None
    with tempfile.TemporaryDirectory() as tmp:
        frames_path = Path(tmp) / "frames.npy"
        np.save(frames_path, frames)
        for _ in range(repeats):
            got = run_posecbr(frames, estimators)
            for m in MODES:
                ours[m]["seconds"].append(got[m]["seconds"])
                ours[m]["cpu_seconds"].append(got[m]["cpu_seconds"])
                ours[m]["landmarks"] = got[m]["landmarks"]
            if mp_python is None:
                continue
            mp_round = run_mediapipe(mp_python, frames_path)
            if mp_round is None:  # a failed MediaPipe run: posecbr only from here on
                mp_python, theirs = None, None
                continue
            theirs = _with_mediapipe_round(theirs, mp_round)
    return ours, theirs


def _with_mediapipe_round(
    theirs: dict[str, Any] | None, mp_round: dict[str, Any]
) -> dict[str, Any]:
    """The MediaPipe rounds so far with one more (its timings added, its landmarks kept)."""
    if theirs is None:
        theirs = {
            "mediapipe": mp_round["mediapipe"],
            "modes": {m: {"seconds": [], "cpu_seconds": []} for m in MODES},
        }
    for m in MODES:
        theirs["modes"][m]["seconds"] += mp_round["modes"][m]["seconds"]
        theirs["modes"][m]["cpu_seconds"] += mp_round["modes"][m]["cpu_seconds"]
        theirs["modes"][m]["landmarks"] = mp_round["modes"][m]["landmarks"]
    return theirs


def mode_row(n: int, ours: dict[str, Any], mp_mode: dict[str, Any] | None) -> dict[str, Any]:
    """The figures of one mode over ``n`` frames: posecbr's, and with MediaPipe's rounds
    (``mp_mode``) its figures, the speed ratios and the landmark difference."""
    fps = n / statistics.median(ours["seconds"])
    row: dict[str, Any] = {
        "posecbr_fps": fps,
        "posecbr_seconds": ours["seconds"],
        "posecbr_cpu_ms_per_frame": 1000 * statistics.median(ours["cpu_seconds"]) / n,
        "posecbr_frames_with_person": sum(x is not None for x in ours["landmarks"]),
    }
    if mp_mode is None:
        return row
    mp_fps = n / statistics.median(mp_mode["seconds"])
    diff, both = mean_difference(ours["landmarks"], mp_mode["landmarks"])
    # Each round's own ratio: the two ran back to back, under the same load.
    paired = [m / o for o, m in zip(ours["seconds"], mp_mode["seconds"], strict=True)]
    row.update(
        mediapipe_fps=mp_fps,
        mediapipe_seconds=mp_mode["seconds"],
        mediapipe_frames_with_person=sum(x is not None for x in mp_mode["landmarks"]),
        ratio_of_medians=fps / mp_fps,
        ratio=statistics.median(paired),
        ratio_per_round=paired,
        mediapipe_cpu_ms_per_frame=1000 * statistics.median(mp_mode["cpu_seconds"]) / n,
        # CPU time per frame depends far less on other processes than wall time does.
        cpu_ratio=statistics.median(mp_mode["cpu_seconds"])
        / statistics.median(ours["cpu_seconds"]),
        mean_landmark_difference_px=diff,
        frames_compared=both,
    )
    return row


def print_row(mode: str, row: dict[str, Any]) -> None:
    """One line of the table: posecbr's figures, MediaPipe's beside them when it ran."""
    fps = row["posecbr_fps"]
    if "mediapipe_fps" not in row:
        cpu = f"{row['posecbr_cpu_ms_per_frame']:.1f}"
        print(f"{mode:<20} {fps:>12.1f} {'-':>14} {'-':>7} {cpu:>14} {'-':>10} {'-':>8}")
        return
    cpu = f"{row['posecbr_cpu_ms_per_frame']:.1f}/{row['mediapipe_cpu_ms_per_frame']:.1f}"
    print(
        f"{mode:<20} {fps:>12.1f} {row['mediapipe_fps']:>14.1f} {row['ratio']:>7.2f} {cpu:>14}"
        f" {row['cpu_ratio']:>10.2f} {row['mean_landmark_difference_px']:>8.2f}"
    )


if __name__ == "__main__":
    sys.exit(main())
