"""QMP fitting and DAD speed, against pysindy's own fit in the same run.

Run: ``python -m benchmarks.qmp [--repeats N] [--quick]``. One core: BLAS threads are pinned
to 1 before numpy loads. Writes ``benchmarks/results/qmp.json``.

Measured:
- one QMP fit = the period search for one signal over one 4-s window at 30 Hz (32 periods,
  plus the refinement rounds for ours). pysindy: ``ps.SINDy(...).fit`` once per period with the
  same library and STLSQ, keeping the smallest residual (no refinement, so it does less work).
  Ours: ``fit_signals`` on that one signal, and amortised over a clip's worth of signals and
  windows fitted in one call (all 94 state signals of a 10-s clip). The same batch by
  pysindy as fast as it goes: per window and period one ``SINDy.fit`` with all 94 signals as
  targets (the fair bulk ratio; the one-signal-per-call ratio is shown beside it).
- one fixed-period fit (no search): pysindy's fit vs the batched STLSQ.
- DAD per clip on real data: state signals + QMP fits + ADD + scoring, for 10-s clips made
  of consecutive UI-PRMD deep-squat repetitions (Kinect, 30 Hz) and HDM05 squat takes
  (120 Hz), and per HDM05/UI-PRMD clip as recorded. Goal: 10-s clip < 100 ms on one core.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from collections.abc import Callable  # noqa: E402
from functools import partial  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results" / "qmp.json"


def _median_time(fn: Callable[[], Any], repeats: int, inner: int = 1) -> float:
    """Median seconds per call over ``repeats`` timings of ``inner`` calls (after a warm-up)."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        times.append((time.perf_counter() - t0) / inner)
    return statistics.median(times)


def _signal(seconds: float, fps: float = 30.0, seed: int = 0) -> np.ndarray:
    t = np.arange(int(seconds * fps)) / fps
    rng = np.random.default_rng(seed)
    return 2.0 + 0.6 * np.cos(2 * np.pi * t / 2.3 + 0.4) + 0.01 * rng.standard_normal(len(t))


def bench_fits(repeats: int) -> dict[str, Any]:
    import pysindy as ps

    from features.qmp import STLSQ, ExplicitTimeLibrary, QMPConfig, SavitzkyGolay, fit_signals
    from features.qmp.fit import fit_shared_periods, period_grid

    cfg = QMPConfig()
    fps, window = 30.0, 4.0
    x = _signal(window, fps)
    t = np.arange(len(x)) / fps
    xdot = SavitzkyGolay()(x[:, None], fps)
    periods = period_grid(cfg.min_period_s, window / 2, cfg.n_periods)
    lib, opt = ExplicitTimeLibrary(), STLSQ()

    def pysindy_search() -> float:
        best = np.inf
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for period in periods:
                m = ps.SINDy(feature_library=lib.to_pysindy(period), optimizer=opt.to_pysindy())
                m.fit(np.zeros((len(t), 1)), t=t, x_dot=xdot, u=t[:, None])
                c = np.asarray(m.coefficients())[0]
                best = min(best, float(((xdot[:, 0] - lib.matrix(t, period) @ c) ** 2).sum()))
        return best

    def pysindy_one() -> None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = ps.SINDy(feature_library=lib.to_pysindy(2.3), optimizer=opt.to_pysindy())
            m.fit(np.zeros((len(t), 1)), t=t, x_dot=xdot, u=t[:, None])

    def ours_one_period() -> None:
        fit_shared_periods(t, xdot, np.array([2.3]), lib, opt)

    def ours_search() -> None:
        fit_signals(x[:, None], fps, ["x"], config=cfg)

    # A 10-s clip's worth: 94 signals (all state signals), 4-s windows every 1 s -> 7 windows.
    clip = np.stack([_signal(10.0, fps, seed=s) for s in range(94)], axis=1)
    names = [f"s{i}" for i in range(94)]
    n_windows = 7

    def ours_bulk() -> None:
        fit_signals(clip, fps, names, config=cfg, window_s=window, step_s=1.0)

    # pysindy on the same batch, as fast as it goes: per window and period ONE fit with all 94
    # signals as targets (pysindy fits the columns of x_dot together), best period per signal
    win_len = int(window * fps)
    tw = np.arange(win_len) / fps
    windows = [clip[int(s * fps) : int(s * fps) + win_len] for s in range(n_windows)]
    win_dots = [SavitzkyGolay()(w, fps) for w in windows]

    def pysindy_bulk() -> np.ndarray:
        best = np.full((n_windows, 94), np.inf)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for w, xdot_w in enumerate(win_dots):
                for period in periods:
                    m = ps.SINDy(
                        feature_library=lib.to_pysindy(period, n_states=94),
                        optimizer=opt.to_pysindy(),
                    )
                    m.fit(np.zeros((win_len, 94)), t=tw, x_dot=xdot_w, u=tw[:, None])
                    c = np.asarray(m.coefficients())  # (94, 6)
                    resid = ((xdot_w - lib.matrix(tw, period) @ c.T) ** 2).sum(axis=0)
                    best[w] = np.minimum(best[w], resid)
        return best

    ps_search = _median_time(pysindy_search, max(3, repeats // 4))
    ps_one = _median_time(pysindy_one, repeats, inner=5)
    our_one = _median_time(ours_one_period, repeats, inner=50)
    our_search = _median_time(ours_search, repeats, inner=5)
    our_bulk = _median_time(ours_bulk, repeats)
    ps_bulk = _median_time(pysindy_bulk, max(3, repeats // 5))
    bulk_per_fit = our_bulk / (94 * n_windows)
    ps_bulk_per_fit = ps_bulk / (94 * n_windows)
    return {
        "setup": f"one signal, one {window:g}-s window at {fps:g} Hz, {len(periods)} periods",
        "pysindy_period_search_fits_per_s": 1.0 / ps_search,
        "ours_period_search_single_fits_per_s": 1.0 / our_search,
        "ours_period_search_bulk_fits_per_s": 1.0 / bulk_per_fit,
        "bulk_clip_ms": 1e3 * our_bulk,
        "bulk_clip": "94 signals x 7 windows (10-s clip, 4-s windows, 1-s step)",
        "pysindy_fixed_period_fits_per_s": 1.0 / ps_one,
        "ours_fixed_period_fits_per_s": 1.0 / our_one,
        "ratio_search_single": ps_search / our_search,
        "ratio_search_bulk": ps_search / bulk_per_fit,
        "pysindy_period_search_bulk_fits_per_s": 1.0 / ps_bulk_per_fit,
        "pysindy_bulk": "per window and period one SINDy.fit with all 94 signals as targets",
        "ratio_search_bulk_vs_pysindy_bulk": ps_bulk_per_fit / bulk_per_fit,
        "ratio_fixed_period": ps_one / our_one,
    }


def _uiprmd_squat_10s() -> list[Any]:
    """10-s clips: consecutive deep-squat repetitions of one subject, joined end to end."""
    from features.datasets import iter_dataset
    from features.poses import PoseSequence

    out = []
    for subject in ("s01", "s02", "s03"):
        reps = list(
            iter_dataset(DATA / "ui-prmd", movements={"m01"}, subjects={subject}, correct=True)
        )
        reps.sort(key=lambda c: c.extras["episode"])
        frames, total = [], 0
        for c in reps:
            frames.append(c.seq.positions)
            total += len(c.seq.positions)
            if total >= 300:
                break
        pos = np.concatenate(frames)[:300]
        s0 = reps[0].seq
        out.append(PoseSequence(pos, s0.joint_names, s0.fps, skeleton=s0.skeleton))
    return out


def _hdm05_squat_10s() -> list[Any]:
    from features.datasets import iter_dataset
    from features.poses import PoseSequence

    takes = list(iter_dataset(DATA / "hdm05", labels={"squat1Reps"}, subjects={"bd"}))
    pos = np.concatenate([c.seq.positions for c in takes])
    n = int(10 * takes[0].seq.fps)
    s0 = takes[0].seq
    if len(pos) < n:
        pos = np.concatenate([pos] * (n // len(pos) + 1))
    return [PoseSequence(pos[:n], s0.joint_names, s0.fps, skeleton=s0.skeleton)]


def bench_dad(repeats: int) -> dict[str, Any]:
    from cbr.dad import detect
    from features.datasets import iter_dataset
    from features.fluents import state_signals
    from features.qmp.add import load_add

    add = load_add()
    out: dict[str, Any] = {}
    for name, clips in (
        ("uiprmd_deep_squat_10s_30hz", _uiprmd_squat_10s()),
        ("hdm05_squat_10s_120hz", _hdm05_squat_10s()),
    ):
        per_clip = [_median_time(partial(detect, c, add), repeats) for c in clips]
        signals_only = [_median_time(partial(state_signals, c), repeats) for c in clips]
        out[name] = {
            "clips": len(clips),
            "seconds_per_clip": float(clips[0].positions.shape[0] / clips[0].fps),
            "dad_ms_median": 1e3 * statistics.median(per_clip),
            "of_which_state_signals_ms": 1e3 * statistics.median(signals_only),
        }
    recorded = list(iter_dataset(DATA / "hdm05", labels={"squat1Reps"}, subjects={"bk"}))
    recorded += list(iter_dataset(DATA / "ui-prmd", episodes={6}, subjects={"s04"}))
    times = [_median_time(partial(detect, c.seq, add), max(3, repeats // 2)) for c in recorded]
    secs = [c.seq.positions.shape[0] / c.seq.fps for c in recorded]
    out["recorded_clips"] = {
        "clips": len(recorded),
        "mean_clip_s": float(np.mean(secs)),
        "dad_ms_median": 1e3 * statistics.median(times),
        "dad_ms_max": 1e3 * max(times),
    }
    return out


def bench_accuracy() -> dict[str, Any]:
    """DAD accuracy on clips the ADD thresholds were not set on: UI-PRMD Kinect episodes 4-10
    (the ADD was tuned on Kinect episodes 1-3), UI-PRMD Vicon episodes 4-10 (correct
    repetitions only exist), and HDM05 actor dg (tuned on bd and bk)."""
    from collections import Counter

    from cbr.dad import DADClassifier
    from features.datasets import iter_dataset

    out: dict[str, Any] = {}
    uiprmd = list(iter_dataset(DATA / "ui-prmd", episodes=set(range(4, 11))))
    vicon = list(iter_dataset(DATA / "ui-prmd", sensor="vicon", episodes=set(range(4, 11))))
    hdm05 = list(iter_dataset(DATA / "hdm05", subjects={"dg"}))
    for name, clips in (
        ("uiprmd_kinect_episodes_4_10", uiprmd),
        ("uiprmd_vicon_episodes_4_10", vicon),
        ("hdm05_actor_dg", hdm05),
    ):
        X, y = [c.seq for c in clips], np.array([c.label for c in clips])
        pred = DADClassifier().fit(X, y).predict(X)
        ok = pred == y
        correct = np.array([c.extras.get("correct", True) for c in clips])
        per_class = Counter(y.tolist())
        out[name] = {
            "clips": len(clips),
            "classes": len(per_class),
            "accuracy": float(ok.mean()),
            "accuracy_correct_executions": float(ok[correct].mean()),
            "accuracy_incorrect_executions": float(ok[~correct].mean())
            if (~correct).any()
            else None,
            "per_class": {k: float(ok[y == k].mean()) for k in sorted(per_class)},
        }
    return out


def _versions() -> dict[str, str]:
    import pysindy
    import scipy

    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "pysindy": getattr(pysindy, "__version__", "?"),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15, help="timings per measure (median)")
    parser.add_argument(
        "--quick", action="store_true", help="fewer repeats (smoke run, written to qmp_quick.json)"
    )
    parser.add_argument(
        "--accuracy", action="store_true", help="also DAD accuracy on held-out real clips (~1 min)"
    )
    args = parser.parse_args(argv)
    repeats = 3 if args.quick else max(3, args.repeats)

    fits = bench_fits(repeats)
    print(f"QMP fits ({fits['setup']}), one core, median of {repeats}:")
    print(f"  {'':42s}{'fits/s':>12s}{'vs pysindy':>12s}")
    rows = [
        ("pysindy period search (loop of SINDy.fit)", fits["pysindy_period_search_fits_per_s"],
         1.0),
        ("ours, period search, one signal per call", fits["ours_period_search_single_fits_per_s"],
         fits["ratio_search_single"]),
        ("pysindy period search, bulk (94 sig/call)",
         fits["pysindy_period_search_bulk_fits_per_s"],
         fits["pysindy_period_search_bulk_fits_per_s"] / fits["pysindy_period_search_fits_per_s"]),
        ("ours, period search, bulk (94 sig x 7 win)", fits["ours_period_search_bulk_fits_per_s"],
         fits["ratio_search_bulk"]),
        ("pysindy, one fixed period", fits["pysindy_fixed_period_fits_per_s"], 1.0),
        ("ours, one fixed period", fits["ours_fixed_period_fits_per_s"],
         fits["ratio_fixed_period"]),
    ]  # fmt: skip
    for label, rate, ratio in rows:
        print(f"  {label:42s}{rate:12.1f}{ratio:11.1f}x")
    print(f"  bulk call for the whole clip: {fits['bulk_clip_ms']:.1f} ms")
    print(
        f"  same batch, ours vs pysindy fitting all signals in one call: "
        f"{fits['ratio_search_bulk_vs_pysindy_bulk']:.1f}x"
    )

    dad: dict[str, Any] = {}
    if DATA.is_dir():
        dad = bench_dad(repeats)
        print("\nDAD per clip (state signals + QMP fits + ADD + scoring), one core:")
        for name, r in dad.items():
            if name == "recorded_clips":
                print(
                    f"  {name:30s} {r['clips']} clips of {r['mean_clip_s']:.1f} s on average: "
                    f"median {r['dad_ms_median']:.1f} ms, max {r['dad_ms_max']:.1f} ms"
                )
            else:
                sig_ms = r["of_which_state_signals_ms"]
                print(
                    f"  {name:30s} {r['seconds_per_clip']:.0f}-s clip: "
                    f"{r['dad_ms_median']:.1f} ms (state signals {sig_ms:.1f} ms)  goal < 100 ms"
                )
    else:
        print(f"\n(no real data at {DATA}: DAD timing skipped)")

    accuracy: dict[str, Any] = {}
    if args.accuracy and DATA.is_dir():
        accuracy = bench_accuracy()
        print("\nDAD accuracy (no training; ADD thresholds not set on these clips):")
        for name, r in accuracy.items():
            inc = r["accuracy_incorrect_executions"]
            inc_text = f", incorrect executions {inc:.1%}" if inc is not None else ""
            print(
                f"  {name:30s} {r['clips']} clips, {r['classes']} classes: {r['accuracy']:.1%}"
                f" (correct executions {r['accuracy_correct_executions']:.1%}{inc_text})"
            )
            for label, acc in r["per_class"].items():
                print(f"      {label:46s} {acc:6.1%}")

    result = {
        "benchmark": "qmp",
        "machine": {
            "platform": platform.platform(),
            "processor": platform.processor() or platform.machine(),
            "cpu_count": os.cpu_count(),
            "threads": 1,
            # Other work on the machine slows every timing; the load says how busy it was.
            "load_average_1_5_15min_at_end": list(os.getloadavg()),
        },
        "versions": _versions(),
        "repeats": repeats,
        "fits": fits,
        "dad": dad,
        "accuracy": accuracy,
    }
    # a smoke run's figures never replace a full run's (README quotes those)
    path = RESULTS.with_name("qmp_quick.json") if args.quick else RESULTS
    write_json(result, path)
    print(f"\nwrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
