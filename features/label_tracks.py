"""Recordings labelled over time: label files (one label per frame, or per block of seconds,
as Fox et al.'s labels of CMU recordings), the files naming their codes, and the label of
every frame.

- :class:`LabelTrack`: how a recording is labelled (label file, block length, names file);
- :func:`read_label_track`, :func:`read_label_names`: the files read, refusing what would put
  labels on the wrong frames (a table of times, a header line, NUL characters, another
  encoding) with one line naming the file;
- :func:`frame_labels`: the label of every frame, the count fitted to the recording;
- :func:`labelled_stretches`: runs of one label.

How a labels CSV names a track and cuts a recording by it is :mod:`features.datasets`'.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import DataError
from features.fileio import not_utf8, path_exists
from features.text import counted


@dataclass(frozen=True)
class LabelTrack:
    """How a recording is labelled over time: the label file, the seconds each label covers
    (None: one label per frame) and an optional file naming the codes."""

    path: Path
    block_s: float | None = None
    names: Path | None = None

    def __post_init__(self) -> None:
        if self.block_s is not None and not (np.isfinite(self.block_s) and self.block_s > 0):
            raise DataError(
                f"the label block must be a finite number of seconds > 0, got {self.block_s!r}",
                self.path,
            )


def _read_label_text(path: Path, what: str) -> str:
    """The text of a label or label names file (a BOM dropped); one DataError naming the file
    otherwise, as every other input says it: a folder, a missing file, a pipe ("the label file
    is a folder, not a file", not Python's "[Errno 21] Is a directory"), or a file in another
    encoding (a Windows code page) by the line and byte of its first character that is not
    UTF-8, as a labels CSV's is."""
    if not path_exists(path):
        raise DataError(f"no such {what}", path)
    if path.is_dir():
        raise DataError(f"the {what} is a folder, not a file", path)
    _refuse_a_pipe(path, f"a {what}")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise DataError(f"cannot read the {what} ({exc.strerror or exc})", path) from None
    text = utf8_text(data, what, path)
    refuse_inner_bom(text, what, path)
    return text


def utf8_text(data: bytes, what: str, path: Path) -> str:
    """``data``, the bytes of the ``what`` file at ``path`` (a label file, a labels CSV), as
    text, a UTF-8 byte order mark dropped; else one DataError naming the file and what it is:
    a binary file a user could give in its place (a case base, a pose file, a gzip-compressed
    copy), UTF-16 text (Excel's "Unicode Text", PowerShell's ``>``), or text in another
    encoding (a Windows code page) by the line and byte of its first character that is not
    UTF-8."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        why = not_utf8(data, exc)
        if why.binary is not None:  # a case base given as --truth
            raise DataError(f"is {why.binary}, not a {what}", path) from None
        if why.utf16:
            raise DataError("UTF-16 text (its byte order mark): save it as UTF-8", path) from None
        raise DataError(f"not UTF-8 text ({why.where}): save it as UTF-8", path) from None


def refuse_inner_bom(text: str, what: str, path: Path, part: str = "a label") -> None:
    """Refuse a byte order mark inside ``text`` (one at its start already dropped), by the
    line it stands on: files each saved with one and joined together (``cat a.txt b.txt``),
    where it would be read, unseen, as part of ``part``."""
    at = text.find("\ufeff")
    if at >= 0:
        raise DataError(
            f"line {text.count(chr(10), 0, at) + 1}: a byte order mark (U+FEFF, unseen) inside"
            f" the {what}, where a file saved with one begins: files joined together? It would"
            f" be read as part of {part}; remove it",
            path,
        )


def _refuse_a_pipe(path: Path, what: str) -> None:
    """Refuse a pipe, socket or device (reading a pipe waits for a writer that may never
    come); a folder or a missing file is refused by the read, naming the reason."""
    if path_exists(path) and not path.is_file() and not path.is_dir():
        raise DataError(f"is a pipe, socket or device, not {what}", path)


_COMMENT = re.compile(r"(?:^|(?<=[\s,]))#.*")


def _uncommented(line: str) -> str:
    """``line`` without its comment: from a ``#`` that begins a word (at the line's start,
    or after a space, tab or comma) to the end; a ``#`` inside a label (``take#2``) is part
    of it."""
    return _COMMENT.sub("", line)


def read_label_names(path: str | Path) -> dict[str, str]:
    """Names of label codes: one ``code name`` pair per line (space, tab or comma between;
    ``#`` starts a comment). Raises DataError naming the file and line."""
    path = Path(path)
    text = _read_label_text(path, "label names file")
    _refuse_nul(text, path)
    names: dict[str, str] = {}
    for line_no, raw in enumerate(text.splitlines(), start=1):
        line = _uncommented(raw).strip()
        if not line:
            continue
        parts = re.split(r"[\s,]+", line, maxsplit=1)
        if len(parts) != 2 or not parts[1].strip():
            raise DataError(f"line {line_no}: expected 'code name', got {raw.strip()!r}", path)
        if parts[0] in names:
            raise DataError(f"line {line_no}: code {parts[0]!r} named twice", path)
        names[parts[0]] = parts[1].strip()
    if not names:
        raise DataError("no label names in it", path)
    return names


def code_order(code: str) -> tuple[int, int, str]:
    """How label codes are listed: whole numbers by value (2 before 10), then the rest as
    text."""
    number = code.isascii() and code.isdigit()
    return (0, int(code), code) if number else (1, 0, code)


def read_label_track(path: str | Path, names: dict[str, str] | None = None) -> list[str]:
    """The labels of a label file in order: tokens separated by spaces, tabs, commas or line
    ends (as in Fox et al.'s labels of CMU recordings; ``#`` starts a comment, as in a label
    names file),
    each mapped through ``names`` when given. Raises DataError for an empty or unreadable
    file or a code ``names`` does not name."""
    path = Path(path)
    raw = _read_label_text(path, "label file")
    _refuse_nul(raw, path)
    text = "\n".join(_uncommented(line) for line in raw.splitlines())
    tokens = [t for t in re.split(r"[\s,]+", text) if t]
    if not tokens:
        raise DataError("the label file holds no labels", path)
    _refuse_semicolons(text, path)
    _refuse_a_labels_csv(text, path)
    _refuse_a_table(text, path)
    _refuse_a_header(text, tokens, path)
    _refuse_empty_labels(text, path)
    if names is None:
        return tokens
    unknown = sorted({t for t in tokens if t not in names}, key=code_order)
    if unknown:
        held = ", ".join(_short(c) for c in list(names)[:5]) + (", ..." if len(names) > 5 else "")
        listed = ", ".join(_short(c) for c in unknown[:5]) + (", ..." if len(unknown) > 5 else "")
        raise DataError(
            f"line {_first_line(text, set(unknown))}: label code(s) {listed} not in the label"
            f" names (which name {held}){_written_otherwise(unknown, names)}",
            path,
        )
    return [names[t] for t in tokens]


def _first_line(text: str, codes: set[str]) -> int:
    """The line of ``text`` (comments gone) where one of ``codes`` first stands."""
    return next(
        n
        for n, line in enumerate(text.splitlines(), start=1)
        if codes.intersection(re.split(r"[\s,]+", line))
    )


def _written_otherwise(unknown: list[str], names: dict[str, str]) -> str:
    """When the codes not named are numbers the names file names written otherwise (``1.0``
    or ``01`` for ``1``, as a spreadsheet or pandas writes whole numbers), which: the codes
    are matched as written."""
    named = {value: code for code in names if (value := _number(code)) is not None}
    same = [(u, named[v]) for u in unknown if (v := _number(u)) is not None and v in named]
    if not same:
        return ""
    shown = ", ".join(f"{_short(u)} for {_short(c)}" for u, c in same[:3])
    return f": the same numbers written otherwise ({shown}); write them as the names file does"


def _number(code: str) -> float | None:
    """``code`` as a finite number, or None."""
    try:
        value = float(code)
    except ValueError:
        return None
    return value if np.isfinite(value) else None


def _short(code: str) -> str:
    """A label code as an error line shows it: its first 40 characters."""
    return code if len(code) <= 40 else code[:40] + "..."


def _refuse_semicolons(text: str, path: Path) -> None:
    """Refuse a label file whose labels are separated by semicolons (``1;1;6;6``, as a
    spreadsheet saves a row in many locales), naming its first line holding one: read as
    one label per line, its count would not fit the recording for a reason the file does
    not show, or its codes would be no code of the names file (the whole line named as one
    code). A label file separates its labels by spaces, tabs, commas or line ends."""
    for line_no, line in enumerate(text.splitlines(), start=1):
        if ";" in line:
            raise DataError(
                f"line {line_no}: labels separated by ';' ({line.strip()[:40]!r}); a label"
                " file separates its labels by spaces, tabs, commas or line ends",
                path,
            )


# two commas or two tabs with nothing but spaces (or other whitespace) between
_EMPTY_CELL = re.compile(r"([,\t])[^\S\n]*\1")


def _refuse_empty_labels(text: str, path: Path) -> None:
    """Refuse a label file with an empty label between two commas or two tabs (``1,1,,2``,
    ``1<tab>1<tab><tab>2``: a spreadsheet row with a cell left empty, saved as CSV or as
    "Tab delimited" text, a frame or block nobody labelled), naming its first line holding
    one: the separators run together, so every label after it was read one frame or block
    early, and when the count still fitted (one label more than the frames need is taken)
    nothing said so. A tab separates cells as a comma does (labels lined up are lined up
    with spaces, which may run). Empty cells that end a line (a spreadsheet's shorter last
    row, ``2,2,,``) are no label's place and are let be, and so are the spaces and tabs that
    begin one (a line indented)."""
    lines = text.splitlines()
    for line_no, line in enumerate(lines, start=1):
        cells = line.rstrip(", \t")
        indent = len(cells) - len(cells.lstrip(" \t"))
        if (empty := _EMPTY_CELL.search(cells, indent)) is not None:
            before = "\n".join([*lines[: line_no - 1], line[: empty.start()]])
            labels = [t for t in re.split(r"[\s,]+", before) if t]
            after = f" after label {len(labels)} ({_short(labels[-1])!r})" if labels else ""
            between = "commas" if empty.group(1) == "," else "tabs"
            aligned = "" if between == "commas" else " (to line labels up, use spaces)"
            raise DataError(
                f"line {line_no}: an empty label between {between}{after}; a label file gives"
                " every frame or block a label (read without one, the labels after it would"
                f" fall a frame or block early): write one there{aligned}",
                path,
            )


def _refuse_nul(text: str, path: Path) -> None:
    """Refuse a label file or label names file holding a NUL character (stored with each
    case, and no store holds one, as in a labels CSV), naming its line and the word of the
    line it is in. Text of NULs every other character is UTF-16 read as UTF-8: said so."""
    at = text.find("\x00")
    if at < 0:
        return
    line_start = text.rfind("\n", 0, at) + 1
    line_no = text.count("\n", 0, at) + 1
    line = text[line_start:].split("\n", 1)[0]
    words = list(re.finditer(r"[^\s,]+", line))  # a NUL is neither space nor comma
    word_no, word = next(
        (i, m.group()) for i, m in enumerate(words, 1) if m.end() > at - line_start
    )
    utf16 = text.count("\x00") * 3 >= len(text)
    raise DataError(
        f"line {line_no}, word {word_no}: {word[:80]!r} contains a NUL character"
        + (" (UTF-16 text? save the file as UTF-8)" if utf16 else " (a case base cannot store it)"),
        path,
    )


def _refuse_a_labels_csv(text: str, path: Path) -> None:
    """Refuse a labels CSV given for a label file (its header ``path,label`` or
    ``path,label_file`` on the first line): read as labels, its paths and labels were one
    label each, refused as a count that does not fit "(another frame rate or label
    block?)", or, fitting by chance, trained as activities named after its paths."""
    first = next((ln.strip() for ln in text.splitlines() if ln.strip()), "")
    words = {w.casefold() for w in re.split(r"[\s,]+", first)}
    if "path" in words and words & {"label", "label_file"}:
        raise DataError(
            f"line 1: {first[:40]!r} is a labels CSV's header, and this a labels CSV, not a"
            " label file: a label file takes the labels alone, one per frame or block",
            path,
        )


def _refuse_a_table(text: str, path: Path) -> None:
    """Refuse a label file that is a table whose first column counts up (``time,label`` or
    ``frame label`` per line, a header line allowed): read as labels, its times would be
    labels too, and the count would not fit the recording for a reason the file does not
    show. A label file holds the labels alone, one per frame or block."""
    rows = [re.split(r"[\s,]+", line.strip()) for line in text.splitlines() if line.strip()]
    body = rows[1:] if rows and not _numbers(rows[0][:1]) else rows
    widths = {len(r) for r in body}
    if len(body) < 2 or len(widths) != 1 or widths == {1}:
        return
    first = _numbers([r[0] for r in body])
    labels = {t for r in body for t in r[1:]}
    # a column of times takes a new value on every line; labels repeat (a label file wrapped
    # one activity per line, "1 1 1 / 2 2 2 / 3 3 3", has as many lines as labels)
    if first is not None and bool(np.all(np.diff(first) > 0)) and len(body) > 2 * len(labels):
        raise DataError(
            f"the label file is a table of {widths.pop()} columns whose first counts up (times"
            " or frames?); it takes the labels alone, one per frame or per block"
            " (--label-block), separated by spaces, commas or line ends",
            path,
        )
    _refuse_intervals(rows, path)


def _refuse_intervals(rows: list[list[str]], path: Path) -> None:
    """Refuse a label file that is a table of labelled stretches (``label,start_s,end_s`` per
    line, as ``tools/make_workout.py`` writes its truth, a header allowed): a column of words
    beside a column of numbers that counts up (times or frames). Read as labels, its words
    and times were labels alike, and the count was refused as another frame rate or block.
    Labels alone, however wrapped, have no column of words beside one of numbers."""
    body = rows[1:] if rows and not _any_number(rows[0]) else rows
    widths = {len(r) for r in body}
    if len(body) < 2 or len(widths) != 1 or widths == {1}:
        return
    columns = [list(c) for c in zip(*body, strict=True)]
    words = [c for c in columns if not _any_number(c)]
    times = [v for c in columns if (v := _numbers(c)) is not None and np.all(np.diff(v) > 0)]
    if words and times:
        raise DataError(
            f"the label file is a table of {widths.pop()} columns, labels beside numbers that"
            " count up (stretches: label, start, end?); it takes the labels alone, one per"
            " frame or per block (--label-block), separated by spaces, commas or line ends",
            path,
        )


def _any_number(tokens: list[str]) -> bool:
    """Whether one of ``tokens`` is a number."""
    return any(_numbers([t]) is not None for t in tokens)


#: the names a column of labels is given (``pandas.Series.to_csv`` writes one on top)
_HEADER_WORDS = frozenset(
    "label labels activity activities action actions class classes code codes target y"
    " annotation annotations gesture gestures category".split()
)


def _refuse_a_header(text: str, tokens: list[str], path: Path) -> None:
    """Refuse a label file whose first line is a column's name alone (``label``, as pandas
    writes a column out, over numeric codes or a label each line): read as the first label,
    it would shift every label one frame or block later, and pass when the frames fill the
    last block exactly. A word alone on the first line, nowhere else in the file, that is a
    column's usual name or the only word among numbers."""
    first = next((ln.strip() for ln in text.splitlines() if ln.strip()), "")
    head = tokens[0]
    if first != head or len(tokens) < 3 or head in tokens[1:]:
        return
    numbers = _numbers(tokens[1:]) is not None and _numbers([head]) is None
    if not numbers and head.casefold() not in _HEADER_WORDS:
        return
    raise DataError(
        f"line 1: {head[:40]!r} looks like a column's name, not a label"
        f" ({'the others are numbers' if numbers else 'it is nowhere else in the file'}); a"
        " label file takes the labels alone, one per frame or block: remove that line",
        path,
    )


def _numbers(tokens: list[str]) -> np.ndarray | None:
    """``tokens`` as numbers, or None when one is not a number."""
    try:
        return np.array([float(t) for t in tokens])
    except ValueError:
        return None


def track_labels(track: LabelTrack) -> list[str]:
    """The labels a recording's label file holds (through its names file, if any), each
    once, codes in :func:`code_order`: what its labelled stretches can be
    labelled. DataError as :func:`read_label_track`."""
    names = read_label_names(track.names) if track.names is not None else None
    return sorted(set(read_label_track(track.path, names)), key=code_order)


def frame_labels(
    labels: list[str],
    n_frames: int,
    fps: float,
    block_s: float | None,
    where: str | Path,
    recording: str = "",
    rate: str = "",
) -> np.ndarray:
    """The label of every frame, ``(n_frames,)`` objects, from one label per frame
    (``block_s`` None) or one per ``block_s`` seconds (label t covers [t, t+1) x block_s).

    The count must fit the recording: one label per block, the last block possibly partial;
    one more label is accepted when the frames fill the last block exactly (a label for the
    recording's end time as well as its start: some label files are made
    that way), so a file of one label per frame may hold one more than there are frames, and no
    more. Labels are per time: they must reach the last frame's time, not the end of its
    frame, so a recording thinned below one frame per block (CMU at 2 fps, 0.1-s labels made
    at 120 fps) takes the labels of its whole length, whose end lies within its last frame's
    time. Otherwise DataError naming the file (and ``recording``, the name of the recording
    it was given for, when known: one label file may be named for several): a different
    count means another frame rate or block length, and labels would land on the wrong
    frames. ``rate``: where ``fps`` came from when it was assumed (:func:`assumed_rate`),
    said beside it, as the likely reason."""
    low, high = _fitting(n_frames, fps, block_s, where)
    if not low <= len(labels) <= high:
        raise _not_fitting(len(labels), n_frames, fps, block_s, where, recording, rate)
    per_block = 1.0 if block_s is None else block_s * fps
    block = np.floor(np.arange(n_frames) / per_block + 1e-9).astype(np.int64)
    return np.asarray(labels, dtype=object)[np.minimum(block, len(labels) - 1)]


def assumed_rate(metadata: Mapping[str, Any]) -> str:
    """Where a recording's frame rate came from when it was assumed, not read or given
    (``fps_source`` of its metadata: an AMC file, which carries no rate, is read at the CMU
    and HDM05 rate), else "": a label file that does not fit such a recording was most
    likely made at its true rate."""
    source = str(metadata.get("fps_source", ""))
    return source if source.startswith("assumed") else ""


def check_count(
    n_labels: int,
    frames: tuple[int, int],
    fps: float,
    block_s: float | None,
    where: str | Path,
    recording: str = "",
    rate: str = "",
) -> None:
    """Refuse, before a recording is read, ``n_labels`` labels that fit none of the frame
    counts ``frames`` (fewest, most) it can be read with at ``fps``, as :func:`frame_labels`
    refuses them for the most (the count its file states); a count that fits one of them
    is left for :func:`frame_labels` to judge once it is read. ``rate``: as there."""
    fewest, most = frames
    for n_frames in range(most, fewest - 1, -1):
        low, high = _fitting(n_frames, fps, block_s, where)
        if low <= n_labels <= high:
            return
    raise _not_fitting(n_labels, most, fps, block_s, where, recording, rate)


def _fitting(
    n_frames: int, fps: float, block_s: float | None, where: str | Path
) -> tuple[int, int]:
    """The fewest and most labels that fit ``n_frames`` frames at ``fps`` (see
    :func:`frame_labels`); DataError naming ``where`` for a block too short to count."""
    per_block = 1.0 if block_s is None else block_s * fps
    blocks = n_frames / per_block if per_block > 0 else float("inf")
    if not np.isfinite(blocks):  # a block of 1e-320 s: more blocks than a number holds
        raise DataError(
            f"a label block of {block_s:g} s is too short for {counted(n_frames, 'frame')} at"
            f" {fps:g} fps (more blocks than can be counted)",
            where,
        )
    # labels are per time: they must reach the last frame's time ((n - 1) / fps), which at a
    # rate below one frame per block (a recording thinned to 2 fps, 0.1-s labels) lies up to
    # a frame's time before the frames' end (n / fps): a label file made at the full rate
    # ends between the two. With a whole number of frames a block (one label per frame,
    # 0.1 s at 30 or 120 fps) this is ceil(n / per_block), as before; with 2.5 (25 fps) it
    # may be one fewer. A recording of any frames needs a label, however long the block.
    last = (n_frames - 1) / per_block
    low = max(int(np.floor(last + 1e-9)) + 1, min(n_frames, 1)) if n_frames else 0
    high = int(np.floor(blocks + 1e-9)) + 1
    return low, high


def _not_fitting(
    n_labels: int,
    n_frames: int,
    fps: float,
    block_s: float | None,
    where: str | Path,
    recording: str,
    rate: str = "",
) -> DataError:
    """Why ``n_labels`` labels do not fit ``n_frames`` frames at ``fps`` (``rate``: where an
    assumed ``fps`` came from), naming ``where``."""
    low, high = _fitting(n_frames, fps, block_s, where)
    unit = "frame" if block_s is None else f"{block_s:g} s"
    need = (
        str(low) if low == high else f"{low} or {high}" if high == low + 1 else f"{low} to {high}"
    )
    return DataError(
        f"{counted(n_labels, 'label')} (one per {unit})"
        f" {'does' if n_labels == 1 else 'do'} not fit the recording"
        f"{' ' + recording if recording else ''}: {counted(n_frames, 'frame')} at {fps:g}"
        f" fps{f' ({rate})' if rate else ''} need {need}{_why_not_fit(where, low, high, n_labels)}",
        where,
    )


def _why_not_fit(where: str | Path, low: int, high: int, n_labels: int) -> str:
    """What likely made a label file's count not fit: labels written one per line with
    spaces in them ("sit down", read as two labels) when its lines would fit, else another
    frame rate or block length. Labels given in memory (``where`` text, not a path) have no
    lines to read."""
    if not isinstance(where, Path):
        return " (another frame rate or label block?)"
    try:
        text = where.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError, ValueError):
        text = ""
    lines = [_uncommented(ln).strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln]
    spaced = next((ln for ln in lines if len(re.split(r"[\s,]+", ln)) > 1), None)
    if spaced is None or len(lines) < 2 or not low <= len(lines) <= high or len(lines) >= n_labels:
        return " (another frame rate or label block?)"
    parts = re.split(r"[\s,]+", spaced)
    return (
        f": its {len(lines)} lines would, and a line such as {spaced[:40]!r} is"
        f" {len(parts)} labels (labels are separated by spaces, tabs and commas: write"
        f" {'_'.join(parts)[:40]})"
    )


def labelled_stretches(frame_label: np.ndarray) -> list[tuple[int, int, str]]:
    """Runs of one label: ``(start, end, label)`` frames, end exclusive, in order."""
    n = len(frame_label)
    change = np.flatnonzero(frame_label[1:] != frame_label[:-1]) + 1
    starts = np.r_[0, change]
    ends = np.r_[change, n]
    return [(int(a), int(b), str(frame_label[a])) for a, b in zip(starts, ends, strict=True)]
