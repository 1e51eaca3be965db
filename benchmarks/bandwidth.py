"""Memory read bandwidth of one core, and the floor it sets on a full scan of a case matrix.

Run: ``python -m benchmarks.bandwidth [--rows 1000000] [--dims 200] [--repeats 5]``

A plain pass over ``rows x dims`` float32 values must read them all: at the bandwidth one
thread gets (numpy's float32 sum over the same matrix, which reads each value once and does
one addition per value), no exact search that looks at every row can be faster than
``bytes / bandwidth``. Writes ``benchmarks/results/bandwidth.json`` with the load average.
"""

from __future__ import annotations

from benchmarks import _common as C  # first: pins the thread pools before numpy loads

# isort: split
import argparse  # noqa: E402
import sys  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import json_out, write_json  # noqa: E402

RESULTS = C.RESULTS / "bandwidth.json"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10**6)
    ap.add_argument("--dims", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", type=json_out, default=RESULTS)
    args = ap.parse_args(argv)
    threads = C.pin_one_thread()
    x = np.random.default_rng(0).random((args.rows, args.dims), dtype=np.float32)
    load_before = C.load()
    ms = C.median_ms(lambda: x.sum(dtype=np.float32), args.repeats)
    gb = x.nbytes / 1e9
    rate = gb / (ms / 1000)
    print(
        f"{args.rows} x {args.dims} float32 ({gb:.2f} GB): sum {ms:.1f} ms, {rate:.2f} GB/s on "
        f"one thread; a full scan cannot take less than {ms:.1f} ms at this bandwidth "
        f"(load {load_before})"
    )
    doc = {
        "benchmark": "bandwidth",
        "command": "python -m benchmarks.bandwidth " + " ".join(argv or sys.argv[1:]),
        "what": "one thread's read bandwidth: median ms of numpy's float32 sum over the matrix",
        "threads": threads,
        "rows": args.rows,
        "dims": args.dims,
        "gigabytes": round(gb, 3),
        "ms_sum": round(ms, 2),
        "gb_per_s": round(rate, 2),
        "scan_floor_ms": round(ms, 2),
        "bandwidth_needed_for_20_ms_gb_per_s": round(gb / 0.020, 1),
        "load_avg": [load_before, C.load()],
        "versions": C.versions("numpy"),
    }
    write_json(doc, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
