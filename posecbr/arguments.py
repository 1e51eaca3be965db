"""The argparse types of the commands' arguments."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from features.errors import ConfigError


def path_arg(text: str) -> Path:
    """A file or folder argument. An empty one (``posecbr describe "$CLIP"`` with CLIP unset)
    is refused: ``Path("")`` is the current folder, which nobody named."""
    if not text:
        raise argparse.ArgumentTypeError("is an empty path (an unset variable?)")
    return Path(text)


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
