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

from dataclasses import dataclass

import numpy as np

from casebase_store import StoreTransaction

from .casebase import CaseBase
from .problem import Problem
from .retrieve import retrieve


@dataclass(frozen=True)
class Revision:
    action: str  # "moved" | "relabelled" | "none"
    index: int  # position in the case base (-1: none)
    case_id: int
    old_label: str
    new_label: str
    distance: float
    reason: str


def revise(
    cb: CaseBase,
    problem: Problem | np.ndarray,
    true_label: str,
    *,
    rate: float = 0.25,
    relabel_margin: float = 0.5,
) -> Revision:
    """Adjust ``cb`` in place toward the observation ``problem`` labelled ``true_label``."""
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    true_label = str(true_label)
    assert cb.ids is not None
    r = retrieve(cb, values, 1)
    i, d = int(r.indices[0]), float(r.distances[0])
    if cb.labels[i] == true_label:
        target, reason = i, f"nearest case has the true label {true_label!r}; moved toward the "
        reason += f"observation by {rate:g}"
    else:
        same = np.flatnonzero(cb.labels == true_label)
        if len(same):
            near = retrieve(cb.subset(same), values, 1)
            j, dj = int(same[near.indices[0]]), float(near.distances[0])
        else:
            j, dj = -1, np.inf
        if d < relabel_margin * dj:
            old = str(cb.labels[i])
            cb.labels[i] = true_label
            return Revision(
                "relabelled",
                i,
                int(cb.ids[i]),
                old,
                true_label,
                d,
                f"observation labelled {true_label!r} lies at {d:.3g} from this {old!r} case, "
                f"less than {relabel_margin:g} x the nearest {true_label!r} case ({dj:.3g})",
            )
        target = j
        d = dj
        reason = (
            f"nearest case was {str(cb.labels[i])!r} (distance {float(r.distances[0]):.3g}); "
            f"moved the nearest {true_label!r} case toward the observation by {rate:g}"
        )
    cb.problems[target] = cb.problems[target] + rate * (values - cb.problems[target])
    if cb.reps is not None:
        cb.reps[target] = cb.measure.represent(cb.problems[target][None])[0]
    cb._index = None
    lab = str(cb.labels[target])
    return Revision("moved", target, int(cb.ids[target]), lab, lab, d, reason)


def record_revision(tx: StoreTransaction, name: str, cb: CaseBase, rev: Revision) -> None:
    """Inside ``tx``: write the revised case and its maintenance-log entry."""
    info = tx.case_base(name)
    if rev.action == "moved" and rev.case_id >= 0:
        tx.update_case(rev.case_id, features=cb.problems[rev.index].astype(np.float32))
    elif rev.action == "relabelled" and rev.case_id >= 0:
        tx.update_case(rev.case_id, label=rev.new_label)
    tx.log(
        info,
        "revise",
        case_id=rev.case_id if rev.case_id >= 0 else None,
        reason=f"{rev.action}: {rev.reason}",
    )
