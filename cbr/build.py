"""Building a stored case base from labelled clips, and classifying clips with one (the work
behind ``posecbr train`` and ``posecbr classify``). Each user action is one store transaction.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from sklearn.base import clone

from casebase_store import CaseStore, NewCase
from features.errors import ConfigError, DataError
from features.poses import PoseSequence
from features.progress import progress

from .casebase import CaseBase, subject_of
from .estimator import CaseBaseClassifier
from .explain import Explanation, explain
from .maintenance import EDITORS, MaintenanceReport, record_trim
from .problem import FeatureConfig, warm
from .retain import RetainDecision, record_retention, retain, typical_distance
from .retrieve import retrieve
from .reuse import reuse
from .revise import Revision, record_revision, revise


@dataclass(frozen=True)
class BuildResult:
    name: str
    n_cases: int
    n_kept: int
    label_counts: dict[str, int]
    config: FeatureConfig
    trim: MaintenanceReport | None
    learned: dict[str, Any]


def check_training_set(labels: Sequence[str], where: str) -> None:
    if len(labels) == 0:
        raise DataError("the training set is empty (no clips found)", where)
    classes = sorted(set(labels))
    if len(classes) < 2:
        raise DataError(
            f"the training set has only one activity ({classes[0]!r}); a classifier needs at "
            "least two",
            where,
        )


def check_same_config(stored: dict[str, Any], wanted: FeatureConfig, name: str, where: str) -> None:
    """Refuse to mix cases from another feature configuration into a case base."""
    have = FeatureConfig.from_dict(stored)
    for key in ("level", "length", "qmp_part"):
        if getattr(have, key) != getattr(wanted, key):
            raise ConfigError(
                f"case base {name!r} was built with features {have.describe()}, not "
                f"{wanted.describe()} ({key} differs); use another --name or --replace",
                where,
            )
    if isinstance(wanted.states, tuple) and tuple(wanted.states) != tuple(have.states):
        raise ConfigError(
            f"case base {name!r} was built with other fluent states; use another --name or "
            "--replace",
            where,
        )


def build_case_base(
    store: CaseStore,
    name: str,
    clips: Sequence[PoseSequence],
    labels: Sequence[str],
    estimator: CaseBaseClassifier,
    *,
    replace: bool = False,
    append: bool = False,
    editor: str | None = None,
    keep: float = 0.7,
) -> BuildResult:
    """Learn the case base as ``estimator.fit`` does (states, side handling, feature weights,
    mirror cases), optionally trim it, and store it in ONE transaction.

    With ``append`` onto an existing case base the stored configuration, measure and weights
    are kept and the clips are added as further cases (nothing is re-learned).
    """
    labels = [str(v) for v in labels]
    check_training_set(labels, "training set")
    k = int(estimator.k)
    if append and store.has_case_base(name):
        info = store.get_case_base(name)
        check_same_config(info.feature_config, estimator.wanted_config(), name, store.where)
        old = CaseBase.from_store(store, name)
        config, measure = old.config, old.measure
        probs = [
            old.problem_of(s)
            for s in progress(clips, desc="features", total=len(clips), unit="clip")
        ]
        cb = CaseBase(
            config,
            measure,
            np.stack([p.values for p in probs]),
            np.array(labels, dtype=object),
            old.names,
            old.words,
            sources=tuple(s.source for s in clips),
            subjects=tuple(subject_of(s) for s in clips),
        )
        origin = np.arange(len(clips))
        extra = None
        learned: dict[str, Any] = {}
    else:
        fitted = clone(estimator).set_params(trim=None)
        level, mirror = estimator.wanted_config().level, estimator.needs_mirror_images()
        for seq in progress(clips, desc="features", total=len(clips), unit="clip"):
            warm(seq, level, mirror=mirror)
        fitted.fit(list(clips), labels)
        cb, config, measure = fitted.case_base_, fitted.feature_config_, fitted.measure_
        origin = fitted.case_origin_
        extra = (
            f"side handling {fitted.side_}, feature weights {fitted.weighting_}, "
            f"{fitted.phases_} phases"
        )
        learned = {
            "side": fitted.side_,
            "feature_weights": fitted.weighting_,
            "phases": fitted.phases_,
            "mirror_cases": fitted.mirror_cases_,
            "inner_loso_accuracy": dict(fitted.selection_),
        }
    report = None
    if editor is not None:
        if editor not in EDITORS:
            raise ConfigError(f"unknown editor {editor!r} (known: {', '.join(EDITORS)})", "editor")
        fn = EDITORS[editor]
        report = fn(cb, keep, k) if editor == "novelty-benefit" else fn(cb)
    kind = measure.cache_kind(tuple(cb.problems.shape[1:]))
    reps = measure.represent(cb.problems) if kind is not None else None
    case_clips = [clips[int(i) % len(clips)] for i in origin]  # a mirror image: its clip
    frames = [
        (
            int(s.metadata.get("frame_offset", 0)),
            int(s.metadata.get("frame_offset", 0)) + s.n_frames,
        )
        for s in case_clips
    ]
    with store.transaction() as tx:
        if append and tx.has_case_base(name):  # as this transaction sees it
            info = tx.case_base(name)
        else:
            info = tx.create_case_base(
                name,
                config.to_dict(),
                cb.names,
                cb.words,
                measure.params(),
                replace=replace,
            )
        new = [
            NewCase(
                label=str(cb.labels[i]),
                features=cb.problems[i].astype(np.float32),
                source=cb.sources[i],
                frame_start=frames[i][0],
                frame_end=frames[i][1],
                subject=cb.subjects[i],
                skeleton=str(case_clips[i].metadata.get("source_skeleton", case_clips[i].skeleton)),
                origin="trained",
            )
            for i in range(len(cb))
        ]
        ids = tx.add_cases(info, progress(new, desc="storing", total=len(new), unit="case"))
        if kind is not None and reps is not None:
            tx.put_representations(kind, {cid: reps[i] for i, cid in enumerate(ids)})
        tx.log(
            info,
            "build",
            reason=f"{len(ids)} cases from {len(clips)} clips of {len(set(labels))} "
            f"activities, features {config.describe()}, similarity {measure.name}"
            + ("" if extra is None else f", {extra}"),
        )
        if report is not None:
            record_trim(tx, info.name, report, np.asarray(ids))
    return BuildResult(
        name,
        len(cb),
        len(cb) if report is None else report.size_after,
        {lab: labels.count(lab) for lab in sorted(set(labels))},
        config,
        report,
        learned,
    )


@dataclass(frozen=True)
class Classification:
    source: str
    true_label: str | None
    explanation: Explanation
    revision: Revision | None = None
    retention: RetainDecision | None = None
    novelty: float | None = None  # nearest-case distance / the case base's usual one

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"clip": self.source, **self.explanation.to_dict()}
        if self.novelty is not None:
            out["novelty"] = self.novelty
        if self.true_label is not None:
            out["true_label"] = self.true_label
            out["correct"] = self.true_label == self.explanation.label
        if self.revision is not None:
            r = self.revision
            out["revision"] = {
                "action": r.action,
                "case_id": r.case_id,
                "old_label": r.old_label,
                "new_label": r.new_label,
                "reason": r.reason,
            }
        if self.retention is not None:
            d = self.retention
            out["retention"] = {
                "retained": d.retained,
                "novelty": d.novelty,
                "benefit": d.benefit,
                "reason": d.reason,
            }
        return out


def classify_clips(
    store: CaseStore,
    name: str,
    clips: Sequence[PoseSequence],
    true_labels: Sequence[str | None],
    *,
    k: int = 5,
    feedback: str | None = None,
    novelty_threshold: float = 0.5,
    benefit_threshold: float = 0.2,
) -> list[Classification]:
    """Classify clips. With ``feedback`` (the true label of every clip): a clip whose novelty
    and benefit pass the thresholds is retained as a new case; otherwise the most similar case
    is revised toward it (:func:`cbr.revise.revise`); one transaction per clip."""
    cb = CaseBase.from_store(store, name)
    classes = np.unique(cb.labels.astype(str))
    scale = typical_distance(cb)
    out = []
    for seq, truth in progress(
        list(zip(clips, true_labels, strict=True)),
        desc="classifying",
        total=len(clips),
        unit="clip",
    ):
        p = cb.problem_of(seq)
        if p.values.shape != cb.problems.shape[1:]:
            raise DataError(
                f"problem shape {p.values.shape} differs from the case base's "
                f"{cb.problems.shape[1:]}",
                seq.source,
            )
        r = retrieve(cb, p, k)
        sol = reuse(r, classes)
        exp = explain(cb, p, r, sol)
        rev = dec = None
        if feedback is not None:
            dec = retain(
                cb,
                p,
                feedback,
                k=k,
                novelty_threshold=novelty_threshold,
                benefit_threshold=benefit_threshold,
                scale=scale,
                source=seq.source,
            )
            if not dec.retained:
                rev = revise(cb, p, feedback)
            with store.transaction() as tx:  # one transaction per clip's feedback
                cid = record_retention(tx, name, dec, p.values, feedback, source=seq.source)
                if cid is not None:
                    assert cb.ids is not None
                    cb.ids[-1] = cid
                if rev is not None:
                    record_revision(tx, name, cb, rev)
            classes = np.unique(cb.labels.astype(str))
        nov = float(r.distances[0]) / scale if len(r.distances) and scale > 0 else None
        out.append(Classification(seq.source, truth, exp, rev, dec, nov))
    return out
