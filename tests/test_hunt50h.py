"""Every benchmark's results record the machine and library versions, run alone too; a
folder given as ``--out`` is refused before the run.

README's "Speed" says every benchmark writes its JSON "with the machine, versions, threads and
load average"; ``python -m benchmarks`` added the machine to a result without it, but a
benchmark run alone (``python -m benchmarks.segment_cuts``, ``repetition_bounds``,
``segment_live``, ``stored_judges``, ``bandwidth``, ``solve``, ``retrieval``, ``dtw``) wrote
none: its figures could not be told from another machine's. ``benchmarks.write_json`` now adds
the record to a result that has none. A folder given as ``--out`` (``bandwidth``, ``dtw``,
``retrieval``, ``quantized``, ``solve``, ``faults``, ``explanations``, ``long_clip``,
``long_recording``, ``unknown_bounds``) ran the whole benchmark and then ended in a traceback;
``benchmarks.json_out`` refuses it when the options are read.
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_a_result_without_the_machine_gets_it_and_one_with_its_own_keeps_it(
    tmp_path: Path,
) -> None:
    from benchmarks import write_json

    write_json({"benchmark": "x", "rows": [1, 2]}, tmp_path / "r.json")
    own = {"platform": "p", "threads": 1, "load_average_1_5_15min_at_end": [1.0, 2.0, 3.0]}
    write_json({"benchmark": "y", "machine": own}, tmp_path / "own.json")

    doc = json.loads((tmp_path / "r.json").read_text(encoding="utf-8"))
    assert doc["benchmark"] == "x" and doc["rows"] == [1, 2]
    machine = doc["machine"]
    assert machine["python"] == platform.python_version()
    assert machine["cpu_count"] == os.cpu_count()
    assert machine["platform"] == platform.platform()
    assert machine["versions"]["numpy"] == importlib.metadata.version("numpy")
    assert machine["versions"]["scipy"] == importlib.metadata.version("scipy")
    assert json.loads((tmp_path / "own.json").read_text(encoding="utf-8"))["machine"] == own


def test_a_benchmark_run_alone_records_the_machine(tmp_path: Path) -> None:
    """``bandwidth`` (a tiny matrix) as typed, in its own process: it wrote only the numpy
    version before."""
    out = tmp_path / "bandwidth.json"
    done = subprocess.run(
        [sys.executable, "-m", "benchmarks.bandwidth", "--rows", "100", "--dims", "4",
         "--repeats", "1", "--out", str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["rows"] == 100 and doc["dims"] == 4
    assert doc["machine"]["cpu_count"] == os.cpu_count()
    assert doc["machine"]["versions"]["numpy"] == importlib.metadata.version("numpy")


def test_a_folder_for_out_is_refused_before_the_run(tmp_path: Path) -> None:
    """``--out`` naming a folder: the benchmark ran to its end, then stopped with a traceback
    saying the output "is not a regular file (a device, pipe or socket)"; now argparse's
    error names the folder, before any work (exit 2), and nothing is written in it."""
    done = subprocess.run(
        [sys.executable, "-m", "benchmarks.bandwidth", "--rows", "100", "--dims", "4",
         "--repeats", "1", "--out", str(tmp_path)],
        cwd=ROOT, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 2
    assert done.stdout == ""  # no figures: nothing was measured
    assert "Traceback" not in done.stderr
    assert done.stderr.splitlines()[-1].endswith(
        f"argument --out: {tmp_path} is a folder: name the .json file to write the results to"
    )
    assert list(tmp_path.iterdir()) == []
