"""Writing outputs safely: every file posecbr writes appears whole or not at all, and never
replaces one of the inputs it was made from.

- :func:`atomic_path`: a temporary file beside the destination, renamed over it only when the
  writer finished without error (a crash or kill leaves the old file, or none, plus no stray
  temporary file once the ``with`` block is left);
- :func:`write_text_atomic`, :func:`write_bytes_atomic`, :func:`write_json_atomic`: the usual
  cases of that;
- :func:`check_output`: before any work starts, refuse an output path that is a folder, lies in
  a folder that does not exist, or is one of the inputs.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .errors import DataError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_path(path: str | Path, *, make_parents: bool = True) -> Iterator[Path]:
    """A temporary path beside ``path``; renamed to ``path`` when the block ends normally.

    The temporary file has the permissions of an ordinary new file (umask applied). On an error
    inside the block it is removed and ``path`` is left as it was.
    """
    dest = Path(path)
    try:
        if make_parents:
            dest.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=dest.parent)
        os.close(fd)
    except OSError as exc:
        raise DataError(f"cannot write: {exc.strerror or exc}", dest) from None
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; outputs are ordinary files
        os.replace(tmp, dest)
    except OSError as exc:
        raise DataError(f"cannot write: {exc.strerror or exc}", dest) from None
    finally:
        tmp.unlink(missing_ok=True)


def write_bytes_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8, newlines as given) to ``path`` atomically."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
    return Path(path)


def write_json_atomic(path: str | Path, obj: Any, *, indent: int | None = 1) -> Path:
    """Write ``obj`` as JSON (UTF-8, non-ASCII kept, NaN allowed) to ``path`` atomically."""
    text = json.dumps(obj, indent=indent, ensure_ascii=False, allow_nan=True)
    return write_text_atomic(path, text + "\n")


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (a.exists() and b.exists() and a.samefile(b))
    except OSError:
        return False


def check_output(
    path: str | Path,
    *,
    inputs: Iterable[str | Path] = (),
    what: str = "output",
    must_not_exist: bool = False,
    make_parents: bool = False,
) -> Path:
    """Check an output path before any work starts; returns it as a Path.

    Refused, with one line naming the path: a folder; a file inside a folder that does not
    exist (unless ``make_parents``: the writer creates it, so only a file in its way is
    refused); one of ``inputs`` (an output never overwrites an input); an existing file when
    ``must_not_exist``.
    """
    out = Path(path)
    if out.is_dir():
        raise DataError(f"the {what} is a folder, not a file", out)
    if make_parents:
        parent = next((p for p in out.parents if p.exists()), None)
        if parent is not None and not parent.is_dir():
            raise DataError(f"cannot write the {what}: {parent} is a file, not a folder", out)
    elif not out.parent.is_dir():
        raise DataError(f"the folder of the {what} does not exist", out.parent)
    for src in inputs:
        if _same_file(out, Path(src)):
            raise DataError(f"the {what} would overwrite an input ({src})", out)
    if must_not_exist and out.exists():
        raise DataError(f"the {what} already exists", out)
    return out
