"""The records the store's API takes and gives: a case to add, a case base's description, its
cases as arrays, one case, its maintenance log, the whole of it to copy."""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np

from .errors import StoreError


@dataclass(frozen=True)
class Seen:
    """What a command that replaces case base ``name`` saw of it before its long work (the
    training): its identity and version, or (``uid`` None) that there was none. The replace
    is refused when the case base is no longer so: cases another process added, trimmed or
    revised meanwhile, or a case base it created or replaced meanwhile, would be lost."""

    uid: str | None = None
    version: int | None = None


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
    """One case with its provenance, as
    :meth:`casebase_store.store.StoreTransaction.cases_framed` finds it; ``poses``: the digest
    of its clip's poses, None when not known (stored before it was kept, or in a store made
    before, which has no place for it)."""

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
    exactly (:meth:`casebase_store.store.CaseStore.read_whole`,
    :meth:`casebase_store.store.StoreTransaction.copy_case_base`): its description, its columns
    as stored (the configuration, names and model as their JSON text, byte for byte), every
    case, in use or trimmed, by id (its problem as its stored ``.npy`` bytes), the cached
    representations of its cases and its maintenance log, in order. Dates are UTC."""

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
