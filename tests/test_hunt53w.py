"""`posecbr compare`'s two bootstraps under leave-one-subject-out draw the same resamples: the
subjects, then each drawn subject's clips, for the accuracy's interval over people as for
macro-F1's (checked by hand and against resamples drawn one by one as documented, scored by
scikit-learn); and the results reader refuses person figures that make no sense."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sklearn.metrics import f1_score

from cbr.evaluation.stats import bootstrap_accuracy, bootstrap_macro_f1
from posecbr.cli import main


def documented_resamples(subjects: np.ndarray, n_boot: int, seed: int) -> list[np.ndarray]:
    """The two-stage resamples as documented, one by one: per resample the sorted subjects
    drawn ``g`` times (``rng.integers(0, g, (n_boot, g))``), then each drawn subject's ``m``
    clips (in dataset order) drawn ``m`` times by ``floor(u * m)``, the ``u`` from
    ``rng.random`` taken in that order."""
    names = sorted(set(subjects.tolist()))
    members = [np.flatnonzero(subjects == s) for s in names]
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, len(names), size=(n_boot, len(names)))
    u = iter(rng.random(sum(len(members[k]) for k in draws.ravel())))
    return [
        np.array([members[k][int(next(u) * len(members[k]))] for k in d for _ in members[k]])
        for d in draws
    ]


def accuracy_over_resamples(
    correct: np.ndarray, subjects: np.ndarray, n_boot: int, seed: int
) -> tuple[float, float]:
    """The 2.5 % and 97.5 % points of the accuracy over :func:`documented_resamples`."""
    acc = [float(np.mean(correct[i])) for i in documented_resamples(subjects, n_boot, seed)]
    lo, hi = np.quantile(acc, [0.025, 0.975])
    return float(lo), float(hi)


def test_people_interval_draws_each_persons_clips_again_by_hand() -> None:
    # One person right on one clip of two: drawing people alone always gives 1/2; drawing
    # the two clips again gives 0, 1/2, 1 with chances 1/4, 1/2, 1/4.
    assert bootstrap_accuracy(np.array([True, False]), np.array(["a", "a"])) == (0.0, 1.0)
    # A right on one clip of two, B on both. People: AA, AB, BB with 1/4, 1/2, 1/4. A's two
    # clips drawn again: k right of 2 with 1/4, 1/2, 1/4. Accuracy over the four clips drawn:
    # AA (k1 + k2) / 4, k1 + k2 ~ Binomial(4, 1/2); AB (k + 2) / 4; BB 1.
    # P(0) = 1/4 * 1/16 = 1/64 (1.6 %) < 2.5 % < P(<= 1/4) = 1/64 + 1/4 * 4/16 = 5/64;
    # P(1) = 1/4 + 1/2 * 1/4 + 1/4 * 1/16 = 25/64 > 2.5 %: the interval is [1/4, 1].
    # People alone: 1/2, 3/4, 1, so [1/2, 1].
    correct = np.array([True, False, True, True])
    who = np.array(["A", "A", "B", "B"])
    assert bootstrap_accuracy(correct, who, n_boot=4000, seed=1) == (0.25, 1.0)
    # Everyone all right or all wrong: drawing clips again changes nothing.
    assert bootstrap_accuracy(np.array([False, False, True, True]), who) == (0.0, 1.0)
    assert np.isnan(bootstrap_accuracy(np.array([], dtype=bool), np.array([]))).all()


def test_accuracy_and_macro_f1_share_the_documented_resamples() -> None:
    # Three people of 12, 8 and 10 clips, interleaved; errors on all three, most the third's.
    rng = np.random.default_rng(11)
    subjects = rng.permutation(np.repeat(np.array(["s4", "s1", "s7"]), [12, 8, 10]))
    t = rng.integers(0, 3, len(subjects))
    wrong = rng.random(len(t)) < np.where(subjects == "s7", 0.5, 0.15)
    p = np.where(wrong, (t + 1) % 3, t)
    picks = documented_resamples(subjects, 60, 4)
    f1 = [f1_score(t[i], p[i], average="macro", zero_division=0) for i in picks]
    want_f1 = tuple(np.quantile(f1, [0.025, 0.975]))
    assert bootstrap_macro_f1(t, p, 3, n_boot=60, seed=4, groups=subjects) == pytest.approx(
        want_f1, abs=1e-12
    )
    want = accuracy_over_resamples(t == p, subjects, 60, 4)
    assert bootstrap_accuracy(t == p, subjects, n_boot=60, seed=4) == pytest.approx(want, abs=1e-12)


def _put(doc: dict[str, Any], key: str, value: Any) -> None:
    """Set ``key`` of the first row tested against the best (one with Wilcoxon's figures)."""
    m = next(m for m in doc["methods"] if "wilcoxon_n" in m)
    m[key] = value


BAD_PEOPLE = [
    ("wilcoxon_n", -1, "key 'methods[{i}].wilcoxon_n' must be a whole number of 0 or more, got -1"),
    ("wilcoxon_n", 4, "key 'methods[{i}].wilcoxon_n' counts 4 subjects whose accuracies differ,"
     " more than the 3 in per_subject"),
    ("wilcoxon_w", -2.5, "key 'methods[{i}].wilcoxon_w' must be a finite number of 0 or more,"
     " got -2.5"),
    ("accuracy_ci_people", [0.9, 0.8], "key 'methods[{i}].accuracy_ci_people' must be two shares"
     " in [0, 1], the lower first, got [0.9, 0.8]"),
    ("accuracy_ci_people", [-0.1, 0.5], "key 'methods[{i}].accuracy_ci_people' must be two"
     " shares in [0, 1], the lower first, got [-0.1, 0.5]"),
    ("accuracy_ci_people", [0.5, 1.25], "key 'methods[{i}].accuracy_ci_people' must be two"
     " shares in [0, 1], the lower first, got [0.5, 1.25]"),
]  # fmt: skip


@pytest.mark.parametrize(("key", "value", "message"), BAD_PEOPLE)
def test_report_refuses_person_figures_that_make_no_sense(
    compared_slice: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    key: str,
    value: Any,
    message: str,
) -> None:
    doc = json.loads((compared_slice / "r.json").read_text())
    assert sorted({c["subject"] for c in doc["clips"]}) == ["s01", "s02", "s03"]
    i = next(j for j, m in enumerate(doc["methods"]) if "wilcoxon_n" in m)
    _put(doc, key, value)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    out = tmp_path / "report.html"
    assert main(["report", str(bad), "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"posecbr report: error: {bad}: {message.format(i=i)}"]
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json"]
