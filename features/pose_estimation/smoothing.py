"""Temporal filters for landmarks: the One Euro filter and a first-order low-pass filter.

One Euro filter (Casiez, Roussel, Vogel, CHI 2012): an exponential low-pass whose cutoff rises
with the signal's speed, so a still joint is smoothed hard (little jitter) and a moving one
lightly (little lag). Per sample, with sampling frequency f = 1/dt:

    alpha(fc) = 1 / (1 + f / (2 pi fc))
    dx  = lowpass((x - x_prev_raw) * value_scale * f, alpha(derivate_cutoff))
    fc  = min_cutoff + beta * |dx|
    out = lowpass(x, alpha(fc))

This is the variant MediaPipe uses for pose landmarks (``value_scale`` = 1 / object size, so
speed is measured in body sizes per second and the same parameters suit near and far
people). The parameters used by :mod:`features.pose_estimation.tracker` are MediaPipe 0.10.21's
pose settings (see :data:`IMAGE_FILTER`, :data:`WORLD_FILTER`, :data:`AUX_FILTER`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OneEuroParams:
    """``min_cutoff`` and ``derivate_cutoff`` in Hz; ``beta`` in 1/(scaled unit)."""

    min_cutoff: float
    beta: float
    derivate_cutoff: float = 1.0


# Image landmarks (pixels, speed scaled by the body's size): still joints are smoothed with a
# ~0.05 Hz cutoff, fast ones barely (beta 80).
IMAGE_FILTER = OneEuroParams(min_cutoff=0.05, beta=80.0, derivate_cutoff=1.0)
# World landmarks (metres, no scaling): depth is the noisy axis (a 1 px crop shift moves world
# landmarks by ~4 cm), hence the filter on all three axes.
WORLD_FILTER = OneEuroParams(min_cutoff=0.1, beta=40.0, derivate_cutoff=1.0)
# The two auxiliary landmarks that place the next frame's region of interest: smoothed hard so
# the crop does not jitter (crop jitter is what makes depth jitter).
AUX_FILTER = OneEuroParams(min_cutoff=0.01, beta=10.0, derivate_cutoff=1.0)
# Visibility: first-order low-pass, new value weighted 0.1.
VISIBILITY_ALPHA = 0.1


class OneEuroFilter:
    """One Euro filter over an array of values filtered independently (any fixed shape)."""

    def __init__(self, params: OneEuroParams, frequency: float = 30.0) -> None:
        self.params = params
        self._default_frequency = frequency
        self.reset()

    def reset(self) -> None:
        self._frequency = self._default_frequency
        self._last_time: float | None = None
        self._x: np.ndarray | None = None  # filtered value
        self._x_raw: np.ndarray | None = None  # last raw value
        self._dx: np.ndarray | None = None  # filtered derivative

    @staticmethod
    def _alpha(cutoff: np.ndarray | float, frequency: float) -> np.ndarray | float:
        te = 1.0 / frequency
        tau = 1.0 / (2.0 * math.pi * np.asarray(cutoff))
        return 1.0 / (1.0 + tau / te)

    def apply(self, time_s: float, value: np.ndarray, value_scale: float = 1.0) -> np.ndarray:
        """Filter one sample taken at ``time_s`` seconds; returns an array shaped like ``value``."""
        value = np.asarray(value, dtype=np.float64)
        if self._last_time is not None and time_s <= self._last_time:
            return value  # out-of-order sample: nothing sensible to do but pass it through
        if self._last_time is not None:
            self._frequency = 1.0 / (time_s - self._last_time)
        self._last_time = time_s
        if self._x is None or self._x_raw is None or self._dx is None:
            self._x = value.copy()
            self._x_raw = value.copy()
            self._dx = np.zeros_like(value)
            return value.copy()
        p = self.params
        dvalue = (value - self._x_raw) * value_scale * self._frequency
        a_d = self._alpha(p.derivate_cutoff, self._frequency)
        self._dx = a_d * dvalue + (1.0 - a_d) * self._dx
        cutoff = p.min_cutoff + p.beta * np.abs(self._dx)
        a = self._alpha(cutoff, self._frequency)
        self._x = a * value + (1.0 - a) * self._x
        self._x_raw = value.copy()
        return self._x.copy()


class LowPassFilter:
    """``out = alpha * value + (1 - alpha) * previous_out`` (the first sample passes through)."""

    def __init__(self, alpha: float) -> None:
        self.alpha = alpha
        self._state: np.ndarray | None = None

    def reset(self) -> None:
        self._state = None

    def apply(self, value: np.ndarray) -> np.ndarray:
        value = np.asarray(value, dtype=np.float64)
        if self._state is None:
            self._state = value.copy()
        else:
            self._state = self.alpha * value + (1.0 - self.alpha) * self._state
        return self._state.copy()
