"""scikit-learn's estimator protocol, followed without importing scikit-learn.

scikit-learn takes any object that follows its protocol as an estimator (duck typing;
"Developing scikit-learn estimators" in its documentation): parameters are the keyword
arguments of ``__init__``, kept under their own names (``get_params``, ``set_params``, which
``sklearn.base.clone`` reads to make an unfitted copy), tags from ``__sklearn_tags__``, and
``NotFittedError`` from a method called before ``fit``. Subclassing ``sklearn.base``'s
classes would import scikit-learn (about a second: it brings SciPy's statistics and pandas)
in every command that classifies, for none of its algorithms. :class:`Classifier` follows the
protocol here; scikit-learn is imported only where its own types must be handed over: the
tags (asked for by scikit-learn itself, loaded already) and ``NotFittedError``, at the raise.
"""

from __future__ import annotations

import copy
import functools
import inspect
import math
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

from features.errors import ConfigError, InputError, ParameterError

#: how wide ``repr`` lays out the parameters before it wraps, as scikit-learn's repr does
REPR_WIDTH = 80


class Classifier:
    """A classifier as scikit-learn sees one: ``get_params``, ``set_params``, a repr naming
    the parameters that differ from their defaults, ``__sklearn_tags__`` (a classifier, its
    target required) and ``score`` (the accuracy). Subclasses define ``__init__`` storing
    every keyword argument under its own name, and ``fit`` and ``predict``."""

    @classmethod
    def _parameters(cls) -> list[inspect.Parameter]:
        """The parameters of ``__init__`` (without ``self``), sorted by name, as
        scikit-learn lists them."""
        params = list(inspect.signature(cls.__init__).parameters.values())[1:]
        if any(p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) for p in params):
            raise TypeError(f"{cls.__name__}.__init__ must name every parameter")
        return sorted(params, key=lambda p: p.name)

    def get_params(self, deep: bool = True) -> dict[str, Any]:  # noqa: ARG002
        """Every parameter's value, by name (``deep``: taken as scikit-learn passes it; no
        parameter of these classifiers is itself an estimator, so there is nothing deeper)."""
        return {p.name: getattr(self, p.name) for p in self._parameters()}

    def set_params(self, **params: Any) -> Any:
        """Set the named parameters and return the classifier; a name that is not a parameter
        is refused (:class:`features.errors.InputError`, a ``ValueError``) before any is set."""
        names = [p.name for p in self._parameters()]
        bad = next((name for name in params if name not in names), None)
        if bad is not None:
            raise InputError(
                f"Invalid parameter {bad!r} for estimator {type(self).__name__}; valid "
                f"parameters: {', '.join(names)}",
                "set_params",
            )
        for name, value in params.items():
            setattr(self, name, value)
        return self

    def __repr__(self) -> str:
        changed = [
            f"{p.name}={getattr(self, p.name)!r}"
            for p in self._parameters()
            if _differs(getattr(self, p.name), p.default)
        ]
        return _laid_out(type(self).__name__, changed)

    def __sklearn_tags__(self) -> Any:
        from sklearn.utils import ClassifierTags, Tags, TargetTags

        return Tags(
            estimator_type="classifier",
            target_tags=TargetTags(required=True),
            classifier_tags=ClassifierTags(),
        )

    def predict(self, X: Any) -> np.ndarray:
        raise NotImplementedError

    def score(self, X: Any, y: Any, sample_weight: Any = None) -> float:
        """The share of the clips in ``X`` whose predicted class is their label in ``y``
        (weighted by ``sample_weight``)."""
        return accuracy(y, self.predict(X), sample_weight)


def _differs(value: Any, default: Any) -> bool:
    """Whether a parameter's ``value`` is not its ``default``, as its repr shows it (a NaN
    is NaN)."""
    if _is_nan(value) and _is_nan(default):
        return False
    return repr(value) != repr(default)


def _is_nan(value: Any) -> bool:
    return isinstance(value, float | np.floating) and math.isnan(value)


def _laid_out(name: str, items: list[str]) -> str:
    """``name(item, item, ...)``, wrapped before an item that would pass :data:`REPR_WIDTH`
    and indented under the first."""
    if not items:
        return f"{name}()"
    indent = " " * (len(name) + 1)
    lines, line = [], f"{name}("
    for i, item in enumerate(items):
        piece = item + ("," if i < len(items) - 1 else ")")
        if not line.endswith("(") and len(line) + 1 + len(piece) > REPR_WIDTH:
            lines.append(line)
            line = indent + piece
        else:
            line += piece if line.endswith("(") else " " + piece
    return "\n".join([*lines, line])


Checked = TypeVar("Checked", bound=Callable[..., Any])


def parameters_checked(check: Checked) -> Checked:
    """``check`` (a method that refuses parameters) raising :class:`ParameterError`, a
    ``ValueError`` as scikit-learn's estimators raise for a parameter they cannot use, for
    any :class:`ConfigError` under it (the feature configuration's and the similarity
    registry's own checks among them); the message and what it names unchanged."""

    @functools.wraps(check)
    def checked(*args: Any, **kwargs: Any) -> Any:
        try:
            return check(*args, **kwargs)
        except ParameterError:
            raise
        except ConfigError as exc:
            raise ParameterError(exc.message, exc.source) from exc

    return checked  # type: ignore[return-value]


def accuracy(truth: Any, predicted: np.ndarray, sample_weight: Any = None) -> float:
    """The (weighted) share of ``predicted`` labels equal to the ``truth``; as many of each
    are needed, and each a label, not a sequence of them (a column ``[["a"], ["b"]]`` matched
    none: :class:`features.errors.InputError` otherwise, as ``fit`` refuses it)."""
    labels = list(truth) if hasattr(truth, "__iter__") and not isinstance(truth, str) else None
    if labels is None or len(labels) != len(predicted):
        given = "no sequence" if labels is None else f"{len(labels)} labels"
        raise InputError(f"must hold one label per clip ({len(predicted)}), got {given}", "y")
    nested = next((i for i, t in enumerate(labels) if np.ndim(t) != 0), None)
    if nested is not None:
        raise InputError(
            f"must be 1-D, one label per clip: y[{nested}] is a {type(labels[nested]).__name__}",
            "y",
        )
    right = np.array([bool(t == p) for t, p in zip(labels, predicted.tolist(), strict=True)])
    return float(np.average(right, weights=sample_weight))


def check_fitted(estimator: object, attribute: str) -> None:
    """Refuse ``estimator`` with scikit-learn's ``NotFittedError`` unless ``fit`` has set
    ``attribute`` (to anything but None)."""
    if getattr(estimator, attribute, None) is None:
        raise not_fitted(estimator, "call 'fit' with appropriate arguments before using it")


def check_case_base_classifier(clf: object, then: str) -> None:
    """Refuse ``clf`` unless it is a fitted case base classifier (it has a ``case_base_``):
    an unfitted one with scikit-learn's ``NotFittedError``, saying what to do (``then``), as
    its ``predict`` does; anything else (None, :func:`cbr.stored.load_classifier`'s
    ``StoredClassifier`` holding one, another kind of classifier) with
    :class:`features.errors.InputError` naming ``clf``: "not fitted" would send its caller to
    fit what is no such classifier."""
    if getattr(clf, "case_base_", None) is not None:
        return
    if isinstance(clf, Classifier) and callable(getattr(clf, "solve", None)):
        raise not_fitted(clf, then)
    got = "None" if clf is None else f"a {type(clf).__name__}"
    held = getattr(clf, "classifier", None)
    if getattr(held, "case_base_", None) is not None:  # load_classifier's StoredClassifier
        got += f" (its .classifier, a {type(held).__name__}, is one)"
    raise InputError(f"must be a fitted CaseBaseClassifier, got {got}", "clf")


def not_fitted(estimator: object, then: str) -> Exception:
    """scikit-learn's ``NotFittedError`` for ``estimator``, saying what to do (``then``).
    scikit-learn is imported here, for a caller's mistake alone."""
    from sklearn.exceptions import NotFittedError

    error: Exception = NotFittedError(
        f"This {type(estimator).__name__} instance is not fitted yet: {then}"
    )
    return error


Fitted = TypeVar("Fitted", bound=Classifier)


def unfitted_copy(estimator: Fitted) -> Fitted:
    """A new classifier of ``estimator``'s class with copies of its parameters and nothing
    fitted: what ``sklearn.base.clone`` makes of it."""
    return type(estimator)(**copy.deepcopy(estimator.get_params(deep=False)))
