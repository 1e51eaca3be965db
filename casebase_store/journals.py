"""A change a killed or failed writer left half-made in a SQLite file (its hot journal) undone,
for a command about to write, which first checks it can."""

from __future__ import annotations

import os
from contextlib import suppress
from pathlib import Path
from typing import TYPE_CHECKING

from .driver_errors import SQLITE_READONLY_ROLLBACK, translate_error
from .errors import StoreError
from .locations import check_name_length, check_timeout, check_writable, journal_file, sqlite_file

if TYPE_CHECKING:
    from sqlalchemy import Engine

#: The first bytes of a rollback journal that holds a transaction (SQLite zeroes or deletes
#: it when the transaction ends)
_JOURNAL_MAGIC = bytes.fromhex("d9d505f920a163d7")


def _hot_journal(path: Path) -> bool:
    """Whether ``path``'s rollback journal holds a transaction (left by a killed writer when no
    process is writing it now)."""
    try:
        if not journal_file(path).is_file():  # a pipe would make open() wait for a writer
            return False
        with open(journal_file(path), "rb") as fh:
            return fh.read(len(_JOURNAL_MAGIC)) == _JOURNAL_MAGIC
    except OSError:
        return False


def roll_back_interrupted(url_or_path: str | Path, *, timeout_s: float = 30.0) -> bool:
    """Undo the transaction a killed writer left in a SQLite file (its ``-journal``), as
    SQLite does when a connection that may write opens it: for a command that will write,
    which reads the store read-only first (a read-only connection cannot undo it and fails
    with :class:`casebase_store.errors.InterruptedWrite`). Returns whether one was undone;
    nothing happens to a file without such a journal, another backend, or a transaction another
    process is still writing (SQLite undoes only a journal whose writer is gone)."""
    file = sqlite_file(url_or_path)
    if file is None:
        return False
    check_name_length(file)
    if not file.is_file() or not _hot_journal(file):
        return False
    # the connection's modules (SQLAlchemy) only for a journal to undo: a command's
    # prepare_write of a file without one, before its refusals, imports none of them
    from sqlalchemy.exc import DBAPIError

    from .engine import dispose, make_engine

    check_timeout(timeout_s)
    for readonly in (True, False):  # first a look that writes nothing: is it to be undone?
        engine, where = make_engine(file, timeout_s, readonly)
        try:
            with engine.connect() as conn:
                conn.exec_driver_sql("SELECT count(*) FROM sqlite_master").scalar()
            return not readonly
        except DBAPIError as exc:
            code = getattr(exc.orig, "sqlite_errorcode", None)
            if not (readonly and code == SQLITE_READONLY_ROLLBACK):
                raise translate_error(exc, where, timeout_s) from None
        finally:
            dispose(engine)
    return False


def undo_failed_write(engine: Engine, timeout_s: float) -> None:
    """After a write transaction of ``engine`` failed: undo what it wrote into a SQLite file.
    A write that failed partway (the disk full, or a file size limit reached, as changed pages
    spilled into the file) leaves the file half-changed and its journal beside it, for the
    next connection that may write to undo: readers, which open it read-only, then refused it
    as a killed writer's. The failed connection is closed first (it holds the journal's
    changes undone no more). Nothing happens for another backend or a file without such a
    journal."""
    from .engine import is_sqlite  # the engine's module was imported to make ``engine``

    if not is_sqlite(engine):
        return
    file = Path(str(engine.url.database))
    if not _hot_journal(file):
        return
    engine.dispose()
    with suppress(StoreError):  # another process writing now: its journal, not undone
        roll_back_interrupted(file, timeout_s=min(timeout_s, 1.0))


def prepare_write(url_or_path: str | Path, *, timeout_s: float = 30.0) -> bool:
    """For a command that will change a store and reads it read-only first: refuse, before any
    work, a SQLite file it cannot write (the file read-only, or its folder, where SQLite writes
    its journal; a new file's folder), then undo a change a killed writer left half-made
    (:func:`roll_back_interrupted`, whose answer it returns)."""
    file = sqlite_file(url_or_path)
    if file is not None:
        check_name_length(file)
    if file is not None and file.is_file():
        check_writable(file)
    elif file is not None and file.parent.is_dir() and not file.exists():
        # a new file: its folder (``casebase copy --to`` said "unable to open database file")
        if not os.access(file.parent, os.W_OK | os.X_OK):
            raise StoreError(
                f"cannot write the case base file: the folder {file.parent} is read-only", file
            )
    return roll_back_interrupted(url_or_path, timeout_s=timeout_s)
