"""The case matrix of a large case base as a memory-mapped ``.npy`` file beside the database.

A case base of 10^6 cases x 200 features is 800 MB in float32. Loaded from SQL, every process
(each ``posecbr classify``, each worker of ``compare --jobs``) decodes and stacks its own
copy. Written once as an ``.npy`` file and opened with ``np.load(mmap_mode="r")``, the rows are
read from the page cache, shared by every process on the machine, and only the pages a search
touches are read at all; the similarity measures use such a matrix in place (the Euclidean
index keeps a read-only float32 matrix as it is, without a copy).

Files are keyed by what they hold, so a stale matrix is never read: ``<database>.matrices/
<case base>~<hash>.<kind>.<version>.npy`` where ``<case base>`` is the name with the
characters a file name cannot safely hold replaced by ``_``, ``<hash>`` a short hash of the
exact name (so "a b" and "a_b", or "A" and "a" on a file system blind to case, do not share
files: each removed the other's as stale), and ``version`` the case base's version (anything
that changes whenever an active case's features change: ids, revision counter, content hash;
see :func:`content_version`). Files posecbr 0.2 named without the hash are still read when
of the very case base and version asked for. Written atomically (a temporary file beside it,
renamed when complete: a reader sees the whole matrix or none), in chunks, so writing a
matrix larger than memory needs no full copy either. Older versions of the same case base
and kind are removed when a new one is written (a process that still maps one keeps reading
it: POSIX unlink); :func:`case_matrix_files` lists them all for a sweep of those of case
bases gone or too small to be mapped any more (``cbr.stored.remove_stale_matrices``).
"""

from __future__ import annotations

import glob
import hashlib
import re
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from features.errors import DataError
from features.fileio import atomic_path

#: a case base at least this large (in cases) stored in a SQLite file keeps its problems and
#: representations as memory-mapped matrices beside the file: every process maps one copy
#: (the page cache's) instead of decoding and stacking its own from SQL (``cbr.stored``
#: writes them; here, so that a command can tell a case base needs none without loading it)
MAPPED_MIN_CASES = 20_000

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


def _prefix(case_base: str, kind: str) -> str:
    """The start of the file names of ``case_base``'s matrices of ``kind`` (every version):
    its name made safe, then a hash of the exact name (``~`` never comes out of the slug, so
    no name's files start like another's)."""
    h = hashlib.sha256(case_base.encode("utf-8", "surrogatepass")).hexdigest()[:12]
    return f"{_slug(case_base)}~{h}.{_slug(kind)}."


def _legacy_prefix(case_base: str, kind: str) -> str:
    """The start of the file names older posecbr gave them: without the hash, so two names
    with the same slug ("a b", "a_b") shared them."""
    return f"{_slug(case_base)}.{_slug(kind)}."


def matrix_path(database: str | Path, case_base: str, kind: str, version: str) -> Path:
    """Where the matrix of ``case_base``'s representation ``kind`` at ``version`` lives."""
    db = Path(database)
    folder = db.with_name(db.name + ".matrices")
    return folder / f"{_prefix(case_base, kind)}{_slug(version)}.npy"


def find_case_matrix(
    database: str | Path, case_base: str, kind: str, version: str, identity: str = ""
) -> Path:
    """The file holding ``case_base``'s ``kind`` at ``version``: :func:`matrix_path`, or the
    name an older posecbr gave it when only that is there and ``version`` begins with the
    case base's ``identity`` (then the file is its own, though another case base whose name
    has the same slug shared the name; without an identity it is never read)."""
    path = matrix_path(database, case_base, kind, version)
    if path.exists() or not identity or not version.startswith(identity):
        return path
    legacy = path.with_name(f"{_legacy_prefix(case_base, kind)}{_slug(version)}.npy")
    return legacy if legacy.exists() else path


#: a matrix file's name in either naming, ``<name>[~<hash>].<kind>.<version>.npy`` (neither
#: kind nor version holds a dot; the name may)
_MATRIX_FILE = re.compile(r"(?s).+\.[A-Za-z0-9_=-]+\.(?P<version>[A-Za-z0-9_=-]+)\.npy")


def case_matrix_files(database: str | Path) -> list[tuple[Path, str]]:
    """Every file beside ``database`` named as a case matrix (either naming), with its
    version (as :func:`matrix_path` wrote it); nothing else (temporaries, other files)."""
    db = Path(database)
    folder = db.with_name(db.name + ".matrices")
    try:
        names = sorted(p.name for p in folder.iterdir())
    except OSError:  # none written yet, or a folder that cannot be listed
        return []
    found = ((n, _MATRIX_FILE.fullmatch(n)) for n in names)
    return [(folder / n, m["version"]) for n, m in found if m is not None]


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
    kind = np.dtype(dtype)
    header = {
        "descr": np.lib.format.dtype_to_descr(kind),
        "fortran_order": False,
        "shape": tuple(int(n) for n in shape),
    }
    with atomic_path(dest) as tmp, open(tmp, "wb") as out:
        # written, not through a memory map: a full disk is then an error of write() ("No
        # space left on device", a DataError naming the file), where a memory-mapped page
        # that finds no room killed the process with SIGBUS ("Bus error"), after the change
        # whose copy this is had committed, its temporary file left behind
        np.lib.format.write_array_header_1_0(out, header)
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
            out.write(np.ascontiguousarray(c, dtype=kind).tobytes())
            at += len(c)
        if at != shape[0]:
            raise DataError(f"case matrix got {at} rows, expected {shape[0]}", dest)
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
    identity: str = "",
) -> np.ndarray:
    """The memory-mapped matrix of ``case_base``'s ``kind`` at ``version``: opened when it is
    on disk, else written first from ``chunks()``; then its older versions are removed.
    ``identity``: how every version of this case base (and no other's) begins; with it, a
    file an older posecbr named without the hash is read when of this version, and removed
    when of an older one (one of another identity may be another case base's whose name has
    the same slug, and is kept); without it such files are never read, and all removed."""
    path = find_case_matrix(database, case_base, kind, version, identity)
    if not path.exists():
        write_case_matrix(path, chunks(), shape, dtype)
        for prefix, own in (
            (_prefix(case_base, kind), ""),
            (_legacy_prefix(case_base, kind), _slug(identity) if identity else ""),
        ):
            for old in path.parent.glob(glob.escape(prefix) + "*.npy"):
                stale = old.name[len(prefix) : -4]
                if old != path and stale.count(".") == 0 and stale.startswith(own):
                    old.unlink(missing_ok=True)
    return open_case_matrix(path, shape)
