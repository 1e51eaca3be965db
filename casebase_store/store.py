"""The case base store's repository API: the only place in posecbr that talks to a database.

Open a store with :func:`open_store` (a SQLite file path, or any SQLAlchemy URL). Every user
action is one transaction::

    store = open_store("cb.sqlite", create=True)  # a new file; without: it must exist
    with store.transaction() as tx:          # BEGIN IMMEDIATE on SQLite
        cb = tx.create_case_base("squats", feature_config, names, words, {"name": "dtw"})
        tx.add_cases(cb, cases)
        tx.log(cb, "trim", reason="...")
    arrays = store.load_cases("squats")      # ids, labels, features (N, ...) and provenance

A process killed inside ``transaction()`` leaves the store as it was before (SQLite's journal
rolls the transaction back when the file is next opened; a PostgreSQL server rolls back the
transaction of a client whose connection dies). SQLite files use a rollback journal and a busy
timeout so several processes can write one file; write transactions start with
``BEGIN IMMEDIATE`` so two writers queue instead of failing on a read-to-write upgrade.
Commands that only read open the store read-only (``open_store(..., readonly=True)``): they
create no file, not even a journal, and work on a case base in a read-only folder. On
PostgreSQL the same timeout is the connect timeout and the ``lock_timeout`` of every session,
so a write blocked by another client's lock fails with the same "locked" error. A write
transaction holds each case base it checks or creates (an advisory lock on its name) until it
ends, so PostgreSQL's writers of one case base queue as SQLite's do.

The same code runs on every backend; what differs is kept to :mod:`casebase_store.engine`
(the engine and its per-dialect connect hooks). Values a stricter server would refuse
(over-long names, NUL characters in text) are refused first (:mod:`casebase_store.encoding`),
with the same error on every backend.
"""

from __future__ import annotations

import hashlib
import json
import os
import sqlite3
import uuid
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from datetime import datetime
from pathlib import Path
from typing import Any, TypeVar, cast

import numpy as np
from sqlalchemy import Engine, Table, delete, func, insert, inspect, select, update
from sqlalchemy import text as sql_text
from sqlalchemy.exc import DBAPIError, SQLAlchemyError
from sqlalchemy.orm import Session

from features.fileio import remove_stale_temporaries, temporary_prefix
from features.version import __version__

from .driver_errors import translate_error
from .encoding import (
    as_stored,
    as_utc,
    canonical_json,
    check_case_base_name,
    check_document,
    check_poses,
    check_text,
    config_hash,
    decode_array,
    decode_arrays,
    encode_array,
    read_json,
)
from .engine import dispose, is_sqlite, leave_wal_mode, make_engine
from .errors import CaseBaseGone, EmptyStore, StaleCaseError, StoreError
from .journals import undo_failed_write
from .locations import (
    check_to_open,
    check_url_or_path,
    refuse_dangling,
    sqlite_file,
)
from .models import (
    SCHEMA_VERSION,
    UPGRADABLE,
    Base,
    CaseBaseRow,
    CaseRow,
    MaintenanceRow,
    RepresentationRow,
    SchemaVersion,
)
from .records import (
    CaseArrays,
    CaseBaseInfo,
    MaintenanceEntry,
    NewCase,
    Seen,
    SourcedCase,
    StoredCase,
    WholeCaseBase,
    check_width,
)

ORIGINS = ("trained", "retained", "revised")

#: Serialises creating the tables when several clients open an empty PostgreSQL database at
#: once (``pg_advisory_xact_lock`` key; any constant unlikely to collide with other apps).
_PG_INIT_LOCK = 0x706F736563627231  # "posecbr1"
#: The first key of the per-case-base locks (``pg_advisory_xact_lock(int, int)``, a key space
#: apart from the one-key locks; the second key is from the case base's name).
_PG_NAME_LOCKS = 0x706F7365  # "pose"


def listed_names(names: Sequence[str]) -> str:
    """Case base names as a list in a message: each as it is, or quoted when it would not
    read as itself there (spaces around it, a comma, a character that does not print):
    "squats " among others was "a, b, squats )"."""
    return ", ".join(
        repr(n) if n != n.strip() or "," in n or not n.isprintable() else n for n in names
    )


def _inserted_id(result: Any) -> int:
    """The id of the one row an insert without RETURNING added."""
    key = result.inserted_primary_key
    assert key is not None  # an insert's result has one
    return int(key[0])


class CaseStore:
    """A case base store on one database. Create with :func:`open_store`."""

    def __init__(self, engine: Engine, where: str, timeout_s: float, readonly: bool) -> None:
        self.engine = engine
        self.where = where
        self.timeout_s = timeout_s
        self.readonly = readonly
        self._write_engine = engine.execution_options(posecbr_write=True)
        #: whether the cases table has the column of their clips' poses digests (a store made
        #: before it has none until `casebase upgrade`: read and written as it is)
        self.keeps_poses = True
        self.closed = False

    def _open(self) -> None:
        """Refuse a store used after :meth:`close`: its engine would connect again, unasked,
        and to a SQLite file deleted or moved meanwhile make an empty one in its place."""
        if self.closed:
            raise StoreError(
                "the store is closed (used after its `with` block or close()): open it again"
                " with open_store()",
                self.where,
            )

    # -- plumbing

    @contextmanager
    def _errors(self) -> Iterator[None]:
        try:
            yield
        except StoreError:
            raise
        except (DBAPIError, SQLAlchemyError, sqlite3.Error) as exc:
            raise translate_error(exc, self.where, self.timeout_s) from None

    @contextmanager
    def transaction(self) -> Iterator[StoreTransaction]:
        """One write transaction: everything inside commits together or not at all. Every case
        base whose cases it changed gets its version raised by one, in the same commit."""
        self._open()
        if self.readonly:
            raise StoreError("opened read-only: this command does not write", self.where)
        try:
            with self._errors(), Session(self._write_engine, expire_on_commit=False) as session:
                with session.begin():
                    tx = StoreTransaction(self, session)
                    yield tx
                    tx._bump_versions()
        except BaseException:
            self._undo_failed_write()
            raise
        leave_wal_mode(self.engine)  # posecbr 0.1's WAL mode, once a write has committed

    def _undo_failed_write(self) -> None:
        """After a write transaction failed: undo what it wrote (:func:`undo_failed_write`)."""
        undo_failed_write(self.engine, self.timeout_s)

    @contextmanager
    def _read(self) -> Iterator[Session]:
        """A read transaction that sees one snapshot of the store (SQLite's WAL readers always
        do; PostgreSQL needs REPEATABLE READ for several statements to agree)."""
        self._open()
        with self._errors(), Session(self.engine, expire_on_commit=False) as session:
            with session.begin():
                if self.engine.dialect.name == "postgresql":
                    session.connection(execution_options={"isolation_level": "REPEATABLE READ"})
                yield session

    def _init_schema(self, create: bool) -> None:
        with self._errors():
            names = set(inspect(self.engine).get_table_names())
            if SchemaVersion.__tablename__ in names:
                with self._read() as s:
                    row = s.get(SchemaVersion, 1)
                if row is None or row.version != SCHEMA_VERSION:
                    found = "none" if row is None else str(row.version)
                    hint = ""
                    if row is not None and row.version in UPGRADABLE:
                        db = "FILE" if is_sqlite(self.engine) else "URL"  # not a file
                        hint = f" (convert it with `posecbr casebase upgrade --db {db}`)"
                    elif row is not None and row.version > SCHEMA_VERSION:
                        hint = " (written by a newer posecbr: read it with that one)"
                    raise StoreError(
                        f"case base store schema version {found}, this posecbr "
                        f"{__version__} reads version {SCHEMA_VERSION}{hint}",
                        self.where,
                    )
                # a store missing its cases table is said so where it is read ("a table is
                # missing"), not here: SQLAlchemy's NoSuchTableError says only "cases"
                has_cases = CaseRow.__tablename__ in names
                columns = (
                    inspect(self.engine).get_columns(CaseRow.__tablename__) if has_cases else []
                )
                self.keeps_poses = "poses" in {c["name"] for c in columns}
                return
            if names:
                raise StoreError(
                    "not a posecbr case base store (the database holds other tables: "
                    + ", ".join(sorted(names)[:5])
                    + ")",
                    self.where,
                )
            if not create:
                raise EmptyStore("no case base store here (empty database)", self.where)
            with self.transaction() as tx:
                conn = tx.session.connection()
                if self.engine.dialect.name == "postgresql":
                    # two clients creating the tables at once: the second waits, then finds them
                    conn.exec_driver_sql(f"SELECT pg_advisory_xact_lock({_PG_INIT_LOCK})")
                if SchemaVersion.__tablename__ in inspect(conn).get_table_names():
                    return  # another client created it meanwhile (BEGIN IMMEDIATE on SQLite)
                Base.metadata.create_all(conn)
                tx.session.add(SchemaVersion(id=1, version=SCHEMA_VERSION))

    def close(self) -> None:
        """Release the store's connections (the engine's pool); the store is not used after
        (a read or write then is a StoreError saying it is closed). Closing again does
        nothing."""
        self.closed = True
        dispose(self.engine)

    def __enter__(self) -> CaseStore:
        return self

    def __reduce__(self) -> Any:
        """A store is a connection to its database: not pickled or copied (pickle said "Can't
        pickle local object 'create_engine.<locals>.connect'")."""
        raise StoreError(
            "a case base store is a connection to its database and is not pickled or copied:"
            " give another process the file or URL to open_store(), or pickle the classifier"
            " load_classifier() read",
            self.where,
        )

    def __exit__(self, *exc: object) -> None:
        """``with open_store(...) as store:`` closes the store at the end of the block, also
        when it raised."""
        self.close()

    # -- reads

    def list_case_bases(self) -> list[CaseBaseInfo]:
        with self._read() as s:
            # one row at a time: a damaged one is named. Text is sorted here, not by the
            # server: PostgreSQL sorts by the database's collation ("apple" before "Squat" in
            # en-US), SQLite by code point, and a store gives one order wherever it lives
            names = sorted(s.scalars(select(CaseBaseRow.name)).all())
            return [self._info(s, self._row(s, n)) for n in names]

    def identities(self) -> dict[str, tuple[str, int]]:
        """Every case base's identity (``uid``) with its name and version, read without
        checking the rest of it (what names its matrix files beside the database)."""
        with self._read() as s:
            rows = s.execute(select(CaseBaseRow.uid, CaseBaseRow.name, CaseBaseRow.version))
            return {str(uid): (str(name), int(version)) for uid, name, version in rows}

    def get_case_base(self, name: str) -> CaseBaseInfo:
        with self._read() as s:
            return self._info(s, self._row(s, name))

    def has_case_base(self, name: str) -> bool:
        with self._read() as s:
            return s.scalar(select(CaseBaseRow.id).where(CaseBaseRow.name == name)) is not None

    def choose(self, name: str | None) -> str:
        """``name`` when the store holds it; without a name, the store's only case base (a store
        of several, or of none, is refused naming them, and saying to choose one with ``name``:
        the commands say ``--name``)."""
        if name is not None:
            self.get_case_base(name)  # names the case bases there when absent
            return name
        names = [cb.name for cb in self.list_case_bases()]
        if len(names) == 1:
            return names[0]
        if names:
            raise StoreError(
                f"the store holds case bases {listed_names(names)}: choose one with `name`",
                self.where,
            )
        raise StoreError("the store holds no case base (run posecbr train)", self.where)

    def load_case_base(
        self, name: str, *, include_inactive: bool = False, features: bool = True
    ) -> tuple[CaseBaseInfo, CaseArrays]:
        """The case base's description and its cases, read from one snapshot (the version in
        the description is the version of exactly these cases). ``features=False``: every
        column but the problems (``features`` is then empty), for a caller that has them
        elsewhere (a memory-mapped case matrix of this version)."""
        with self._read() as s:
            row = self._row(s, name)
            return self._info(s, row), self._cases(s, row, include_inactive, None, features)

    def load_cases(
        self, name: str, *, include_inactive: bool = False, ids: Sequence[int] | None = None
    ) -> CaseArrays:
        """The case base's cases as arrays (features ``(n, *shape)`` float64), by id order."""
        with self._read() as s:
            return self._cases(s, self._row(s, name), include_inactive, ids)

    def _cases(
        self,
        s: Session,
        cb: CaseBaseRow,
        include_inactive: bool,
        ids: Sequence[int] | None,
        with_features: bool = True,
    ) -> CaseArrays:
        columns = [
            CaseRow.id,
            CaseRow.label,
            CaseRow.source,
            CaseRow.subject,
            CaseRow.origin,
            CaseRow.frame_start,
            CaseRow.frame_end,
            CaseRow.active,
        ]
        q = select(*columns, *([CaseRow.features] if with_features else [])).where(
            CaseRow.case_base_id == cb.id
        )
        if not include_inactive:
            q = q.where(CaseRow.active.is_(True))
        if ids is not None:
            q = q.where(CaseRow.id.in_([int(i) for i in ids]))
        rows = s.execute(q.order_by(CaseRow.id)).all()
        features = self._stack_features(cb, rows) if with_features else np.zeros((0,))
        return CaseArrays(
            ids=np.array([r.id for r in rows], dtype=np.int64),
            labels=np.array([r.label for r in rows], dtype=object),
            features=features,
            sources=tuple(r.source for r in rows),
            subjects=tuple(r.subject for r in rows),
            origins=tuple(r.origin for r in rows),
            frame_ranges=tuple((r.frame_start, r.frame_end) for r in rows),
            active=np.array([bool(r.active) for r in rows], dtype=bool),
        )

    def _stack_features(self, cb: CaseBaseRow, rows: Sequence[Any]) -> np.ndarray:
        """The problems of ``rows`` as one float64 array ``(n, *shape)``; damaged or mixed
        blobs are a StoreError naming the case base."""
        arrays = [decode_array(r.features, f"features of case {r.id}", self.where) for r in rows]
        if not arrays:
            return np.zeros((0,), dtype=np.float64)
        shapes = {a.shape for a in arrays}
        if len(shapes) > 1:
            raise StoreError(
                f"case base {cb.name!r} is damaged: its cases have features of different "
                f"shapes ({', '.join(str(sh) for sh in sorted(shapes)[:3])})",
                self.where,
            )
        if not all(np.issubdtype(a.dtype, np.floating) for a in arrays):
            raise StoreError(f"case base {cb.name!r} is damaged: non-numeric features", self.where)
        return np.stack(arrays).astype(np.float64, copy=False)

    def load_representations(
        self, name: str, kind: str, *, version: int | None = None
    ) -> dict[int, np.ndarray]:
        """Cached per-case representations of one ``kind`` (case id -> array). ``version``:
        those of the cases of that version of the case base, read before: a case base changed
        since is :class:`StaleCaseError` (a case revised meanwhile may have the representation
        of its new problem cached already; read everything again)."""
        with self._read() as s:
            cb = self._row(s, name)
            if version is not None and cb.version != version:
                raise StaleCaseError(
                    f"case base {name!r} was changed by another process while it was read "
                    f"(version {version}, now {cb.version})",
                    self.where,
                )
            q = (
                select(RepresentationRow.case_id, RepresentationRow.data)
                .join(CaseRow, CaseRow.id == RepresentationRow.case_id)
                .where(CaseRow.case_base_id == cb.id, RepresentationRow.kind == kind)
            )
            return {
                int(cid): decode_array(data, f"cached {kind} of case {cid}", self.where)
                for cid, data in s.execute(q)
            }

    def maintenance_log(self, name: str) -> list[MaintenanceEntry]:
        with self._read() as s:
            cb = self._row(s, name)
            damaged = f"case base {name!r} is damaged: a date in its maintenance log is not a date"
            with self._dates(damaged):
                rows = s.scalars(
                    select(MaintenanceRow)
                    .where(MaintenanceRow.case_base_id == cb.id)
                    .order_by(MaintenanceRow.id)
                ).all()
            return [
                MaintenanceEntry(
                    r.id, r.action, r.case_id, r.novelty, r.benefit, r.reason, as_utc(r.at)
                )
                for r in rows
            ]

    def read_whole(self, name: str) -> WholeCaseBase:
        """Case base ``name`` whole (:class:`WholeCaseBase`), read from one snapshot and checked
        as a command reading it would (its JSON, every problem and cached representation, its
        dates; its log naming only its own cases): damage is a StoreError here, never copied."""
        with self._read() as s:
            row = self._row(s, name)
            info = self._info(s, row)
            damaged = f"case base {name!r} is damaged: a date in it is not a date"
            with self._dates(damaged):
                cases = _rows_of(s, CaseRow, row.id, () if self.keeps_poses else ("poses",))
                log = _rows_of(s, MaintenanceRow, row.id)
            reps = [
                dict(r)
                for r in s.execute(
                    select(
                        RepresentationRow.case_id, RepresentationRow.kind, RepresentationRow.data
                    )
                    .join(CaseRow, CaseRow.id == RepresentationRow.case_id)
                    .where(CaseRow.case_base_id == row.id)
                    .order_by(RepresentationRow.id)
                ).mappings()
            ]
            columns = {
                c: getattr(row, c)
                for c in (
                    "version",
                    "feature_config",
                    "feature_hash",
                    "feature_names",
                    "feature_words",
                    "similarity_config",
                    "model",
                    "code_version",
                )
            }
            columns["created_at"] = as_utc(row.created_at)
        self._check_problems(info, cases)
        for r in reps:
            decode_array(r["data"], f"cached {r['kind']} of case {r['case_id']}", self.where)
        ids = {int(c["id"]) for c in cases}
        for e in log:
            if e["case_id"] is not None and int(e["case_id"]) not in ids:
                raise StoreError(
                    f"case base {name!r} is damaged: its maintenance log names case "
                    f"{e['case_id']}, which is not one of its cases",
                    self.where,
                )
        for c in cases:
            c["created_at"], c["updated_at"] = as_utc(c["created_at"]), as_utc(c["updated_at"])
        for e in log:
            e["at"] = as_utc(e["at"])
        return WholeCaseBase(info, columns, tuple(cases), tuple(reps), tuple(log))

    def _check_problems(self, info: CaseBaseInfo, cases: Sequence[Mapping[str, Any]]) -> None:
        """Every case's stored problem reads as :meth:`_stack_features` reads them (one shape,
        numbers, as many columns as the case base names), one at a time: a copy of a large case
        base holds its bytes, not a stacked float64 matrix beside them."""
        shapes: set[tuple[int, ...]] = set()
        for c in cases:
            a = decode_array(c["features"], f"features of case {c['id']}", self.where)
            if not np.issubdtype(a.dtype, np.floating):
                raise StoreError(
                    f"case base {info.name!r} is damaged: non-numeric features", self.where
                )
            shapes.add(a.shape)
        if len(shapes) > 1:
            raise StoreError(
                f"case base {info.name!r} is damaged: its cases have features of different "
                f"shapes ({', '.join(str(sh) for sh in sorted(shapes)[:3])})",
                self.where,
            )
        if shapes:
            (shape,) = shapes
            check_width(info, shape[-1] if shape else 1, self.where)

    def count_cases(self, name: str, *, include_inactive: bool = False) -> int:
        with self._read() as s:
            cb = self._row(s, name)
            q = select(func.count(CaseRow.id)).where(CaseRow.case_base_id == cb.id)
            if not include_inactive:
                q = q.where(CaseRow.active.is_(True))
            return int(s.scalar(q) or 0)

    # -- convenience writes (one transaction each)

    def add_cases(self, name: str, cases: Iterable[NewCase]) -> list[int]:
        with self.transaction() as tx:
            return tx.add_cases(tx.case_base(name), cases)

    # -- helpers

    @contextmanager
    def _dates(self, what: str) -> Iterator[None]:
        """Rows fetched inside carry dates; SQLite keeps them as text, and text that is not a
        date is damage (a StoreError saying ``what``), not a crash."""
        try:
            yield
        except ValueError as exc:
            raise StoreError(f"{what} ({exc})", self.where) from None

    def _row(self, s: Session, name: str) -> CaseBaseRow:
        with self._dates(f"case base {name!r} is damaged: its created_at is not a date"):
            row = s.scalar(select(CaseBaseRow).where(CaseBaseRow.name == name))
        if row is None:
            known = sorted(s.scalars(select(CaseBaseRow.name)).all())  # as list_case_bases
            hint = (
                f" (case bases here: {listed_names(known)})" if known else " (the store is empty)"
            )
            raise StoreError(f"no case base named {name!r}{hint}", self.where)
        return row

    def _info(self, s: Session, r: CaseBaseRow) -> CaseBaseInfo:
        rows = s.execute(
            select(CaseRow.label, func.count(CaseRow.id))
            .where(CaseRow.case_base_id == r.id, CaseRow.active.is_(True))
            .group_by(CaseRow.label)
        )
        # by code point on every backend (as list_case_bases sorts names)
        counts = dict(sorted((label, n) for label, n in rows))
        what = f"configuration of case base {r.name!r}"
        info = CaseBaseInfo(
            id=r.id,
            name=r.name,
            feature_config=read_json(r.feature_config, f"feature {what}", self.where),
            feature_hash=r.feature_hash,
            feature_names=tuple(
                read_json(r.feature_names, f"feature names of {r.name!r}", self.where)
            ),
            feature_words=tuple(
                read_json(r.feature_words, f"feature words of {r.name!r}", self.where)
            ),
            similarity=read_json(r.similarity_config, f"similarity {what}", self.where),
            code_version=r.code_version,
            created_at=as_utc(r.created_at),
            n_cases=int(sum(counts.values())),
            label_counts={str(k): int(v) for k, v in counts.items()},
            uid=r.uid,
            version=int(r.version),
            model=read_json(r.model, f"model of case base {r.name!r}", self.where),
        )
        for key, kind in (("feature_config", dict), ("similarity", dict), ("model", dict)):
            if not isinstance(getattr(info, key), kind):
                raise StoreError(f"the {key} of case base {r.name!r} is not an object", self.where)
        return info


class StoreTransaction:
    """Writes inside one :meth:`CaseStore.transaction` (commit on exit, rollback on error).

    Changes to cases name the case base they belong to (a :class:`CaseBaseInfo` read in this
    transaction); a case of another case base, or one no longer there, is refused.
    """

    def __init__(self, store: CaseStore, session: Session) -> None:
        self.store = store
        self.session = session
        self._changed: set[int] = set()
        self._created: set[int] = set()

    def _bump_versions(self) -> None:
        # a case base created in this transaction starts at version 1, whatever it holds
        changed = sorted(self._changed - self._created)
        if changed:
            self.session.execute(
                update(CaseBaseRow)
                .where(CaseBaseRow.id.in_(changed))
                .values(version=CaseBaseRow.version + 1)
            )
        self._changed.clear()

    def _lock(self, name: str) -> None:
        """Hold the case base ``name`` against every other writer of it until this transaction
        ends, as SQLite's ``BEGIN IMMEDIATE`` holds the whole file. PostgreSQL's writers run at
        READ COMMITTED and would otherwise both pass a check of what they read (two trims of
        one version both committed; two trains of one new name met a unique constraint). The
        lock is taken before the check, so the check sees what the other writer committed."""
        if self.session.get_bind().dialect.name != "postgresql":
            return
        key = int.from_bytes(hashlib.sha256(name.encode("utf-8")).digest()[:4], "big", signed=True)
        self.session.execute(
            select(func.pg_advisory_xact_lock(_PG_NAME_LOCKS, key))
        )  # waits at most the store's timeout (lock_timeout), then "locked"

    def case_base(self, name: str) -> CaseBaseInfo:
        self._lock(name)
        return self.store._info(self.session, self.store._row(self.session, name))

    def has_case_base(self, name: str) -> bool:
        """Whether ``name`` exists, as this transaction sees it."""
        q = select(CaseBaseRow.id).where(CaseBaseRow.name == name)
        return self.session.scalar(q) is not None

    def expect(self, name: str, uid: str, version: int | None = None) -> CaseBaseInfo:
        """The case base ``name``, checked to be the very one read earlier (same ``uid``):
        a case base replaced or deleted by another process since is refused, so nothing read
        from the old one is ever written into the new one. ``version``: the cases must also be
        exactly as read (a change decided on all of them, such as a trim, is refused with
        :class:`StaleCaseError` when another process changed any case since). Other writers of
        ``name`` wait until this transaction ends: what is checked here stays so."""
        self._lock(name)
        if not self.has_case_base(name):
            raise CaseBaseGone(
                f"case base {name!r} was deleted by another process since it was read; "
                "nothing was written",
                self.store.where,
            )
        info = self.case_base(name)
        if info.uid != uid:
            raise CaseBaseGone(
                f"case base {name!r} was replaced by another process since it was read; "
                "nothing was written (run the command again)",
                self.store.where,
            )
        if version is not None and info.version != version:
            raise StaleCaseError(
                f"case base {name!r} was changed by another process since it was read "
                f"(version {version}, now {info.version}); nothing was written (run the "
                "command again)",
                self.store.where,
            )
        return info

    def create_case_base(
        self,
        name: str,
        feature_config: Mapping[str, Any],
        feature_names: Sequence[str],
        feature_words: Sequence[str],
        similarity: Mapping[str, Any],
        *,
        model: Mapping[str, Any] | None = None,
        replace: bool = False,
        seen: Seen | None = None,
    ) -> CaseBaseInfo:
        """A new, empty case base with a new identity; ``replace`` drops an existing one of
        that name first (its cases and history go with it). ``seen``: what the caller read of
        it before (:class:`Seen`); the one there now must be that very one, as it was."""
        s = self.session
        check_case_base_name(name, self.store.where)
        self._lock(name)  # another process creating or replacing it meanwhile: after it
        with self.store._dates(f"case base {name!r} is damaged: its created_at is not a date"):
            old = s.scalar(select(CaseBaseRow).where(CaseBaseRow.name == name))
        if replace and seen is not None:
            self._check_seen(name, old, seen)
        if old is not None:
            if not replace:
                raise StoreError(
                    f"a case base named {name!r} already exists (choose another name or replace "
                    "it)",
                    self.store.where,
                )
            s.delete(old)
            s.flush()
        where = self.store.where
        for what, doc in (
            ("feature configuration", feature_config),
            ("feature names", feature_names),
            ("feature words", feature_words),
            ("similarity configuration", similarity),
            ("model", model or {}),
        ):
            check_document(doc, what, where)
        row = CaseBaseRow(
            uid=uuid.uuid4().hex,
            version=1,
            name=name,
            feature_config=canonical_json(dict(feature_config)),
            feature_hash=config_hash(feature_config),
            feature_names=json.dumps(list(feature_names), ensure_ascii=False),
            feature_words=json.dumps(list(feature_words), ensure_ascii=False),
            similarity_config=canonical_json(dict(similarity)),
            model=canonical_json(dict(model or {})),
            code_version=__version__,
        )
        s.add(row)
        s.flush()
        self._created.add(row.id)
        return self.store._info(s, row)

    def _check_seen(self, name: str, old: CaseBaseRow | None, seen: Seen) -> None:
        """Refuse to replace ``old`` (case base ``name`` now) unless it is what was ``seen``
        (one deleted meanwhile loses nothing: it is created anew)."""
        again = "nothing was written (run the command again to replace it as it is now)"
        if old is None:
            return
        if seen.uid is None:
            raise StaleCaseError(
                f"case base {name!r} was created by another process since this command "
                f"started; {again}",
                self.store.where,
            )
        if old.uid != seen.uid:
            raise StaleCaseError(
                f"case base {name!r} was replaced by another process since it was read; {again}",
                self.store.where,
            )
        if old.version != seen.version:
            raise StaleCaseError(
                f"case base {name!r} was changed by another process since it was read (version "
                f"{seen.version}, now {old.version}); {again}",
                self.store.where,
            )

    def copy_case_base(self, whole: WholeCaseBase, name: str) -> tuple[CaseBaseInfo, list[int]]:
        """Write the case base ``whole`` (read from this or another store by
        :meth:`CaseStore.read_whole`) here as ``name``, exactly: its configuration, model and
        version, every case (in use or trimmed) in order with its problem's bytes, its cached
        representations and its maintenance log with their dates. It gets an identity of its
        own (a copy is a case base of its own: a change to one is none to the other). Its cases
        keep their ids when no id of this store's was ever as high as its lowest (a store made
        for it, or of later cases): what commands print (``#12``) then reads the same. Else
        they are numbered after this store's, in the same order, and the log with them.
        Returns the copy's description and its cases' ids, in the order of ``whole.cases``. A
        case base of that name here already is refused (nothing written)."""
        s, where = self.session, self.store.where
        check_case_base_name(name, where)
        self._lock(name)
        if self.has_case_base(name):
            raise StoreError(
                f"a case base named {name!r} is here already: nothing was copied (name the "
                "copy with `name`)",
                where,
            )
        postgres = s.get_bind().dialect.name == "postgresql"
        if postgres:  # no other writer takes a case id until this commits (_highest_case_id)
            s.execute(sql_text("LOCK TABLE cases IN SHARE ROW EXCLUSIVE MODE"))
        ids = [int(c["id"]) for c in whole.cases]
        keep = not ids or ids[0] > self._highest_case_id(postgres)
        row = CaseBaseRow(uid=uuid.uuid4().hex, name=name, **whole.columns)
        s.add(row)
        s.flush()
        self._created.add(row.id)  # created here: its version is the one copied
        skip = ("case_base_id",) if keep else ("id", "case_base_id")
        rows = [
            # a case read from a store made before its clip's poses digest was kept has none;
            # a store made before has no place for it (a case of unknown poses there)
            {"poses": None, **{k: v for k, v in c.items() if k not in skip}, "case_base_id": row.id}
            for c in whole.cases
        ]
        if not self.store.keeps_poses:
            for r in rows:
                del r["poses"]
        moved = dict(zip(ids, self._insert_cases(rows), strict=True))
        if keep and ids and postgres:  # explicit ids do not move the sequence
            s.execute(
                sql_text("SELECT setval(pg_get_serial_sequence('cases', 'id'), :top)"),
                {"top": max(ids)},
            )
        s.add_all(
            RepresentationRow(case_id=moved[int(r["case_id"])], kind=r["kind"], data=r["data"])
            for r in whole.representations
        )
        s.flush()
        info = self.store._info(s, row)
        for e in whole.log:
            case_id = e["case_id"]
            self.log(
                info,
                e["action"],
                case_id=None if case_id is None else moved[int(case_id)],
                novelty=e["novelty"],
                benefit=e["benefit"],
                reason=e["reason"],
                at=e["at"],
            )
        s.flush()
        return info, [moved[i] for i in ids]

    def _highest_case_id(self, postgres: bool) -> int:
        """The highest case id this store ever gave (0: none): its cases' and the sequence's
        (SQLite's ``sqlite_sequence``, PostgreSQL's), which remember ids of cases gone."""
        s = self.session
        top = int(s.scalar(select(func.max(CaseRow.id))) or 0)
        if postgres:
            seq = s.scalar(
                sql_text(
                    "SELECT pg_sequence_last_value(pg_get_serial_sequence('cases', 'id')::regclass)"
                )
            )
        else:
            seq = s.scalar(sql_text("SELECT seq FROM sqlite_sequence WHERE name = 'cases'"))
        return max(top, int(seq or 0))

    def set_model(self, cb: CaseBaseInfo, model: Mapping[str, Any]) -> None:
        """Replace the fitted model of ``cb`` (what fit learned besides the cases)."""
        check_document(model, "model", self.store.where)
        self.session.execute(
            update(CaseBaseRow)
            .where(CaseBaseRow.id == cb.id)
            .values(model=canonical_json(dict(model)), code_version=__version__)
        )
        self._changed.add(cb.id)

    def add_cases(self, cb: CaseBaseInfo, cases: Iterable[NewCase]) -> list[int]:
        """Insert cases (streamed: an iterator is consumed inside this transaction, 500 at a
        time). A store made before the cases kept their clips' poses digests stores them
        without it."""
        ids: list[int] = []
        rows: list[dict[str, Any]] = []
        where = self.store.where
        for c in cases:
            if c.origin not in ORIGINS:
                raise StoreError(f"unknown case origin {c.origin!r}", where)
            if c.skeleton is not None:
                check_text(c.skeleton, "skeleton name", where, max_len=64)
            check_text(as_stored(c.source), "source", where)
            if c.subject is not None:
                check_text(c.subject, "subject", where)
            row = {
                "case_base_id": cb.id,
                "label": check_text(str(c.label), "label", where),
                "features": encode_array(np.asarray(c.features)),
                "source": as_stored(c.source),
                "frame_start": c.frame_start,
                "frame_end": c.frame_end,
                "subject": c.subject,
                "skeleton": c.skeleton,
                "origin": c.origin,
            }
            poses = None if c.poses is None else check_poses(c.poses, where)
            if self.store.keeps_poses:
                row["poses"] = poses
            rows.append(row)
            if len(rows) == 500:
                ids += self._insert_cases(rows)
                rows = []
        ids += self._insert_cases(rows)
        if ids:
            self._changed.add(cb.id)
        return ids

    def _insert_cases(self, rows: Sequence[Mapping[str, Any]]) -> list[int]:
        """Insert ``rows`` (dicts of the same columns) into the cases table: their ids, in
        order. Only the columns given are named (the ORM would name every column of today's
        schema, those a store made before lacks too)."""
        if not rows:
            return []
        table = cast(Table, CaseRow.__table__)
        if not self.session.get_bind().dialect.insert_returning:  # SQLite before 3.35
            conn = self.session.connection()
            return [_inserted_id(conn.execute(insert(table).values(**row))) for row in rows]
        q = insert(table).returning(table.c.id, sort_by_parameter_order=True)
        return [int(i) for i in self.session.execute(q, list(rows)).scalars()]

    def cases_from(
        self, cb: CaseBaseInfo, sources: Iterable[str]
    ) -> dict[tuple[str, int | None, int | None], int]:
        """The active cases of ``cb`` made from ``sources``, by (source, first frame, end
        frame): their ids (the first of each); each source as given (a file name that is not
        UTF-8 is looked for as it is stored, :func:`as_stored`)."""
        given: dict[str, set[str]] = {}
        for source in sources:
            given.setdefault(as_stored(source), set()).add(source)
        wanted = sorted(given)
        out: dict[tuple[str, int | None, int | None], int] = {}
        for i in range(0, len(wanted), 500):  # bounded IN lists
            # no ORDER BY: SQLite would rather read the cases in id order than use the index
            # on their sources (ix_cases_case_base_id_source); sorted here
            q = (
                select(CaseRow.id, CaseRow.source, CaseRow.frame_start, CaseRow.frame_end)
                .where(CaseRow.case_base_id == cb.id, CaseRow.active.is_(True))
                .where(CaseRow.source.in_(wanted[i : i + 500]))
            )
            for case_id, source, a, b in sorted(self.session.execute(q).all(), key=lambda r: r[0]):
                for name in given[source]:
                    out.setdefault((name, a, b), int(case_id))
        return out

    def case_of_poses(
        self, cb: CaseBaseInfo, poses: str, frames: tuple[int | None, int | None]
    ) -> int | None:
        """The id of the first active case of ``cb`` made of the clip of these ``poses`` (its
        digest) and ``frames`` (first frame, end frame; a case stored without its frames: of
        these poses alone), None when there is none: one stored without its digest, and every
        case of a store made before the digests were kept, is none."""
        if not self.store.keeps_poses:
            return None
        q = (
            select(CaseRow.id, CaseRow.frame_start, CaseRow.frame_end)
            .where(
                CaseRow.case_base_id == cb.id,
                CaseRow.active.is_(True),
                CaseRow.poses == check_poses(poses, self.store.where),
            )
            .order_by(CaseRow.id)
        )
        for case_id, a, b in self.session.execute(q):
            if a is None or b is None or (a, b) == tuple(frames):
                return int(case_id)
        return None

    def cases_framed(
        self, cb: CaseBaseInfo, frames: Iterable[tuple[int | None, int | None]]
    ) -> Iterator[list[SourcedCase]]:
        """The active cases of ``cb`` made of one of ``frames`` (first frame, end frame) of
        their source, or stored without their frames (before they were kept), by id, with
        their features and the digest of their clip's poses (None when not known), 500 at a
        time: the cases a clip of those frames may repeat, whatever its file is called (a copy
        of a stored clip's file under another name)."""
        wanted = set(frames)
        poses = CaseRow.poses if self.store.keeps_poses else sql_text("NULL")
        q = (
            select(CaseRow.id, CaseRow.source, CaseRow.frame_start, CaseRow.frame_end, poses)
            .where(CaseRow.case_base_id == cb.id, CaseRow.active.is_(True))
            .order_by(CaseRow.id)
        )
        found = [
            (int(case_id), source, a, b, digest)
            for case_id, source, a, b, digest in self.session.execute(q)
            if a is None or b is None or (a, b) in wanted
        ]
        for i in range(0, len(found), 500):  # bounded IN lists, and memory
            rows = found[i : i + 500]
            q2 = select(CaseRow.id, CaseRow.features).where(CaseRow.id.in_([r[0] for r in rows]))
            blobs = {int(k): v for k, v in self.session.execute(q2)}
            what = [f"features of case {r[0]}" for r in rows]
            arrays = decode_arrays([blobs[r[0]] for r in rows], what, self.store.where)
            yield [SourcedCase(*r[:4], a, r[4]) for r, a in zip(rows, arrays, strict=True)]

    def _case_row(self, cb: CaseBaseInfo, case_id: int, lock: bool) -> CaseRow:
        q = select(CaseRow).where(CaseRow.id == int(case_id))
        if lock:
            q = q.with_for_update()  # PostgreSQL: the row is ours until commit
        row = self.session.scalar(q)
        if row is None or row.case_base_id != cb.id:
            raise StaleCaseError(
                f"case {case_id} is no longer in case base {cb.name!r} (changed by another "
                "process since it was read); nothing was written",
                self.store.where,
            )
        return row

    def read_case(self, cb: CaseBaseInfo, case_id: int) -> StoredCase:
        """Case ``case_id`` of ``cb`` as it is now, locked against other writers until this
        transaction ends (read, change and write a case in one transaction)."""
        row = self._case_row(cb, case_id, lock=True)
        what = f"features of case {case_id}"
        return StoredCase(
            int(row.id),
            row.label,
            decode_array(row.features, what, self.store.where).astype(np.float64),
            bool(row.active),
        )

    def update_case(
        self,
        cb: CaseBaseInfo,
        case_id: int,
        *,
        features: np.ndarray | None = None,
        label: str | None = None,
        origin: str = "revised",
    ) -> None:
        """Change case ``case_id`` of ``cb`` (its cached representations are dropped)."""
        row = self._case_row(cb, case_id, lock=True)
        if features is not None:
            row.features = encode_array(np.asarray(features))
            # cached representations were computed from the old problem
            self.session.execute(
                delete(RepresentationRow).where(RepresentationRow.case_id == int(case_id))
            )
        if label is not None:
            row.label = check_text(str(label), "label", self.store.where)
        row.origin = origin
        self.session.flush()
        self._changed.add(cb.id)

    def deactivate_cases(self, cb: CaseBaseInfo, case_ids: Iterable[int]) -> int:
        """Mark cases of ``cb`` as trimmed (kept for the history, no longer used for
        retrieval); the number of cases that changed."""
        ids = [int(i) for i in case_ids]
        n = 0
        for start in range(0, len(ids), 500):
            chunk = ids[start : start + 500]
            result = self.session.execute(
                update(CaseRow)
                .where(
                    CaseRow.id.in_(chunk),
                    CaseRow.case_base_id == cb.id,
                    CaseRow.active.is_(True),
                )
                .values(active=False)
            )
            n += int(getattr(result, "rowcount", 0) or 0)
        if n:
            self._changed.add(cb.id)
        return n

    def put_representations(self, kind: str, reps: Mapping[int, np.ndarray]) -> None:
        """Cache per-case representations of ``kind`` (replacing older ones)."""
        ids = [int(i) for i in reps]
        for start in range(0, len(ids), 500):
            chunk = ids[start : start + 500]
            self.session.execute(
                delete(RepresentationRow).where(
                    RepresentationRow.case_id.in_(chunk), RepresentationRow.kind == kind
                )
            )
        self.session.add_all(
            RepresentationRow(case_id=i, kind=kind, data=encode_array(reps[i])) for i in ids
        )
        self.session.flush()

    def log(
        self,
        cb: CaseBaseInfo,
        action: str,
        *,
        case_id: int | None = None,
        novelty: float | None = None,
        benefit: float | None = None,
        reason: str = "",
        at: datetime | None = None,
    ) -> None:
        """One entry of ``cb``'s maintenance log (``at``: when; now unless given, as by a
        copy of a case base, whose log keeps its dates)."""
        self.session.add(
            MaintenanceRow(
                case_base_id=cb.id,
                case_id=case_id,
                action=action,
                novelty=None if novelty is None else float(novelty),
                benefit=None if benefit is None else float(benefit),
                reason=as_stored(reason),
                **({} if at is None else {"at": at}),
            )
        )


def open_store(
    url_or_path: str | Path,
    *,
    create: bool = False,
    readonly: bool = False,
    timeout_s: float = 30.0,
) -> CaseStore:
    """Open (and, if ``create``, initialise) a case base store.

    ``url_or_path``: a file path (SQLite) or any SQLAlchemy URL (``postgresql://...``).
    By default the store must exist: a missing SQLite file is a :class:`StoreError` naming it
    (nothing is created: a mistyped path to read leaves no empty file behind), an empty
    database an :class:`EmptyStore`. ``create=True``, to write: creates the file and the
    tables when there are none.
    ``readonly``: for commands that only read: nothing is written, and a case base file in a
    read-only folder can be read. Raises :class:`StoreError` naming the file for a corrupt,
    locked, foreign or other-version database, naming ``url_or_path`` for an empty one or one
    of another type (the commands say ``--db``).
    """
    check_to_open(url_or_path, timeout_s, create=create, readonly=readonly)
    engine, where = make_engine(url_or_path, timeout_s, readonly)
    store = CaseStore(engine, where, timeout_s, readonly)
    try:
        store._init_schema(create and not readonly)
    except BaseException:
        dispose(engine)
        raise
    return store


T = TypeVar("T")


def write_store(
    url_or_path: str | Path,
    action: Callable[[StoreTransaction], T],
    *,
    timeout_s: float = 30.0,
) -> T:
    """``action(tx)`` in one write transaction on the store at ``url_or_path``, creating the
    store when there is none.

    A SQLite file that does not exist yet is built under a temporary name beside it and appears
    under its own name only when complete: a failed first write leaves no file, a killed one
    only its hidden temporary, which the next write removes. If another process created the
    file meanwhile, ``action`` runs again, on that store.
    """
    check_url_or_path(url_or_path)
    file = sqlite_file(url_or_path)
    if file is not None:  # the temporaries of killed first writes (named for their process)
        remove_stale_temporaries(file.parent, file.name)
    if file is None or file.exists():
        store = open_store(url_or_path, create=True, timeout_s=timeout_s)
        try:
            with store.transaction() as tx:
                return action(tx)
        finally:
            store.close()
    tmp = file.with_name(f"{temporary_prefix(file.name)}{uuid.uuid4().hex[:8]}.new")
    try:
        try:
            store = open_store(tmp, create=True, timeout_s=timeout_s)
            try:
                with store.transaction() as tx:
                    result = action(tx)
            finally:
                store.close()
        except StoreError as exc:  # named for the file asked for, never its hidden temporary
            if exc.source != str(tmp):
                raise
            raise type(exc)(exc.message, file) from None
        try:
            os.link(tmp, file)  # appears whole, and never over a store made meanwhile
        except FileExistsError:
            refuse_dangling(file)  # else it "exists" for link() alone: this would loop
            return write_store(url_or_path, action, timeout_s=timeout_s)
        except OSError as exc:
            raise StoreError(f"cannot create the case base file ({exc.strerror})", file) from None
        return result
    finally:
        for suffix in ("", "-journal", "-wal", "-shm"):
            # a read-only file system refuses even to unlink what was never created
            with suppress(OSError):
                Path(f"{tmp}{suffix}").unlink(missing_ok=True)


def _rows_of(
    s: Session,
    table: type[CaseRow] | type[MaintenanceRow],
    case_base_id: int,
    lacking: Sequence[str] = (),
) -> list[dict[str, Any]]:
    """Every row of ``table`` (cases or the maintenance log) of one case base, whole, in the
    order they were written; ``lacking``: columns of today's schema the store has not (made
    before they were added)."""
    columns = [c for c in table.__table__.columns if c.name not in lacking]
    return [
        dict(r)
        for r in s.execute(
            select(*columns).where(table.case_base_id == case_base_id).order_by(table.id)
        ).mappings()
    ]
