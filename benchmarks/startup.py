"""Start-up time of the ``posecbr`` command, against ``python -c pass`` in the same run.

Run: ``python -m benchmarks.startup [--repeats N] [--file POSEFILE]``. Writes
``benchmarks/results/startup.json``.

Measured, each in a new process as a user starts it (the console script beside this
interpreter, or ``python -m posecbr`` without one), wall-clock and CPU time (user + system of
the child):
- ``python -c pass``: the interpreter alone, the floor every command pays;
- ``posecbr --version`` and ``posecbr --help``: the parser with every command registered
  (goal: under 0.3 s wall);
- ``posecbr describe FILE`` on one pose file (default: the bundled deep squat), after one
  unmeasured run so numba's cache holds the compiled kernels (goal: under 1.5 s wall);
- three refusals of a user's mistake, each named before the command's work and its heavy
  imports (exit status 1, as the table expects): ``posecbr train MISSING --db NEW`` (a data
  file that is not there), ``posecbr classify FILE --db MISSING`` and ``posecbr segment FILE
  --db MISSING`` (a case base file that is not there), in a temporary folder.

The runs are interleaved (each round runs every command once, in turn) so that other work on
a shared machine slows them alike; the table gives the median and the fastest run of each, and
the median's excess over ``python -c pass``. The load average before and after says how busy
the machine was.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from benchmarks import write_json

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "startup.json"
CLIP = ROOT / "posecbr" / "demo_data" / "uiprmd" / "m01_s01_e01.npz"
GOALS_S = {"posecbr --version": 0.3, "posecbr --help": 0.3, "posecbr describe FILE": 1.5}


def posecbr_command() -> list[str]:
    """How a user starts posecbr with this interpreter: its console script, else ``-m``."""
    script = Path(sys.executable).parent / "posecbr"
    return [str(script)] if script.is_file() else [sys.executable, "-m", "posecbr"]


#: the commands measured that refuse (exit status 1): a mistake named before the work
REFUSALS = (
    "posecbr train MISSING --db NEW",
    "posecbr classify FILE --db MISSING",
    "posecbr segment FILE --db MISSING",
)


def commands(clip: Path, folder: Path) -> dict[str, list[str]]:
    """The command lines measured; ``folder``: an empty folder for the refusals' files that
    are not there."""
    posecbr = posecbr_command()
    missing, new = str(folder / "missing.sqlite"), str(folder / "new.sqlite")
    return {
        "python -c pass": [sys.executable, "-c", "pass"],
        "posecbr --version": [*posecbr, "--version"],
        "posecbr --help": [*posecbr, "--help"],
        "posecbr describe FILE": [*posecbr, "describe", str(clip)],
        REFUSALS[0]: [*posecbr, "train", str(folder / "missing.npz"), "--db", new],
        REFUSALS[1]: [*posecbr, "classify", str(clip), "--db", missing],
        REFUSALS[2]: [*posecbr, "segment", str(clip), "--db", missing],
    }


def timed_run(cmd: list[str], status: int = 0) -> tuple[float, float]:
    """Wall seconds and CPU seconds (user + system) of one run of ``cmd``, which is to exit
    with ``status``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=False)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != status:
        said = proc.stderr.decode(errors="replace").strip()[-500:]
        raise SystemExit(f"{' '.join(cmd)} exited {proc.returncode}, not {status}: {said}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def measure(cmds: dict[str, list[str]], repeats: int) -> dict[str, dict[str, list[float]]]:
    """``repeats`` interleaved rounds; per command its wall and CPU times."""
    for name, cmd in cmds.items():  # warm-up: numba's cache, the OS file cache
        timed_run(cmd, int(name in REFUSALS))
    times: dict[str, dict[str, list[float]]] = {n: {"wall": [], "cpu": []} for n in cmds}
    for _ in range(repeats):
        for name, cmd in cmds.items():
            wall, cpu = timed_run(cmd, int(name in REFUSALS))
            times[name]["wall"].append(wall)
            times[name]["cpu"].append(cpu)
    return times


def summarise(times: dict[str, dict[str, list[float]]]) -> dict[str, dict[str, Any]]:
    floor = statistics.median(times["python -c pass"]["wall"])
    out: dict[str, dict[str, Any]] = {}
    for name, t in times.items():
        median = statistics.median(t["wall"])
        goal = GOALS_S.get(name)
        out[name] = {
            "wall_median_s": round(median, 4),
            "wall_min_s": round(min(t["wall"]), 4),
            "cpu_median_s": round(statistics.median(t["cpu"]), 4),
            "over_python_s": round(median - floor, 4),
            "goal_wall_s": goal,
            "meets_goal": None if goal is None else median < goal,
            "wall_s": [round(x, 4) for x in t["wall"]],
        }
    return out


def print_table(rows: dict[str, dict[str, Any]]) -> None:
    print(f"{'command':<36}{'median s':>10}{'fastest s':>11}{'CPU s':>8}{'over python':>13}  goal")
    for name, r in rows.items():
        goal = "" if r["goal_wall_s"] is None else f"< {r['goal_wall_s']} s: "
        goal += "" if r["meets_goal"] is None else ("met" if r["meets_goal"] else "NOT met")
        print(f"{name:<36}{r['wall_median_s']:>10.3f}{r['wall_min_s']:>11.3f}"
              f"{r['cpu_median_s']:>8.3f}{r['over_python_s']:>13.3f}  {goal}")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.startup", description=__doc__)
    parser.add_argument("--repeats", type=int, default=15, help="interleaved rounds (15)")
    parser.add_argument("--file", type=Path, default=CLIP, help="pose file for describe")
    args = parser.parse_args(argv)
    load_before = list(os.getloadavg())
    with tempfile.TemporaryDirectory(prefix="posecbr-startup-") as folder:
        times = measure(commands(args.file, Path(folder)), args.repeats)
    load_after = list(os.getloadavg())
    rows = summarise(times)
    print_table(rows)
    print(f"load average (1, 5, 15 min) before {load_before}, after {load_after}; "
          f"{os.cpu_count()} CPUs")  # fmt: skip
    from benchmarks.__main__ import machine

    write_json(
        {
            "benchmark": "startup",
            "run_utc": datetime.now(UTC).isoformat(timespec="seconds"),
            "repeats": args.repeats,
            "file": str(
                args.file.relative_to(ROOT) if args.file.is_relative_to(ROOT) else args.file
            ),
            "started_as": "posecbr" if len(posecbr_command()) == 1 else "python -m posecbr",
            # Other work on the machine slows every timing; the load says how busy it was.
            "load_average_1_5_15min_before": load_before,
            "load_average_1_5_15min_after": load_after,
            "results": rows,
            "machine": machine(),
        },
        RESULTS,
    )
    print(f"results: {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
