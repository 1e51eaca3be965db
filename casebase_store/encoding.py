"""Values as a store keeps them: arrays as ``.npy`` bytes, documents as canonical JSON, text
refused where any backend would refuse it, times in UTC."""

from __future__ import annotations

import hashlib
import io
import json
import re
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from typing import Any

import numpy as np

from .errors import StoreError


def encode_array(array: np.ndarray) -> bytes:
    """``.npy`` bytes of ``array`` (no pickles: an array of Python objects is a
    :class:`StoreError`)."""
    values = np.asarray(array, order="C")  # a 0-d array stays 0-d
    if values.dtype.hasobject:
        raise StoreError(
            "an array of Python objects (dtype object) cannot be stored: "
            "give numbers or text (a numeric or str dtype)"
        )
    buf = io.BytesIO()
    np.save(buf, values, allow_pickle=False)
    return buf.getvalue()


def decode_array(data: bytes, what: str = "array", where: str = "") -> np.ndarray:
    """The array stored by :func:`encode_array`; a damaged blob is a :class:`StoreError`
    naming ``what`` (e.g. ``"features of case 12"``)."""
    try:
        array: np.ndarray = np.load(io.BytesIO(data), allow_pickle=False)
        return array
    except (ValueError, OSError, EOFError, TypeError) as exc:
        raise StoreError(f"the {what} is damaged ({exc})", where or None) from None


def decode_arrays(blobs: Sequence[bytes], what: Sequence[str], where: str = "") -> list[np.ndarray]:
    """:func:`decode_array` of each of ``blobs`` (``what``: each one's name for an error),
    as float64; a blob with the ``.npy`` header of the one before it (the cases of a case
    base share theirs) is read as a view of its bytes, its header not parsed again (parsing
    is most of :func:`numpy.load`'s time: 60 us a blob, 1.3 s of CPU for 20,000 cases)."""
    out: list[np.ndarray] = []
    head, like = b"", None
    for blob, name in zip(blobs, what, strict=True):
        if like is not None and len(blob) == len(head) + like.nbytes and blob.startswith(head):
            out.append(np.frombuffer(blob, like.dtype, offset=len(head)).reshape(like.shape))
            continue
        array = decode_array(blob, name, where)
        if not np.issubdtype(array.dtype, np.number) or np.iscomplexobj(array):
            raise StoreError(f"the {name} is damaged (not real numbers)", where or None)
        out.append(array.astype(np.float64, copy=False))
        if array.dtype == np.float64 and array.flags.c_contiguous and 0 < array.nbytes:
            head, like = blob[: len(blob) - array.nbytes], array
    return out


def read_json(text: str, what: str, where: str) -> Any:
    try:
        return json.loads(text)
    except (TypeError, ValueError) as exc:
        raise StoreError(f"the {what} is not valid JSON ({exc})", where) from None


def config_hash(config: Mapping[str, Any]) -> str:
    """SHA-256 of the canonical JSON of a feature configuration."""
    return hashlib.sha256(canonical_json(config).encode("utf-8")).hexdigest()


def canonical_json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=False)


def as_utc(value: datetime) -> datetime:
    """Timezone-aware UTC: SQLite hands stored times back naive (they were written in UTC),
    PostgreSQL aware in the session's zone; callers get the same value from both."""
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


#: The longest case base name a store holds (its column's width on every backend)
NAME_MAX = 200


def check_case_base_name(name: str, where: str) -> str:
    """``name`` when a store can hold it as a case base's name (text of at most
    :data:`NAME_MAX` characters, not blank, no NUL, UTF-8); else a :class:`StoreError` naming
    ``where``: for a command to refuse it before any work, as the write would."""
    check_text(name, "case base name", where, max_len=NAME_MAX)
    if not name.strip():
        raise StoreError("the case base name is empty", where)
    return name


def check_text(value: str, what: str, where: str, max_len: int | None = None) -> str:
    # PostgreSQL refuses NUL in text and enforces VARCHAR lengths, SQLite stores both; refuse
    # them on every backend so a store behaves the same wherever it lives
    if not isinstance(value, str):
        raise StoreError(f"the {what} must be text, got {value!r}", where)
    if "\x00" in value:
        raise StoreError(f"{what} {value!r} contains a NUL character", where)
    _check_utf8(value, what, where)
    if max_len is not None and len(value) > max_len:
        raise StoreError(
            f"{what} is {len(value)} characters long (at most {max_len}): {value[:40]!r}...",
            where,
        )
    return value


def check_poses(value: str, where: str) -> str:
    """A case's poses digest: a SHA-256 as 64 hexadecimal digits (what compares them)."""
    if not isinstance(value, str) or not re.fullmatch(r"[0-9a-f]{64}", value):
        raise StoreError(f"a poses digest is 64 hexadecimal digits, got {value!r}", where)
    return value


def _check_utf8(value: str, what: str, where: str, within: str = "") -> None:
    """Refuse text that has no UTF-8 form: a name read from a file or folder whose bytes are
    not UTF-8 (Python keeps them as lone surrogates), which no database driver can send.
    ``within``: the document that holds it."""
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        said = f"the {within} holds {value!r}, which" if within else f"{what} {value!r}"
        raise StoreError(
            f"{said} is not UTF-8 text (a name in another encoding, from a file or folder"
            " name?): rename it",
            where,
        ) from None


def check_document(doc: Any, what: str, where: str) -> Any:
    """``doc`` (JSON-ready), every string in it checked by :func:`_check_utf8`."""
    stack = [doc]
    while stack:
        item = stack.pop()
        if isinstance(item, str):
            _check_utf8(item, "text", where, within=what)
        elif isinstance(item, Mapping):
            stack.extend(item.keys())
            stack.extend(item.values())
        elif isinstance(item, list | tuple):
            stack.extend(item)
    return doc


def as_stored(text: str) -> str:
    """Provenance text (a clip's file name, a log entry's reason) as it is stored: bytes of a
    file name that are not UTF-8 written as ``\\xNN`` (the name stays readable and the same
    name is always stored alike)."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    return text
