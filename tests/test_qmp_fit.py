"""QMP fitting: synthetic signals with known parameters, agreement with pysindy, bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from features.errors import ConfigError
from features.qmp import (
    FLAT,
    NOT_ENOUGH_DATA,
    OK,
    STLSQ,
    ExplicitTimeLibrary,
    QMPConfig,
    SavitzkyGolay,
    fill_short_gaps,
    fit_signals,
    period_grid,
    search_period,
    sliding_windows,
)
from features.qmp.fit import fit_each_period, fit_shared_periods

FPS = 30.0


def _clip(duration_s: float = 8.0) -> np.ndarray:
    return np.arange(int(duration_s * FPS)) / FPS


# (offset, amplitude, period_s, phase_rad, trend per s): x = c + A cos(2 pi t / P + phi) + tau t
CASES = [
    (2.0, 0.6, 2.3, 0.7, 0.0),
    (1.0, 0.3, 1.1, -1.2, 0.0),
    (1.5, 0.8, 3.7, 2.0, 0.08),
    (0.5, 0.4, 1.6, 0.0, -0.1),
]


def test_synthetic_period_amplitude_phase_and_trend_are_recovered() -> None:
    t = _clip()
    rng = np.random.default_rng(7)
    cols = [
        c + a * np.cos(2 * np.pi * t / p + phi) + tau * t + 0.005 * rng.standard_normal(len(t))
        for c, a, p, phi, tau in CASES
    ]
    fits = fit_signals(np.stack(cols, 1), FPS, [f"s{i}" for i in range(len(CASES))])
    for i, (_c, a, p, phi, tau) in enumerate(CASES):
        assert fits.status[0, i] == OK
        assert fits.quantity("period_s")[0, i] == pytest.approx(p, rel=0.05)
        assert fits.quantity("amplitude")[0, i] == pytest.approx(a, rel=0.1)
        gap = np.angle(np.exp(1j * (fits.quantity("phase_rad")[0, i] - phi)))
        assert abs(gap) < 0.25
        assert fits.quantity("trend")[0, i] == pytest.approx(tau, abs=0.03)


def test_long_oscillation_up_to_the_window_length_is_found_by_half_period_terms() -> None:
    # One slow cycle per window (a single repetition): 6 s period in a 6 s clip.
    t = _clip(6.0)
    x = 1.0 - 0.5 * np.cos(2 * np.pi * t / 6.0)
    fits = fit_signals(x[:, None], FPS, ["x"])
    assert fits.quantity("period_s")[0, 0] == pytest.approx(6.0, rel=0.05)
    assert fits.quantity("amplitude")[0, 0] == pytest.approx(0.5, rel=0.1)


def test_steady_ramp_is_a_trend_without_oscillation() -> None:
    t = _clip(5.0)
    fits = fit_signals((0.3 + 0.2 * t)[:, None], FPS, ["x"])
    assert fits.quantity("trend")[0, 0] == pytest.approx(0.2, abs=1e-6)
    assert fits.quantity("amplitude")[0, 0] == 0.0
    assert np.isnan(fits.quantity("period_s")[0, 0])
    assert np.isnan(fits.period_T_s[0, 0])  # no sinusoid selected: T means nothing


def _pysindy_fit(t: np.ndarray, xdot: np.ndarray, period: float, opt: STLSQ) -> np.ndarray:
    import pysindy as ps

    lib = ExplicitTimeLibrary()
    model = ps.SINDy(feature_library=lib.to_pysindy(period), optimizer=opt.to_pysindy())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pysindy warns when thresholding empties a fit
        model.fit(np.zeros((len(t), 1)), t=t, x_dot=xdot[:, None], u=t[:, None])
    return np.asarray(model.coefficients())[0]


def _reference_signals() -> tuple[np.ndarray, np.ndarray]:
    t = _clip(4.0)
    rng = np.random.default_rng(3)
    x = np.stack(
        [
            0.8 * np.cos(2 * np.pi * t / 1.7) + 0.1 * t,
            0.3 * np.sin(2 * np.pi * t / 0.9) + 0.04 * rng.standard_normal(len(t)),
            0.05 * np.cos(2 * np.pi * t / 2.5) + 0.02 * rng.standard_normal(len(t)),
            0.2 * t**2,
        ],
        axis=1,
    )
    return t, SavitzkyGolay()(x, FPS)


@pytest.mark.parametrize("opt", [STLSQ(), STLSQ(threshold=0.2, alpha=0.5), STLSQ(alpha=0.0)])
@pytest.mark.parametrize("frame_block", [None, 13])
def test_bulk_fit_gives_pysindy_coefficients(opt: STLSQ, frame_block: int | None) -> None:
    # frame_block 13: the normal equations summed over blocks of 13 frames (a long clip's way)
    t, xdot = _reference_signals()
    periods = period_grid(0.6, 2.0, 7)
    coef, _support, _rss = fit_shared_periods(
        t, xdot, periods, ExplicitTimeLibrary(), opt, frame_block
    )
    n_zeroed = 0
    for p, period in enumerate(periods):
        for s in range(xdot.shape[1]):
            ref = _pysindy_fit(t, xdot[:, s], period, opt)
            np.testing.assert_allclose(coef[p, s], ref, rtol=1e-6, atol=1e-8)
            n_zeroed += int((ref == 0).sum())
    assert n_zeroed > 0  # thresholding did act, so the sparse path is what was compared


def test_fit_at_each_columns_period_in_blocks_of_frames_gives_pysindy_coefficients() -> None:
    # the refinement rounds' fit (one period per signal), normal equations summed 17 frames
    # at a time
    t, xdot = _reference_signals()
    periods = np.array([[0.7, 1.3, 2.1, 1.0], [1.7, 0.9, 2.5, 1.9]])
    opt = STLSQ()
    coef, _support, _rss = fit_each_period(
        t, xdot, periods, ExplicitTimeLibrary(), opt, frame_block=17
    )
    assert len(t) > 6 * 17
    for k in range(periods.shape[0]):
        for s in range(xdot.shape[1]):
            ref = _pysindy_fit(t, xdot[:, s], periods[k, s], opt)
            np.testing.assert_allclose(coef[k, s], ref, rtol=1e-6, atol=1e-8)


def test_pysindy_fitting_all_signals_in_one_call_gives_the_same_coefficients() -> None:
    # the benchmark's fair peer: pysindy with every signal as a target of one fit
    import pysindy as ps

    t, xdot = _reference_signals()
    opt = STLSQ()
    lib = ExplicitTimeLibrary()
    n = xdot.shape[1]
    for period in (0.9, 1.7):
        model = ps.SINDy(feature_library=lib.to_pysindy(period, n_states=n),
                         optimizer=opt.to_pysindy())  # fmt: skip
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model.fit(np.zeros((len(t), n)), t=t, x_dot=xdot, u=t[:, None])
        together = np.asarray(model.coefficients())
        assert together.shape == (n, 6)
        for s in range(n):
            np.testing.assert_allclose(together[s], _pysindy_fit(t, xdot[:, s], period, opt))


def test_period_search_matches_a_pysindy_loop_over_the_same_periods() -> None:
    t, xdot = _reference_signals()
    periods = period_grid(0.6, 2.0, 9)
    opt = STLSQ()
    best = search_period(t, xdot, periods, ExplicitTimeLibrary(), opt, selection="residual")
    lib = ExplicitTimeLibrary()
    for s in range(xdot.shape[1]):
        rss = []
        for period in periods:
            c = _pysindy_fit(t, xdot[:, s], period, opt)
            rss.append(float(((xdot[:, s] - lib.matrix(t, period) @ c) ** 2).sum()))
        k = int(np.argmin(rss))
        assert best.period_T_s[s] == pytest.approx(periods[k])
        np.testing.assert_allclose(
            best.coefficients[s], _pysindy_fit(t, xdot[:, s], periods[k], opt), atol=1e-8
        )


def test_flat_signal_gives_an_explicit_flat_result() -> None:
    fits = fit_signals(np.full((90, 1), 1.2), FPS, ["left_knee"])
    assert fits.status[0, 0] == FLAT
    assert fits.quantity("amplitude")[0, 0] == 0.0
    assert fits.quantity("trend")[0, 0] == 0.0
    assert np.isnan(fits.quantity("period_s")[0, 0])
    assert fits.describe("left_knee")["status"] == "flat"


def test_clip_shorter_than_a_fit_needs_is_not_enough_data() -> None:
    fits = fit_signals(np.linspace(0, 1, 5)[:, None], FPS, ["x"])
    assert fits.status[0, 0] == NOT_ENOUGH_DATA
    assert fits.describe("x")["status"] == "not enough data"
    assert np.isnan(fits.quantity("amplitude")[0, 0])


def test_short_nan_stretch_is_interpolated_and_long_one_is_not_enough_data() -> None:
    t = _clip(10.0)
    x = 1.0 + 0.5 * np.cos(2 * np.pi * t / 2.0)
    short, long_ = x.copy(), x.copy()
    short[100:106] = np.nan  # 0.2 s
    long_[30:75] = np.nan  # 1.5 s, inside the first windows only
    fits = fit_signals(np.stack([short, long_], 1), FPS, ["a", "b"], window_s=4.0, step_s=1.0)
    assert (fits.status[:, 0] == OK).all()
    assert np.allclose(fits.quantity("period_s")[:, 0], 2.0, rtol=0.05)
    starts = fits.windows[:, 0]
    gap_inside = (starts < 75) & (fits.windows[:, 1] > 30)
    assert (fits.status[gap_inside, 1] == NOT_ENOUGH_DATA).all()
    assert (fits.status[~gap_inside, 1] == OK).all() and (~gap_inside).any()


def test_fill_short_gaps_by_hand() -> None:
    x = np.array([[0.0], [np.nan], [2.0], [np.nan], [np.nan], [np.nan], [6.0], [np.nan]])
    out = fill_short_gaps(x, max_gap=2)
    assert out[1, 0] == pytest.approx(1.0)
    assert np.isnan(out[3:6, 0]).all()  # a 3-frame gap stays missing
    assert out[7, 0] == 6.0  # an edge gap takes the nearest value


def test_sliding_windows_cover_the_clip() -> None:
    w = sliding_windows(n_frames=300, fps=30.0, window_s=4.0, step_s=1.0)
    assert w[0].tolist() == [0, 120]
    assert w[-1].tolist() == [180, 300]
    assert (w[:, 1] - w[:, 0] == 120).all()
    assert sliding_windows(50, 30.0, 4.0, 1.0).tolist() == [[0, 50]]


def test_bad_settings_raise_config_errors() -> None:
    with pytest.raises(ConfigError, match="threshold"):
        STLSQ(threshold=-1.0)
    with pytest.raises(ConfigError, match="selection"):
        QMPConfig(selection="aic")
    with pytest.raises(ConfigError, match="window_s"):
        SavitzkyGolay(window_s=0.0)
