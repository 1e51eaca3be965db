"""How unlike the stored cases a clip is, calibrated on the case base itself.

A new clip's *novelty* is the distance to its nearest case divided by the case base's usual
held-out nearest-case distance (the ``scale``: the median over held-out training clips, exact
matches left out, so binary QMP vectors, whose held-out clips often match a case exactly, get a
usable unit). It is *unlike the stored cases* when

- its nearest case is farther than the ``quantile`` of the held-out training clips'
  nearest-case distances (``"distance"``); or
- its summary features leave the range the cases span in more of the features than held-out
  training clips of its answer do (``"features"``, :class:`FeatureRanges`): a
  measure-independent score, which sees what a distance averages away (a movement the case
  base knows, done with joints that sit where no case's did). The features are the fluent
  summary fluents/euclidean's problem is (:data:`DESCRIPTION`: fluent confidences, joint
  angles and positions, their mean, lowest, highest and spread over the clip) in every
  configuration: a dtw or signature sequence of those columns summarised over time
  (:func:`summary`) is that summary already; beside a QMP vector (or a sequence of other
  columns) it is computed from the clip, so "unlike the stored cases" looks at the same
  features whatever the measure (case bases stored before this summarise their own problems
  and are judged so); or
- it was recorded with a skeleton (sensor) none of the training clips was recorded with
  (``"sensor"``): the joints of another sensor sit elsewhere on the body, so its clips are
  not comparable with the cases however near they look.

With both scores each flags beyond its own 0.995 quantile (:data:`SHARED_QUANTILE`), so
together they keep about the false alarms one at 0.99 had.

Held out means what a new person is: with subjects known, each training clip's nearest case
among the OTHER subjects' cases (leave-one-subject-out); otherwise among the cases of other
clips (leave-one-out; a clip's own mirror image does not count). The calibration is learned in
``fit`` for whatever feature level and measure the case base uses, and stored with it, so the
flag means the same for every configuration.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .casebase import CaseBase
from .problem import FeatureConfig, candidate_config, extract_problem

#: the clip description the feature score judges whatever the case base's own problem: the
#: fluent summary that fluents/euclidean's problem is (its default columns: angle fluents,
#: joint angles and positions; mean, lowest, highest, variation over 32 frames; no phase
#: means), resolved by the training clips' available columns
DESCRIPTION = FeatureConfig("fluents", states="angles", angles=True, positions=True,
                            summary=True)  # fmt: skip
#: held-out clips whose nearest-case distance is below this quantile are "like the cases"
UNLIKE_QUANTILE = 0.99
#: the quantile of each of the two scores (distance, features) when both flag: they share the
#: false-alarm budget of one at :data:`UNLIKE_QUANTILE`
SHARED_QUANTILE = 0.995
#: reference sets the feature ranges are kept for: held-out groups are pooled into at most
#: this many folds (a clip held out is compared with the ranges of the other folds' cases)
RANGE_FOLDS = 8
#: held-out clips' weight of the global scale in each label's own (a label with this many
#: clips takes half its scale from its own clips, half from all)
LABEL_PRIOR = 5.0
#: training clips used to calibrate (a seeded sample: the distances cost a full scan each)
CALIBRATION_SAMPLE = 256
#: held-out distances below this share of the largest one are exact matches
EXACT_SHARE = 1e-3


def own_description(config: FeatureConfig) -> bool:
    """Whether a case base of ``config`` is judged on its own problems rather than on
    :data:`DESCRIPTION` computed beside them: a fluent summary already (fluents/euclidean),
    or a fluent sequence of the description's columns and length (dtw and signature with the
    default columns), whose :func:`summary` is the description itself."""
    if config.level != "fluents":
        return False
    if config.summary:
        return True
    return int(config.length) == int(DESCRIPTION.length) and tuple(
        candidate_config(config).states
    ) == tuple(candidate_config(DESCRIPTION).states)


def describe(seq: Any, description: FeatureConfig) -> np.ndarray:
    """The description ``(F,)`` of the clip ``seq`` ``(frames, joints, 3)`` under a resolved
    ``description`` (:data:`DESCRIPTION`'s columns): what the feature score judges."""
    return extract_problem(seq, description).values


def summary(values: np.ndarray) -> np.ndarray:
    """The summary features of one problem: a vector ``(n,)`` as it is, a sequence
    ``(length, n)`` as its columns' mean, minimum, maximum and standard deviation over time
    ``(4 n,)`` (missing values left out; a column missing throughout stays NaN)."""
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 1:
        return v
    with warnings.catch_warnings():  # a column missing throughout: NaN, as it should
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.concatenate([np.nanmean(v, 0), np.nanmin(v, 0), np.nanmax(v, 0), np.nanstd(v, 0)])


def summaries(problems: np.ndarray) -> np.ndarray:
    """:func:`summary` of every problem ``(n, *problem_shape)``: ``(n, features)``."""
    p = np.asarray(problems, dtype=np.float64)
    if p.ndim == 2:
        return p
    return np.stack([summary(x) for x in p]) if len(p) else np.zeros((0, 4 * p.shape[-1]))


def outside_share(s: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The share of features of ``s`` ``(..., F)`` outside ``[lo, hi]`` ``(..., F)`` (a
    missing value, or a feature no case has, is not outside)."""
    out = (s < lo) | (s > hi)
    return np.asarray(out.mean(axis=-1), dtype=np.float64)


@dataclass(frozen=True, eq=False)
class FeatureRanges:
    """How far outside the cases' feature ranges a clip is, against held-out training clips.

    ``lo``/``hi`` ``(folds, F)``: per fold, the smallest and largest summary feature of the
    cases of the OTHER folds (the groups: subjects, recordings or clips, pooled into at most
    :data:`RANGE_FOLDS` folds). A clip's *outside share* is the share of its features outside
    a fold's range, averaged over the folds: each range is one that a held-out training clip
    was compared with (its own fold's), so a new clip is scored as they were. ``scales``:
    per label, the typical outside share of held-out clips of that label (their median,
    shrunk toward all clips' by :data:`LABEL_PRIOR`; at least one feature's share), and
    ``default`` for a label not among them; ``unlike_ratio``: the ``quantile`` of held-out
    clips' outside share over their label's scale, beyond which a clip is unlike the cases.
    ``description``: the resolved fluent summary (:data:`DESCRIPTION`) a clip is described by
    for the score, computed from the clip beside the case base's problem; None: the summary of
    the problem itself (fluents/euclidean, and case bases stored before descriptions)."""

    lo: np.ndarray
    hi: np.ndarray
    labels: tuple[str, ...]
    scales: tuple[float, ...]
    default: float
    unlike_ratio: float
    quantile: float
    description: FeatureConfig | None = None

    def outside(self, s: np.ndarray) -> float:
        """The outside share of one clip's summary ``s`` ``(F,)``."""
        s = np.asarray(s, dtype=np.float64)
        if s.shape[-1] != self.lo.shape[-1]:
            return 0.0  # a problem of other columns (not this case base's): no score
        return float(outside_share(s[None, :], self.lo, self.hi).mean())

    def scale(self, label: str) -> float:
        where = dict(zip(self.labels, self.scales, strict=True))
        return where.get(str(label), self.default)

    def ratio(self, s: np.ndarray, label: str) -> float:
        """The outside share in units of held-out clips of ``label``."""
        return self.outside(s) / self.scale(label)

    def unlike(self, s: np.ndarray, label: str) -> bool:
        return self.ratio(s, label) > self.unlike_ratio

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, FeatureRanges):
            return NotImplemented
        return (
            np.array_equal(self.lo, other.lo, equal_nan=True)
            and np.array_equal(self.hi, other.hi, equal_nan=True)
            and (self.labels, self.scales, self.default, self.unlike_ratio, self.quantile,
                 self.description)
            == (other.labels, other.scales, other.default, other.unlike_ratio, other.quantile,
                other.description)
        )  # fmt: skip

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN, a feature no case of the other folds has, stored as None)."""
        d = {"lo": _nan_none(self.lo), "hi": _nan_none(self.hi), "labels": list(self.labels),
             "scales": list(self.scales), "default": self.default,
             "unlike_ratio": self.unlike_ratio, "quantile": self.quantile}  # fmt: skip
        if self.description is not None:
            d["description"] = self.description.to_dict()
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> FeatureRanges:
        lo = np.array(d["lo"], dtype=np.float64)
        hi = np.array(d["hi"], dtype=np.float64)
        labels = tuple(str(v) for v in d["labels"])
        scales = tuple(float(v) for v in d["scales"])
        if lo.shape != hi.shape or lo.ndim != 2 or len(labels) != len(scales):
            raise ValueError("feature ranges must be paired (folds, features) arrays")
        described = d.get("description")
        return cls(lo, hi, labels, scales, float(d["default"]), float(d["unlike_ratio"]),
                   float(d["quantile"]),
                   FeatureConfig.from_dict(described) if described else None)  # fmt: skip


def _nan_none(a: np.ndarray) -> list[list[float | None]]:
    """``(r, c)`` as nested lists, NaN as None (JSON has no NaN)."""
    return [[None if np.isnan(v) else float(v) for v in row] for row in a]


def fold_of(groups: np.ndarray, folds: int = RANGE_FOLDS, seed: int = 0) -> np.ndarray:
    """Each item's fold ``(n,)``: its group's, the groups dealt into at most ``folds`` folds
    in a seeded order (all items of a group in one fold)."""
    names = sorted({str(g) for g in groups})
    order = np.random.default_rng(seed).permutation(len(names))
    where = {names[j]: i % min(folds, len(names)) for i, j in enumerate(order)}
    return np.array([where[str(g)] for g in groups], dtype=np.int64)


def fit_ranges(
    cases: np.ndarray,
    case_groups: np.ndarray,
    queries: np.ndarray,
    groups: np.ndarray,
    labels: Sequence[str] | np.ndarray,
    quantile: float = SHARED_QUANTILE,
    description: FeatureConfig | None = None,
) -> FeatureRanges | None:
    """The feature ranges of ``cases`` ``(m, F)`` (summaries, group ``case_groups`` ``(m,)``)
    calibrated on the training clips ``queries`` ``(n, F)`` (group ``groups`` ``(n,)``,
    label ``labels``), each scored against the cases of the other folds; ``description``: the
    configuration the summaries were computed with (None: the problems' own). None when the
    cases form fewer than two groups (nothing to hold out)."""
    everyone = np.concatenate([np.asarray(case_groups, dtype=object),
                               np.asarray(groups, dtype=object)])  # fmt: skip
    fold = fold_of(everyone)
    case_fold, query_fold = fold[: len(cases)], fold[len(cases) :]
    k = int(fold.max()) + 1 if len(fold) else 0
    if k < 2:
        return None
    with warnings.catch_warnings():  # a feature no case of the other folds has: NaN, no range
        warnings.simplefilter("ignore", RuntimeWarning)
        lo = np.stack([np.nanmin(cases[case_fold != f], axis=0) for f in range(k)])
        hi = np.stack([np.nanmax(cases[case_fold != f], axis=0) for f in range(k)])
    held = outside_share(queries, lo[query_fold], hi[query_fold])
    floor = 1.0 / max(cases.shape[-1], 1)  # one feature's share: no scale of 0
    text = np.asarray([str(v) for v in labels], dtype=object)
    default = max(float(np.median(held)), floor)
    names = tuple(sorted(set(text.tolist())))
    scales = []
    for name in names:
        mine = held[text == name]
        shrunk = (len(mine) * float(np.median(mine)) + LABEL_PRIOR * default) / (
            len(mine) + LABEL_PRIOR
        )
        scales.append(max(shrunk, floor))
    per = dict(zip(names, scales, strict=True))
    ratios = held / np.array([per[v] for v in text])
    return FeatureRanges(lo, hi, names, tuple(scales), default,
                         float(np.quantile(ratios, quantile)), quantile, description)  # fmt: skip


@dataclass(frozen=True)
class NoveltyCalibration:
    """scale: median held-out nearest-case distance (exact matches left out); unlike_ratio:
    the ``quantile`` of the held-out distances, in units of ``scale``, above which a clip is
    flagged; basis: how the training clips were held out; n: how many were; skeletons: the
    skeletons (sensors) the training clips were recorded with (empty: not known); features:
    the summary features' ranges (None: the distance alone, as case bases stored before
    them)."""

    scale: float
    unlike_ratio: float
    quantile: float
    basis: str
    n: int
    skeletons: tuple[str, ...] = ()
    features: FeatureRanges | None = field(default=None, compare=True)

    def ratio(self, distance: float) -> float:
        """Nearest-case distance in units of the case base's usual one."""
        return float(distance) / self.scale if self.scale > 0 else float("inf")

    def reason(
        self,
        distance: float,
        skeleton: str | None = None,
        values: np.ndarray | None = None,
        label: str | None = None,
    ) -> str:
        """Why a clip is unlike the stored cases: ``"sensor"`` (recorded with a skeleton no
        training clip was), else :meth:`measured` with its problem ``values`` (vector or
        sequence) and answer ``label``."""
        if skeleton is not None and self.skeletons and skeleton not in self.skeletons:
            return "sensor"
        return self.measured(distance, values, label)

    def measured(
        self, distance: float, values: np.ndarray | None = None, label: str | None = None
    ) -> str:
        """Why a clip is unlike the stored cases by what it shows, the sensor aside:
        ``"distance"`` (its nearest case is farther than held-out clips' are), ``"features"``
        (its summary features leave the cases' ranges more than held-out clips of its answer
        ``label`` do; only with ``values``, the clip's :attr:`FeatureRanges.description` when
        the ranges have one, else its problem, and ``label``) or ``""`` (neither)."""
        by_distance, by_features = self.scores(distance, values, label)
        return "distance" if by_distance else "features" if by_features else ""

    def scores(
        self, distance: float, values: np.ndarray | None = None, label: str | None = None
    ) -> tuple[bool, bool]:
        """Whether each score alone flags the clip (:meth:`measured`): the nearest-case
        ``distance`` and the summary features of ``values`` for the answer ``label``."""
        by_distance = self.ratio(distance) > self.unlike_ratio
        by_features = (
            self.features is not None
            and values is not None
            and label is not None
            and self.features.unlike(summary(values), label)
        )
        return by_distance, bool(by_features)

    @property
    def description(self) -> FeatureConfig | None:
        """The clip description the feature score judges (None: the problem itself)."""
        return None if self.features is None else self.features.description

    def unlike(self, distance: float, skeleton: str | None = None) -> bool:
        return bool(self.reason(distance, skeleton))

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"scale": self.scale, "unlike_ratio": self.unlike_ratio,
                             "quantile": self.quantile, "basis": self.basis, "n": self.n,
                             "skeletons": list(self.skeletons)}  # fmt: skip
        if self.features is not None:
            d["features"] = self.features.to_dict()
        return d

    def describe(self) -> dict[str, Any]:
        """:meth:`to_dict` without the feature ranges' arrays (what a person reads)."""
        d = self.to_dict()
        if self.features is not None:
            f = self.features
            d["features"] = {"unlike_ratio": f.unlike_ratio, "quantile": f.quantile,
                             "folds": int(f.lo.shape[0]), "features": int(f.lo.shape[1]),
                             "default_scale": f.default,
                             "described_by": "the case base's problems" if f.description is None
                             else f.description.describe()}  # fmt: skip
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NoveltyCalibration:
        return cls(
            float(d["scale"]),
            float(d["unlike_ratio"]),
            float(d["quantile"]),
            str(d["basis"]),
            int(d["n"]),
            tuple(str(s) for s in d.get("skeletons", ())),
            FeatureRanges.from_dict(d["features"]) if d.get("features") else None,
        )


def held_out_distances(
    cb: CaseBase,
    queries: np.ndarray,
    groups: np.ndarray,
    case_groups: np.ndarray,
) -> np.ndarray:
    """Distance from each query ``(q, *problem_shape)`` to its nearest case of another group:
    ``groups`` ``(q,)`` the query's group, ``case_groups`` ``(n_cases,)`` each case's."""
    measure, index = cb.measure, cb.index
    out = np.full(len(queries), np.inf)
    for i, p in enumerate(queries):  # one full scan per query: the measure's array work
        d = measure.distances(measure.represent_query(p), index)
        d = np.where(case_groups == groups[i], np.inf, d)
        out[i] = float(d.min()) if len(d) else np.inf
    return out


def from_distances(
    d: np.ndarray,
    basis: str,
    quantile: float = UNLIKE_QUANTILE,
    skeletons: tuple[str, ...] = (),
) -> NoveltyCalibration:
    """The calibration from held-out nearest-case distances ``d`` ``(q,)``."""
    d = np.asarray(d, dtype=np.float64)
    d = d[np.isfinite(d)]
    if len(d) == 0:
        return NoveltyCalibration(1.0, float("inf"), quantile, basis, 0, skeletons)
    # an exact match comes out of the float32 search a little above 0: below a thousandth of
    # the largest distance, a distance counts as 0 and does not set the unit
    apart = d[d > EXACT_SHARE * d.max()]
    scale = float(np.median(apart)) if len(apart) else 1.0
    unlike = float(np.quantile(d, quantile)) / scale
    return NoveltyCalibration(scale, unlike, quantile, basis, len(d), skeletons)


def sample(n: int, size: int, seed: int = 0) -> np.ndarray:
    """Positions of at most ``size`` of ``n`` items (a seeded sample, sorted; all when fewer)."""
    if n <= size:
        return np.arange(n)
    return np.sort(np.random.default_rng(seed).choice(n, size, replace=False))


def calibrate(
    cb: CaseBase,
    queries: np.ndarray,
    query_groups: np.ndarray,
    case_groups: np.ndarray,
    basis: str,
    *,
    quantile: float = UNLIKE_QUANTILE,
    size: int = CALIBRATION_SAMPLE,
    seed: int = 0,
) -> NoveltyCalibration:
    """Calibrate on the training clips ``queries`` ``(n, *problem_shape)`` as the classifier
    sees them: each is held out from the cases of its own group (``query_groups`` ``(n,)``
    against ``case_groups`` ``(n_cases,)``: subjects, or clip indices); ``basis`` names the
    grouping."""
    pick = sample(len(queries), size, seed)
    groups = np.asarray(query_groups, dtype=object)
    d = held_out_distances(cb, queries[pick], groups[pick], np.asarray(case_groups, dtype=object))
    return from_distances(d, basis, quantile)
