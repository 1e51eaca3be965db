"""Progress bars for anything that takes more than a few seconds (tqdm, on stderr)."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Iterator
from typing import TypeVar

from .text import shown

T = TypeVar("T")


def progress_enabled() -> bool:
    """Bars show on an interactive stderr unless POSECBR_NO_PROGRESS is set."""
    return sys.stderr.isatty() and not os.environ.get("POSECBR_NO_PROGRESS")


def progress(
    items: Iterable[T], desc: str, total: int | None = None, unit: str = "it", leave: bool = True
) -> Iterator[T]:
    """Iterate ``items`` with a progress bar on stderr (silent when not interactive)."""
    if not progress_enabled():
        yield from items
        return
    from tqdm import tqdm  # imported only when a bar is shown

    yield from tqdm(
        items,
        desc=shown(desc),  # descriptions name the user's files
        total=total,
        unit=unit,
        leave=leave,
        file=sys.stderr,
        dynamic_ncols=True,
    )
