"""Helpers shared by the readers: text reading and placing joints on the canonical skeleton."""

from __future__ import annotations

import gzip
import io
import zlib
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from features.errors import DataError
from features.fileio import GZIP_MAGIC, file_head, path_exists
from features.text import size_words

from ..poses import MAX_BYTES_ENV, read_limits
from ..skeleton import BLAZEPOSE_33, JOINT_INDEX


def _check_file(path: Path) -> None:
    """A DataError naming ``path`` unless it is a file to read: missing, a folder, or a pipe,
    socket or device (opened, a pipe waits for a writer that may never come)."""
    if not path_exists(path):
        raise DataError("no such file", path)
    if path.is_dir():
        raise DataError("is a folder, not a file", path)
    if not path.is_file():
        raise DataError("is a pipe, socket or device, not a file", path)


def gzipped(path: Path) -> bool:
    """Whether the file at ``path`` is gzip-compressed: named ``.gz``, or starting with gzip's
    magic bytes whatever its name (``gzip -c take.bvh > copy.bvh``, a download kept
    compressed), which was read as text and refused as "not a BVH file"."""
    return path.suffix == ".gz" or file_head(path, len(GZIP_MAGIC)) == GZIP_MAGIC


def read_text(path: Path) -> str:
    """The text of ``path`` (gzip when :func:`gzipped`), latin-1 tolerant, newlines unified,
    without a UTF-8 byte order mark; UTF-16 when it starts with a UTF-16 byte order mark.

    Raises DataError naming the file when it is missing, a folder, a pipe, socket or device
    (reading a pipe waits for a writer that may never come: an ASF skeleton given with
    ``--asf``, or the one beside an AMC file), unreadable, a truncated gzip, or larger
    (decompressed) than the reading limit of :func:`features.poses.read_limits`.
    """
    _check_file(path)
    _, limit = read_limits()
    too_big = DataError(
        f"holds more than {size_words(limit)} of text (raise the limit with {MAX_BYTES_ENV}=BYTES)",
        path,
    )
    try:
        if gzipped(path):
            # at most one byte past the limit is decompressed: a small gzip can expand to GBs
            with gzip.open(path, "rb") as fh:
                raw = fh.read(limit + 1)
        elif path.stat().st_size > limit:
            raise too_big
        else:
            raw = path.read_bytes()
    except (OSError, EOFError, zlib.error) as exc:
        raise DataError(f"cannot read ({type(exc).__name__}: {exc})", path) from None
    if len(raw) > limit:
        raise too_big
    # a byte order mark (Windows editors write one) is no part of the text: left in, it glued
    # itself to the first word ("HIERARCHY", an AMC header's "#") and the file was refused
    raw = raw.removeprefix(b"\xef\xbb\xbf")
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        # UTF-16 with its byte order mark, as Windows tools write text (PowerShell's ``>``,
        # Notepad's "Unicode"): read as latin-1 it was "not a BVH file", every other byte NUL
        try:
            text = raw.decode("utf-16")
        except UnicodeDecodeError:
            raise DataError("starts as UTF-16 text (byte order mark) but is not", path) from None
    else:
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            # Motion capture headers (HDM05 AMC) carry latin-1 bytes; latin-1 decodes anything.
            text = raw.decode("latin-1")
    return text.replace("\r\n", "\n").replace("\r", "\n")


def read_csv_matrix(path: Path, n_columns: int) -> np.ndarray:
    """A numeric comma-separated file as ``(rows, n_columns)`` float64; blank lines are no row.

    Raises DataError naming the file and line (the file's own line number, blank lines
    counted) for a row of the wrong width or a non-number, and line and column for the first
    number that is not finite (``nan``, ``inf``, or beyond float64's range).
    """
    lines = read_text(path).split("\n")
    numbers = [i + 1 for i, line in enumerate(lines) if line.strip()]
    rows = [lines[n - 1] for n in numbers]
    if not rows:
        raise DataError("file is empty", path)
    # Fast path: numpy's parser reads all rows at once; any shape or number problem falls
    # through to the row by row pass below, which names the offending line.
    try:
        fast = np.loadtxt(io.StringIO("\n".join(rows)), delimiter=",", ndmin=2)
    except ValueError:
        fast = None
    if fast is not None and fast.shape == (len(rows), n_columns):
        _check_finite(fast, rows, numbers, path)
        return fast
    out = np.empty((len(rows), n_columns))
    for i, (line_no, line) in enumerate(zip(numbers, rows, strict=True)):
        parts = line.split(",")
        if len(parts) != n_columns:
            raise DataError(
                f"line {line_no}: expected {n_columns} comma-separated numbers, got {len(parts)}"
                " (truncated or not this format?)",
                path,
            )
        try:
            out[i] = [float(p) for p in parts]
        except ValueError:
            raise DataError(f"line {line_no}: not a number in {line[:60]!r}", path) from None
    _check_finite(out, rows, numbers, path)
    return out


def _check_finite(values: np.ndarray, rows: list[str], numbers: list[int], path: Path) -> None:
    """Refuse ``values`` (one row per line of ``rows``, the file's lines ``numbers``) holding a
    number that is not finite, naming the first one's line, column and text."""
    bad = np.argwhere(~np.isfinite(values))
    if len(bad):
        row, col = (int(v) for v in bad[0])
        text = rows[row].split(",")[col].strip()
        where = f"line {numbers[row]}, column {col + 1}"
        raise DataError(f"contains non-finite numbers: the first, {text[:30]!r}, at {where}", path)


def to_canonical(
    points: np.ndarray, source_names: tuple[str, ...], joint_map: Mapping[str, str]
) -> np.ndarray:
    """Place source points on the 33 BlazePose joints.

    points: ``(frames, len(source_names), 3)``; joint_map: BlazePose name -> source name.
    Returns ``(frames, 33, 3)`` with NaN for every BlazePose joint the map does not name.
    """
    index = {n: i for i, n in enumerate(source_names)}
    out = np.full((points.shape[0], len(BLAZEPOSE_33), 3), np.nan)
    dst = [JOINT_INDEX[b] for b in joint_map]
    src = [index[s] for s in joint_map.values()]
    out[:, dst, :] = points[:, src, :]
    return out
