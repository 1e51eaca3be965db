"""Retrieve: the k cases most similar to a problem under the case base's measure."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .casebase import CaseBase
from .problem import Problem


@dataclass(frozen=True)
class Retrieval:
    """The k nearest cases, nearest first: positions in the case base, distances ``(k,)``,
    labels ``(k,)`` and store ids ``(k,)``."""

    indices: np.ndarray
    distances: np.ndarray
    labels: np.ndarray
    case_ids: np.ndarray


def retrieve(
    casebase: CaseBase, problem: Problem | np.ndarray, k: int, *, exclude: int | None = None
) -> Retrieval:
    """The ``k`` nearest cases to ``problem`` (``exclude``: a case position to leave out, for
    leave-one-out evaluation)."""
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    measure = casebase.measure
    query = measure.represent_query(values)
    extra = 0 if exclude is None else 1
    idx, dist = measure.nearest(query, casebase.index, int(k) + extra)
    if exclude is not None:
        keep = idx != exclude
        idx, dist = idx[keep][: int(k)], dist[keep][: int(k)]
    assert casebase.ids is not None
    return Retrieval(idx, dist, casebase.labels[idx], casebase.ids[idx])


def nearest_of_other_label(
    casebase: CaseBase, problem: Problem | np.ndarray, label: str
) -> tuple[int, float] | None:
    """Position and distance of the nearest case whose label is not ``label`` (or None)."""
    other = np.flatnonzero(casebase.labels != label)
    if len(other) == 0:
        return None
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    sub = casebase.subset(other)
    idx, dist = sub.measure.nearest(sub.measure.represent_query(values), sub.index, 1)
    return int(other[idx[0]]), float(dist[0])
