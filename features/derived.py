"""What one clip yields, computed once per :class:`~features.poses.PoseSequence` object and kept
for as long as that object lives: its fluents, state signals and QMPs (and, through
:mod:`features.body`, its mirror image and body-frame positions).

Fluent evaluation is the expensive part and does not depend on any case-base configuration,
so cross-validation folds, mirror handling and explanations share one computation per clip.
:func:`forget` drops a clip's entries early (bounded memory when streaming a corpus).
:func:`stretch` cuts frames out of a clip sharing what was computed per frame for the whole
clip (segmenting a long recording classifies many overlapping stretches of it).
"""

from __future__ import annotations

import dataclasses
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from .fluents import FluentResult
    from .poses import PoseSequence
    from .qmp import QMPFeatures
    from .repetitions import MovementSignals
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


def is_cached(seq: PoseSequence, kind: str) -> bool:
    """Whether ``kind`` is already computed for ``seq`` (a caller warmed it and keeps it)."""
    cache = _CACHES.get(kind)
    return cache is not None and seq in cache


def forget(seq: PoseSequence) -> None:
    """Drop everything cached for ``seq`` (over a copy of the kinds: another thread may
    compute a kind for the first time meanwhile)."""
    for cache in list(_CACHES.values()):
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


def movement_signals_of(seq: PoseSequence) -> MovementSignals:
    """:func:`features.repetitions.movement_signals` of the canonical clip (the joint angles
    repetitions are counted on), cached: segmenting a recording counts the periods in many
    spans of them and the repetitions of every segment."""

    def compute(s: PoseSequence) -> MovementSignals:
        from .repetitions import movement_signals

        return movement_signals(s.to_canonical())

    return derived(seq, "movement_signals", compute)


def _cut_rows(value: Any, start: int, stop: int) -> Any:
    """The frames ``start:stop`` of a per-frame result (fluents, state signals, an array)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        arrays = {
            f.name: getattr(value, f.name)[start:stop]
            for f in dataclasses.fields(value)
            if f.name in ("confidence", "values", "head_length_m", "distances_m")
        }
        return dataclasses.replace(value, **arrays)
    return value[start:stop]


# results with one row per frame: a stretch's rows are the clip's rows
_PER_FRAME = ("fluents", "signals", "arm_planes", "frame_rows", "torso_rows")


def stretch(seq: PoseSequence, start: int, stop: int) -> PoseSequence:
    """Frames ``start`` (inclusive) to ``stop`` (exclusive) of ``seq`` as a new clip that shares
    the per-frame results already computed for ``seq``: its fluents, state signals, arm planes,
    the rows its body frame is set from and which frames show the torso, and those of its
    mirror image. Motion states near the cut then keep the frames around it as context, as
    they had in the whole clip. Per-clip results (body-frame positions, which side moves
    more, QMPs) are computed for the stretch itself."""
    part = seq.slice_frames(start, stop)
    for kind in _PER_FRAME:
        cache = _CACHES.get(kind)
        value = None if cache is None else cache.get(seq)
        if cache is not None and value is not None:
            cache[part] = _cut_rows(value, start, stop)
    mirrors = _CACHES.get("mirror")
    mirror = None if mirrors is None else mirrors.get(seq)
    if mirrors is not None and mirror is not None:
        mirrors[part] = stretch(mirror, start, stop)
    return part
