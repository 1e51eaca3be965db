"""The explicit-time basis of the paper's QMPs (eqs. 4-9), as one library object.

Every QMP models a state signal's derivative as a sparse combination of

    1, t, cos(2*pi*t/T), sin(2*pi*t/T), cos(pi*t/T), sin(pi*t/T)

where t is seconds since the window start and T the period under test. The basis depends on
time only, so one matrix per period serves every signal and every window of the same length:
that is what makes the bulk fit cheap.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

FEATURE_NAMES: tuple[str, ...] = (
    "1",
    "t",
    "cos(2pi t/T)",
    "sin(2pi t/T)",
    "cos(pi t/T)",
    "sin(pi t/T)",
)
"""Readable names of the six basis functions, in column order."""

# Short machine names used in feature vectors and JSON (same order as FEATURE_NAMES).
COEFFICIENT_KEYS: tuple[str, ...] = ("const", "t", "cos_T", "sin_T", "cos_2T", "sin_2T")


@dataclass(frozen=True)
class ExplicitTimeLibrary:
    """The six explicit-time basis functions of a QMP (paper eqs. 4-9)."""

    @property
    def feature_names(self) -> tuple[str, ...]:
        return FEATURE_NAMES

    @property
    def n_features(self) -> int:
        return len(FEATURE_NAMES)

    def matrices(self, t: np.ndarray, periods: np.ndarray) -> np.ndarray:
        """Evaluate the basis for several periods at once.

        t: ``(frames,)`` seconds; periods: ``(n_periods,)`` seconds.
        Returns Theta: ``(n_periods, frames, 6)``.
        """
        t = np.asarray(t, dtype=np.float64)
        periods = np.asarray(periods, dtype=np.float64)
        whole = 2.0 * np.pi * t[None, :] / periods[:, None]  # (P, frames)
        half = 0.5 * whole
        ones = np.ones_like(whole)
        times = np.broadcast_to(t[None, :], whole.shape)
        return np.stack(
            [ones, times, np.cos(whole), np.sin(whole), np.cos(half), np.sin(half)], axis=-1
        )

    def matrix(self, t: np.ndarray, period: float) -> np.ndarray:
        """Theta for one period: ``(frames, 6)``."""
        theta: np.ndarray = self.matrices(t, np.array([period]))[0]
        return theta

    def to_pysindy(self, period: float, n_states: int = 1) -> Any:
        """The same basis as a pysindy library acting on a control input ``u = t``.

        Used as the reference implementation: ``ps.SINDy(feature_library=lib).fit(x, t=t,
        x_dot=xdot, u=t)`` fits the same model, one signal at a time (``x`` ``(samples, 1)``)
        or ``n_states`` signals in one call (``x`` ``(samples, n_states)``, the control after
        them).
        """
        import pysindy as ps

        w = 2.0 * np.pi / period
        functions = [
            lambda z: z,
            lambda z: np.cos(w * z),
            lambda z: np.sin(w * z),
            lambda z: np.cos(0.5 * w * z),
            lambda z: np.sin(0.5 * w * z),
        ]
        names = [
            lambda z: z,
            lambda z: f"cos(2pi {z}/T)",
            lambda z: f"sin(2pi {z}/T)",
            lambda z: f"cos(pi {z}/T)",
            lambda z: f"sin(pi {z}/T)",
        ]
        custom = ps.CustomLibrary(
            library_functions=functions, function_names=names, include_bias=True
        )
        # Columns 0..n_states-1 are the states, then the control (time): the basis sees only
        # time.
        return ps.GeneralizedLibrary([custom], inputs_per_library=[[n_states]])
