"""Exact Euclidean k = 5 retrieval on hard data as well as easy, against the peers, one thread.

Run: ``python -m benchmarks.retrieval [--sizes 10000,100000] [--queries 20] [--million]``
(``--million`` adds 10^6 x 200 cases of every kind, read from a memory-mapped case matrix
file; about 5 GB of memory and disk, several minutes).

Data kinds (float32 case matrices; queries are new points, never copies of cases):

- ``unstructured``: uniform in [0, 1]^D (no low-rank structure: no bound prunes);
- ``random-walk``: each row a walk of D Gaussian steps (smooth, strongly correlated dims);
- ``clustered``: 100 centres uniform in [0, 1]^D, cases and queries centre + N(0, 0.1^2);
- ``real``: UI-PRMD Kinect clips of subjects s01-s06 (1200 repetitions) as case-base
  features, resampled with replacement and jittered (sd 0.05, clipped to [0, 1]) to the size;
  the queries are the clips of s07-s08, people the case base has never seen. At 200 dims:
  each fluent state's mean and standard deviation over the clip (212 values, the shape of
  the case base's clip summaries); at 3400 dims: the resampled fluent sequence (32 frames x
  106 states = 3392 values, what DTW and signatures compare).

Methods, one thread each (threadpoolctl, FAISS ``omp_set_num_threads(1)``), in rounds over
all queries with the methods' order rotated (``benchmarks._common.side_by_side``): posecbr
``Euclidean.nearest`` (the PCA bound, the quantized pass where it prunes nothing, the plain
pass where neither prunes; ``surv`` / ``q-surv``: the running share of cases that passed
each bound and got their float distance, 1.0 when a bound stopped being tried, nan: never
ran), posecbr plain (the same measure without the bound), scikit-learn
``NearestNeighbors(algorithm="brute")``, FAISS ``IndexFlatL2``; and for the whole query
batch at once posecbr ``nearest_many`` and FAISS ``search`` on all queries. Every method's
neighbours are checked against posecbr plain. Writes ``benchmarks/results/retrieval.json``
with the load average.
"""

from __future__ import annotations

from benchmarks import _common as C  # first: pins the thread pools before numpy loads

# isort: split
import argparse  # noqa: E402
import gc  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import json_out, write_json  # noqa: E402
from cbr.similarity import Euclidean  # noqa: E402

K = 5
RESULTS = C.RESULTS / "retrieval.json"


def real_features() -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """dims -> (case-base features of s01-s06 ``(m, dims)``, query features of s07-s08)."""
    from cbr.problem import FeatureConfig, extract_problem, resolve_config

    clips = C.uiprmd_clips()
    seqs = [c.seq for c in clips]
    config = resolve_config(FeatureConfig(), seqs)
    flu = np.stack([extract_problem(s, config).values for s in seqs])  # (n, 32, 106)
    summary = np.concatenate([flu.mean(axis=1), flu.std(axis=1)], axis=1)  # (n, 212)
    case, query = C.subject_split(clips)
    seqflat = flu.reshape(len(flu), -1)
    return {200: (summary[case], summary[query]), 3400: (seqflat[case], seqflat[query])}


def synthetic(
    kind: str, n: int, dims: int, n_queries: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """A float32 case matrix ``(n, dims)`` of ``kind`` and float64 queries, built in chunks."""
    x = np.empty((n, dims), dtype=np.float32)
    centres = rng.random((100, dims))

    def rows(m: int) -> np.ndarray:
        if kind == "unstructured":
            return rng.random((m, dims))
        if kind == "random-walk":
            return np.cumsum(rng.normal(size=(m, dims)), axis=1)
        return centres[rng.integers(0, 100, m)] + rng.normal(scale=0.1, size=(m, dims))

    for a in range(0, n, 20000):
        x[a : a + 20000] = rows(min(20000, n - a))
    return x, rows(n_queries)


def fill_memmap(x: np.ndarray, folder: Path) -> np.ndarray:
    """``x`` written as a case matrix file and opened memory-mapped (the storage of item 4)."""
    from casebase_store.case_matrix import open_case_matrix, write_case_matrix

    path = folder / "cases.npy"
    write_case_matrix(path, (x[a : a + 65536] for a in range(0, len(x), 65536)), x.shape)
    return open_case_matrix(path, x.shape)


def run_one(kind: str, cases: np.ndarray, queries: np.ndarray, storage: str) -> dict[str, Any]:
    """Every method on one case matrix: ms per query, neighbours checked."""
    import faiss
    from sklearn.neighbors import NearestNeighbors

    n, dims = cases.shape
    load_before = C.load()
    m = Euclidean()
    t0 = time.perf_counter()
    pruned = m.build_index(cases)
    build_s = time.perf_counter() - t0
    plain = Euclidean(prune_min_cases=10**12).build_index(cases)
    peer_sk = NearestNeighbors(n_neighbors=K, algorithm="brute").fit(cases)
    peer_fa = faiss.IndexFlatL2(dims)
    peer_fa.add(np.ascontiguousarray(cases))
    q32 = queries.astype(np.float32)
    reps = [m.represent_query(q) for q in queries]
    methods = {
        "posecbr": lambda j: m.nearest(reps[j], pruned, K)[0],
        "posecbr_plain": lambda j: m.nearest(reps[j], plain, K)[0],
        "sklearn_brute": lambda j: peer_sk.kneighbors(q32[j : j + 1], return_distance=False)[0],
        "faiss_flat": lambda j: peer_fa.search(q32[j : j + 1], K)[1][0],
    }
    ms, answers = C.side_by_side(methods, len(queries), rounds=3)
    batch_reps = np.stack(reps)
    ms["posecbr_batch"] = C.median_ms(lambda: m.nearest_many(batch_reps, pruned, K), 3) / len(
        queries
    )
    ms["faiss_flat_batch"] = C.median_ms(lambda: peer_fa.search(q32, K), 3) / len(queries)
    want = answers["posecbr_plain"]
    batch_i = m.nearest_many(batch_reps, pruned, K)[0]
    identical = C.identical_neighbours({**answers, "posecbr_batch": batch_i}, want)
    row = {
        "kind": kind,
        "cases": n,
        "dims": dims,
        "storage": storage,
        "queries": len(queries),
        "build_s": round(build_s, 3),
        "bound_rank": None if pruned.basis is None else int(pruned.basis.shape[1]),
        "codes_mb": codes_mb(pruned),
        "surviving_share": round(float(pruned.pruning[0]), 4),
        "quantized_surviving_share": (  # None: the quantized pass never ran (PCA pruned)
            None
            if pruned.codes is None or pruned.codes.pruning[1] == 0
            else round(float(pruned.codes.pruning[0]), 6)
        ),
        "ms_per_query": {k: round(v, 3) for k, v in ms.items()},
        "queries_with_identical_neighbours": identical,
        "load_avg": [load_before, C.load()],
    }
    return row


def codes_mb(index: Any) -> dict[str, Any]:
    """The memory (MB) of the index's codes beside the case matrix: the PCA codes and the
    whole rows' codes (``4-bit`` or ``8-bit``; None: no such codes)."""
    whole = index.codes
    kind = None if whole is None else "4-bit" if hasattr(whole.codes, "errs") else "8-bit"
    nbytes = None
    if whole is not None:
        nbytes = whole.codes.nbytes if kind == "4-bit" else whole.codes.nbytes + whole.errs.nbytes
    return {
        "pca": None if index.pca is None else round(index.pca.codes.nbytes / 1e6, 1),
        "whole_rows": None if nbytes is None else round(nbytes / 1e6, 1),
        "whole_rows_codes": kind,
    }


def print_row(r: dict[str, Any]) -> None:
    ms = r["ms_per_query"]
    qs = r["quantized_surviving_share"]
    print(
        f"{r['kind']:<13} {r['cases']:>8} {r['dims']:>5} {r['storage']:<7} "
        f"{ms['posecbr']:>8.2f} {ms['posecbr_plain']:>8.2f} {ms['sklearn_brute']:>8.2f} "
        f"{ms['faiss_flat']:>8.2f} {ms['posecbr_batch']:>8.2f} {ms['faiss_flat_batch']:>8.2f} "
        f"{ms['faiss_flat'] / ms['posecbr']:>6.1f}x  {r['surviving_share']:>5.3f} "
        f"{qs if qs is not None else float('nan'):>7.5f} {r['load_avg'][0]:>5.2f}",
        flush=True,
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="10000,100000", help="case-base sizes")
    ap.add_argument("--queries", type=int, default=20)
    ap.add_argument("--kinds", default="unstructured,random-walk,clustered,real")
    ap.add_argument("--wide", default="unstructured,clustered,real", help="kinds at 3400 dims")
    ap.add_argument("--million", action="store_true", help="add 10^6 x 200, memory-mapped")
    ap.add_argument("--out", type=json_out, default=RESULTS)
    args = ap.parse_args(argv)
    C.require_peer("faiss", "faiss-cpu", "retrieval")
    threads = C.pin_one_thread()
    sizes = [int(s) for s in args.sizes.split(",") if s]
    kinds = [k for k in args.kinds.split(",") if k]
    wide = [k for k in args.wide.split(",") if k]
    rng = np.random.default_rng(0)
    real = real_features() if "real" in kinds + wide else {}
    plan = [(k, n, 200, "memory") for n in sizes for k in kinds]
    plan += [(k, n, 3400, "memory") for n in sizes for k in wide]
    if args.million:
        plan += [(k, 10**6, 200, "memmap") for k in kinds]
    print(
        f"{'data':<13} {'cases':>8} {'dims':>5} {'storage':<7} {'posecbr':>8} {'plain':>8} "
        f"{'sklearn':>8} {'faiss':>8} {'batch':>8} {'faiss-b':>8} {'vs faiss':>7} "
        f"{'surv':>5} {'q-surv':>7} {'load':>5}   (ms per query, k={K}, one thread)"
    )
    rows = []
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="posecbr-bench-") as tmp:
        for kind, n, dims, storage in plan:
            if kind == "real":
                base, q = real[dims]
                cases = C.grow(base, n, rng, 0.05, (0.0, 1.0))
                queries = q[np.linspace(0, len(q) - 1, args.queries).astype(int)]
            else:
                cases, queries = synthetic(kind, n, dims, args.queries, rng)
            if storage == "memmap":
                mapped = fill_memmap(cases, Path(tmp))
                del cases
                gc.collect()
                cases = mapped
            r = run_one(kind, cases, np.asarray(queries, dtype=np.float64), storage)
            r["dims"] = int(cases.shape[1])
            rows.append(r)
            print_row(r)
            del cases
            gc.collect()
    doc = {
        "benchmark": "retrieval",
        "command": "python -m benchmarks.retrieval " + " ".join(argv or sys.argv[1:]),
        "what": "exact Euclidean k-nearest search, ms per query (median over queries)",
        "k": K,
        "threads": threads,
        "versions": C.versions("numpy", "numba", "scikit-learn", "faiss-cpu", "threadpoolctl"),
        "data": {
            "unstructured": "uniform [0, 1]^D",
            "random-walk": "cumulative sums of D standard normal steps",
            "clustered": "100 uniform centres + N(0, 0.1^2)",
            "real": "UI-PRMD s01-s06 clip features resampled + jitter 0.05; queries s07-s08 "
            "(200 dims: per-state mean and sd over the clip, 212 values; 3400 dims: fluent "
            "sequence 32 x 106 = 3392 values)",
        },
        "results": rows,
        "seconds": round(time.perf_counter() - started, 1),
        "goals": {
            "no slower than FAISS IndexFlatL2 single query": "every row",
            ">= 5x faster than FAISS on clustered and real": "clustered, real rows",
            "10^6 x 200 per query": "< 20 ms",
        },
    }
    write_json(doc, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
