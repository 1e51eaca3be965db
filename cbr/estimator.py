"""``CaseBaseClassifier``: the CBR cycle behind the scikit-learn estimator contract.

``X`` is a sequence (list or 1-D object array) of :class:`features.poses.PoseSequence`; ``y``
the activity labels. ``__init__`` only stores its parameters; ``fit`` extracts the problems,
builds (and optionally trims) the case base; learned state ends with ``_``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.validation import check_is_fitted

from features.poses import PoseSequence
from posecbr.errors import ConfigError, DataError

from .casebase import CaseBase
from .explain import Explanation, explain
from .problem import FeatureConfig, Problem, extract_problem, resolve_config
from .retrieve import Retrieval, retrieve
from .reuse import Solution, reuse
from .similarity import get_measure


def as_sequences(X: Any, where: str = "X") -> list[PoseSequence]:
    """``X`` as a list of PoseSequence (a list, tuple or 1-D object array)."""
    if isinstance(X, PoseSequence):
        raise DataError("X must be a sequence of PoseSequence, got a single PoseSequence", where)
    items = list(np.asarray(X, dtype=object).reshape(-1)) if isinstance(X, np.ndarray) else list(X)
    for i, s in enumerate(items):
        if not isinstance(s, PoseSequence):
            raise DataError(f"X[{i}] is a {type(s).__name__}, not a PoseSequence", where)
    return items


class CaseBaseClassifier(ClassifierMixin, BaseEstimator):
    """k-nearest-case classifier over qualitative posture features.

    features: ``"fluents"`` or ``"qmp"`` (feature level).
    similarity: a registered measure name (``"euclidean"``, ``"dtw"``, ``"signature"``, ...).
    k: number of retrieved cases.
    weights: ``"distance"`` (1/d vote) or ``"uniform"``.
    length: frames a fluent sequence is resampled to.
    states: fluent states (group name or list of machine names), see ``FeatureConfig``.
    similarity_params: parameters of the measure (e.g. ``{"band": 0.1}`` for dtw).
    trim: fraction of cases kept by novelty/benefit trimming at fit time (None: keep all).
    """

    def __init__(
        self,
        features: str = "fluents",
        similarity: str = "dtw",
        k: int = 5,
        weights: str = "distance",
        length: int = 32,
        states: str | Sequence[str] = "angles",
        similarity_params: dict[str, Any] | None = None,
        trim: float | None = None,
    ) -> None:
        self.features = features
        self.similarity = similarity
        self.k = k
        self.weights = weights
        self.length = length
        self.states = states
        self.similarity_params = similarity_params
        self.trim = trim

    # -- helpers

    def _feature_config(self) -> FeatureConfig:
        states = self.states if isinstance(self.states, str) else tuple(self.states)
        return FeatureConfig(level=self.features, length=self.length, states=states)  # type: ignore[arg-type]

    def _check_params(self) -> None:
        if not isinstance(self.k, int | np.integer) or int(self.k) < 1:
            raise ConfigError(f"k must be a positive integer, got {self.k!r}", "k")
        if self.weights not in ("distance", "uniform"):
            raise ConfigError(
                f"weights must be 'distance' or 'uniform', got {self.weights!r}", "weights"
            )
        if self.trim is not None and not 0.0 < float(self.trim) <= 1.0:
            raise ConfigError(f"trim must be in (0, 1], got {self.trim!r}", "trim")

    def problems(self, X: Any) -> list[Problem]:
        """The problem of every clip in ``X`` under the fitted configuration."""
        check_is_fitted(self, "case_base_")
        return [extract_problem(s, self.feature_config_) for s in as_sequences(X)]

    # -- sklearn API

    def fit(self, X: Any, y: Any) -> CaseBaseClassifier:
        """Build the case base from clips ``X`` and labels ``y``."""
        self._check_params()
        seqs = as_sequences(X)
        y_arr = np.asarray(y)
        if len(seqs) == 0:
            raise DataError("the training set is empty", "X")
        if y_arr.ndim != 1 or len(y_arr) != len(seqs):
            raise DataError(f"{len(seqs)} clips but y has shape {y_arr.shape}", "y")
        classes = np.unique(y_arr)
        if len(classes) < 2:
            raise DataError(
                f"the training set has only one activity ({classes[0]!r}); a classifier needs "
                "at least two",
                "y",
            )
        measure = get_measure(self.similarity, **(self.similarity_params or {}))
        config = resolve_config(self._feature_config(), seqs)
        probs = [extract_problem(s, config) for s in seqs]
        cb = CaseBase(
            config,
            measure,
            np.stack([p.values for p in probs]),
            np.array([str(v) for v in y_arr], dtype=object),
            probs[0].names,
            probs[0].words,
            sources=tuple(s.source for s in seqs),
            subjects=tuple(
                None if s.metadata.get("subject") is None else str(s.metadata["subject"])
                for s in seqs
            ),
        )
        if self.trim is not None and float(self.trim) < 1.0:
            from .maintenance import trim_novelty_benefit

            cb = trim_novelty_benefit(cb, keep=float(self.trim), k=int(self.k)).casebase
        self.classes_ = classes
        self.feature_config_ = config
        self.measure_ = measure
        self.case_base_ = cb
        self.feature_names_ = probs[0].names
        return self

    def _class_labels(self) -> np.ndarray:
        return np.array([str(c) for c in self.classes_], dtype=object)

    def solve(self, X: Any) -> list[tuple[Problem, Retrieval, Solution]]:
        """Problem, retrieved cases and reused solution for every clip in ``X``."""
        check_is_fitted(self, "case_base_")
        out = []
        labels = self._class_labels()
        for p in self.problems(X):
            r = retrieve(self.case_base_, p, int(self.k))
            out.append((p, r, reuse(r, labels, self.weights)))  # type: ignore[arg-type]
        return out

    def predict_proba(self, X: Any) -> np.ndarray:
        """``(n_clips, n_classes)`` vote shares, columns in ``classes_`` order."""
        return np.stack([s.proba for _, _, s in self.solve(X)])

    def predict(self, X: Any) -> np.ndarray:
        """``(n_clips,)`` predicted labels (values of ``classes_``)."""
        proba = self.predict_proba(X)
        return self.classes_[np.argmax(proba, axis=1)]

    def explain(self, X: Any) -> list[Explanation]:
        """An explanation in words for every clip in ``X``."""
        return [explain(self.case_base_, p, r, s) for p, r, s in self.solve(X)]

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.input_tags.two_d_array = False
        tags.non_deterministic = False
        return tags
