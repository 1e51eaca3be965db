"""Retain: add an observation as a new case when it is novel and beneficial.

- novelty = distance to the nearest case / the case base's typical nearest-neighbour distance
  (median over a sample of cases, leave-one-out): > 1 means farther than usual;
- benefit = 1 - the vote share the case base gives the true label today: 0 when it is already
  classified right with full confidence, 1 when the true label gets no vote.

Both must reach their thresholds. :func:`record_retention` writes the case and the log
entry inside the caller's transaction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from casebase_store import NewCase, StoreTransaction

from .casebase import CaseBase
from .problem import Problem
from .retrieve import retrieve
from .reuse import Weights, reuse


@dataclass(frozen=True)
class RetainDecision:
    retained: bool
    novelty: float
    benefit: float
    reason: str


def typical_distance(cb: CaseBase, sample: int = 64, seed: int = 0) -> float:
    """Median leave-one-out nearest-neighbour distance over up to ``sample`` cases."""
    n = len(cb)
    if n < 2:
        return 1.0
    pick = np.random.default_rng(seed).choice(n, min(sample, n), replace=False)
    d = [float(retrieve(cb, cb.problems[i], 1, exclude=int(i)).distances[0]) for i in pick]
    med = float(np.median(d))
    return med if med > 0 else (float(np.mean(d)) or 1.0)


def novelty(cb: CaseBase, problem: Problem | np.ndarray, scale: float | None = None) -> float:
    values = problem.values if isinstance(problem, Problem) else problem
    d = float(retrieve(cb, values, 1).distances[0])
    return d / (scale if scale is not None else typical_distance(cb))


def benefit(
    cb: CaseBase, problem: Problem | np.ndarray, label: str, k: int, weights: Weights = "distance"
) -> float:
    values = problem.values if isinstance(problem, Problem) else problem
    classes = np.unique(np.append(cb.labels.astype(str), str(label)))
    sol = reuse(retrieve(cb, values, k), classes, weights)
    return float(1.0 - sol.proba[list(classes).index(str(label))])


def retain(
    cb: CaseBase,
    problem: Problem | np.ndarray,
    label: str,
    *,
    k: int = 5,
    novelty_threshold: float = 0.5,
    benefit_threshold: float = 0.2,
    scale: float | None = None,
    source: str = "",
    subject: str | None = None,
) -> RetainDecision:
    """Decide whether to retain, and if so append the case to ``cb`` (in memory)."""
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    nov = novelty(cb, values, scale)
    ben = benefit(cb, values, label, k)
    ok = nov >= novelty_threshold and ben >= benefit_threshold
    why = (
        f"novelty {nov:.3g} {'>=' if nov >= novelty_threshold else '<'} {novelty_threshold:g}, "
        f"benefit {ben:.3g} {'>=' if ben >= benefit_threshold else '<'} {benefit_threshold:g}"
    )
    if ok:
        cb.add(values, label, source=source, subject=subject, origin="retained")
    return RetainDecision(ok, nov, ben, ("retained: " if ok else "not retained: ") + why)


def record_retention(
    tx: StoreTransaction,
    name: str,
    decision: RetainDecision,
    problem: np.ndarray,
    label: str,
    *,
    source: str = "",
    subject: str | None = None,
) -> int | None:
    """Inside ``tx``: log the decision (and add the case, if retained); the new case id."""
    info = tx.case_base(name)
    case_id = None
    if decision.retained:
        case = NewCase(
            str(label),
            np.asarray(problem, dtype=np.float32),
            source=source,
            subject=subject,
            origin="retained",
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
