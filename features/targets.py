"""A clip's value of a column (its label, subject or an extra, named in any case) as a class
name, or read as yes or no."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .clips import Clip


def extra(extras: Mapping[str, Any], column: str) -> Any:
    """The value of ``column`` among a clip's extras, its name in any case (a labels CSV's
    columns keep their spelling: ``Correct`` is the column ``correct``); None if absent."""
    if column in extras:
        return extras[column]
    low = column.strip().lower()
    return next((v for k, v in extras.items() if k.strip().lower() == low), None)


def clip_column(clip: Clip, column: str) -> Any:
    """A clip's value of ``column``: label, subject, or a metadata extra (None if absent)."""
    value = column_of(clip.label, clip.subject, clip.extras, column)
    return extra(clip.seq.metadata, column) if value is None else value


def column_of(label: str, subject: str | None, extras: Mapping[str, Any], column: str) -> Any:
    """The value of ``column`` of a clip of this label, subject and extras (None if absent)."""
    if column == "label":
        return label
    if column == "subject":
        return subject
    value = extra(extras, column)
    if value is None:  # named in another case: a read clip's metadata holds both
        low = column.strip().lower()
        return label if low == "label" else subject if low == "subject" else None
    return value


def clip_target(clip: Clip, column: str) -> str | None:
    """A clip's value of ``column`` as a class name (:func:`target_value`); None when the clip
    has none (absent or empty)."""
    return _as_target(clip_column(clip, column))


def clip_target_of(
    label: str, subject: str | None, extras: Mapping[str, Any], column: str
) -> str | None:
    """:func:`clip_target` of a clip of this label, subject and extras, not read yet."""
    return _as_target(column_of(label, subject, extras, column))


def _as_target(value: Any) -> str | None:
    return None if value is None or value == "" else target_value(value)


def target_value(value: Any) -> str:
    """A column value as a class name: booleans (UI-PRMD's ``correct``) read "correct" /
    "incorrect"."""
    if isinstance(value, bool | np.bool_):
        return "correct" if bool(value) else "incorrect"
    return str(value)


_TRUE = frozenset({"true", "1", "yes", "y", "t", "correct"})


_FALSE = frozenset({"false", "0", "no", "n", "f", "incorrect"})


def truth_value(value: Any) -> bool | None:
    """A class name read as yes or no (``"true"``, ``"1"``, ``"correct"``, ... / ``"false"``,
    ``"0"``, ``"incorrect"``, ...; any case); None when it reads as neither."""
    text = str(value).strip().lower()
    return True if text in _TRUE else False if text in _FALSE else None
