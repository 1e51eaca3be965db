"""`posecbr compare` under leave-one-subject-out gives the accuracy on every subject held out
and its spread over them (results.json, results.csv, the printed table, the report), checked
against scikit-learn's ``accuracy_score`` on the run's own predictions grouped by subject;
k-fold says there is none, and a results file written before still renders."""

from __future__ import annotations

import csv
import json
import statistics
from pathlib import Path
from typing import Any

import pytest
from sklearn.metrics import accuracy_score

from cbr.evaluation.report import render_html
from cbr.evaluation.results import CompareResults
from cbr.evaluation.tables import format_table


def _by_subject(doc: dict[str, Any], m: dict[str, Any]) -> dict[str, tuple[int, float]]:
    """Clips and accuracy per subject, counted from the clips' subjects and targets and the
    method's predictions (scikit-learn's accuracy on each subject's clips)."""
    out = {}
    for person in sorted({c["subject"] for c in doc["clips"]}):
        mine = [i for i, c in enumerate(doc["clips"]) if c["subject"] == person]
        truth = [doc["clips"][i]["target"] for i in mine]
        said = [m["predictions"][i] for i in mine]
        out[person] = (len(mine), float(accuracy_score(truth, said)))
    return out


def _csv(path: Path) -> dict[str, dict[str, str]]:
    with open(path, newline="") as fh:
        return {r["method"]: r for r in csv.DictReader(fh)}


def test_accuracy_per_subject_held_out_against_scikit_learn(compared_slice: Path) -> None:
    doc = json.loads((compared_slice / "r.json").read_text())
    assert doc["cv"]["scheme"] == "loso"
    rows = _csv(compared_slice / "r.csv")
    results = CompareResults.from_dict(doc)
    table = format_table(results)
    page = render_html(results, {})
    scored = [m for m in doc["methods"] if m["status"] == "ok"]
    assert len(scored) == 3  # euclidean, dtw, DAD
    for m in scored:
        want = _by_subject(doc, m)
        assert sorted(want) == ["s01", "s02", "s03"]
        got = m["per_subject"]
        assert {p: r["n"] for p, r in got.items()} == {p: n for p, (n, _) in want.items()}
        for p, (_, a) in want.items():
            assert got[p]["accuracy"] == pytest.approx(a, abs=1e-12), (m["name"], p)
        values = [a for _, a in want.values()]
        mean, sd, low = statistics.mean(values), statistics.stdev(values), min(values)
        row = rows[m["name"]]
        for key, v in (("mean", mean), ("sd", sd), ("min", low), ("max", max(values))):
            assert float(row[f"person_{key}"]) == pytest.approx(v, abs=1e-6), (m["name"], key)
        for p, (_, a) in want.items():
            assert float(row[f"subject:{p}"]) == pytest.approx(a, abs=1e-6)
        # the printed row, and the report's results table and summary row
        line = next(x for x in table.splitlines() if x.startswith(m["name"] + " "))
        cell = f"{100 * mean:.1f} ± {100 * sd:.1f} ({100 * low:.1f})"
        assert cell in line
        assert f">{cell}</td>" in page
        assert f"<td>{100 * mean:.1f} ± {100 * sd:.1f}</td>" in page
    assert "id='subjects'" in page and "s02 (18)" in page
    assert max(len(x) for x in table.splitlines()) <= 100
    assert "the accuracy on each of the 3 subjects held out" in table
    assert "macro-F1's 95 % interval: bootstrap over subjects, then each one's clips" in table


def test_k_fold_gives_no_accuracy_per_person(compared_three: Path) -> None:
    # One subject's clips in three stratified folds: a fold is no person held out.
    doc = json.loads((compared_three / "results.json").read_text())
    assert doc["cv"]["scheme"] == "kfold"
    (m,) = doc["methods"]
    assert m["per_subject"] == {}
    row = _csv(compared_three / "results.csv")[m["name"]]
    assert row["person_mean"] == row["person_sd"] == row["person_min"] == ""
    results = CompareResults.from_dict(doc)
    table = format_table(results)
    assert "person %" not in table.splitlines()[0]
    assert "no accuracy per person: kfold folds are not people held out" in table
    assert "macro-F1's 95 % interval: bootstrap over clips" in table
    page = render_html(results, {})
    assert "No accuracy per person: kfold folds are not people held out one by one." in page
    assert "per person %" not in page


def test_results_written_before_still_render(compared_slice: Path) -> None:
    doc = json.loads((compared_slice / "r.json").read_text())
    for m in doc["methods"]:
        m.pop("per_subject", None)  # written before the key was
    results = CompareResults.from_dict(doc)
    page = render_html(results, {})
    assert "No accuracy per person: this results file was written before it was given." in page
    assert "id='results'" in page and "per person %" not in page
    table = format_table(results)
    assert "person %" not in table.splitlines()[0]
    assert "cbr fluents/euclidean *" in table
