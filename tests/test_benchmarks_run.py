"""The benchmarks still run: ``benchmarks.compare`` end to end on a slice of the bundled demo
data (the suite runs no other benchmark; ``python -m benchmarks NAME`` runs any of them).

``compare --quick`` takes about a minute on the whole demo subset (180 clips); this runs its
``main`` on the correct repetitions of two movements of it (18 clips of three subjects: three
leave-one-subject-out folds), its results written under ``tmp_path``, never into
``benchmarks/results``. The tslearn peer is kept, since it is what the benchmark's ratios are
measured against; its numba kernels are loaded from numba's cache, not compiled again
(``cbr.evaluation.peers.cache_tslearn_kernels``, warmed by ``tests/_kernels.py``).
"""

from __future__ import annotations

import csv
import json
import math
import shutil
from pathlib import Path

import pytest

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
MOVEMENTS = {"m01", "m02"}


def _demo_slice(folder: Path) -> int:
    """The correct demo repetitions of ``MOVEMENTS`` copied into ``folder`` with their labels;
    how many."""
    folder.mkdir()
    with (DEMO / "labels.csv").open(newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        fields = reader.fieldnames
        rows = [r for r in reader if r["movement"] in MOVEMENTS and r["correct"] == "true"]
    assert fields is not None
    with (folder / "labels.csv").open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    for r in rows:
        shutil.copy(DEMO / r["path"], folder / r["path"])
    return len(rows)


def test_compare_quick_runs_and_records_the_peers(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from benchmarks import compare  # imported here: tslearn's chatter under the filter above

    n_clips = _demo_slice(tmp_path / "demo")
    out = tmp_path / "compare.json"
    monkeypatch.setattr(compare, "QUICK", (("demo slice", tmp_path / "demo", "label"),))
    monkeypatch.setattr(compare, "RESULTS", out)
    # the run prints its path relative to the project: a path under tmp_path is not
    monkeypatch.setattr(compare, "ROOT", tmp_path)

    assert compare.main(["--quick"]) == 0

    printed = capsys.readouterr().out
    methods = ["cbr fluents/euclidean", "cbr fluents/dtw", "cbr fluents/signature",
               "cbr qmp/euclidean", "dad", "dtw-knn"]  # fmt: skip
    for name in methods:  # one table row each
        assert any(line.startswith(name) for line in printed.splitlines()), name
    # the demo subset's figures beside the shared data's, never over them
    assert not out.exists()
    doc = json.loads((tmp_path / "compare_quick.json").read_text(encoding="utf-8"))
    assert doc["benchmark"] == "compare"
    assert "platform" in doc["machine"]
    task = doc["tasks"]["demo slice"]
    assert task["n_clips"] == n_clips == 18
    assert task["subjects"] == ["s01", "s02", "s03"]
    assert task["cv"] == {"scheme": "loso", "n_folds": 3, "bootstrap_over": "subjects"}
    assert sorted(task["classes"]) == ["deep_squat", "hurdle_step"]
    by_name = {m["name"]: m for m in task["methods"]}
    assert set(methods) <= set(by_name)
    for name in methods:
        m = by_name[name]
        assert m["status"] == "ok", m
        assert 0.0 <= m["accuracy"] <= 1.0
        assert m["predict_ms_per_clip"] > 0
    assert by_name[task["best_interpretable"]]["interpretable"]
    versus = task["best_interpretable_vs_peers"]
    assert "dtw-knn" in {v["peer"] for v in versus}  # tslearn is a dependency: it always runs
    for v in versus:
        assert v["interpretable"] == task["best_interpretable"]
        assert math.isfinite(v["predict_time_ratio"]) and v["predict_time_ratio"] > 0
        assert -1.0 <= v["accuracy_difference"] <= 1.0
        assert 0.0 <= v["mcnemar_p"] <= 1.0
        assert 0.0 <= v["wilcoxon_p"] <= 1.0  # the demo's three subjects held out


@pytest.mark.skipif(
    __import__("importlib.util").util.find_spec("faiss") is not None,
    reason="faiss is installed here: the benchmarks would run, not refuse",
)
@pytest.mark.parametrize("name", ["quantized", "retrieval"])
def test_a_benchmark_without_its_peer_says_so_in_one_line(name: str, tmp_path: Path) -> None:
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "out.json"
    done = subprocess.run(
        [sys.executable, "-m", f"benchmarks.{name}", "--sizes", "100", "--out", str(out)],
        cwd=root, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 1
    assert done.stderr.strip().splitlines() == [
        f"python -m benchmarks.{name}: needs faiss-cpu, the peer it measures against"
        " (pip install -e '.[bench]')"
    ]
    assert done.stdout == "" and not out.exists()


def test_benchmark_results_are_strict_json(tmp_path: Path) -> None:
    """A benchmark's median of no boundary found is infinite: it was written ``Infinity``,
    which JSON has not (strict readers refuse it). Non-finite figures are written null,
    nested too; finite ones are kept."""
    from benchmarks import write_json
    from tests.test_json_hunt import strict

    doc = {"median": float("inf"), "rows": [1.5, float("nan"), {"x": -float("inf")}], "n": 3}
    write_json(doc, tmp_path / "r.json")

    got = strict((tmp_path / "r.json").read_text())
    got.pop("machine")  # added to a result without it (tests/test_hunt50h.py)
    assert got == {"median": None, "rows": [1.5, None, {"x": None}], "n": 3}
