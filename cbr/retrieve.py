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


def _measured(casebase: CaseBase, problem: Problem | np.ndarray) -> np.ndarray | None:
    """Which of a problem's values were measured, for a measure that can leave the rest out
    (None: all, a bare array of values, or a measure that compares every value): the fills
    of features the clip never showed are left out of its distances."""
    if not isinstance(problem, Problem) or not casebase.measure.leaves_out:
        return None
    return problem.measured()


def _nearest(
    casebase: CaseBase, problem: Problem | np.ndarray, k: int, measured: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` nearest cases to ``problem`` over its ``measured`` values (:func:`_measured`)."""
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    measure = casebase.measure
    query = measure.represent_query(values)
    if measured is None:
        return measure.nearest(query, casebase.index, k)
    return measure.nearest_measured(query, casebase.index, k, measured)


def query_distances(casebase: CaseBase, problem: Problem | np.ndarray) -> np.ndarray:
    """``(n_cases,)`` the distance from ``problem`` to every case, over its measured values
    (the distances :func:`retrieve` ranks)."""
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    measure = casebase.measure
    query = measure.represent_query(values)
    measured = _measured(casebase, problem)
    if measured is None:
        return measure.distances(query, casebase.index)
    return measure.distances_measured(query, casebase.index, measured)


def retrieve(
    casebase: CaseBase, problem: Problem | np.ndarray, k: int, *, exclude: int | None = None
) -> Retrieval:
    """The ``k`` nearest cases to ``problem`` (``exclude``: a case position to leave out, for
    leave-one-out evaluation). The fills of features the problem's clip never showed
    (``Problem.unseen``) are left out of the distance where the measure can leave values
    out (:meth:`cbr.similarity.base.SimilarityMeasure.distances_measured`)."""
    _check_k(k)
    casebase.check_not_empty()
    extra = 0 if exclude is None else 1
    idx, dist = _nearest(casebase, problem, int(k) + extra, _measured(casebase, problem))
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
    in the same order, as one :func:`retrieve` per problem (a problem with fills left out
    is searched on its own)."""
    _check_k(k)
    casebase.check_not_empty()
    if not problems:
        return []
    measure = casebase.measure
    measured = [_measured(casebase, p) for p in problems]
    whole = [i for i, m in enumerate(measured) if m is None]
    found: dict[int, tuple[np.ndarray, np.ndarray]] = {
        i: _nearest(casebase, problems[i], int(k), m)
        for i, m in enumerate(measured)
        if m is not None
    }  # problems with fills left out: one pass each
    if whole:
        queries = np.stack(
            [
                measure.represent_query(p.values if isinstance(p, Problem) else np.asarray(p))
                for p in (problems[i] for i in whole)
            ]
        )
        many = measure.nearest_many(queries, casebase.index, int(k))
        found.update((i, (many[0][j], many[1][j])) for j, i in enumerate(whole))
    idx = [found[i][0] for i in range(len(problems))]
    dist = [found[i][1] for i in range(len(problems))]
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
    if _measured(casebase, problem) is not None:  # one pass over the measured values
        d = query_distances(casebase, problem)
        pos = np.flatnonzero(other)
        best = int(pos[np.argmin(d[pos])])  # argmin: ties to the lower case
        return best, float(d[best])
    values = problem.values if isinstance(problem, Problem) else np.asarray(problem)
    query = casebase.measure.represent_query(values)
    k = 8
    while True:
        idx, dist = casebase.measure.nearest(query, casebase.index, min(k, len(casebase)))
        hit = np.flatnonzero(other[idx])
        if len(hit):
            return int(idx[hit[0]]), float(dist[hit[0]])
        k *= 4
