"""The judges stored with a fitted model: those calibrated when it is stored (the margin judges
from one held-out scan of its case base), written as records by name and read back."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from features.errors import DataError

from .casebase import CaseBase
from .unknown_held_out import held_out_activities
from .unknown_judges import (
    ActivityMargin,
    Familiarity,
    Margin,
    MarginDistance,
    SpreadFar,
    SpreadMargin,
)
from .unknown_records import Calibrated, added_fields

STORED: dict[str, type[Calibrated]] = {
    "margin": Margin,
    "margin-distance": MarginDistance,
    "activities": Familiarity,
    "activity-margin": ActivityMargin,
    "spread-margin": SpreadMargin,
    "spread-far": SpreadFar,
}
"""The judges calibrated on the case base, by name: calibrated when a model is stored
(:func:`calibrate_judges`) and stored with it. (``held-out`` reads the classifier's novelty
calibration, already stored.)"""


AT_FIT = ("margin", "margin-distance", "activity-margin", "spread-margin", "spread-far")
"""The judges calibrated when a model is stored: the margins, from one held-out scan of the
case base for at most :data:`cbr.unknown_held_out.MARGIN_SAMPLE` cases (grows linearly with the
case base); ``spread-margin``'s choice of power, rate and prior adds a fraction of a second of
CPU to it (:func:`cbr.unknown_weights.inner_grid`); ``spread-far`` takes ``spread-margin``'s and
the held-out cases' nearest distances (:meth:`SpreadFar.bounding`). ``activities`` measures
every case against every other (grows with the square: seconds on thousands of cases, hours on
the 100,000 of a 50,000-clip training set) and is calibrated when asked for, as before
(docs/measurements.md, "Figures behind the code's rules: A model's judges calibrated when
stored")."""


def calibrate_judges(cb: CaseBase, names: Sequence[str] = tuple(STORED)) -> dict[str, Calibrated]:
    """The judges ``names`` (of :data:`STORED`) calibrated on ``cb``, by name; the margin
    judges share one held-out scan of the case base. A judge the case base cannot calibrate
    (fewer than three activities, no activity with cases apart) is left out: ``segment``
    then says why, as it did before judges were stored."""
    three = len(set(np.asarray(cb.labels).astype(str).tolist())) >= 3
    held = held_out_activities(cb) if three and set(AT_FIT) & set(names) else None
    out: dict[str, Calibrated] = {}
    for name in names:
        inner = out.get("spread-margin")
        if name == "spread-far" and isinstance(inner, SpreadMargin) and held is not None:
            out[name] = SpreadFar.bounding(inner, held)  # one choice of the spread, not two
            continue
        try:
            out[name] = STORED[name].of(cb, held=held)
        except DataError:
            continue
    return out


def judges_to_dict(judges: Mapping[str, Calibrated]) -> dict[str, dict[str, Any]]:
    """The calibrated judges as JSON-ready records, by name."""
    return {name: judge.to_dict() for name, judge in judges.items()}


def judges_apart(
    judges: Mapping[str, Calibrated],
) -> tuple[dict[str, dict[str, Any]], dict[str, dict[str, Any]]]:
    """The calibrated judges as JSON-ready records by name (:func:`judges_to_dict`) without
    the fields marked :data:`cbr.unknown_records.ADDED`, and those fields by name (judges with
    none left out): what a posecbr stores, so that one older than such a field reads the records
    (it refuses a field it does not know) and ignores the rest. :func:`judges_from_dict` joins
    them."""
    records: dict[str, dict[str, Any]] = {}
    apart: dict[str, dict[str, Any]] = {}
    for name, judge in judges.items():
        record = judge.to_dict()
        moved = {f: record.pop(f) for f in added_fields(judge) if f in record}
        records[name] = record
        if moved:
            apart[name] = moved
    return records, apart


def judges_from_dict(d: Mapping[str, Any], added: Any = None) -> dict[str, Calibrated]:
    """The judges :func:`judges_to_dict` wrote (``d``), or :func:`judges_apart` (``d`` its
    records, ``added`` the fields stored apart: those of a judge not in ``d``, as those a
    judge does not know, are what a reader may do without, and are left out). ValueError
    naming the judge and the field for a record that is not one (an unknown judge's name
    included)."""
    if not isinstance(d, Mapping):
        raise ValueError(f"the stored judges must be a record by name, got {d!r}")
    if added is None:
        added = {}
    if not isinstance(added, Mapping):
        raise ValueError(f"the judges' fields stored apart must be a record by name, got {added!r}")
    out: dict[str, Calibrated] = {}
    for name, record in d.items():
        if name not in STORED:
            raise ValueError(f"unknown judge {name!r}")
        try:
            out[name] = STORED[name].from_dict(record, added.get(name))
        except ValueError as exc:
            raise ValueError(f"{name}: {exc.args[0]}") from None
    return out
