"""The argparse types of the commands' arguments."""

from __future__ import annotations

import argparse
from pathlib import Path


def path_arg(text: str) -> Path:
    """A file or folder argument. An empty one (``posecbr describe "$CLIP"`` with CLIP unset)
    is refused: ``Path("")`` is the current folder, which nobody named."""
    if not text:
        raise argparse.ArgumentTypeError("is an empty path (an unset variable?)")
    return Path(text)
