"""The registry of similarity measures: names -> classes (see :mod:`cbr.similarity.base`).

Kept apart from the measures and free of numpy, so that listing the names (``posecbr
--help``) imports nothing heavy: a built-in measure's module is imported when it is first
asked for by name (``dtw`` brings numba and scipy, ``signature`` iisignature), and measures
published as entry points in the group ``posecbr.similarity`` load on the first look-up.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

from features.errors import ConfigError
from features.text import did_you_mean

if TYPE_CHECKING:
    from .base import SimilarityMeasure

_REGISTRY: dict[str, type[SimilarityMeasure]] = {}
_BUILTIN = {
    "dtw": "cbr.similarity.dtw",
    "euclidean": "cbr.similarity.euclidean",
    "signature": "cbr.similarity.signature",
}
_ENTRY_POINTS_LOADED = False
M = TypeVar("M", bound="type[SimilarityMeasure]")


def register_measure(name: str) -> Callable[[M], M]:
    """Class decorator registering a :class:`SimilarityMeasure` under ``name``."""

    def deco(cls: M) -> M:
        cls.name = name
        _REGISTRY[name] = cls
        return cls

    return deco


def _load_entry_points() -> None:
    global _ENTRY_POINTS_LOADED
    if _ENTRY_POINTS_LOADED:
        return
    _ENTRY_POINTS_LOADED = True
    from importlib.metadata import entry_points

    for ep in entry_points(group="posecbr.similarity"):
        ep.load()


def available_measures() -> tuple[str, ...]:
    """Names of every measure: built in, registered or published as an entry point."""
    _load_entry_points()
    return tuple(sorted(set(_REGISTRY) | set(_BUILTIN)))


def get_measure(spec: str | SimilarityMeasure | dict[str, Any], **params: Any) -> SimilarityMeasure:
    """A measure from its name (+ params), a ``params()`` dict, or a measure instance."""
    from .base import SimilarityMeasure

    if isinstance(spec, SimilarityMeasure):
        return dataclasses.replace(spec, **params) if params else spec
    if isinstance(spec, dict):
        params = {**{k: v for k, v in spec.items() if k != "name"}, **params}
        spec = str(spec.get("name", ""))
    _load_entry_points()
    if str(spec) in _BUILTIN and str(spec) not in _REGISTRY:
        importlib.import_module(_BUILTIN[str(spec)])
    cls = _REGISTRY.get(str(spec))
    if cls is None:
        raise ConfigError(
            f"unknown similarity {spec!r} (known: {', '.join(available_measures())})"
            f"{did_you_mean(str(spec), available_measures())}",
            "similarity",
        )
    fields = {f.name for f in dataclasses.fields(cls)}
    bad = sorted(set(params) - fields)
    if bad:
        raise ConfigError(
            f"similarity {spec!r} has no parameter {', '.join(bad)} "
            f"(parameters: {', '.join(sorted(fields)) or 'none'})",
            "similarity",
        )
    try:
        return cls(**params)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"bad parameters for similarity {spec!r}: {exc}", "similarity") from None
