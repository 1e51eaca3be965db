"""``CaseBaseClassifier``: the CBR cycle behind the scikit-learn estimator contract.

``X`` is a sequence (list or 1-D object array) of :class:`features.poses.PoseSequence`; ``y``
the activity labels. ``__init__`` only stores its parameters; ``fit`` extracts the problems,
builds (and optionally trims) the case base; learned state ends with ``_``.

Learned at fit time from the training clips only (so cross-validation stays honest):

- which fluent states and joint angles describe the clips (available in enough of them);
- the side handling (``mirror``, :mod:`cbr.fitting`): clips as recorded, left-side clips
  described by their mirror image (``"canonical"``), or the mirror image of every training clip
  as a further, penalised case (``"augment"``), so a subject who does a movement with the left
  arm finds the right-arm cases;
- ``feature_weights``: z-normalisation and Fisher-ratio weights of the features
  (:mod:`cbr.weights`), used by the euclidean measure and cited by explanations.

With vector problems under euclidean (clip summaries, QMPs), ``"auto"`` chooses the side
handling, the weighting and (clip summaries) the phase means by leave-one-subject-out accuracy
inside the training clips (one-standard-error rule: canonical side, fisher weights and no
phase means unless another choice is better by more than a standard error); a fold of an outer
cross-validation never sees its test clips. Fixed values skip the search.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.validation import check_is_fitted

from features.body import mirrored, moves_left_more
from features.errors import ConfigError, DataError
from features.poses import PoseSequence

from .casebase import CaseBase, subject_of
from .explain import Explanation, explain
from .fitting import (
    AUTO_PHASES,
    MIN_SUBJECTS_TO_JUDGE_WEIGHTS,
    SIDES,
    assemble_cases,
    inner_loso_accuracy,
    side_name,
)
from .problem import FeatureConfig, Problem, extract_problem, resolve_config
from .retrieve import Retrieval, retrieve
from .reuse import Solution, reuse
from .similarity import get_measure
from .weights import MIRROR_FLAG, WEIGHTINGS


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
    positions: add the limb joints' positions in the person's own frame at the start of the
      clip ("left wrist height", in torso lengths; :func:`features.body.body_positions`).
    summary: describe a clip by per-feature statistics (mean, lowest, highest, variation)
      instead of its sequence; ``"auto"``: for the euclidean measure at the fluent level.
    mirror: side handling: ``"off"`` (False), ``"augment"`` (True: mirror images of the
      training clips as further cases), ``"canonical"`` (left-side clips mirrored), or
      ``"auto"``: chosen by inner leave-one-subject-out for vector problems under euclidean
      when the training clips name two or more subjects ("off" otherwise).
    feature_weights: ``"fisher"`` (z-normalised, weighted by between/within-activity variance,
      learned in fit), ``"none"`` (raw values), or ``"auto"``: chosen like ``mirror`` when the
      training clips name three or more subjects; fisher with fewer (an inner fold would learn
      the weights from one person) and for clip summaries without subjects; none otherwise.
    phases: with clip summaries, also the mean of every feature over each of this many equal
      stretches of the clip ("left knee angle (middle third)"); ``"auto"``: three or none,
      chosen like ``mirror``.
    """

    def __init__(
        self,
        features: str = "fluents",
        similarity: str = "euclidean",
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
        phases: int | str = "auto",
        positions: bool = True,
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
        self.phases = phases
        self.positions = positions

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
            positions=bool(self.positions) and fluents,
            summary=self._summary() if summary is None else summary,
            # "auto": computed with the phases, which fit may then drop
            phases=(AUTO_PHASES if self.phases == "auto" else int(self.phases))
            if self._summary()
            else 0,
        )

    def _check_params(self) -> None:
        if not isinstance(self.k, int | np.integer) or int(self.k) < 1:
            raise ConfigError(f"k must be a positive integer, got {self.k!r}", "k")
        if self.weights not in ("distance", "uniform"):
            raise ConfigError(
                f"weights must be 'distance' or 'uniform', got {self.weights!r}", "weights"
            )
        if self.trim is not None and not 0.0 < float(self.trim) <= 1.0:
            raise ConfigError(f"trim must be in (0, 1], got {self.trim!r}", "trim")
        if self.summary != "auto" and not isinstance(self.summary, bool | np.bool_):
            raise ConfigError(
                f"summary must be True, False or 'auto', got {self.summary!r}", "summary"
            )
        if not isinstance(self.mirror, bool | np.bool_) and self.mirror not in ("auto", *SIDES):
            raise ConfigError(
                f"mirror must be True, False, 'auto', {', '.join(repr(s) for s in SIDES)}; "
                f"got {self.mirror!r}",
                "mirror",
            )
        if self.phases != "auto" and (
            not isinstance(self.phases, int | np.integer) or int(self.phases) < 0
        ):
            raise ConfigError(
                f"phases must be 'auto' or a whole number >= 0, got {self.phases!r}", "phases"
            )
        if self.feature_weights not in ("auto", *WEIGHTINGS):
            raise ConfigError(
                f"feature_weights must be 'auto', 'fisher' or 'none', got {self.feature_weights!r}",
                "feature_weights",
            )

    def _selectable(self, vectors: bool, measure: Any) -> bool:
        """Whether the side handling and weighting can be chosen by inner cross-validation:
        vector problems under a measure that takes learned weights (euclidean)."""
        return vectors and hasattr(measure, "multiplier")

    def wanted_config(self) -> FeatureConfig:
        """The feature configuration these parameters ask for, before fit resolves it."""
        return self._feature_config()

    def _candidates(self, vectors: bool, measure: Any) -> tuple[list[str], list[str]]:
        """The side handlings and weightings fit chooses between."""
        selectable = self._selectable(vectors, measure)
        if self.mirror == "auto":
            sides = list(SIDES) if selectable else ["off"]
        else:
            sides = [side_name(self.mirror)]
        if self.feature_weights == "auto":
            weightings = ["none", "fisher"] if selectable else ["none"]
        else:
            weightings = [str(self.feature_weights)]
        if "augment" in sides and not vectors:
            sides = ["augment"]  # sequence problems: plain augmentation, nothing to choose
        return sides, weightings

    def needs_mirror_images(self) -> bool:
        """Whether fit will describe the mirror image of every training clip (some side
        handling it may use needs them)."""
        measure = get_measure(self.similarity, **(self.similarity_params or {}))
        vectors = self.features == "qmp" or self._summary()
        sides, _ = self._candidates(vectors, measure)
        return "augment" in sides or "canonical" in sides

    def problems(self, X: Any) -> list[Problem]:
        """The problem of every clip in ``X`` under the fitted configuration."""
        check_is_fitted(self, "case_base_")
        return [self.case_base_.problem_of(s) for s in as_sequences(X)]

    # -- sklearn API

    def fit(self, X: Any, y: Any) -> CaseBaseClassifier:
        """Build the case base from clips ``X`` and labels ``y``.

        With ``mirror="auto"`` / ``feature_weights="auto"`` on vector problems, the side
        handling and the weighting are chosen by leave-one-subject-out cross-validation inside
        the training clips (``selection_`` holds the scores); the test clips of an outer
        cross-validation never take part.
        """
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
        real = [extract_problem(s, config) for s in seqs]
        vectors = real[0].values.ndim == 1
        if self.feature_weights not in ("auto", "none") and not self._selectable(vectors, measure):
            raise ConfigError(
                "learned feature weights need vector problems and a measure that takes them "
                "(summary=True or QMP features, with similarity='euclidean')",
                "feature_weights",
            )
        sides, weightings = self._candidates(vectors, measure)
        labels = np.array([str(v) for v in y_arr], dtype=object)
        subjects = np.array(
            [subject_of(s) or "" for s in seqs],
            dtype=object,
        )
        need_mirror = "augment" in sides or "canonical" in sides
        mirror_probs = [extract_problem(mirrored(s), config) for s in seqs] if need_mirror else []
        R = np.stack([p.values for p in real])
        M = np.stack([p.values for p in mirror_probs]) if need_mirror else None
        left = np.array([moves_left_more(s) for s in seqs]) if "canonical" in sides else None
        # phase columns come last: without them, the problem is the first `base` columns
        phase_options = [int(config.phases)]
        if self.phases == "auto" and config.phases and self._selectable(vectors, measure):
            phase_options = [0, int(config.phases)]
        base = R.shape[1] - len(config.states) * int(config.phases) if config.summary else None

        def cols(A: np.ndarray | None, phases: int) -> np.ndarray | None:
            return A if A is None or phases or base is None else A[:, :base]

        self.selection_ = {}
        n_subjects = len(set(subjects) - {""})
        if len(weightings) > 1 and n_subjects < MIN_SUBJECTS_TO_JUDGE_WEIGHTS:
            # an inner fold would learn the weights from one subject, whose within-activity
            # spread leaves out how people differ: the judgement would be biased against them
            weightings = ["fisher"]
        side, weighting, phases = sides[0], weightings[0], phase_options[-1]
        if len(sides) * len(weightings) * len(phase_options) > 1:
            if n_subjects >= 2 and "" not in set(subjects):
                scores = {
                    (sd, wt, ph): inner_loso_accuracy(
                        cols(R, ph),  # type: ignore[arg-type]
                        cols(M, ph),
                        left,
                        labels,
                        subjects,
                        sd,
                        wt,
                        int(self.k),
                        self.weights,
                    )
                    for ph in phase_options
                    for sd in sides
                    for wt in weightings
                }
                best = max(scores, key=lambda c: scores[c])  # first best wins
                # one-standard-error rule: the plain choice (the side-invariant handling, the
                # learned weights, no phase means) stays unless another beats it by more than
                # the standard error of the best inner accuracy; inner scores are noisy, and
                # chasing their small differences lost accuracy on held-out subjects
                plain = (
                    sides[0],
                    "fisher" if "fisher" in weightings else weightings[0],
                    phase_options[0],
                )
                se = float(np.sqrt(scores[best] * (1.0 - scores[best]) / len(labels)))
                if scores[best] - scores[plain] <= se:
                    best = plain
                side, weighting, phases = best
                self.selection_ = {
                    f"{sd}/{wt}/{ph} phases": a for (sd, wt, ph), a in scores.items()
                }
            else:  # no subjects to hold out: the fixed choice
                side = "off"
                weighting = "fisher" if "fisher" in weightings and self._summary() else "none"
        if side == "canonical":
            config = dataclasses.replace(config, side="canonical")
        if phases != config.phases:
            config = dataclasses.replace(config, phases=phases)
            R, M = cols(R, phases), cols(M, phases)  # type: ignore[assignment]
        cases = assemble_cases(R, M, left, labels, side, weighting, vectors)
        if cases.weights is not None:
            measure = get_measure(
                measure,
                centre=tuple(float(v) for v in cases.weights.centre),
                multiplier=tuple(float(v) for v in cases.weights.multiplier()),
            )
        n = len(seqs)
        case_seqs = [(mirrored(seqs[i - n]) if i >= n else seqs[i]) for i in cases.origin.tolist()]
        if side == "canonical" and left is not None:
            case_seqs = [mirrored(s) if lm else s for s, lm in zip(case_seqs, left, strict=True)]
        names, words = real[0].names[: R.shape[-1]], real[0].words[: R.shape[-1]]
        if cases.flag:
            names, words = (*names, MIRROR_FLAG), (*words, "mirror image of a training clip")
        cb = CaseBase(
            config,
            measure,
            cases.values,
            cases.labels,
            names,
            words,
            sources=tuple(s.source for s in case_seqs),
            subjects=tuple(subject_of(s) for s in case_seqs),
        )
        origin = cases.origin
        if self.trim is not None and float(self.trim) < 1.0:
            from .maintenance import trim_novelty_benefit

            report = trim_novelty_benefit(cb, keep=float(self.trim), k=int(self.k))
            cb, origin = report.casebase, origin[report.kept]
        self.case_origin_ = origin
        self.classes_ = classes
        self.feature_config_ = config
        self.measure_ = measure
        self.case_base_ = cb
        self.feature_names_ = names
        self.feature_weights_ = cases.weights
        self.side_ = side
        self.weighting_ = weighting
        self.phases_ = int(config.phases)
        self.mirror_ = side == "augment"
        self.mirror_flag_ = cases.flag
        self.mirror_cases_ = int((cases.origin >= n).sum())
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
