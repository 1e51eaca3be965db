"""The pure scoring helpers of ``benchmarks.unknown_ceiling`` (issue 14's ceiling of any
threshold), against values worked out by hand and against scikit-learn."""

from __future__ import annotations

import math

import numpy as np
import pytest
from sklearn.metrics import roc_auc_score

from benchmarks.unknown_ceiling import (
    auroc,
    called,
    combined_scores,
    figures,
    logistic_fused,
    oracle_rate,
    oracle_threshold,
    pure_windows,
    spaced,
    tail_fused,
    tail_p,
)


def test_oracle_threshold_keeps_the_share_of_known_scores() -> None:
    known = np.arange(1.0, 21.0)  # 1..20: 19 of 20 (95 %) kept at 19, 18 of 20 at 18
    assert oracle_threshold(known) == 19.0
    assert oracle_threshold(known, 0.90) == 18.0
    assert oracle_threshold(known, 0.91) == 19.0  # 18.2 scores: the 19th smallest
    assert oracle_threshold(np.array([3.0, 1.0, 2.0]), 1.0) == 3.0
    assert oracle_threshold(np.array([5.0]), 0.5) == 5.0


def test_oracle_rate_by_hand() -> None:
    known = np.arange(1.0, 21.0)  # threshold 19 at 95 %
    novel = np.array([0.5, 10.0, 19.0, 19.5, 25.0])  # above 19: 19.5 and 25 (19 ties: known)
    assert oracle_rate(known, novel) == pytest.approx(2 / 5)
    kept, caught = called(known, novel, 19.0)
    assert (kept, caught) == (19 / 20, 2 / 5)
    assert oracle_rate(known, novel, 0.5) == pytest.approx(3 / 5)  # threshold 10: 19 above
    assert math.isnan(oracle_rate(np.zeros(0), novel))


def test_auroc_is_sklearns_and_ranks_infinity_first() -> None:
    rng = np.random.default_rng(3)
    known, novel = rng.normal(0, 1, 40), rng.normal(0.7, 1, 30)
    truth = np.r_[np.zeros(40), np.ones(30)]
    assert auroc(known, novel) == pytest.approx(roc_auc_score(truth, np.r_[known, novel]))
    # by hand: pairs (known, novel) with novel above, ties half: (1,2) (1,inf) (3,inf); (3,2) no
    assert auroc(np.array([1.0, 3.0]), np.array([2.0, np.inf])) == pytest.approx(3 / 4)
    assert auroc(np.array([1.0, 2.0]), np.array([2.0])) == pytest.approx(0.75)
    assert math.isnan(auroc(np.array([1.0]), np.zeros(0)))


def test_figures_name_the_calibrated_shares() -> None:
    out = figures(np.array([1.0, 2.0, 3.0, 4.0]), np.array([2.5, 5.0]), 3.0)
    # pairs with the novel score above: 2.5 over 1 and 2, 5 over all four
    assert out["auroc"] == pytest.approx(6 / 8)
    assert out["oracle_unknown_at_95_known"] == pytest.approx(1 / 2)  # threshold 4
    assert out["calibrated"] == {"threshold": 3.0, "known_kept": 0.75, "novel_unknown": 0.5}


def test_pure_windows_leave_out_windows_across_a_change() -> None:
    class Rec:
        blocks = np.array(["a"] * 10 + ["b"] * 10, dtype=object)

    # 10 frames a second: block i's centre at frame i + 0.5
    spans = np.array([[0, 10], [5, 15], [10, 20], [12, 14]])
    assert pure_windows(Rec(), spans, 10.0).tolist() == ["a", None, "b", "b"]  # type: ignore[arg-type]


def test_spaced_keeps_the_ends() -> None:
    items = [f"m{i:02d}" for i in range(1, 11)]
    assert spaced(items, 4) == ["m01", "m04", "m07", "m10"]
    assert spaced(items, None) == items
    assert spaced(items, 12) == items


def test_tail_p_counts_the_held_out_scores_at_or_above() -> None:
    held = np.array([3.0, 1.0, 4.0, 2.0])
    # (1 + #held >= x) / 5: 0 -> 5/5, 2 -> 4/5 (2, 3, 4), 4.5 and inf -> 1/5
    assert tail_p(held, np.array([0.0, 2.0, 4.5, np.inf])) == pytest.approx([1, 0.8, 0.2, 0.2])


def test_tail_fusions_by_hand() -> None:
    held = {"a": np.array([1.0, 2.0, 3.0, 4.0]), "b": np.array([10.0, 20.0, 30.0, 40.0])}
    scores = {"a": np.array([2.0, 4.5]), "b": np.array([45.0, 10.0])}
    # p of a: 4/5, 1/5; of b: 1/5, 5/5
    assert tail_fused(held, scores, "tail-max") == pytest.approx([math.log(5), math.log(5)])
    fisher = [-2 * math.log(4 / 25), -2 * math.log(1 / 5)]
    assert tail_fused(held, scores, "tail-fisher") == pytest.approx(fisher)
    with pytest.raises(ValueError, match="fusion"):
        tail_fused(held, scores, "mean")


def test_combined_thresholds_come_from_the_held_out_known_scores() -> None:
    known = {"a": np.array([1.0, 2.0, 3.0, 4.0]), "b": np.array([10.0, 20.0, 30.0, 40.0])}
    novel = {"a": np.array([5.0, 6.0, 8.0]), "b": np.array([50.0, 70.0, 90.0])}
    out = combined_scores(
        {"known": known, "novel": novel}, {"a": np.array([2.0]), "b": np.array([45.0])}
    )
    # held-out known cases against themselves: p 5/5, 4/5, 3/5, 2/5 for both parts; the
    # 95 % threshold keeps all four: the largest, -log(2/5) (Fisher: -2 * 2 log(2/5))
    assert out["tail-max"][1] == pytest.approx(math.log(2.5))
    assert out["tail-fisher"][1] == pytest.approx(-4 * math.log(0.4))
    assert out["tail-max"][0] == pytest.approx([math.log(5)])  # b's 45 is above every held one
    assert set(out) == {"tail-max", "tail-fisher", "logistic"}


def test_logistic_fusion_orders_windows_by_the_held_out_novel_side() -> None:
    rng = np.random.default_rng(0)
    known = {"a": rng.uniform(1, 2, 50), "b": rng.uniform(1, 2, 50)}
    novel = {"a": rng.uniform(3, 6, 50), "b": rng.uniform(1, 2, 50)}  # only a tells them apart
    s = logistic_fused(known, novel, {"a": np.array([1.5, 4.0, np.inf]), "b": np.ones(3)})
    assert s[0] < 0 < s[1] <= s[2]  # known side, novel side; inf at the top of the range


def test_smoothed_reader_smooths_each_file_once(monkeypatch: pytest.MonkeyPatch) -> None:
    # --smooth-jitter: every file read is features.jitter.smooth_jitter's of it, made once
    from pathlib import Path

    import benchmarks.segment_people as sp
    from benchmarks.repetitions import Group
    from benchmarks.unknown_ceiling import SmoothedReader
    from features.jitter import smooth_jitter
    from features.poses import BLAZEPOSE_33, PoseSequence

    pos = np.repeat(np.arange(99, dtype=np.float64).reshape(1, 33, 3) / 100.0, 60, axis=0)
    pos[:, 15, 0] += 0.01 * (-1.0) ** np.arange(60)  # 1 cm of jitter on the left wrist
    raw = PoseSequence(pos, BLAZEPOSE_33, 30.0)
    reads = []
    monkeypatch.setattr(sp, "read_one", lambda g, p: reads.append(p) or raw)
    read = SmoothedReader()
    group = Group("ui-prmd-kinect", "s01", "m01", (Path("a"),))
    got = read(group, Path("a"))
    assert np.array_equal(got.positions, smooth_jitter(raw).positions)
    assert not np.array_equal(got.positions, raw.positions)
    assert read(group, Path("a")) is got and reads == [Path("a")]


def _recording(movements: list[str | None], voted: list[str], judge: list[float]) -> dict:
    """A measured recording as :func:`benchmarks.unknown_ceiling.measure_left_out` keeps it,
    with only the scores a ``--judge-only`` run has."""
    n = len(movements)
    score = np.array(judge, dtype=float)
    return {
        "movements": np.array(movements, dtype=object),
        "voted": np.array(voted, dtype=object),
        "scores": {"spread-margin": score, "margin": score / 2, "nearest": score * 3},
        "evidence": score / 10,
        "unlike": score > 1.0,
        "blocks_novel": 0,
        "blocks_novel_unknown": 0,
        "blocks_known": 0,
        "blocks_known_unknown": 0,
        "centres_s": np.arange(n, dtype=float),
    }


def test_a_judge_only_run_is_summarised_with_the_known_windows_voted_accuracy() -> None:
    from benchmarks.unknown_ceiling import scores_in, summarise

    # "b" left out: windows of a and c are known; the window across a change (None) counts
    # in neither; of the three known windows (a, a, c) two are voted their own movement
    rec = _recording(["a", "a", "b", "b", None, "c"], ["a", "c", "a", "c", "a", "c"],
                     [0.5, 0.9, 2.0, 1.5, 3.0, 0.7])  # fmt: skip
    left = {"recordings": {"s05-1": rec}, "thresholds": {"spread-margin": 1.0}}
    parts = [("b", left)]
    assert scores_in(parts) == ("spread-margin", "margin", "nearest")
    out = summarise(parts)
    assert out["known_windows_voted_right"] == pytest.approx(2 / 3)
    assert out["known_windows"] == 3 and out["novel_windows"] == 2
    assert out["windows_across_a_change_left_out"] == 1
    # known 0.5, 0.9, 0.7 lie below both novel ones: AUROC 1, every novel window above the
    # oracle threshold (0.9, the highest known: 3 of 3 at 95 %)
    assert out["spread-margin"]["auroc"] == 1.0
    assert out["spread-margin"]["oracle_unknown_at_95_known"] == 1.0
    assert out["spread-margin"]["calibrated"] == {"known_kept": 1.0, "novel_unknown": 1.0}
    assert "lof" not in out and "dtw" not in out and "tail-fisher" not in out


def test_variants_name_their_options_results_and_cache() -> None:
    from benchmarks.unknown_ceiling import Variant

    assert Variant().params() == {"feature_weights": "none"} and Variant().suffix() == ""
    both = Variant("fisher", True)
    assert both.params() == {"feature_weights": "fisher", "velocity": True}
    assert both.suffix() == "_fisher_velocity"


def test_log_signature_of_a_step_by_hand() -> None:
    from benchmarks.unknown_ceiling import SigSpec, log_signatures

    # one channel, two frames at 1: from the basepoint the path (t, x) runs (0, 0) ->
    # (0.5, 1) -> (1, 1). Level 1 the increments (1, 1); level 2 the Levy area of (t, x),
    # 1/2 sum_k [(t_k-1 - t_0) dx_k - (x_k-1 - x_0) dt_k] = 1/2 [0 + (0.5 * 0 - 1 * 0.5)]
    got = log_signatures(np.ones((1, 2, 1)), SigSpec(depth=2, lead_lag=False))
    np.testing.assert_allclose(got, [[1.0, 1.0, -0.25]], atol=1e-12)


def test_signature_terms_match_what_a_window_gives() -> None:
    from benchmarks.unknown_ceiling import SigSpec, log_signatures

    rng = np.random.default_rng(0)
    # a lead-lagged depth-3 window of the eight angles: 17 channels with time,
    # 17 + C(17, 2) + (17^3 - 17) / 3 Lyndon words
    spec = SigSpec("angles", 3, True)
    assert spec.terms() == 17 + 136 + 1632
    assert log_signatures(rng.normal(size=(2, 60, 8)), spec).shape == (2, spec.terms())
    assert SigSpec().suffix() == "" and SigSpec("positions", 2, False).suffix() == (
        "_sig-positions-d2-nolag"
    )


def test_nearest_and_margin_by_hand() -> None:
    from benchmarks.unknown_ceiling import nearest_and_margin

    d = np.array([[1.0, 2.0, 4.0], [3.0, 0.5, 0.6], [0.0, 1.0, 0.0]])
    y = np.array(["a", "a", "b"])
    # nearest of a / of b: 1 / 4, 0.5 / 0.6, 0 / 0 (margin 1 when d2 is 0)
    d1, margin = nearest_and_margin(d, y)
    np.testing.assert_allclose(d1, [1.0, 0.5, 0.0])
    np.testing.assert_allclose(margin, [0.25, 0.5 / 0.6, 1.0])


def test_signature_scores_leave_the_left_out_movements_windows_out() -> None:
    from benchmarks.unknown_ceiling import SIG_FISHER, SigSpec, with_signature

    rng = np.random.default_rng(1)
    n = 20  # windows per person and movement: three people, movements a, b and c
    X = rng.normal(size=(9 * n, 20, 8))
    y = np.repeat(np.array(["a", "b", "c"] * 3, dtype=object), n)
    people = np.repeat(np.array(["p1"] * 3 + ["p2"] * 3 + ["p3"] * 3, dtype=object), n)
    # the test windows: a copy of one of p2's c windows and of one of p3's a windows
    sig = {"X": X, "y": y, "people": people, "test": {"r": X[[5 * n, 6 * n]]}}
    rec = _recording(["c", "a"], ["a", "a"], [0.5, 2.0])
    held = {"known": {"spread-margin": np.array([1.0, 2.0, 3.0])}}
    out = with_signature(
        {"recordings": {"r": rec}, "thresholds": {}}, sig, "c", SigSpec(depth=2), held
    )
    s = out["recordings"]["r"]["scores"]
    # with c left out only a's and b's windows are cases: the a window's twin is among them,
    # the c window's is not (a random window lies far from every other)
    assert s["sig-nearest"][1] == pytest.approx(0.0, abs=1e-9) and s["sig-nearest"][0] > 1.0
    assert s["sig-margin"][1] == pytest.approx(0.0, abs=1e-9) and s["sig-margin"][0] > 0.5
    assert out["sig_cases"] == 6 * n
    assert set(out["thresholds"]) == {"sig-nearest", "sig-margin", "sig-lof"}
    # Fisher of the two tails: the judge's 2.0 at (1 + 2) / 4 among 1, 2, 3; the a window's
    # nearest 0 at (1 + 120) / 121 = 1 among the 120 held-out nearest distances (all above 0)
    assert s[SIG_FISHER][1] == pytest.approx(-2 * math.log(3 / 4))
