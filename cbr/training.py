"""Training a stored case base from labelled clips (the work behind ``posecbr train``).

The classifier is fitted exactly as ``CaseBaseClassifier.fit`` fits it in Python (it is the same
call), then stored whole (:mod:`cbr.stored`) in ONE transaction: an interrupted or failed train
leaves the store as it was, and a store file that did not exist before appears only complete
(:func:`casebase_store.write_store`).
Appending adds cases to a stored case base without learning anything anew.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import clone

from casebase_store import StoreTransaction, open_store, write_store
from features.errors import ConfigError, DataError
from features.poses import PoseSequence
from features.progress import progress

from .casebase import CaseBase, frames_of, skeleton_of, subject_of
from .estimator import CaseBaseClassifier, check_labels, unusable
from .maintenance import MaintenanceReport, record_trim
from .problem import FeatureConfig, warm
from .stored import (
    StoredClassifier,
    case_records,
    load_classifier,
    model_document,
    write_matrices,
)
from .stored import stored_case_base as to_store


@dataclass(frozen=True)
class TrainResult:
    """What ``train`` stored: ``n_cases`` cases (``n_active`` after editing), how many clips of
    each label, the clips skipped because they show no person, and what fit learned."""

    name: str
    n_cases: int
    n_active: int
    label_counts: dict[str, int]
    config: FeatureConfig
    similarity: str
    maintenance: MaintenanceReport | None
    learned: dict[str, Any]
    skipped: list[str] = field(default_factory=list)


def usable(clips: Sequence[PoseSequence]) -> tuple[list[int], list[str]]:
    """Positions of the clips that can be learned from, and the names of those that cannot
    (no frame shows the person's torso)."""
    bad = set(unusable(clips))
    names = [clips[i].source or f"clip {i}" for i in sorted(bad)]
    return [i for i in range(len(clips)) if i not in bad], names


def _learned(clf: CaseBaseClassifier) -> dict[str, Any]:
    return {
        "side": clf.side_,
        "feature_weights": clf.weighting_,
        "phases": clf.phases_,
        "mirror_cases": clf.mirror_cases_,
        "inner_loso_accuracy": dict(clf.selection_),
        "unlike_cases": clf.novelty_.to_dict(),
    }


def fit_case_base(
    clips: Sequence[PoseSequence], labels: Sequence[Any], estimator: CaseBaseClassifier
) -> CaseBaseClassifier:
    """``estimator`` cloned and fitted on ``clips``; the expensive features are computed first,
    clip by clip, with a progress bar."""
    level, mirror = estimator.wanted_config().level, estimator.needs_mirror_images()
    for seq in progress(clips, desc="features", total=len(clips), unit="clip"):
        warm(seq, level, mirror=mirror)
    fitted: CaseBaseClassifier = clone(estimator)
    return fitted.fit(list(clips), list(labels))


def _counts(labels: Sequence[str]) -> dict[str, int]:
    values, counts = np.unique(np.asarray(labels, dtype=str), return_counts=True)
    return {str(v): int(c) for v, c in zip(values, counts, strict=True)}


def train(
    db: str | Path,
    name: str,
    clips: Sequence[PoseSequence],
    labels: Sequence[Any],
    estimator: CaseBaseClassifier,
    *,
    target: str = "label",
    replace: bool = False,
) -> TrainResult:
    """Fit ``estimator`` on the usable ``clips`` and store it as case base ``name`` in ``db``
    (a SQLite file or SQLAlchemy URL). Clips that show no person are skipped and named."""
    if not name.strip():
        raise ConfigError("the case base name is empty", "--name")
    text = [str(v) for v in check_labels(labels, len(clips))]
    keep, skipped = usable(clips)
    clips, text = [clips[i] for i in keep], [text[i] for i in keep]
    if not clips:
        raise DataError("no clip shows a person: nothing to learn from", "training set")
    fitted = fit_case_base(clips, text, estimator)
    cb = to_store(fitted)

    def write(tx: StoreTransaction) -> None:
        info = tx.create_case_base(
            name,
            fitted.feature_config_.to_dict(),
            cb.names,
            cb.words,
            fitted.measure_.params(),
            model=model_document(fitted, target),
            replace=replace,
        )
        records = progress(case_records(cb), desc="storing", total=len(cb), unit="case")
        ids = np.asarray(tx.add_cases(info, records))
        _cache_representations(tx, fitted, cb, ids)
        tx.log(info, "build", reason=_build_reason(fitted, len(clips), text))
        if fitted.maintenance_ is not None:
            record_trim(tx, info, fitted.maintenance_, ids)

    write_store(db, write)
    _refresh_matrices(db, name)
    return TrainResult(
        name,
        len(cb),
        len(fitted.case_base_),
        _counts(text),
        fitted.feature_config_,
        fitted.measure_.name,
        fitted.maintenance_,
        _learned(fitted),
        skipped,
    )


def _cache_representations(
    tx: StoreTransaction, clf: CaseBaseClassifier, cb: CaseBase, ids: np.ndarray
) -> None:
    kind = clf.measure_.cache_kind(tuple(cb.problems.shape[1:]))
    if kind is not None:
        reps = clf.measure_.represent(cb.problems)
        tx.put_representations(kind, {int(cid): reps[i] for i, cid in enumerate(ids)})


def _build_reason(clf: CaseBaseClassifier, n_clips: int, labels: Sequence[str]) -> str:
    return (
        f"{len(to_store(clf))} cases from {n_clips} clips of {len(set(labels))} activities, "
        f"features {clf.feature_config_.describe()}, similarity {clf.measure_.name}, side "
        f"handling {clf.side_}, feature weights {clf.weighting_}, {clf.phases_} phases"
    )


def append(
    db: str | Path,
    name: str,
    clips: Sequence[PoseSequence],
    labels: Sequence[Any],
    *,
    target: str = "label",
) -> TrainResult:
    """Add the usable ``clips`` as cases of the stored case base ``name``, described with its
    stored configuration (nothing is learned anew), in one transaction checked against the
    case base that was read."""
    text = [str(v) for v in check_labels(labels, len(clips))]
    keep, skipped = usable(clips)
    clips, text = [clips[i] for i in keep], [text[i] for i in keep]
    if not clips:
        raise DataError("no clip shows a person: nothing to add", "training set")
    store = open_store(db, create=False)
    try:
        stored = load_classifier(store, name)
        if stored.target != target:
            raise ConfigError(
                f"case base {name!r} predicts {stored.target!r}, not {target!r}: its cases "
                f"cannot take --target {target}",
                "--target",
            )
        cb = _new_cases(stored, clips, text)
        with store.transaction() as tx:
            info = tx.expect(name, stored.uid)
            ids = np.asarray(tx.add_cases(info, case_records(cb)))
            _cache_representations(tx, stored.classifier, cb, ids)
            tx.log(info, "append", reason=f"{len(cb)} cases from {len(clips)} clips")
        write_matrices(store, name)
        total = store.count_cases(name)
    finally:
        store.close()
    clf = stored.classifier
    return TrainResult(
        name, len(cb), total, _counts(text), clf.feature_config_, clf.measure_.name, None, {},
        skipped,
    )  # fmt: skip


def _refresh_matrices(db: str | Path, name: str) -> None:
    """A large case base's memory-mapped matrices, written for the state just stored."""
    store = open_store(db, create=False)
    try:
        write_matrices(store, name)
    finally:
        store.close()


def _new_cases(
    stored: StoredClassifier, clips: Sequence[PoseSequence], labels: list[str]
) -> CaseBase:
    """The clips as cases in the stored case base's columns."""
    clf = stored.classifier
    problems = [
        clf.case_base_.problem_of(s)
        for s in progress(clips, desc="features", total=len(clips), unit="clip")
    ]
    return CaseBase(
        clf.feature_config_,
        clf.measure_,
        np.stack([p.values for p in problems]),
        np.array(labels, dtype=object),
        clf.case_base_.names,
        clf.case_base_.words,
        sources=tuple(s.source for s in clips),
        subjects=tuple(subject_of(s) for s in clips),
        frames=tuple(frames_of(s) for s in clips),
        skeletons=tuple(skeleton_of(s) for s in clips),
    )
