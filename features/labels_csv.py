"""A labels CSV (``path,label[,subject][,start,end]``, or a recording's ``label_file``) read into
checked rows, every problem one line naming the file and line."""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Collection
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import DataError
from features.fileio import path_exists
from features.text import spelt_among

from .label_tracks import LabelTrack, refuse_inner_bom, utf8_text

CSV_REQUIRED = ("path", "label")


_CSV_COLUMNS = ("path", "label", "subject", "start", "end")  # any other column is an extra


def check_rows_apart(
    csv_path: Path, labels: Collection[str] | None = None, twice: bool = False
) -> None:
    """Refuse the labels CSV ``csv_path`` when two of its rows give frames of one file
    different labels, as :func:`features.datasets.check_no_overlaps` says (``labels``,
    ``twice`` as there). DataError naming the CSV and both lines, read from the rows alone (no
    clip is read)."""
    by_file: dict[Path, list[dict[str, Any]]] = {}
    tracked: dict[Path, dict[str, Any]] = {}
    for rec in read_labels_csv(csv_path):
        key = rec["path"].resolve()
        if rec["track"] is None and labels is not None and not spelt_among(rec["label"], labels):
            continue
        if key in tracked or (rec["track"] is not None and key in by_file):
            first = tracked.get(key) or by_file[key][0]
            raise DataError(_tracked_twice(first, rec), csv_path)
        if rec["track"] is not None:
            tracked[key] = rec
        else:
            by_file.setdefault(key, []).append(rec)
    for rows in by_file.values():
        if twice:
            _check_listed_once(rows, csv_path)
        _check_one_label(rows, csv_path)


def _check_listed_once(rows: list[dict[str, Any]], csv_path: Path) -> None:
    """Refuse two of ``rows`` (of one file) of the same stretch and label."""
    listed: dict[tuple[float, float], dict[str, Any]] = {}
    for rec in rows:
        first = listed.setdefault(_span(rec), rec)
        if first is not rec and first["label"] == rec["label"]:
            raise DataError(_listed_twice(first, rec), csv_path)


def _check_one_label(rows: list[dict[str, Any]], csv_path: Path) -> None:
    """Refuse two of ``rows`` (of one file) that share frames and differ in label: a sweep
    in order of start, keeping each label's row that reaches farthest."""
    reach: dict[str, dict[str, Any]] = {}
    for rec in sorted(rows, key=lambda r: (_span(r)[0], r["line"])):
        start, end = _span(rec)
        other = max(
            (r for lab, r in reach.items() if lab != rec["label"] and _span(r)[1] > start),
            key=lambda r: _span(r)[1],
            default=None,
        )
        if other is not None:
            raise DataError(_overlap(other, rec), csv_path)
        if rec["label"] not in reach or _span(reach[rec["label"]])[1] < end:
            reach[rec["label"]] = rec


def _tracked_twice(a: dict[str, Any], b: dict[str, Any]) -> str:
    """Why a row naming a label file and a later row of the same file cannot both be."""
    track = a if a["track"] is not None else b

    def shown(rec: dict[str, Any]) -> str:
        if rec["track"] is not None:
            return f"label file {rec['track'].path.name}"
        frames = "whole" if rec["start"] is None else f"frames {rec['start']},{rec['end']}"
        return f"{frames} ({rec['label']!r})"

    return (
        f"lines {a['line']} and {b['line']} both give frames of {b['path'].name}"
        f" ({shown(a)}; {shown(b)}): line {track['line']} labels all of it over time, so they"
        " would be cases twice; list the recording once"
    )


def _listed_twice(a: dict[str, Any], b: dict[str, Any]) -> str:
    """Why two rows of the same stretch and label cannot both be."""
    frames = "whole" if a["start"] is None else f"frames {a['start']},{a['end']}"
    return (
        f"lines {a['line']} and {b['line']} both give {b['path'].name} {frames}"
        f" ({a['label']!r}): the one stretch would be written twice; list it once"
    )


def _span(rec: dict[str, Any]) -> tuple[float, float]:
    """A row's frames ``[start, end)``; a whole file's from 0 to infinity."""
    return (0, math.inf) if rec["start"] is None else (rec["start"], rec["end"])


def _overlap(a: dict[str, Any], b: dict[str, Any]) -> str:
    """Why rows ``a`` and ``b`` (``a`` starting first, or the whole file) cannot both be."""

    def shown(rec: dict[str, Any]) -> str:
        frames = "whole" if rec["start"] is None else f"frames {rec['start']},{rec['end']}"
        return f"{frames} ({rec['label']!r})"

    first, second = sorted((a, b), key=lambda r: r["line"])
    lo, hi = max(_span(a)[0], _span(b)[0]), min(_span(a)[1], _span(b)[1])
    shared = "its frames" if math.isinf(hi) else f"frames {int(lo)}-{int(hi) - 1}"
    ranged = a["start"] is not None and b["start"] is not None
    return (
        f"lines {first['line']} and {second['line']} give {b['path'].name} {shown(first)}"
        f" and {shown(second)}: {shared} would be cases of two activities"
        + (" (end is exclusive: rows 0,300 and 300,600 meet)" if ranged else "")
    )


def _parse_bool(value: str) -> Any:
    low = value.strip().lower()
    if low in ("true", "yes"):
        return True
    if low in ("false", "no"):
        return False
    return value


def read_labels_csv(csv_path: str | Path, unlabelled: bool = False) -> list[dict[str, Any]]:
    """Rows of a labels CSV as dicts: path (resolved), label, subject, start, end, extras.

    Header row required with at least ``path`` and ``label``. Raises DataError naming the
    file and line for a malformed row or a missing clip file, or for an empty label unless
    ``unlabelled`` (clips to classify, not to train on: pieces of a new recording).
    """
    csv_path = Path(csv_path)
    rows = _unnamed_columns_dropped(_csv_rows(csv_path), csv_path)
    header = _csv_header(rows[0], csv_path)
    records = (
        _csv_record(header, row, line_no, csv_path, unlabelled)
        for line_no, row in enumerate(rows[1:], start=2)
        if row and any(c.strip() for c in row)  # blank rows are skipped
    )
    return list(records)


def _csv_rows(csv_path: Path) -> list[list[str]]:
    """Every row of the CSV file (at least one); one clear error for a missing, non-UTF-8,
    malformed or empty file."""
    if not csv_path.is_file():
        raise DataError("no such file", csv_path)
    rows: list[list[str]] = []
    try:
        data = csv_path.read_bytes()
    except OSError as exc:
        raise DataError(f"cannot read the labels CSV ({exc.strerror or exc})", csv_path) from None
    text = utf8_text(data, "labels CSV", csv_path)
    # two labels CSVs joined (cat a.csv b.csv), the second saved with a byte order mark: it
    # would begin a path or label unseen ("no such file \ufeffrec2.npz")
    refuse_inner_bom(text, "labels CSV", csv_path, "a path or label")
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    try:
        rows.extend(reader)
    except csv.Error as exc:
        # an unclosed quote runs to the end of the file: name the row it opened on
        raise DataError(f"line {len(rows) + 1}: malformed CSV ({exc})", csv_path) from None
    if not rows:
        raise DataError(
            "empty CSV: a header row path,label[,subject][,start,end] is required", csv_path
        )
    return rows


def _unnamed_columns_dropped(rows: list[list[str]], csv_path: Path) -> list[list[str]]:
    """``rows`` without the columns the header leaves unnamed, which no row fills: the empty
    columns a spreadsheet saves after the last one used (``path,label,,`` and ``a.npz,squat,,``:
    Excel writes them once a cell out there has been touched), which were refused as
    "repeated column names", or kept as a column named "". A value in an unnamed column is
    refused naming its line and column: no name says what it is. An unnamed FIRST column is
    a row index, as pandas' ``to_csv()`` and R's ``write.csv`` save one (``,path,label`` and
    ``0,a.npz,squat``): dropped with its values, as before it was read as a column ""."""
    unnamed = [i for i, name in enumerate(rows[0]) if not name.strip()]
    if not unnamed or len(unnamed) == len(rows[0]):
        return rows  # no column named at all: the header's own error says so
    if unnamed[0] == 0:  # a row index
        rows = [row[1:] for row in rows]
        return _unnamed_columns_dropped(rows, csv_path) if len(unnamed) > 1 else rows
    for line_no, row in enumerate(rows[1:], start=2):
        filled = next((i for i in unnamed if i < len(row) and row[i].strip()), None)
        if filled is not None:
            raise DataError(
                f"line {line_no}: column {filled + 1} holds {row[filled].strip()[:40]!r}, and"
                " the header (line 1) gives that column no name",
                csv_path,
            )
    drop = set(unnamed)
    return [[c for i, c in enumerate(row) if i not in drop] for row in rows]


def _csv_header(row: list[str], csv_path: Path) -> list[str]:
    """The column names: those the reader knows (``path``, ``label``, ``subject``, ``start``,
    ``end`` and those of a recording labelled over time) in lower case, written in any case;
    every other column as the file spells it (spaces around it stripped). ``path`` and
    ``label`` (or ``label_file``) present, none repeated (in any case), ``start`` and ``end``
    both or neither."""
    known = (*_CSV_COLUMNS, *_TRACK_COLUMNS)
    header = [h.strip().lower() if h.strip().lower() in known else h.strip() for h in row]
    missing = [c for c in CSV_REQUIRED if c not in header]
    if missing == ["label"] and "label_file" in header:
        missing = []  # recordings labelled over time
    other = next((c for c in (";", "\t") if len(row) == 1 and c in row[0]), None)
    if missing and other is not None:  # Excel in many locales saves "CSV" with semicolons
        raise DataError(
            f"line 1: the columns are separated by {'tabs' if other == chr(9) else repr(other)},"
            " not commas (header path,label[,subject][,start,end])",
            csv_path,
        )
    if missing:
        raise DataError(
            f"line 1: header must name columns path,label[,subject][,start,end]; missing"
            f" {', '.join(missing)} (header row required)",
            csv_path,
        )
    if len({h.lower() for h in header}) != len(header):
        raise DataError("line 1: repeated column names in the header", csv_path)
    if ("start" in header) != ("end" in header):
        raise DataError("line 1: columns start and end go together", csv_path)
    return header


def _csv_record(
    header: list[str], row: list[str], line_no: int, csv_path: Path, unlabelled: bool = False
) -> dict[str, Any]:
    """One data row as the record :func:`read_labels_csv` returns (an empty label refused
    unless ``unlabelled``)."""
    if len(row) != len(header):
        raise DataError(
            f"line {line_no}: {len(row)} fields, the header has {len(header)}", csv_path
        )
    rec = dict(zip(header, (c.strip() for c in row), strict=True))
    for column in ("label", "subject"):  # stored with each case: no store holds a NUL
        if "\x00" in rec.get(column, ""):
            raise DataError(
                f"line {line_no}: column {column}: {rec[column]!r} contains a NUL character "
                "(a case base cannot store it)",
                csv_path,
            )
    if not rec["path"]:
        raise DataError(f"line {line_no}: empty path", csv_path)
    track = _track_columns(rec, csv_path, line_no)
    if not rec.get("label") and track is None and not unlabelled:
        raise DataError(f"line {line_no}: empty label", csv_path)
    clip = _clip_path(rec["path"], line_no, csv_path)
    start, end = _frame_range(rec, line_no, csv_path)
    if track is not None and start is not None:
        raise DataError(
            f"line {line_no}: start and end do not go with a label_file (it labels the whole"
            " recording, frame by frame or block by block)",
            csv_path,
        )
    extras = {
        k: _parse_bool(v) for k, v in rec.items() if k not in (*_CSV_COLUMNS, *_TRACK_COLUMNS)
    }
    return {
        "path": clip,
        "label": rec.get("label", ""),
        "subject": rec.get("subject") or None,
        "start": start,
        "end": end,
        "extras": extras,
        "line": line_no,
        "track": track,
    }


def _clip_path(path: str, line_no: int, csv_path: Path) -> Path:
    """The clip a row names (relative to the CSV's folder), which must exist."""
    clip = Path(path)
    if not clip.is_absolute():
        clip = csv_path.parent / clip
    if not path_exists(clip, f"line {line_no}: ", csv_path):
        raise DataError(f"line {line_no}: {_no_such_file(path, clip, csv_path)}", csv_path)
    return clip


def _no_such_file(value: str, looked_for: Path, csv_path: Path) -> str:
    """What a labels CSV's missing file is, in words; a relative path says where it was
    looked for (from the CSV's folder, not the working folder), and a path written with
    Windows' backslashes between folders says so when the file is there with slashes. A URL
    is said to be one: the path looked for (``http:/me:secret@host/x.mp4``) would show its
    password, which messages hide only in a URL."""
    if re.match(r"[A-Za-z][A-Za-z0-9+.-]+://", value):
        return (
            f"{value[:200]} is a URL, not a file (a labels CSV names files on this machine;"
            " posecbr watch plays a stream)"
        )
    if "\\" in value:
        slashed = value.replace("\\", "/")
        there = Path(slashed) if Path(slashed).is_absolute() else csv_path.parent / slashed
        try:
            found = path_exists(there)
        except DataError:  # not a path the system can look up either
            found = False
        if found:
            return (
                f"no such file {value[:200]} ({slashed[:200]} is there: a path takes / between"
                " folders, not \\)"
            )
    if Path(value).is_absolute():
        return f"no such file {value[:200]}"
    where = str(looked_for)[:200]
    return f"no such file {value[:200]} (looked for {where}: paths are from the CSV's folder)"


def _frame_range(
    rec: dict[str, str], line_no: int, csv_path: Path
) -> tuple[int | None, int | None]:
    """A row's ``start`` and ``end`` frames (end exclusive); (None, None) without them."""
    if "start" not in rec or not (rec["start"] or rec["end"]):
        return None, None
    try:
        start, end = int(rec["start"]), int(rec["end"])
    except ValueError:
        raise DataError(
            f"line {line_no}: start and end must be whole frame numbers,"
            f" got {rec['start']!r}, {rec['end']!r}",
            csv_path,
        ) from None
    if start < 0 or end <= start:
        raise DataError(
            f"line {line_no}: need 0 <= start < end (end exclusive), got {start}, {end}",
            csv_path,
        )
    return start, end


_TRACK_COLUMNS = ("label_file", "label_block_s", "label_names")


def _track_columns(rec: dict[str, str], csv_path: Path, line_no: int) -> LabelTrack | None:
    """The label track a labels CSV row names (``label_file``, ``label_block_s``,
    ``label_names``), or None."""
    if not rec.get("label_file"):
        stray = [c for c in ("label_block_s", "label_names") if rec.get(c)]
        if stray:
            raise DataError(
                f"line {line_no}: {' and '.join(stray)} go{'es' if len(stray) == 1 else ''}"
                " with a label_file, and the row has none",
                csv_path,
            )
        return None
    if rec.get("label"):
        raise DataError(f"line {line_no}: give a label or a label_file, not both", csv_path)

    def resolve(column: str) -> Path:
        value = rec[column]
        f = Path(value)
        f = f if f.is_absolute() else csv_path.parent / f
        # a path the system cannot look up (a name too long): one line, not a traceback
        if not path_exists(f, f"line {line_no}: column {column}: ", csv_path):
            raise DataError(f"line {line_no}: {_no_such_file(value, f, csv_path)}", csv_path)
        if not f.is_file():  # a pipe would wait for a writer
            raise DataError(
                f"line {line_no}: column {column}: {value[:200]} is a folder, pipe, socket or"
                " device, not a file",
                csv_path,
            )
        return f

    block: float | None = None
    if rec.get("label_block_s"):
        try:
            block = float(rec["label_block_s"])
        except ValueError:
            block = float("nan")
        if not (np.isfinite(block) and block > 0):
            raise DataError(
                f"line {line_no}: label_block_s must be a finite number of seconds > 0, got"
                f" {rec['label_block_s']!r}",
                csv_path,
            )
    names = resolve("label_names") if rec.get("label_names") else None
    return LabelTrack(resolve("label_file"), block, names)
