"""`posecbr compare`'s macro-F1 interval under leave-one-subject-out resamples subjects, then
the clips of each drawn subject (one person's clips share the errors made on that person),
checked against scikit-learn's ``f1_score`` on the same resamples; and the report says what
was resampled."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from sklearn.metrics import f1_score

from cbr.evaluation.report import render_html
from cbr.evaluation.results import CompareResults
from cbr.evaluation.stats import bootstrap_macro_f1
from features.errors import DataError


def _sklearn_two_stage(
    t: np.ndarray, p: np.ndarray, subjects: np.ndarray, n_boot: int, seed: int
) -> tuple[float, float]:
    """The documented two-stage resamples, one by one: per resample the sorted subjects drawn
    ``g`` times (``rng.integers(0, g, (n_boot, g))``), then each drawn subject's ``m`` clips
    drawn ``m`` times by ``floor(u * m)``, the ``u`` from ``rng.random`` in that order;
    every resample scored by scikit-learn's ``f1_score``."""
    names = sorted(set(subjects.tolist()))
    members = [np.flatnonzero(subjects == s) for s in names]
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, len(names), size=(n_boot, len(names)))
    u = rng.random(sum(len(members[k]) for k in draws.ravel()))
    used, scores = 0, []
    for d in draws:
        picked = []
        for k in d:
            m = len(members[k])
            picked += [members[k][int(x * m)] for x in u[used : used + m]]
            used += m
        i = np.array(picked)
        scores.append(f1_score(t[i], p[i], average="macro", zero_division=0))
    lo, hi = np.quantile(scores, [0.025, 0.975])
    return float(lo), float(hi)


def test_subject_bootstrap_against_scikit_learn_on_the_documented_resamples() -> None:
    # Three people of 12, 8 and 10 clips (not in order); every error is the third person's:
    # those of their clips at an even position answered as another class (4 of their 10).
    rng = np.random.default_rng(3)
    subjects = rng.permutation(np.repeat(np.array([4, 1, 7]), [12, 8, 10]))
    t = rng.integers(0, 3, len(subjects))
    p = np.where((subjects == 7) & (np.arange(len(t)) % 2 == 0), (t + 1) % 3, t)
    want = _sklearn_two_stage(t, p, subjects, 120, 5)
    got = bootstrap_macro_f1(t, p, 3, n_boot=120, seed=5, groups=subjects)
    assert got == pytest.approx(want, abs=1e-12)
    assert int((t != p).sum()) == 4
    # Clips alone: a resample holds some of the third person's clips, never mostly theirs.
    clips = bootstrap_macro_f1(t, p, 3, n_boot=120, seed=5)
    assert got[0] < clips[0] - 0.05


def test_leave_one_subject_out_interval_resamples_subjects(compared_slice: Path) -> None:
    doc = json.loads((compared_slice / "r.json").read_text())
    assert doc["cv"]["scheme"] == "loso"
    assert doc["cv"]["bootstrap_over"] == "subjects"
    classes = doc["dataset"]["classes"]
    t = np.array([classes.index(c["target"]) for c in doc["clips"]])
    subjects = np.array([c["subject"] for c in doc["clips"]])
    scored = [m for m in doc["methods"] if m["status"] == "ok"]
    assert len(scored) == 3  # euclidean, dtw, DAD
    for m in scored:
        p = np.array([classes.index(v) for v in m["predictions"]])
        want = bootstrap_macro_f1(
            t, p, len(classes), doc["settings"]["bootstrap"], seed=doc["settings"]["seed"],
            groups=subjects,
        )  # fmt: skip
        assert m["macro_f1_ci"] == pytest.approx(want, abs=1e-12), m["name"]
    page = render_html(CompareResults.from_dict(doc), {})
    assert "bootstrap 95 % interval over subjects and their clips" in page


def test_k_fold_interval_resamples_clips(compared_three: Path) -> None:
    # One subject: k-fold over clips, and the bootstrap draws clips (the same resamples as
    # scikit-learn's in tests/test_compare_stats.py).
    doc = json.loads((compared_three / "results.json").read_text())
    assert doc["cv"]["scheme"] == "kfold"
    assert doc["cv"]["bootstrap_over"] == "clips"
    page = render_html(CompareResults.from_dict(doc), {})
    assert "bootstrap 95 % interval over clips;" in page


def test_results_of_an_earlier_run_are_read_as_resampled_over_clips(
    compared_slice: Path,
) -> None:
    doc = json.loads((compared_slice / "r.json").read_text())
    del doc["cv"]["bootstrap_over"]  # written before the key was
    page = render_html(CompareResults.from_dict(doc), {})
    assert "bootstrap 95 % interval over clips;" in page
    doc["cv"]["bootstrap_over"] = "people"
    with pytest.raises(DataError, match=r"key 'cv.bootstrap_over' must be 'clips' or 'subjects'"):
        CompareResults.from_dict(doc)
