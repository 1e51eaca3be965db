"""The argparse types of the commands' arguments, and what is checked of them against the data."""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Collection, Iterable
from pathlib import Path
from typing import Any

from features.errors import ConfigError

#: a URL's scheme and "://" (two letters at least: not a drive letter)
_URL = re.compile(r"[A-Za-z][A-Za-z0-9+.-]+://")


def path_arg(text: str) -> Path:
    """A file or folder argument. An empty one (``posecbr describe "$CLIP"`` with CLIP unset)
    is refused: ``Path("")`` is the current folder, which nobody named. So is a URL: as a
    path its "//" became "/" (``http:/me:secret@host/x.mp4``), and the file of that name
    was not found, said with the password shown (the messages hide a URL's password, not
    a path's)."""
    if not text:
        raise argparse.ArgumentTypeError("is an empty path (an unset variable?)")
    if is_url(text):
        raise argparse.ArgumentTypeError(f"{text} {NOT_A_PATH}")
    return Path(text)


#: what a URL given for a file is told
NOT_A_PATH = (
    "is a URL, not a path on this machine (posecbr watch plays a stream; the other commands"
    " read and write files)"
)


def is_url(text: str) -> bool:
    """Whether ``text`` begins as a URL does (``http://``, ``rtsp://``, ``file://``)."""
    return bool(_URL.match(text))


#: the largest whole number a ``--param`` value may be: past it no float (nor a C long, which
#: numba and numpy read parameters as) holds it
MAX_PARAM_INT = 2**63 - 1


def param_value(key: str, raw: str) -> Any:
    """The value of ``--param KEY=RAW``: RAW read as JSON when it parses (numbers, lists,
    true, null), else the string itself. A number past any float or of more digits than
    Python reads is refused here, naming the key: it was a traceback of the check that meets
    it (``float(10**400)``)."""
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        return raw
    except RecursionError:  # json's decoder recurses once per level of nesting
        raise ConfigError(f"the value of {key} is nested too deeply", "--param") from None
    except ValueError:  # a whole number of more digits than Python reads
        raise ConfigError(
            f"the value of {key} is a number of more than {sys.get_int_max_str_digits()} digits",
            "--param",
        ) from None
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, list):
            stack.extend(item)
        elif isinstance(item, dict):
            stack.extend(item.values())
        elif isinstance(item, int) and not isinstance(item, bool) and abs(item) > MAX_PARAM_INT:
            raise ConfigError(f"the value of {key} holds too large a number", "--param")
    return value


def check_found(found: Iterable[Any], asked: Collection[str] | None, flag: str, what: str) -> None:
    """Refuse a ``--labels`` or ``--subjects`` entry (``asked``) that none of the clips' values
    ``found`` is (mistyped): the work on the others alone would be taken for the one asked
    for. ``what`` says what a clip is to have it ("labelled", "of subject")."""
    have = {str(v) for v in found if v is not None}
    missing = sorted(set(asked or ()) - have)
    if missing:
        raise ConfigError(f"no clip {what} {', '.join(repr(m) for m in missing)} in the data", flag)
