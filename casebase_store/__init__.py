"""The case base store (SQLAlchemy; SQLite by default): the only package that speaks SQL."""

from .encoding import canonical_json, check_case_base_name, config_hash, decode_array, encode_array
from .engine import in_wal_mode
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
    check_url_or_path,
    same_store,
    shown_db,
    sqlite_file,
    store_files,
)
from .models import SCHEMA_VERSION
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
from .store import CaseStore, StoreTransaction, open_store, write_store
from .upgrade import missing_columns, missing_indexes, upgrade_store

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
