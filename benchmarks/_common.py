"""Helpers shared by the search benchmarks: one thread for every library, timings taken side by
side (rounds over every method in rotated order, so all see the same machine load), the load
average, and the real UI-PRMD features.

Import this module before numpy: it pins the thread pools of BLAS/OpenMP/numba to one thread
through the environment (threadpoolctl and faiss are pinned again at run time).
"""

from __future__ import annotations

import os
import platform

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import importlib.metadata  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

# peers' import-time chatter (tslearn without h5py, aeon's numba casts) is not a result
warnings.filterwarnings("ignore", message="h5py not installed")
warnings.filterwarnings("ignore", message="unsafe cast from uint64 to int64")

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results"


def require_peer(module: str, package: str, benchmark: str) -> None:
    """Exit with one line when ``module``, the peer ``benchmark`` measures against, is not
    installed (the ``bench`` extra): without its peer a benchmark has nothing to compare."""
    import importlib.util

    if importlib.util.find_spec(module) is None:
        raise SystemExit(
            f"python -m benchmarks.{benchmark}: needs {package}, the peer it measures against "
            "(pip install -e '.[bench]')"
        )


def pin_one_thread() -> dict[str, Any]:
    """One thread for BLAS and OpenMP (threadpoolctl) and FAISS; what is pinned, as data."""
    from threadpoolctl import threadpool_info, threadpool_limits

    threadpool_limits(1)
    try:
        import faiss

        faiss.omp_set_num_threads(1)
    except ImportError:
        pass
    return {
        "policy": "one thread per library unless a row says threads=2",
        "pools": [
            {"api": p["internal_api"], "threads": p["num_threads"]} for p in threadpool_info()
        ],
    }


def load() -> float:
    """The 1-minute load average (the machine is shared: figures under load are slower)."""
    return round(os.getloadavg()[0], 2)


def versions(*packages: str) -> dict[str, str | None]:
    out: dict[str, str | None] = {}
    for pkg in packages:
        try:
            out[pkg] = importlib.metadata.version(pkg)
        except importlib.metadata.PackageNotFoundError:
            out[pkg] = None
    return out


def one_thread_machine() -> dict[str, Any]:
    """The machine facts of a benchmark run on one thread, with the load average at its end."""
    return {
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "threads": 1,
        "load_average_1_5_15min_at_end": list(os.getloadavg()),
    }


def side_by_side(
    methods: dict[str, Callable[[int], Any]], n_queries: int, rounds: int = 3
) -> tuple[dict[str, float], dict[str, list[Any]]]:
    """Median ms per query of each method over ``rounds`` x ``n_queries`` timings, and each
    method's answers (query order, from the first round).

    Each round runs every method over all the queries, methods in an order rotated by the
    round, so a burst of load on the shared machine hits all alike while each method runs in
    its steady state (a method timed right after another that swept 1 GB through the caches
    measured up to 5x slower than alone); a method's first call is a warm-up, not timed.
    """
    names = list(methods)
    for name in names:
        methods[name](0)
    times: dict[str, list[float]] = {n: [] for n in names}
    answers: dict[str, list[Any]] = {n: [] for n in names}
    for r in range(rounds):
        for s in range(len(names)):
            name = names[(r + s) % len(names)]
            for j in range(n_queries):
                t0 = time.perf_counter()
                got = methods[name](j)
                times[name].append(time.perf_counter() - t0)
                if r == 0:
                    answers[name].append(got)
    return {n: 1000 * statistics.median(times[n]) for n in names}, answers


def identical_neighbours(answers: dict[str, Any], want: Any) -> dict[str, int]:
    """For each method of ``answers`` (its neighbours of every query, in query order), how many
    queries it answered with exactly the neighbours of ``want``, in the same order."""
    return {
        name: sum(bool(np.array_equal(a, w)) for a, w in zip(got, want, strict=True))
        for name, got in answers.items()
    }


def median_ms(fn: Callable[[], Any], repeats: int) -> float:
    """Median ms of ``repeats`` calls of ``fn`` after one warm-up."""
    fn()
    t = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return 1000 * statistics.median(t)


def uiprmd_clips() -> list[Any]:
    """Every UI-PRMD Kinect clip in ``../shared/data`` (1600 repetitions, 10 movements)."""
    from features.datasets import load_dataset

    path = DATA / "ui-prmd"
    if not path.exists():
        raise SystemExit(f"benchmark: no UI-PRMD data under {path}")
    return load_dataset(path, progress_desc="loading UI-PRMD")


def subject_split(clips: list[Any]) -> tuple[np.ndarray, np.ndarray]:
    """Boolean masks (case base, queries): subjects s01-s06 build the case base, the clips of
    s07-s08 (people it has never seen) are the queries."""
    subjects = np.array([str(c.seq.metadata.get("subject", "")) for c in clips])
    query = np.isin(subjects, ["s07", "s08", "7", "8", "07", "08"])
    if not query.any() or query.all():
        raise SystemExit(f"benchmark: cannot split UI-PRMD by subject ({sorted(set(subjects))})")
    return ~query, query


def grow(
    base: np.ndarray, n: int, rng: np.random.Generator, jitter: float, clip: tuple[float, float]
) -> np.ndarray:
    """``n`` rows sampled with replacement from ``base`` ``(m, ...)``, each with Gaussian
    jitter of sd ``jitter`` (clipped to ``clip``), float32, built in chunks."""
    out = np.empty((n, *base.shape[1:]), dtype=np.float32)
    for a in range(0, n, 20000):
        pick = rng.integers(0, len(base), min(20000, n - a))
        noise = rng.normal(scale=jitter, size=(len(pick), *base.shape[1:]))
        out[a : a + len(pick)] = np.clip(base[pick] + noise, *clip)
    return out
