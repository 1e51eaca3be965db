"""Converting a store written by an older posecbr to the current schema, in one transaction.

Schema 1 -> 2: case bases get an identity (``uid``), a version and an (empty) fitted model;
ids are never reused from now on (SQLite ``AUTOINCREMENT``). Every row keeps its id, so
maintenance-log entries still name their cases. A case base from schema 1 has no stored model:
it is classified with the defaults its configuration implies (see ``cbr.stored``).

Columns and indexes added since without a version of their own (a store made before them is
read and written as it is: the cases' poses digests, the index on their sources) are added
by the upgrade too, empty (NULL) for the cases there.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

from sqlalchemy import MetaData, inspect, text

from features.version import __version__

from .driver_errors import translate_error
from .engine import dispose, in_wal_mode, leave_wal_mode, make_engine
from .errors import StoreError
from .journals import undo_failed_write
from .locations import check_name_length, check_writable, sqlite_file
from .models import (
    SCHEMA_VERSION,
    UPGRADABLE,
    CaseBaseRow,
    CaseRow,
    MaintenanceRow,
    RepresentationRow,
    SchemaVersion,
)
from .store import _PG_INIT_LOCK

_TABLES = (CaseBaseRow, CaseRow, RepresentationRow, MaintenanceRow)


def upgrade_store(url_or_path: str | Path, *, timeout_s: float = 30.0) -> int:
    """Bring the store to :data:`SCHEMA_VERSION`; returns the version it had (the current one
    when nothing was to do). Everything happens in one transaction: an interrupted upgrade
    leaves the store as it was."""
    file = sqlite_file(url_or_path)
    if file is not None:
        check_name_length(file)
    if file is not None and not file.exists():
        raise StoreError("no such case base file", file)
    # a file that cannot be written is refused before SQLite opens it to write, when it has
    # something to convert (before: "unable to open database file", or, for a read-only file
    # still in WAL mode, "disk I/O error" with -wal and -shm files left beside it)
    if file is not None and _nothing_to_do_unwritable(file, timeout_s):
        return SCHEMA_VERSION
    engine, where = make_engine(url_or_path, timeout_s, readonly=False)
    try:
        try:
            found = _convert(engine, where)
        except BaseException:  # a full disk partway: the file as it was, no journal left
            undo_failed_write(engine, timeout_s)
            raise
        # posecbr 0.1's WAL mode, once the store reads as current; another process holding
        # the file open keeps it there (before: "nothing to do", the file still in WAL mode)
        if not leave_wal_mode(engine) and file is not None and in_wal_mode(file):
            done = f"converted from schema version {found} to {SCHEMA_VERSION}, but " * (
                found != SCHEMA_VERSION
            )
            raise StoreError(
                f"{done}the file is still in WAL mode: another process is reading or writing"
                " it; run `posecbr casebase upgrade --db FILE` again once it has closed it",
                where,
            )
        return found
    except StoreError:
        raise
    except Exception as exc:  # a driver error of any backend: one line naming the store
        raise translate_error(exc, where, timeout_s) from None
    finally:
        dispose(engine)


def _convert(engine: Any, where: str) -> int:
    """Convert the store of ``engine`` in one transaction; returns the version it had."""
    with engine.execution_options(posecbr_write=True).begin() as conn:
        if conn.dialect.name == "postgresql":
            # as SQLite's BEGIN IMMEDIATE: two upgrades at once, the second waits for the
            # first, then finds the store converted (at READ COMMITTED both read version
            # 1, and the second gave up "locked" or converted the store again)
            conn.exec_driver_sql(f"SELECT pg_advisory_xact_lock({_PG_INIT_LOCK})")
        found = _schema_version(conn, where)
        if found != SCHEMA_VERSION:
            _check_upgradable(found, where)  # refused: the file as it was, WAL mode too
            _from_1(conn)
        _add_columns(conn)
        _add_indexes(conn)
    return found


def _add_columns(conn: Any) -> None:
    """Add the (nullable) columns of today's schema that the store's tables lack (added since
    it was made): NULL in every row there."""
    look = inspect(conn)
    for table in _TABLES:
        name = table.__tablename__
        have = {c["name"] for c in look.get_columns(name)}
        for column in table.__table__.columns:
            if column.name not in have:
                assert column.nullable, column.name  # a column of values would need them
                quote = conn.dialect.identifier_preparer.quote
                kind = column.type.compile(dialect=conn.dialect)
                conn.execute(
                    text(f"ALTER TABLE {quote(name)} ADD COLUMN {quote(column.name)} {kind}")
                )


def missing_columns(url_or_path: str | Path, *, timeout_s: float = 30.0) -> list[str]:
    """The columns of today's schema (``table.column``) that the store lacks (it was made
    before they were added; :func:`upgrade_store` adds them), read without writing; none
    when it cannot be read (what is wrong with it is told by the upgrade)."""
    return _missing(url_or_path, timeout_s, _lacking_columns)


def _lacking_columns(look: Any, tables: set[str]) -> list[str]:
    return [
        f"{table.__tablename__}.{column.name}"
        for table in _TABLES
        if table.__tablename__ in tables
        for column in table.__table__.columns
        if column.name not in {c["name"] for c in look.get_columns(table.__tablename__)}
    ]


def _add_indexes(conn: Any) -> None:
    """Create the indexes of today's schema that the store lacks (added since it was made)."""
    for table in _TABLES:
        for index in table.__table__.indexes:  # type: ignore[attr-defined]
            index.create(conn, checkfirst=True)


def missing_indexes(url_or_path: str | Path, *, timeout_s: float = 30.0) -> list[str]:
    """The indexes of today's schema that the store lacks (it was made before they were
    added; :func:`upgrade_store` creates them), read without writing; none when it cannot be
    read (what is wrong with it is told by the upgrade)."""
    return _missing(url_or_path, timeout_s, _lacking_indexes)


def _lacking_indexes(look: Any, tables: set[str]) -> list[str]:
    return [
        str(index.name)
        for table in _TABLES
        if table.__tablename__ in tables
        for index in table.__table__.indexes  # type: ignore[attr-defined]
        if index.name not in {i["name"] for i in look.get_indexes(table.__tablename__)}
    ]


def _missing(
    url_or_path: str | Path, timeout_s: float, lacking: Callable[[Any, set[str]], list[str]]
) -> list[str]:
    """What ``lacking`` finds missing in the store (its inspector, its tables), read without
    writing; none when it cannot be read."""
    file = sqlite_file(url_or_path)
    if file is not None and not file.is_file():
        return []
    try:
        engine, _ = make_engine(url_or_path, timeout_s, readonly=True)
    except Exception:  # a driver error of any backend: the upgrade says it
        return []
    try:
        with engine.connect() as conn:
            look = inspect(conn)
            return lacking(look, set(look.get_table_names()))
    except Exception:  # a driver error of any backend: the upgrade says it
        return []
    finally:
        dispose(engine)


def _nothing_to_do_unwritable(file: Path, timeout_s: float) -> bool:
    """For a SQLite file this process cannot write (the file or its folder read-only): True
    when it needs no conversion (the current schema with every index and column of today's,
    not in WAL mode: the caller returns, having read it read-only); refused in one line when
    it does, naming what the upgrade would add (before: "nothing to do" for a store of the
    current version lacking an index or a column). False for a writable file."""
    try:
        check_writable(file)
    except StoreError as refused:
        if in_wal_mode(file):  # leaving WAL mode writes the file
            raise
        engine, where = make_engine(file, timeout_s, readonly=True)
        try:
            with engine.connect() as conn:
                found = _schema_version(conn, where)
                look = inspect(conn)
                tables = set(look.get_table_names())
                lacking = [f"the index {n}" for n in _lacking_indexes(look, tables)]
                lacking += [f"the column {n}" for n in _lacking_columns(look, tables)]
        except StoreError:
            raise
        except Exception as exc:  # a driver error: one line naming the store
            raise translate_error(exc, where, timeout_s) from None
        finally:
            engine.dispose()
        if found != SCHEMA_VERSION:
            _check_upgradable(found, where)  # a version it could not convert anywhere
            raise
        if lacking:  # as the upgrade of a writable file says it added them
            raise StoreError(
                f"would add {' and '.join(lacking)} of a newer schema, but {refused.message}",
                refused.source,
            ) from None
        return True
    return False


def _check_upgradable(found: int, where: str) -> None:
    """Refuse a schema version this posecbr cannot convert (a newer one, an unknown one)."""
    if found > SCHEMA_VERSION:
        raise StoreError(
            f"the store has schema version {found}, newer than this posecbr "
            f"{__version__} knows ({SCHEMA_VERSION}): read it with the posecbr that "
            "wrote it",
            where,
        )
    if found not in UPGRADABLE:
        raise StoreError(
            f"cannot upgrade a store of schema version {found}: posecbr upgrades "
            f"versions {', '.join(map(str, UPGRADABLE))}",
            where,
        )


def _schema_version(conn: Any, where: str) -> int:
    if SchemaVersion.__tablename__ not in inspect(conn).get_table_names():
        raise StoreError("not a posecbr case base store", where)
    version = conn.execute(
        text(f"SELECT version FROM {SchemaVersion.__tablename__} WHERE id = 1")
    ).scalar()
    if version is None:
        raise StoreError("the store has no schema version", where)
    return int(version)


def _from_1(conn: Any) -> None:
    old = MetaData()
    old.reflect(conn, only=[t.__tablename__ for t in _TABLES])
    rows = {
        t.__tablename__: conn.execute(old.tables[t.__tablename__].select()).mappings().all()
        for t in _TABLES
    }
    old.drop_all(conn)
    for table in (t.__table__ for t in _TABLES):
        table.create(conn)  # type: ignore[attr-defined]
    bases = [
        {**dict(r), "uid": uuid.uuid4().hex, "version": 1, "model": "{}"}
        for r in rows[CaseBaseRow.__tablename__]
    ]
    for model, data in ((CaseBaseRow, bases),) + tuple(
        (t, [dict(r) for r in rows[t.__tablename__]]) for t in _TABLES[1:]
    ):
        if data:
            conn.execute(model.__table__.insert(), data)  # type: ignore[attr-defined]
    if conn.dialect.name == "postgresql":  # explicit ids do not move the sequences
        for t in _TABLES:
            conn.execute(
                text(
                    f"SELECT setval(pg_get_serial_sequence('{t.__tablename__}', 'id'), "
                    f"COALESCE((SELECT MAX(id) FROM {t.__tablename__}), 0) + 1, false)"
                )
            )
    conn.execute(
        SchemaVersion.__table__.update()  # type: ignore[attr-defined]
        .where(SchemaVersion.id == 1)
        .values(version=SCHEMA_VERSION)
    )
