"""The case base store (SQLAlchemy; SQLite by default): the only package that speaks SQL.

What tells a store's place and checks it (:mod:`.locations`, :mod:`.journals`' ``prepare_write``),
its errors, encodings and records load with the package; the names of the modules that speak
SQL (the engine, the store, its tables and upgrades) are imported on first use, and with them
SQLAlchemy (about half a second), so that a command refuses a missing file or a ``--db`` that
is a folder before paying for them.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .encoding import canonical_json, check_case_base_name, config_hash, decode_array, encode_array
from .errors import (
    CaseBaseGone,
    EmptyStore,
    InterruptedWrite,
    NotADatabase,
    StaleCaseError,
    StoreError,
)
from .journals import prepare_write, roll_back_interrupted
from .locations import (
    EMPTY_DB,
    check_store_file,
    check_to_open,
    check_url_or_path,
    same_store,
    shown_db,
    sqlite_file,
    store_files,
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

if TYPE_CHECKING:
    from .engine import in_wal_mode
    from .models import SCHEMA_VERSION
    from .store import CaseStore, StoreTransaction, write_store
    from .upgrade import missing_columns, missing_indexes, upgrade_store

#: the names whose modules import SQLAlchemy, and those modules
_LAZY = {
    "in_wal_mode": ".engine",
    "SCHEMA_VERSION": ".models",
    "CaseStore": ".store",
    "StoreTransaction": ".store",
    "write_store": ".store",
    "missing_columns": ".upgrade",
    "missing_indexes": ".upgrade",
    "upgrade_store": ".upgrade",
}

__all__ = [
    "EMPTY_DB",
    "SCHEMA_VERSION",
    "CaseArrays",
    "CaseBaseGone",
    "CaseBaseInfo",
    "CaseStore",
    "EmptyStore",
    "InterruptedWrite",
    "MaintenanceEntry",
    "NewCase",
    "Seen",
    "SourcedCase",
    "StaleCaseError",
    "NotADatabase",
    "StoreError",
    "StoreTransaction",
    "StoredCase",
    "WholeCaseBase",
    "canonical_json",
    "check_case_base_name",
    "check_url_or_path",
    "check_store_file",
    "check_to_open",
    "check_width",
    "config_hash",
    "decode_array",
    "encode_array",
    "in_wal_mode",
    "open_store",
    "prepare_write",
    "roll_back_interrupted",
    "same_store",
    "shown_db",
    "sqlite_file",
    "store_files",
    "write_store",
    "missing_columns",
    "missing_indexes",
    "upgrade_store",
]


def open_store(
    url_or_path: str | Path,
    *,
    create: bool = False,
    readonly: bool = False,
    timeout_s: float = 30.0,
) -> CaseStore:
    """Open (and, if ``create``, initialise) a case base store:
    :func:`casebase_store.store.open_store`, whose refusals of a case base file (no such file,
    a folder, a missing folder: :func:`check_to_open`) come before SQLAlchemy is imported."""
    check_to_open(url_or_path, timeout_s, create=create, readonly=readonly)
    from .store import open_store as opened

    return opened(url_or_path, create=create, readonly=readonly, timeout_s=timeout_s)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
