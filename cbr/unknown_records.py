"""A calibrated judge as a plain record of its fields, stored with the fitted model and read back
checked, a field added later stored apart where an older posecbr does not look."""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Mapping
from typing import Any, TypeVar

from .casebase import CaseBase
from .unknown_held_out import Held

_C = TypeVar("_C", bound="Calibrated")


class Calibrated:
    """A judge calibrated on a case base: a frozen dataclass stored with the fitted model as a
    plain record of its fields (:meth:`to_dict`, :meth:`from_dict`), so that ``segment`` and
    ``watch`` read it instead of scanning the case base each run. Generic over the fields: a
    new field (with a default, which a record stored before it takes) or a new judge (one
    line in :data:`cbr.unknown_stored.STORED`) needs no code here. Fields are ``float`` (>= 0,
    not NaN; +inf is written ``"inf"``: JSON has none), ``int`` (>= 0), ``str``, ``tuple[float,
    ...]`` (a list of such numbers) or ``tuple[str, ...]`` (a list of texts).

    A field added once posecbr stored judges, which a reader that does not know it can do
    without, is marked ``metadata={ADDED: True}``: it is stored apart from the record
    (:func:`cbr.unknown_stored.judges_apart`), where an older posecbr does not look (its reader
    refuses a record with a field it does not know: "unknown field 'activities'"), and a field
    stored apart that this reader does not know (a newer posecbr's) is ignored
    (:meth:`from_dict`)."""

    @classmethod
    def of(cls: type[_C], cb: CaseBase, *, held: Held | None = None) -> _C:
        """Calibrated on ``cb`` (``held``: its :func:`cbr.unknown_held_out.held_out_activities`,
        when measured)."""
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        """The fields as JSON-ready values."""
        return {
            f.name: _plain(getattr(self, f.name))
            for f in dataclasses.fields(typing.cast(Any, self))
        }

    @classmethod
    def from_dict(cls: type[_C], d: Mapping[str, Any], added: Any = None) -> _C:
        """The judge :meth:`to_dict` wrote (``d``), with the fields stored apart from it
        (``added``: :func:`cbr.unknown_stored.judges_apart`; a field of it this reader does not
        know, a newer posecbr's, is ignored). ValueError naming the field for a record that is
        not one: an unknown field in ``d``, a missing one without a default, a wrong type, a
        negative or NaN number, a field stored both in ``d`` and apart or apart though not
        marked so."""
        if not isinstance(d, Mapping):
            raise ValueError(f"a stored judge must be a record of fields, got {d!r}")
        fields = {f.name: f for f in dataclasses.fields(typing.cast(Any, cls))}
        extra = sorted(set(d) - set(fields))
        if extra:
            raise ValueError(f"unknown field {extra[0]!r}")
        d = {**d, **_added_known(cls, fields, d, added)}
        types = typing.get_type_hints(cls)
        values = {}
        for name, f in fields.items():
            if name in d:
                values[name] = _field(name, types[name], d[name])
            elif f.default is dataclasses.MISSING:
                raise ValueError(f"field {name!r} is missing")
        return cls(**values)


ADDED = "added"
"""The metadata key marking a judge's field stored apart from its record
(:class:`Calibrated`)."""


def added_fields(cls: Any) -> tuple[str, ...]:
    """The fields of the judge (or judge class) ``cls`` stored apart from its record (marked
    :data:`ADDED`), in their order."""
    return tuple(f.name for f in dataclasses.fields(cls) if f.metadata.get(ADDED))


def _added_known(
    cls: Any, fields: Mapping[str, Any], d: Mapping[str, Any], added: Any
) -> dict[str, Any]:
    """The fields stored apart (``added``) that ``cls`` knows, checked against its record
    ``d`` (:meth:`Calibrated.from_dict`); the others, a newer posecbr's, left out."""
    if added is None:
        return {}
    if not isinstance(added, Mapping):
        raise ValueError(f"the fields stored apart must be a record of fields, got {added!r}")
    apart = set(added_fields(cls))
    out = {}
    for name in sorted(set(added) & set(fields)):
        if name in d:
            raise ValueError(f"field {name!r} is stored twice (in the record and apart)")
        if name not in apart:
            raise ValueError(f"field {name!r} is stored apart, where it is not kept")
        out[name] = added[name]
    return out


def _plain(value: Any) -> Any:
    """A field's value for JSON: +inf as ``"inf"``."""
    if isinstance(value, float) and math.isinf(value) and value > 0:
        return "inf"
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _field(name: str, kind: Any, value: Any) -> Any:
    """A stored field's value as its type ``kind`` (ValueError naming ``name`` when it is not
    one)."""
    if kind is float:
        number = math.inf if value == "inf" else value
        if isinstance(number, int | float) and not isinstance(number, bool) and number >= 0:
            return float(number)  # NaN fails the comparison
        raise ValueError(f"field {name!r} must be a number >= 0, got {value!r}")
    if kind is int:
        if isinstance(value, int) and not isinstance(value, bool) and value >= 0:
            return value
        raise ValueError(f"field {name!r} must be a whole number >= 0, got {value!r}")
    if kind is str:
        if isinstance(value, str) and value:
            return value
        raise ValueError(f"field {name!r} must be a non-empty text, got {value!r}")
    if typing.get_origin(kind) is tuple:  # tuple[float, ...], tuple[str, ...]
        (item, _) = typing.get_args(kind)
        if isinstance(value, list):
            return tuple(_field(name, item, v) for v in value)
        words = "numbers >= 0" if item is float else "texts"
        raise ValueError(f"field {name!r} must be a list of {words}, got {value!r}")
    raise ValueError(f"field {name!r} is of a type that is not stored ({kind!r})")
