"""Exact kNN-DTW (k = 5, Sakoe-Chiba radius 6, 64 frames x 8 channels) on hard data as well as
easy, against tslearn, aeon and dtaidistance in the same run.

Run: ``python -m benchmarks.dtw [--sizes 1600,10000] [--queries 10] [--large] [--million]``
(``--large`` adds 10^5 cases; ``--million`` 10^6 random-walk and real sequences from
memory-mapped case matrices, ~6 GB of disk and page cache, several minutes).

Data kinds (float64 in memory, float32 when memory-mapped; queries never copies of cases):

- ``noise``: i.i.d. N(0, 1) frames (unstructured: no lower bound is tight);
- ``random-walk``: cumulative sums of N(0, 1) steps along the frames;
- ``clustered``: 20 random-walk prototypes + N(0, 0.5^2) per frame;
- ``real``: the eight limb angles (elbows, knees, armpits, hips; radians) of UI-PRMD Kinect
  clips resampled to 64 frames, the series ``posecbr compare``'s DTW peer sees: subjects
  s01-s06 as cases (resampled with replacement + jitter sd 0.05 rad to the size), the clips
  of s07-s08 as queries.

Methods: posecbr ``DTW.nearest`` on one thread (``jobs=1``) and on two (``jobs=2``: the
fallback scan and the brute force use both cores), tslearn ``KNeighborsTimeSeriesClassifier``
``kneighbors``, aeon ``KNeighborsTimeSeriesClassifier`` ``kneighbors`` (window = radius /
frames), dtaidistance ``dtw_ndim.distance_matrix_fast`` one query against all cases (C,
``parallel=False``) then the k smallest. The peers run one thread. Timings side by side in
rotated rounds; every method's neighbours are checked against posecbr's brute force.
Writes ``benchmarks/results/dtw.json`` with the load average.
"""

from __future__ import annotations

from benchmarks import _common as C  # first: pins the thread pools before numpy loads

# isort: split
import argparse  # noqa: E402
import gc  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import json_out, write_json  # noqa: E402
from cbr.similarity import DTW  # noqa: E402
from cbr.similarity.base import smallest_k  # noqa: E402
from cbr.similarity.dtw import envelope  # noqa: E402

K = 5
RADIUS = 6
FRAMES, CHANNELS = 64, 8
RESULTS = C.RESULTS / "dtw.json"
PEER_MAX = {"tslearn": 1600, "aeon": 1600, "dtaidistance": 10000}  # slow peers: small sizes


def real_series() -> tuple[np.ndarray, np.ndarray]:
    """Eight limb angles ``(clips, 64, 8)`` of s01-s06 (cases) and s07-s08 (queries)."""
    from cbr.evaluation.peers import angle_series

    clips = C.uiprmd_clips()
    ang = np.stack([angle_series(c.seq, FRAMES) for c in clips])
    case, query = C.subject_split(clips)
    return ang[case], ang[query]


def synthetic(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` sequences ``(n, 64, 8)`` float32 of ``kind``, built in chunks."""
    out = np.empty((n, FRAMES, CHANNELS), dtype=np.float32)
    protos = np.cumsum(rng.normal(size=(20, FRAMES, CHANNELS)), axis=1)
    for a in range(0, n, 20000):
        m = min(20000, n - a)
        steps = rng.normal(size=(m, FRAMES, CHANNELS))
        if kind == "noise":
            out[a : a + m] = steps
        elif kind == "random-walk":
            out[a : a + m] = np.cumsum(steps, axis=1)
        else:
            out[a : a + m] = protos[rng.integers(0, 20, m)] + 0.5 * steps
    return out


def mapped_index(m: DTW, cases: np.ndarray, folder: Path) -> Any:
    """The DTW index over memory-mapped case matrices: sequences, upper and lower envelopes."""
    from casebase_store.case_matrix import open_case_matrix, write_case_matrix

    def chunks(which: int) -> Any:
        for a in range(0, len(cases), 50000):
            part = np.asarray(cases[a : a + 50000])
            yield part if which == 0 else envelope(part, RADIUS)[which - 1]

    arrays = []
    for which, name in enumerate(("cases", "upper", "lower")):
        path = folder / f"dtw-{name}.npy"
        write_case_matrix(path, chunks(which), cases.shape)
        arrays.append(open_case_matrix(path, cases.shape))
    return m.index_from(*arrays)


def peers(cases: np.ndarray, queries: np.ndarray) -> dict[str, Callable[[int], Any]]:
    """The peers installed on this machine, each answering query j with k case indices."""
    out: dict[str, Callable[[int], Any]] = {}
    n = len(cases)
    x64 = np.ascontiguousarray(cases, dtype=np.float64)
    q64 = np.ascontiguousarray(queries, dtype=np.float64)
    labels = np.arange(n) % 2
    if n <= PEER_MAX["tslearn"]:
        from tslearn.neighbors import KNeighborsTimeSeriesClassifier as TsKnn

        ts = TsKnn(
            n_neighbors=K,
            metric="dtw",
            metric_params={"global_constraint": "sakoe_chiba", "sakoe_chiba_radius": RADIUS},
        ).fit(x64, labels)
        out["tslearn"] = lambda j: ts.kneighbors(q64[j : j + 1], return_distance=False)[0]
    if n <= PEER_MAX["aeon"]:
        try:
            from aeon.classification.distance_based import KNeighborsTimeSeriesClassifier
        except ImportError:
            pass
        else:
            ae = KNeighborsTimeSeriesClassifier(
                n_neighbors=K, distance="dtw", distance_params={"window": RADIUS / FRAMES}
            ).fit(x64.transpose(0, 2, 1), labels)
            qt = q64.transpose(0, 2, 1)
            out["aeon"] = lambda j: ae.kneighbors(qt[j : j + 1], return_distance=False)[0]
    if n <= PEER_MAX["dtaidistance"]:
        try:
            from dtaidistance import dtw_ndim
        except ImportError:
            pass
        else:

            def dtai(j: int) -> np.ndarray:
                series = np.concatenate([q64[j : j + 1], x64])
                d = dtw_ndim.distance_matrix_fast(
                    series,
                    window=RADIUS + 1,  # dtaidistance's window allows |i - j| < window
                    block=((0, 1), (1, n + 1)),
                    compact=True,
                    parallel=False,
                )
                return smallest_k(np.asarray(d), K)[0]

            out["dtaidistance"] = dtai
    return out


def run_one(kind: str, index_cases: Any, cases: np.ndarray, queries: np.ndarray,
            storage: str, rounds: int) -> dict[str, Any]:  # fmt: skip
    n = len(cases)
    load_before = C.load()
    reps = {}
    ours: dict[str, Callable[[int], Any]] = {}
    for jobs in (1, 2):
        m = DTW(radius=RADIUS, jobs=jobs)
        reps[jobs] = [m.represent_query(q) for q in queries]
        ours[f"posecbr_{jobs}thread"] = (
            lambda j, m=m, jobs=jobs: m.nearest(reps[jobs][j], index_cases, K)[0]
        )  # fmt: skip
    methods = {**ours, **(peers(cases, queries) if storage == "memory" else {})}
    ms, answers = C.side_by_side(methods, len(queries), rounds)
    brute = DTW(radius=RADIUS, jobs=2)
    want = [smallest_k(brute.distances(r, index_cases), K)[0] for r in reps[2]]
    identical = C.identical_neighbours(answers, want)
    return {
        "kind": kind,
        "cases": n,
        "frames": FRAMES,
        "channels": CHANNELS,
        "radius": RADIUS,
        "storage": storage,
        "queries": len(queries),
        "ms_per_query": {k: round(v, 3) for k, v in ms.items()},
        "queries_with_identical_neighbours": identical,
        "load_avg": [load_before, C.load()],
    }


def print_row(r: dict[str, Any]) -> None:
    ms = r["ms_per_query"]

    def f(name: str) -> str:
        return f"{ms[name]:>9.2f}" if name in ms else f"{'-':>9}"

    print(
        f"{r['kind']:<12} {r['cases']:>8} {r['storage']:<7} {f('posecbr_1thread')} "
        f"{f('posecbr_2thread')} {f('dtaidistance')} {f('tslearn')} {f('aeon')} "
        f"{r['load_avg'][0]:>5.2f}",
        flush=True,
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1600,10000")
    ap.add_argument("--queries", type=int, default=10)
    ap.add_argument("--kinds", default="noise,random-walk,clustered,real")
    ap.add_argument("--large", action="store_true", help="add 10^5 cases")
    ap.add_argument("--million", action="store_true", help="add 10^6 cases, memory-mapped")
    ap.add_argument("--out", type=json_out, default=RESULTS)
    args = ap.parse_args(argv)
    threads = C.pin_one_thread()
    kinds = [k for k in args.kinds.split(",") if k]
    sizes = [int(s) for s in args.sizes.split(",") if s] + ([100000] if args.large else [])
    plan = [(k, n, "memory") for n in sizes for k in kinds]
    if args.million:
        plan += [(k, 10**6, "memmap") for k in kinds if k in ("random-walk", "real")]
    rng = np.random.default_rng(0)
    real = real_series() if "real" in kinds else None
    print(
        f"{'data':<12} {'cases':>8} {'storage':<7} {'posecbr-1':>9} {'posecbr-2':>9} "
        f"{'dtaidist':>9} {'tslearn':>9} {'aeon':>9} {'load':>5}   (ms per query, k={K})"
    )
    rows = []
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="posecbr-bench-") as tmp:
        for kind, n, storage in plan:
            if kind == "real":
                assert real is not None
                cases = C.grow(real[0], n, rng, 0.05, (-np.inf, np.inf))
                queries = real[1][np.linspace(0, len(real[1]) - 1, args.queries).astype(int)]
            else:
                cases = synthetic(kind, n, rng)
                queries = synthetic(kind, args.queries, rng).astype(np.float64)
            m = DTW(radius=RADIUS)
            if storage == "memmap":
                index = mapped_index(m, cases, Path(tmp))
                cases = index.cases
            else:
                cases = cases.astype(np.float64)  # as a case base holds them
                index = m.index_for(cases)
            rounds = 3 if n <= 10000 else 1
            r = run_one(kind, index, cases, np.asarray(queries, np.float64), storage, rounds)
            rows.append(r)
            print_row(r)
            del cases, index
            gc.collect()
    doc = {
        "benchmark": "dtw",
        "command": "python -m benchmarks.dtw " + " ".join(argv or sys.argv[1:]),
        "what": "exact k-nearest DTW, ms per query (median over queries and rounds)",
        "k": K,
        "radius": RADIUS,
        "threads": threads,
        "versions": C.versions("numpy", "numba", "tslearn", "aeon", "dtaidistance"),
        "data": {
            "noise": "i.i.d. N(0, 1) frames",
            "random-walk": "cumulative sums of N(0, 1) steps",
            "clustered": "20 random-walk prototypes + N(0, 0.5^2)",
            "real": "UI-PRMD eight limb angles, 64 frames: s01-s06 resampled + jitter 0.05 "
            "rad as cases, s07-s08 clips as queries",
        },
        "results": rows,
        "seconds": round(time.perf_counter() - started, 1),
        "goals": {
            ">= 1.2x faster than dtaidistance on noise": "one thread each",
            ">= 20x faster than tslearn on random walks and real": "one thread each",
            "10^6 sequences per query": "< 500 ms on 2 cores",
        },
    }
    write_json(doc, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
