"""The peer classifiers a user would otherwise reach for (tslearn's DTW k-NN, MiniRocket), fed
the eight limb angles of each clip."""

from __future__ import annotations

import sys
import uuid
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin

from features.derived import derived
from features.errors import ConfigError, DataError
from features.poses import PoseSequence

from .settings import minirocket_backend

# The eight limb angles the peers see (elbows, knees, armpits, hips): raw joint angles in
# radians from the same state signals the fluents are computed from.
LIMB_ANGLES = (
    "left_elbow",
    "right_elbow",
    "left_knee",
    "right_knee",
    "left_armpit",
    "right_armpit",
    "left_hip",
    "right_hip",
)


def _limb_angles(seq: PoseSequence) -> np.ndarray:
    """The eight limb angles ``(frames, 8)`` (radians, NaN where a joint is missing)."""
    from features.fluents import state_signals

    sig = state_signals(seq)
    index = {n: i for i, n in enumerate(sig.names)}
    missing = [a for a in LIMB_ANGLES if a not in index]
    if missing:
        raise DataError(f"state signals lack {', '.join(missing)}", seq.source or "clip")
    return np.asarray(sig.values[:, [index[a] for a in LIMB_ANGLES]])


def angle_series(seq: PoseSequence, length: int) -> np.ndarray:
    """The eight limb angles of ``seq`` (radians), gaps interpolated, resampled to ``length``
    frames: ``(length, 8)``. Cached per sequence object and length (every fold shares one)."""
    from ..problem import fill_nan_time, resample

    def compute(s: PoseSequence) -> np.ndarray:
        return resample(fill_nan_time(_limb_angles(s), 0.0), int(length))

    return derived(seq, f"limb angles/{int(length)}", compute)


def cache_tslearn_kernels() -> int:
    """Let numba keep tslearn's compiled kernels on disk, as it keeps ours (``cache=True``):
    tslearn compiles its DTW on first use in every process (15-20 s of CPU on a slow core),
    again in each spawned fold worker of ``compare --jobs``; cached, the next process loads
    it in a second or two. The same machine code runs either way. Every kernel of the
    ``tslearn.metrics`` modules imported so far; returns how many were newly cached."""
    from numba.core.dispatcher import Dispatcher

    newly = 0
    for name, module in list(sys.modules.items()):
        if not name.startswith("tslearn.metrics") or module is None:
            continue
        for value in list(vars(module).values()):
            cache = getattr(value, "_cache", None)
            if (isinstance(value, Dispatcher) and value.__module__ == name
                    and type(cache).__name__ == "NullCache"):  # fmt: skip
                _name_for_every_process(value)
                value.enable_caching()
                newly += 1
    return newly


def _name_for_every_process(kernel: Any) -> None:
    """Give tslearn's ``kernel`` the same identity in every process: its module and name.
    numba finds a kernel in its cache by a hash of its code and of the values it closes over,
    and tslearn's DTW and mask kernels close over other kernels, which pickle with a random
    id drawn anew in each process (``Dispatcher._uuid``): every new process missed the cache,
    compiled the DTW again (~2.5 s of CPU) and added one more copy to the cache. An id
    already drawn (the kernel pickled before) is kept; a numba without ``_set_uuid`` (a
    private method) leaves the kernel as it is."""
    set_uuid = getattr(kernel, "_set_uuid", None)
    if set_uuid is not None and getattr(kernel, "_MemoMixin__uuid", None) is None:
        qualname = f"{kernel.py_func.__module__}.{kernel.py_func.__qualname__}"
        set_uuid(str(uuid.uuid5(uuid.NAMESPACE_URL, f"numba-kernel:{qualname}")))


class DTWKNNPeer(ClassifierMixin, BaseEstimator):
    """k-NN with DTW from tslearn (``KNeighborsTimeSeriesClassifier``) on the eight limb
    angles resampled to ``length`` frames: the plain peer a user would reach for."""

    def __init__(self, length: int = 64, n_neighbors: int = 1) -> None:
        self.length = length
        self.n_neighbors = n_neighbors

    def _series(self, X: Sequence[PoseSequence]) -> np.ndarray:
        """``(n_clips, length, 8)``."""
        return np.stack([angle_series(s, int(self.length)) for s in X])

    def fit(self, X: Sequence[PoseSequence], y: Any) -> DTWKNNPeer:
        with warnings.catch_warnings():  # tslearn warns that optional h5py is missing
            warnings.simplefilter("ignore", UserWarning)
            from tslearn.neighbors import KNeighborsTimeSeriesClassifier

        cache_tslearn_kernels()
        self.model_ = KNeighborsTimeSeriesClassifier(
            n_neighbors=int(self.n_neighbors), metric="dtw"
        )
        self.model_.fit(self._series(X), np.asarray(y))
        self.classes_ = self.model_.classes_
        return self

    def predict(self, X: Sequence[PoseSequence]) -> np.ndarray:
        return np.asarray(self.model_.predict(self._series(X)))


def _minirocket(random_state: int) -> Any:
    """An unfitted MiniRocket transform from whichever library is installed."""
    backend = minirocket_backend()
    if backend == "sktime":
        from sktime.transformations.panel.rocket import MiniRocketMultivariate

        return MiniRocketMultivariate(random_state=random_state, n_jobs=1)
    if backend == "aeon":
        from aeon.transformations.collection.convolution_based import MiniRocket

        return MiniRocket(random_state=random_state, n_jobs=1)
    raise ConfigError(
        "MiniRocket needs sktime or aeon (pip install sktime); the peer is skipped", "minirocket"
    )


class MiniRocketPeer(ClassifierMixin, BaseEstimator):
    """MiniRocket features (sktime or aeon) + ridge regression with built-in cross-validated
    regularisation, on the eight limb angles: a strong, non-interpretable peer."""

    def __init__(self, length: int = 64, random_state: int = 0) -> None:
        self.length = length
        self.random_state = random_state

    def _panel(self, X: Sequence[PoseSequence]) -> np.ndarray:
        """``(n_clips, 8, length)``: (n, channels, time), the layout both libraries take."""
        return np.stack([angle_series(s, int(self.length)).T for s in X])

    def fit(self, X: Sequence[PoseSequence], y: Any) -> MiniRocketPeer:
        from sklearn.linear_model import RidgeClassifierCV
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        panel = self._panel(X)
        self.transform_ = _minirocket(self.random_state).fit(panel)
        feats = np.asarray(self.transform_.transform(panel), dtype=np.float64)
        self.ridge_ = make_pipeline(
            StandardScaler(), RidgeClassifierCV(alphas=np.logspace(-3, 3, 10))
        ).fit(feats, np.asarray(y))
        self.classes_ = self.ridge_.classes_
        return self

    def predict(self, X: Sequence[PoseSequence]) -> np.ndarray:
        feats = np.asarray(self.transform_.transform(self._panel(X)), dtype=np.float64)
        return np.asarray(self.ridge_.predict(feats))
