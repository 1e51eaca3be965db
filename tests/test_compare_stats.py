"""Statistics of `posecbr compare` against published and hand-computed values, and against
scikit-learn."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.metrics import f1_score

from cbr.evaluation.stats import bootstrap_macro_f1, macro_f1, mcnemar_exact, wilson_interval


@pytest.mark.parametrize(
    ("k", "n", "lo", "hi"),
    [
        # Newcombe (1998), "Two-sided confidence intervals for the single proportion",
        # Stat. Med. 17:857-872, table I, method 3 (Wilson score, no continuity correction).
        (81, 263, 0.2553, 0.3662),
        (15, 148, 0.0624, 0.1605),
        (0, 20, 0.0, 0.1611),
        (1, 29, 0.0061, 0.1718),
        # By hand, z = 1.95996: centre (0.8 + z^2/20) / (1 + z^2/10) = 0.71674, half-width
        # z / (1 + z^2/10) * sqrt(0.016 + z^2/400) = 0.22658.
        (8, 10, 0.4902, 0.9433),
    ],
)
def test_wilson_interval_matches_published_values(k: int, n: int, lo: float, hi: float) -> None:
    got = wilson_interval(k, n)
    assert got == pytest.approx((lo, hi), abs=1e-4)


def test_wilson_interval_empty_sample_is_undefined() -> None:
    assert all(np.isnan(wilson_interval(0, 0)))


@pytest.mark.parametrize(
    ("b", "c", "p"),
    [
        (1, 9, 22 / 1024),  # 2 * (C(10,0) + C(10,1)) / 2^10
        (9, 1, 22 / 1024),  # symmetric
        (0, 5, 2 / 32),  # 2 * 0.5^5
        (3, 3, 1.0),  # no evidence either way
        (0, 0, 1.0),  # no discordant pair
        (2, 12, 2 * (1 + 14 + 91) / 2**14),  # 2 * sum_{i<=2} C(14, i) / 2^14
    ],
)
def test_mcnemar_exact_against_hand_computed_binomial_tails(b: int, c: int, p: float) -> None:
    assert mcnemar_exact(b, c) == pytest.approx(p, rel=1e-12)


@pytest.mark.parametrize(
    ("t", "p", "want"),
    [
        # By hand. class 0: tp 1, fp 1, fn 1 -> F1 2/4; class 1: tp 2, fp 1, fn 0 -> 4/5;
        # class 2: tp 0, fn 1 -> 0. Mean 0.4333...
        ([0, 0, 1, 1, 2], [0, 1, 1, 1, 0], (0.5 + 0.8 + 0.0) / 3),
        # Class 2 is only predicted, never true: it counts (F1 0). class 0: tp 1, fn 1 -> 2/3.
        ([0, 0, 1], [0, 2, 1], (2 / 3 + 1.0 + 0.0) / 3),
        (["a", "b", "b"], ["a", "b", "b"], 1.0),
    ],
)
def test_macro_f1_against_hand_computed_values(t: list, p: list, want: float) -> None:
    assert macro_f1(np.array(t), np.array(p)) == pytest.approx(want, abs=1e-12)


def test_wilson_interval_holds_the_proportion_at_zero_and_one_hundred_percent() -> None:
    # The hand-written formula gave an upper bound of 0.9999999999999999 for 10 of 10 (and a
    # lower bound a hair above 0 for 0 of 3), which matplotlib drew as a negative error bar.
    for n in range(1, 301):
        lo, hi = wilson_interval(n, n)
        assert hi == 1.0 and 0.0 <= lo < 1.0
        lo, hi = wilson_interval(0, n)
        assert lo == 0.0 and 0.0 < hi <= 1.0
    # Newcombe (1998) table I again: 0 of 20 -> [0, 0.1611]; by symmetry 20 of 20.
    assert wilson_interval(20, 20) == pytest.approx((1 - 0.1611, 1.0), abs=1e-4)


def test_bootstrap_interval_equals_a_loop_over_scikit_learn_on_the_same_resamples() -> None:
    rng = np.random.default_rng(7)
    t = rng.integers(0, 4, 80)
    p = np.where(rng.random(80) < 0.75, t, rng.integers(0, 4, 80))
    n_boot = 300
    # The same resamples the function draws (documented: default_rng(seed).integers(0, n, (B, n))).
    idx = np.random.default_rng(11).integers(0, len(t), size=(n_boot, len(t)))
    scores = [
        f1_score(t[i], p[i], average="macro", labels=np.union1d(t[i], p[i]), zero_division=0)
        for i in idx
    ]
    want = np.quantile(scores, [0.025, 0.975])
    got = bootstrap_macro_f1(t, p, 4, n_boot=n_boot, seed=11)
    assert got == pytest.approx(tuple(want), abs=1e-12)
    point = f1_score(t, p, average="macro")
    assert got[0] <= point <= got[1]


def test_bootstrap_of_perfect_predictions_is_a_point() -> None:
    t = np.array([0, 1, 2, 0, 1, 2, 2])
    assert bootstrap_macro_f1(t, t.copy(), 3, n_boot=200) == (1.0, 1.0)
