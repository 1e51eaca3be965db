"""A confidence that is a probability and a flag calibrated per case base.

Expected values are worked out by hand (ECE bins, quantiles), come from a peer library
(scikit-learn's Platt scaling), or are the issue's own observations on the bundled demo (the
QMP case base flagged 38 of 60 ordinary clips)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from casebase_store import StoreError
from cbr.calibration import (
    UNCALIBRATED,
    ConfidenceCalibration,
    calibrate_confidence,
    ece_if_calibrated,
    ece_interval,
    expected_calibration_error,
    log_odds,
    platt,
)
from cbr.estimator import CaseBaseClassifier
from cbr.novelty import NoveltyCalibration, from_distances
from cbr.stored import _confidence
from features.datasets import load_dataset

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd" / "labels.csv"


def test_expected_calibration_error_by_hand() -> None:
    # ten clips at 0.95 of which nine right: one bin, |0.9 - 0.95| = 0.05
    assert expected_calibration_error(np.full(10, 0.95), np.array([1] * 9 + [0])) == (
        pytest.approx(0.05)
    )
    # two bins of five: 0.55 with 3 right (gap 0.05), 0.85 with 5 right (gap 0.15)
    conf = np.array([0.55] * 5 + [0.85] * 5)
    right = np.array([1, 1, 1, 0, 0] + [1] * 5)
    assert expected_calibration_error(conf, right) == pytest.approx(0.5 * 0.05 + 0.5 * 0.15)
    # a perfectly calibrated set scores 0
    assert expected_calibration_error(np.array([1.0, 1.0, 0.5, 0.5]), np.array([1, 1, 1, 0])) == 0


def test_ece_interval_is_the_binomial_spread_of_one_bin() -> None:
    # 100 clips at 0.5, 50 right: one bin, so a resample's ECE is |B / 100 - 0.5| with B the
    # right clips drawn, B ~ Binomial(100, 0.5); P(|B - 50| <= 9) = 0.944 and
    # P(|B - 50| <= 10) = 0.965 (binomial tables), so the 97.5th percentile is 0.10 or 0.11,
    # the lower end 0.00 (|B - 50| = 0 has probability 0.080)
    lo, hi = ece_interval(np.full(100, 0.5), np.array([1, 0] * 50))
    assert lo == pytest.approx(0.0) and hi in (pytest.approx(0.10), pytest.approx(0.11))
    # every clip right at confidence 1: every resample scores 0
    assert ece_interval(np.ones(20), np.ones(20, dtype=bool)) == (0.0, 0.0)
    # the interval holds the ECE of the clips themselves
    conf = np.array([0.55] * 5 + [0.85] * 5)
    right = np.array([1, 1, 1, 0, 0] + [1] * 5)
    lo, hi = ece_interval(conf, right)
    assert lo <= expected_calibration_error(conf, right) <= hi


def test_platt_scaling_agrees_with_scikit_learn() -> None:
    from sklearn.calibration import _sigmoid_calibration  # the peer: Platt's method

    rng = np.random.default_rng(3)
    share = rng.uniform(0.2, 1.0, 300)
    right = rng.uniform(size=300) < share**2  # right more often at higher shares
    a, b = platt(log_odds(share), right)
    A, B = _sigmoid_calibration(log_odds(share), right.astype(float))
    # scikit-learn writes P = 1 / (1 + exp(A f + B)): A = -a, B = -b
    assert a == pytest.approx(-A, abs=1e-3) and b == pytest.approx(-B, abs=1e-3)
    cal = calibrate_confidence(share, right, "leave-one-subject-out")
    expected = 1.0 / (1.0 + np.exp(-(a * log_odds(np.array([0.5, 0.9])) + b)))
    assert [cal(0.5), cal(0.9)] == pytest.approx(expected.tolist(), abs=1e-9)
    assert np.all(np.diff(cal.y) >= 0) and 0.0 < cal.y[0] and cal.y[-1] < 1.0
    assert cal.n == 300 and cal.accuracy == pytest.approx(right.mean())
    assert ConfidenceCalibration.from_dict(cal.to_dict()) == cal


def test_a_case_base_right_every_time_held_out_is_not_certain() -> None:
    # 18 held-out clips all right: Laplace's rule of succession, (18 + 1) / (18 + 2)
    cal = calibrate_confidence(np.full(18, 1.0), np.ones(18, dtype=bool), "x")
    assert cal(1.0) == pytest.approx(19 / 20) and cal(0.4) == pytest.approx(19 / 20)


def test_a_case_base_stored_without_calibration_answers_with_the_vote_share() -> None:
    assert _confidence({}, "cb", "x.sqlite") is UNCALIBRATED and UNCALIBRATED(0.8) == 0.8
    # a case base fitted with no held-out clip stores the vote share: read back as such
    stored = json.loads(json.dumps({"confidence": UNCALIBRATED.to_dict()}))
    assert _confidence(stored, "cb", "x.sqlite")(0.8) == 0.8


def test_a_damaged_stored_calibration_is_refused_not_replaced() -> None:
    bad = {"confidence": {"x": [0.5, 0.4], "y": [0.1, 0.2], "basis": "x", "n": 2,
                          "accuracy": 0.5}}  # fmt: skip
    with pytest.raises(StoreError) as err:  # knots out of order: refused, not trusted
        _confidence(bad, "cb", "x.sqlite")
    assert "case base 'cb' has a damaged confidence calibration" in err.value.message
    assert "paired and increasing" in err.value.message and "x.sqlite" in str(err.value)


def test_novelty_unit_leaves_exact_matches_out() -> None:
    # binary QMP vectors: most held-out clips match a case exactly (distance ~0 after float32
    # rounding); the unit is the median of the others, the flag their 99th percentile
    d = np.array([1e-4] * 60 + [1.0, 2.0, 3.0, 4.0, 5.0] * 8)
    cal = from_distances(d, "leave-one-subject-out")
    assert cal.scale == pytest.approx(3.0)
    assert cal.unlike_ratio == pytest.approx(np.quantile(d, 0.99) / 3.0)
    assert not cal.unlike(5.0) and cal.unlike(5.1)
    assert cal.reason(5.1) == "distance" and cal.reason(1.0) == ""


def test_a_clip_recorded_with_another_skeleton_is_unlike_the_cases() -> None:
    cal = NoveltyCalibration(1.0, 2.0, 0.99, "leave-one-subject-out", 10, ("uiprmd_kinect",))
    assert cal.reason(0.5, "uiprmd_kinect") == "" and cal.reason(0.5, "asf_amc") == "sensor"
    assert cal.reason(0.5, None) == ""  # a clip that names no skeleton is judged by distance
    assert NoveltyCalibration.from_dict(cal.to_dict()) == cal
    old = {k: v for k, v in cal.to_dict().items() if k != "skeletons"}  # before skeletons
    assert NoveltyCalibration.from_dict(old).reason(0.5, "asf_amc") == ""


def test_the_demo_qmp_case_base_flags_few_ordinary_clips() -> None:
    train = load_dataset(DEMO, subjects={"s01", "s02"})
    test = load_dataset(DEMO, subjects={"s03"})
    clf = CaseBaseClassifier(features="qmp").fit([c.seq for c in train], [c.label for c in train])
    flagged = sum(s.unlike_cases for s in clf.solve([c.seq for c in test]))
    # the issue saw 38 of 60 flagged: the unit was the float32 rounding of exact matches
    assert flagged <= 6, f"{flagged} of 60 ordinary clips flagged"


def test_a_perfect_confidence_scores_the_binomial_noise() -> None:
    # every clip at 0.5: one bin, and a resample's ECE is |B / 100 - 0.5|, B ~ Binomial(100,
    # 0.5); P(|B - 50| <= 3) = 0.516 and <= 2 is 0.383, so the median is 0.03; P(|B - 50| <= 9)
    # = 0.943 and <= 10 is 0.965 (binomial tables): the 95th percentile is 0.10 (0.09 to 0.10
    # from 2,000 draws)
    mid, high = ece_if_calibrated(np.full(100, 0.5))
    assert mid == pytest.approx(0.03) and 0.09 - 1e-9 <= high <= 0.10 + 1e-9
    assert ece_if_calibrated(np.ones(30)) == (0.0, 0.0)  # certain and right: no noise


def test_a_calibrated_confidence_scores_within_the_noise_of_one() -> None:
    # answers right with exactly their confidence (drawn with known probabilities): their ECE
    # lies below the 95th percentile of what a perfectly calibrated confidence scores in 19 of
    # 20 draws; answers right 15 points less often than their confidence lie above it
    rng = np.random.default_rng(5)
    conf = rng.uniform(0.5, 1.0, (20, 300))
    right = rng.uniform(size=(20, 300)) < conf
    worse = rng.uniform(size=(20, 300)) < conf - 0.15
    below = [expected_calibration_error(c, r) <= ece_if_calibrated(c)[1] for c, r in
             zip(conf, right, strict=True)]  # fmt: skip
    above = [expected_calibration_error(c, r) > ece_if_calibrated(c)[1] for c, r in
             zip(conf, worse, strict=True)]  # fmt: skip
    assert sum(below) >= 17 and all(above)
