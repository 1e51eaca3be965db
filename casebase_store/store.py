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

The same code runs on every backend; what differs is kept to :func:`_make_engine` and the
per-dialect connect hooks. Values a stricter server would refuse (over-long names, NUL
characters in text) are refused here first, with the same error on every backend.
"""

from __future__ import annotations

import codecs
import hashlib
import io
import json
import os
import re
import sqlite3
import uuid
import weakref
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, TypeVar, cast
from urllib.parse import quote

import numpy as np
from sqlalchemy import (
    Engine,
    Table,
    create_engine,
    delete,
    event,
    func,
    insert,
    inspect,
    select,
    update,
)
from sqlalchemy import text as sql_text
from sqlalchemy.engine import URL, Connection, make_url
from sqlalchemy.exc import ArgumentError, DBAPIError, SQLAlchemyError
from sqlalchemy.orm import Session

from features.errors import ConfigError, PosecbrError
from features.fileio import (
    SQLITE_MAGIC,
    binary_kind,
    file_head,
    path_exists,
    remove_stale_temporaries,
    temporary_prefix,
)
from features.text import hide_passwords
from features.values import is_number
from features.version import __version__

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

ORIGINS = ("trained", "retained", "revised")

#: Serialises creating the tables when several clients open an empty PostgreSQL database at
#: once (``pg_advisory_xact_lock`` key; any constant unlikely to collide with other apps).
_PG_INIT_LOCK = 0x706F736563627231  # "posecbr1"
#: The first key of the per-case-base locks (``pg_advisory_xact_lock(int, int)``, a key space
#: apart from the one-key locks; the second key is from the case base's name).
_PG_NAME_LOCKS = 0x706F7365  # "pose"


class StoreError(PosecbrError):
    """The case base store cannot be opened, read or written (names the database)."""


class NotADatabase(StoreError):
    """A file that is no SQLite database; ``looks_like``: what it looks like it is (a pose
    file, a picture, ...), or None. The store does not know where its path came from: the
    command line says which option takes the case base (:meth:`taken_by`)."""

    def __init__(self, looks_like: str | None, where: str) -> None:
        self.looks_like = looks_like
        super().__init__(
            f"not a readable SQLite database ({looks_like or 'corrupt or not a database'})", where
        )

    def taken_by(self, option: str) -> NotADatabase:
        """The same refusal saying that ``option`` takes the case base file (the file given
        to it looks like something else: the two files swapped); itself when it looks like
        nothing known."""
        if self.looks_like is None or self.source is None:
            return self
        said = NotADatabase(f"{self.looks_like}: {option} takes the case base file", self.source)
        said.looks_like = self.looks_like
        return said


class EmptyStore(StoreError):
    """A database without a case base store in it yet (``open_store`` without ``create``): the
    first write creates one."""


class InterruptedWrite(StoreError):
    """A SQLite file whose last writer was killed inside a transaction: its ``-journal``
    holds what to undo, which a command that only reads does not write
    (:func:`roll_back_interrupted` does)."""


class CaseBaseGone(StoreError):
    """The case base read earlier was replaced or deleted by another process since: nothing
    was written into what took its place, and what was written into it is gone with it."""


class StaleCaseError(StoreError):
    """A case read earlier is no longer as it was (deleted, moved to another case base, or
    trimmed by another process): nothing was written; reload and decide again."""


@dataclass(frozen=True)
class Seen:
    """What a command that replaces case base ``name`` saw of it before its long work (the
    training): its identity and version, or (``uid`` None) that there was none. The replace
    is refused when the case base is no longer so: cases another process added, trimmed or
    revised meanwhile, or a case base it created or replaced meanwhile, would be lost."""

    uid: str | None = None
    version: int | None = None


# ----------------------------------------------------------------------------- arrays


def encode_array(array: np.ndarray) -> bytes:
    """``.npy`` bytes of ``array`` (no pickles: an array of Python objects is a
    :class:`StoreError`)."""
    values = np.asarray(array, order="C")  # a 0-d array stays 0-d
    if values.dtype.hasobject:
        raise StoreError(
            "an array of Python objects (dtype object) cannot be stored: "
            "give numbers or text (a numeric or str dtype)"
        )
    buf = io.BytesIO()
    np.save(buf, values, allow_pickle=False)
    return buf.getvalue()


def decode_array(data: bytes, what: str = "array", where: str = "") -> np.ndarray:
    """The array stored by :func:`encode_array`; a damaged blob is a :class:`StoreError`
    naming ``what`` (e.g. ``"features of case 12"``)."""
    try:
        array: np.ndarray = np.load(io.BytesIO(data), allow_pickle=False)
        return array
    except (ValueError, OSError, EOFError, TypeError) as exc:
        raise StoreError(f"the {what} is damaged ({exc})", where or None) from None


def decode_arrays(blobs: Sequence[bytes], what: Sequence[str], where: str = "") -> list[np.ndarray]:
    """:func:`decode_array` of each of ``blobs`` (``what``: each one's name for an error),
    as float64; a blob with the ``.npy`` header of the one before it (the cases of a case
    base share theirs) is read as a view of its bytes, its header not parsed again (parsing
    is most of :func:`numpy.load`'s time: 60 us a blob, 1.3 s of CPU for 20,000 cases)."""
    out: list[np.ndarray] = []
    head, like = b"", None
    for blob, name in zip(blobs, what, strict=True):
        if like is not None and len(blob) == len(head) + like.nbytes and blob.startswith(head):
            out.append(np.frombuffer(blob, like.dtype, offset=len(head)).reshape(like.shape))
            continue
        array = decode_array(blob, name, where)
        if not np.issubdtype(array.dtype, np.number) or np.iscomplexobj(array):
            raise StoreError(f"the {name} is damaged (not real numbers)", where or None)
        out.append(array.astype(np.float64, copy=False))
        if array.dtype == np.float64 and array.flags.c_contiguous and 0 < array.nbytes:
            head, like = blob[: len(blob) - array.nbytes], array
    return out


def _json(text: str, what: str, where: str) -> Any:
    try:
        return json.loads(text)
    except (TypeError, ValueError) as exc:
        raise StoreError(f"the {what} is not valid JSON ({exc})", where) from None


def config_hash(config: Mapping[str, Any]) -> str:
    """SHA-256 of the canonical JSON of a feature configuration."""
    return hashlib.sha256(canonical_json(config).encode("utf-8")).hexdigest()


def canonical_json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=False)


def _utc(value: datetime) -> datetime:
    """Timezone-aware UTC: SQLite hands stored times back naive (they were written in UTC),
    PostgreSQL aware in the session's zone; callers get the same value from both."""
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


#: The longest case base name a store holds (its column's width on every backend)
NAME_MAX = 200


def listed_names(names: Sequence[str]) -> str:
    """Case base names as a list in a message: each as it is, or quoted when it would not
    read as itself there (spaces around it, a comma, a character that does not print):
    "squats " among others was "a, b, squats )"."""
    return ", ".join(
        repr(n) if n != n.strip() or "," in n or not n.isprintable() else n for n in names
    )


def check_case_base_name(name: str, where: str) -> str:
    """``name`` when a store can hold it as a case base's name (text of at most
    :data:`NAME_MAX` characters, not blank, no NUL, UTF-8); else a :class:`StoreError` naming
    ``where``: for a command to refuse it before any work, as the write would."""
    _check_text(name, "case base name", where, max_len=NAME_MAX)
    if not name.strip():
        raise StoreError("the case base name is empty", where)
    return name


def _check_text(value: str, what: str, where: str, max_len: int | None = None) -> str:
    # PostgreSQL refuses NUL in text and enforces VARCHAR lengths, SQLite stores both; refuse
    # them on every backend so a store behaves the same wherever it lives
    if not isinstance(value, str):
        raise StoreError(f"the {what} must be text, got {value!r}", where)
    if "\x00" in value:
        raise StoreError(f"{what} {value!r} contains a NUL character", where)
    _check_utf8(value, what, where)
    if max_len is not None and len(value) > max_len:
        raise StoreError(
            f"{what} is {len(value)} characters long (at most {max_len}): {value[:40]!r}...",
            where,
        )
    return value


def _inserted_id(result: Any) -> int:
    """The id of the one row an insert without RETURNING added."""
    key = result.inserted_primary_key
    assert key is not None  # an insert's result has one
    return int(key[0])


def _check_poses(value: str, where: str) -> str:
    """A case's poses digest: a SHA-256 as 64 hexadecimal digits (what compares them)."""
    if not isinstance(value, str) or not re.fullmatch(r"[0-9a-f]{64}", value):
        raise StoreError(f"a poses digest is 64 hexadecimal digits, got {value!r}", where)
    return value


def _check_utf8(value: str, what: str, where: str, within: str = "") -> None:
    """Refuse text that has no UTF-8 form: a name read from a file or folder whose bytes are
    not UTF-8 (Python keeps them as lone surrogates), which no database driver can send.
    ``within``: the document that holds it."""
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        said = f"the {within} holds {value!r}, which" if within else f"{what} {value!r}"
        raise StoreError(
            f"{said} is not UTF-8 text (a name in another encoding, from a file or folder"
            " name?): rename it",
            where,
        ) from None


def _check_document(doc: Any, what: str, where: str) -> Any:
    """``doc`` (JSON-ready), every string in it checked by :func:`_check_utf8`."""
    stack = [doc]
    while stack:
        item = stack.pop()
        if isinstance(item, str):
            _check_utf8(item, "text", where, within=what)
        elif isinstance(item, Mapping):
            stack.extend(item.keys())
            stack.extend(item.values())
        elif isinstance(item, list | tuple):
            stack.extend(item)
    return doc


def _as_stored(text: str) -> str:
    """Provenance text (a clip's file name, a log entry's reason) as it is stored: bytes of a
    file name that are not UTF-8 written as ``\\xNN`` (the name stays readable and the same
    name is always stored alike)."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    return text


# ----------------------------------------------------------------------------- records


@dataclass(frozen=True)
class NewCase:
    """A case to add: problem ``features`` (any shape, same for the whole case base) + label;
    ``poses``: a digest of the poses of the clip it was made of (what tells a copy of the clip
    under another file name), None when not known."""

    label: str
    features: np.ndarray
    source: str = ""
    frame_start: int | None = None
    frame_end: int | None = None
    subject: str | None = None
    skeleton: str | None = None
    origin: str = "trained"
    poses: str | None = None


@dataclass(frozen=True)
class CaseBaseInfo:
    """What a case base is: its configuration, fitted model and size.

    uid: the case base's identity (a replaced case base of the same name gets a new one);
    version: grows by one with every committed change to its cases.
    """

    id: int
    name: str
    # the columns, the measure (its learned weights) and the model are left out of the repr:
    # half a megabyte of it for a case base of 80 cases (``load_classifier``'s result printed)
    feature_config: dict[str, Any] = field(repr=False)
    feature_hash: str
    feature_names: tuple[str, ...] = field(repr=False)
    feature_words: tuple[str, ...] = field(repr=False)
    similarity: dict[str, Any] = field(repr=False)
    code_version: str
    created_at: datetime
    n_cases: int
    label_counts: dict[str, int] = field(default_factory=dict)
    uid: str = ""
    version: int = 1
    model: dict[str, Any] = field(default_factory=dict, repr=False)


@dataclass(frozen=True)
class StoredCase:
    """One case as a transaction reads it (to change it)."""

    id: int
    label: str
    features: np.ndarray
    active: bool


@dataclass(frozen=True)
class SourcedCase:
    """One case with its provenance, as :meth:`StoreTransaction.cases_framed` finds it;
    ``poses``: the digest of its clip's poses, None when not known (stored before it was kept,
    or in a store made before, which has no place for it)."""

    id: int
    source: str
    frame_start: int | None
    frame_end: int | None
    features: np.ndarray
    poses: str | None = None


@dataclass(frozen=True)
class CaseArrays:
    """All (active) cases of a case base as arrays; row ``i`` of each is case ``ids[i]``.

    features: ``(n_cases, *problem_shape)`` float64.
    """

    ids: np.ndarray  # (n,) int64
    labels: np.ndarray  # (n,) str (object)
    features: np.ndarray
    sources: tuple[str, ...]
    subjects: tuple[str | None, ...]
    origins: tuple[str, ...]
    frame_ranges: tuple[tuple[int | None, int | None], ...]
    #: (n,) bool: the case takes part (False: trimmed; only with ``include_inactive``)
    active: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))


@dataclass(frozen=True)
class MaintenanceEntry:
    id: int
    action: str
    case_id: int | None
    novelty: float | None
    benefit: float | None
    reason: str
    at: datetime


@dataclass(frozen=True)
class WholeCaseBase:
    """Everything one case base is, as its store holds it, for copying it to another store
    exactly (:meth:`CaseStore.read_whole`, :meth:`StoreTransaction.copy_case_base`): its
    description, its columns as stored (the configuration, names and model as their JSON
    text, byte for byte), every case, in use or trimmed, by id (its problem as its stored
    ``.npy`` bytes), the cached representations of its cases and its maintenance log, in
    order. Dates are UTC."""

    info: CaseBaseInfo
    columns: dict[str, Any]
    cases: tuple[dict[str, Any], ...]
    representations: tuple[dict[str, Any], ...]
    log: tuple[dict[str, Any], ...]


def check_width(info: CaseBaseInfo, width: int, where: str) -> None:
    """The case base names as many feature columns as its cases have (``width``), or is
    damaged: a StoreError naming both."""
    if len(info.feature_names) and width != len(info.feature_names):
        raise StoreError(
            f"case base {info.name!r} is damaged: its cases have {width} "
            f"feature columns but the case base names {len(info.feature_names)}",
            where,
        )


# ----------------------------------------------------------------------------- engine


def _is_sqlite(engine: Engine) -> bool:
    return engine.dialect.name == "sqlite"


#: the start of a database URL of one of SQLAlchemy's dialects (``postgresql+psycopg:``)
#: without the ``://`` before its server (a "/" or the ":" missing): a URL mistyped, not a
#: file's name
_MISTYPED_URL = re.compile(
    r"(?i)(?:postgres(?:ql)?|mysql|mariadb|oracle|mssql|sqlite)(?:\+\w+)?(?::(?!//)|//)"
)
#: the user and password after it (``me:PASSWORD@host``), to hide the password
_USER_PASSWORD = re.compile(r"^(/*[^:@/]*:)[^@]*@")
#: a database URL with no scheme at all (``me:PASSWORD@host/db``): a user, a colon and a
#: password before an "@", where a path's first folder is seldom so named
_SCHEMELESS_URL = re.compile(r"[^:@/\\]+:[^@]*@")


def sqlite_file(url_or_path: str | Path) -> Path | None:
    """The file of a SQLite path or ``sqlite:///`` URL (None: another backend or in memory).
    A database URL missing the ``//`` before its server (``postgresql:/me:PW@host/db``) that
    is no file is refused as a mistyped URL, its password hidden: taken for a file's name, it
    was printed whole in the refusal (or a file of that name made). So is one with no scheme
    at all (``me:PW@host/db``)."""
    text = str(url_or_path)
    if "://" not in text:
        typo = _MISTYPED_URL.match(text)
        if typo and not os.path.lexists(text):
            scheme = typo[0].rstrip(":/")
            raise StoreError(
                f'not a database URL ("://" goes after {scheme!r}) nor a case base file',
                typo[0] + _USER_PASSWORD.sub(r"\1***@", text[typo.end() :]),
            )
        if _SCHEMELESS_URL.match(text) and not os.path.lexists(text):
            raise StoreError(
                "looks like a database URL without its scheme (postgresql+psycopg://...),"
                " and is no case base file",
                _USER_PASSWORD.sub(r"\1***@", text),
            )
        return Path(text)
    try:
        url = make_url(text)
    except (ArgumentError, ValueError):  # ValueError: a port that is not a number
        return None
    if url.get_backend_name() != "sqlite" or url.database in (None, "", ":memory:"):
        return None
    db = str(url.database)
    return Path(db[len("file:") :].split("?")[0]) if db.startswith("file:") else Path(db)


def store_files(url_or_path: str | Path) -> list[Path]:
    """The files of a SQLite store (path or ``sqlite:///`` URL) on this machine: the database
    and its journals (``-journal``, ``-wal``, ``-shm``); none for another backend. What an
    output of a command that reads the store must never be: ``--db sqlite:///cb.mp4
    --overlay cb.mp4`` compared the URL's text with the output and missed it."""
    file = sqlite_file(url_or_path)
    if file is None:
        return []
    return [file.with_name(file.name + j) for j in ("", "-journal", "-wal", "-shm")]


def same_store(a: str | Path, b: str | Path) -> bool:
    """Whether two ``--db`` values name one store: one SQLite file (the same file, however
    named: a link, ``./``, a ``sqlite:///`` URL), or one database of one server (backend,
    host, port and database alike; the driver and the user may differ)."""
    fa, fb = sqlite_file(a), sqlite_file(b)
    if fa is not None or fb is not None:
        if fa is None or fb is None:
            return False
        try:
            return os.path.samefile(fa, fb)
        except OSError:  # one of them not there (yet)
            return fa.resolve() == fb.resolve()
    try:
        ua, ub = make_url(str(a)), make_url(str(b))
    except (ArgumentError, ValueError):
        return str(a) == str(b)

    def key(u: URL) -> tuple[Any, ...]:
        return (u.get_backend_name(), (u.host or "").lower(), u.port, u.database)

    return key(ua) == key(ub)


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


#: The first bytes of a rollback journal that holds a transaction (SQLite zeroes or deletes
#: it when the transaction ends)
_JOURNAL_MAGIC = bytes.fromhex("d9d505f920a163d7")

_INTERRUPTED = (
    "its last change was interrupted (the process writing it was killed): {journal} holds what "
    "to undo"
)


def _journal(path: Path) -> Path:
    """The rollback journal of the database file ``path``: beside the file a symbolic link
    leads to, where SQLite writes it."""
    real = path.resolve()
    return real.with_name(real.name + "-journal")


def _hot_journal(path: Path) -> bool:
    """Whether ``path``'s rollback journal holds a transaction (left by a killed writer when no
    process is writing it now)."""
    try:
        if not _journal(path).is_file():  # a pipe would make open() wait for a writer
            return False
        with open(_journal(path), "rb") as fh:
            return fh.read(len(_JOURNAL_MAGIC)) == _JOURNAL_MAGIC
    except OSError:
        return False


def roll_back_interrupted(url_or_path: str | Path, *, timeout_s: float = 30.0) -> bool:
    """Undo the transaction a killed writer left in a SQLite file (its ``-journal``), as
    SQLite does when a connection that may write opens it: for a command that will write,
    which reads the store read-only first (a read-only connection cannot undo it and fails
    with :class:`InterruptedWrite`). Returns whether one was undone; nothing happens to a
    file without such a journal, another backend, or a transaction another process is still
    writing (SQLite undoes only a journal whose writer is gone)."""
    file = sqlite_file(url_or_path)
    if file is None:
        return False
    check_name_length(file)
    if not file.is_file() or not _hot_journal(file):
        return False
    _check_timeout(timeout_s)
    for readonly in (True, False):  # first a look that writes nothing: is it to be undone?
        engine, where = _make_engine(file, timeout_s, readonly)
        try:
            with engine.connect() as conn:
                conn.exec_driver_sql("SELECT count(*) FROM sqlite_master").scalar()
            return not readonly
        except DBAPIError as exc:
            code = getattr(exc.orig, "sqlite_errorcode", None)
            if not (readonly and code == _SQLITE_READONLY_ROLLBACK):
                raise _translate(exc, where, timeout_s) from None
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
    if not _is_sqlite(engine):
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


def check_writable(file: Path) -> None:
    """Refuse, in one line, an existing SQLite file this process cannot write: the file
    read-only, or its folder (where SQLite writes its journal, and the ``-wal`` and ``-shm``
    files of a file still in WAL mode)."""
    folder = file.resolve().parent
    if not os.access(folder, os.W_OK | os.X_OK):
        raise StoreError(
            f"cannot write the case base file: the folder {folder} is read-only (SQLite "
            "writes its journal beside it)",
            file,
        )
    if not os.access(file, os.W_OK):
        raise StoreError("cannot write the case base file: it is read-only", file)


#: SQLite's extended result code for a read-only connection that met such a journal
_SQLITE_READONLY_ROLLBACK = 776
#: SQLite's extended result code for a write(2) that failed (EIO; EFBIG: RLIMIT_FSIZE)
_SQLITE_IOERR_WRITE = 778
#: SQLite's result code for a write the disk had no room for (ENOSPC), of the file or journal
_SQLITE_FULL = 13
#: SQLite's extended result code for a write to a file deleted or renamed while open
_SQLITE_READONLY_DBMOVED = 1032


def _make_engine(url_or_path: str | Path, timeout_s: float, readonly: bool) -> tuple[Engine, str]:
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
    if _is_sqlite(engine):
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


def _hide_password(text: str) -> str:
    """``text`` with the password of a URL in it replaced by ``***``, as SQLAlchemy shows a URL
    it could read, for a URL it could not (as every message shows one)."""
    return hide_passwords(text)


def _shown_url(url: URL) -> str:
    """``url`` as the user is shown it: without its password, whether given before the host
    (``me:PASSWORD@host``) or as libpq's ``?password=`` parameter."""
    hidden = {key: "***" for key in url.query if key.lower() == "password"}
    text = url.update_query_dict(hidden).render_as_string(hide_password=True)
    return text.replace("=%2A%2A%2A", "=***")


def shown_db(url_or_path: str | Path) -> str:
    """How to name a store to the user: a case base file as given, a database URL without its
    password (``postgresql://me:***@host/db``), as :class:`StoreError` names them."""
    text = str(url_or_path)
    if "://" not in text:
        return text
    try:
        return _shown_url(make_url(text))
    except (ArgumentError, ValueError):
        return _hide_password(text)


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
            raise StoreError(f"not a database URL ({exc})", _hide_password(text)) from None
        except ValueError:  # SQLAlchemy reads the port with int()
            raise StoreError(
                "not a database URL (its port is not a number)", _hide_password(text)
            ) from None
        if url.get_backend_name() == "sqlite":  # no file: in memory (sqlite://, :memory:)
            raise StoreError(
                "an in-memory SQLite database keeps nothing once the command ends: name a "
                "case base file (a path, or sqlite:///FILE)",
                text,
            )
        return url, _shown_url(url)
    check_store_file(file)
    if readonly:
        return _sqlite_readonly_url(file), str(file)
    # built, not parsed: a path's "?" or "%20" is part of the file name, not a URL's query or
    # escape ("a?b.sqlite" as text made SQLAlchemy open a file "a")
    return URL.create("sqlite", database=str(file)), str(file)


def check_name_length(file: Path) -> None:
    """Refuse a case base file name too long for the file system with its journal's ending
    (SQLite writes ``NAME-journal``): before anything asks whether the file exists, which for
    a name longer than the file system allows is an OSError, not "no"."""
    try:
        allowed = os.pathconf(file.parent, "PC_NAME_MAX")
    except (OSError, ValueError):
        allowed = 255
    if len(os.fsencode(file.name + "-journal")) > allowed:
        raise StoreError(
            f"the file name is too long: {len(os.fsencode(file.name))} bytes, at most "
            f"{allowed - len('-journal')} (SQLite writes a journal named NAME-journal beside it)",
            file,
        )


def check_store_file(file: Path) -> None:
    """Refuse a case base file that could not be written: a folder, a device, pipe or socket,
    one in a folder that does not exist, or a name too long for its journal beside it (SQLite
    writes ``NAME-journal``)."""
    if not file.parent.exists():  # named with the file asked for, as every refusal of it
        raise StoreError(f"folder does not exist ({file.parent})", file)
    check_name_length(file)
    if file.is_dir():
        raise StoreError("is a folder, not a case base file", file)
    if file.exists() and not file.is_file():  # SQLite would wait on a pipe for a writer
        raise StoreError("is not a case base file: a device, pipe or socket", file)
    for side in (Path(f"{file}{j}") for j in ("-journal", "-wal", "-shm")):
        if side.exists() and not side.is_file():  # SQLite opens these too
            raise StoreError(
                f"{side.name} beside it, where SQLite keeps its journal, is not a file (a "
                "folder, device, pipe or socket): remove or rename it",
                file,
            )
    _refuse_dangling(file)


def _refuse_dangling(file: Path) -> None:
    """A symbolic link to a file that does not exist is refused: a new store appears under its
    name only when no file of that name exists (never over one made meanwhile), and the link
    is one for good."""
    if file.is_symlink() and not file.exists():
        raise StoreError(
            f"is a symbolic link to {os.readlink(file)}, which does not exist: create the case"
            " base there, or name another file",
            file,
        )


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
        raise _translate(exc, where, timeout_s) from None
    try:
        guard.execute("SELECT count(*) FROM sqlite_master").fetchone()
    except sqlite3.Error as exc:
        guard.close()
        raise _translate(exc, where, timeout_s) from None
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
    if not _is_sqlite(engine) or not in_wal_mode(Path(str(engine.url.database))):
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
    folder = _journal(Path(where)).parent  # where the journal is, and would be removed
    if code == _SQLITE_READONLY_ROLLBACK and not os.access(folder, os.W_OK | os.X_OK):
        return InterruptedWrite(
            f"{_INTERRUPTED.format(journal=_journal(Path(where)))}; its folder cannot be "
            "written, so it cannot be rolled back here: copy both files to a folder that "
            "can be written and run `posecbr casebase upgrade --db FILE` there",
            where,
        )
    if code == _SQLITE_READONLY_ROLLBACK and not os.access(where, os.W_OK):
        # the file itself read-only (its folder writable): no command here can undo it
        return InterruptedWrite(
            f"{_INTERRUPTED.format(journal=_journal(Path(where)))}; the file cannot be "
            "written, so it cannot be rolled back here: make it writable, or copy both files "
            "to where they can be written, and run `posecbr casebase upgrade --db FILE` there",
            where,
        )
    if code == _SQLITE_READONLY_ROLLBACK:  # before "readonly" below: the file can be written
        return InterruptedWrite(
            f"{_INTERRUPTED.format(journal=_journal(Path(where)))}, and a command "
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


def _translate(exc: BaseException, where: str, timeout_s: float) -> StoreError:
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


# ----------------------------------------------------------------------------- store


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
            raise _translate(exc, self.where, self.timeout_s) from None

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
                        db = "FILE" if _is_sqlite(self.engine) else "URL"  # not a file
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
                    r.id, r.action, r.case_id, r.novelty, r.benefit, r.reason, _utc(r.at)
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
            columns["created_at"] = _utc(row.created_at)
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
            c["created_at"], c["updated_at"] = _utc(c["created_at"]), _utc(c["updated_at"])
        for e in log:
            e["at"] = _utc(e["at"])
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
            feature_config=_json(r.feature_config, f"feature {what}", self.where),
            feature_hash=r.feature_hash,
            feature_names=tuple(_json(r.feature_names, f"feature names of {r.name!r}", self.where)),
            feature_words=tuple(_json(r.feature_words, f"feature words of {r.name!r}", self.where)),
            similarity=_json(r.similarity_config, f"similarity {what}", self.where),
            code_version=r.code_version,
            created_at=_utc(r.created_at),
            n_cases=int(sum(counts.values())),
            label_counts={str(k): int(v) for k, v in counts.items()},
            uid=r.uid,
            version=int(r.version),
            model=_json(r.model, f"model of case base {r.name!r}", self.where),
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
            _check_document(doc, what, where)
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
        _check_document(model, "model", self.store.where)
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
                _check_text(c.skeleton, "skeleton name", where, max_len=64)
            _check_text(_as_stored(c.source), "source", where)
            if c.subject is not None:
                _check_text(c.subject, "subject", where)
            row = {
                "case_base_id": cb.id,
                "label": _check_text(str(c.label), "label", where),
                "features": encode_array(np.asarray(c.features)),
                "source": _as_stored(c.source),
                "frame_start": c.frame_start,
                "frame_end": c.frame_end,
                "subject": c.subject,
                "skeleton": c.skeleton,
                "origin": c.origin,
            }
            poses = None if c.poses is None else _check_poses(c.poses, where)
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
        UTF-8 is looked for as it is stored, :func:`_as_stored`)."""
        given: dict[str, set[str]] = {}
        for source in sources:
            given.setdefault(_as_stored(source), set()).add(source)
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
                CaseRow.poses == _check_poses(poses, self.store.where),
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
            row.label = _check_text(str(label), "label", self.store.where)
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
                reason=_as_stored(reason),
                **({} if at is None else {"at": at}),
            )
        )


EMPTY_DB = "is empty: name a case base file (SQLite) or a SQLAlchemy URL"
"""The error of an empty case base path (``url_or_path``; the commands' ``--db``)."""


def _check_timeout(timeout_s: Any) -> None:
    """Refuse a ``timeout_s`` that is not a finite number of seconds >= 0 (SQLite turns
    its busy timeout off for a negative one; a bool is no time)."""
    if not (is_number(timeout_s) and 0.0 <= float(timeout_s) < float("inf")):
        raise ConfigError(f"must be a number of seconds >= 0, got {timeout_s!r}", "timeout_s")


def check_url_or_path(url_or_path: Any, name: str = "url_or_path") -> None:
    """Refuse, naming ``name`` (the caller's argument), what is no file path or URL, or an
    empty one: ``open_store(5)`` made a file "5", and ``write_store(None, ...)`` (so
    ``cbr.training.train(None, ...)``, an unset variable) a case base file "None"."""
    if not isinstance(url_or_path, str | os.PathLike):
        raise StoreError(
            f"a case base is a file path or a SQLAlchemy URL, got {url_or_path!r}", name
        )
    if not str(url_or_path).strip():
        raise StoreError(EMPTY_DB, name)


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
    check_url_or_path(url_or_path)
    _check_timeout(timeout_s)
    file = sqlite_file(url_or_path)
    if file is not None:
        check_name_length(file)
    if file is not None and (readonly or not create) and not path_exists(file):
        raise StoreError("no such case base file", file)
    engine, where = _make_engine(url_or_path, timeout_s, readonly)
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
            _refuse_dangling(file)  # else it "exists" for link() alone: this would loop
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
