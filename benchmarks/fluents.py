"""Fluent engine speed: frames/s for the state signals and for every fluent (all 96 fluents,
instantaneous and locally temporal, 566 states), on one core.

Run: ``python -m benchmarks.fluents [--repeats N] [--clips N] [--quick]``. Thread pools are
pinned to 1 before numpy/numba load. Writes ``benchmarks/results/fluents.json``.

Compared in the same run, on the same signals:
- ``numba``: the compiled single-pass kernels (the default backend);
- ``numpy``: the whole-array numpy reference (``backend="numpy"``);
- ``naive``: a straightforward per-frame implementation — a Python loop over frames that
  computes each fluent's states with ``math.exp`` and the temporal product from the lagged
  values with ``**`` (written here from the paper's equations, independently of both
  backends; run on a subset of frames and checked against the reference).

Sequences. The headline, full 33-joint BlazePose poses with every state computed: the
landmarks posecbr's BlazePose extracts from two real videos in ``../shared/data/videos``
(a reverse lunge, a lateral leg raise; every joint present), read at 30 Hz and tiled to the
length of the others. Beside it: a synthetic 33-joint person (arms raised, a squat, a nod, 5 mm
jitter), UI-PRMD Kinect clips concatenated (30 Hz, 16 BlazePose joints mapped: face and hand
fluents unavailable, NaN, and skipped by the fast path while the reference computes them),
HDM05 squats (120 Hz: integer lag 4) and UI-PRMD Vicon clips (~100 Hz: a fractional lag,
interpolated, the slower temporal path) — plus the per-clip cost as a pipeline pays it (one
``evaluate`` call per UI-PRMD clip, Python overhead included).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
from features.fluents import (  # noqa: E402
    DEFAULT_TABLE,
    FluentSpec,
    FluentTable,
    evaluate,
    state_signals,
)
from features.poses import PoseSequence  # noqa: E402
from features.progress import progress  # noqa: E402
from features.signals import StateSignals  # noqa: E402
from features.skeleton import BLAZEPOSE_33, JOINT_INDEX  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
KINECT = DATA / "ui-prmd" / "data" / "Segmented Movements" / "Kinect" / "Positions"
RESULTS = ROOT / "benchmarks" / "results" / "fluents.json"


# The machine may be shared: by default time is this process's CPU time (one thread), which
# leaves out the time it waits for a core; ``--clock wall`` measures elapsed time instead.
CLOCKS: dict[str, Callable[[], float]] = {"cpu": time.process_time, "wall": time.perf_counter}
_clock = CLOCKS["cpu"]


def _median_time(fn: Callable[[], Any], repeats: int) -> float:
    """Median seconds per call over ``repeats`` timings (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = _clock()
        fn()
        times.append(_clock() - t0)
    return statistics.median(times)


# --- sequences --------------------------------------------------------------------------------


def _kinect_clips(n_clips: int) -> list[PoseSequence]:
    from features.readers.uiprmd import read_uiprmd_kinect

    files = sorted(KINECT.glob("*_positions.txt.gz"))
    if not files:
        raise SystemExit(f"benchmarks.fluents: no UI-PRMD Kinect clips under {KINECT}")
    # every movement and subject, spread evenly over the sorted list
    pick = [files[i] for i in np.linspace(0, len(files) - 1, min(n_clips, len(files))).astype(int)]
    return [read_uiprmd_kinect(p).to_canonical() for p in progress(pick, "reading UI-PRMD")]


def _concat(clips: list[PoseSequence], fps: float) -> PoseSequence:
    pos = np.concatenate([c.positions for c in clips])
    return PoseSequence(pos, BLAZEPOSE_33, fps, source="concatenated clips")


def _vicon_clips(n_clips: int) -> PoseSequence | None:
    """UI-PRMD Vicon clips concatenated: ~100 Hz, a fractional lag (10/3 frames)."""
    from features.readers.uiprmd import read_uiprmd_vicon

    files = sorted((KINECT.parent.parent / "Vicon" / "Positions").glob("*_positions.txt.gz"))
    if not files:
        return None
    pick = [files[i] for i in np.linspace(0, len(files) - 1, min(n_clips, len(files))).astype(int)]
    clips = [read_uiprmd_vicon(p).to_canonical() for p in progress(pick, "reading Vicon")]
    return _concat(clips, clips[0].fps)


def _hdm05_squats() -> PoseSequence | None:
    from features.readers.asfamc import read_asf_amc

    amcs = sorted((DATA / "hdm05" / "train").glob("*/HDM_*_squat1Reps_*_120.amc"))
    clips = []
    for amc in amcs:
        actor = amc.name.split("_")[1]
        asf = amc.parent / f"HDM_{actor}.asf"
        if asf.exists():
            clips.append(read_asf_amc(asf, amc).to_canonical())
    return _concat(clips, 120.0) if clips else None


_VIDEOS = ("lunge/fit_reverse_lunge_pexels8233047.mp4",
           "side_lying_leg_raise/fit_lateral_leg_raise_pexels6974513.mp4")  # fmt: skip


def _real_blazepose(frames: int) -> PoseSequence | None:
    """Full 33-joint BlazePose landmarks from real videos (posecbr's own BlazePose on
    onnxruntime: a reverse lunge and a lateral leg raise, 25 fps, every joint present), read
    at 30 Hz (the integer-lag path of a 30-fps camera) and tiled forward and backward (no
    jumps at the seams) to ``frames`` frames. None without the videos."""
    from features.pose_estimation import estimate_poses

    paths = [DATA / "videos" / v for v in _VIDEOS]
    if not all(p.exists() for p in paths):
        return None
    parts = [estimate_poses(p).to_canonical().positions for p in paths]
    real = np.concatenate(parts)
    cycle = np.concatenate([real, real[::-1]])
    pos = np.resize(cycle, (frames, *real.shape[1:]))  # repeats the cycle
    return PoseSequence(pos, BLAZEPOSE_33, 30.0, source="BlazePose on real videos")


# A standing person (metres, y up, facing +z, left = +x): the 33 BlazePose landmarks.
_STANDING = {
    "nose": (0.0, 1.63, 0.10), "left_eye_inner": (0.015, 1.67, 0.09),
    "left_eye": (0.03, 1.67, 0.08), "left_eye_outer": (0.045, 1.67, 0.07),
    "right_eye_inner": (-0.015, 1.67, 0.09), "right_eye": (-0.03, 1.67, 0.08),
    "right_eye_outer": (-0.045, 1.67, 0.07), "left_ear": (0.08, 1.65, 0.0),
    "right_ear": (-0.08, 1.65, 0.0), "mouth_left": (0.03, 1.58, 0.09),
    "mouth_right": (-0.03, 1.58, 0.09), "left_shoulder": (0.20, 1.50, 0.0),
    "right_shoulder": (-0.20, 1.50, 0.0), "left_elbow": (0.20, 1.20, 0.0),
    "right_elbow": (-0.20, 1.20, 0.0), "left_wrist": (0.20, 0.95, 0.0),
    "right_wrist": (-0.20, 0.95, 0.0), "left_pinky": (0.21, 0.87, 0.0),
    "right_pinky": (-0.21, 0.87, 0.0), "left_index": (0.20, 0.86, 0.02),
    "right_index": (-0.20, 0.86, 0.02), "left_thumb": (0.19, 0.90, 0.03),
    "right_thumb": (-0.19, 0.90, 0.03), "left_hip": (0.15, 1.00, 0.0),
    "right_hip": (-0.15, 1.00, 0.0), "left_knee": (0.15, 0.55, 0.0),
    "right_knee": (-0.15, 0.55, 0.0), "left_ankle": (0.15, 0.10, 0.0),
    "right_ankle": (-0.15, 0.10, 0.0), "left_heel": (0.15, 0.05, -0.05),
    "right_heel": (-0.15, 0.05, -0.05), "left_foot_index": (0.15, 0.02, 0.15),
    "right_foot_index": (-0.15, 0.02, 0.15),
}  # fmt: skip


def _synthetic_blazepose(frames: int, fps: float = 30.0, seed: int = 0) -> PoseSequence:
    """A full 33-joint person: arms abduct to overhead and back (4 s), a squat (6 s), a nod
    (3 s), plus 5 mm Gaussian jitter like a video pose estimator. ``(frames, 33, 3)``."""
    t = np.arange(frames) / fps
    base = np.array([_STANDING[name] for name in BLAZEPOSE_33])
    pos = np.broadcast_to(base, (frames, 33, 3)).copy()
    idx = JOINT_INDEX
    arm = ("elbow", "wrist", "pinky", "index", "thumb")
    abd = np.radians(170.0) * 0.5 * (1 - np.cos(2 * np.pi * t / 4.0))  # 0..170 degrees
    for side, sign in (("left", 1.0), ("right", -1.0)):
        sh = base[idx[f"{side}_shoulder"]]
        for part in arm:
            j = idx[f"{side}_{part}"]
            rel = base[j] - sh
            c, s = np.cos(abd), np.sin(abd) * sign  # rotation about the forward (z) axis
            pos[:, j, 0] = sh[0] + c * rel[0] - s * rel[1]
            pos[:, j, 1] = sh[1] + s * rel[0] + c * rel[1]
    # squat: hips and everything above drop, knees go forward
    depth = 0.35 * 0.5 * (1 - np.cos(2 * np.pi * t / 6.0))
    upper = [j for j, name in enumerate(BLAZEPOSE_33)
             if not any(k in name for k in ("knee", "ankle", "heel", "foot"))]  # fmt: skip
    pos[:, upper, 1] -= depth[:, None]
    for side in ("left", "right"):
        pos[:, idx[f"{side}_knee"], 2] += 0.8 * depth
        pos[:, idx[f"{side}_knee"], 1] -= 0.3 * depth
    # nod: face landmarks move forward and down
    nod = 0.04 * np.sin(2 * np.pi * t / 3.0)
    face = [j for j, name in enumerate(BLAZEPOSE_33)
            if any(k in name for k in ("nose", "eye", "mouth"))]  # fmt: skip
    pos[:, face, 2] += nod[:, None]
    pos[:, face, 1] -= 0.5 * np.abs(nod)[:, None]
    pos += np.random.default_rng(seed).normal(0.0, 0.005, pos.shape)
    return PoseSequence(pos, BLAZEPOSE_33, fps, source="synthetic BlazePose")


# --- the naive per-frame peer -----------------------------------------------------------------


class _NaivePeer:
    """The paper's equations (2)-(6) for one frame and one fluent at a time, in plain Python
    (``math.exp``, ``**``): the naive peer."""

    def __init__(self, sig: StateSignals, fps: float, table: FluentTable) -> None:
        self.sig, self.table = sig, table
        self.logit = math.log((1 - table.epsilon) / table.epsilon)
        self.col = {name: i for i, name in enumerate(sig.names)}
        self.dist_col = {name: i for i, name in enumerate(sig.names[len(sig.angle_names) :])}
        self.index_of = {s.name: i for i, s in enumerate(table.specs)}
        self.lag = fps / table.reference_fps

    def lower(self, x: float, tau: float, delta: float) -> float:
        """Eq. 2: a state that holds below τ."""
        if math.isnan(x):
            return math.nan
        if x < tau - delta:
            return 1.0
        if x > tau + delta:
            return 0.0
        return 1.0 / (1.0 + math.exp(self.logit / delta * (x - tau)))

    def sample(self, f: int, j: int, m: int) -> tuple[float, bool]:
        """Signal j ``m`` reference intervals before frame f (interpolated), and whether the
        clip reaches back that far."""
        values = self.sig.values
        pos = f - m * self.lag
        ok = pos >= -1e-9
        pos = min(max(pos, 0.0), values.shape[0] - 1.0)
        lo = math.floor(pos)
        w = pos - lo
        if w == 0.0:
            return float(values[lo, j]), ok
        hi = min(lo + 1, values.shape[0] - 1)
        return float(values[lo, j] * (1 - w) + values[hi, j] * w), ok

    def motion(self, f: int, j: int, tau: float, delta: float) -> tuple[float, float]:
        """Eq. 5 toward s0 and toward sn at frame f: the product over the window."""
        s = [self.sample(f, j, m) for m in range(self.table.window + 1)]
        if not s[1][1]:
            return math.nan, math.nan
        to_lo = to_hi = 1.0
        for a in range(self.table.window):
            if not s[a + 1][1]:
                continue  # no history: counts as 1
            d = s[a][0] - s[a + 1][0]
            to_lo *= self.lower(d, -tau, delta) ** (1.0 / (a + 1))
            to_hi *= (1.0 - self.lower(d, tau, delta)) ** (1.0 / (a + 1))
        return to_lo, to_hi

    def states(self, f: int, s: FluentSpec) -> dict[str, float]:
        """Every state of fluent ``s`` at frame f, by column code (a tilt pair's shared
        states still for this direction alone)."""
        j = self.col[s.signal]
        x = float(self.sig.values[f, j])
        c0 = self.lower(x, s.lower.tau, s.lower.delta)
        c2 = (1.0 - self.lower(x, s.upper.tau, s.upper.delta)) if s.upper else 0.0 * x
        m_lo, m_hi = self.motion(f, j, s.motion_threshold.tau, s.motion_threshold.delta)
        st = {"lo": c0, "hi": c2, "two_hi": 1.0 - c0, "mid": (1 - c0) * (1 - c2),
              "m_lo": m_lo, "m_hi": m_hi, "still": (1 - m_lo) * (1 - m_hi)}  # fmt: skip
        if s.kind == "distance":
            d = float(self.sig.distances_m[f, self.dist_col[s.signal]])
            st["touch"] = math.nan if math.isnan(d) else float(d <= self.table.touching_m)
        return st

    def row(self, per: list[dict[str, float]]) -> list[float]:
        """One frame's confidences in evaluate's column order, from every fluent's states."""
        row: list[float] = []
        for s, st in zip(self.table.specs, per, strict=True):
            mid, still = st["mid"], st["still"]
            if s.paired_with is not None:  # tilt pair: upright / tilt steady need both
                other = per[self.index_of[s.paired_with]]
                mid, still = mid * other["mid"], still * other["still"]
            row += _instant_columns(s, st, mid)
            if s.kind == "distance":
                row.append(st["touch"])
            row += [st["m_lo"], st["m_hi"]] + ([] if s.secondary else [still])
        return row


def _instant_columns(s: FluentSpec, st: dict[str, float], mid: float) -> list[float]:
    """The instantaneous states of fluent ``s`` in evaluate's column order."""
    if s.upper is None:
        return [st["lo"], st["two_hi"]]
    if s.secondary:
        return [st["lo"], st["hi"]]
    return [st["lo"], mid, st["hi"]]


def naive_evaluate(sig: StateSignals, fps: float, table: FluentTable, frames: int) -> np.ndarray:
    """The first ``frames`` rows of every state's confidence, one frame and one fluent at a
    time, straight from the paper's equations (2)-(6). Returns ``(frames, n_states)``."""
    peer = _NaivePeer(sig, fps, table)
    rows = [peer.row([peer.states(f, s) for s in table.specs]) for f in range(frames)]
    return np.array(rows)


def naive_signals(seq: PoseSequence, frames: int) -> None:
    """Per-frame peer for the signals: the reference geometry called on one frame at a time."""
    for f in range(frames):
        state_signals(seq.slice_frames(f, f + 1), backend="numpy")


# --- measurements -----------------------------------------------------------------------------


def _compile_seconds() -> dict[str, float]:
    """Wall seconds for a fresh process to import the engine and evaluate a 10-frame clip:
    with an empty numba cache (compiling) and again with the cache it left (loading)."""
    code = (
        "import time; t0 = time.perf_counter();"
        "import numpy as np;"
        "from features.fluents import evaluate; from features.poses import PoseSequence;"
        "from features.skeleton import BLAZEPOSE_33;"
        "p = np.random.default_rng(0).normal(size=(10, 33, 3));"
        "evaluate(PoseSequence(p, BLAZEPOSE_33, 30.0));"
        "print(time.perf_counter() - t0, time.process_time())"
    )
    out: dict[str, float] = {}

    def run(source: str, key: str, env: dict[str, str] | None = None) -> None:
        res = subprocess.run([sys.executable, "-c", source], env=env, cwd=ROOT,
                             capture_output=True, text=True, check=True)  # fmt: skip
        wall, cpu = res.stdout.strip().splitlines()[-1].split()
        out[key] = float(wall)
        out[key.replace("_s", "_cpu_s")] = float(cpu)

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONDONTWRITEBYTECODE="1")
        run(code, "cold_cache_s", env)
        run(code, "warm_cache_s", env)
    call = "evaluate(PoseSequence(p, BLAZEPOSE_33, 30.0)"
    run(code.replace(call + ")", call + ", backend='numpy')"), "numpy_backend_s")
    return out


def bench_sequence(name: str, seq: PoseSequence, repeats: int, naive_frames: int) -> dict[str, Any]:
    n = seq.n_frames
    # Both backends evaluate the same signals: those the default pipeline computes (numba,
    # frames-major, as evaluate(seq) gets them).
    sig = state_signals(seq, backend="numba")
    row: dict[str, Any] = {"sequence": name, "frames": n, "fps": seq.fps}
    sig_fast = _median_time(lambda: state_signals(seq, backend="numba"), repeats)
    sig_ref = _median_time(lambda: state_signals(seq, backend="numpy"), repeats)
    k = min(naive_frames, n)
    sig_naive = _median_time(lambda: naive_signals(seq, k), max(1, repeats // 2)) / k * n
    ev_fast = _median_time(lambda: evaluate(seq, signals=sig, backend="numba"), repeats)
    ev_ref = _median_time(lambda: evaluate(seq, signals=sig, backend="numpy"), repeats)
    ev_naive = _median_time(lambda: naive_evaluate(sig, seq.fps, DEFAULT_TABLE, k),
                            max(1, repeats // 2)) / k * n  # fmt: skip
    both = _median_time(lambda: evaluate(seq), repeats)
    # agreement on the same signals: numba vs numpy (all frames), naive vs numpy (subset)
    fast = evaluate(seq, signals=sig, backend="numba").confidence
    ref = evaluate(seq, signals=sig, backend="numpy").confidence
    naive = naive_evaluate(sig, seq.fps, DEFAULT_TABLE, k)
    nan_same = bool(np.array_equal(np.isnan(fast), np.isnan(ref))) and bool(
        np.array_equal(np.isnan(naive), np.isnan(ref[:k]))
    )
    defined = float(np.mean(~np.isnan(ref)))
    row.update(
        signals_fps={"numba": n / sig_fast, "numpy": n / sig_ref, "naive": n / sig_naive},
        evaluate_fps={"numba": n / ev_fast, "numpy": n / ev_ref, "naive": n / ev_naive},
        end_to_end_fps_numba=n / both,
        naive_frames=k,
        max_abs_diff_numba_vs_numpy=float(np.nanmax(np.abs(fast - ref))),
        max_abs_diff_naive_vs_numpy=float(np.nanmax(np.abs(naive - ref[:k]))),
        nan_pattern_identical=nan_same,
        defined_fraction=defined,
        n_states=int(ref.shape[1]),
    )
    return row


def bench_per_clip(clips: list[PoseSequence], repeats: int) -> dict[str, Any]:
    """One ``evaluate(clip)`` (signals included) per clip, as a pipeline calls it."""
    frames = sum(c.n_frames for c in clips)

    def run(backend: str) -> None:
        for c in clips:
            evaluate(c, signals=state_signals(c, backend=backend),  # type: ignore[arg-type]
                     backend=backend)  # type: ignore[arg-type]  # fmt: skip

    t_fast = _median_time(lambda: run("numba"), repeats)
    t_ref = _median_time(lambda: run("numpy"), repeats)
    return {
        "clips": len(clips),
        "frames": frames,
        "mean_frames_per_clip": frames / len(clips),
        "fps": {"numba": frames / t_fast, "numpy": frames / t_ref},
        "ms_per_clip": {"numba": 1e3 * t_fast / len(clips), "numpy": 1e3 * t_ref / len(clips)},
    }


def bench_output_write(frames: int, n_states: int, repeats: int) -> dict[str, float]:
    """The floor under evaluate: allocating and filling a fresh ``(frames, n_states)`` float64
    array (page faults included), and refilling one already mapped."""

    def fresh() -> None:
        a = np.empty((frames, n_states))
        a.fill(1.0)

    a = np.empty((frames, n_states))
    return {
        "fresh_array_fps": frames / _median_time(fresh, repeats),
        "refill_fps": frames / _median_time(lambda: a.fill(2.0), repeats),
    }


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _versions() -> dict[str, str]:
    import numba

    return {"python": platform.python_version(), "numpy": np.__version__,
            "numba": numba.__version__}  # fmt: skip


def _print_table(rows: list[dict[str, Any]]) -> None:
    head = f"{'sequence':<34}{'frames':>8}  {'stage':<9}{'numba':>12}{'numpy':>12}{'naive':>10}"
    head += f"{'numba/numpy':>13}{'numba/naive':>13}"
    print(head)
    print("-" * len(head))
    for r in rows:
        for stage in ("signals", "evaluate"):
            fps = r[f"{stage}_fps"]
            print(f"{r['sequence']:<34}{r['frames']:>8}  {stage:<9}{fps['numba']:>12,.0f}"
                  f"{fps['numpy']:>12,.0f}{fps['naive']:>10,.0f}"
                  f"{fps['numba'] / fps['numpy']:>12.1f}x"
                  f"{fps['numba'] / fps['naive']:>12.0f}x")  # fmt: skip
        print(f"{'':<34}{'':>8}  {'both':<9}{r['end_to_end_fps_numba']:>12,.0f}"
              f"   (max |numba-numpy| {r['max_abs_diff_numba_vs_numpy']:.1e},"
              f" |naive-numpy| {r['max_abs_diff_naive_vs_numpy']:.1e})")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.fluents", description=__doc__)
    ap.add_argument("--repeats", type=int, default=7, help="timings per measurement (median)")
    ap.add_argument("--clips", type=int, default=200, help="UI-PRMD Kinect clips to concatenate")
    ap.add_argument("--naive-frames", type=int, default=300, help="frames for the naive peer")
    ap.add_argument(
        "--quick",
        action="store_true",
        help="few clips and repeats (smoke run, written to fluents_quick.json)",
    )
    ap.add_argument(
        "--clock", choices=sorted(CLOCKS), default="cpu",
        help="cpu: process CPU time (default; fair on a shared machine) or wall",
    )  # fmt: skip
    args = ap.parse_args(argv)
    global _clock
    _clock = CLOCKS[args.clock]
    if args.quick:
        args.repeats, args.clips, args.naive_frames = 3, 20, 60
    load_before = os.getloadavg()
    compile_s = _compile_seconds()
    clips = _kinect_clips(args.clips)
    kinect = _concat(clips, 30.0)
    sequences = []
    real33 = _real_blazepose(kinect.n_frames)
    if real33 is not None:  # the headline: full BlazePose-33 poses, every state computed
        sequences.append(("BlazePose 33, real videos (30 Hz)", real33))
    sequences += [
        ("BlazePose 33, synthetic (30 Hz)", _synthetic_blazepose(kinect.n_frames)),
        (f"UI-PRMD Kinect x{len(clips)} clips (30 Hz)", kinect),
    ]
    hdm = _hdm05_squats()
    if hdm is not None:
        sequences.append(("HDM05 squats (120 Hz, lag 4)", hdm))
    vicon = _vicon_clips(max(2, args.clips // 10))
    if vicon is not None:
        sequences.append((f"UI-PRMD Vicon ({vicon.fps:g} Hz, lag {vicon.fps / 30:.2f})", vicon))
    rows = [bench_sequence(name, seq, args.repeats, args.naive_frames)
            for name, seq in progress(sequences, "benchmarking")]  # fmt: skip
    per_clip = bench_per_clip(clips, args.repeats)
    floor = bench_output_write(kinect.n_frames, rows[0]["n_states"], args.repeats)
    _print_table(rows)
    head = rows[0]
    print(
        f"\nheadline, {head['sequence']} ({head['defined_fraction']:.1%} of states defined): "
        f"evaluate {head['evaluate_fps']['numba']:,.0f} frames/s on one core (goal 1,000,000: "
        f"{'met' if head['evaluate_fps']['numba'] >= 1e6 else 'NOT met'}), signals + evaluate "
        f"{head['end_to_end_fps_numba']:,.0f}"
    )
    print(f"\nper clip (signals + evaluate, {per_clip['clips']} UI-PRMD clips of "
          f"{per_clip['mean_frames_per_clip']:.0f} frames): numba "
          f"{per_clip['ms_per_clip']['numba']:.2f} ms/clip ({per_clip['fps']['numba']:,.0f} "
          f"frames/s), numpy {per_clip['ms_per_clip']['numpy']:.2f} ms/clip "
          f"({per_clip['fps']['numpy']:,.0f} frames/s)")  # fmt: skip
    print(
        f"output floor ({rows[0]['n_states']} float64 per frame): fresh array "
        f"{floor['fresh_array_fps']:,.0f} frames/s, refill {floor['refill_fps']:,.0f} frames/s"
    )
    print(
        f"start-up (import + first evaluate, fresh process, wall / CPU s): empty numba cache "
        f"{compile_s['cold_cache_s']:.1f} / {compile_s['cold_cache_cpu_s']:.1f}, warm cache "
        f"{compile_s['warm_cache_s']:.1f} / {compile_s['warm_cache_cpu_s']:.1f}, numpy backend "
        f"{compile_s['numpy_backend_s']:.1f} / {compile_s['numpy_backend_cpu_s']:.1f}"
    )
    print(
        f"times: median of {args.repeats}, {args.clock} clock, one thread; load average "
        f"{load_before[0]:.1f} on {os.cpu_count()} cores"
    )
    result = {
        "benchmark": "fluents",
        "command": "python -m benchmarks.fluents " + " ".join(argv or sys.argv[1:]),
        "goal_fps_one_core": 1_000_000,
        "headline": "evaluate_fps.numba of sequences[0]: full BlazePose-33, every state",
        "sequences": rows,
        "per_clip": per_clip,
        "output_floor": floor,
        "startup_s": compile_s,
        "repeats": args.repeats,
        "clock": args.clock,
        "machine": {
            "cpu": _cpu_model(),
            "cpu_count": os.cpu_count(),
            "threads_used": 1,
            "load_average_before": load_before,
            "load_average_after": os.getloadavg(),
            "platform": platform.platform(),
        },
        "versions": _versions(),
        "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    # a smoke run's figures never replace a full run's (README quotes those)
    path = RESULTS.with_name("fluents_quick.json") if args.quick else RESULTS
    write_json(result, path)
    print(f"wrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
