"""``DADClassifier``: DAD behind the scikit-learn classifier contract, its input checked as
scikit-learn estimators check theirs."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from collections.abc import Set as AbstractSet
from numbers import Number
from pathlib import Path
from typing import Any

import numpy as np

from features.body import no_person, torso_share
from features.errors import InputError
from features.poses import PoseSequence
from features.qmp.add import ADD, load_add

from ..estimator_protocol import Classifier, check_fitted
from .detection import DADConfig, default_step, detect
from .names import class_of_activity

_NEEDS = "must be a sequence (list, tuple or 1-D object array) of PoseSequence"


def pose_sequences(X: Any) -> list[PoseSequence]:
    """``X`` as a non-empty list of PoseSequence; anything else is an :class:`InputError`
    naming what was given (a numeric array, a single clip, an item of another type, a set or
    a mapping, whose order is not the clips': the answers were given in the set's)."""
    if isinstance(X, PoseSequence):
        raise InputError(f"{_NEEDS}, got a single PoseSequence (wrap it in a list)", "X")
    if isinstance(X, np.ndarray) and (X.dtype != object or X.ndim != 1):
        raise InputError(f"{_NEEDS}, got a {X.dtype} array of shape {X.shape}", "X")
    if X is None or isinstance(X, str | bytes) or not hasattr(X, "__iter__"):
        raise InputError(f"{_NEEDS}, got {type(X).__name__}", "X")
    if isinstance(X, AbstractSet | Mapping):  # no order to match the answers or labels to
        kind = "set" if isinstance(X, AbstractSet) else "mapping"
        raise InputError(
            f"{_NEEDS}, got a {kind} ({type(X).__name__}): its order is not the clips' (a list"
            " of them keeps it)",
            "X",
        )
    items = list(X)
    for i, s in enumerate(items):
        if not isinstance(s, PoseSequence):
            raise InputError(f"X[{i}] is of type {type(s).__name__}, not a PoseSequence", "X")
    if not items:
        raise InputError("is empty: at least one clip is needed", "X")
    return items


def _missing(v: Any) -> bool:
    return v is None or (isinstance(v, float | np.floating) and bool(np.isnan(v)))


def class_labels(y: Any, n_clips: int) -> np.ndarray:
    """``y`` as a 1-D array of ``n_clips`` class labels: not None, no missing (None/NaN)
    label, not a continuous target."""
    if y is None:
        raise InputError("is None: one label per clip is needed", "y")
    # object dtype first: numpy would turn a NaN among strings into the string "nan"
    values = y if isinstance(y, np.ndarray) else np.asarray(_as_list(y), dtype=object)
    if values.ndim != 1:
        raise InputError(f"must be 1-D (one label per clip), got shape {values.shape}", "y")
    if len(values) != n_clips:
        raise InputError(f"X has {n_clips} clips but y has {len(values)} labels", "y")
    items = values.tolist()
    bad = next((i for i, v in enumerate(items) if _missing(v)), None)
    if bad is not None:
        raise InputError(f"y[{bad}] is {items[bad]!r}: every clip needs a label", "y")
    kinds = sorted({_kind(v) for v in items})
    if values.dtype == object and len(kinds) > 1:
        raise InputError(f"mixes label types ({', '.join(kinds)}); use one type", "y")
    if values.dtype == object:
        # a list of labels: in numpy's own type (ints stay ints), as scikit-learn reads y
        values = np.asarray(values.tolist())
    from sklearn.utils.multiclass import check_classification_targets  # fit alone needs it

    try:
        check_classification_targets(values)
    except ValueError as exc:  # a continuous or multi-output target
        raise InputError(str(exc).splitlines()[0], "y") from None
    return values


def _kind(v: Any) -> str:
    return (
        "string" if isinstance(v, str) else "number" if isinstance(v, Number) else type(v).__name__
    )


def _as_list(y: Any) -> Any:
    return list(y) if hasattr(y, "__iter__") and not isinstance(y, str | bytes) else y


class DADClassifier(Classifier):
    """DAD with the scikit-learn classifier contract (X: a sequence of PoseSequence).

    ``fit`` learns nothing but ``classes_`` (DAD needs no training data) and which class each
    ADD activity stands for, names matched ignoring case, spaces, underscores and hyphens
    (CMU's "Squat" is the ADD's "squat"; two classes one activity cannot tell apart are
    refused, see :func:`~cbr.dad.names.class_of_activity`); ``predict`` maps the
    top-ranked ADD activity among those standing for a known class to that class (activities
    for other datasets' labels are ignored); a clip DAD cannot judge ("not enough data"), or
    one where no activity standing for a class could be scored, gets the first class, except
    a clip that shows no person (no frame with a torso) or has a single frame: those are
    refused with an :class:`~features.errors.InputError` (a ``DataError``), as
    :class:`~cbr.estimator.CaseBaseClassifier` refuses a clip with no person.
    ``decision_function`` gives each class its best activity's score; ``predict_proba``
    normalises those scores.

    Input is checked as scikit-learn checks it, with :class:`features.errors.InputError` (a
    ``ValueError``): X a non-empty sequence of PoseSequence (``predict([])`` is refused, as
    scikit-learn refuses zero samples), y 1-D with one label per clip and none missing;
    ``predict`` before ``fit`` raises ``sklearn.exceptions.NotFittedError``.

    add: an :class:`ADD`, a path to an ADD file, or None for the shipped one; window_s and
    step_s: the sliding windows (see :class:`~cbr.dad.detection.DADConfig`; step_s None: 1 s,
    or the window's length when that is shorter).
    """

    def __init__(
        self,
        add: ADD | str | Path | None = None,
        window_s: float = 4.0,
        step_s: float | None = None,
    ) -> None:
        self.add = add
        self.window_s = window_s
        self.step_s = step_s

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.input_tags.two_d_array = False  # X holds pose sequences, not a numeric table
        return tags

    def fit(self, X: Sequence[PoseSequence], y: Sequence[Any] | np.ndarray) -> DADClassifier:
        """Record the classes of ``y`` and load the ADD; X: ``(n_clips,)`` PoseSequence."""
        labels = class_labels(y, len(pose_sequences(X)))
        step = default_step(self.window_s) if self.step_s is None else self.step_s
        self.config_ = DADConfig(window_s=self.window_s, step_s=step)
        self.add_ = self.add if isinstance(self.add, ADD) else load_add(self.add)
        self.classes_ = np.unique(labels)
        # which class each activity scores for, names matched as a user reads them
        self.activity_class_ = class_of_activity(self.add_, self.classes_.tolist())
        return self

    def _class_scores(self, seq: PoseSequence) -> np.ndarray:
        result = detect(seq, self.add_, self.config_)
        scores = np.full(len(self.classes_), -1.0)
        for rank, act in enumerate(result.activities):
            i = self.activity_class_.get(act.activity)
            if i is None or not np.isfinite(act.score):
                continue
            # The rank breaks ties between equal ratios (more matched weight ranks first).
            scores[i] = max(scores[i], act.score - 1e-6 * rank)
        return scores

    def decision_function(self, X: Sequence[PoseSequence]) -> np.ndarray:
        """Best activity score per class, ``(n_clips, n_classes)``; -1 where no activity."""
        check_fitted(self, "classes_")
        seqs = pose_sequences(X)
        for i, seq in enumerate(seqs):
            self._check_judgeable(seq, seq.source or f"X[{i}]")
        return np.stack([self._class_scores(seq) for seq in seqs])

    def _check_judgeable(self, seq: PoseSequence, where: str) -> None:
        if torso_share(seq) == 0.0:
            raise InputError(f"{no_person(seq)}: nothing to classify", where)
        if seq.positions.shape[0] < 2:
            raise InputError("has one frame, no movement: nothing to classify", where)

    def predict(self, X: Sequence[PoseSequence]) -> np.ndarray:
        """The class of each clip, ``(n_clips,)``."""
        scores = self.decision_function(X)  # checks fitted before classes_ is read
        return np.asarray(self.classes_[np.argmax(scores, axis=1)])

    def predict_proba(self, X: Sequence[PoseSequence]) -> np.ndarray:
        """The class scores normalised to sum to one, ``(n_clips, n_classes)``: each class's
        score clipped at 0, plus 1e-9 and a trace (1e-12) of the score itself, so that the
        order is :meth:`predict`'s (a class whose best activity scored 0 stays above a class
        with no activity, as in its argmax)."""
        decision = self.decision_function(X)  # >= -1 (no activity)
        scores = np.clip(decision, 0.0, None) + 1e-9 + 1e-12 * (1.0 + decision)
        return np.asarray(scores / scores.sum(axis=1, keepdims=True))
