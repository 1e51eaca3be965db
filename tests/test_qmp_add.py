"""The Action Description Database: shipped entries, schema validation, criteria on fits."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from features.errors import ConfigError
from features.qmp import fit_signals
from features.qmp.add import default_add_path, evaluate_criteria, load_add, parse_add

UIPRMD_LABELS = {
    "deep_squat",
    "hurdle_step",
    "inline_lunge",
    "side_lunge",
    "sit_to_stand",
    "standing_active_straight_leg_raise",
    "standing_shoulder_abduction",
    "standing_shoulder_extension",
    "standing_shoulder_internal_external_rotation",
    "standing_shoulder_scaption",
}


def test_shipped_add_covers_the_papers_activities_uiprmd_and_hdm05_squat() -> None:
    add = load_add()
    labels = {label for act in add.activities.values() for label in act.labels}
    assert {"squat", "push_up", "jumping_jack", "single_leg_romanian_deadlift"} <= labels
    assert UIPRMD_LABELS <= labels
    assert "squat1Reps" in labels
    for act in add.activities.values():
        assert len(act.sequence) >= 2
        assert all(1 <= s.weight <= 10 for s in act.sequence)
    for name in (
        "knee_oscillation",
        "consistent_leg_distance",
        "arms_in_phase_with_legs",
        "shoulder_translation_synchronised",
    ):
        assert name in add.criteria


def _raw() -> dict:
    return tomllib.loads(default_add_path().read_text())


def _error(raw: dict) -> str:
    with pytest.raises(ConfigError) as exc:
        parse_add(raw, "my_add.toml")
    return str(exc.value)


def test_missing_field_names_entry_and_field() -> None:
    raw = _raw()
    del raw["qmp"]["knee_oscillation"]["words"]
    msg = _error(raw)
    assert "my_add.toml" in msg and "qmp 'knee_oscillation'" in msg and "'words'" in msg

    raw = _raw()
    del raw["activity"]["squat"]["labels"]
    msg = _error(raw)
    assert "activity 'squat'" in msg and "'labels'" in msg


def test_unknown_signal_and_quantity_are_named() -> None:
    raw = _raw()
    raw["qmp"]["knee_oscillation"]["conditions"][0]["signal"] = "{side}_kneee"
    msg = _error(raw)
    assert "qmp 'knee_oscillation'" in msg and "conditions[0]" in msg and "left_kneee" in msg

    raw = _raw()
    raw["qmp"]["knee_oscillation"]["conditions"][0]["quantity"] = "wobble"
    assert "unknown quantity 'wobble'" in _error(raw)


def test_bad_weights_sequences_and_references() -> None:
    raw = _raw()
    raw["activity"]["squat"]["sequence"][0]["weight"] = 11
    msg = _error(raw)
    assert "activity 'squat'" in msg and "sequence[0]" in msg and "'weight'" in msg

    raw = _raw()
    raw["activity"]["squat"]["sequence"] = raw["activity"]["squat"]["sequence"][:1]
    assert "at least two QMPs" in _error(raw)

    raw = _raw()
    raw["activity"]["squat"]["sequence"][1]["qmp"] = "moonwalk"
    assert "unknown qmp 'moonwalk'" in _error(raw)

    raw = _raw()
    raw["qmp"]["knee_oscillation"]["conditions"][0] = {
        "signal": "{side}_knee",
        "quantity": "amplitude",
    }
    assert "'min' or 'max'" in _error(raw)


def test_distance_signals_may_be_written_either_way_round() -> None:
    raw = _raw()
    raw["qmp"]["consistent_leg_distance"]["conditions"][0]["signal"] = "right_heel~left_heel"
    add = parse_add(raw)
    assert add.criteria["consistent_leg_distance"].signals == ("left_heel~right_heel",)


def test_files_that_are_missing_or_not_toml(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not found"):
        load_add(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[qmp.x\nwords = 1")
    with pytest.raises(ConfigError, match="not valid TOML") as exc:
        load_add(bad)
    assert "bad.toml" in str(exc.value)


def test_user_add_file_with_own_activity(tmp_path: Path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text(
        """
schema = 1
[qmp.elbows_pump]
words = "elbows bending and straightening"
sides = "both"
conditions = [{ signal = "{side}_elbow", quantity = "amplitude", min = 0.4 }]
[qmp.still_legs]
words = "legs still"
sides = "both"
conditions = [{ signal = "{side}_knee", quantity = "amplitude", max = 0.2 }]
[activity.curl]
words = "biceps curl"
labels = ["curl"]
sequence = [{ qmp = "elbows_pump", weight = 9 }, { qmp = "still_legs", weight = 4 }]
"""
    )
    add = load_add(path)
    assert list(add.activities) == ["curl"]
    assert set(add.signals) == {"left_elbow", "right_elbow", "left_knee", "right_knee"}


def test_criteria_on_synthetic_knees_in_and_out_of_phase() -> None:
    add = load_add()
    t = np.arange(120) / 30.0
    knee = 2.2 + 0.7 * np.cos(2 * np.pi * t / 2.0)
    knee_late = 2.2 + 0.7 * np.cos(2 * np.pi * t / 2.0 + np.pi)  # half a cycle later
    names = add.signals
    base = np.full((len(t), len(names)), 1.5) + 1e-4 * np.arange(len(names))

    def met(left: np.ndarray, right: np.ndarray) -> dict[str, bool]:
        values = base.copy()
        values[:, names.index("left_knee")] = left
        values[:, names.index("right_knee")] = right
        res = evaluate_criteria(add, fit_signals(values, 30.0, names))
        return {n: bool(m) for n, m in zip(res.names, res.met[0], strict=True)}

    together = met(knee, knee)
    assert together["knee_oscillation"] and together["knees_in_phase"]
    apart = met(knee, knee_late)
    assert apart["knee_oscillation"] and not apart["knees_in_phase"]
    one = met(knee, np.full(len(t), 3.0))
    assert not one["knee_oscillation"] and one["one_knee_oscillation"]


def test_phase_gap_of_a_quarter_cycle() -> None:
    from features.qmp.add import phase_gap

    t = np.arange(150) / 30.0
    a = 2.0 + 0.5 * np.cos(2 * np.pi * t / 1.25)
    b = 2.0 + 0.5 * np.cos(2 * np.pi * t / 1.25 - np.pi / 2)  # a quarter cycle later
    fits = fit_signals(np.stack([a, b, a], 1), 30.0, ["a", "b", "c"])
    assert phase_gap(fits, 0, 1)[0] == pytest.approx(np.pi / 2, abs=0.1)
    assert phase_gap(fits, 0, 2)[0] == pytest.approx(0.0, abs=0.05)


def test_a_relation_missed_for_its_amplitude_says_so() -> None:
    # both knees bend together (phase gap 0, same period) but only 0.1 rad out and back:
    # knees_in_phase asks at least 0.2 rad of each, so the amplitude is what fails and the
    # explanation must show it, not only the phase gap and period ratio that pass
    add = load_add()
    t = np.arange(120) / 30.0
    knee = 2.2 + 0.1 * np.cos(2 * np.pi * t / 2.0)
    names = add.signals
    values = np.full((len(t), len(names)), 1.5) + 1e-4 * np.arange(len(names))
    values[:, names.index("left_knee")] = knee
    values[:, names.index("right_knee")] = knee
    res = evaluate_criteria(add, fit_signals(values, 30.0, names))
    q = res.names.index("knees_in_phase")
    assert not res.met[0, q] and res.observable[0, q]
    (text,) = res.failed[q]
    assert text.startswith("left knee oscillating in phase with right knee (observed phase gap")
    seen = re.search(r"smaller amplitude ([0-9.e-]+)°\)$", text)  # in degrees, as all angles
    assert seen is not None, text
    assert float(seen.group(1)) == pytest.approx(5.73, abs=0.3)  # 0.1 rad
