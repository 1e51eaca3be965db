"""Retrieval latency against case-base size, and kNN-DTW against tslearn.

Run: ``python -m benchmarks.retrieval [--sizes 1000,10000,100000] [--queries 20]``.

Case bases are built from real problems: every UI-PRMD Kinect clip in ``../shared/data``
(1600 repetitions, 10 movements) turned into its fluent problem (default configuration: angle
states, 32 frames) and its QMP vector (binary ADD criteria); a case base of size N samples
those problems with replacement and jitters them (fluents: Gaussian sd 0.05 clipped to [0, 1];
QMP: 5 % of bits flipped), stored as float32. Queries are other jittered real problems.

Measured per measure and size: index build time and the median classification latency
(problem representation + k = 5 retrieval + vote) over the queries. DTW is compared with
tslearn's ``KNeighborsTimeSeriesClassifier`` (same band, k = 5, uniform vote) on the same cases
and queries (float64 on both sides; median over alternating repeats of the whole query set);
predictions must be identical. Writes ``benchmarks/results/retrieval.json``.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import write_json
from cbr.problem import FeatureConfig, extract_problem, resolve_config
from cbr.retrieve import Retrieval
from cbr.reuse import reuse
from cbr.similarity import DTW, Euclidean, Signature, SimilarityMeasure

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results" / "retrieval.json"
K = 5


def load_problems() -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """Fluent problems ``(n, 32, d)``, QMP binary vectors ``(n, q)``, labels ``(n,)``."""
    from features.datasets import load_dataset

    clips = load_dataset(DATA / "ui-prmd", progress_desc="loading UI-PRMD")
    seqs = [c.seq for c in clips]
    config = resolve_config(FeatureConfig(), seqs)
    flu = np.stack([extract_problem(s, config).values for s in seqs]).astype(np.float32)
    qcfg = FeatureConfig(level="qmp")
    qmp = np.stack([extract_problem(s, qcfg).values for s in seqs]).astype(np.float32)
    labels = np.array([c.label for c in clips], dtype=object)
    return flu, qmp, labels, list(config.states)


def synth(
    base: np.ndarray, labels: np.ndarray, n: int, rng: np.random.Generator, binary: bool
) -> tuple[np.ndarray, np.ndarray]:
    pick = rng.integers(0, len(base), n)
    out = np.empty((n, *base.shape[1:]), dtype=np.float32)
    for a in range(0, n, 10000):  # chunks: no float64 copy of the whole case base
        b = base[pick[a : a + 10000]]
        if binary:
            flip = rng.random(b.shape) < 0.05
            out[a : a + 10000] = np.where(flip, 1.0 - b, b)
        else:
            noise = rng.normal(scale=0.05, size=b.shape).astype(np.float32)
            out[a : a + 10000] = np.clip(b + noise, 0.0, 1.0)
    return out, labels[pick]


def represent_chunked(m: SimilarityMeasure, cases: np.ndarray) -> np.ndarray:
    if isinstance(m, Euclidean):
        return cases.reshape(len(cases), -1)
    parts = []
    for a in range(0, len(cases), 5000):
        parts.append(np.asarray(m.represent(cases[a : a + 5000]), dtype=np.float32))
    return np.concatenate(parts)


def time_queries(
    m: SimilarityMeasure, index: Any, queries: np.ndarray, labels: np.ndarray
) -> tuple[float, list[str], list[np.ndarray]]:
    """Median ms per query of represent + retrieve + vote; predictions; neighbour indices."""
    classes = np.unique(labels.astype(str))
    times, preds, nbrs = [], [], []
    for q in queries:
        t0 = time.perf_counter()
        qr = m.represent_query(q.astype(np.float64))
        idx, dist = m.nearest(qr, index, K)
        sol = reuse(Retrieval(idx, dist, labels[idx], idx), classes, "uniform")
        times.append(time.perf_counter() - t0)
        preds.append(sol.label)
        nbrs.append(idx)
    return 1000 * float(np.median(times)), preds, nbrs


def tslearn_compare(
    cases: np.ndarray, labels: np.ndarray, queries: np.ndarray, radius: int, repeats: int
) -> dict[str, Any]:
    from tslearn.neighbors import KNeighborsTimeSeriesClassifier

    peer = KNeighborsTimeSeriesClassifier(
        n_neighbors=K,
        metric="dtw",
        metric_params={"global_constraint": "sakoe_chiba", "sakoe_chiba_radius": radius},
    )
    x64 = cases.astype(np.float64)  # both sides in float64, as CaseBaseClassifier runs
    peer.fit(x64, labels.astype(str))
    peer.predict(queries[:1].astype(np.float64))  # compile outside the timing
    m = DTW(radius=radius)
    index = m.build_index(m.represent(x64))
    time_queries(m, index, queries[:1], labels)  # compile
    peer_times, our_times = [], []
    for _ in range(repeats):  # alternate, so both see the same machine load
        t0 = time.perf_counter()
        want = peer.predict(queries.astype(np.float64))
        peer_times.append((time.perf_counter() - t0) / len(queries))
        t0 = time.perf_counter()
        _, preds, _ = time_queries(m, index, queries, labels)
        our_times.append((time.perf_counter() - t0) / len(queries))
    t_peer, t_ours = float(np.median(peer_times)), float(np.median(our_times))
    same = bool(np.array_equal(np.asarray(preds), want))
    return {
        "cases": len(cases),
        "queries": len(queries),
        "radius": radius,
        "repeats": repeats,
        "tslearn_ms_per_query": 1000 * t_peer,
        "posecbr_ms_per_query": 1000 * t_ours,
        "speedup": t_peer / t_ours,
        "identical_predictions": same,
    }


def versions() -> dict[str, str]:
    import iisignature
    import numba
    import sklearn
    import sqlalchemy
    import tslearn

    return {
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "numba": numba.__version__,
        "tslearn": tslearn.__version__,
        "iisignature": str(iisignature.version()),
        "scikit-learn": sklearn.__version__,
        "sqlalchemy": sqlalchemy.__version__,
    }


def machine() -> dict[str, Any]:
    cpu = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"platform": platform.platform(), "cpu": cpu, "cpus": os.cpu_count()}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--queries", type=int, default=20)
    ap.add_argument("--tslearn-sizes", default="1000,10000")
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    sizes = [int(s) for s in args.sizes.split(",")]
    rng = np.random.default_rng(0)

    t0 = time.perf_counter()
    flu, qmp, labels, states = load_problems()
    print(
        f"problems: {len(flu)} clips, fluents {flu.shape[1:]}, qmp {qmp.shape[1:]} "
        f"({time.perf_counter() - t0:.0f} s)"
    )
    q_flu, _ = synth(flu, labels, args.queries, rng, binary=False)
    q_qmp, _ = synth(qmp, labels, args.queries, rng, binary=True)

    setups: list[tuple[str, str, SimilarityMeasure, np.ndarray, np.ndarray, bool]] = [
        ("euclidean", "qmp", Euclidean(), qmp, q_qmp, True),
        ("euclidean", "fluents", Euclidean(), flu, q_flu, False),
        ("signature", "fluents", Signature(), flu, q_flu, False),
        ("dtw", "fluents", DTW(), flu, q_flu, False),
    ]
    rows: list[dict[str, Any]] = []
    print(
        f"{'measure':<10} {'features':<8} {'cases':>7} {'dims':>7} {'build s':>8} {'ms/query':>9}"
    )
    for name, level, m, base, queries, binary in setups:
        for n in sizes:
            cases, lab = synth(base, labels, n, rng, binary)
            t1 = time.perf_counter()
            if isinstance(m, DTW):  # envelopes straight into the index, no stacked copy
                index = m.index_for(cases)
                reps = cases
            else:
                reps = represent_chunked(m, cases)
                index = m.build_index(reps)
            build = time.perf_counter() - t1
            time_queries(m, index, queries[:1], lab)  # warm up (numba compile)
            ms, _, _ = time_queries(m, index, queries, lab)
            dims = int(np.prod(reps.shape[1:])) * (3 if isinstance(m, DTW) else 1)
            rows.append(
                {
                    "measure": name,
                    "features": level,
                    "cases": n,
                    "dims": dims,
                    "build_s": build,
                    "ms_per_query": ms,
                }
            )
            print(f"{name:<10} {level:<8} {n:>7} {dims:>7} {build:>8.1f} {ms:>9.2f}")
            del cases, reps, index
            gc.collect()

    peers = []
    radius = DTW().radius_for(flu.shape[1])
    for n in [int(s) for s in args.tslearn_sizes.split(",") if s]:
        cases, lab = synth(flu, labels, n, rng, binary=False)
        nq = args.queries if n <= 1000 else max(3, args.queries // 4)
        res = tslearn_compare(cases, lab, q_flu[:nq], radius, repeats=3 if n <= 1000 else 1)
        peers.append(res)
        print(
            f"kNN-DTW vs tslearn at {n} cases ({nq} queries): tslearn "
            f"{res['tslearn_ms_per_query']:.1f} ms, posecbr {res['posecbr_ms_per_query']:.1f} "
            f"ms -> {res['speedup']:.1f}x, identical predictions: "
            f"{res['identical_predictions']}"
        )
    doc = {
        "benchmark": "retrieval",
        "command": "python -m benchmarks.retrieval " + " ".join(argv or sys.argv[1:]),
        "machine": machine(),
        "versions": versions(),
        "k": K,
        "fluent_states": len(states),
        "latency": rows,
        "dtw_vs_tslearn": peers,
        "goals": {"dtw_speedup_vs_tslearn": ">= 10", "vector_ms_per_query_at_100k": "< 20"},
    }
    write_json(doc, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
