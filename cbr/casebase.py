"""The in-memory case base: problems, solutions and provenance as arrays, plus the measure's
per-case representations and search index (built once, reused by every query). Loading one
from the store is :mod:`cbr.stored`."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from features.errors import DataError

from .problem import FeatureConfig, Problem, extract_problem
from .similarity import SimilarityMeasure


def subject_of(seq: Any) -> str | None:
    """The subject a clip's metadata names, as text (None when it names none)."""
    subject = seq.metadata.get("subject")
    return None if subject is None else str(subject)


def frames_of(seq: Any) -> tuple[int, int]:
    """The clip's frames in its source recording: ``(start, end)``, end exclusive."""
    start = int(seq.metadata.get("frame_offset", 0))
    return start, start + int(seq.n_frames)


def piece_name(source: str, frames: Sequence[int] | None, origin: str | None = None) -> str:
    """``source`` named with the frames of it a clip is (start, end exclusive; shown with the
    end inclusive, as ``segment``'s table), or alone when the clip is the whole file. A file
    cut from another recording (``origin``, as ``convert`` writes a labelled stretch) counts
    its frames in that recording, and says so."""
    if frames is None:
        return source
    return f"{source} frames {frames[0]}-{frames[1] - 1}" + (f" of {origin}" if origin else "")


def piece_fields(frames: Sequence[int] | None) -> dict[str, Any]:
    """The JSON fields of a clip that is a piece of its file (``classify --json``): its frames
    as ``start_frame`` and ``end_frame`` (end exclusive), the names ``reps``, ``segment`` and
    ``describe`` give a stretch, and as ``frames`` ``[start, end]``, the name kept from before
    (elsewhere ``frames`` is a count); none for a whole file."""
    if frames is None:
        return {}
    start, end = int(frames[0]), int(frames[1])
    return {"frames": [start, end], "start_frame": start, "end_frame": end}


def frame_array(frames: Sequence[tuple[int | None, int | None]]) -> np.ndarray:
    """``(n, 2)`` the frame ranges ``frames`` (start, end exclusive), ``(-1, -1)`` where not
    known."""
    rows = [(-1, -1) if a is None or b is None else (a, b) for a, b in frames]
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def overlapping(query: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: which of the frame ranges ``frames`` ``(n, 2)`` (:func:`frame_array`)
    share a frame with ``query`` ``(2,)``; a range not known overlaps nothing."""
    a, b = int(query[0]), int(query[1])
    if a < 0:
        return np.zeros(len(frames), dtype=bool)
    return np.asarray((frames[:, 0] >= 0) & (frames[:, 0] < b) & (a < frames[:, 1]))


def skeleton_of(seq: Any) -> str:
    """The skeleton the clip was recorded with (before conversion to the canonical one)."""
    return str(seq.metadata.get("source_skeleton", seq.skeleton))


@dataclass(eq=False)
class CaseBase:
    """Cases as arrays: ``problems`` ``(n, *problem_shape)``, ``labels`` ``(n,)``.

    ``ids``: store ids (``-1`` for cases not stored); provenance per case: ``sources`` (the
    clip), ``subjects``, ``origins`` (trained, retained, revised), ``frames`` (start, end) in
    the source recording, ``skeletons``, ``poses`` (the
    :func:`cbr.described.poses_digest` of the clip it was made of, its mirror image's case
    too; "" when not known); ``names``/``words``: the problem's feature columns.
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
    frames: tuple[tuple[int | None, int | None], ...] = ()
    skeletons: tuple[str | None, ...] = ()
    poses: tuple[str, ...] = ()
    reps: np.ndarray | None = None
    _index: Any = field(default=None, repr=False)
    #: what explanations derive from the cases (label profiles, ...): emptied when they change
    cache: dict[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        # float64 problems (a read-only memory-mapped matrix among them) are used in place
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
        self.frames = tuple(self.frames) or ((None, None),) * n
        self.skeletons = tuple(self.skeletons) or (None,) * n
        self.poses = tuple(self.poses) or ("",) * n

    def __len__(self) -> int:
        return len(self.labels)

    def __repr__(self) -> str:
        """What it holds, in a line: its fields hold a name and a word a column and a source
        a case, and its measure learned weights a column (the dataclass's repr of 80 cases
        ran to 100,000 characters)."""
        return (
            f"CaseBase({len(self)} cases of {len(set(self.labels.tolist()))} labels, problems"
            f" {self.problems.shape}, {self.config.level}, {type(self.measure).__name__})"
        )

    def check_not_empty(self, where: str = "case base") -> None:
        """Refuse a case base of no cases (every case trimmed, or a subset of none) where
        cases are compared with: DataError naming ``where``, not numpy's error of an empty
        sequence or a vote of no neighbours."""
        if len(self) == 0:
            raise DataError("the case base holds no cases: nothing to compare with", where)

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
        self.cache.clear()

    def set_problem(self, i: int, values: np.ndarray) -> None:
        """Replace the problem of case ``i`` (its representation follows; the search index is
        rebuilt on next use)."""
        if not self.problems.flags.writeable:  # a mapped matrix: change a copy of it
            self.problems = np.array(self.problems)
        self.problems[i] = np.asarray(values, dtype=np.float64).reshape(self.problems.shape[1:])
        if self.reps is not None:
            if not self.reps.flags.writeable:
                self.reps = np.array(self.reps)
            self.reps[i] = self.measure.represent(self.problems[i][None])[0]
        self._index = None
        self.cache.clear()

    def set_label(self, i: int, label: str) -> None:
        """Replace the solution of case ``i``."""
        self.labels[i] = str(label)
        self.cache.clear()

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
            ids=self.ids[idx],
            sources=tuple(self.sources[i] for i in idx),
            subjects=tuple(self.subjects[i] for i in idx),
            origins=tuple(self.origins[i] for i in idx),
            frames=tuple(self.frames[i] for i in idx),
            skeletons=tuple(self.skeletons[i] for i in idx),
            poses=tuple(self.poses[i] for i in idx),
            reps=None if self.reps is None else self.reps[idx],
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
        frames: tuple[int | None, int | None] = (None, None),
        skeleton: str | None = None,
        poses: str = "",
    ) -> None:
        """Append one case (the search index is rebuilt on next use); ``poses``: the digest of
        the clip it was made of ("" when not known)."""
        assert self.ids is not None
        self.problems = np.concatenate([self.problems, np.asarray(problem)[None]])
        self.labels = np.append(self.labels, np.array([str(label)], dtype=object))
        self.ids = np.append(self.ids, np.int64(case_id))
        self.sources += (source,)
        self.subjects += (subject,)
        self.origins += (origin,)
        self.frames += (frames,)
        self.skeletons += (skeleton,)
        self.poses += (poses,)
        if self.reps is not None:
            self.reps = np.concatenate([self.reps, self.measure.represent(self.problems[-1:])])
        self._index = None
        self.cache.clear()
