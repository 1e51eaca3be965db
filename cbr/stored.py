"""A fitted :class:`~cbr.estimator.CaseBaseClassifier` stored with its case base, and loaded
back whole: the cases, the feature configuration, the measure with its learned weights, and the
model document (the estimator's parameters, what fit chose, the novelty and confidence
calibrations and the column the solutions come from). ``posecbr classify``, ``segment`` and
the Python API then classify with exactly the classifier ``posecbr train`` fitted.

Problems are stored as float64, so a stored and reloaded classifier answers exactly as the one
fitted in memory.
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from casebase_store import (
    CaseArrays,
    CaseBaseInfo,
    NewCase,
    StaleCaseError,
    StoreError,
    case_matrix,
    sqlite_file,
)
from casebase_store import check_width as check_width  # defined here before
from casebase_store.case_matrix import (
    cached_case_matrix,
    case_matrix_files,
    find_case_matrix,
    open_case_matrix,
)
from features.errors import ConfigError, DataError, PosecbrError
from features.text import first_few, shown

from .calibration import UNCALIBRATED, ConfidenceCalibration
from .casebase import CaseBase
from .estimator import CaseBaseClassifier
from .novelty import NoveltyCalibration, calibrate
from .problem import FeatureConfig
from .similarity import SimilarityMeasure, get_measure
from .unknown_records import Calibrated
from .unknown_stored import AT_FIT, calibrate_judges, judges_apart, judges_from_dict
from .weights import MIRROR_FLAG, FeatureWeights
from .words import CASE_KINDS as CASE_KINDS

if TYPE_CHECKING:
    from casebase_store import CaseStore, StoreTransaction

#: bump when the model document changes meaning: a posecbr that reads up to a lower format
#: refuses the model (:func:`check_format`). A field an older reader may ignore needs no bump
#: (a new top-level key; a judge's field stored apart, :func:`judges_document`).
MODEL_FORMAT = 1


@dataclass
class StoredClassifier:
    """A classifier loaded from a store: its case base's ``name``, identity (``uid``) and the
    ``version`` of the cases it holds, the label ``target`` it predicts (``"label"`` or another
    column such as ``"correct"``), the fitted ``classifier`` (case ids in
    ``classifier.case_base_.ids``) and what each case is (``cases``: ``train --split``'s
    ``"clips"``, ``"repetitions"`` or ``"windows"``; None for a case base stored before this
    was recorded)."""

    name: str
    uid: str
    version: int
    target: str
    classifier: CaseBaseClassifier
    info: CaseBaseInfo
    cases: str | None = None


def _jsonable(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, np.generic):
        return value.item()
    return value


def model_document(
    clf: CaseBaseClassifier, target: str = "label", cases: str = "clips"
) -> dict[str, Any]:
    """Everything ``fit`` learned besides the cases, the measure and the feature configuration
    (which the store keeps in their own columns), as JSON-able data, with the column the
    solutions come from (``target``) and what a case is (``cases``: a whole clip, a
    repetition or a window, as ``train --split`` cut them); the unknown judges
    calibrated on its case base (``clf.judges_``), stamped with the version of the case base
    they hold for (1: the store creates a case base at version 1, whatever it holds)."""
    fw = clf.feature_weights_
    doc = {
        "format": MODEL_FORMAT,
        "params": _jsonable(clf.get_params()),
        "tuples": _tuples(clf.get_params()),
        "target": target,
        "cases": cases,
        "side": clf.side_,
        "weighting": clf.weighting_,
        "phases": clf.phases_,
        "mirror_flag": bool(clf.mirror_flag_),
        "mirror_cases": int(clf.mirror_cases_),
        "selection": {k: float(v) for k, v in clf.selection_.items()},
        "feature_weights": None
        if fw is None
        else {k: getattr(fw, k).tolist() for k in ("centre", "scale", "weight")},
        "novelty": clf.novelty_.to_dict(),
        "confidence": clf.confidence_.to_dict(),
    }
    judges = getattr(clf, "judges_", None)
    if judges:
        doc["judges"] = judges_document(judges, 1)
    typed = _typed_classes(clf.classes_)
    if typed is not None:
        doc["classes"] = typed
    return doc


def _tuples(params: Mapping[str, Any]) -> list[str]:
    """The names of the parameters given as tuples, which JSON keeps as lists: read back as
    tuples, and the others as lists, ``get_params`` gives what ``__init__`` was given."""
    return sorted(name for name, value in params.items() if isinstance(value, tuple))


def _typed_classes(classes: np.ndarray) -> list[int] | list[bool] | list[float] | None:
    """``classes`` as a list of whole numbers, of true/false values or of other numbers when
    they all are one of these (labels fitted as such, which the store keeps as text): read
    back, the classifier answers with them, in their order ("10" sorts before "9" as text),
    and scores against them. None for any other labels (text)."""
    values = np.asarray(classes)
    kinds = {values.dtype.kind} if values.dtype != object else {_kind(v) for v in values}
    if kinds == {"b"}:
        return [bool(v) for v in values]
    if kinds <= {"i", "u"}:
        return [int(v) for v in values]
    if kinds == {"f"} and all(math.isfinite(float(v)) for v in values):
        return [float(v) for v in values]
    return None


def _kind(value: Any) -> str:
    """The numpy kind of one label: ``b`` true/false, ``i`` whole number, ``f`` other number,
    ``O`` anything else."""
    if isinstance(value, bool | np.bool_):
        return "b"
    if isinstance(value, int | np.integer):
        return "i"
    if isinstance(value, float | np.floating):
        return "f"
    return "O"


def _stored_classes(model: dict[str, Any]) -> np.ndarray | None:
    """The classes :func:`_typed_classes` stored, as fitted; None when none were or they are
    not all of one of its kinds."""
    stored = model.get("classes")
    if not isinstance(stored, list) or not stored:
        return None
    kinds = {type(v) for v in stored}
    if kinds in ({int}, {bool}, {float}):
        return np.asarray(stored)
    return None


def judges_document(judges: dict[str, Calibrated], version: int) -> dict[str, Any]:
    """The model document's ``judges``: the calibrated unknown judges and the version of the
    case base they were calibrated on (a judge of another version is stale: not read). The
    fields a judge gained once judges were stored (``activities``) are kept apart from its
    record, in ``added_fields`` (:func:`cbr.unknown.judges_apart`): a posecbr older than them
    reads the records and ignores the rest (it refuses a record with a field it does not know,
    "unknown field 'activities'", and reads nothing of the document but
    ``case_base_version`` and ``calibrated``)."""
    records, apart = judges_apart(judges)
    doc: dict[str, Any] = {"case_base_version": version, "calibrated": records}
    if apart:
        doc[ADDED_FIELDS] = apart
    return doc


ADDED_FIELDS = "added_fields"
"""The key of the judges' fields kept apart from their records in the model document's
``judges`` (:func:`judges_document`)."""


def calibrate_stored_judges(clf: CaseBaseClassifier) -> None:
    """Calibrate the unknown judges :data:`cbr.unknown.AT_FIT` on the classifier's case
    base, to be stored with it (:func:`model_document`): ``segment`` and ``watch`` then read
    them instead of scanning the case base at every start."""
    clf.judges_ = calibrate_judges(clf.case_base_, AT_FIT)


def recalibrated(clf: CaseBaseClassifier, cb: CaseBase) -> dict[str, Calibrated]:
    """The unknown judges ``clf`` holds stored, calibrated anew on ``cb`` (what its case base
    becomes: the edit of ``casebase trim``, which costs more than calibrating)."""
    return calibrate_judges(cb, tuple(clf.judges_)) if clf.judges_ else {}


def judges_after_change(
    tx: StoreTransaction, info: CaseBaseInfo, judges: dict[str, Calibrated] | None = None
) -> None:
    """Inside ``tx``, which changes the cases of ``info``: store ``judges`` (calibrated on the
    cases as they will be) in place of the stored ones, or, by default, drop the stored ones
    (calibrated on the cases as they were; ``segment`` then calibrates at run time). The
    transaction bumps the version once: the new judges are stamped with the next one."""
    model = dict(info.model)
    if judges:
        model["judges"] = judges_document(judges, info.version + 1)
    elif "judges" in model:
        del model["judges"]
    else:
        return
    tx.set_model(info, model)


def case_records(cb: CaseBase) -> Iterator[NewCase]:
    """The cases of ``cb`` as store records, with their provenance, one at a time (the store
    consumes them inside its transaction: no second copy of the case base)."""
    for i in range(len(cb)):
        yield NewCase(
            label=str(cb.labels[i]),
            features=np.asarray(cb.problems[i], dtype=np.float64),
            source=cb.sources[i],
            frame_start=cb.frames[i][0],
            frame_end=cb.frames[i][1],
            subject=cb.subjects[i],
            skeleton=cb.skeletons[i],
            origin=cb.origins[i],
            poses=cb.poses[i] or None,
        )


def stored_case_base(clf: CaseBaseClassifier) -> CaseBase:
    """What is stored for a fitted classifier: its case base, or, when fit edited it, the case
    base before editing (the dropped cases are kept, inactive, for the maintenance history)."""
    report = clf.maintenance_
    if report is not None and report.before is not None:
        return report.before
    return clf.case_base_


def _config(info: CaseBaseInfo, where: str) -> FeatureConfig:
    try:
        config = FeatureConfig.from_dict(info.feature_config)
    except (ConfigError, TypeError, ValueError) as exc:
        raise StoreError(
            f"case base {info.name!r} has an unreadable feature configuration ({exc})", where
        ) from None
    if not config.resolved:  # every stored configuration names its states
        raise StoreError(
            f"case base {info.name!r} has a damaged feature configuration (no list of states)",
            where,
        )
    return config


def _measure(info: CaseBaseInfo, where: str) -> SimilarityMeasure:
    try:
        return get_measure(info.similarity)
    except ConfigError as exc:
        raise StoreError(f"case base {info.name!r}: {exc.message}", where) from None


def _representations(
    store: CaseStore, info: CaseBaseInfo, arrays: CaseArrays, measure: SimilarityMeasure
) -> np.ndarray | None:
    """The measure's per-case representations: from the store's cache where present, the rest
    computed (and cached, unless the store is read-only)."""
    kind = measure.cache_kind(tuple(arrays.features.shape[1:]))
    if kind is None:
        return None
    cached = store.load_representations(info.name, kind, version=info.version)
    missing = [i for i, cid in enumerate(arrays.ids) if int(cid) not in cached]
    if missing:
        new = measure.represent(arrays.features[missing])
        for j, i in enumerate(missing):
            cached[int(arrays.ids[i])] = new[j]
        if not store.readonly:
            with store.transaction() as tx:
                # cached only for the cases as read: a case revised since would keep the
                # representation of its old problem (and retrieval would use that)
                if tx.expect(info.name, info.uid).version == info.version:
                    tx.put_representations(
                        kind, {int(arrays.ids[i]): new[j] for j, i in enumerate(missing)}
                    )
    return np.stack([cached[int(cid)] for cid in arrays.ids]).astype(np.float64)


#: a case base at least this large (in cases) stored in a SQLite file keeps its problems and
#: representations as memory-mapped matrices beside the file (the store's figure)
MAPPED_MIN_CASES = case_matrix.MAPPED_MIN_CASES
_MATRICES = ("problems", "representations")


def _matrix_key(info: CaseBaseInfo) -> str:
    """The matrices of one state of one case base: identity and version."""
    return f"{info.uid}-{info.version}"


def _matrix_identity(info: CaseBaseInfo) -> str:
    """How the key of every state of this case base, and of no other, begins."""
    return f"{info.uid}-"


def write_matrices(store: CaseStore, name: str, min_cases: int | None = None) -> bool:
    """Write the memory-mapped matrices of case base ``name`` as it is now (a large case base
    in a SQLite file; the commands that change a case base call this after their change).
    Returns whether it wrote them; read-only commands only ever read them."""
    db = sqlite_file(store.where)
    least = MAPPED_MIN_CASES if min_cases is None else min_cases
    if db is None or store.readonly:
        return False
    try:
        remove_stale_matrices(store, name)
    except (PosecbrError, OSError):  # after the change committed: a copy's tidying, no more
        pass
    if store.count_cases(name) < least:
        return False
    info, arrays = store.load_case_base(name)
    measure = _measure(info, store.where)
    chunk = 8192

    def problems() -> Iterator[np.ndarray]:
        for a in range(0, len(arrays.ids), chunk):
            yield arrays.features[a : a + chunk]

    def representations() -> Iterator[np.ndarray]:
        for a in range(0, len(arrays.ids), chunk):
            yield measure.represent(arrays.features[a : a + chunk])

    rep_shape = measure.represent(arrays.features[:1]).shape[1:]
    key, identity = _matrix_key(info), _matrix_identity(info)
    try:
        cached_case_matrix(
            db, name, "problems", key, arrays.features.shape, problems, np.float64, identity
        )
        cached_case_matrix(
            db, name, "representations", key, (len(arrays.ids), *rep_shape), representations,
            identity=identity,
        )  # fmt: skip
    except DataError as exc:
        # called after the change committed: the matrices are a copy of the cases for speed,
        # and a reader without them reads the database. Failing here said the command failed,
        # and run again it made its change twice (a second trim)
        print(
            f"note: {shown(str(exc))} (the change is stored; commands read its cases from the"
            " database instead of a memory-mapped copy)",
            file=sys.stderr,
        )
        return False
    return True


_KEY = re.compile(r"(?P<uid>[0-9a-f]{32})-(?P<version>[0-9]+)")


def remove_stale_matrices(store: CaseStore, name: str) -> None:
    """Remove the matrix files beside a SQLite store that nothing will read again, in either
    naming (posecbr 0.2 named them without the hash): those of case bases no longer in it
    (replaced by ``train --replace``: an identity no case base has) and those of ``name``'s
    older versions. Other case bases' files of their current state, and files not named as
    matrices, are left alone; a file that cannot be removed is left too (a copy for speed)."""
    db = sqlite_file(store.where)
    if db is None or store.readonly:
        return
    # the files are listed before the case bases are read: matrices are written after their
    # change commits, so a file listed is of a case base (or version) already readable here
    files = case_matrix_files(db)
    if not files:
        return
    live = store.identities()
    for path, key in files:
        m = _KEY.fullmatch(key)
        if m is None:
            continue
        owner = live.get(m["uid"])
        gone = owner is None
        older = owner is not None and owner[0] == name and int(m["version"]) < owner[1]
        if gone or older:
            try:
                path.unlink(missing_ok=True)
            except OSError:
                pass


def _mapped(store: CaseStore, info: CaseBaseInfo, n: int) -> tuple[np.ndarray, ...] | None:
    """The problems and representations of exactly this version, memory-mapped, when a writer
    left them beside the database (None: read from SQL)."""
    db = sqlite_file(store.where)
    if db is None or n < 1:
        return None
    key, identity = _matrix_key(info), _matrix_identity(info)
    paths = [find_case_matrix(db, info.name, kind, key, identity) for kind in _MATRICES]
    if not all(p.exists() for p in paths):
        return None
    try:
        out = tuple(open_case_matrix(p) for p in paths)
    except DataError:
        return None  # damaged or half-removed: the SQL store is the truth
    return out if all(len(m) == n for m in out) else None


def _read(
    store: CaseStore, name: str
) -> tuple[CaseBaseInfo, CaseArrays, tuple[np.ndarray, ...] | None]:
    """The case base's description and cases, with its mapped matrices when a writer left
    them for exactly this version; otherwise one read of everything, problems included."""
    info, arrays = store.load_case_base(name, features=False)
    mapped = _mapped(store, info, len(arrays.ids))
    if mapped is None:
        info, arrays = store.load_case_base(name)
    return info, arrays, mapped


def _case_base(
    store: CaseStore,
    info: CaseBaseInfo,
    arrays: CaseArrays,
    config: FeatureConfig,
    mapped: tuple[np.ndarray, ...] | None,
) -> CaseBase:
    measure = _measure(info, store.where)
    if len(arrays.ids) == 0:
        raise StoreError(f"case base {info.name!r} has no cases", store.where)
    check_width(info, (arrays.features if mapped is None else mapped[0]).shape[-1], store.where)
    problems = arrays.features if mapped is None else mapped[0]
    check_finite(info.name, problems, arrays.ids, store.where)
    cb = CaseBase(
        config,
        measure,
        problems,
        arrays.labels,
        info.feature_names,
        info.feature_words,
        ids=arrays.ids,
        sources=arrays.sources,
        subjects=arrays.subjects,
        origins=arrays.origins,
        frames=arrays.frame_ranges,
    )
    cb.reps = _representations(store, info, arrays, measure) if mapped is None else mapped[1]
    return cb


def check_finite(name: str, problems: np.ndarray, ids: np.ndarray, where: str) -> None:
    """Refuse case base ``name`` when a stored problem (``problems`` ``(n, ...)``, the cases
    ``ids``) holds NaN or an infinity: a StoreError naming the case base and those cases.
    Training never stores one: every problem made of a clip has its gaps filled
    (:func:`cbr.problem.extract_problem`: a state never seen gets the configured fill, an
    angle 0.5, a position 0; a QMP not testable is 0), a revision moves a problem toward
    another such problem, and every measure refuses such a case at each query ("case rows 3
    hold NaN or inf"). So the case base was changed outside posecbr, and each clip was
    refused in turn in the measure's words, none naming the case base. Checked with one sum
    per row (NaN and infinities carry through it); the rows whose sum is not finite are
    looked at value by value (finite values whose sum overflowed are no damage)."""
    n = len(problems)
    if n == 0:
        return
    rows = problems.reshape(n, -1)
    with np.errstate(over="ignore", invalid="ignore"):
        sums = rows.sum(axis=1)
    suspect = np.flatnonzero(~np.isfinite(sums))
    if not len(suspect):
        return
    bad = suspect[~np.isfinite(rows[suspect]).all(axis=1)]
    if not len(bad):
        return
    cases = [str(int(ids[i])) for i in bad]
    if len(cases) == 1:
        said, them = f"problem of case {cases[0]} holds", "it"
    else:
        said, them = f"problems of cases {first_few(cases)} hold", "them"
    raise StoreError(
        f"case base {name!r} is damaged: the {said} NaN or an infinity, which training never"
        f" stores (changed outside posecbr?): no clip can be compared with {them}; train the"
        " case base again, or use a copy made before",
        where,
    )


def _params(
    model: dict[str, Any], config: FeatureConfig, measure: SimilarityMeasure
) -> dict[str, Any]:
    """The estimator's parameters: stored ones, or (a case base from before models were stored)
    the ones its configuration implies."""
    params = dict(model.get("params") or {})
    if params and "class_weight" not in params:
        # stored before the vote was class-balanced: it votes as it was calibrated
        params["class_weight"] = "none"
    if not params:
        params = {
            "features": config.level,
            "similarity": measure.name,
            "length": config.length,
            "summary": config.summary,
            "phases": config.phases,
        }
    known = set(CaseBaseClassifier().get_params())
    # stored before the tuples were named: states was read back as a tuple
    named = model.get("tuples", ["states"])
    tuples = {str(v) for v in named} if isinstance(named, list) else set()
    return {k: (tuple(v) if k in tuples and isinstance(v, list) else v)
            for k, v in params.items() if k in known}  # fmt: skip


def check_format(model: Mapping[str, Any], name: str, where: str) -> None:
    """StoreError when the model document of case base ``name`` is of a later format than
    :data:`MODEL_FORMAT` (stored by a newer posecbr whose model means what this one cannot
    read: answering from it would answer otherwise than it). A model without a format, or of
    this one or an earlier, is read."""
    stored = model.get("format")
    if isinstance(stored, int) and not isinstance(stored, bool) and stored > MODEL_FORMAT:
        raise StoreError(
            f"case base {name!r} was stored by a newer posecbr (model format {stored}); this"
            f" one reads up to format {MODEL_FORMAT}: upgrade posecbr to read it",
            where,
        )


def load_classifier(store: CaseStore, name: str) -> StoredClassifier:
    """The fitted classifier stored as case base ``name`` (its active cases); a large case base
    maps its matrices from beside the database when they are there (:func:`write_matrices`)."""
    for tries in range(3):  # the cases and their cached representations of one version
        info, arrays, mapped = _read(store, name)
        check_format(info.model, name, store.where)
        config = _config(info, store.where)
        try:
            cb = _case_base(store, info, arrays, config, mapped)
            break
        except StaleCaseError:  # changed between the two reads: read it again
            if tries == 2:
                raise
    model = info.model
    clf = CaseBaseClassifier(**_params(model, config, cb.measure))
    try:
        clf._check_params()
    except ConfigError as exc:
        raise StoreError(f"case base {name!r} has a bad model ({exc})", store.where) from None
    fw = model.get("feature_weights")
    clf.feature_config_ = config
    clf.measure_ = cb.measure
    clf.case_base_ = cb
    clf.feature_names_ = cb.names
    clf.feature_weights_ = (
        None if not fw else FeatureWeights(*(np.asarray(fw[k], dtype=np.float64)
                                             for k in ("centre", "scale", "weight")))
    )  # fmt: skip
    clf.side_ = str(model.get("side", "canonical" if config.side == "canonical" else "off"))
    clf.weighting_ = str(model.get("weighting", "none"))
    clf.phases_ = int(config.phases)
    clf.mirror_flag_ = bool(model.get("mirror_flag", False))
    clf.mirror_ = clf.side_ == "augment"
    clf.mirror_cases_ = int(model.get("mirror_cases", 0))
    clf.selection_ = dict(model.get("selection") or {})
    clf.case_origin_ = np.arange(len(cb))
    clf.maintenance_ = None
    clf.novelty_ = _novelty(model, cb, name, store.where)
    clf.confidence_ = _confidence(model, name, store.where)
    clf.judges_ = _judges(model, info.version, name, store.where)
    typed = _stored_classes(model)
    if typed is not None:
        clf.classes_ = typed  # kept by refresh while the cases' labels match
    clf.refresh()
    target = str(model.get("target", "label"))
    clf.target_ = target  # explain()'s words without a target= given: "a correct repetition"
    cases = model.get("cases")
    return StoredClassifier(
        name, info.uid, info.version, target, clf, info, None if cases is None else str(cases)
    )


def _damaged(name: str, what: str, exc: Exception, where: str) -> StoreError:
    """The error for a stored calibration that is there but cannot be read: answering without
    it would silently change what the case base says."""
    reason = (
        exc.args[0] if isinstance(exc, ValueError) and exc.args else f"{type(exc).__name__}: {exc}"
    )
    return StoreError(f"case base {name!r} has a damaged {what} ({reason})", where)


def _confidence(model: dict[str, Any], name: str, where: str) -> ConfidenceCalibration:
    """The stored confidence calibration; a case base stored without one (before posecbr
    0.3) answers with the plain vote share. StoreError when it is there but damaged."""
    if "confidence" not in model:
        return UNCALIBRATED
    try:
        return ConfidenceCalibration.from_dict(model["confidence"])
    except (AttributeError, KeyError, TypeError, ValueError) as exc:
        raise _damaged(name, "confidence calibration", exc, where) from None


def _novelty(model: dict[str, Any], cb: CaseBase, name: str, where: str) -> NoveltyCalibration:
    """The stored calibration; for a case base stored without one (written by posecbr 0.1),
    calibrated now on its cases, each held out from the cases of its own clip. StoreError when
    it is there but damaged."""
    if model.get("novelty"):
        try:
            return NoveltyCalibration.from_dict(model["novelty"])
        except (AttributeError, KeyError, TypeError, ValueError) as exc:
            raise _damaged(name, "novelty calibration", exc, where) from None
    clip = np.array([s.removesuffix(" (mirrored)") for s in cb.sources], dtype=object)
    real = np.ones(len(cb), dtype=bool)
    if cb.names and cb.names[-1] == MIRROR_FLAG:
        real = cb.problems[:, -1] == 0.0
    return calibrate(cb, cb.problems[real], clip[real], clip, "leave-one-out")


def _judges(model: dict[str, Any], version: int, name: str, where: str) -> dict[str, Calibrated]:
    """The stored unknown judges; none for a case base stored without them (before posecbr
    stored judges, or with fewer than three activities) or whose cases changed since they
    were calibrated (another version): ``segment`` calibrates those at run time. StoreError
    when they are there but damaged."""
    stored = model.get("judges")
    if stored is None:
        return {}
    try:
        if not isinstance(stored, dict):
            raise ValueError(f"the stored judges must be a record, got {stored!r}")
        stamp = stored["case_base_version"]
        if isinstance(stamp, bool) or not isinstance(stamp, int):
            raise ValueError(f"case_base_version must be a whole number, got {stamp!r}")
        judges = judges_from_dict(stored["calibrated"], stored.get(ADDED_FIELDS))
    except (KeyError, TypeError, ValueError) as exc:
        raise _damaged(name, "unknown judge calibration", exc, where) from None
    return judges if stamp == version else {}
