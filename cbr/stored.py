"""A fitted :class:`~cbr.estimator.CaseBaseClassifier` stored with its case base, and loaded
back whole: the cases, the feature configuration, the measure with its learned weights, and the
model document (the estimator's parameters, what fit chose, the novelty calibration and the
column the solutions come from). ``posecbr classify``, ``segment`` and the Python API then
classify with exactly the classifier ``posecbr train`` fitted.

Problems are stored as float64, so a stored and reloaded classifier answers exactly as the one
fitted in memory.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from casebase_store import CaseArrays, CaseBaseInfo, CaseStore, NewCase, StoreError
from features.errors import ConfigError

from .casebase import CaseBase
from .estimator import CaseBaseClassifier
from .novelty import NoveltyCalibration, calibrate
from .problem import FeatureConfig
from .similarity import SimilarityMeasure, get_measure
from .weights import MIRROR_FLAG, FeatureWeights

#: bump when the model document changes meaning
MODEL_FORMAT = 1


@dataclass
class StoredClassifier:
    """A classifier loaded from a store: its case base's ``name``, identity (``uid``) and the
    ``version`` of the cases it holds, the label ``target`` it predicts (``"label"`` or another
    column such as ``"correct"``) and the fitted ``classifier`` (case ids in
    ``classifier.case_base_.ids``)."""

    name: str
    uid: str
    version: int
    target: str
    classifier: CaseBaseClassifier
    info: CaseBaseInfo


def _jsonable(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, np.generic):
        return value.item()
    return value


def model_document(clf: CaseBaseClassifier, target: str = "label") -> dict[str, Any]:
    """Everything ``fit`` learned besides the cases, the measure and the feature configuration
    (which the store keeps in their own columns), as JSON-able data."""
    fw = clf.feature_weights_
    return {
        "format": MODEL_FORMAT,
        "params": _jsonable(clf.get_params()),
        "target": target,
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
    }


def case_records(cb: CaseBase) -> list[NewCase]:
    """The cases of ``cb`` as store records, with their provenance."""
    return [
        NewCase(
            label=str(cb.labels[i]),
            features=cb.problems[i].astype(np.float64),
            source=cb.sources[i],
            frame_start=cb.frames[i][0],
            frame_end=cb.frames[i][1],
            subject=cb.subjects[i],
            skeleton=cb.skeletons[i],
            origin=cb.origins[i],
        )
        for i in range(len(cb))
    ]


def stored_case_base(clf: CaseBaseClassifier) -> CaseBase:
    """What is stored for a fitted classifier: its case base, or, when fit edited it, the case
    base before editing (the dropped cases are kept, inactive, for the maintenance history)."""
    report = clf.maintenance_
    if report is not None and report.before is not None:
        return report.before
    return clf.case_base_


def _config(info: CaseBaseInfo, where: str) -> FeatureConfig:
    try:
        return FeatureConfig.from_dict(info.feature_config)
    except (ConfigError, TypeError, ValueError) as exc:
        raise StoreError(
            f"case base {info.name!r} has an unreadable feature configuration ({exc})", where
        ) from None


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
    cached = store.load_representations(info.name, kind)
    missing = [i for i, cid in enumerate(arrays.ids) if int(cid) not in cached]
    if missing:
        new = measure.represent(arrays.features[missing])
        for j, i in enumerate(missing):
            cached[int(arrays.ids[i])] = new[j]
        if not store.readonly:
            with store.transaction() as tx:
                tx.expect(info.name, info.uid)
                tx.put_representations(
                    kind, {int(arrays.ids[i]): new[j] for j, i in enumerate(missing)}
                )
    return np.stack([cached[int(cid)] for cid in arrays.ids]).astype(np.float64)


def _case_base(
    store: CaseStore, info: CaseBaseInfo, arrays: CaseArrays, config: FeatureConfig
) -> CaseBase:
    measure = _measure(info, store.where)
    if len(arrays.ids) == 0:
        raise StoreError(f"case base {info.name!r} has no cases", store.where)
    if len(info.feature_names) and arrays.features.shape[-1] != len(info.feature_names):
        raise StoreError(
            f"case base {info.name!r} is damaged: its cases have {arrays.features.shape[-1]} "
            f"feature columns but the case base names {len(info.feature_names)}",
            store.where,
        )
    cb = CaseBase(
        config,
        measure,
        arrays.features,
        arrays.labels,
        info.feature_names,
        info.feature_words,
        ids=arrays.ids,
        sources=arrays.sources,
        subjects=arrays.subjects,
        origins=arrays.origins,
        frames=arrays.frame_ranges,
    )
    cb.reps = _representations(store, info, arrays, measure)
    return cb


def _params(
    model: dict[str, Any], config: FeatureConfig, measure: SimilarityMeasure
) -> dict[str, Any]:
    """The estimator's parameters: stored ones, or (a case base from before models were stored)
    the ones its configuration implies."""
    params = dict(model.get("params") or {})
    if not params:
        params = {
            "features": config.level,
            "similarity": measure.name,
            "length": config.length,
            "summary": config.summary,
            "phases": config.phases,
        }
    known = set(CaseBaseClassifier().get_params())
    return {k: (tuple(v) if k == "states" and isinstance(v, list) else v)
            for k, v in params.items() if k in known}  # fmt: skip


def load_classifier(store: CaseStore, name: str) -> StoredClassifier:
    """The fitted classifier stored as case base ``name`` (its active cases)."""
    info, arrays = store.load_case_base(name)
    config = _config(info, store.where)
    cb = _case_base(store, info, arrays, config)
    model = info.model
    clf = CaseBaseClassifier(**_params(model, config, cb.measure))
    try:
        clf._check_params()
    except ConfigError as exc:
        raise StoreError(
            f"case base {name!r} has a bad model ({exc.message})", store.where
        ) from None
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
    clf.novelty_ = _novelty(model, cb)
    clf.refresh()
    target = str(model.get("target", "label"))
    return StoredClassifier(name, info.uid, info.version, target, clf, info)


def _novelty(model: dict[str, Any], cb: CaseBase) -> NoveltyCalibration:
    """The stored calibration; for a case base stored without one (written by posecbr 0.1),
    calibrated now on its cases, each held out from the cases of its own clip."""
    if model.get("novelty"):
        try:
            return NoveltyCalibration.from_dict(model["novelty"])
        except (KeyError, TypeError, ValueError):
            pass  # an unreadable calibration is recomputed below
    clip = np.array([s.removesuffix(" (mirrored)") for s in cb.sources], dtype=object)
    real = np.ones(len(cb), dtype=bool)
    if cb.names and cb.names[-1] == MIRROR_FLAG:
        real = cb.problems[:, -1] == 0.0
    return calibrate(cb, cb.problems[real], clip[real], clip, "leave-one-out")
