"""Hunt 48h3: the fluents and QMP basis pinned to SPEC.md's numbers, worked out here by hand.

Until now no test failed if a fluent's threshold changed (the synthetic bodies sit far from
every band, > 0.999), nor if a bound's comparison flipped between < and <= in the compiled
kernel, nor if a motion threshold or the touching distance moved. Each test below writes the
SPEC's value itself (radians as multiples of pi, head-lengths, metres) and computes the
expected confidence from SPEC's formula with plain Python, never from the project's functions:

- instantaneous: C(s0) = 1 if x < tau - delta, 0 if x > tau + delta, else
  1 / (1 + exp(k (x - tau))), k = ln((1 - eps) / eps) / delta, eps = 1e-3; s2 the mirror
  image; a middle state (1 - C(s0)) (1 - C(s2)) (a tilt pair's: over both directions, paper
  section "Tilted"); a two-state fluent's states sum to 1;
- locally temporal: the change per frame at 30 fps compared with tau = -/+ pi/72 (near:
  0.05 head-lengths), delta the same, multiplied over r = 5 frames with exponents 1/(age + 1);
- touching: the distance in raw units (metres) <= 0.1, binary, whatever the head-length;
- each angle from a synthetic body posed by hand (tests/bodies.py: facing +z, y up, left +x).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from features.fluents import evaluate
from features.signals import ANGLE_SIGNALS, NEAR_SIGNALS, StateSignals, near_pairs, state_signals
from tests.bodies import HEAD, UPPER_BODY, rot_x, rot_y, rot_z, rotate, standing, to_sequence

PI = math.pi
EPS = 1e-3
BACKENDS = ("numba", "numpy")
# the compiled kernel computes in float32 (within 1e-6 of the float64 reference); exact 0 and
# 1 stay exact in both
TOL = {"numba": 2e-6, "numpy": 1e-12}

Q1, Q3 = (7 * PI / 16, PI / 16), (9 * PI / 16, PI / 16)
FRONT, OUT = ("in_front", "centered", "behind"), ("outward", "at_side", "inward")
# SPEC's fluent table: fluent -> (angle signal, states s0..sn, lower (tau, delta), upper or None,
# motion toward s0, motion toward sn). The state and motion names are the project's words for
# SPEC's (bent / straight, ...); what is pinned is which one holds at small angles.
SPEC_TABLE: dict[str, tuple[str, tuple[str, ...], tuple[float, float],
                            tuple[float, float] | None, str, str]] = {}  # fmt: skip
for _side in ("left", "right"):
    SPEC_TABLE.update({
        f"{_side}_arm_bent": (f"{_side}_elbow", ("bent", "straight"), (5 * PI / 8, PI / 8),
                              None, "bending", "straightening"),
        f"{_side}_leg_bent": (f"{_side}_knee", ("bent", "straight"), (19 * PI / 24, PI / 24),
                              None, "bending", "straightening"),
        f"{_side}_arm_in_front": (f"{_side}_upper_arm_sagittal", FRONT, Q1, Q3,
                                  "moving_forward", "moving_backward"),
        f"{_side}_leg_in_front": (f"{_side}_upper_leg_sagittal", FRONT, Q1, Q3,
                                  "moving_forward", "moving_backward"),
        f"{_side}_arm_raised": (f"{_side}_armpit", ("lowered", "chest_level", "raised"),
                                (3 * PI / 8, PI / 8), Q3, "lowering", "raising"),
        f"{_side}_leg_raised": (f"{_side}_hip", ("raised", "lowered"), (13 * PI / 16, PI / 16),
                                None, "raising", "lowering"),
        f"{_side}_arm_outward": (f"{_side}_upper_arm_frontal", OUT, Q1, Q3,
                                 "moving_outward", "moving_inward"),
        f"{_side}_leg_outward": (f"{_side}_upper_leg_frontal", OUT, Q1, Q3,
                                 "moving_outward", "moving_inward"),
    })  # fmt: skip
for _part, _neck in (("head", "neck"), ("torso", "torso")):
    SPEC_TABLE.update({
        f"{_part}_tilted_forward": (f"{_neck}_sagittal",
                                    ("tilted_forward", "upright", "tilted_backward"), Q1, Q3,
                                    "tilting_forward", "tilting_backward"),
        f"{_part}_tilted_left": (f"{_neck}_frontal", ("tilted_left", "upright", "tilted_right"),
                                 Q1, Q3, "tilting_left", "tilting_right"),
        f"{_part}_twisted": (f"{_neck}_transverse", ("twisted_left", "centered", "twisted_right"),
                             Q1, Q3, "twisting_left", "twisting_right"),
    })  # fmt: skip
# the no-motion state's name, by fluent family
_STEADY_WORDS = {"arm_bent": "bend_steady", "leg_bent": "bend_steady",
                 "in_front": "front_back_steady", "raised": "height_steady",
                 "outward": "sideways_steady", "tilted": "tilt_steady", "twisted": "twist_steady",
                 "near": "keeping_distance_to"}  # fmt: skip
TILT_PAIRS = {
    "head_tilted_forward": "head_tilted_left",
    "torso_tilted_forward": "torso_tilted_left",
}
NEAR = (0.5, 0.25)  # head-lengths
STEADY = {
    f: next(w for key, w in _STEADY_WORDS.items() if key in f)
    for f in [*SPEC_TABLE, *(f"near:{a}~{b}" for a, b in near_pairs())]
}
MOTION_ANGLE, MOTION_NEAR = PI / 72, 0.05  # per frame at 30 fps: rad, head-lengths


def lower(x: float, tau: float, delta: float) -> float:
    """SPEC's lower state, from its words."""
    if math.isnan(x):
        return math.nan
    if x < tau - delta:
        return 1.0
    if x > tau + delta:
        return 0.0
    k = math.log((1 - EPS) / EPS) / delta
    return 1.0 / (1.0 + math.exp(k * (x - tau)))


def _sweep(tau: float, delta: float) -> list[float]:
    """Both edges of the band exactly (where < and <= differ), its centre, and beyond."""
    return [tau - 2 * delta, tau - delta, tau - 0.4 * delta, tau, tau + 0.7 * delta,
            tau + delta, tau + 3 * delta]  # fmt: skip


def _signals(values: np.ndarray, distances_m: np.ndarray | None = None) -> StateSignals:
    frames = values.shape[0]
    if distances_m is None:
        distances_m = np.full((frames, len(NEAR_SIGNALS)), np.nan)
    return StateSignals(
        ANGLE_SIGNALS + NEAR_SIGNALS, values, 30.0, np.full(frames, 0.3), distances_m
    )


def _evaluate(values: np.ndarray, backend: str, distances_m: np.ndarray | None = None) -> dict:
    body = standing()
    seq = to_sequence(*[body] * values.shape[0], fps=30.0)
    result = evaluate(seq, signals=_signals(values, distances_m), backend=backend)  # type: ignore[arg-type]
    return dict(zip(result.state_names, np.asarray(result.confidence, np.float64).T, strict=True))


def _instantaneous_sweeps() -> np.ndarray:
    """Every signal sweeps its fluent's lower band, then its upper band (14 frames)."""
    names = ANGLE_SIGNALS + NEAR_SIGNALS
    values = np.full((14, len(names)), np.nan)
    for signal, _states, lo, up, _m0, _m1 in SPEC_TABLE.values():
        values[:, names.index(signal)] = _sweep(*lo) + _sweep(*(up or lo))
    for a, b in near_pairs():
        values[:, names.index(f"{a}~{b}")] = _sweep(*NEAR) + _sweep(*NEAR)
    return values


def _extremes(fluent: str, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """C(s0) and C(s2) of a three-state fluent by SPEC's formula, from its swept signal."""
    signal, _states, lo, up, _m0, _m1 = SPEC_TABLE[fluent]
    assert up is not None
    x = values[:, (ANGLE_SIGNALS + NEAR_SIGNALS).index(signal)]
    return np.array([lower(v, *lo) for v in x]), np.array([1 - lower(v, *up) for v in x])


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_angle_fluent_has_the_spec_thresholds_and_state_order(backend: str) -> None:
    values = _instantaneous_sweeps()
    c = _evaluate(values, backend)
    tol = TOL[backend]
    for fluent, (signal, states, lo, up, _m0, _m1) in SPEC_TABLE.items():
        x = values[:, (ANGLE_SIGNALS + NEAR_SIGNALS).index(signal)]
        c0 = np.array([lower(v, *lo) for v in x])
        got = [c.get(f"{fluent}.{state}") for state in states]
        np.testing.assert_allclose(got[0], c0, atol=tol, err_msg=f"{fluent}.{states[0]}")
        if up is None:  # two states summing to 1
            np.testing.assert_allclose(got[1], 1 - c0, atol=tol, err_msg=fluent)
            continue
        c2 = _extremes(fluent, values)[1]
        np.testing.assert_allclose(got[2], c2, atol=tol, err_msg=f"{fluent}.{states[2]}")
        if fluent in TILT_PAIRS.values():  # its middle state is the pair's one
            assert got[1] is None
            continue
        middle = (1 - c0) * (1 - c2)
        if fluent in TILT_PAIRS:  # upright: neither extreme in either direction
            o0, o2 = _extremes(TILT_PAIRS[fluent], values)
            middle = middle * (1 - o0) * (1 - o2)
        np.testing.assert_allclose(got[1], middle, atol=tol, err_msg=f"{fluent}.{states[1]}")
    assert len(SPEC_TABLE) == 22  # 8 sided families x 2 sides, 2 tilt pairs, 2 twists


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_near_pair_has_the_spec_thresholds_in_head_lengths(backend: str) -> None:
    values = _instantaneous_sweeps()
    c = _evaluate(values, backend)
    expected = np.array([lower(v, *NEAR) for v in _sweep(*NEAR) * 2])
    for a, b in near_pairs():
        np.testing.assert_allclose(c[f"near:{a}~{b}.near"], expected, atol=TOL[backend])
        np.testing.assert_allclose(c[f"near:{a}~{b}.far_from"], 1 - expected, atol=TOL[backend])


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("direction", [-1.0, 1.0])
@pytest.mark.parametrize("share", [1.0, 0.5])
def test_every_motion_threshold_is_the_spec_one_per_frame_at_30_fps(
    backend: str, direction: float, share: float
) -> None:
    """Every signal changes by ``share`` of its motion threshold each frame, toward s0
    (direction -1) or sn. At the full threshold the state toward that side sits at its band's
    centre (0.5 a frame, so 0.5^(1 + 1/2 + ...) over the window); at half of it, halfway into
    the band (which pins delta); the other side is beyond its band (exactly 0)."""
    names = ANGLE_SIGNALS + NEAR_SIGNALS
    frames = 8
    step = np.array([MOTION_NEAR if "~" in n else MOTION_ANGLE for n in names])
    values = 1.0 + direction * share * np.arange(frames)[:, None] * step[None, :]
    c = _evaluate(values, backend)
    # one frame's confidence, the same for angles and head-lengths (the band scales with tau)
    frame = lower(-share, -1.0, 1.0)
    toward = [frame ** sum(1 / (a + 1) for a in range(min(f, 5))) for f in range(1, frames)]
    toward_s0 = np.array(toward) if direction < 0 else np.zeros(frames - 1)
    toward_sn = np.array(toward) if direction > 0 else np.zeros(frames - 1)
    motions = {f: (m0, m1) for f, (_s, _st, _lo, _up, m0, m1) in SPEC_TABLE.items()}
    motions.update({f"near:{a}~{b}": ("approaching", "moving_away_from") for a, b in near_pairs()})
    still = (1 - toward_s0) * (1 - toward_sn)
    for fluent, (m0, m1) in motions.items():
        got0, got1 = c[f"{fluent}.{m0}"], c[f"{fluent}.{m1}"]
        assert np.isnan(got0[0]) and np.isnan(got1[0])  # no change before the first frame
        np.testing.assert_allclose(got0[1:], toward_s0, atol=TOL[backend], err_msg=fluent)
        np.testing.assert_allclose(got1[1:], toward_sn, atol=TOL[backend], err_msg=fluent)
        if fluent in TILT_PAIRS.values():  # its no-motion state is the pair's one
            continue
        # no motion: (1 - C(->s0)) (1 - C(->sn)); a tilt pair's over both directions, which
        # move alike here
        expected = still**2 if fluent in TILT_PAIRS else still
        np.testing.assert_allclose(c[f"{fluent}.{STEADY[fluent]}"][1:], expected,
                                   atol=TOL[backend], err_msg=fluent)  # fmt: skip
    assert len(motions) == 22 + 74


@pytest.mark.parametrize("backend", BACKENDS)
def test_touching_is_within_a_tenth_of_a_raw_unit_inclusive_and_binary(backend: str) -> None:
    """SPEC: touching <= 0.1 raw units (metres), binary, not in head-lengths: the same metres
    touch whatever the head-length (the near-distance columns here say 3 hl throughout)."""
    names = ANGLE_SIGNALS + NEAR_SIGNALS
    metres = [0.0, 0.05, 0.1, float(np.nextafter(0.1, 1.0)), 0.1000001, 0.3, np.nan]
    values = np.full((len(metres), len(names)), 3.0)
    distances = np.repeat(np.array(metres)[:, None], len(NEAR_SIGNALS), axis=1)
    c = _evaluate(values, backend, distances)
    for a, b in near_pairs():
        got = c[f"near:{a}~{b}.touching"]
        np.testing.assert_array_equal(got, [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, np.nan])


# ---- angles from bodies posed by hand -------------------------------------------------------

NECK = np.array([0.0, 1.5, 0.0])
HIPS = np.array([0.0, 1.0, 0.0])


def _angle(body: dict[str, np.ndarray], name: str, backend: str) -> float:
    return float(state_signals(to_sequence(body), backend).column(name)[0])  # type: ignore[arg-type]


def _by_hand(u: np.ndarray, v: np.ndarray) -> float:
    """The angle between two vectors by the law of cosines, written out."""
    return math.acos(float(u @ v) / math.sqrt(float(u @ u) * float(v @ v)))


def _arm_at(body: dict[str, np.ndarray], side: str, direction: np.ndarray) -> None:
    """The upper arm 0.3 m from the shoulder along ``direction``."""
    d = np.asarray(direction, dtype=float)
    body[f"{side}_elbow"] = body[f"{side}_shoulder"] + 0.3 * d / np.linalg.norm(d)


@pytest.mark.parametrize("backend", BACKENDS)
def test_head_and_torso_tilt_angles_by_hand(backend: str) -> None:
    # neck -> mid-ear is straight up: 90 degrees from forward (sagittal) and from left (frontal)
    assert _angle(standing(), "neck_sagittal", backend) == pytest.approx(PI / 2)
    assert _angle(standing(), "neck_frontal", backend) == pytest.approx(PI / 2)
    # the head pitched 30 degrees forward about the neck: 60 degrees from forward
    forward = rotate(standing(), HEAD, rot_x(30), NECK)
    assert _angle(forward, "neck_sagittal", backend) == pytest.approx(PI / 3)
    assert _angle(forward, "neck_frontal", backend) == pytest.approx(PI / 2)
    # rolled 20 degrees to the person's left: 70 degrees from left, still 90 from forward
    left = rotate(standing(), HEAD, rot_z(20), NECK)
    assert _angle(left, "neck_frontal", backend) == pytest.approx(PI / 2 - PI / 9)
    assert _angle(left, "neck_sagittal", backend) == pytest.approx(PI / 2)
    # the whole upper body leaning 25 degrees to the person's left over the hips
    lean = rotate(standing(), UPPER_BODY, rot_z(25), HIPS)
    assert _angle(lean, "torso_frontal", backend) == pytest.approx(PI / 2 - 25 * PI / 180)
    assert _angle(lean, "torso_sagittal", backend) == pytest.approx(PI / 2)
    assert _angle(lean, "neck_frontal", backend) == pytest.approx(PI / 2)  # head moved with it


@pytest.mark.parametrize("backend", BACKENDS)
def test_head_twist_angle_by_hand(backend: str) -> None:
    # neck -> nose (0, ., 0.10) against neck -> left shoulder (0.20, 0, 0), in the transverse
    # plane: 90 degrees; the head turned 40 degrees to the person's left: 50 degrees
    assert _angle(standing(), "neck_transverse", backend) == pytest.approx(PI / 2)
    turned = rotate(standing(), HEAD, rot_y(40), NECK)
    assert _angle(turned, "neck_transverse", backend) == pytest.approx(PI / 2 - 40 * PI / 180)


@pytest.mark.parametrize("backend", BACKENDS)
def test_upper_arm_and_leg_against_forward_and_outward_by_hand(backend: str) -> None:
    body = standing()
    # left arm 30 degrees out to the side from hanging: 60 degrees from the outward axis
    # (the person's left, +x); the right arm 50 degrees forward from hanging: 40 degrees from
    # forward in the sagittal plane, and 90 from its outward axis (-x) in the frontal plane
    _arm_at(body, "left", np.array([math.sin(PI / 6), -math.cos(PI / 6), 0.0]))
    a = 50 * PI / 180
    _arm_at(body, "right", np.array([0.0, -math.cos(a), math.sin(a)]))
    assert _angle(body, "left_upper_arm_frontal", backend) == pytest.approx(PI / 3)
    assert _angle(body, "left_upper_arm_sagittal", backend) == pytest.approx(PI / 2)
    assert _angle(body, "right_upper_arm_sagittal", backend) == pytest.approx(PI / 2 - a)
    assert _angle(body, "right_upper_arm_frontal", backend) == pytest.approx(PI / 2)
    # the right arm straight out to its side (-x): 0 from its outward axis
    _arm_at(body, "right", np.array([-1.0, 0.0, 0.0]))
    assert _angle(body, "right_upper_arm_frontal", backend) == pytest.approx(0.0, abs=1e-7)
    # left thigh swung 35 degrees back: 125 degrees from forward (sagittal)
    b = 35 * PI / 180
    body["left_knee"] = body["left_hip"] + 0.45 * np.array([0.0, -math.cos(b), -math.sin(b)])
    assert _angle(body, "left_upper_leg_sagittal", backend) == pytest.approx(PI / 2 + b)
    assert _angle(body, "left_upper_leg_frontal", backend) == pytest.approx(PI / 2)


@pytest.mark.parametrize("backend", BACKENDS)
def test_elbow_knee_armpit_and_hip_use_the_spec_joints(backend: str) -> None:
    """Each joint of the triangle moved on its own changes the angle as the SPEC's triangle
    says (elbow: shoulder-elbow-wrist; knee: hip-knee-ankle; armpit: elbow-shoulder-hip; hip:
    knee-hip-shoulder), and no other joint does."""
    body = standing()
    body["left_wrist"] = body["left_elbow"] + np.array([0.0, 0.0, 0.25])  # forearm forward
    body["left_index"] = body["left_elbow"] + np.array([0.0, 0.3, 0.0])  # not in the triangle
    assert _angle(body, "left_elbow", backend) == pytest.approx(PI / 2)
    body["right_ankle"] = body["right_knee"] + np.array([0.0, -0.3, -0.3])  # shin back 45 deg
    body["right_heel"] = body["right_knee"]  # not in the triangle
    assert _angle(body, "right_knee", backend) == pytest.approx(3 * PI / 4)
    # armpit: the left upper arm down and forward (S->E); S->H is 0.5 down, 0.05 inward
    se = np.array([0.0, -0.18, 0.24])
    body["left_elbow"] = body["left_shoulder"] + se
    sh = np.array([-0.05, -0.5, 0.0])
    assert _angle(body, "left_armpit", backend) == pytest.approx(_by_hand(se, sh))
    # hip: the upper body pitched 30 degrees forward about the hips, the legs straight down:
    # H->K = (0, -0.45, 0), H->S = (-0.05, 0.5, 0) pitched forward
    bent = rotate(standing(), UPPER_BODY, rot_x(30), HIPS)
    c30, s30 = math.cos(PI / 6), math.sin(PI / 6)
    hs = np.array([0.05, 0.5 * c30, 0.5 * s30])  # the left side's
    assert _angle(bent, "left_hip", backend) == pytest.approx(
        _by_hand(np.array([0.0, -0.45, 0.0]), hs)
    )


# ---- QMP basis --------------------------------------------------------------------------------


def test_qmp_library_is_the_spec_explicit_time_basis() -> None:
    """SPEC: {1, t, cos(2 pi t/T), sin(2 pi t/T), cos(pi t/T), sin(pi t/T)}, t in seconds."""
    from features.qmp.library import ExplicitTimeLibrary

    t = np.linspace(0.0, 3.0, 91)
    period = 1.3
    w = 2 * math.pi / period
    by_hand = np.column_stack(
        [np.ones_like(t), t, np.cos(w * t), np.sin(w * t), np.cos(w * t / 2), np.sin(w * t / 2)]
    )
    np.testing.assert_allclose(ExplicitTimeLibrary().matrix(t, period), by_hand, atol=1e-12)
    # (the pysindy library the fits are checked against gives the same coefficients:
    # tests/test_qmp_fit.py, so it is this basis too)


# ---- DAD's score -----------------------------------------------------------------------------


def test_dad_scores_the_weighted_ratio_of_the_qmps_met_in_order() -> None:
    """SPEC: each activity scores the weighted ratio of its QMPs detected in sequence. An
    activity of five QMPs (weights 6, 5, 4, 3, 2) over three windows: A in window 0, B in 1,
    C never, D in 2, E only in 0 (before D: out of order), and a sixth QMP F (weight 7) that
    no window can observe, left out of the ratio (README: not observable). The heaviest
    in-order chain is A, B, D: (6 + 5 + 3) / (6 + 5 + 4 + 3 + 2)."""
    from cbr.dad.detection import _score_activity
    from features.qmp.add import Activity, CriteriaResult, Step, load_add

    add = load_add()
    names = tuple(add.criteria)[:6]
    weights = (6, 5, 4, 3, 2, 7)
    act = Activity("made_up", "made up", ("made_up",),
                   tuple(Step(q, w) for q, w in zip(names, weights, strict=True)))  # fmt: skip
    met = np.zeros((3, 6), dtype=bool)
    met[0, 0] = met[1, 1] = met[2, 3] = met[0, 4] = True
    observable = np.ones((3, 6), dtype=bool)
    observable[:, 5] = False
    crit = CriteriaResult(names, met, observable, met.astype(float), np.full(6, -1),
                          ((),) * 6)  # fmt: skip
    windows_s = np.array([[0.0, 4.0], [1.0, 5.0], [2.0, 6.0]])
    score = _score_activity(act, add, crit, windows_s)
    assert score.score == pytest.approx(14 / 20)
    assert (score.met_weight, score.observable_weight) == (14, 20)
    assert [o.status for o in score.qmps] == [
        "met", "met", "not met", "met", "out of order", "not observable"
    ]  # fmt: skip


def test_dad_places_the_qmps_met_in_order_in_windows_in_that_order() -> None:
    """The windows reported for the QMPs met are in the sequence's order: A (met in windows 0
    and 2) then B (met in window 1 only) is A in window 0, B in window 1, never A in 2."""
    from cbr.dad import ordered_match

    met = np.array([[1, 0, 1], [0, 1, 0]], dtype=bool)
    assert ordered_match(met, [1, 1]) == (2, [0, 1])
