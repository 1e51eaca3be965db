"""Robust derivatives of noisy state signals (pose angles jitter frame to frame)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from features.errors import ConfigError


@dataclass(frozen=True)
class SavitzkyGolay:
    """Savitzky-Golay derivative: a local polynomial fit, differentiated analytically.

    window_s: smoothing window in seconds (rounded to an odd number of frames, at least
    ``polyorder + 2``); polyorder: degree of the local polynomial. The same smoothing family
    as pysindy's ``SmoothedFiniteDifference``, applied in one call to all signals.
    """

    window_s: float = 0.25
    polyorder: int = 2

    def __post_init__(self) -> None:
        if not (np.isfinite(self.window_s) and self.window_s > 0):
            raise ConfigError(f"window_s must be > 0, got {self.window_s!r}", "SavitzkyGolay")
        if self.polyorder < 1:
            raise ConfigError(f"polyorder must be >= 1, got {self.polyorder!r}", "SavitzkyGolay")

    def window_frames(self, fps: float) -> int:
        """The odd frame count of the smoothing window at ``fps``."""
        n = int(round(self.window_s * fps))
        n = max(n, self.polyorder + 2)
        return n if n % 2 == 1 else n + 1

    def min_frames(self, fps: float) -> int:
        """The fewest frames a signal needs for a derivative."""
        return self.window_frames(fps)

    def __call__(self, x: np.ndarray, fps: float) -> np.ndarray:
        """Derivative along axis 0. x: ``(frames, ...)`` without NaN. Returns the same shape,
        in units per second."""
        n = self.window_frames(fps)
        if x.shape[0] < n:
            raise ValueError(f"need at least {n} frames for the derivative, got {x.shape[0]}")
        from scipy.signal import savgol_filter  # here: scipy.signal costs 0.6 s to import

        dx: np.ndarray = savgol_filter(
            x, n, self.polyorder, deriv=1, delta=1.0 / fps, axis=0, mode="interp"
        )
        return dx

    def smooth(self, x: np.ndarray, fps: float) -> np.ndarray:
        """The smoothed signal itself (same window), ``(frames, ...)``."""
        n = self.window_frames(fps)
        from scipy.signal import savgol_filter

        smooth: np.ndarray = savgol_filter(x, n, self.polyorder, deriv=0, axis=0, mode="interp")
        return smooth
