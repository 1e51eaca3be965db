"""``CaseBaseClassifier``: the CBR cycle behind the scikit-learn estimator contract.

``X`` is a sequence (list or 1-D object array) of :class:`features.poses.PoseSequence`; ``y``
the activity labels. ``__init__`` only stores its parameters; ``fit`` extracts the problems,
builds (and optionally trims) the case base; learned state ends with ``_``.

Learned at fit time from the training clips only (so cross-validation stays honest):

- which fluent states and joint angles describe the clips (available in enough of them);
- mirror images: with ``mirror`` on, the left-right mirror image of every training clip is a
  further case, so a subject who does a movement with the left arm finds the right-arm cases.
  A mirror image costs a distance penalty (:func:`cbr.weights.mirror_penalty`: the median
  distance between a training clip and its nearest clip of the same activity), so it wins
  only when no real case is about as close: activities that differ by side ("kick with the
  left leg") keep their real cases first;
- ``feature_weights``: z-normalisation and Fisher-ratio weights of the summary features
  (:mod:`cbr.weights`), used by the euclidean measure and cited by explanations.

The defaults (joint angles on, clip summaries with Fisher weights for euclidean, automatic
mirroring) were the best interpretable configuration in leave-one-subject-out comparisons on
UI-PRMD and HDM05 (``python -m benchmarks.compare``).
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
from .problem import FeatureConfig, Problem, extract_problem, mirrored, resolve_config
from .retrieve import Retrieval, retrieve
from .reuse import Solution, reuse
from .similarity import get_measure
from .weights import (
    WEIGHTINGS,
    confusing_mirrors,
    learn_weights,
    mirror_penalty,
    with_mirror_flag,
)


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
    angles: add the named joint angles ("left knee angle") to the fluent confidences.
    summary: describe a clip by per-feature statistics (mean, lowest, highest, variation)
      instead of its sequence; ``"auto"``: for the euclidean measure at the fluent level.
    mirror: add the mirror image of every training clip as a case (True/False), or
      ``"auto"``: for clip summaries under euclidean when the training clips name at least two
      subjects (people differ in the side they favour).
    feature_weights: ``"fisher"`` (z-normalised, weighted by between/within-activity variance,
      learned in fit), ``"none"``, or ``"auto"`` (fisher for clip summaries, none otherwise).
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
        angles: bool = True,
        summary: bool | str = "auto",
        mirror: bool | str = "auto",
        feature_weights: str = "auto",
    ) -> None:
        self.features = features
        self.similarity = similarity
        self.k = k
        self.weights = weights
        self.length = length
        self.states = states
        self.similarity_params = similarity_params
        self.trim = trim
        self.angles = angles
        self.summary = summary
        self.mirror = mirror
        self.feature_weights = feature_weights

    # -- helpers

    def _summary(self) -> bool:
        if self.summary == "auto":
            return self.features == "fluents" and self.similarity == "euclidean"
        return bool(self.summary) and self.features == "fluents"

    def _feature_config(self, summary: bool | None = None) -> FeatureConfig:
        states = self.states if isinstance(self.states, str) else tuple(self.states)
        fluents = self.features == "fluents"
        return FeatureConfig(
            level=self.features,  # type: ignore[arg-type]
            length=self.length,
            states=states,
            angles=bool(self.angles) and fluents,
            summary=self._summary() if summary is None else summary,
        )

    def _weighting(self, vectors: bool) -> str:
        if self.feature_weights == "auto":
            return "fisher" if vectors and self._summary() else "none"
        return str(self.feature_weights)

    def _check_params(self) -> None:
        if not isinstance(self.k, int | np.integer) or int(self.k) < 1:
            raise ConfigError(f"k must be a positive integer, got {self.k!r}", "k")
        if self.weights not in ("distance", "uniform"):
            raise ConfigError(
                f"weights must be 'distance' or 'uniform', got {self.weights!r}", "weights"
            )
        if self.trim is not None and not 0.0 < float(self.trim) <= 1.0:
            raise ConfigError(f"trim must be in (0, 1], got {self.trim!r}", "trim")
        for name in ("summary", "mirror"):
            value = getattr(self, name)
            if value != "auto" and not isinstance(value, bool | np.bool_):
                raise ConfigError(f"{name} must be True, False or 'auto', got {value!r}", name)
        if self.feature_weights not in ("auto", *WEIGHTINGS):
            raise ConfigError(
                f"feature_weights must be 'auto', 'fisher' or 'none', got {self.feature_weights!r}",
                "feature_weights",
            )

    def _use_mirror(self, seqs: list[PoseSequence]) -> bool:
        if self.mirror == "auto":
            # mirror images answer people who favour the other side, so they are added when the
            # training clips name two or more subjects; the penalty column needs clip summaries
            # under the euclidean measure
            subjects = {s.metadata.get("subject") for s in seqs} - {None}
            return self._summary() and self.similarity == "euclidean" and len(subjects) >= 2
        return bool(self.mirror)

    def problems(self, X: Any) -> list[Problem]:
        """The problem of every clip in ``X`` under the fitted configuration."""
        check_is_fitted(self, "case_base_")
        probs = [extract_problem(s, self.feature_config_) for s in as_sequences(X)]
        return [with_mirror_flag(p, 0.0) for p in probs] if self.mirror_flag_ else probs

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
        use_mirror = self._use_mirror(seqs)
        case_seqs = seqs + [mirrored(s) for s in seqs] if use_mirror else seqs
        case_y = np.concatenate([y_arr, y_arr]) if use_mirror else y_arr
        probs = [extract_problem(s, config) for s in case_seqs]
        flag = use_mirror and probs[0].values.ndim == 1
        if flag:  # vector problems: mark the mirror images (a penalised column, see below)
            probs = [with_mirror_flag(p, float(i >= len(seqs))) for i, p in enumerate(probs)]
        values = np.stack([p.values for p in probs])
        weighting = self._weighting(values.ndim == 2)
        self.feature_weights_ = None
        if weighting != "none" and (values.ndim != 2 or not hasattr(measure, "multiplier")):
            raise ConfigError(
                "learned feature weights need vector problems and a measure that takes them "
                "(summary=True or QMP features, with similarity='euclidean')",
                "feature_weights",
            )
        if weighting != "none":
            if flag:
                # weights from the real clips only: with the mirror images in, features that
                # tell a left-side activity from its right-side twin would look uninformative
                real = values[: len(seqs), :-1]
                base = learn_weights(real, y_arr, weighting)
                fw = mirror_penalty(base, real, y_arr)
                bad = confusing_mirrors(
                    base, real, values[len(seqs) :, :-1], y_arr, float(np.sqrt(fw.weight[-1]))
                )
                if bad.any():  # side-specific activities: drop the images that mimic another
                    keep = np.concatenate([np.ones(len(seqs), dtype=bool), ~bad])
                    values, case_y = values[keep], case_y[keep]
                    case_seqs = [s for s, k in zip(case_seqs, keep, strict=True) if k]
            else:
                fw = learn_weights(values, case_y, weighting)
            measure = get_measure(
                measure,
                centre=tuple(float(v) for v in fw.centre),
                multiplier=tuple(float(v) for v in fw.multiplier()),
            )
            self.feature_weights_ = fw
        cb = CaseBase(
            config,
            measure,
            values,
            np.array([str(v) for v in case_y], dtype=object),
            probs[0].names,
            probs[0].words,
            sources=tuple(s.source for s in case_seqs),
            subjects=tuple(
                None if s.metadata.get("subject") is None else str(s.metadata["subject"])
                for s in case_seqs
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
        self.mirror_ = use_mirror
        self.mirror_flag_ = flag
        self.mirror_cases_ = len(case_seqs) - len(seqs)
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
