"""Revise: with the true label of an observation, adjust the case base toward it.

The most similar case decides what changes (an LVQ-style update, Kohonen 1990):

- it has the true label: its problem moves toward the observation by ``rate``
  (``p <- p + rate (q - p)``);
- it has another label and the observation is much closer to it than to any case of the true
  label (``d_wrong < relabel_margin * d_true``): its solution becomes the true label (the case
  was mislabelled or is ambiguous);
- otherwise the nearest case of the true label moves toward the observation.

Every revision is recorded in the store's maintenance log by :func:`record_revision`
(inside the caller's transaction).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from casebase_store import CaseBaseInfo, StaleCaseError
from features.errors import ConfigError

from .casebase import CaseBase
from .problem import Problem
from .retrieve import retrieve

if TYPE_CHECKING:
    from casebase_store import StoreTransaction


@dataclass(frozen=True)
class Revision:
    """What revising does: ``action`` "moved" (the case's problem moves toward the observation
    by ``rate``) or "relabelled"; ``index`` its position in the case base, ``case_id`` its store
    id (-1: not stored)."""

    action: str
    index: int
    case_id: int
    old_label: str
    new_label: str
    distance: float
    reason: str
    rate: float = 0.25


def _check_rate(rate: float) -> None:
    """A move's ``rate`` must be a number in (0, 1]: 0 changes nothing, more overshoots."""
    if (
        isinstance(rate, bool)
        or not isinstance(rate, numbers.Real)
        or not (math.isfinite(float(rate)) and 0.0 < float(rate) <= 1.0)
    ):
        raise ConfigError(f"must be a number in (0, 1], got {rate!r}", "rate")


def plan_revision(
    cb: CaseBase,
    problem: Problem | np.ndarray,
    true_label: str,
    *,
    rate: float = 0.25,
    relabel_margin: float = 0.5,
) -> Revision:
    """The revision the observation ``problem`` labelled ``true_label`` calls for (nothing is
    changed yet: :func:`apply_revision` or :func:`record_revision` carry it out)."""
    _check_rate(rate)
    true_label = str(true_label)
    assert cb.ids is not None
    r = retrieve(cb, problem, 1)  # the fills of features never shown left out, as solve does
    i, d = int(r.indices[0]), float(r.distances[0])
    if cb.labels[i] == true_label:
        why = f"nearest case has the true label {true_label!r}; moved toward the observation "
        return Revision(
            "moved", i, int(cb.ids[i]), true_label, true_label, d, why + f"by {rate:g}", rate
        )
    same = np.flatnonzero(cb.labels == true_label)
    j, dj = -1, np.inf
    if len(same):
        near = retrieve(cb.subset(same), problem, 1)
        j, dj = int(same[near.indices[0]]), float(near.distances[0])
    old = str(cb.labels[i])
    if d < relabel_margin * dj:
        return Revision(
            "relabelled",
            i,
            int(cb.ids[i]),
            old,
            true_label,
            d,
            f"observation labelled {true_label!r} lies at {d:.3g} from this {old!r} case, "
            f"less than {relabel_margin:g} x the nearest {true_label!r} case ({dj:.3g})",
            rate,
        )
    return Revision(
        "moved",
        j,
        int(cb.ids[j]),
        true_label,
        true_label,
        dj,
        f"nearest case was {old!r} (distance {d:.3g}); moved the nearest {true_label!r} case "
        f"toward the observation by {rate:g}",
        rate,
    )


def observed(problem: Problem | np.ndarray) -> np.ndarray:
    """The values of ``problem`` a case is moved toward: NaN where the value is the fill of a
    feature its clip never showed (:meth:`cbr.problem.Problem.measured`), which is no
    observation to move a case toward."""
    if not isinstance(problem, Problem):
        return np.asarray(problem)
    values = np.asarray(problem.values, dtype=np.float64)
    measured = problem.measured()
    if measured is None:
        return values
    return np.where(measured.reshape(values.shape), values, np.nan)


def _moved(p: np.ndarray, observation: np.ndarray, rate: float) -> np.ndarray:
    """Case ``p`` moved by ``rate`` toward ``observation``; where the observation is missing
    (NaN: :func:`observed`) the case keeps its value."""
    obs = np.asarray(observation, dtype=np.float64).reshape(np.shape(p))
    return np.asarray(p + rate * np.where(np.isnan(obs), 0.0, obs - p))


def apply_revision(cb: CaseBase, rev: Revision, observation: np.ndarray) -> None:
    """Carry out ``rev`` on the in-memory case base (``observation``: the problem values,
    NaN where not observed: :func:`observed`)."""
    _check_rate(rev.rate)
    if rev.action == "relabelled":
        cb.set_label(rev.index, rev.new_label)
    elif rev.action == "moved":
        cb.set_problem(rev.index, _moved(cb.problems[rev.index], observation, rev.rate))


def revise(
    cb: CaseBase,
    problem: Problem | np.ndarray,
    true_label: str,
    *,
    rate: float = 0.25,
    relabel_margin: float = 0.5,
) -> Revision:
    """Adjust ``cb`` in place toward the observation ``problem`` labelled ``true_label``."""
    rev = plan_revision(cb, problem, true_label, rate=rate, relabel_margin=relabel_margin)
    apply_revision(cb, rev, observed(problem))
    return rev


def record_revision(
    tx: StoreTransaction, info: CaseBaseInfo, rev: Revision, observation: np.ndarray
) -> np.ndarray | None:
    """Inside ``tx``: write the revision and its maintenance-log entry.

    A move is applied to the case as it is in the store NOW (read and locked in this
    transaction), not to this process's copy: ``p <- p + rate (q - p)`` on the stored ``p``, so
    concurrent revisions of one case all take effect (where ``q`` is NaN, a fill the clip
    never showed: :func:`observed`, ``p`` stays). A case trimmed or relabelled meanwhile
    is neither moved nor relabelled (:class:`StaleCaseError`: the caller reads the cases
    again): the revision was decided on its label as read. Returns the case's new problem
    (None when no problem changed)."""
    _check_rate(rev.rate)
    new = None
    if rev.action in ("moved", "relabelled") and rev.case_id >= 0:
        # a trimmed case no longer takes part in retrieval: revising it would change nothing
        current = tx.read_case(info, rev.case_id)
        if not current.active:
            raise StaleCaseError(
                f"case {rev.case_id} was trimmed by another process since it was read; "
                "nothing was written",
                tx.store.where,
            )
        # a case another process relabelled is no longer the one decided on: a move pulled
        # a case of another activity toward this observation, a relabel undid the other's
        if current.label != rev.old_label:
            raise StaleCaseError(
                f"case {rev.case_id} was relabelled by another process since it was read "
                f"({rev.old_label!r}, now {current.label!r}); nothing was written",
                tx.store.where,
            )
        if rev.action == "moved":
            new = _moved(current.features, observation, rev.rate)
            tx.update_case(info, rev.case_id, features=new)
        else:
            tx.update_case(info, rev.case_id, label=rev.new_label)
    tx.log(
        info,
        "revise",
        case_id=rev.case_id if rev.case_id >= 0 else None,
        reason=f"{rev.action}: {rev.reason}",
    )
    return new
