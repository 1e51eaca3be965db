"""Where a store is: a SQLite file (its journals beside it) or a database URL, told apart,
checked before anything opens it, compared, and named without its password."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from features.errors import ConfigError
from features.fileio import path_exists
from features.text import hide_passwords
from features.values import is_number

from .errors import StoreError

if TYPE_CHECKING:
    from sqlalchemy.engine import URL

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
    url = _parsed_url(text)
    if url is None:
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
    ua, ub = _parsed_url(str(a)), _parsed_url(str(b))
    if ua is None or ub is None:
        return str(a) == str(b)

    def key(u: URL) -> tuple[Any, ...]:
        return (u.get_backend_name(), (u.host or "").lower(), u.port, u.database)

    return key(ua) == key(ub)


def journal_file(path: Path) -> Path:
    """The rollback journal of the database file ``path``: beside the file a symbolic link
    leads to, where SQLite writes it."""
    real = path.resolve()
    return real.with_name(real.name + "-journal")


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


def _hide_password(text: str) -> str:
    """``text`` with the password of a URL in it replaced by ``***``, as SQLAlchemy shows a URL
    it could read, for a URL it could not (as every message shows one)."""
    return hide_passwords(text)


def shown_url(url: URL) -> str:
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
    url = _parsed_url(text)
    return _hide_password(text) if url is None else shown_url(url)


def _parsed_url(text: str) -> URL | None:
    """``text`` read as a database URL by SQLAlchemy, imported here, when a URL is met: a
    case base file's path is told without it (a command's refusals come before it)."""
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import ArgumentError

    try:
        return make_url(text)
    except (ArgumentError, ValueError):  # ValueError: a port that is not a number
        return None


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
    refuse_dangling(file)


def refuse_dangling(file: Path) -> None:
    """A symbolic link to a file that does not exist is refused: a new store appears under its
    name only when no file of that name exists (never over one made meanwhile), and the link
    is one for good."""
    if file.is_symlink() and not file.exists():
        raise StoreError(
            f"is a symbolic link to {os.readlink(file)}, which does not exist: create the case"
            " base there, or name another file",
            file,
        )


EMPTY_DB = "is empty: name a case base file (SQLite) or a SQLAlchemy URL"
"""The error of an empty case base path (``url_or_path``; the commands' ``--db``)."""


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


def check_timeout(timeout_s: Any) -> None:
    """Refuse a ``timeout_s`` that is not a finite number of seconds >= 0 (SQLite turns
    its busy timeout off for a negative one; a bool is no time)."""
    if not (is_number(timeout_s) and 0.0 <= float(timeout_s) < float("inf")):
        raise ConfigError(f"must be a number of seconds >= 0, got {timeout_s!r}", "timeout_s")


def check_to_open(
    url_or_path: Any, timeout_s: Any = 30.0, *, create: bool = False, readonly: bool = False
) -> Path | None:
    """What :func:`casebase_store.store.open_store` refuses before it connects, told without
    SQLAlchemy for a case base file: no path or URL (:func:`check_url_or_path`), a
    ``timeout_s`` that is no time, a file name too long, a file that does not exist (to read,
    or to open without ``create``), and what :func:`check_store_file` refuses (a folder, a
    device, a missing folder). The SQLite file; None for a database URL of another backend."""
    check_url_or_path(url_or_path)
    check_timeout(timeout_s)
    file = sqlite_file(url_or_path)
    if file is None:
        return None
    check_name_length(file)
    if (readonly or not create) and not path_exists(file):
        raise StoreError("no such case base file", file)
    check_store_file(file)
    return file
