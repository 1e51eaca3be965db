"""QMP characterisation: bulk SINDy fits of state signals over sliding windows.

For every state signal (joint angle in radians, joint distance in head-lengths) and every
window, the derivative is fitted on the explicit-time library (:mod:`.library`) with STLSQ
(:mod:`.optimizer`) for a range of periods T, and the best period is kept: by default the one
with the smallest BIC, the residual penalised by the number of terms
(``QMPConfig(selection="residual")``: the smallest residual, the rule of the paper's section
"High level: QMPs" and of SPEC.md; see :func:`selection_score`). All signals and windows are
fitted together as array work.

Readable quantities derived from the coefficients ``(c0, c1, a1, b1, a2, b2)`` of
``x' = c0 + c1 t + a1 cos(wt) + b1 sin(wt) + a2 cos(wt/2) + b2 sin(wt/2)``, ``w = 2 pi / T``:
integrating gives oscillations of amplitude ``hypot(a1, b1) / w`` (period T) and
``hypot(a2, b2) / (w/2)`` (period 2T); the larger is the *dominant* oscillation, whose amplitude,
period and phase are reported (phase: the signal's component is ``A cos(2 pi t / period +
phase)``, t from the window start). ``trend`` is c0 (units per second), ``accel`` is c1.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from features.errors import ConfigError

from .differentiation import SavitzkyGolay
from .library import COEFFICIENT_KEYS, ExplicitTimeLibrary
from .optimizer import STLSQ

OK, FLAT, NOT_ENOUGH_DATA = 0, 1, 2
STATUS_WORDS: tuple[str, ...] = ("ok", "flat", "not enough data")
SELECTIONS: tuple[str, ...] = ("bic", "residual")

QUANTITIES: tuple[str, ...] = (
    "amplitude",
    "period_s",
    "phase_rad",
    "trend",
    "accel",
    "r2",
    "residual_rms",
    "mean",
    "min",
    "max",
    "range",
    "net_change",
)
"""Per-window, per-signal quantities a criterion may test (see :meth:`QMPFits.quantity`)."""


def signal_unit(name: str) -> str:
    """``"hl"`` (head-lengths) for a joint distance ``a~b``, else ``"rad"``."""
    return "hl" if "~" in name else "rad"


@dataclass(frozen=True)
class QMPConfig:
    """How QMPs are fitted: the model parts and the period search.

    min_period_s / max_period_s: range of T searched. T is capped at half the window (None =
    that cap) so that the half-period terms cos/sin(pi t/T) complete a cycle in the window:
    a longer T makes them nearly collinear with 1 and t, and the fit then trades huge
    cancelling coefficients that mean nothing. Oscillations up to the window length are still
    found, by the half-period terms (reported period = 2T);
    n_periods: geometric grid size; refine_rounds: each halves the grid step around the best T
    (per signal); max_gap_s: NaN runs up to this long are interpolated, longer ones make the
    window "not enough data"; flat_tolerance: a window whose signal moves less than this
    (peak to peak, signal units) is "flat"; fit_fps: derivatives are fitted at about this rate
    (higher-rate input is subsampled after differentiation; None = every frame).
    """

    library: ExplicitTimeLibrary = field(default_factory=ExplicitTimeLibrary)
    optimizer: STLSQ = field(default_factory=STLSQ)
    differentiation: SavitzkyGolay = field(default_factory=SavitzkyGolay)
    min_period_s: float = 0.6
    max_period_s: float | None = None
    n_periods: int = 32
    refine_rounds: int = 3
    max_gap_s: float = 0.3
    flat_tolerance: float = 1e-3
    fit_fps: float | None = 30.0
    selection: str = "bic"

    def __post_init__(self) -> None:
        if not (self.min_period_s > 0):
            raise ConfigError(f"min_period_s must be > 0, got {self.min_period_s}", "QMPConfig")
        if self.max_period_s is not None and self.max_period_s < self.min_period_s:
            raise ConfigError("max_period_s must be >= min_period_s", "QMPConfig")
        if self.n_periods < 2:
            raise ConfigError(f"n_periods must be >= 2, got {self.n_periods}", "QMPConfig")
        if self.selection not in SELECTIONS:
            raise ConfigError(
                f"selection must be one of {SELECTIONS}, got {self.selection!r}", "QMPConfig"
            )
        if self.refine_rounds < 0 or self.max_gap_s < 0 or self.flat_tolerance < 0:
            raise ConfigError("refine_rounds, max_gap_s, flat_tolerance must be >= 0", "QMPConfig")

    def min_frames(self, fps: float) -> int:
        """The fewest frames a window needs: a derivative window and twice the basis size."""
        return max(self.differentiation.min_frames(fps), 2 * self.library.n_features)


def period_grid(min_period_s: float, max_period_s: float, n: int) -> np.ndarray:
    """Geometric grid of candidate periods T, ``(n,)`` seconds."""
    if max_period_s <= min_period_s:
        return np.array([min_period_s])
    return np.geomspace(min_period_s, max_period_s, n)


@dataclass(frozen=True)
class PeriodSearch:
    """Best fit per column. coefficients ``(S, 6)``, support ``(S, 6)`` bool, period_T_s /
    rss ``(S,)``."""

    coefficients: np.ndarray
    support: np.ndarray
    period_T_s: np.ndarray
    rss: np.ndarray


#: basis rows (frames x periods) evaluated at once: the normal equations of a long window are
#: summed over blocks of frames, so that its basis is never held whole (10^6 frames at 32
#: periods would take 1.5 GB; a block takes about 50 MB)
THETA_ROWS = 1 << 20


def frame_blocks(frames: int, bases: int, frame_block: int | None = None) -> Iterator[slice]:
    """The blocks of ``frames`` frames the normal equations are summed over: ``frame_block``
    frames each, or (None) as many as keep ``bases`` basis matrices within
    :data:`THETA_ROWS` rows."""
    block = int(frame_block) if frame_block else max(1, THETA_ROWS // max(1, bases))
    for a in range(0, frames, max(1, block)):
        yield slice(a, a + block)


def fit_shared_periods(
    t: np.ndarray,
    xdot: np.ndarray,
    periods: np.ndarray,
    library: ExplicitTimeLibrary,
    optimizer: STLSQ,
    frame_block: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit every column of ``xdot`` (``(frames, S)``) at every period (``(P,)``).

    Returns coefficients ``(P, S, 6)``, support ``(P, S, 6)``, residual sum of squares
    ``(P, S)``. One Gram matrix per period serves all columns. The normal equations
    (Theta^T Theta, Theta^T xdot) are summed over blocks of frames (:func:`frame_blocks`):
    the same numbers as one block, up to rounding.
    """
    n = library.n_features
    gram = np.zeros((len(periods), n, n))
    rhs_t = np.zeros((len(periods), n, xdot.shape[1]))  # (P, 6, S): BLAS's layout
    for part in frame_blocks(len(t), len(periods), frame_block):
        theta = library.matrices(t[part], periods)  # (P, block, 6)
        gram += np.einsum("pfk,pfl->pkl", theta, theta)
        rhs_t += np.matmul(theta.transpose(0, 2, 1), xdot[part])
    rhs = rhs_t.transpose(0, 2, 1)  # (P, S, 6)
    coef, support = optimizer.fit_normal(gram[:, None], rhs)
    rss = _rss(xdot, coef, gram[:, None], rhs)
    return coef, support, rss


def fit_each_period(
    t: np.ndarray,
    xdot: np.ndarray,
    periods: np.ndarray,
    library: ExplicitTimeLibrary,
    optimizer: STLSQ,
    frame_block: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit column s of ``xdot`` (``(frames, S)``) at periods ``periods[:, s]`` (``(K, S)``),
    the normal equations summed over blocks of frames as in :func:`fit_shared_periods`.

    Returns coefficients ``(K, S, 6)``, support ``(K, S, 6)``, rss ``(K, S)``.
    """
    k, s = periods.shape
    n = library.n_features
    gram = np.zeros((k, s, n, n))
    rhs = np.zeros((k, s, n))
    for part in frame_blocks(len(t), k * s, frame_block):
        theta = library.matrices(t[part], periods.reshape(-1)).reshape(k, s, -1, n)  # (K,S,f,6)
        gram += np.einsum("ksfi,ksfj->ksij", theta, theta)
        rhs += np.einsum("ksfi,fs->ksi", theta, xdot[part])
    coef, support = optimizer.fit_normal(gram, rhs)
    return coef, support, _rss(xdot, coef, gram, rhs)


def _rss(xdot: np.ndarray, coef: np.ndarray, gram: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """||y - Theta w||^2 from the normal equations: y.y - 2 w.b + w.G.w (clipped at 0)."""
    yy = np.einsum("fs,fs->s", xdot, xdot)
    quad = np.einsum("...i,...ij,...j->...", coef, gram, coef)
    rss: np.ndarray = np.maximum(yy - 2.0 * np.einsum("...i,...i->...", coef, rhs) + quad, 0.0)
    return rss


def selection_score(
    rss: np.ndarray, n_terms: np.ndarray, n_samples: int, selection: str, energy: np.ndarray
) -> np.ndarray:
    """Score to minimise when choosing T (broadcasting shapes).

    ``"residual"`` is the paper's rule (smallest residual). ``"bic"`` adds the Bayesian
    information criterion's penalty ``k ln n`` to ``n ln(rss/n)``: with dozens of candidate
    periods, a denser model wins on residual alone by fitting noise; among fits with equally
    many terms both rules pick the same T.
    """
    if selection == "residual":
        return rss
    if selection != "bic":
        raise ConfigError(f"selection must be one of {SELECTIONS}, got {selection!r}", "QMPConfig")
    floor = 1e-12 * energy + 1e-300  # a noise-free fit must not score -inf
    penalty = n_terms * np.log(n_samples)
    bic: np.ndarray = n_samples * np.log(np.maximum(rss, floor) / n_samples) + penalty
    return bic


def search_period(
    t: np.ndarray,
    xdot: np.ndarray,
    periods: np.ndarray,
    library: ExplicitTimeLibrary,
    optimizer: STLSQ,
    refine_rounds: int = 0,
    selection: str = "bic",
    frame_block: int | None = None,
) -> PeriodSearch:
    """The paper's period search: fit at every candidate T, keep the best-scoring one.

    t: ``(frames,)`` seconds from the window start; xdot: ``(frames, S)`` derivatives; periods:
    ``(P,)`` candidate T (ascending; geometric). Each refinement round then tries the best T
    times ``r**-0.5`` and ``r**0.5`` (r = current grid ratio) per column and halves the step,
    so after n rounds the period is known to about ``r**(2**-n)``. selection: see
    :func:`selection_score`. frame_block: frames of the basis evaluated at once
    (:func:`frame_blocks`).
    """
    n = len(t)
    energy = np.einsum("fs,fs->s", xdot, xdot)
    coef, support, rss = fit_shared_periods(t, xdot, periods, library, optimizer, frame_block)
    score = selection_score(rss, support.sum(axis=-1), n, selection, energy)
    best = np.argmin(score, axis=0)  # (S,); ties -> the shorter period
    cols = np.arange(xdot.shape[1])
    best_T = periods[best]
    best_coef, best_support = coef[best, cols], support[best, cols]
    best_rss, best_score = rss[best, cols], score[best, cols]
    ratio = float(periods[1] / periods[0]) if len(periods) > 1 else 1.0
    lo, hi = float(periods[0]), float(periods[-1])
    for _ in range(refine_rounds if ratio > 1.0 else 0):
        step = np.sqrt(ratio)
        cand = np.clip(np.stack([best_T / step, best_T * step]), lo, hi)  # (2, S)
        c2, s2, r2 = fit_each_period(t, xdot, cand, library, optimizer, frame_block)
        sc2 = selection_score(r2, s2.sum(axis=-1), n, selection, energy)
        for k in range(2):
            better = sc2[k] < best_score
            best_T = np.where(better, cand[k], best_T)
            best_coef = np.where(better[:, None], c2[k], best_coef)
            best_support = np.where(better[:, None], s2[k], best_support)
            best_rss = np.where(better, r2[k], best_rss)
            best_score = np.where(better, sc2[k], best_score)
        ratio = step
    return PeriodSearch(best_coef, best_support, best_T, best_rss)


def fill_short_gaps(values: np.ndarray, max_gap: int) -> np.ndarray:
    """Linearly interpolate NaN runs of at most ``max_gap`` frames (edge runs: nearest value).

    values: ``(frames, S)``. Longer runs stay NaN. Returns a new array.
    """
    out = np.array(values, dtype=np.float64, copy=True)
    missing = np.isnan(out)
    if not missing.any():
        return out
    frames = np.arange(out.shape[0])
    for s in np.flatnonzero(missing.any(axis=0)):  # loop over signals with gaps only
        col, miss = out[:, s], missing[:, s]
        if miss.all():
            continue
        # Run lengths of the NaN stretches; the missing frames in order are the runs one after
        # another, so each run's verdict is repeated over its frames (no loop over the runs: a
        # flickering joint has one per frame or two).
        starts = np.flatnonzero(miss & ~np.r_[False, miss[:-1]])
        ends = np.flatnonzero(miss & ~np.r_[miss[1:], False]) + 1
        lengths = ends - starts
        short = np.zeros_like(miss)
        short[miss] = np.repeat(lengths <= max_gap, lengths)
        good = ~miss
        col[short] = np.interp(frames[short], frames[good], col[good])
    return out


@dataclass(frozen=True)
class QMPFits:
    """QMP fits of S signals over W windows.

    signal_names ``(S,)``; windows ``(W, 2)`` frame [start, stop) in the source clip; fps;
    coefficients ``(W, S, 6)`` on the derivative (order :data:`.library.COEFFICIENT_KEYS`);
    period_T_s ``(W, S)`` the chosen T; status ``(W, S)`` int (0 ok, 1 flat, 2 not enough
    data); quantities: name -> ``(W, S)`` float (see :data:`QUANTITIES`; NaN where not
    defined).
    """

    signal_names: tuple[str, ...]
    windows: np.ndarray
    fps: float
    coefficients: np.ndarray
    period_T_s: np.ndarray
    status: np.ndarray
    quantities: dict[str, np.ndarray]

    @property
    def units(self) -> tuple[str, ...]:
        return tuple(signal_unit(n) for n in self.signal_names)

    def index(self, signal: str) -> int:
        try:
            return self.signal_names.index(signal)
        except ValueError:
            raise KeyError(f"no state signal {signal!r}") from None

    def quantity(self, name: str) -> np.ndarray:
        """A quantity for every window and signal, ``(W, S)``."""
        if name not in self.quantities:
            raise KeyError(f"unknown QMP quantity {name!r} (known: {', '.join(QUANTITIES)})")
        return self.quantities[name]

    def describe(self, signal: str, window: int = 0) -> dict[str, Any]:
        """One fit in readable form (JSON-serialisable)."""
        s = self.index(signal)
        unit = signal_unit(signal)
        out: dict[str, Any] = {
            "signal": signal,
            "window_s": [
                float(self.windows[window, 0] / self.fps),
                float(self.windows[window, 1] / self.fps),
            ],
            "status": STATUS_WORDS[int(self.status[window, s])],
            "T_s": _num(self.period_T_s[window, s]),
            "coefficients": {
                k: _num(v)
                for k, v in zip(COEFFICIENT_KEYS, self.coefficients[window, s], strict=True)
            },
        }
        for q in QUANTITIES:
            out[quantity_key(q, unit)] = _num(self.quantities[q][window, s])
        return out


_UNIT_SUFFIX = {
    "amplitude": "_{u}",
    "trend": "_{u}_per_s",
    "accel": "_{u}_per_s2",
    "mean": "_{u}",
    "min": "_{u}",
    "max": "_{u}",
    "range": "_{u}",
    "net_change": "_{u}",
    "residual_rms": "_{u}_per_s",
}


def quantity_key(quantity: str, unit: str) -> str:
    """The readable key of a quantity with its unit: ``amplitude`` -> ``amplitude_rad``."""
    return quantity + _UNIT_SUFFIX.get(quantity, "").format(u=unit)


def _num(v: float) -> float | None:
    return None if not np.isfinite(v) else float(v)


def sliding_windows(n_frames: int, fps: float, window_s: float | None, step_s: float) -> np.ndarray:
    """Frame ranges ``(W, 2)`` [start, stop) of windows ``window_s`` long every ``step_s``.

    A clip shorter than one window (or window_s None) gives one window covering the clip; the
    last window is aligned to the clip's end so that no frames are left out.
    """
    if window_s is None:
        return np.array([[0, n_frames]])
    win = max(1, int(round(window_s * fps)))
    if n_frames <= win:
        return np.array([[0, n_frames]])
    step = max(1, int(round(step_s * fps)))
    starts = list(range(0, n_frames - win + 1, step))
    if starts[-1] + win < n_frames:
        starts.append(n_frames - win)
    return np.array([[a, a + win] for a in starts])


_BLOCK = 512  # columns (window x signal) per period search call
_SEARCH_FIELDS = ("coefficients", "support", "period_T_s", "rss")


def fit_signals(
    values: np.ndarray,
    fps: float,
    names: Sequence[str],
    *,
    config: QMPConfig | None = None,
    window_s: float | None = None,
    step_s: float = 1.0,
    frame_block: int | None = None,
) -> QMPFits:
    """Characterise QMPs of every signal over sliding windows.

    values: ``(frames, S)`` state signals (NaN = unavailable); fps: frame rate; names:
    ``(S,)`` signal names. window_s None fits one window over the whole clip. Windows with too
    few frames, or with NaN gaps longer than ``config.max_gap_s``, are "not enough data";
    motionless ones are "flat" (amplitude 0, trend 0, period undefined). frame_block: frames
    of the fit's basis evaluated at once (:func:`frame_blocks`; None: bounded by
    :data:`THETA_ROWS`).
    """
    cfg = config or QMPConfig()
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] != len(names):
        raise ValueError(f"values must be (frames, {len(names)}), got {values.shape}")
    n_frames, n_sig = values.shape
    windows = sliding_windows(n_frames, fps, window_s, step_s)
    n_win = len(windows)
    n_coef = cfg.library.n_features
    coef = np.zeros((n_win, n_sig, n_coef))
    period_T = np.full((n_win, n_sig), np.nan)
    status = np.full((n_win, n_sig), NOT_ENOUGH_DATA, dtype=np.int8)
    q = {name: np.full((n_win, n_sig), np.nan) for name in QUANTITIES}
    result = QMPFits(tuple(names), windows, float(fps), coef, period_T, status, q)
    win_frames = int(windows[0, 1] - windows[0, 0])
    if win_frames < cfg.min_frames(fps) or n_sig == 0:
        return result

    filled = fill_short_gaps(values, int(round(cfg.max_gap_s * fps)))
    # Windows are equally long: stack (window, signal) into columns sharing one basis.
    idx = windows[:, :1] + np.arange(win_frames)[None, :]  # (W, F)
    ok_data, flat = _usable(filled, idx, fps, cfg)
    # the gaps left become placeholder zeros (``filled`` is ours: changed in place rather
    # than copied, a long clip's signals being large); the frames they reach are not ok_data
    filled[~np.isfinite(filled)] = 0.0
    _levels(cfg.differentiation.smooth(filled, fps), idx, ok_data, q)
    status[ok_data] = OK
    status[flat] = FLAT
    for name in ("amplitude", "trend", "accel"):
        q[name][flat] = 0.0
    fit_mask = ok_data & ~flat
    if fit_mask.any():
        cols = np.argwhere(fit_mask)  # (n, 2): window, signal
        xdot = cfg.differentiation(filled, fps)
        del filled  # the long-clip peak is the signals' few copies: one less
        y, t = _fit_columns(xdot, idx, cols, fps, cfg)
        del xdot
        _fit_windows(y, t, cols, idx.shape[1] / fps, cfg, frame_block, result)
    return result


def _usable(
    filled: np.ndarray, idx: np.ndarray, fps: float, cfg: QMPConfig
) -> tuple[np.ndarray, np.ndarray]:
    """Which windows of each signal have data enough (``ok_data``) and which of those are
    motionless (``flat``), ``(W, S)`` each. filled: ``(frames, S)`` signals after short gaps
    are filled; idx: ``(W, F)`` the frames of every window."""
    # here, not at the top: importing the QMP package (as cbr.problem does for every command
    # that reads a case base) loads no SciPy until a fit runs
    from scipy.ndimage import binary_erosion

    finite = np.isfinite(filled)
    # The whole clip is differentiated once. Frames within half a smoothing window of a
    # remaining gap would see the placeholder zeros, so they count as missing too.
    reach = np.ones((cfg.differentiation.window_frames(fps), 1), dtype=bool)
    valid = binary_erosion(finite, structure=reach, border_value=1)
    ok_data: np.ndarray = valid[idx].all(axis=1)  # (W, S)
    raw = filled[idx]  # (W, F, S)
    np.copyto(raw, 0.0, where=~ok_data[:, None, :])
    flat: np.ndarray = ok_data & (np.ptp(raw, axis=1) < cfg.flat_tolerance)
    return ok_data, flat


def _levels(
    smooth: np.ndarray, idx: np.ndarray, ok_data: np.ndarray, q: dict[str, np.ndarray]
) -> None:
    """The level quantities (mean, min, max, range, net change) of the windows ``idx``
    ``(W, F)`` with ``ok_data`` ``(W, S)``, into ``q``. They come from the smoothed signal
    ``smooth`` ``(frames, S)``: single-frame tracking spikes would set min/max."""
    seg = smooth[idx]  # (W, F, S)
    del smooth
    np.copyto(seg, 0.0, where=~ok_data[:, None, :])
    q["mean"][ok_data] = seg.mean(axis=1)[ok_data]
    q["min"][ok_data] = seg.min(axis=1)[ok_data]
    q["max"][ok_data] = seg.max(axis=1)[ok_data]
    q["range"][ok_data] = np.ptp(seg, axis=1)[ok_data]
    q["net_change"][ok_data] = (seg[:, -1] - seg[:, 0])[ok_data]


def _fit_columns(
    xdot: np.ndarray, idx: np.ndarray, cols: np.ndarray, fps: float, cfg: QMPConfig
) -> tuple[np.ndarray, np.ndarray]:
    """The derivatives the fits of ``cols`` ``(n, 2)`` (window, signal) are made on,
    ``(F', n)``, at times ``(F',)`` seconds from the window start, from ``xdot``
    ``(frames, S)`` and the frames ``idx`` ``(W, F)`` of every window."""
    # Subsample high-rate input after differentiation: the basis is smooth over seconds.
    sub = max(1, int(fps // cfg.fit_fps)) if cfg.fit_fps else 1
    frames_sub = np.arange(0, idx.shape[1], sub)
    y: np.ndarray = xdot[idx[cols[:, 0]][:, frames_sub], cols[:, 1][:, None]].T
    return y, frames_sub / fps


def _fit_windows(
    y: np.ndarray,
    t: np.ndarray,
    cols: np.ndarray,
    duration: float,
    cfg: QMPConfig,
    frame_block: int | None,
    result: QMPFits,
) -> None:
    """The period search of every (window, signal) of ``cols`` ``(n, 2)`` on its derivative,
    column of ``y`` ``(F', n)`` at times ``t`` ``(F',)`` in windows of ``duration`` seconds:
    the coefficients and quantities into ``result``."""
    max_T = min(cfg.max_period_s or duration / 2.0, duration / 2.0)
    periods = period_grid(min(cfg.min_period_s, max_T), max_T, cfg.n_periods)
    # Columns go in blocks so that a long clip's many windows do not build one huge array.
    parts = [
        search_period(
            t, y[:, a : a + _BLOCK], periods, cfg.library, cfg.optimizer,
            cfg.refine_rounds, cfg.selection, frame_block,
        )
        for a in range(0, y.shape[1], _BLOCK)
    ]  # fmt: skip
    best = PeriodSearch(*(np.concatenate([getattr(p, f) for p in parts]) for f in _SEARCH_FIELDS))
    w_i, s_i = cols[:, 0], cols[:, 1]
    result.coefficients[w_i, s_i] = best.coefficients
    # T means nothing for a fit without a sinusoidal term: report it as undefined.
    has_wave = best.support[:, 2:].any(axis=1)
    result.period_T_s[w_i, s_i] = np.where(has_wave, best.period_T_s, np.nan)
    q = result.quantities
    for name, v in derived_quantities(best.coefficients, best.period_T_s).items():
        q[name][w_i, s_i] = v
    # Fraction of the derivative's energy explained (uncentred: a steady ramp has a
    # constant derivative, which the constant term explains fully).
    energy = (y**2).sum(axis=0)
    q["r2"][w_i, s_i] = 1.0 - best.rss / np.maximum(energy, 1e-300)
    q["residual_rms"][w_i, s_i] = np.sqrt(best.rss / len(t))


def derived_quantities(coefficients: np.ndarray, period_T_s: np.ndarray) -> dict[str, np.ndarray]:
    """Readable quantities from coefficients ``(n, 6)`` and periods ``(n,)``.

    Returns amplitude (signal units), period_s, phase_rad (in (-pi, pi]), trend (units/s),
    accel (units/s^2), each ``(n,)``.
    """
    c = np.asarray(coefficients, dtype=np.float64)
    T = np.asarray(period_T_s, dtype=np.float64)
    w = 2.0 * np.pi / T
    amp_whole = np.hypot(c[:, 2], c[:, 3]) / w
    amp_half = np.hypot(c[:, 4], c[:, 5]) / (0.5 * w)
    whole = amp_whole >= amp_half
    a = np.where(whole, c[:, 2], c[:, 4])
    b = np.where(whole, c[:, 3], c[:, 5])
    amplitude = np.where(whole, amp_whole, amp_half)
    # x = (a/w) sin(wt) - (b/w) cos(wt) = A cos(wt + phase) with phase = atan2(-a, -b).
    phase = np.where(amplitude > 0, np.arctan2(-a, -b), np.nan)
    period = np.where(amplitude > 0, np.where(whole, T, 2.0 * T), np.nan)
    return {
        "amplitude": amplitude,
        "period_s": period,
        "phase_rad": phase,
        "trend": c[:, 0],
        "accel": c[:, 1],
    }
