"""DAD (Dynamic Action Detection): the expert-system baseline, no training data needed.

- :mod:`cbr.dad.outcome`: what DAD answers for a clip (``DADResult``, ``ActivityScore``,
  ``QMPOutcome``);
- :mod:`cbr.dad.matching`: the heaviest chain of QMPs detected in order (``ordered_match``);
- :mod:`cbr.dad.detection`: windows, QMP criteria and activity scores (``detect``,
  ``detect_signals``, ``DADConfig``);
- :mod:`cbr.dad.classifier`: ``DADClassifier``, the scikit-learn face of DAD.

It depends on :mod:`features` only; the CBR core never imports it.
"""

from .classifier import DADClassifier
from .detection import DADConfig, detect, detect_signals
from .matching import ordered_match
from .outcome import NOT_ENOUGH_DATA, ActivityScore, DADResult, QMPOutcome

__all__ = [
    "NOT_ENOUGH_DATA",
    "ActivityScore",
    "DADClassifier",
    "DADConfig",
    "DADResult",
    "QMPOutcome",
    "detect",
    "detect_signals",
    "ordered_match",
]
