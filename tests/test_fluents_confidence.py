"""The paper's confidence formulas (eqs. 2-6), the parameter table and unavailable values."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from features.errors import ConfigError
from features.fluents import (
    DEFAULT_TABLE,
    FluentTable,
    confidence_lower,
    confidence_upper,
    evaluate,
    parse_value,
)
from tests.bodies import standing, to_sequence

PI = math.pi
EPS = 1e-3


@pytest.mark.parametrize(
    ("tau", "delta"), [(5 * PI / 8, PI / 8), (19 * PI / 24, PI / 24), (0.5, 0.25)]
)
def test_logistic_at_the_band_edges_and_centre(tau: float, delta: float) -> None:
    x = np.array([tau - delta, tau, tau + delta, tau - 2 * delta, tau + 2 * delta])
    lo = confidence_lower(x, tau, delta, EPS)
    np.testing.assert_allclose(lo, [1 - EPS, 0.5, EPS, 1.0, 0.0], atol=1e-12)
    hi = confidence_upper(x, tau, delta, EPS)
    np.testing.assert_allclose(hi, [EPS, 0.5, 1 - EPS, 0.0, 1.0], atol=1e-12)


def test_logistic_slope_matches_eq_2() -> None:
    tau, delta = 7 * PI / 16, PI / 16
    theta = tau + 0.3 * delta
    k = math.log((1 - EPS) / EPS) / delta
    assert confidence_lower(np.array([theta]), tau, delta, EPS)[0] == pytest.approx(
        1 / (1 + math.exp(k * (theta - tau)))
    )


def test_nan_angle_gives_nan_confidence() -> None:
    out = confidence_lower(np.array([np.nan]), 1.0, 0.1, EPS)
    assert np.isnan(out[0])


def _elbow_sequence(angles: np.ndarray, fps: float = 30.0):  # type: ignore[no-untyped-def]
    """A left elbow whose angle follows ``angles`` (radians), the rest standing still."""
    frames = []
    for a in angles:
        body = standing()
        # upper arm straight down from the shoulder; forearm at angle a from the upper arm,
        # swinging forward (in the sagittal plane)
        elbow = body["left_elbow"]
        body["left_wrist"] = elbow + 0.25 * np.array([0.0, -math.cos(PI - a), math.sin(PI - a)])
        frames.append(body)
    return to_sequence(*frames, fps=fps)


# The float64 reference to ~1e-15; the compiled kernel computes in float32: within 1e-6.
BACKENDS = [("numpy", {"rel": 1e-9}), ("numba", {"abs": 1e-6})]


@pytest.mark.parametrize(("backend", "tol"), BACKENDS)
def test_temporal_product_on_a_hand_made_angle_sequence(backend: str, tol: dict) -> None:
    # The elbow closes by exactly pi/72 per frame: each frame's "toward bent" confidence is the
    # logistic at its centre, 0.5, and the straightening one is 0 (beyond the band).
    angles = PI - 0.2 - np.arange(8) * PI / 72
    result = evaluate(_elbow_sequence(angles), backend=backend)  # type: ignore[arg-type]
    bending = result.column("left_arm_bent.bending")
    straightening = result.column("left_arm_bent.straightening")
    steady = result.column("left_arm_bent.bend_steady")
    assert np.isnan(bending[0])  # no previous frame: no motion can be measured
    # frame f uses the min(f, 5) newest changes with exponents 1, 1/2, 1/3, ...
    for f in range(1, 8):
        exponent = sum(1 / (a + 1) for a in range(min(f, 5)))
        assert bending[f] == pytest.approx(0.5**exponent, **tol)
        assert straightening[f] == 0.0
        assert steady[f] == pytest.approx((1 - 0.5**exponent) * 1.0, **tol)


@pytest.mark.parametrize(("backend", "tol"), BACKENDS)
def test_one_still_frame_in_the_window_stops_the_motion(backend: str, tol: dict) -> None:
    angles = PI - 0.2 - np.array([0, 1, 2, 3, 3, 4, 5, 6, 7, 8, 9]) * PI / 24
    result = evaluate(_elbow_sequence(angles), backend=backend)  # type: ignore[arg-type]
    bending = result.column("left_arm_bent.bending")
    # Changes of pi/24 are beyond the band (confidence 1). A zero change sits exactly on the
    # band's edge tau + delta = 0, confidence epsilon; it weighs in with exponent 1/(age + 1)
    # while it is inside the window (frames 4..8), then bending resumes.
    assert bending[3] == 1.0
    for age in range(5):
        assert bending[4 + age] == pytest.approx(EPS ** (1 / (age + 1)), **tol)
    assert bending[9] == 1.0


def test_temporal_confidence_does_not_depend_on_frame_rate() -> None:
    # The same motion (elbow closing at pi/36 per 1/30 s) filmed at 30 and at 60 fps.
    # The same motion, the elbow closing at 0.9 * pi/72 per 1/30 s, filmed at 30 and 60 fps:
    # frame f at 30 fps and frame 2f at 60 fps are the same instant and must agree once the
    # window is full.
    speed = 30 * 0.9 * PI / 72  # rad/s
    b30 = evaluate(_elbow_sequence(PI - 0.2 - speed * np.arange(12) / 30, fps=30))
    b60 = evaluate(_elbow_sequence(PI - 0.2 - speed * np.arange(24) / 60, fps=60))
    bend30 = b30.column("left_arm_bent.bending")
    bend60 = b60.column("left_arm_bent.bending")
    assert 0.01 < bend30[8] < 0.99  # inside the logistic band, so the comparison has teeth
    for f in range(5, 12):
        assert bend60[2 * f] == pytest.approx(bend30[f], rel=1e-9)


def test_single_frame_clip_has_instantaneous_but_no_temporal_fluents() -> None:
    result = evaluate(to_sequence(standing()))
    assert result.confidence.shape == (1, len(result.state_names))
    inst = result.confidence[0, ~result.temporal]
    temporal = result.confidence[0, result.temporal]
    assert np.isnan(temporal).all()
    assert np.isfinite(inst).all()


def test_missing_and_zero_length_links_are_unavailable_not_zero() -> None:
    body = standing()
    body["left_elbow"] = body["left_shoulder"].copy()  # zero-length upper arm
    del body["right_wrist"]  # joint missing from the skeleton -> NaN
    body["left_knee"] = np.array([np.nan, np.nan, np.nan])
    result = evaluate(to_sequence(body))
    c = dict(zip(result.state_names, result.confidence[0], strict=True))
    assert np.isnan(c["left_arm_bent.bent"]) and np.isnan(c["left_arm_bent.straight"])
    assert np.isnan(c["left_arm_raised.raised"])
    assert np.isnan(c["right_arm_bent.bent"])
    assert np.isnan(c["left_leg_bent.bent"]) and np.isnan(c["left_leg_raised.raised"])
    assert c["right_leg_bent.straight"] > 0.99  # the rest is still computed


def test_parse_value_reads_multiples_of_pi() -> None:
    assert parse_value("5pi/8", "t") == pytest.approx(5 * PI / 8)
    assert parse_value("pi/72", "t") == pytest.approx(PI / 72)
    assert parse_value("0.25", "t") == 0.25
    assert parse_value(2, "t") == 2.0
    with pytest.raises(ConfigError):
        parse_value("five", "t")


def test_table_override_from_file(tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "t.json"
    path.write_text(json.dumps({"window": 3, "fluents": {"leg_bent": {"lower": {"tau": "3pi/4"}}}}))
    table = FluentTable.from_file(path)
    assert table.window == 3
    for side in ("left", "right"):
        spec = table.spec(f"{side}_leg_bent")
        assert spec.lower.tau == pytest.approx(3 * PI / 4)
        assert spec.lower.delta == pytest.approx(PI / 24)  # untouched
    assert DEFAULT_TABLE.spec("left_leg_bent").lower.tau == pytest.approx(19 * PI / 24)
    toml = tmp_path / "t.toml"
    toml.write_text('[fluents.left_arm_raised.upper]\ntau = "pi/2"\n')
    assert FluentTable.from_file(toml).spec("left_arm_raised").upper.tau == pytest.approx(PI / 2)  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("content", "needle"),
    [
        ('{"fluents": {"elbow_wiggle": {}}}', "unknown fluent"),
        ('{"fluents": {"arm_bent": {"upper": {"tau": 1}}}}', "no such boundary"),
        ('{"fluents": {"arm_bent": {"lower": {"delta": -1}}}}', "delta must be positive"),
        ('{"window": 0}', "window"),
        ('{"windw": 5}', "unknown setting"),
        ("{not json", "malformed"),
    ],
)
def test_malformed_threshold_files_name_the_problem(tmp_path, content: str, needle: str) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "t.json"
    path.write_text(content)
    with pytest.raises(ConfigError) as err:
        FluentTable.from_file(path)
    assert needle in str(err.value)
    assert str(path) in str(err.value)
