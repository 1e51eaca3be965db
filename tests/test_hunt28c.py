"""Hunt 28c: fluents and QMPs against SPEC, worked out independently.

QMP fits against pysindy's SINDy configured as SPEC says (the explicit-time library built here,
STLSQ with the documented threshold and alpha) on signals with a known answer; periods of a
sinusoid over frame rates and window lengths; fluents at the arccos domain's ends; the body
frame under whole-body rotations and the mirror image; the gap filling of the QMP fit
(the straight line between each short gap's neighbours).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.signal import savgol_coeffs, savgol_filter

from features.fluents import Backend, evaluate
from features.qmp import NOT_ENOUGH_DATA, OK, fill_short_gaps, fit_signals
from features.signals import ANGLE_SIGNALS, state_signals
from tests.bodies import rot_x, rot_y, rot_z, rotate, standing, to_sequence

FPS = 30.0
# SPEC's QMP fit as the project documents it (features/qmp/optimizer.py, differentiation.py):
# STLSQ threshold 0.05, alpha 0.05; Savitzky-Golay derivative over 0.25 s (9 frames at 30 fps,
# the nearest odd count to 7.5 above it), quadratic.
THRESHOLD, ALPHA, SG_FRAMES, SG_ORDER = 0.05, 0.05, 9, 2


def _pysindy_coefficients(t: np.ndarray, x: np.ndarray, period: float) -> np.ndarray:
    """pysindy's SINDy on {1, t, cos 2pi t/T, sin 2pi t/T, cos pi t/T, sin pi t/T} (time as
    the control input), the derivative from scipy's Savitzky-Golay filter."""
    import pysindy as ps

    w = 2.0 * np.pi / period
    basis = ps.CustomLibrary(
        library_functions=[
            lambda z: z,
            lambda z: np.cos(w * z),
            lambda z: np.sin(w * z),
            lambda z: np.cos(0.5 * w * z),
            lambda z: np.sin(0.5 * w * z),
        ],
        include_bias=True,
    )
    library = ps.GeneralizedLibrary([basis], inputs_per_library=[[1]])  # time only
    xdot = savgol_filter(x, SG_FRAMES, SG_ORDER, deriv=1, delta=1.0 / FPS, mode="interp")
    model = ps.SINDy(feature_library=library, optimizer=ps.STLSQ(threshold=THRESHOLD, alpha=ALPHA))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(x[:, None], t=t, x_dot=xdot[:, None], u=t[:, None])
    coefficients: np.ndarray = np.asarray(model.coefficients())[0]
    return coefficients


def test_qmp_fits_are_pysindys_sindy_and_recover_known_signals() -> None:
    t = np.arange(120) / FPS  # 4 s
    amp, period = 0.5, 1.0
    signals = {
        "sine": 1.0 + amp * np.sin(2 * np.pi * t / period),
        "decay": 1.0 + np.exp(-t),
        "drift": 1.0 + 0.3 * t,
        "constant": np.full(len(t), 2.0),
    }
    fits = fit_signals(np.stack(list(signals.values()), axis=1), FPS, ["left_knee"] * 4)
    q = fits.quantities
    sine, decay, drift, constant = range(4)
    # the sine and the decay: the coefficients pysindy finds at the fit's own period
    for s in (sine, decay):
        x = list(signals.values())[s]
        ref = _pysindy_coefficients(t, x, float(fits.period_T_s[0, s]))
        np.testing.assert_allclose(fits.coefficients[0, s], ref, atol=1e-8)
    # the sine's known answer: period 1 s; amplitude A times the derivative filter's gain at
    # that frequency (the filter's response worked out from its coefficients), phase -pi/2
    omega = 2 * np.pi / period
    taps = savgol_coeffs(SG_FRAMES, SG_ORDER, deriv=1, delta=1.0 / FPS, use="dot")
    lags = np.arange(SG_FRAMES) - SG_FRAMES // 2
    gain = abs(np.sum(taps * np.exp(1j * omega * lags / FPS))) / omega
    assert q["period_s"][0, sine] == pytest.approx(period, rel=0.01)
    assert q["amplitude"][0, sine] == pytest.approx(amp * gain, rel=0.02)
    assert q["phase_rad"][0, sine] == pytest.approx(-np.pi / 2, abs=0.05)
    assert fits.status[0, sine] == OK
    # the drift: a constant derivative, the trend; no oscillation, so no period (pysindy too)
    assert q["trend"][0, drift] == pytest.approx(0.3, abs=1e-9)
    assert q["amplitude"][0, drift] == 0.0 and np.isnan(q["period_s"][0, drift])
    np.testing.assert_allclose(
        _pysindy_coefficients(t, signals["drift"], 1.0), [0.3, 0, 0, 0, 0, 0], atol=1e-9
    )
    # the decay slows down: a negative trend, a positive acceleration
    assert q["trend"][0, decay] < 0 < q["accel"][0, decay]
    # the constant: flat, amplitude 0, no period, its level
    assert fits.status[0, constant] == 1  # flat
    assert q["amplitude"][0, constant] == 0.0 and np.isnan(q["period_s"][0, constant])
    assert q["mean"][0, constant] == pytest.approx(2.0)


@pytest.mark.parametrize("fps", [5.0, 24.0, 30.0, 100.0, 120.0])
def test_period_of_a_sinusoid_at_many_frame_rates_and_window_lengths(fps: float) -> None:
    period = 1.5
    for cycles in (1.5, 2.0, 3.7):
        n = int(round(cycles * period * fps))
        t = np.arange(n) / fps
        fits = fit_signals((1.0 + 0.5 * np.sin(2 * np.pi * t / period))[:, None], fps, ["x"])
        got = fits.quantities["period_s"][0, 0]
        if fits.status[0, 0] == NOT_ENOUGH_DATA:  # 5 fps, 1.5 cycles: 11 frames, 12 needed
            assert n < 12 and np.isnan(got)
            continue
        assert got == pytest.approx(period, rel=0.03), (fps, cycles)


def test_period_longer_than_the_window_gaps_and_tiny_windows_are_never_a_zero_period() -> None:
    t = np.arange(27) / FPS  # 0.9 s of a 1.5-s oscillation
    fits = fit_signals((1 + 0.5 * np.sin(2 * np.pi * t / 1.5))[:, None], FPS, ["x"])
    got = fits.quantities["period_s"][0, 0]
    assert 0.0 < got <= 0.9 + 1e-9  # at most the window: the longest the search can tell
    # NaN gaps: a short one is filled (the period still found), a long one is not enough data
    t = np.arange(167) / FPS
    x = 1 + 0.5 * np.sin(2 * np.pi * t / 1.5)
    short, long = x.copy(), x.copy()
    short[40:45] = np.nan
    long[40:80] = np.nan
    fits = fit_signals(np.stack([short, long], axis=1), FPS, ["a", "b"])
    assert fits.quantities["period_s"][0, 0] == pytest.approx(1.5, rel=0.02)
    assert fits.status[0, 1] == NOT_ENOUGH_DATA and np.isnan(fits.quantities["period_s"][0, 1])
    # two and three frames: nothing to fit, nothing invented
    for n in (2, 3):
        fits = fit_signals(np.arange(float(n))[:, None], FPS, ["x"])
        assert fits.status[0, 0] == NOT_ENOUGH_DATA
        assert all(np.isnan(v[0, 0]) for v in fits.quantities.values())


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_elbow_at_0_and_180_degrees_and_a_zero_length_forearm(backend: Backend) -> None:
    body = standing()  # the arm hangs straight: the elbow is at exactly 180 degrees
    folded = dict(body, left_wrist=np.array([0.20, 1.45, 0.0]))  # back up the upper arm: 0
    flat = dict(body, left_wrist=body["left_elbow"].copy())  # a forearm of no length
    r = evaluate(to_sequence(body, folded, flat), backend=backend)
    bent, straight = r.column("left_arm_bent.bent"), r.column("left_arm_bent.straight")
    sig = state_signals(to_sequence(body, folded, flat), backend).column("left_elbow")
    assert sig[0] == pytest.approx(np.pi, abs=1e-12) and sig[1] == pytest.approx(0.0, abs=1e-7)
    assert (bent[0], straight[0]) == (0.0, 1.0)
    assert (bent[1], straight[1]) == (1.0, 0.0)
    assert np.isnan(sig[2]) and np.isnan(bent[2]) and np.isnan(straight[2])
    # the other arm and the legs are untouched
    assert r.column("right_arm_bent.straight")[2] == 1.0
    assert r.column("left_leg_bent.straight")[2] == 1.0


def _posed() -> dict[str, np.ndarray]:
    """The standing body with the left arm raised 60 degrees forward, the right arm 45
    degrees out to the side, the left knee bent 40 degrees and the head turned 20 degrees to
    the left."""
    b = standing()
    p = rotate(b, ("left_elbow", "left_wrist"), rot_x(-60), b["left_shoulder"])
    p = rotate(p, ("right_elbow", "right_wrist"), rot_z(45), p["right_shoulder"])
    p = rotate(p, ("left_ankle",), rot_x(40), p["left_knee"])
    head = ("nose", "left_ear", "right_ear", "left_eye", "right_eye")
    return rotate(p, head, rot_y(20), 0.5 * (p["left_shoulder"] + p["right_shoulder"]))


# by hand: the posed body's angles in degrees
POSED = {
    "left_knee": 140.0,
    "left_upper_arm_sagittal": 30.0,  # 60 degrees forward of hanging: 30 from forward
    "right_upper_arm_frontal": 45.0,  # 45 degrees out: 45 from the outward axis
    "right_upper_arm_sagittal": 90.0,
    "neck_transverse": 70.0,  # the nose 20 degrees nearer the left shoulder
    "torso_transverse": 90.0,
    "neck_sagittal": 90.0,
    "neck_frontal": 90.0,
}


@pytest.mark.parametrize(
    ("turn", "torso_sagittal"),
    [
        (rot_y(-90), 90.0),  # facing -x
        (rot_y(180), 90.0),  # facing -z
        (rot_x(-90), 180.0),  # lying on the back: the torso tilted fully backward
        (rot_x(90), 0.0),  # lying face down: fully forward
        (rot_z(180), 90.0),  # upside down: the torso's tilt in its heading's plane is 90
    ],
)
def test_body_frame_follows_the_person_however_the_body_is_turned(
    turn: np.ndarray, torso_sagittal: float
) -> None:
    body = {k: turn @ v for k, v in _posed().items()}
    backends: tuple[Backend, ...] = ("numpy", "numba")
    for backend in backends:
        sig = state_signals(to_sequence(body), backend)
        got = dict(zip(sig.names, np.degrees(sig.values[0]), strict=True))
        for name, want in POSED.items():
            assert got[name] == pytest.approx(want, abs=1e-6), (backend, name)
        assert got["torso_sagittal"] == pytest.approx(torso_sagittal, abs=1e-6), backend


def test_mirror_image_swaps_the_sides_and_turns_twists_and_tilts_the_other_way() -> None:
    from features.body import mirrored, swap_side

    body = rotate(_posed(), tuple(_posed()), rot_z(10), np.zeros(3))  # leaning 10 deg left
    seq = to_sequence(body)
    own = state_signals(seq, "numpy")
    mir = state_signals(mirrored(seq), "numpy")
    a = dict(zip(own.names, own.values[0], strict=True))
    m = dict(zip(mir.names, mir.values[0], strict=True))
    sideways = {"neck_transverse", "torso_transverse", "neck_frontal", "torso_frontal"}
    for name in ANGLE_SIGNALS:
        if name in sideways:  # the head turned left is turned right in the mirror
            assert m[name] == pytest.approx(np.pi - a[name], abs=1e-9), name
        else:
            assert m[swap_side(name)] == pytest.approx(a[name], abs=1e-9), name
    assert np.degrees(a["torso_frontal"]) == pytest.approx(80.0, abs=1e-6)  # 10 deg left


def _fill_by_hand(values: np.ndarray, max_gap: int) -> np.ndarray:
    """Every NaN run of at most ``max_gap`` frames replaced by the straight line between its
    neighbours (a run at an edge: its one neighbour), one run at a time."""
    out = values.copy()
    for s in range(values.shape[1]):
        col = values[:, s]
        f = 0
        while f < len(col):
            if not np.isnan(col[f]):
                f += 1
                continue
            end = f
            while end < len(col) and np.isnan(col[end]):
                end += 1
            left = col[f - 1] if f > 0 else np.nan
            right = col[end] if end < len(col) else np.nan
            if end - f <= max_gap and not (np.isnan(left) and np.isnan(right)):
                for k in range(f, end):
                    if np.isnan(left):
                        out[k, s] = right
                    elif np.isnan(right):
                        out[k, s] = left
                    else:
                        out[k, s] = left + (right - left) * (k - f + 1) / (end - f + 1)
            f = end
    return out


def test_gap_filling_is_the_straight_line_between_the_neighbours() -> None:
    rng = np.random.default_rng(28)
    for _ in range(40):
        x = rng.standard_normal((int(rng.integers(1, 80)), 3))
        x[rng.random(x.shape) < rng.random()] = np.nan
        gap = int(rng.integers(0, 5))
        np.testing.assert_allclose(fill_short_gaps(x, gap), _fill_by_hand(x, gap), atol=1e-12)
