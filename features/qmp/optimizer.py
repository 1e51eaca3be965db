"""Sequentially thresholded least squares (STLSQ), vectorised over many fits at once.

This is the algorithm of pysindy's ``STLSQ`` (Brunton et al. 2016) with its defaults
(``unbias=True``, no column normalisation): start from the full support; repeat a ridge
regression ``min ||y - Theta w||^2 + alpha ||w||^2`` on the current support and drop every
coefficient with ``|w| < threshold`` until the support stops changing (or ``max_iter``); finally
refit the surviving terms by ordinary least squares. pysindy runs it one fit at a time in
Python; here every (period, signal) pair is one slice of a batched 6x6 solve, because with an
explicit-time library all fits of a period share one Gram matrix.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from features.errors import ConfigError


@dataclass(frozen=True)
class STLSQ:
    """Sparse regression settings.

    threshold: coefficients below this magnitude are dropped (units of the derivative: signal
        units per second, e.g. rad/s). alpha: ridge (L2) weight during support selection, the
        paper's tunable alpha. max_iter: cap on thresholding rounds.
    """

    threshold: float = 0.05
    alpha: float = 0.05
    max_iter: int = 20

    def __post_init__(self) -> None:
        if not (np.isfinite(self.threshold) and self.threshold >= 0):
            raise ConfigError(f"threshold must be >= 0, got {self.threshold!r}", "STLSQ")
        if not (np.isfinite(self.alpha) and self.alpha >= 0):
            raise ConfigError(f"alpha must be >= 0, got {self.alpha!r}", "STLSQ")
        if self.max_iter < 1:
            raise ConfigError(f"max_iter must be >= 1, got {self.max_iter!r}", "STLSQ")

    def fit_normal(self, gram: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Run STLSQ on normal equations.

        gram: ``(..., n, n)`` = Theta^T Theta, broadcastable against rhs (e.g. one Gram matrix
        per period shared by all signals); rhs: ``(..., n)`` = Theta^T y. Returns
        (coefficients ``(..., n)``, support ``(..., n)`` bool).
        """
        gram = np.asarray(gram, dtype=np.float64)
        rhs = np.asarray(rhs, dtype=np.float64)
        shape, n = rhs.shape, rhs.shape[-1]
        # Index each fit's Gram matrix instead of materialising one copy per fit.
        gram_ids = np.broadcast_to(
            np.arange(int(np.prod(gram.shape[:-2]))).reshape(gram.shape[:-2]), shape[:-1]
        ).reshape(-1)
        grams = gram.reshape(-1, n, n)
        b = rhs.reshape(-1, n)
        support = np.ones(b.shape, dtype=bool)
        active = np.arange(len(b))
        for _ in range(self.max_iter):
            w = _masked_solve(grams[gram_ids[active]], b[active], support[active], self.alpha)
            new = support[active] & (np.abs(w) >= self.threshold)
            changed = (new != support[active]).any(axis=-1)
            support[active] = new
            # A fit whose support no longer changes would repeat the same solve: it is done.
            active = active[changed]
            if len(active) == 0:
                break
        # Unbias: ordinary least squares on the selected terms (pysindy's default final step).
        coef = np.where(support, _masked_solve(grams[gram_ids], b, support, 0.0), 0.0)
        return coef.reshape(shape), support.reshape(shape)

    def to_pysindy(self) -> Any:
        """The equivalent pysindy optimizer (the reference implementation)."""
        import pysindy as ps

        return ps.STLSQ(threshold=self.threshold, alpha=self.alpha, max_iter=self.max_iter)


def _masked_solve(
    gram: np.ndarray, rhs: np.ndarray, support: np.ndarray, alpha: float
) -> np.ndarray:
    """Solve ``(G + alpha I) w = b`` restricted to each fit's support, in one batched call.

    gram ``(N, n, n)``, rhs and support ``(N, n)``. Rows and columns outside the support become
    the identity with a zero right-hand side, so their coefficient is exactly 0 and the rest is
    the restricted solution.
    """
    n = rhs.shape[-1]
    outer = support[:, :, None] & support[:, None, :]
    a = np.where(outer, gram, 0.0)
    diag = np.arange(n)
    a[:, diag, diag] += np.where(support, alpha, 1.0)
    b = np.where(support, rhs, 0.0)
    try:
        return np.linalg.solve(a, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        # A singular slice (degenerate basis): least squares slice by slice.
        return np.stack(
            [np.linalg.lstsq(ai, bi, rcond=None)[0] for ai, bi in zip(a, b, strict=True)]
        )
