"""``python -m benchmarks``: run every benchmark of the project and index the results.

Every ``benchmarks/<name>.py`` (names not starting with ``_``) is a benchmark with a ``main()``
that prints its table and writes ``benchmarks/results/<name>.json``. Each runs in its own
process (``python -m benchmarks.<name>``) so one that fails or exhausts memory does not stop the
others. Afterwards ``benchmarks/results/index.json`` lists what ran, how long it took, whether it
succeeded and where its results are, with the machine and library versions (which every
result file records too: :func:`benchmarks.write_json` adds them where a benchmark does not).

    python -m benchmarks              # all
    python -m benchmarks compare dtw  # only these
    python -m benchmarks --list
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from benchmarks import write_json

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"


def discover() -> list[str]:
    """Names of the benchmark modules beside this file, sorted."""
    return sorted(p.stem for p in HERE.glob("*.py") if not p.stem.startswith("_"))


def machine() -> dict[str, Any]:
    """Machine and library versions (the same record ``posecbr compare`` writes)."""
    from cbr.evaluation.machine import machine_info

    return machine_info()


def run_one(name: str, timeout_s: float | None) -> dict[str, Any]:
    """Run ``benchmarks.<name>`` in a child process; its output goes to this console."""
    print(f"\n=== benchmark {name} ===", flush=True)
    cmd = [
        sys.executable,
        "-c",
        f"import sys, benchmarks.{name} as b; sys.exit(b.main() or 0)",
    ]
    started = time.perf_counter()
    started_wall = time.time()
    try:
        proc = subprocess.run(cmd, cwd=HERE.parent, timeout=timeout_s, check=False)
        code: int | None = proc.returncode
        status = "ok" if code == 0 else "failed"
    except subprocess.TimeoutExpired:
        code, status = None, "timeout"
    seconds = time.perf_counter() - started
    result = RESULTS / f"{name}.json"
    # Only a file written by this run counts (an old one may be left from an earlier run).
    fresh = result.exists() and result.stat().st_mtime >= started_wall - 1.0
    print(f"=== {name}: {status} in {seconds:.1f} s ===", flush=True)
    return {
        "name": name,
        "status": status,
        "exit_code": code,
        "seconds": round(seconds, 2),
        "results": str(result.relative_to(HERE.parent)) if fresh else None,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks", description=__doc__.split("\n")[0]
    )
    parser.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    parser.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    parser.add_argument(
        "--timeout",
        type=float,
        default=None,
        metavar="S",
        help="stop a benchmark after S seconds (default: no limit)",
    )
    args = parser.parse_args(argv)
    available = discover()
    if args.list:
        print("\n".join(available))
        return 0
    unknown = [n for n in args.names if n not in available]
    if unknown:
        print(
            f"python -m benchmarks: error: no benchmark {', '.join(unknown)} "
            f"(available: {', '.join(available) or 'none'})",
            file=sys.stderr,
        )
        return 2
    names = args.names or available
    info = machine()
    ran = [run_one(n, args.timeout) for n in names]
    index_path = RESULTS / "index.json"
    previous: dict[str, Any] = {}
    if index_path.exists():  # keep entries of benchmarks not run this time
        try:
            previous = {b["name"]: b for b in json.loads(index_path.read_text())["benchmarks"]}
        except (OSError, json.JSONDecodeError, KeyError, TypeError):
            previous = {}
    previous.update(
        {r["name"]: {**r, "run_utc": datetime.now(UTC).isoformat(timespec="seconds")} for r in ran}
    )
    write_json({"machine": info, "benchmarks": [previous[k] for k in sorted(previous)]}, index_path)
    print("\nbenchmark          status      seconds  results")
    for r in ran:
        print(f"{r['name']:<18} {r['status']:<10} {r['seconds']:8.1f}  {r['results'] or '-'}")
    print(f"index: {index_path.relative_to(HERE.parent)}")
    return 0 if all(r["status"] == "ok" for r in ran) else 1


if __name__ == "__main__":
    sys.exit(main())
