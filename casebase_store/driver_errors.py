"""A database driver's or server's error said as the one-line :class:`StoreError` a user reads,
naming the store."""

from __future__ import annotations

import codecs
import os
from pathlib import Path
from typing import Any

from features.fileio import SQLITE_MAGIC, binary_kind, file_head

from .errors import InterruptedWrite, NotADatabase, StoreError
from .locations import journal_file

_INTERRUPTED = (
    "its last change was interrupted (the process writing it was killed): {journal} holds what "
    "to undo"
)


#: SQLite's extended result code for a read-only connection that met such a journal
SQLITE_READONLY_ROLLBACK = 776
#: SQLite's extended result code for a write(2) that failed (EIO; EFBIG: RLIMIT_FSIZE)
_SQLITE_IOERR_WRITE = 778
#: SQLite's result code for a write the disk had no room for (ENOSPC), of the file or journal
_SQLITE_FULL = 13
#: SQLite's extended result code for a write to a file deleted or renamed while open
_SQLITE_READONLY_DBMOVED = 1032

#: How a server or driver says a connection that was open is gone (the server shut down or
#: restarted, an administrator ended the session, the network dropped it).
_LOST_WORDS = (
    "terminating connection",  # PostgreSQL ending a session (pg_terminate_backend, shutdown)
    "server closed the connection",  # libpq
    "connection is closed",  # psycopg, on a connection already gone
    "consuming input failed",  # psycopg, reading from a dropped socket
)


def _what_file(where: str) -> str | None:
    """What a file that is no SQLite database looks like it is, for the one line that refuses
    it (an input given where the case base goes, the two swapped); None when nothing known."""
    head = file_head(where)
    if head.startswith(SQLITE_MAGIC):  # a damaged database: no other kind of file
        return None
    if (kind := binary_kind(head)) is not None:
        return kind
    if _looks_like_text(head):
        return "a text file, such as a labels CSV"
    return None


def _looks_like_text(head: bytes) -> bool:
    """Whether a file's first bytes ``head`` read as UTF-8 text (a byte order mark, as Excel
    saves a CSV, skipped; a character cut off by the end of ``head`` allowed): printable
    characters, tabs and line ends, accented letters among them."""
    try:
        text = codecs.getincrementaldecoder("utf-8-sig")().decode(head, final=False)
    except UnicodeDecodeError:
        return False
    return bool(text) and all(c.isprintable() or c in "\t\r\n" for c in text)


def _by_sqlite_code(code: Any, where: str) -> StoreError | None:
    """The line for a SQLite error its extended result code tells apart (None: read its
    text)."""
    folder = journal_file(Path(where)).parent  # where the journal is, and would be removed
    if code == SQLITE_READONLY_ROLLBACK and not os.access(folder, os.W_OK | os.X_OK):
        return InterruptedWrite(
            f"{_INTERRUPTED.format(journal=journal_file(Path(where)))}; its folder cannot be "
            "written, so it cannot be rolled back here: copy both files to a folder that "
            "can be written and run `posecbr casebase upgrade --db FILE` there",
            where,
        )
    if code == SQLITE_READONLY_ROLLBACK and not os.access(where, os.W_OK):
        # the file itself read-only (its folder writable): no command here can undo it
        return InterruptedWrite(
            f"{_INTERRUPTED.format(journal=journal_file(Path(where)))}; the file cannot be "
            "written, so it cannot be rolled back here: make it writable, or copy both files "
            "to where they can be written, and run `posecbr casebase upgrade --db FILE` there",
            where,
        )
    if code == SQLITE_READONLY_ROLLBACK:  # before "readonly" below: the file can be written
        return InterruptedWrite(
            f"{_INTERRUPTED.format(journal=journal_file(Path(where)))}, and a command "
            "that only reads writes nothing: undo it with `posecbr casebase upgrade --db FILE`"
            " (a command that changes the case base also does)",
            where,
        )
    if code == _SQLITE_READONLY_DBMOVED:  # not "read-only": the file went from under it
        return StoreError(
            "the case base file was deleted or moved while the store was open: nothing was"
            " written (open the store again where the file is)",
            where,
        )
    if code == _SQLITE_IOERR_WRITE:  # write(2) failed: EIO, or EFBIG past a file size limit
        return StoreError(
            "cannot write the database file: disk I/O error (a failing disk, or the file would "
            "grow past a size limit such as `ulimit -f`)",
            where,
        )
    if code == _SQLITE_FULL:  # "database or disk is full", said as "database error: ..."
        return StoreError(
            "cannot write the database file: the disk is full (no room for the file or the "
            "journal SQLite writes beside it): free some space and run again",
            where,
        )
    return None


def translate_error(exc: BaseException, where: str, timeout_s: float) -> StoreError:
    text = str(getattr(exc, "orig", None) or exc).strip()
    low = text.lower()
    code = getattr(getattr(exc, "orig", None) or exc, "sqlite_errorcode", None)
    known = _by_sqlite_code(code, where)
    if known is not None:
        return known
    if "locked" in low or "busy" in low or "lock timeout" in low:
        return StoreError(
            f"database is locked by another process (gave up after {timeout_s:g} s)", where
        )
    if "not a database" in low or "malformed" in low or "disk image" in low:
        return NotADatabase(_what_file(where), where)
    if "unable to open" in low or "readonly" in low or "read-only" in low:
        return StoreError(f"cannot open or write the database ({text})", where)
    if "no such table" in low or ("relation" in low and "does not exist" in low):
        first = text.splitlines()[0]
        return StoreError(
            f"not a whole posecbr case base store: a table is missing ({first})", where
        )
    if "could not decode" in low:
        return StoreError(
            "not a readable case base store (damaged: a text column holds bytes that are not"
            " UTF-8)",
            where,
        )
    if any(
        words in low
        for words in (
            "connection failed",
            "could not connect",
            "connection refused",
            "failed to resolve host",  # psycopg: a host name the DNS does not know
            "could not translate host name",  # libpq's own words for it
        )
    ):
        first = " ".join(text.split())
        return StoreError(f"cannot connect to the database server ({first})", where)
    if any(words in low for words in _LOST_WORDS):
        first = " ".join(text.split())
        return StoreError(f"the connection to the database server was lost ({first})", where)
    first = text.splitlines()[0] if text else type(exc).__name__
    return StoreError(f"database error: {first}", where)
