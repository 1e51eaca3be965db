"""The quantized pass on unstructured rows: 4-bit codes against 8-bit codes and FAISS, one run.

Run: ``python -m benchmarks.quantized [--sizes 10000,100000,1000000] [--dims 200]
[--queries 20]``

Uniform ``[0, 1]^D`` rows (no bound but the quantized pass prunes them): per size the same
rows are indexed twice, with the 4-bit whole-row codes the index chooses on such rows
(:mod:`cbr.similarity.nibbles`) and with the 8-bit codes it used before (built by setting
``cbr.similarity.euclidean.MAX_DIMS`` to 0), and each quantized pass is timed side by side
with FAISS ``IndexFlatL2`` on one thread (``benchmarks._common.side_by_side``: rounds over
all queries, the methods' order rotated). Also the floor each code size sets: a numba sum of
the codes' bytes, widened to 16 bits (the least a pass over them can cost). Every method's
neighbours are checked against FAISS's. Writes ``benchmarks/results/quantized.json`` with the
build times, the codes' memory and the load average.
"""

from __future__ import annotations

from benchmarks import _common as C  # first: pins the thread pools before numpy loads

# isort: split
import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from typing import Any  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

import cbr.similarity.euclidean as euclidean  # noqa: E402
import cbr.similarity.grid_codes as grid_codes  # noqa: E402
from benchmarks import json_out, write_json  # noqa: E402
from cbr.similarity import Euclidean  # noqa: E402

K = 5
RESULTS = C.RESULTS / "quantized.json"


@numba.njit(cache=True, nogil=True)
def byte_sum(a: np.ndarray) -> int:
    """Sum of the bytes ``a`` ``(n,)`` uint8 in 16-bit lanes (64 wide, widened every 128
    rounds so none overflows): the cheapest pass that reads every byte once."""
    total = 0
    acc = np.zeros(64, dtype=np.uint16)
    for c in range(a.shape[0] // 8192):
        acc[:] = 0
        for i in range(128):
            for t in range(64):
                acc[t] += np.uint16(a[c * 8192 + i * 64 + t])
        for t in range(64):
            total += int(acc[t])
    return total


def build(m: Euclidean, x: np.ndarray, eight_bit: bool) -> tuple[Any, float]:
    """The index of ``x`` with 4-bit (or 8-bit) whole-row codes and its build time (s)."""
    keep = euclidean.MAX_DIMS
    euclidean.MAX_DIMS = 0 if eight_bit else keep
    try:
        t0 = time.perf_counter()
        index = m.build_index(x)
        return index, time.perf_counter() - t0
    finally:
        euclidean.MAX_DIMS = keep


def run_one(n: int, dims: int, n_queries: int, rng: np.random.Generator) -> dict[str, Any]:
    import faiss

    x = np.empty((n, dims), dtype=np.float32)
    for a in range(0, n, 20000):
        x[a : a + 20000] = rng.random((min(20000, n - a), dims))
    queries = rng.random((n_queries, dims))
    load_before = C.load()
    m = Euclidean()
    four, build4 = build(m, x, eight_bit=False)
    eight, build8 = build(m, x, eight_bit=True)
    assert isinstance(four.codes, euclidean._Nibbles)
    assert isinstance(eight.codes, grid_codes.PcaCodes)
    peer = faiss.IndexFlatL2(dims)
    peer.add(x)
    reps = [m.represent_query(q) for q in queries]
    q32 = queries.astype(np.float32)

    def quantized(index: Any, j: int) -> np.ndarray:
        v, v_sq = m._query(reps[j])
        return euclidean._quantized_search(index, v, v_sq, K)[0]

    methods = {
        "posecbr_4bit": lambda j: quantized(four, j),
        "posecbr_8bit": lambda j: quantized(eight, j),
        "faiss_flat": lambda j: peer.search(q32[j : j + 1], K)[1][0],
    }
    ms, answers = C.side_by_side(methods, n_queries, rounds=3)
    codes4 = four.codes.codes.codes
    codes8 = eight.codes.codes.reshape(-1)
    ms["byte_sum_4bit_codes"] = C.median_ms(lambda: byte_sum(codes4), 5)
    ms["byte_sum_8bit_codes"] = C.median_ms(lambda: byte_sum(codes8), 5)
    want = answers["faiss_flat"]
    return {
        "cases": n,
        "dims": dims,
        "queries": n_queries,
        "build_s": {"4-bit": round(build4, 2), "8-bit": round(build8, 2)},
        "codes_mb": {
            "4-bit": round(four.codes.codes.nbytes / 1e6, 1),
            "8-bit": round((eight.codes.codes.nbytes + eight.codes.errs.nbytes) / 1e6, 1),
        },
        "surviving_share": {
            "4-bit": round(float(four.codes.pruning[0]), 6),
            "8-bit": round(float(eight.codes.pruning[0]), 6),
        },
        "ms_per_query": {k: round(v, 3) for k, v in ms.items()},
        "queries_with_identical_neighbours": C.identical_neighbours(answers, want),
        "load_avg": [load_before, C.load()],
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="10000,100000,1000000", help="case-base sizes")
    ap.add_argument("--dims", type=int, default=200)
    ap.add_argument("--queries", type=int, default=20)
    ap.add_argument("--out", type=json_out, default=RESULTS)
    args = ap.parse_args(argv)
    C.require_peer("faiss", "faiss-cpu", "quantized")
    threads = C.pin_one_thread()
    rng = np.random.default_rng(0)
    print(
        f"{'cases':>8} {'dims':>5} {'4-bit':>7} {'8-bit':>7} {'faiss':>7} {'sum 4b':>7} "
        f"{'sum 8b':>7} {'vs faiss':>8} {'surv 4b':>8} {'MB 4b/8b':>11} {'build s':>11} "
        f"{'load':>5}   (ms per query, k={K}, one thread)"
    )
    rows = []
    for n in [int(s) for s in args.sizes.split(",") if s]:
        r = run_one(n, args.dims, args.queries, rng)
        rows.append(r)
        ms, mb, bs = r["ms_per_query"], r["codes_mb"], r["build_s"]
        print(
            f"{n:>8} {args.dims:>5} {ms['posecbr_4bit']:>7.2f} {ms['posecbr_8bit']:>7.2f} "
            f"{ms['faiss_flat']:>7.2f} {ms['byte_sum_4bit_codes']:>7.2f} "
            f"{ms['byte_sum_8bit_codes']:>7.2f} {ms['faiss_flat'] / ms['posecbr_4bit']:>7.1f}x "
            f"{r['surviving_share']['4-bit']:>8.5f} {mb['4-bit']:>5.1f}/{mb['8-bit']:<5.1f} "
            f"{bs['4-bit']:>5.1f}/{bs['8-bit']:<5.1f} {r['load_avg'][0]:>5.2f}",
            flush=True,
        )
    doc = {
        "benchmark": "quantized",
        "command": "python -m benchmarks.quantized " + " ".join(argv or sys.argv[1:]),
        "what": "the quantized pass on uniform rows, 4-bit vs 8-bit codes vs FAISS IndexFlatL2, "
        "ms per query (median over queries x rounds); byte_sum_*: a pass over the codes' "
        "bytes alone",
        "k": K,
        "threads": threads,
        "machine": C.one_thread_machine(),
        "versions": C.versions("numpy", "numba", "faiss-cpu"),
        "results": rows,
    }
    write_json(doc, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
