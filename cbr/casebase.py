"""The in-memory case base: problems, solutions and provenance as arrays, plus the measure's
per-case representations and search index (built once, reused by every query)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from casebase_store import CaseStore, NewCase
from features.errors import DataError

from .problem import FeatureConfig, Problem, extract_problem
from .similarity import SimilarityMeasure, get_measure


def subject_of(seq: Any) -> str | None:
    """The subject a clip's metadata names, as text (None when it names none)."""
    subject = seq.metadata.get("subject")
    return None if subject is None else str(subject)


@dataclass(eq=False)
class CaseBase:
    """Cases as arrays: ``problems`` ``(n, *problem_shape)``, ``labels`` ``(n,)``.

    ``ids``: store ids (``-1`` for cases not stored); ``sources``/``subjects``/``origins``:
    provenance per case; ``names``/``words``: the problem's feature columns.
    """

    config: FeatureConfig
    measure: SimilarityMeasure
    problems: np.ndarray
    labels: np.ndarray
    names: tuple[str, ...]
    words: tuple[str, ...]
    ids: np.ndarray | None = None
    sources: tuple[str, ...] = ()
    subjects: tuple[str | None, ...] = ()
    origins: tuple[str, ...] = ()
    reps: np.ndarray | None = None
    _index: Any = field(default=None, repr=False)

    def __post_init__(self) -> None:
        self.problems = np.asarray(self.problems, dtype=np.float64)
        self.labels = np.asarray([str(v) for v in self.labels], dtype=object)
        n = len(self.labels)
        if len(self.problems) != n:
            raise DataError(f"{len(self.problems)} problems but {n} labels", "case base")
        if self.ids is None:
            self.ids = np.full(n, -1, dtype=np.int64)
        self.sources = tuple(self.sources) or ("",) * n
        self.subjects = tuple(self.subjects) or (None,) * n
        self.origins = tuple(self.origins) or ("trained",) * n

    def __len__(self) -> int:
        return len(self.labels)

    @property
    def classes(self) -> np.ndarray:
        return np.unique(self.labels)

    @property
    def index(self) -> Any:
        """The measure's search index over all cases (built on first use)."""
        if self._index is None:
            if self.reps is None:
                self.reps = self.measure.represent(self.problems)
            self._index = self.measure.build_index(self.reps)
        return self._index

    def problem_of(self, seq: Any) -> Problem:
        """The problem of a new clip ``seq`` (a PoseSequence) in this case base's columns: the
        configured features, plus a 0 in the mirror-image column when the case base has one."""
        from .weights import MIRROR_FLAG, with_mirror_flag

        p = extract_problem(seq, self.config)
        if self.names and self.names[-1] == MIRROR_FLAG:
            p = with_mirror_flag(p, 0.0)
        return p

    def invalidate(self) -> None:
        self.reps = None
        self._index = None

    def subset(self, keep: np.ndarray | Sequence[int]) -> CaseBase:
        """The case base restricted to ``keep`` (bool mask or indices), reps reused."""
        idx = np.flatnonzero(keep) if np.asarray(keep).dtype == bool else np.asarray(keep, int)
        assert self.ids is not None
        return CaseBase(
            self.config,
            self.measure,
            self.problems[idx],
            self.labels[idx],
            self.names,
            self.words,
            self.ids[idx],
            tuple(self.sources[i] for i in idx),
            tuple(self.subjects[i] for i in idx),
            tuple(self.origins[i] for i in idx),
            None if self.reps is None else self.reps[idx],
        )

    def add(
        self,
        problem: np.ndarray,
        label: str,
        *,
        case_id: int = -1,
        source: str = "",
        subject: str | None = None,
        origin: str = "retained",
    ) -> None:
        """Append one case (the search index is rebuilt on next use)."""
        assert self.ids is not None
        self.problems = np.concatenate([self.problems, np.asarray(problem)[None]])
        self.labels = np.append(self.labels, np.array([str(label)], dtype=object))
        self.ids = np.append(self.ids, np.int64(case_id))
        self.sources += (source,)
        self.subjects += (subject,)
        self.origins += (origin,)
        if self.reps is not None:
            self.reps = np.concatenate([self.reps, self.measure.represent(problem[None])])
        self._index = None

    def new_cases(self, origin: str = "trained") -> list[NewCase]:
        """The cases as store records (provenance kept)."""
        return [
            NewCase(
                label=str(self.labels[i]),
                features=self.problems[i].astype(np.float32),
                source=self.sources[i],
                subject=self.subjects[i],
                origin=origin,
            )
            for i in range(len(self))
        ]

    @classmethod
    def from_store(
        cls, store: CaseStore, name: str, measure: SimilarityMeasure | None = None
    ) -> CaseBase:
        """Load a stored case base; per-case representations come from the store's cache
        (missing ones are computed and cached in one transaction)."""
        info = store.get_case_base(name)
        config = FeatureConfig.from_dict(info.feature_config)
        measure = measure or get_measure(info.similarity)
        arrays = store.load_cases(name)
        if len(arrays.ids) == 0:
            raise DataError(f"case base {name!r} has no cases", store.where)
        cb = cls(
            config,
            measure,
            arrays.features,
            arrays.labels,
            info.feature_names,
            info.feature_words,
            arrays.ids,
            arrays.sources,
            arrays.subjects,
            arrays.origins,
        )
        kind = measure.cache_kind(tuple(arrays.features.shape[1:]))
        if kind is not None:
            cached = store.load_representations(name, kind)
            missing = [i for i, cid in enumerate(arrays.ids) if int(cid) not in cached]
            if missing:
                new = measure.represent(arrays.features[missing])
                with store.transaction() as tx:
                    tx.put_representations(
                        kind, {int(arrays.ids[i]): new[j] for j, i in enumerate(missing)}
                    )
                for j, i in enumerate(missing):
                    cached[int(arrays.ids[i])] = new[j]
            cb.reps = np.stack([cached[int(cid)] for cid in arrays.ids]).astype(np.float64)
        return cb
