"""Retrieve: the k cases most similar to a problem under the case base's measure."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from features.errors import ConfigError

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


def _check_k(k: int) -> None:
    if isinstance(k, bool) or not isinstance(k, int | np.integer) or k < 1:
        raise ConfigError(f"must be a whole number >= 1, got {k!r}", "k")


def retrieve(
    casebase: CaseBase, problem: Problem | np.ndarray, k: int, *, exclude: int | None = None
) -> Retrieval:
    """The ``k`` nearest cases to ``problem`` (``exclude``: a case position to leave out, for
    leave-one-out evaluation)."""
    _check_k(k)
    casebase.check_not_empty()
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


def retrieve_many(
    casebase: CaseBase, problems: Sequence[Problem | np.ndarray], k: int
) -> list[Retrieval]:
    """:func:`retrieve` for every problem at once: one ``nearest_many`` call, which a measure
    may batch (Euclidean: one matrix product per block of queries), with the same neighbours,
    in the same order, as one :func:`retrieve` per problem."""
    _check_k(k)
    casebase.check_not_empty()
    if not problems:
        return []
    measure = casebase.measure
    queries = np.stack(
        [
            measure.represent_query(p.values if isinstance(p, Problem) else np.asarray(p))
            for p in problems
        ]
    )
    idx, dist = measure.nearest_many(queries, casebase.index, int(k))
    assert casebase.ids is not None
    return [
        Retrieval(i, d, casebase.labels[i], casebase.ids[i]) for i, d in zip(idx, dist, strict=True)
    ]


def nearest_of_other_label(
    casebase: CaseBase, problem: Problem | np.ndarray, label: str
) -> tuple[int, float] | None:
    """Position and distance of the nearest case whose label is not ``label`` (or None).

    Widens an exact k-nearest search on the whole case base (8, 32, 128, ... cases) until a
    case of another label shows up, so the search index is reused, never rebuilt."""
    other = casebase.labels != label
    if not other.any():
        return None
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    query = casebase.measure.represent_query(values)
    k = 8
    while True:
        idx, dist = casebase.measure.nearest(query, casebase.index, min(k, len(casebase)))
        hit = np.flatnonzero(other[idx])
        if len(hit):
            return int(idx[hit[0]]), float(dist[hit[0]])
        k *= 4
