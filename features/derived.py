"""What one clip yields, computed once per :class:`~features.poses.PoseSequence` object and kept
for as long as that object lives: its fluents, state signals and QMPs (and, through
:mod:`features.body`, its mirror image and body-frame positions).

Fluent evaluation is the expensive part and does not depend on any case-base configuration,
so cross-validation folds, mirror handling and explanations share one computation per clip.
:func:`forget` drops a clip's entries early (bounded memory when streaming a corpus).
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from .fluents import FluentResult
    from .poses import PoseSequence
    from .qmp import QMPFeatures
    from .signals import StateSignals

T = TypeVar("T")
_CACHES: dict[str, weakref.WeakKeyDictionary[Any, Any]] = {}


def derived(seq: PoseSequence, kind: str, compute: Callable[[PoseSequence], T]) -> T:
    """``compute(seq)``, computed once per sequence object and ``kind``."""
    cache = _CACHES.setdefault(kind, weakref.WeakKeyDictionary())
    out = cache.get(seq)
    if out is None:
        out = compute(seq)
        cache[seq] = out
    return out


def forget(seq: PoseSequence) -> None:
    """Drop everything cached for ``seq``."""
    for cache in _CACHES.values():
        cache.pop(seq, None)


def fluents_of(seq: PoseSequence) -> FluentResult:
    """:func:`features.fluents.evaluate` of the canonical clip, cached."""

    def compute(s: PoseSequence) -> FluentResult:
        from .fluents import evaluate

        return evaluate(s.to_canonical())

    return derived(seq, "fluents", compute)


def signals_of(seq: PoseSequence) -> StateSignals:
    """:func:`features.signals.state_signals` of the canonical clip, cached."""

    def compute(s: PoseSequence) -> StateSignals:
        from .signals import state_signals

        return state_signals(s.to_canonical())

    return derived(seq, "signals", compute)


def qmp_of(seq: PoseSequence) -> QMPFeatures:
    """:func:`features.qmp.qmp_features` of the canonical clip, cached."""

    def compute(s: PoseSequence) -> QMPFeatures:
        from .qmp import qmp_features

        return qmp_features(s.to_canonical())

    return derived(seq, "qmp", compute)
