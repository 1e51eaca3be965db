"""The similarity-measure plug-in interface (its registry: :mod:`cbr.similarity.registry`).

A measure is a small frozen dataclass: configuration in fields, computation in methods that
compare ONE query against the WHOLE case base as array work. The life cycle:

1. ``represent(problems)``: per-case representation, ``(n_cases, ...)``; stored in the case
   base store under ``cache_kind(problem_shape)`` (``None`` = not worth caching);
2. ``build_index(reps)``: in-memory acceleration structures (norms, envelopes); default: reps;
3. ``represent_query(problem)`` then ``distances(query_rep, index)`` -> ``(n_cases,)`` and
   ``nearest(query_rep, index, k)`` -> the k nearest (indices, distances), ties broken by the
   lower case index so every measure's neighbours are deterministic; ``nearest_many`` the
   same for a batch of queries (default: a loop; a measure may batch the work).

Adding a measure (nothing else changes)::

    from dataclasses import dataclass
    import numpy as np
    from cbr.similarity import SimilarityMeasure, register_measure

    @register_measure("manhattan")
    @dataclass(frozen=True)
    class Manhattan(SimilarityMeasure):
        '''Sum of absolute differences over the flattened problem.'''
        def represent(self, problems):
            return problems.reshape(len(problems), -1)
        def distances(self, query_rep, index):
            return np.abs(index - query_rep).sum(axis=1)

Import the module before use (or expose it as an entry point in the group
``posecbr.similarity``); ``get_measure("manhattan")``, ``CaseBaseClassifier(similarity=
"manhattan")`` and ``posecbr train --similarity manhattan`` then find it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from features.errors import ConfigError
from features.text import dataclass_line

# The registry lives in its own module (no numpy) so naming the measures costs nothing; these
# names stay importable from here.
from .registry import available_measures, get_measure, register_measure

__all__ = [
    "SimilarityMeasure",
    "available_measures",
    "check_weighting",
    "get_measure",
    "register_measure",
    "smallest_k",
    "weighted",
]


@dataclass(frozen=True)
class SimilarityMeasure:
    """Base class of similarity measures (distances: smaller = more similar)."""

    name: ClassVar[str] = ""
    # True for measures that align sequences (a QMP vector, one per clip, has nothing to align)
    compares_sequences: ClassVar[bool] = False
    # True for measures whose distances_measured leaves a query's unmeasured values out
    leaves_out: ClassVar[bool] = False

    def cache_kind(self, problem_shape: tuple[int, ...]) -> str | None:
        """Key under which per-case representations are cached in the store (None: don't)."""
        del problem_shape  # part of the plug-in interface: DTW's key depends on the length
        return None

    def represent(self, problems: np.ndarray) -> np.ndarray:
        """Per-case representation of problems ``(n, *problem_shape)`` -> ``(n, ...)``."""
        return np.asarray(problems, dtype=np.float64)

    def build_index(self, reps: np.ndarray) -> Any:
        """In-memory search structure over all cases' representations."""
        return reps

    def represent_query(self, problem: np.ndarray) -> np.ndarray:
        """Representation of one query problem ``problem_shape`` -> one row of ``represent``."""
        row: np.ndarray = self.represent(np.asarray(problem, dtype=np.float64)[None])[0]
        return row

    def distances(self, query_rep: np.ndarray, index: Any) -> np.ndarray:
        """Distances from the query to every case, ``(n_cases,)``."""
        raise NotImplementedError

    def nearest(self, query_rep: np.ndarray, index: Any, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The ``k`` nearest cases: (indices ``(k,)``, distances ``(k,)``), nearest first."""
        d = self.distances(query_rep, index)
        return smallest_k(d, k)

    def nearest_many(
        self, query_reps: np.ndarray, index: Any, k: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`nearest` for each of ``m`` queries (rows of ``represent``): indices and
        distances ``(m, k)``. Measures override it when a batch is cheaper than a loop."""
        found = [self.nearest(q, index, k) for q in query_reps]
        kk = min(int(k), len(found[0][0])) if found else 0
        idx = np.array([f[0] for f in found], dtype=np.int64).reshape(len(found), kk)
        dist = np.array([f[1] for f in found], dtype=np.float64).reshape(len(found), kk)
        return idx, dist

    def distances_measured(
        self, query_rep: np.ndarray, index: Any, measured: np.ndarray
    ) -> np.ndarray:
        """:meth:`distances` over the query's measured values alone: ``measured``
        ``(problem size,)`` bool, False for a fill of a feature the query never showed
        (:meth:`cbr.problem.Problem.measured`). A measure that can leave values out
        (:attr:`leaves_out`) compares the rest, scaled to all of them; this default compares
        every value, the fills too, as before the query's fills were known."""
        del measured  # part of the plug-in interface: a measure that aligns cannot drop values
        return self.distances(query_rep, index)

    def nearest_measured(
        self, query_rep: np.ndarray, index: Any, k: int, measured: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`nearest` by :meth:`distances_measured` (ties to the lower index)."""
        return smallest_k(self.distances_measured(query_rep, index, measured), k)

    def params(self) -> dict[str, Any]:
        """The measure as data: ``{"name": ..., field: value, ...}`` (JSON-able)."""
        return {"name": self.name, **dataclasses.asdict(self)}

    def __repr__(self) -> str:
        """Its fields in one line, learned weights by their count (:func:`dataclass_line`):
        a measure with the weights ``fit`` learned ran to tens of thousands of characters, one
        value of each of two weights per column. A measure declared ``@dataclass(repr=False)``
        inherits it (the ones here are)."""
        return dataclass_line(self)


def check_weighting(
    centre: tuple[float, ...] | None, multiplier: tuple[float, ...] | None, measure: str
) -> None:
    """Validate a measure's learned feature weighting (both or neither, same length)."""
    if (centre is None) != (multiplier is None):
        raise ConfigError("centre and multiplier go together", f"similarity {measure}")
    if centre is not None and multiplier is not None and len(centre) != len(multiplier):
        raise ConfigError(
            f"centre has {len(centre)} values but multiplier {len(multiplier)}",
            f"similarity {measure}",
        )


def check_whole(measure: str, **values: object) -> None:
    """Refuse a count parameter (a band radius in frames, a signature depth, threads, ...)
    that is not a whole number: ``--param radius=2.5`` was read as 2 without a word. ``None``
    (the parameter left to its default rule) passes."""
    for name, value in values.items():
        if value is None:
            continue
        whole = isinstance(value, int | np.integer) and not isinstance(value, bool)
        if not whole and not (isinstance(value, float | np.floating) and float(value).is_integer()):
            raise ConfigError(
                f"{name} must be a whole number, got {value!r}", f"similarity {measure}"
            )


def weighted(
    x: np.ndarray,
    centre: tuple[float, ...] | None,
    multiplier: tuple[float, ...] | None,
    measure: str,
) -> np.ndarray:
    """``(x - centre) * multiplier`` over the last axis of ``x`` ``(..., D)`` (float64)."""
    c = np.asarray(centre, dtype=np.float64)
    m = np.asarray(multiplier, dtype=np.float64)
    if x.shape[-1] != len(m):
        raise ConfigError(
            f"the weighting has {len(m)} columns but the problems have {x.shape[-1]}",
            f"similarity {measure}",
        )
    return (np.asarray(x, dtype=np.float64) - c) * m


def smallest_k(d: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices and values of the ``k`` smallest of ``d``; ties go to the lower index."""
    k = min(int(k), len(d))
    if k <= 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    if k < len(d):
        kth = np.partition(d, k - 1)[k - 1]
        cand = np.flatnonzero(d <= kth)  # every tie of the k-th value stays a candidate
    else:
        cand = np.arange(len(d))
    order = np.lexsort((cand, d[cand]))[:k]
    idx = cand[order].astype(np.int64)
    return idx, d[idx]
