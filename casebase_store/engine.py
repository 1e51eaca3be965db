"""The SQLAlchemy engine of a store's database, configured for its backend: the timeouts and
locks, read-only connections that create nothing, and a SQLite file still in posecbr 0.1's WAL
mode kept as it is until a write commits."""

from __future__ import annotations

import os
import sqlite3
import weakref
from pathlib import Path
from typing import Any
from urllib.parse import quote

from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import URL, Connection, make_url
from sqlalchemy.exc import ArgumentError, SQLAlchemyError

from features.fileio import SQLITE_MAGIC
from features.text import hide_passwords

from .driver_errors import translate_error
from .errors import StoreError
from .locations import check_store_file, shown_url, sqlite_file


def is_sqlite(engine: Engine) -> bool:
    return engine.dialect.name == "sqlite"


def in_wal_mode(path: Path) -> bool:
    """Whether the SQLite file ``path`` is in WAL mode (as posecbr 0.1 wrote its stores), from
    its header alone (bytes 18 and 19, the file format's write and read versions: 2 in WAL
    mode), without opening it with SQLite."""
    try:
        if not path.is_file():  # a pipe would make open() wait for a writer
            return False
        with open(path, "rb") as fh:
            head = fh.read(20)
    except OSError:  # also a name longer than the file system allows
        return False
    return head.startswith(SQLITE_MAGIC) and 2 in head[18:20]


def _sqlite_readonly_url(path: Path) -> URL:
    """A read-only SQLite URL for ``path``. A database still in WAL mode (written by posecbr
    0.1) needs its ``-wal`` and ``-shm`` files: where this process cannot create them (a
    read-only folder) the file is opened ``immutable``. Where it can, SQLite creates them
    and, opened read-only, cannot remove them again; ``immutable`` there would read without
    locks a file that a writer may be converting or changing. So such a file in a folder that
    can be written is refused before SQLite opens it: ``posecbr casebase upgrade`` (a writer)
    converts it to a rollback journal once. A file with a rollback journal needs no side file
    to be read, in any folder: it is read with SQLite's locks, which wait for a writer still
    writing it and tell its journal from a killed writer's (read ``immutable``, a writer
    elsewhere allowed to write the folder was said to be killed, and its changes read
    half-made)."""
    params = {"mode": "ro", "uri": "true"}
    given, path = path, path.resolve()  # SQLite's side files are beside the file a link names
    shm = path.with_name(path.name + "-shm")
    writable = os.access(path.parent, os.W_OK)
    if writable and in_wal_mode(path):
        raise StoreError(
            "the file is in WAL mode (as posecbr 0.1 wrote it): reading it would leave "
            f"{path.name}-wal and {path.name}-shm beside it; convert it once with "
            "`posecbr casebase upgrade --db FILE`",
            given,
        )
    if not writable and not shm.exists() and in_wal_mode(path):
        if _wal_frames(path):  # immutable ignores the -wal: unseen
            raise StoreError(
                f"{path.name}-wal beside it holds changes not yet in the file, and without "
                f"{path.name}-shm, in a folder that cannot be written, they cannot be read: "
                "copy the files to a folder that can be written and run `posecbr casebase "
                "upgrade --db FILE` there",
                given,
            )
        params["immutable"] = "1"
    # built, not parsed: SQLAlchemy would undo the quoting, and SQLite would then read a "?",
    # "#" or "%20" of the file's name as the URI's query, fragment or escape (a read of
    # "a?b.sqlite" opened, and created, a file "a")
    return URL.create("sqlite", database=f"file:{quote(str(path.resolve()))}", query=params)


def _wal_frames(path: Path) -> bool:
    """Whether ``path``'s ``-wal`` file holds frames (changes, committed or not, not yet copied
    into the file): more than its 32-byte header."""
    wal = path.with_name(path.name + "-wal")
    try:
        return wal.is_file() and wal.stat().st_size > 32
    except OSError:
        return False


def make_engine(url_or_path: str | Path, timeout_s: float, readonly: bool) -> tuple[Engine, str]:
    """The engine for a case base file or database URL, configured for ``timeout_s`` and
    ``readonly``, and the name to show for it (a URL without its password)."""
    url, where = _engine_url(url_or_path, readonly)
    backend = url.get_backend_name()
    try:
        engine = create_engine(url, **_connect_args(url, timeout_s))
    except ImportError as exc:
        hint = _driver_hint(url.drivername) if backend == "postgresql" else ""
        raise StoreError(
            f"the database driver for {url.drivername} is not installed: {exc}{hint}", where
        ) from None
    except (ArgumentError, SQLAlchemyError) as exc:
        raise StoreError(f"cannot use database URL ({exc}){_scheme_hint(url)}", where) from None
    if is_sqlite(engine):
        _configure_sqlite(engine, timeout_s, readonly)
        if not readonly:
            _hold_wal(engine, timeout_s, where)
    elif engine.dialect.name == "postgresql":
        _configure_postgresql(engine, timeout_s, readonly)
    return engine, where


def _driver_hint(drivername: str) -> str:
    """What installs the missing PostgreSQL driver of ``drivername``: posecbr's extra installs
    psycopg 3 (``postgresql+psycopg``), not psycopg2 or any other driver."""
    extra = "pip install 'posecbr[postgres]'"
    if drivername in ("postgresql", "postgresql+psycopg"):
        return f" ({extra})"
    return f" (install that driver, or write the URL as postgresql+psycopg://... after {extra})"


def _scheme_hint(url: URL) -> str:
    """What a URL SQLAlchemy has no dialect for was likely meant to say: ``postgres://``
    (Heroku's and many a ``DATABASE_URL``'s spelling, which SQLAlchemy 1.4 dropped) is
    ``postgresql://``; a scheme in capitals (``SQLITE:///cb.sqlite``) is read as written."""
    scheme = url.drivername
    backend, plus, driver = scheme.lower().partition("+")
    if backend == "postgres":
        return f": write postgresql{plus}{driver}:// (SQLAlchemy's name), not {scheme}://"
    if scheme != scheme.lower():
        return f": write the scheme in lower case, {scheme.lower()}://"
    return ""


def _engine_url(url_or_path: str | Path, readonly: bool) -> tuple[URL, str]:
    """The database URL of a case base file (read-only when asked; its folder must exist) or
    of a URL, and the name to show for it."""
    file = sqlite_file(url_or_path)
    if file is None:
        text = str(url_or_path)
        try:
            url = make_url(text)
        except ArgumentError as exc:
            raise StoreError(f"not a database URL ({exc})", hide_passwords(text)) from None
        except ValueError:  # SQLAlchemy reads the port with int()
            raise StoreError(
                "not a database URL (its port is not a number)", hide_passwords(text)
            ) from None
        if url.get_backend_name() == "sqlite":  # no file: in memory (sqlite://, :memory:)
            raise StoreError(
                "an in-memory SQLite database keeps nothing once the command ends: name a "
                "case base file (a path, or sqlite:///FILE)",
                text,
            )
        return url, shown_url(url)
    check_store_file(file)
    if readonly:
        return _sqlite_readonly_url(file), str(file)
    # built, not parsed: a path's "?" or "%20" is part of the file name, not a URL's query or
    # escape ("a?b.sqlite" as text made SQLAlchemy open a file "a")
    return URL.create("sqlite", database=str(file)), str(file)


def _connect_args(url: URL, timeout_s: float) -> dict[str, Any]:
    """``create_engine`` keywords that bound how long connecting may wait."""
    backend = url.get_backend_name()
    if backend == "sqlite":
        return {"connect_args": {"timeout": timeout_s}}
    if backend == "postgresql" and "connect_timeout" not in url.query:
        # libpq waits for an unreachable server as long as the OS does (minutes)
        return {"connect_args": {"connect_timeout": max(1, int(round(timeout_s)))}}
    return {}


def _configure_sqlite(engine: Engine, timeout_s: float, readonly: bool) -> None:
    # pysqlite's own transaction handling starts transactions late and never IMMEDIATE; take
    # it over (SQLAlchemy's documented recipe) so writers lock up front and queue politely.
    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_conn: sqlite3.Connection, _record: object) -> None:
        dbapi_conn.isolation_level = None
        cur = dbapi_conn.cursor()
        cur.execute(f"PRAGMA busy_timeout = {int(timeout_s * 1000)}")
        cur.execute("PRAGMA foreign_keys = ON")
        if not readonly:  # the journal mode is a property of the file: readers leave it
            # a rollback journal, not WAL: a reader then needs no side files, so reading
            # creates nothing and works in a read-only folder. A store written in WAL mode by
            # posecbr 0.1 is converted by its first writer, once a write of it has committed
            # (leave_wal_mode): converting it here, on connecting, changed the file of a
            # command then refused (an old schema, a name taken), which must change nothing
            if not in_wal_mode(Path(str(engine.url.database))):
                cur.execute("PRAGMA journal_mode = DELETE")
            cur.execute("PRAGMA synchronous = FULL")
        cur.close()

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Connection) -> None:
        write = conn.get_execution_options().get("posecbr_write", False)
        conn.exec_driver_sql("BEGIN IMMEDIATE" if write else "BEGIN")


#: Writer engines on a file in WAL mode with its ``-wal`` file beside it, and the read-only
#: connection to the file :func:`_hold_wal` holds open for each
_WAL_GUARDS: weakref.WeakKeyDictionary[Engine, sqlite3.Connection] = weakref.WeakKeyDictionary()


def _hold_wal(engine: Engine, timeout_s: float, where: str) -> None:
    """For the writer ``engine`` of a file in WAL mode (as posecbr 0.1 left its stores) whose
    ``-wal`` file is there: hold a read-only connection to the file open until the writer's
    connections have closed (:func:`dispose`). SQLite's last connection to close such a file
    copies the ``-wal`` file's changes into it and deletes the ``-wal`` and ``-shm`` files (a
    checkpoint): a command refused after opening the store (a name taken, a schema it cannot
    convert) changed the file's bytes. The writer's connections then close while another is
    open, which keeps them from it, and a read-only one cannot checkpoint. The first write
    that commits lets it go to leave WAL mode (:func:`leave_wal_mode`). Without a ``-wal``
    file the writer's close deletes the two it created and changes nothing."""
    file = Path(str(engine.url.database)).resolve()
    if not in_wal_mode(file) or not file.with_name(file.name + "-wal").exists():
        return
    url = f"file:{quote(str(file))}?mode=ro"
    try:
        guard = sqlite3.connect(url, uri=True, timeout=timeout_s, isolation_level=None)
    except sqlite3.Error as exc:
        raise translate_error(exc, where, timeout_s) from None
    try:
        guard.execute("SELECT count(*) FROM sqlite_master").fetchone()
    except sqlite3.Error as exc:
        guard.close()
        raise translate_error(exc, where, timeout_s) from None
    _WAL_GUARDS[engine] = guard


def _let_wal_go(engine: Engine) -> None:
    """Close the read-only connection :func:`_hold_wal` holds for ``engine``, if any."""
    guard = _WAL_GUARDS.pop(engine, None)
    if guard is not None:
        guard.close()


def dispose(engine: Engine) -> None:
    """Close ``engine``'s connections, then the read-only one :func:`_hold_wal` may hold for
    it (in this order: the writer's connections close while it is open, so a refused writer
    leaves a file in WAL mode and its ``-wal`` file as they were)."""
    engine.dispose()
    _let_wal_go(engine)


def leave_wal_mode(engine: Engine) -> bool:
    """Convert the SQLite file of the writer ``engine`` from WAL mode (as posecbr 0.1 left its
    stores) to a rollback journal, for readers that then need no side files; returns whether
    it did. Run after a write committed, outside any transaction: a command refused before
    (an old schema, a name taken) leaves the file as it was. Another process holding the file
    open makes it wait (the busy timeout), then give up: the next writer converts it."""
    _let_wal_go(engine)  # a write has committed: the file changes now, as it should
    if not is_sqlite(engine) or not in_wal_mode(Path(str(engine.url.database))):
        return False
    raw = engine.raw_connection()  # the driver's connection: no BEGIN around the PRAGMA
    try:
        cur = raw.cursor()
        try:
            cur.execute("PRAGMA journal_mode = DELETE")
            row = cur.fetchone()
            return row is not None and str(row[0]).lower() == "delete"
        finally:
            cur.close()
    except sqlite3.Error:  # busy: left in WAL mode, which the next writer converts
        return False
    finally:
        raw.close()


def _configure_postgresql(engine: Engine, timeout_s: float, readonly: bool) -> None:
    # the counterpart of SQLite's busy timeout: a statement waiting for another session's lock
    # gives up after timeout_s (PostgreSQL's default is to wait forever)
    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_conn: Any, _record: object) -> None:
        cur = dbapi_conn.cursor()
        cur.execute(f"SET lock_timeout = {int(timeout_s * 1000)}")
        if readonly:
            cur.execute("SET default_transaction_read_only = on")
        cur.close()
        dbapi_conn.commit()  # SET ran in the driver's implicit transaction
