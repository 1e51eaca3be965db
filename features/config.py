"""Reading the user's configuration files (fluent thresholds, the ADD): JSON or TOML, checked
so that any problem is one ConfigError naming the file."""

from __future__ import annotations

import json
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

from features.errors import ConfigError
from features.fileio import not_utf8

# A configuration file is a few kilobytes; anything far larger is the wrong file.
MAX_CONFIG_BYTES = 10 * 1024**2


def _read_text(path: Path, what: str) -> str:
    if path.is_dir():
        raise ConfigError(f"the {what} is a folder, not a file", path)
    try:
        size = path.stat().st_size
        if size > MAX_CONFIG_BYTES:
            raise ConfigError(
                f"the {what} is {size / 1e6:.0f} MB: too large for a configuration file", path
            )
        # a pipe or a device has no size to check first: read no more than the most allowed
        with path.open("rb") as fh:
            data = fh.read(MAX_CONFIG_BYTES + 1)
        if len(data) > MAX_CONFIG_BYTES:
            raise ConfigError(
                f"the {what} is over {MAX_CONFIG_BYTES / 1e6:.0f} MB: too large for a"
                " configuration file",
                path,
            )
    except FileNotFoundError:
        raise ConfigError(f"{what} not found", path) from None
    except OSError as exc:
        raise ConfigError(f"cannot read the {what} ({exc.strerror or exc})", path) from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"the {what} is not UTF-8 text{_not_utf8(data, exc)}", path) from None


def _not_utf8(data: bytes, exc: UnicodeDecodeError) -> str:
    """What a configuration file that is not UTF-8 text is, after "is not UTF-8 text": UTF-16
    and the binary files a user has beside it (a gzip-compressed copy, a case base) said as
    such, where every one was "a binary file?"; else where its first character that is not
    UTF-8 stands."""
    why = not_utf8(data, exc)
    if why.utf16:
        return ": it is UTF-16 (its byte order mark); save it as UTF-8"
    if why.binary is not None:
        return f": it is {why.binary}"
    return f" ({why.where}): save it as UTF-8"


def read_config(
    path: str | Path, what: str, fmt: Literal["json", "toml"] | None = None
) -> Mapping[str, Any]:
    """The table in a JSON or TOML file (``fmt``; None: TOML for ``.toml``, else JSON)."""
    path = Path(path)
    text = _read_text(path, what)
    fmt = fmt or ("toml" if path.suffix.lower() == ".toml" else "json")

    def unique(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        # JSON's reader keeps the last of a repeated key and drops the others unsaid (TOML's
        # refuses them): a setting given twice is a mistake to name, not to guess at
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                raise ConfigError(f"the key {key[:64]!r} is given twice in one object", path)
            seen.add(key)
        return dict(pairs)

    try:
        raw = tomllib.loads(text) if fmt == "toml" else json.loads(text, object_pairs_hook=unique)
    except RecursionError:
        raise ConfigError(f"the {what} is nested too deeply", path) from None
    except ValueError as exc:  # JSONDecodeError, TOMLDecodeError, over-long integers
        raise ConfigError(f"not valid {fmt.upper()} ({exc})", path) from None
    if not isinstance(raw, Mapping):
        raise ConfigError(f"the {what} must hold a table/object at the top level", path)
    return raw


__all__ = ["MAX_CONFIG_BYTES", "read_config"]
