"""The case matrix of a large case base as a memory-mapped ``.npy`` file beside the database.

A case base of 10^6 cases x 200 features is 800 MB in float32. Loaded from SQL, every process
(each ``posecbr classify``, each worker of ``compare --jobs``) decodes and stacks its own
copy. Written once as an ``.npy`` file and opened with ``np.load(mmap_mode="r")``, the rows are
read from the page cache, shared by every process on the machine, and only the pages a search
touches are read at all; the similarity measures use such a matrix in place (the Euclidean
index keeps a read-only float32 matrix as it is, without a copy).

Files are keyed by what they hold, so a stale matrix is never read: ``<database>.matrices/
<case base>.<kind>.<version>.npy`` where ``version`` is the case base's version (anything that
changes whenever an active case's features change: ids, revision counter, content hash; see
:func:`content_version`). Written atomically (a temporary file beside it, renamed when
complete: a reader sees the whole matrix or none), in chunks, so writing a matrix larger than
memory needs no full copy either. Older versions of the same case base and kind are removed
when a new one is written (a process that still maps one keeps reading it: POSIX unlink).
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from features.errors import DataError
from features.fileio import atomic_path

_SAFE = re.compile(r"[^A-Za-z0-9_.=-]+")


def _slug(text: str) -> str:
    return _SAFE.sub("_", text).strip("._") or "_"


def content_version(ids: np.ndarray, *parts: str) -> str:
    """A version string from the case ids ``(n,)`` in row order and anything else that
    identifies the content (e.g. a revision counter or the latest update time)."""
    h = hashlib.sha256(np.ascontiguousarray(ids, dtype=np.int64).tobytes())
    for p in parts:
        h.update(b"\0" + p.encode("utf-8"))
    return h.hexdigest()[:20]


def matrix_path(database: str | Path, case_base: str, kind: str, version: str) -> Path:
    """Where the matrix of ``case_base``'s representation ``kind`` at ``version`` lives."""
    db = Path(database)
    folder = db.with_name(db.name + ".matrices")
    return folder / f"{_slug(case_base)}.{_slug(kind)}.{_slug(version)}.npy"


def write_case_matrix(
    path: str | Path,
    chunks: Iterable[np.ndarray],
    shape: tuple[int, ...],
    dtype: np.dtype | type = np.float32,
) -> Path:
    """Write the rows ``chunks`` yields (arrays ``(rows, *shape[1:])``, in order) as one
    ``.npy`` matrix of ``shape`` atomically; nothing larger than a chunk is held in memory.

    Raises DataError naming the file when the chunks do not add up to ``shape``, or contain
    NaN or infinity (a case base's features are finite; missing data never becomes a number).
    """
    dest = Path(path)
    with atomic_path(dest) as tmp:
        out = np.lib.format.open_memmap(tmp, mode="w+", dtype=np.dtype(dtype), shape=shape)
        at = 0
        for chunk in chunks:
            c = np.asarray(chunk)
            if c.shape[1:] != tuple(shape[1:]) or at + len(c) > shape[0]:
                raise DataError(
                    f"case matrix rows of shape {c.shape} do not fit a matrix of {shape} "
                    f"after {at} rows",
                    dest,
                )
            if not np.isfinite(c).all():
                raise DataError(f"case matrix rows {at}..{at + len(c) - 1} are not finite", dest)
            out[at : at + len(c)] = c
            at += len(c)
        if at != shape[0]:
            raise DataError(f"case matrix got {at} rows, expected {shape[0]}", dest)
        out.flush()
        del out
    return dest


def open_case_matrix(path: str | Path, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """The matrix at ``path`` memory-mapped read-only (no copy); ``shape``: the shape it must
    have. Raises DataError naming the file when it is missing, not an ``.npy`` matrix, or of
    another shape."""
    p = Path(path)
    try:
        m = np.load(p, mmap_mode="r", allow_pickle=False)
    except FileNotFoundError:
        raise DataError("no case matrix file", p) from None
    except (OSError, ValueError, EOFError) as exc:
        raise DataError(f"not a case matrix (.npy) file: {exc}", p) from None
    if not isinstance(m, np.ndarray) or m.ndim < 2:
        raise DataError("not a case matrix (.npy with one row per case)", p)
    if shape is not None and tuple(m.shape) != tuple(shape):
        raise DataError(f"case matrix has shape {m.shape}, expected {tuple(shape)}", p)
    return m


def cached_case_matrix(
    database: str | Path,
    case_base: str,
    kind: str,
    version: str,
    shape: tuple[int, ...],
    chunks: Callable[[], Iterable[np.ndarray]],
    dtype: np.dtype | type = np.float32,
) -> np.ndarray:
    """The memory-mapped matrix of ``case_base``'s ``kind`` at ``version``: opened when it is
    on disk, else written first from ``chunks()`` (then older versions are removed)."""
    path = matrix_path(database, case_base, kind, version)
    if not path.exists():
        write_case_matrix(path, chunks(), shape, dtype)
        prefix = f"{_slug(case_base)}.{_slug(kind)}."
        for old in path.parent.glob(prefix + "*.npy"):
            if old != path and old.name[len(prefix) : -4].count(".") == 0:
                old.unlink(missing_ok=True)
    return open_case_matrix(path, shape)
