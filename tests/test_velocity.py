"""The velocity feature option (issue 14's look-alike movements): the summary statistics of
every column's rate of change, stored with the fitted model.

Values are worked out by hand from sequences built for the test; the clips are
tests.test_cbr_weights' hand-built arm movements."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.explain import quantity
from cbr.problem import (
    FeatureConfig,
    candidate_config,
    column_index,
    extract_problem,
    problem_columns,
    resolve_config,
    summarise,
)
from features.errors import ConfigError
from tests.test_cbr_sides import _data
from tests.test_cbr_weights import _arm_clip


def test_rates_of_change_by_hand() -> None:
    # three resampled frames: a goes 0, 1, 3 (steps 1 and 2), b 1, 1, 0 (steps 0 and -1);
    # per clip length (two steps make the clip) the rates are twice the steps
    values = np.array([[0.0, 1.0], [1.0, 1.0], [3.0, 0.0]])
    p = summarise(values, ("a", "b"), ("A", "B"), velocity=True)
    assert p.names[8:] == ("a@rate_mean", "b@rate_mean", "a@rate_min", "b@rate_min",
                           "a@rate_max", "b@rate_max", "a@rate_std", "b@rate_std")  # fmt: skip
    # a's rates 2, 4: mean 3, least 2, most 4, spread 1; b's 0, -2: -1, -2, 0, 1
    np.testing.assert_allclose(p.values[8:], [3, -1, 2, -2, 4, 0, 1, 1])
    # the plain statistics are those without the option
    np.testing.assert_allclose(p.values[:8], summarise(values, ("a", "b"), ("A", "B")).values)
    assert p.words[8] == "A rate of change (mean)" and p.words[14] == "A rate of change (variation)"


def test_rates_come_before_the_phase_means() -> None:
    # 0, 1, ..., 8: the rate is 8 (per clip length) at every step; thirds' means 1, 4, 7
    values = np.arange(9.0)[:, None]
    p = summarise(values, ("angle:left_knee",), ("left knee angle",), phases=3, velocity=True)
    np.testing.assert_allclose(
        p.values, [4.0, 0.0, 8.0, np.std(np.arange(9.0)), 8.0, 8.0, 8.0, 0.0, 1.0, 4.0, 7.0]
    )
    assert p.names[-1] == "angle:left_knee@phase3" and p.names[4] == "angle:left_knee@rate_mean"


def test_a_clip_described_once_over_the_candidates_gives_its_problem() -> None:
    rng = np.random.default_rng(2)
    clips = [_arm_clip("right", "sideways", "s1", rng), _arm_clip("left", "forward", "s1", rng)]
    config = resolve_config(
        FeatureConfig(length=8, angles=True, summary=True, phases=3, velocity=True), clips
    )
    candidates = candidate_config(config)
    whole = extract_problem(clips[0], candidates).values
    mine = extract_problem(clips[0], config)
    np.testing.assert_array_equal(whole[column_index(config, candidates)], mine.values)
    assert mine.names == problem_columns(config)[0]
    # 4 statistics, 4 of the rates, 3 phase means of every column
    assert len(mine.values) == 11 * len(config.states)


def test_off_leaves_the_stored_configuration_as_it_was() -> None:
    plain = FeatureConfig(summary=True)
    assert "velocity" not in plain.to_dict()  # the configuration hash of old case bases
    on = FeatureConfig(summary=True, velocity=True)
    assert on.to_dict()["velocity"] is True
    assert FeatureConfig.from_dict(on.to_dict()) == on
    assert "with rates of change" in on.describe()


def test_rates_need_clip_summaries() -> None:
    with pytest.raises(
        ConfigError, match="^velocity: rates of change need fluent-level clip summaries"
    ):
        FeatureConfig(velocity=True)
    with pytest.raises(ConfigError, match="velocity: must be"):
        FeatureConfig(summary=True, velocity="yes")  # type: ignore[arg-type]
    X, y = _data({"s1": "right", "s2": "right"}, 1, 0)
    with pytest.raises(ConfigError, match="velocity: must be True or False"):
        CaseBaseClassifier(velocity="yes").fit(X, y)  # type: ignore[arg-type]


def test_a_rate_is_said_as_a_plain_number() -> None:
    assert quantity("angle:left_knee@rate_max", 0.5) == (0.5, "")
    assert quantity("angle:left_knee@max", 0.5) == (90.0, "degrees")


def test_the_stored_model_keeps_the_rates(tmp_path: Path) -> None:
    from casebase_store import open_store
    from cbr.stored import load_classifier
    from cbr.training import store_fitted

    X, y = _data({"s1": "right", "s2": "right", "s3": "right"}, 2, 3)
    clf = CaseBaseClassifier(k=1, velocity=True, mirror="off", feature_weights="none").fit(X, y)
    assert clf.feature_config_.velocity
    n = len(clf.feature_config_.states)
    assert len(clf.case_base_.names) == 8 * n + n * clf.phases_
    db = tmp_path / "cb.sqlite"
    store_fitted(db, "default", clf, y)
    store = open_store(str(db), readonly=True)
    try:
        loaded = load_classifier(store, "default").classifier
    finally:
        store.close()
    assert loaded.feature_config_.velocity
    assert loaded.case_base_.names == clf.case_base_.names
    rng = np.random.default_rng(9)
    new = [_arm_clip("right", "sideways", "s9", rng), _arm_clip("both", "forward", "s9", rng)]
    assert list(loaded.predict(new)) == list(clf.predict(new))
