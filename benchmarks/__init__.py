"""The project's benchmarks: ``python -m benchmarks`` runs them all (see ``__main__``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from features.fileio import write_json_atomic


def write_json(doc: Any, path: Path) -> None:
    """Write ``doc`` as JSON to ``path`` atomically (a temporary file beside it, then rename)."""
    write_json_atomic(path, doc)
