"""The case base store (SQLAlchemy; SQLite by default): the only package that speaks SQL."""

from .models import SCHEMA_VERSION
from .store import (
    EMPTY_DB,
    CaseArrays,
    CaseBaseInfo,
    CaseStore,
    EmptyStore,
    MaintenanceEntry,
    NewCase,
    StaleCaseError,
    StoredCase,
    StoreError,
    StoreTransaction,
    canonical_json,
    check_store_file,
    config_hash,
    decode_array,
    encode_array,
    open_store,
    sqlite_file,
    write_store,
)
from .upgrade import upgrade_store

__all__ = [
    "EMPTY_DB",
    "SCHEMA_VERSION",
    "CaseArrays",
    "CaseBaseInfo",
    "CaseStore",
    "EmptyStore",
    "MaintenanceEntry",
    "NewCase",
    "StaleCaseError",
    "StoreError",
    "StoreTransaction",
    "StoredCase",
    "canonical_json",
    "check_store_file",
    "config_hash",
    "decode_array",
    "encode_array",
    "open_store",
    "sqlite_file",
    "write_store",
    "upgrade_store",
]
