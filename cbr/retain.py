"""Retain: add an observation as a new case when it is novel and beneficial.

- novelty = distance to the nearest case / the case base's usual held-out nearest-case
  distance (its calibrated ``scale``, :mod:`cbr.novelty`): > 1 means farther than usual;
- benefit = 1 - the vote share the case base gives the true label today: 0 when it is already
  classified right with full confidence, 1 when the true label gets no vote.

Both must reach their thresholds. :func:`record_retention` writes the case and the log
entry inside the caller's transaction.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from casebase_store import CaseBaseInfo, NewCase
from features.errors import ConfigError

from .casebase import CaseBase
from .problem import Problem
from .retrieve import retrieve
from .reuse import Weights, reuse

if TYPE_CHECKING:
    from casebase_store import StoreTransaction


@dataclass(frozen=True)
class RetainDecision:
    retained: bool
    novelty: float
    benefit: float
    reason: str


def novelty(cb: CaseBase, problem: Problem | np.ndarray, scale: float) -> float:
    """Distance to the nearest case over ``scale`` (the case base's usual held-out nearest-case
    distance, :class:`cbr.novelty.NoveltyCalibration`)."""
    if (
        isinstance(scale, bool)
        or not isinstance(scale, numbers.Real)
        or not (math.isfinite(float(scale)) and float(scale) > 0.0)
    ):
        raise ConfigError(f"must be a finite number > 0, got {scale!r}", "scale")
    return float(retrieve(cb, problem, 1).distances[0]) / scale


def benefit(
    cb: CaseBase, problem: Problem | np.ndarray, label: str, k: int, weights: Weights = "distance"
) -> float:
    classes = np.unique(np.append(cb.labels.astype(str), str(label)))
    sol = reuse(retrieve(cb, problem, k), classes, weights)
    return float(1.0 - sol.proba[list(classes).index(str(label))])


def decide_retention(
    cb: CaseBase,
    problem: Problem | np.ndarray,
    label: str,
    *,
    scale: float,
    k: int = 5,
    novelty_threshold: float = 0.5,
    benefit_threshold: float = 0.2,
    weights: Weights = "distance",
) -> RetainDecision:
    """Whether the observation ``problem`` labelled ``label`` should become a case (nothing is
    changed: :func:`retain` or :func:`record_retention` carry it out)."""
    nov = novelty(cb, problem, scale)
    ben = benefit(cb, problem, label, k, weights)
    ok = nov >= novelty_threshold and ben >= benefit_threshold
    why = (
        f"novelty {nov:.3g} {'>=' if nov >= novelty_threshold else '<'} {novelty_threshold:g}, "
        f"benefit {ben:.3g} {'>=' if ben >= benefit_threshold else '<'} {benefit_threshold:g}"
    )
    return RetainDecision(ok, nov, ben, ("retained: " if ok else "not retained: ") + why)


def retain(
    cb: CaseBase,
    problem: Problem | np.ndarray,
    label: str,
    *,
    scale: float,
    k: int = 5,
    novelty_threshold: float = 0.5,
    benefit_threshold: float = 0.2,
    weights: Weights = "distance",
    source: str = "",
    subject: str | None = None,
) -> RetainDecision:
    """Decide whether to retain, and if so append the case to ``cb`` (in memory)."""
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    dec = decide_retention(
        cb,
        problem,
        label,
        scale=scale,
        k=k,
        novelty_threshold=novelty_threshold,
        benefit_threshold=benefit_threshold,
        weights=weights,
    )
    if dec.retained:
        cb.add(values, label, source=source, subject=subject, origin="retained")
    return dec


def record_retention(
    tx: StoreTransaction,
    info: CaseBaseInfo,
    decision: RetainDecision,
    problem: np.ndarray,
    label: str,
    *,
    source: str = "",
    subject: str | None = None,
    frames: tuple[int | None, int | None] = (None, None),
    skeleton: str | None = None,
    poses: str | None = None,
) -> int | None:
    """Inside ``tx``: log the decision (and add the case, if retained); the new case id.
    ``poses``: the :func:`cbr.described.poses_digest` of the clip the case is made of (what
    tells a copy of it, ``train --append``), None when not known."""
    case_id = None
    if decision.retained:
        case = NewCase(
            str(label),
            np.asarray(problem, dtype=np.float64),
            source=source,
            frame_start=frames[0],
            frame_end=frames[1],
            subject=subject,
            skeleton=skeleton,
            origin="retained",
            poses=poses,
        )
        case_id = tx.add_cases(info, [case])[0]
    tx.log(
        info,
        "retain",
        case_id=case_id,
        novelty=decision.novelty,
        benefit=decision.benefit,
        reason=decision.reason,
    )
    return case_id
