"""`posecbr compare` under leave-one-subject-out gives, beside the figures that count clips as
independent, two whose unit is the person: the accuracy's bootstrap interval over the
subjects and their clips (checked in tests/test_hunt53w.py) and Wilcoxon's
signed-rank test of the subjects' accuracies against the best (checked against hand-worked
p-values and an enumeration of every signing written here with exact fractions)."""

from __future__ import annotations

import csv
import itertools
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.evaluation.report import render_html
from cbr.evaluation.results import CompareResults
from cbr.evaluation.stats import signed_rank
from cbr.evaluation.tables import format_table
from tests.test_hunt53w import accuracy_over_resamples


def _midranks(values: list[Fraction]) -> list[Fraction]:
    """Ranks 1..n of ``values``, ties sharing the mean of the ranks they span."""
    order = sorted(values)
    return [Fraction(2 * order.index(v) + 1 + order.count(v), 2) for v in values]


def _wilcoxon_by_hand(d: list[Fraction]) -> tuple[int, Fraction, Fraction]:
    """Wilcoxon's two-sided exact test, zeros dropped: people, smaller rank sum, p-value as
    the share of all 2^n signings at least as far from the mean rank sum."""
    d = [x for x in d if x != 0]
    ranks = _midranks([abs(x) for x in d])
    plus = sum((r for r, x in zip(ranks, d, strict=True) if x > 0), Fraction(0))
    total = sum(ranks, Fraction(0))
    mid = total / 2
    far = abs(plus - mid)
    hits = sum(
        abs(sum((r for r, s in zip(ranks, signs, strict=True) if s), Fraction(0)) - mid) >= far
        for signs in itertools.product([True, False], repeat=len(d))
    )
    return len(d), min(plus, total - plus), Fraction(hits, 2 ** len(d))


@pytest.mark.parametrize(
    ("d", "n", "w", "p"),
    [
        # |d| 0.05, 0.1, 0.2, 0.2, 0.3 ranked 1, 2, 3.5, 3.5, 5 (the 0 dropped): the negative
        # rank sum 1; signings with a negative sum of 1 or less: none and {1}, 2 of 32, both
        # tails: 4 / 32
        ([0.1, 0.2, 0.2, -0.05, 0.0, 0.3], 5, 1.0, 0.125),
        # five people, all better: 2 / 32 (five people can do no better)
        ([0.1, 0.2, 0.3, 0.4, 0.5], 5, 0.0, 0.0625),
        # 3/10 - 1/10 and 2/10 - 0 are the same fifth: ranks 1.5, 1.5, 3, 4, the negative
        # sum 1.5 (signings {}, {1.5}, {1.5'}: 3 of 16, both tails 6 / 16); as floats
        # (0.19999999999999998 and 0.2) the negative would rank 1 alone and give 4 / 16
        ([-(0.3 - 0.1), 0.2 - 0.0, 0.9, 0.8], 4, 1.5, 0.375),
        # no person's accuracy differs
        ([0.0, 0.0, 0.0], 0, 0.0, 1.0),
    ],
)
def test_signed_rank_hand_worked(d: list[float], n: int, w: float, p: float) -> None:
    got = signed_rank(np.array(d))
    assert got[0] == n
    assert got[1] == pytest.approx(w, abs=1e-12)
    assert got[2] == pytest.approx(p, abs=1e-12)


def test_signed_rank_against_every_signing() -> None:
    # Accuracies as fractions of each person's clips: ties and zeros as real tables give.
    rng = np.random.default_rng(5)
    for _ in range(12):
        people = int(rng.integers(3, 9))
        n = rng.integers(4, 9, people)
        a, b = rng.integers(0, n + 1), rng.integers(0, n + 1)
        exact = [
            Fraction(int(x), int(m)) - Fraction(int(y), int(m))
            for x, y, m in zip(a, b, n, strict=True)
        ]
        k, w, p = _wilcoxon_by_hand(exact)
        got = signed_rank(a / n - b / n)
        assert got[0] == k
        assert got[1] == pytest.approx(float(w), abs=1e-9)
        assert got[2] == pytest.approx(float(p), abs=1e-12), exact


def _people(doc: dict[str, Any], m: dict[str, Any]) -> tuple[list[str], list[int], list[int]]:
    """Subjects (sorted), clips right and clips per subject, from the clips' targets and
    the method's predictions."""
    names = sorted({c["subject"] for c in doc["clips"]})
    right = [0] * len(names)
    n = [0] * len(names)
    for c, said in zip(doc["clips"], m["predictions"], strict=True):
        i = names.index(c["subject"])
        n[i] += 1
        right[i] += int(said == c["target"])
    return names, right, n


def test_compare_gives_the_person_as_the_unit(compared_slice: Path) -> None:
    doc = json.loads((compared_slice / "r.json").read_text())
    with open(compared_slice / "r.csv", newline="") as fh:
        rows = {r["method"]: r for r in csv.DictReader(fh)}
    results = CompareResults.from_dict(doc)
    table = format_table(results).splitlines()
    page = render_html(results, {})
    scored = {m["name"]: m for m in doc["methods"] if m["status"] == "ok"}
    best = doc["best"]
    _, best_right, n = _people(doc, scored[best])
    seed, n_boot = int(doc["settings"]["seed"]), int(doc["settings"]["bootstrap"])
    clips = doc["clips"]
    subjects = np.array([c["subject"] for c in clips])
    assert (
        "people as the unit: the accuracy's 95 % bootstrap over the 3 subjects held out and"
        " their clips;" in table
    )
    for name, m in scored.items():
        _, right, _ = _people(doc, m)
        said = zip(clips, m["predictions"], strict=True)
        correct = np.array([x == c["target"] for c, x in said])
        # the resamples of macro-F1's interval: the subjects, then each one's clips
        low, high = accuracy_over_resamples(correct, subjects, n_boot, seed)
        assert m["accuracy_ci_people"] == pytest.approx([low, high], abs=1e-12), name
        row = rows[name]
        assert float(row["accuracy_people_lo"]) == pytest.approx(low, abs=1e-6)
        assert float(row["accuracy_people_hi"]) == pytest.approx(high, abs=1e-6)
        d = [Fraction(x, k) - Fraction(y, k) for x, y, k in zip(right, best_right, n, strict=True)]
        people, w, p = _wilcoxon_by_hand(d)
        assert (m["wilcoxon_vs"], m["wilcoxon_n"]) == (best, people), name
        assert m["wilcoxon_w"] == pytest.approx(float(w), abs=1e-9)
        assert m["wilcoxon_p"] == pytest.approx(float(p), abs=1e-12)
        assert float(row["wilcoxon_p"]) == pytest.approx(float(p), abs=1e-12)
        # the printed people table and the report's cells
        head = next(i for i, x in enumerate(table) if "[95 % CI over people]" in x)
        line = next(x for x in table[head:] if x.startswith(name + " "))
        interval = f"[{100 * low:4.1f}, {100 * high:5.1f}]"
        assert interval in line, line
        assert line.endswith("best" if name == best else f"{float(p):.3g} ({people})"), line
        assert f"<td>{100 * low:.1f}–{100 * high:.1f}</td>" in page
    assert max(len(x) for x in table) <= 100
    assert "Wilcoxon p vs best (people)" in page


def test_k_fold_and_files_written_before_give_none(
    compared_three: Path, compared_slice: Path
) -> None:
    doc = json.loads((compared_three / "results.json").read_text())
    (m,) = doc["methods"]
    assert "accuracy_ci_people" not in m and "wilcoxon_p" not in m
    with open(compared_three / "results.csv", newline="") as fh:
        (row,) = csv.DictReader(fh)
    assert row["accuracy_people_lo"] == row["wilcoxon_p"] == ""
    assert "people as the unit" not in format_table(CompareResults.from_dict(doc))
    old = json.loads((compared_slice / "r.json").read_text())
    for m in old["methods"]:
        for key in ("accuracy_ci_people", "wilcoxon_vs", "wilcoxon_n", "wilcoxon_w"):
            m.pop(key, None)
        m.pop("wilcoxon_p", None)
    results = CompareResults.from_dict(old)
    assert "people as the unit" not in format_table(results)
    assert "id='results'" in render_html(results, {})
