"""Cost growth: every stage's throughput on 1 and 2 Dask workers, and training at scale.

Run: ``python -m benchmarks.scale`` (corpora of 1,000 and 2,000 clips, about 10 min) or
``python -m benchmarks.scale --big`` (adds 10,000 and 50,000 clips, about an hour more);
``--skip-video`` leaves out decode + pose. Writes ``benchmarks/results/scale.json``.

The corpus is synthetic, built from real clips: the 180 UI-PRMD Kinect repetitions bundled in
``posecbr/demo_data/uiprmd`` (3 subjects, 10 movements), each copy turned about the vertical axis
(up to 20 degrees), played faster or slower (0.8-1.25x), given another body size per
synthetic person (0.9-1.1x) and 3 mm of noise. Copy ``k`` of a subject's clips is a new
person (``s01~k``), so a corpus of 50,000 clips has about 830 people.

Stages (each unit builds its synthetic clip first; the same code in every worker count):

- ``decode + pose``: ``posecbr extract --force`` on 40-frame cuts of the real exercise videos
  in ``../shared/data/videos`` (960 x 540), frames/s, each run on a fresh cluster of its own
  (``local:N``, and for comparison a ``LocalCluster`` with Dask's default settings), with the
  run's CPU seconds booked per process and thread (:data:`ROLES`: the command, the scheduler,
  nannies and client, the workers' task threads, their event loops, their other threads) and
  the machine's busy seconds, so what is not the work shows even on a loaded machine
  (``--only-video`` runs this stage alone and keeps the other figures);
- ``fluents`` (:func:`features.fluents.evaluate`), ``QMPs`` (:func:`features.qmp.qmp_features`),
  ``feature extraction`` (the train work unit, :func:`cbr.training.describe`: problem, mirror
  image, availability), ``classify`` (:meth:`CaseBaseClassifier.solve` against a case base of
  1,000 clips): clips/s on a ``LocalCluster`` of 1 and of 2 single-threaded workers, measured
  in the same run, with each worker's peak memory (VmHWM) and CPU seconds;
- training at scale, each size in a process of its own (peak memory = that process's VmHWM):
  feature extraction in that process, ``fit`` (fit_described), ``store write`` (SQLite, one
  transaction) and ``classify`` (200 new clips), seconds per clip, wall and CPU.

The machine is shared: the load average is recorded before and after every figure, and CPU
seconds beside wall seconds (other processes' load stretches wall time, not CPU time; the
worker-count speed-up a machine can give is ``workers x cpu_share_per_worker``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import write_json

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results" / "scale.json"
VIDEOS = ("glute_bridge", "lunge", "side_lying_leg_raise", "side_plank")
STAGE_UNITS = {"fluents": 400, "qmp": 120, "features": 400, "classify": 400}


# ---- the synthetic corpus -----------------------------------------------------------------


def base_clips() -> list[Any]:
    """The real clips the corpus is built from (canonical sequences)."""
    from features.poses import load_pose

    return [load_pose(p).to_canonical() for p in sorted(DEMO.glob("*.npz"))]


def synthetic(base: list[Any], i: int) -> Any:
    """Clip ``i`` of the corpus: a changed copy of ``base[i % len(base)]`` (see the module)."""
    from features.poses import PoseSequence

    b = base[i % len(base)]
    copy = i // len(base)
    subject = f"{b.metadata.get('subject')}~{copy}"
    person = np.random.default_rng([copy, sum(map(ord, subject))])
    rng = np.random.default_rng(i)
    p = b.positions
    frames = max(8, int(round(len(p) * rng.uniform(0.8, 1.25))))
    t = np.linspace(0.0, len(p) - 1.0, frames)
    lo = np.clip(np.floor(t).astype(int), 0, len(p) - 2)
    w = (t - lo)[:, None, None]
    q = p[lo] * (1.0 - w) + p[lo + 1] * w  # played faster or slower
    angle = np.deg2rad(rng.uniform(-20.0, 20.0))
    c, s = np.cos(angle), np.sin(angle)
    turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    q = (q @ turn.T) * person.uniform(0.9, 1.1) + rng.normal(0.0, 0.003, q.shape)
    meta = {**b.metadata, "subject": subject}
    return PoseSequence(q, b.joint_names, b.fps, source=f"synthetic/{i:06d}", metadata=meta)


# ---- stages on 1 and 2 workers ------------------------------------------------------------


def _peak_rss() -> int:
    """This process's peak resident memory in bytes. Linux's VmHWM: ``ru_maxrss`` of a process
    started by fork and exec begins at its parent's size (the kernel carries the old image's
    peak over), which would bill a worker or a training child for the benchmark's own memory."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def _cpu_s() -> float:
    """CPU seconds this process has used: unlike wall time, not stretched by other
    processes' load on a shared machine."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return float(r.ru_utime + r.ru_stime)


def _worker_cpu(client: Any) -> float:
    return float(sum(client.run(_cpu_s).values()))


# ---- where the CPU goes (per process and thread) -------------------------------------------

#: the roles CPU seconds are booked to during a run on a local cluster
ROLES = (
    "command",  # this process's main thread: the posecbr command (jobs, client, progress)
    "scheduler_nannies_client",  # this process's other threads: the event loop they share
    "worker_tasks",  # the workers' task threads: decode + pose, the work itself
    "worker_event_loops",  # the workers' main threads: comms, heartbeats, monitors, profiler
    "worker_other_threads",  # onnxruntime, OpenCV and BLAS pools, ended threads
    "other_children",  # any other process started from here (multiprocessing's tracker)
)


def _thread_names() -> tuple[int, dict[int, str]]:
    """This process's id and its Python threads' names by native thread id (on a worker)."""
    import threading

    return os.getpid(), {int(t.native_id or 0): t.name for t in threading.enumerate()}


def _machine_busy_s() -> float:
    """CPU seconds the whole machine has been busy since boot (/proc/stat, all CPUs: every
    state but idle and iowait), to tell this run's CPU from other processes'."""
    with open("/proc/stat", encoding="ascii") as fh:
        ticks = [int(v) for v in fh.readline().split()[1:9]]
    return (sum(ticks) - ticks[3] - ticks[4]) / os.sysconf("SC_CLK_TCK")


def _thread_role(name: str, worker: bool) -> str:
    if not worker:
        return "command" if name == "MainThread" else "scheduler_nannies_client"
    if "Dask-Default-Threads" in name:
        return "worker_tasks"
    return "worker_event_loops" if name == "MainThread" else "worker_other_threads"


def _cpu_by_role(client: Any) -> dict[str, float]:
    """CPU seconds so far of this process and every process it started, by :data:`ROLES`
    (threads by their Python names; a process's ended threads go to its catch-all role), and
    the machine's busy seconds."""
    import psutil

    me = psutil.Process()
    workers = dict(client.run(_thread_names).values())
    names = {me.pid: _thread_names()[1], **workers}
    roles = dict.fromkeys(ROLES, 0.0)
    for proc in [me, *me.children(recursive=True)]:
        try:
            threads, total = proc.threads(), sum(proc.cpu_times()[:2])
        except psutil.Error:  # ended meanwhile
            continue
        if proc.pid not in names:
            roles["other_children"] += total
            continue
        worker = proc.pid in workers
        for t in threads:
            role = _thread_role(names[proc.pid].get(t.id, ""), worker)
            roles[role] += t.user_time + t.system_time
        rest = total - sum(t.user_time + t.system_time for t in threads)
        roles["worker_other_threads" if worker else "scheduler_nannies_client"] += rest
    roles["machine_busy"] = _machine_busy_s()
    return roles


def _accounting(before: dict[str, float], after: dict[str, float], seconds: float,
                frames: int) -> dict[str, Any]:  # fmt: skip
    """CPU seconds of one run by role, cores (seconds / wall), other processes' share and
    the overhead: everything of ours that is not a task, over the tasks' CPU."""
    used = {k: after[k] - before[k] for k in ROLES}
    busy = after["machine_busy"] - before["machine_busy"]
    others = busy - sum(used.values())
    overhead = sum(v for k, v in used.items() if k != "worker_tasks")
    return {
        "cpu_s": {k: round(v, 3) for k, v in used.items()},
        "cores": {k: round(v / seconds, 3) for k, v in used.items()},
        "other_processes_cores": round(others / seconds, 3),
        "overhead_vs_tasks": round(overhead / used["worker_tasks"], 4),
        "task_cpu_ms_per_frame": round(1000 * used["worker_tasks"] / frames, 3),
    }


def stage_unit(i: int, base: list[Any], stage: str, model: Any) -> int:
    """One clip through one stage (on a worker); returns the clip's frames."""
    seq = synthetic(base, i)
    if stage == "fluents":
        from features.fluents import evaluate

        evaluate(seq)
    elif stage == "qmp":
        from features.qmp import qmp_features

        qmp_features(seq)
    elif stage == "features":
        from cbr.training import describe

        describe(seq, model)
    elif stage == "classify":
        model.solve([seq])
    return int(seq.n_frames)


def _load() -> list[float]:
    return [round(v, 2) for v in os.getloadavg()]


def _video_corpus(folder: Path, frames: int = 40) -> int:
    """40-frame cuts of the real exercise videos, at their size, as ``folder/<class>/*.mp4``."""
    import cv2

    n = 0
    for name in VIDEOS:
        src = next((DATA / "videos" / name).glob("*.mp4"))
        cap = cv2.VideoCapture(str(src))
        fps = cap.get(cv2.CAP_PROP_FPS)
        (folder / name).mkdir(parents=True, exist_ok=True)
        part, writer = 0, None
        while True:
            ok, bgr = cap.read()
            if not ok:
                break
            if writer is None:
                out = folder / name / f"{src.stem}_{part:02d}.mp4"
                size = (bgr.shape[1], bgr.shape[0])
                writer = cv2.VideoWriter(str(out), cv2.VideoWriter.fourcc(*"mp4v"), fps, size)
                count = 0
            writer.write(bgr)
            count += 1
            if count == frames:
                writer.release()
                writer, part, n = None, part + 1, n + 1
        if writer is not None:
            writer.release()
            n += 1
        cap.release()
    return n


def _timed(client: Any, workers: int, run: Any) -> dict[str, Any]:
    """``run()`` timed on ``client``: wall and worker CPU seconds. ``run`` returns the frames
    done, or a function that counts them, called once the clock has stopped."""
    before, cpu0 = _load(), _worker_cpu(client)
    t0 = time.perf_counter()
    frames = run()
    seconds = time.perf_counter() - t0
    if callable(frames):
        frames = frames()
    cpu = _worker_cpu(client) - cpu0
    return {
        "seconds": round(seconds, 3),
        "frames": frames,
        "worker_cpu_s": round(cpu, 3),
        "cpu_share_per_worker": round(cpu / (seconds * workers), 3),
        "load_before": before,
    }


def _stage_run(client: Any, base: list[Any], stage: str, model: Any, n: int) -> Any:
    from features.cluster import gather, map_outcomes

    def run() -> int:
        items = list(range(n))
        frames, failed = gather(map_outcomes(client, stage_unit, items, [str(i) for i in items],
                                             base, stage, model), n)  # fmt: skip
        if failed:
            raise RuntimeError(f"{stage}: {failed[0].name}: {failed[0].error}")
        return sum(f or 0 for f in frames)

    return run


def _extract_run(client: Any, videos: Path, out: Path) -> Any:
    from posecbr.cli import main

    def frames() -> int:
        from features.poses import load_pose

        return sum(load_pose(p).n_frames for p in out.rglob("*.npz"))

    def run() -> Any:
        code = main(["extract", str(videos), "--out", str(out), "--force", "--scheduler",
                     client.scheduler.address])  # fmt: skip
        if code != 0:
            raise RuntimeError("extract failed")
        return frames  # counted off the clock: reading the pose files is not extraction

    return run


def _summary(runs: list[dict[str, Any]], units: int) -> dict[str, Any]:
    """The median round of one stage on one cluster, with every round kept."""
    mid = sorted(runs, key=lambda r: r["seconds"])[len(runs) // 2]
    return {
        "units": units,
        "frames": mid["frames"],
        "seconds": mid["seconds"],
        "units_per_s": round(units / mid["seconds"], 3),
        "frames_per_s": round(mid["frames"] / mid["seconds"], 2),
        "frames_per_worker_cpu_s": round(
            statistics.median(r["frames"] / r["worker_cpu_s"] for r in runs), 2
        ),
        "cpu_share_per_worker": mid["cpu_share_per_worker"],
        "rounds": runs,
    }


def _per_cpu(runs: list[dict[str, Any]]) -> float:
    return float(statistics.median(r["frames"] / r["worker_cpu_s"] for r in runs))


def _print_stage(stage: str, s: dict[str, Any]) -> None:
    print(f"  {stage:<12} 1 worker {s['1']['frames_per_s']:8.1f} frames/s, 2 workers "
          f"{s['2']['frames_per_s']:8.1f}: x{s['speedup_1_to_2']:.2f} (CPU share per "
          f"worker {s['1']['cpu_share_per_worker']:.2f} / "
          f"{s['2']['cpu_share_per_worker']:.2f}; frames per CPU-second with 2 workers "
          f"x{s['cpu_efficiency_2_vs_1']:.2f} of 1)", flush=True)  # fmt: skip


def _compare_rounds(timed: dict[int, list[dict[str, Any]]], units: int) -> dict[str, Any]:
    """One stage's figures from its rounds on 1 and 2 workers (round r of each back to back)."""
    rounds = len(timed[1])
    ratios = [timed[1][r]["seconds"] / timed[2][r]["seconds"] for r in range(rounds)]
    return {
        "1": _summary(timed[1], units),
        "2": _summary(timed[2], units),
        "speedup_1_to_2": round(statistics.median(ratios), 3),
        "cpu_efficiency_2_vs_1": round(_per_cpu(timed[2]) / _per_cpu(timed[1]), 3),
    }


def _run_stages(rounds: int = 3) -> dict[str, Any]:
    """Every stage but decode + pose on a 1-worker and a 2-worker cluster, alternating,
    ``rounds`` times: the speed-up is the median of the rounds' ratios (each round runs both
    back to back, so load from other processes cancels better than across a run)."""
    from cbr.estimator import CaseBaseClassifier
    from cbr.training import fit_plan
    from features.cluster import connect, gather, map_outcomes

    base = base_clips()
    plan = fit_plan(CaseBaseClassifier())
    train = [synthetic(base, i) for i in range(1000)]
    clf = CaseBaseClassifier().fit(train, [str(s.metadata["label"]) for s in train])
    del train
    stages: dict[str, Any] = {}
    with connect("local:1") as c1, connect("local:2") as c2:
        clients = {1: c1, 2: c2}
        runs: dict[str, Any] = {}
        for stage, n in STAGE_UNITS.items():
            model = plan if stage == "features" else clf
            runs[stage] = {w: _stage_run(c, base, stage, model, n) for w, c in clients.items()}
        for w, c in clients.items():  # load models, compile kernels: untimed
            c.wait_for_workers(w, timeout=300)
            warm = list(range(10**6, 10**6 + 2 * w))
            for stage in STAGE_UNITS:
                model = plan if stage == "features" else clf
                gather(map_outcomes(c, stage_unit, warm, [str(i) for i in warm], base, stage,
                                    model), len(warm))  # fmt: skip
        for stage, by_workers in runs.items():
            timed: dict[int, list[dict[str, Any]]] = {1: [], 2: []}
            for _ in range(rounds):
                for w in (1, 2):
                    timed[w].append(_timed(clients[w], w, by_workers[w]))
            stages[stage] = _compare_rounds(timed, STAGE_UNITS[stage])
            _print_stage(stage, stages[stage])
        stages["worker_peak_rss_bytes"] = {
            str(w): sorted(c.run(_peak_rss).values()) for w, c in clients.items()
        }
    return stages


# ---- decode + pose: posecbr's cluster settings against Dask's defaults ---------------------


def _dask_defaults(n: int) -> AbstractContextManager[Any]:
    """A client of a ``LocalCluster`` made as ``local:N`` makes it, but with Dask's default
    settings (no :data:`features.cluster.LEAN_CONFIG`): the before of the CPU accounting."""
    from features.cluster import connect

    return connect(f"local:{n}", lean=False)


def _warm_extract(client: Any, workers: int, videos: Path, tmp: Path) -> None:
    """Every worker loads the pose models (untimed): a folder of 2 clips per worker."""
    from posecbr.cli import main as posecbr

    client.wait_for_workers(workers, timeout=300)
    warm_in = Path(tempfile.mkdtemp(dir=tmp))
    for v in sorted(videos.rglob("*.mp4"))[: 2 * workers]:  # a folder: runs on the cluster
        (warm_in / v.name).symlink_to(v)
    posecbr(["extract", str(warm_in), "--out", str(tmp / "warm"), "--force", "--scheduler",
             client.scheduler.address])  # fmt: skip


def _timed_extract(client: Any, workers: int, run: Any) -> dict[str, Any]:
    """:func:`_timed` with the run's CPU accounting and the workers' idle seconds (wall x
    workers minus the task stream's compute time: start-up, scheduling and the tail)."""
    from dask.distributed import get_task_stream

    before = _cpu_by_role(client)
    with get_task_stream(client) as stream:
        timed = _timed(client, workers, run)
    acc = _accounting(before, _cpu_by_role(client), timed["seconds"], timed["frames"])
    computing = sum(ss["stop"] - ss["start"] for task in stream.data
                    for ss in task["startstops"] if ss["action"] == "compute")  # fmt: skip
    acc["worker_idle_s"] = round(workers * timed["seconds"] - computing, 3)
    return {**timed, "cpu_accounting": acc}


def _idle_cores(client: Any, seconds: float = 5.0) -> dict[str, float]:
    """Cores the cluster uses by role while it has nothing to do (its bookkeeping alone)."""
    before = _cpu_by_role(client)
    time.sleep(seconds)
    after = _cpu_by_role(client)
    return {k: round((after[k] - before[k]) / seconds, 4) for k in ROLES}


def _median_accounting(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Every accounting figure's median over the rounds."""
    accs = [r["cpu_accounting"] for r in runs]
    med = statistics.median
    return {
        "cores": {k: round(med(a["cores"][k] for a in accs), 3) for k in ROLES},
        "idle_cores": {k: round(med(r["idle_cores"][k] for r in runs), 4) for k in ROLES},
        **{k: round(med(a[k] for a in accs), 4) for k in accs[0] if k not in ("cores", "cpu_s")},
    }


def _one_video_run(config: str, workers: int, tmp: Path) -> dict[str, Any]:
    """One timed ``extract`` of the corpus in ``tmp/videos`` on a cluster of its own (warmed
    up first; no other cluster idles beside it, so all CPU booked is this run's)."""
    from features.cluster import connect

    cluster = connect(f"local:{workers}") if config == "posecbr" else _dask_defaults(workers)
    with cluster as client:
        _warm_extract(client, workers, tmp / "videos", tmp)
        run = _extract_run(client, tmp / "videos", tmp / f"out-{config}-{workers}")
        timed = _timed_extract(client, workers, run)
        timed["idle_cores"] = _idle_cores(client)
        timed["worker_peak_rss_bytes"] = sorted(client.run(_peak_rss).values())
    return timed


def _run_video(rounds: int = 3) -> dict[str, Any]:
    """Decode + pose (``posecbr extract`` of 40-frame cuts) on 1 and 2 workers, on clusters
    with posecbr's settings (``local:N``) and with Dask's defaults, every round running all
    four back to back; each run's CPU is booked by role (:func:`_cpu_by_role`)."""
    configs = ("posecbr", "dask_defaults")
    timed: dict[tuple[str, int], list[dict[str, Any]]] = {}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        n_videos = _video_corpus(tmp / "videos")
        for _ in range(rounds):
            for c in configs:
                for w in (1, 2):
                    timed.setdefault((c, w), []).append(_one_video_run(c, w, tmp))
    result: dict[str, Any] = {}
    for c in configs:
        stage = _compare_rounds({w: timed[c, w] for w in (1, 2)}, n_videos)
        for n in ("1", "2"):
            stage[n]["cpu_accounting"] = _median_accounting(stage[n]["rounds"])
        _print_stage(f"decode_pose ({c})", stage)
        _print_accounting(stage)
        result[c] = stage
    return {**result.pop("posecbr"), "dask_defaults": result["dask_defaults"]}


def _print_accounting(stage: dict[str, Any]) -> None:
    for w in ("1", "2"):
        acc = stage[w]["cpu_accounting"]
        cores = ", ".join(f"{k} {v:.3f}" for k, v in acc["cores"].items())
        print(f"    {w} worker(s), cores: {cores}; other processes "
              f"{acc['other_processes_cores']:.2f}; overhead / tasks "
              f"{acc['overhead_vs_tasks']:.3f}; task CPU {acc['task_cpu_ms_per_frame']:.2f} "
              f"ms/frame; workers idle {acc['worker_idle_s']:.2f} s; the cluster idle "
              f"{sum(acc['idle_cores'].values()):.3f} cores", flush=True)  # fmt: skip


# ---- training at scale (one process per size) -----------------------------------------------


def train_one(n: int) -> dict[str, Any]:
    """Train on ``n`` synthetic clips in this process (see the module): seconds per stage."""
    from cbr.estimator import CaseBaseClassifier
    from cbr.training import describe, fit_plan, store_fitted

    os.environ["POSECBR_NO_PROGRESS"] = "1"
    base = base_clips()
    estimator = CaseBaseClassifier()
    plan = fit_plan(estimator)
    load0, cpu0 = _load(), _cpu_s()
    t0 = time.perf_counter()
    described = [describe(synthetic(base, i), plan) for i in range(n)]
    labels = [str(base[i % len(base)].metadata["label"]) for i in range(n)]
    t1 = time.perf_counter()
    fitted = CaseBaseClassifier().fit_described(described, labels)
    t2 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        store_fitted(Path(tmp) / "cb.sqlite", "default", fitted, labels)
        db_bytes = (Path(tmp) / "cb.sqlite").stat().st_size
    t3, cpu3 = time.perf_counter(), _cpu_s()
    queries = [synthetic(base, 10**7 + i) for i in range(200)]
    t4 = time.perf_counter()
    fitted.solve(queries)
    t5 = time.perf_counter()
    return {
        "clips": n,
        "features_s": round(t1 - t0, 2),
        "fit_s": round(t2 - t1, 2),
        "store_write_s": round(t3 - t2, 2),
        "train_s": round(t3 - t0, 2),
        "train_ms_per_clip": round(1000 * (t3 - t0) / n, 3),
        "train_cpu_s": round(cpu3 - cpu0, 2),
        "train_cpu_ms_per_clip": round(1000 * (cpu3 - cpu0) / n, 3),
        "classify_ms_per_clip": round(1000 * (t5 - t4) / len(queries), 3),
        "cases": len(fitted.case_base_),
        "case_base_bytes_in_memory": int(fitted.case_base_.problems.nbytes),
        "store_bytes": db_bytes,
        "peak_rss_bytes": _peak_rss(),
        "chosen": {
            "side": fitted.side_,
            "weighting": fitted.weighting_,
            "phases": fitted.phases_,
        },  # fmt: skip
        "subjects": len({d.subject for d in described}),
        "load_before": load0,
        "load_after": _load(),
    }


def _train_in_child(n: int) -> dict[str, Any]:
    cmd = [sys.executable, "-m", "benchmarks.scale", "--train-one", str(n)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"training on {n} clips failed: {done.stderr.strip()[-2000:]}")
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    print(f"  train {n:6d} clips: {result['train_ms_per_clip']:.2f} ms/clip "
          f"(features {result['features_s']} s, fit {result['fit_s']} s, store "
          f"{result['store_write_s']} s), peak {result['peak_rss_bytes'] / 2**30:.2f} GiB, "
          f"load {result['load_before'][0]:.1f}", flush=True)  # fmt: skip
    return result


# ---- the table -----------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.scale", description=__doc__)
    parser.add_argument("--big", action="store_true", help="also 10,000 and 50,000 clips")
    parser.add_argument("--sizes", help="training sizes, comma-separated (overrides --big)")
    parser.add_argument("--skip-video", action="store_true", help="no decode + pose stage")
    parser.add_argument("--skip-stages", action="store_true", help="training at scale only")
    parser.add_argument(
        "--only-video",
        action="store_true",
        help="of the stages, decode + pose only (the others' figures kept)",
    )
    parser.add_argument("--skip-training", action="store_true", help="the stages only")
    parser.add_argument("--train-one", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.train_one:
        print(json.dumps(train_one(args.train_one)))
        return 0
    sizes = [1000, 2000] + ([10000, 50000] if args.big else [])
    if args.sizes:
        sizes = [int(s) for s in args.sizes.split(",")]
    from cbr.evaluation.machine import machine_info

    doc = _previous()  # a partial run keeps the other figures
    doc["benchmark"], doc["machine"] = "scale", machine_info()
    doc["corpus"] = "synthetic copies of posecbr/demo_data/uiprmd (see docstring)"
    if not args.skip_stages:
        stages = doc.get("stages", {}) if args.only_video else _run_stages()
        if not args.skip_video:
            stages["decode_pose"] = _run_video()
        doc["stages"] = stages
        write_json(doc, RESULTS)
    if not args.skip_training:
        by_size = {t["clips"]: t for t in doc.get("training", [])}
        for n in sizes:
            by_size[n] = _train_in_child(n)
            doc["training"] = [by_size[k] for k in sorted(by_size)]
            write_json(doc, RESULTS)
        _relative(doc["training"])
    write_json(doc, RESULTS)
    print(f"wrote {RESULTS.relative_to(ROOT)}")
    return 0


def _previous() -> dict[str, Any]:
    try:
        doc = json.loads(RESULTS.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return {}
    return doc if isinstance(doc, dict) else {}


def _relative(training: list[dict[str, Any]]) -> None:
    """Time per clip of every size over that of the smallest (wall and CPU)."""
    first = training[0]
    for t in training:
        t["time_per_clip_vs_smallest"] = round(t["train_ms_per_clip"] / first["train_ms_per_clip"],
                                               3)  # fmt: skip
        if "train_cpu_ms_per_clip" in t and "train_cpu_ms_per_clip" in first:
            t["cpu_per_clip_vs_smallest"] = round(
                t["train_cpu_ms_per_clip"] / first["train_cpu_ms_per_clip"], 3
            )


if __name__ == "__main__":
    sys.exit(main())
