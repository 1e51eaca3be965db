"""The project's benchmarks: ``python -m benchmarks`` runs them all (see ``__main__``)."""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path
from typing import Any

from features.fileio import write_json_atomic


def write_json(doc: Any, path: Path) -> None:
    """Write ``doc`` as JSON to ``path`` atomically (a temporary file beside it, then rename);
    a figure that is not a finite number (a median of no boundary found: infinite) is written
    null, since JSON has no NaN or Infinity and strict readers refuse them. A result that does
    not record the machine gets it (:func:`cbr.evaluation.machine.machine_info`: Python,
    platform, processor, CPUs and library versions), so a benchmark run alone records it as
    one run by ``python -m benchmarks`` does."""
    if isinstance(doc, dict) and "machine" not in doc:
        from cbr.evaluation.machine import machine_info

        doc = {**doc, "machine": machine_info()}
    write_json_atomic(path, _finite(doc))


def _finite(value: Any) -> Any:
    """``value`` with every float that is not finite replaced by None, in lists and dicts."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def json_out(value: str) -> Path:
    """The type of a benchmark's ``--out``: the results JSON to write. A folder (one there, or
    a name ending in ``/``) is refused when the options are read, before the run: the
    benchmark ran to its end and then stopped with a traceback saying the output "is not a
    regular file (a device, pipe or socket)"."""
    if value.endswith(("/", os.sep)) or Path(value).is_dir():
        raise argparse.ArgumentTypeError(
            f"{value} is a folder: name the .json file to write the results to"
        )
    return Path(value)


def no_options(name: str, doc: str | None, argv: list[str] | None) -> None:
    """Parse ``argv`` for ``python -m benchmarks.<name>``, which takes no options: ``--help``
    prints ``doc`` (what it measures and writes) instead of running it and overwriting its
    results, and an unknown option is refused (exit 2)."""
    argparse.ArgumentParser(
        prog=f"python -m benchmarks.{name}",
        description=doc,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    ).parse_args(argv)
