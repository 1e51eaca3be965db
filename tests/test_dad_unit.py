"""DAD pieces with hand-worked answers: in-order matching, a motionless body, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cbr.dad import NOT_ENOUGH_DATA, DADClassifier, DADConfig, detect, ordered_match
from features.errors import ConfigError
from features.poses import PoseSequence
from tests.bodies import standing, to_sequence


def test_ordered_match_prefers_the_heaviest_in_order_chain() -> None:
    # Steps A(5) B(3) C(2); windows 0..2. A only in 0, B anywhere, C never: A then B = 8.
    met = np.array([[1, 0, 0], [1, 1, 1], [0, 0, 0]], dtype=bool)
    total, chosen = ordered_match(met, [5, 3, 2])
    assert total == 8 and chosen[0] == 0 and chosen[1] is not None and chosen[2] is None
    # A only late, B only early: they cannot both count in order; the heavier A wins.
    total, chosen = ordered_match(np.array([[0, 0, 1], [1, 0, 0]], dtype=bool), [5, 3])
    assert (total, chosen) == (5, [2, None])
    # Skipping A (weight 2) lets B(3) then C(4) count: 7 beats A alone or A+C (6).
    met = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 1]], dtype=bool)
    total, chosen = ordered_match(met, [2, 3, 4])
    assert total == 7 and chosen[:2] == [None, 0] and chosen[2] in (1, 2)
    # QMPs that hold in the same window satisfy any order.
    assert ordered_match(np.array([[0, 1], [0, 1]], dtype=bool), [1, 1])[0] == 2


def _still(seconds: float) -> PoseSequence:
    body = standing()
    return to_sequence(*[body] * int(seconds * 30), fps=30.0)


def test_motionless_person_is_not_squatting() -> None:
    result = detect(_still(3.0))
    assert result.status == "ok"
    squat = next(a for a in result.activities if a.activity == "squat")
    knee = next(q for q in squat.qmps if q.qmp == "knee_oscillation")
    assert knee.status == "not met"
    assert any("knee amplitude" in r and "observed 0" in r for r in knee.reasons)
    assert "legs_steady" in result.detected[0]
    assert squat.score < 0.5


def test_clip_shorter_than_a_window_is_one_window_and_too_short_is_not_enough_data() -> None:
    result = detect(_still(2.0), config=DADConfig(window_s=4.0))
    assert len(result.windows_s) == 1 and result.windows_s[0] == (0.0, 2.0)
    short = detect(_still(0.2))
    assert short.status == NOT_ENOUGH_DATA and short.activities == ()
    assert "0.20 s" in short.message
    clf = DADClassifier().fit([_still(0.2)], ["squat"])
    assert clf.predict([_still(0.2)]).tolist() == ["squat"]  # the only class; no crash


def test_joints_missing_everywhere_is_not_enough_data() -> None:
    seq = _still(2.0)
    blank = PoseSequence(np.full_like(seq.positions, np.nan), seq.joint_names, seq.fps)
    result = detect(blank)
    assert result.status == NOT_ENOUGH_DATA
    assert result.to_dict()["status"] == NOT_ENOUGH_DATA


def test_malformed_add_is_a_config_error(tmp_path: Path) -> None:
    path = tmp_path / "add.toml"
    path.write_text(
        'schema = 1\n[qmp.a]\nwords = "a"\nconditions = [{ signal = "left_wing", '
        'quantity = "amplitude", min = 1 }]\n[activity.x]\nwords = "x"\nlabels = ["x"]\n'
        'sequence = [{ qmp = "a", weight = 1 }, { qmp = "a", weight = 2 }]\n'
    )
    with pytest.raises(ConfigError, match="unknown signal 'left_wing'"):
        detect(_still(2.0), add=path)


def test_classifier_follows_the_sklearn_contract() -> None:
    from sklearn.base import clone
    from sklearn.exceptions import NotFittedError

    clf = clone(DADClassifier(window_s=3.0))
    assert clf.get_params() == {"add": None, "window_s": 3.0, "step_s": None}
    with pytest.raises(NotFittedError, match="not fitted"):
        clf.predict([_still(2.0)])
    X, y = [_still(2.0), _still(2.5)], ["standing_shoulder_abduction", "squat"]
    clf.fit(X, y)
    assert list(clf.classes_) == ["squat", "standing_shoulder_abduction"]
    pred = clf.predict(X)
    assert set(pred) <= set(clf.classes_)
    assert clf.score(X, y) == np.mean(pred == np.asarray(y))
