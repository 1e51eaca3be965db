"""The project's benchmarks: ``python -m benchmarks`` runs them all (see ``__main__``)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from features.fileio import write_json_atomic


def write_json(doc: Any, path: Path) -> None:
    """Write ``doc`` as JSON to ``path`` atomically (a temporary file beside it, then rename)."""
    write_json_atomic(path, doc)


def no_options(name: str, doc: str | None, argv: list[str] | None) -> None:
    """Parse ``argv`` for ``python -m benchmarks.<name>``, which takes no options: ``--help``
    prints ``doc`` (what it measures and writes) instead of running it and overwriting its
    results, and an unknown option is refused (exit 2)."""
    argparse.ArgumentParser(
        prog=f"python -m benchmarks.{name}",
        description=doc,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    ).parse_args(argv)
