"""DAD (Dynamic Action Detection): the expert-system baseline, no training data needed.

- :mod:`cbr.dad.outcome`: what DAD answers for a clip (``DADResult``, ``ActivityScore``,
  ``QMPOutcome``);
- :mod:`cbr.dad.matching`: the heaviest chain of QMPs detected in order (``ordered_match``);
- :mod:`cbr.dad.detection`: windows, QMP criteria and activity scores (``detect``,
  ``detect_signals``, ``DADConfig``);
- :mod:`cbr.dad.names`: which of a dataset's class names an activity stands for
  (``class_of_activity``, ``label_key``: case, spaces, underscores and hyphens ignored);
- :mod:`cbr.dad.classifier`: ``DADClassifier``, the scikit-learn face of DAD.

It depends on :mod:`features` only; the CBR core never imports it. ``DADClassifier`` is
imported on first use: ``posecbr dad`` (which calls :func:`detect`) loads no scikit-learn.
"""

from typing import TYPE_CHECKING, Any

from .detection import DADConfig, detect, detect_signals
from .matching import ordered_match
from .names import class_of_activity, label_key, stands_for
from .outcome import NOT_ENOUGH_DATA, ActivityScore, DADResult, QMPOutcome

if TYPE_CHECKING:
    from .classifier import DADClassifier

__all__ = [
    "NOT_ENOUGH_DATA",
    "ActivityScore",
    "DADClassifier",
    "DADConfig",
    "DADResult",
    "QMPOutcome",
    "class_of_activity",
    "detect",
    "detect_signals",
    "label_key",
    "ordered_match",
    "stands_for",
]


def __getattr__(name: str) -> Any:
    if name == "DADClassifier":
        from .classifier import DADClassifier

        return DADClassifier
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
