"""How unlike the stored cases a clip is, calibrated on the case base itself.

A new clip's *novelty* is the distance to its nearest case divided by the case base's usual
held-out nearest-case distance (the ``scale``: the median over held-out training clips, exact
matches left out, so binary QMP vectors, whose held-out clips often match a case exactly, get a
usable unit). It is *unlike the stored cases* when one statistic says it is less usual than
nearly every held-out training clip (:class:`Combined`, :func:`combined_calibration`), from
five scores, each turned into its held-out tail probability:

- the nearest-case distance under the case base's own measure (``"distance"``);
- four scores of the clip's summary features, the same in every configuration (the fluent
  summary fluents/euclidean's problem is, :data:`DESCRIPTION`: fluent confidences, joint
  angles and positions, their mean, lowest, highest and spread over the clip; read off the
  problem when it holds those columns, :func:`from_problem`, else computed from the clip),
  none of which depends on the answer: the share of features outside the ranges the cases
  span (:class:`FeatureRanges`) in units of all held-out clips' and in units of those of the
  label of the nearest training clip in summary space, the distance to that clip
  (:class:`SummaryNeighbours`, each feature in the cases' standard deviations, at most
  :data:`CLIP_SD`), and how far the clip lies from the nearest activity in that activity's
  own spread (:class:`ActivitySpread`: features that each lie within the cases' ranges but
  together fit no one activity). Fisher's method joins them into one (``"features"`` when it
  flags): a measure-independent score, which sees what a distance averages away (a movement the case
  base knows, done with joints that sit where no case's did);

the threshold set so that :data:`FLAG_BUDGET` of the held-out training clips are flagged,
the distance holding :data:`DISTANCE_WEIGHT` of it. Or it was recorded with a skeleton
(sensor) none of the training clips was recorded with (``"sensor"``): the joints of another
sensor sit elsewhere on the body, so its clips are not comparable with the cases however near
they look.

Case bases stored before the combined statistic are judged as they were: the distance and the
outside share (in units of held-out clips of the answer), each beyond its own 0.995 quantile
(:data:`SHARED_QUANTILE`); before the ranges, the distance at 0.99.

Held out means what a new person is: with subjects known, each training clip's nearest case
among the OTHER subjects' cases (leave-one-subject-out); otherwise among the cases of other
clips (leave-one-out; a clip's own mirror image does not count). The calibration is learned in
``fit`` for whatever feature level and measure the case base uses, and stored with it, so the
flag means the same for every configuration.
"""

from __future__ import annotations

import base64
import dataclasses
import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from features.nanstats import over_seen

from .casebase import CaseBase
from .problem import FeatureConfig, candidate_config, column_index, extract_problem

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
#: a summary feature counts at most this many of the cases' standard deviations in the
#: nearest-clip distance (:class:`SummaryNeighbours`)
CLIP_SD = 3.0
#: the share of held-out training clips the combined flag (:class:`Combined`) may call unlike
#: the cases (new people score a little farther than held-out training clips: measured false
#: alarms 2-4 % at this budget)
FLAG_BUDGET = 0.02
#: a summary feature's spread among the cases of one activity counts at least this share of
#: its spread among all cases (:class:`ActivitySpread`): a feature one activity's cases hold
#: constant does not decide alone
SPREAD_FLOOR = 0.25
#: differences :func:`activity_scores` holds at once (clips x activities x features: 32 MB)
SPREAD_BLOCK = 1 << 22
#: the distance's share of the combined flag's threshold (:class:`Combined`): a tail
#: probability this many times the summary's flags
DISTANCE_WEIGHT = 0.25


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


def same_columns(config: FeatureConfig) -> bool:
    """Whether a clip's problem under ``config`` (an :func:`own_description`) holds
    :data:`DESCRIPTION`'s candidate columns, so :func:`from_problem` gives its description."""
    return own_description(config) and tuple(candidate_config(config).states) == tuple(
        candidate_config(DESCRIPTION).states
    )


def from_problem(
    values: np.ndarray, candidates: FeatureConfig, description: FeatureConfig
) -> np.ndarray:
    """The description ``(F,)`` of a clip (resolved ``description``: :data:`DESCRIPTION`'s
    columns) from its problem ``values`` as recorded under ``candidates`` (the candidate
    columns of a :func:`same_columns` configuration): a summary vector's mean, lowest,
    highest and variation blocks (its phase means left out), or a sequence's columns
    summarised over time (:func:`summary`); what :func:`describe` computes from the clip."""
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 1:
        vector: np.ndarray = v[column_index(description, candidates)]
        return vector
    plain = dataclasses.replace(description, summary=False, phases=0)
    out: np.ndarray = summary(v[:, column_index(plain, candidates)])
    return out


def summary(values: np.ndarray) -> np.ndarray:
    """The summary features of one problem: a vector ``(n,)`` as it is, a sequence
    ``(length, n)`` as its columns' mean, minimum, maximum and standard deviation over time
    ``(4 n,)`` (missing values left out; a column missing throughout stays NaN)."""
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 1:
        return v
    reductions = (np.nanmean, np.nanmin, np.nanmax, np.nanstd)
    return np.concatenate([over_seen(f, v, 0) for f in reductions])  # a column missing: NaN


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


def _case_and_query_folds(
    case_groups: np.ndarray, groups: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """The :func:`fold_of` of every case (groups ``case_groups``) and of every training clip
    (``groups``), folded together, or None when they form fewer than two folds."""
    fold = fold_of(np.concatenate([np.asarray(case_groups, dtype=object),
                                   np.asarray(groups, dtype=object)]))  # fmt: skip
    if len(fold) == 0 or int(fold.max()) < 1:
        return None
    return fold[: len(case_groups)], fold[len(case_groups) :]


def _fields_equal(a: Any, b: Any, arrays: tuple[str, ...], plain: tuple[str, ...]) -> bool:
    """Whether ``a`` and ``b`` agree on the named array fields (NaN equal to NaN: a feature no
    case has) and on the other named fields."""
    return all(
        np.array_equal(getattr(a, n), getattr(b, n), equal_nan=True) for n in arrays
    ) and all(getattr(a, n) == getattr(b, n) for n in plain)


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
        return _fields_equal(
            self, other, ("lo", "hi"),
            ("labels", "scales", "default", "unlike_ratio", "quantile", "description"),
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


def ranges_and_held(
    cases: np.ndarray,
    case_groups: np.ndarray,
    queries: np.ndarray,
    groups: np.ndarray,
    labels: Sequence[str] | np.ndarray,
    quantile: float = SHARED_QUANTILE,
    description: FeatureConfig | None = None,
) -> tuple[FeatureRanges, np.ndarray] | None:
    """The feature ranges of ``cases`` ``(m, F)`` (summaries, group ``case_groups`` ``(m,)``)
    calibrated on the training clips ``queries`` ``(n, F)`` (group ``groups`` ``(n,)``,
    label ``labels``), each scored against the cases of the other folds; ``description``: the
    configuration the summaries were computed with (None: the problems' own). None when the
    cases lie in fewer than two folds (nothing to hold out). With them, each query's held-out
    outside share ``(n,)``."""
    everyone = np.concatenate([np.asarray(case_groups, dtype=object),
                               np.asarray(groups, dtype=object)])  # fmt: skip
    fold = fold_of(everyone)
    case_fold, query_fold = fold[: len(cases)], fold[len(cases) :]
    k = int(fold.max()) + 1 if len(fold) else 0
    if k < 2 or len(np.unique(case_fold)) < 2:  # an edited case base may keep one group's
        return None
    # a feature no case of the other folds has: NaN, no range
    lo = np.stack([over_seen(np.nanmin, cases[case_fold != f], 0) for f in range(k)])
    hi = np.stack([over_seen(np.nanmax, cases[case_fold != f], 0) for f in range(k)])
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
    found = FeatureRanges(lo, hi, names, tuple(scales), default,
                          float(np.quantile(ratios, quantile)), quantile, description)  # fmt: skip
    return found, held


def fit_ranges(
    cases: np.ndarray,
    case_groups: np.ndarray,
    queries: np.ndarray,
    groups: np.ndarray,
    labels: Sequence[str] | np.ndarray,
    quantile: float = SHARED_QUANTILE,
    description: FeatureConfig | None = None,
) -> FeatureRanges | None:
    """:func:`ranges_and_held` without the held-out shares."""
    got = ranges_and_held(cases, case_groups, queries, groups, labels, quantile, description)
    return None if got is None else got[0]


def rms_terms(cases: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cases' side of :func:`nearest_rms`, ``(m, F)`` each: where each case has a
    feature (1.0), its values with the missing ones 0 and their squares. Worked out once,
    they serve every query (a clip at a time, as classifying asks)."""
    c = np.asarray(cases, dtype=np.float64)
    c0 = np.nan_to_num(c)
    return (~np.isnan(c)).astype(np.float64), c0, c0**2


def nearest_rms(
    queries: np.ndarray,
    cases: np.ndarray,
    terms: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Each query's ``(q, F)`` nearest case ``(m, F)``: the root mean square difference over
    the features both have (NaN: missing) ``(q,)`` and the case's position ``(q,)`` (-1 and
    ``inf`` when there is no case). One matrix product per term: no loop over cases.
    ``terms``: :func:`rms_terms` of ``cases``, when already worked out."""
    q = np.asarray(queries, dtype=np.float64)
    if len(cases) == 0 or len(q) == 0:
        return np.full(len(q), np.inf), np.full(len(q), -1, dtype=np.int64)
    cm, c0, c2 = rms_terms(cases) if terms is None else terms
    qm, q0 = (~np.isnan(q)).astype(np.float64), np.nan_to_num(q)
    # sum over the shared features of (q - c)^2 = q^2 + c^2 - 2 q c, each masked by the other
    sq = (q0**2) @ cm.T + qm @ c2.T - 2.0 * q0 @ c0.T
    shared = qm @ cm.T
    d2 = np.where(shared > 0, np.maximum(sq, 0.0) / np.maximum(shared, 1.0), np.inf)
    at = np.argmin(d2, axis=1)
    return np.sqrt(d2[np.arange(len(q)), at]), at.astype(np.int64)


@dataclass(frozen=True, eq=False)
class SummaryNeighbours:
    """The nearest training clip in summary space, whatever the case base's measure: each
    summary feature standardised by the cases' ``centre`` and ``scale`` ``(F,)`` (their mean
    and standard deviation) and counted at most :data:`CLIP_SD` standard deviations, so one
    feature no case shows cannot decide alone (the range count sees those). ``cases``
    ``(m, F)``: the training clips kept as cases, so standardised (float16: within
    :data:`CLIP_SD` its rounding is below 0.002), ``labels`` ``(m,)`` their labels."""

    centre: np.ndarray
    scale: np.ndarray
    cases: np.ndarray
    labels: tuple[str, ...]

    def standardise(self, s: np.ndarray) -> np.ndarray:
        """Summaries ``(..., F)`` in the cases' standard deviations, clipped."""
        z = (np.asarray(s, dtype=np.float64) - self.centre) / self.scale
        out: np.ndarray = np.clip(z, -CLIP_SD, CLIP_SD)
        return out

    @cached_property
    def _terms(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`rms_terms` of the cases, for every clip classified with this model."""
        return rms_terms(self.cases)

    def nearest(self, s: np.ndarray) -> tuple[float, str]:
        """One clip's summary ``(F,)``: the distance to its nearest case and that case's
        label (``inf`` and "" for a summary of other columns)."""
        s = np.asarray(s, dtype=np.float64)
        if s.shape[-1] != self.centre.shape[-1]:
            return float("inf"), ""
        d, at = nearest_rms(self.standardise(s)[None, :], self.cases, self._terms)
        return float(d[0]), (self.labels[int(at[0])] if at[0] >= 0 else "")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, SummaryNeighbours):
            return NotImplemented
        return (
            np.array_equal(self.centre, other.centre)
            and np.array_equal(self.scale, other.scale)
            and np.array_equal(self.cases, other.cases, equal_nan=True)
            and self.labels == other.labels
        )

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        return {"centre": self.centre.tolist(), "scale": self.scale.tolist(),
                "cases": _array_text(self.cases), "labels": list(self.labels)}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SummaryNeighbours:
        """Refuses (ValueError, with the reason) what a damaged store would hold."""
        centre = np.array(d["centre"], dtype=np.float64)
        scale = np.array(d["scale"], dtype=np.float64)
        cases = _array_of(d["cases"])
        labels = tuple(str(v) for v in d["labels"])
        if centre.ndim != 1 or scale.shape != centre.shape:
            raise ValueError("the summary neighbours' centre and scale must be paired vectors")
        if not (np.isfinite(centre).all() and np.isfinite(scale).all() and (scale > 0).all()):
            raise ValueError("the summary neighbours' scales must be finite and positive")
        if cases.ndim != 2 or cases.shape[1] != len(centre) or len(labels) != len(cases):
            raise ValueError("the summary neighbours' cases must be (cases, features) with a "
                             "label each")  # fmt: skip
        if np.nanmax(np.abs(cases), initial=0.0) > CLIP_SD:
            raise ValueError(f"the summary neighbours' cases must lie within {CLIP_SD:g} "
                             "standard deviations")  # fmt: skip
        return cls(centre, scale, cases, labels)


def _array_text(a: np.ndarray) -> str:
    """A float16 array as base64 ``.npy`` text (JSON-ready; NaN kept)."""
    buf = io.BytesIO()
    np.save(buf, np.asarray(a, dtype=np.float16), allow_pickle=False)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _array_of(text: Any) -> np.ndarray:
    """The array :func:`_array_text` wrote (ValueError when it is not one)."""
    try:
        a = np.load(io.BytesIO(base64.b64decode(str(text), validate=True)), allow_pickle=False)
    except (OSError, ValueError, EOFError) as e:
        raise ValueError(f"the summary neighbours' cases are not a stored array ({e})") from e
    if a.dtype != np.float16:
        raise ValueError(f"the summary neighbours' cases must be float16, not {a.dtype}")
    out: np.ndarray = np.asarray(a, dtype=np.float16)
    return out


def fit_neighbours(
    cases: np.ndarray,
    case_groups: np.ndarray,
    case_labels: Sequence[str] | np.ndarray,
    queries: np.ndarray,
    groups: np.ndarray,
) -> tuple[SummaryNeighbours, np.ndarray, np.ndarray] | None:
    """The summary neighbours of ``cases`` ``(m, F)`` (group ``case_groups``, label
    ``case_labels`` ``(m,)``) and, for each training clip ``queries`` ``(n, F)`` (group
    ``groups`` ``(n,)``), its held-out distance ``(n,)`` and its nearest case's label ``(n,)``
    among the cases of the other folds (:func:`fold_of`, as :func:`fit_ranges` holds them
    out). None when the cases form fewer than two groups."""
    folds = _case_and_query_folds(case_groups, groups)
    if folds is None:
        return None
    case_fold, query_fold = folds
    # a feature no case has: NaN centre, no part in distances
    centre = np.nan_to_num(over_seen(np.nanmean, cases, 0))
    spread = over_seen(np.nanstd, cases, 0)
    scale = np.where(np.isfinite(spread) & (spread > 1e-9), spread, 1.0)
    labels = np.array([str(v) for v in case_labels], dtype=object)
    found = SummaryNeighbours(centre, scale, np.zeros((0, len(centre))), ())
    z_cases = found.standardise(cases).astype(np.float16)
    z_queries = found.standardise(queries).astype(np.float16)
    held = np.full(len(queries), np.inf)
    near = np.full(len(queries), "", dtype=object)
    for f in np.unique(query_fold):
        mine, theirs = query_fold == f, np.flatnonzero(case_fold != f)
        d, at = nearest_rms(z_queries[mine], z_cases[theirs])
        held[mine] = d
        near[mine] = [labels[theirs[i]] if i >= 0 else "" for i in at]
    neighbours = SummaryNeighbours(centre, scale, z_cases, tuple(labels.tolist()))
    return neighbours, held, near


@dataclass(frozen=True, eq=False)
class ActivitySpread:
    """How far a clip lies from every activity's cases in that activity's own spread: per
    label, the cases' mean ``centres`` and standard deviation ``units`` ``(labels, F)`` of
    each summary feature (a unit at least :data:`SPREAD_FLOOR` of the feature's standard
    deviation over all cases; NaN: no case has the feature). A clip's score is the least over
    the activities of its mean squared standardised difference, each feature counted at most
    :data:`CLIP_SD` deviations: a clip whose features each lie within the cases' ranges, but
    which no one activity's cases spread to (an arm raised as in one exercise, the legs and
    trunk as in another), scores high; the range count and the nearest clip do not see it."""

    centres: np.ndarray
    units: np.ndarray
    labels: tuple[str, ...]

    def scores(self, s: np.ndarray) -> np.ndarray:
        """The score ``(q,)`` of the summaries ``s`` ``(q, F)`` (``inf`` for summaries of other
        columns; a feature missing in the clip or in every case of an activity counts 0)."""
        s = np.atleast_2d(np.asarray(s, dtype=np.float64))
        if s.shape[-1] != self.centres.shape[-1] or len(self.labels) == 0:
            return np.full(len(s), np.inf)
        return activity_scores(s, self.centres, self.units)

    def score(self, s: np.ndarray) -> float:
        """:meth:`scores` of one summary ``(F,)``."""
        return float(self.scores(s)[0])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ActivitySpread):
            return NotImplemented
        return _fields_equal(self, other, ("centres", "units"), ("labels",))

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN, a feature no case of an activity has, stored as None)."""
        return {"centres": _nan_none(self.centres), "units": _nan_none(self.units),
                "labels": list(self.labels)}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ActivitySpread:
        """Refuses (ValueError, with the reason) what a damaged store would hold."""
        centres = np.array(d["centres"], dtype=np.float64)
        units = np.array(d["units"], dtype=np.float64)
        labels = tuple(str(v) for v in d["labels"])
        if centres.ndim != 2 or units.shape != centres.shape or len(labels) != len(centres):
            raise ValueError("the activities' centres and units must be paired (labels, "
                             "features) arrays with a label each")  # fmt: skip
        if (units[~np.isnan(units)] <= 0).any():
            raise ValueError("the activities' units must be positive")
        return cls(centres, units, labels)


def activity_scores(s: np.ndarray, centres: np.ndarray, units: np.ndarray) -> np.ndarray:
    """:meth:`ActivitySpread.scores` of ``s`` ``(q, F)`` against ``centres`` and ``units``
    ``(labels, F)``: per clip, the least over labels of the mean over features of
    ``min(((s - centre) / unit) ** 2, CLIP_SD ** 2)`` (NaN terms count 0). Clips a block at
    a time, so the ``(block, labels, F)`` differences stay within :data:`SPREAD_BLOCK`."""
    out = np.empty(len(s))
    step = max(1, SPREAD_BLOCK // max(centres.size, 1))
    for i in range(0, len(s), step):
        z = (s[i : i + step, None, :] - centres[None, :, :]) / units[None, :, :]
        sq = np.minimum(np.nan_to_num(z * z, nan=0.0), CLIP_SD**2)
        out[i : i + step] = sq.mean(axis=-1).min(axis=-1)
    return out


def spread_of(cases: np.ndarray, labels: np.ndarray) -> ActivitySpread:
    """The :class:`ActivitySpread` of ``cases`` ``(m, F)`` of ``labels`` ``(m,)``."""
    names = tuple(sorted({str(v) for v in labels}))
    # a feature no case (of an activity) has: NaN
    overall = over_seen(np.nanstd, cases, 0)
    centres = np.stack([over_seen(np.nanmean, cases[labels == n], 0) for n in names])
    spread = np.stack([over_seen(np.nanstd, cases[labels == n], 0) for n in names])
    units = np.fmax(spread, SPREAD_FLOOR * overall)
    units = np.where(units > 1e-9, units, np.nan)  # constant among all cases: no part
    return ActivitySpread(centres.reshape(len(names), cases.shape[-1]),
                          units.reshape(len(names), cases.shape[-1]), names)  # fmt: skip


def fit_activities(
    cases: np.ndarray,
    case_groups: np.ndarray,
    case_labels: Sequence[str] | np.ndarray,
    queries: np.ndarray,
    groups: np.ndarray,
) -> tuple[ActivitySpread, np.ndarray] | None:
    """The :class:`ActivitySpread` of ``cases`` ``(m, F)`` (group ``case_groups``, label
    ``case_labels`` ``(m,)``) and each training clip's ``queries`` ``(n, F)`` (group
    ``groups`` ``(n,)``) held-out score ``(n,)``: against the spread of the cases of the
    other folds (:func:`fold_of`, as :func:`fit_ranges` holds them out; their centres and
    units both from those cases, so a held-out clip is judged as a new person's will be).
    None when the cases form fewer than two groups."""
    folds = _case_and_query_folds(case_groups, groups)
    if folds is None:
        return None
    case_fold, query_fold = folds
    cases = np.asarray(cases, dtype=np.float64)
    labels = np.array([str(v) for v in case_labels], dtype=object)
    held = np.full(len(queries), np.inf)
    for f in np.unique(query_fold):
        theirs = case_fold != f
        if theirs.any():
            mine = query_fold == f
            held[mine] = spread_of(cases[theirs], labels[theirs]).scores(queries[mine])
    return spread_of(cases, labels), held


#: the summary scores of :class:`Combined`, besides the case base's own distance: the share
#: of features outside the cases' ranges in units of all held-out clips', the same in units
#: of the held-out clips of the label of the nearest training clip in summary space, and the
#: distance to that clip (:class:`SummaryNeighbours`)
SUMMARY_SCORES = ("outside", "outside_label", "neighbour")
#: the fourth summary score, when the calibration has it (:class:`ActivitySpread`: case bases
#: stored before it join the three alone)
ACTIVITY_SCORE = "activity"


def summary_scores(held: dict[str, Any]) -> tuple[str, ...]:
    """The summary scores Fisher's method joins for held-out scores ``held`` (name: values):
    :data:`SUMMARY_SCORES`, and :data:`ACTIVITY_SCORE` when it was calibrated."""
    return SUMMARY_SCORES + ((ACTIVITY_SCORE,) if ACTIVITY_SCORE in held else ())


@dataclass(frozen=True, eq=False)
class Combined:
    """One calibrated statistic from the novelty scores. Each score is turned into its
    held-out tail probability (the share of held-out training clips that score at least as
    high, ``(1 + count) / (n + 1)``); the summary scores (:data:`SUMMARY_SCORES`) into one by
    Fisher's method (``-sum(log p)``, itself turned into its held-out tail probability,
    ``"summary"``: several moderately unusual features count together); the clip is flagged
    when the summary's tail is at most ``threshold`` or the distance's at most
    ``distance_weight`` times it, the threshold set so that ``budget`` of the held-out clips
    are (a weighted Bonferroni minimum calibrated on the clips themselves: a further score
    costs no second false-alarm budget; the distance, which finds least and whose held-out
    clips are the measure's own sample, gets the smaller share).
    ``held``: per score name, its held-out values sorted ``(n,)``."""

    held: dict[str, np.ndarray]
    threshold: float
    budget: float
    distance_weight: float = 1.0

    def tail(self, name: str, value: float) -> float:
        """The held-out tail probability of ``value`` of score ``name`` (1 for a score not
        calibrated or not measured: NaN)."""
        return float(self.tails(name, np.array([value], dtype=np.float64))[0])

    def tails(self, name: str, values: np.ndarray) -> np.ndarray:
        """:meth:`tail` of each of ``values`` ``(q,)``."""
        v = np.asarray(values, dtype=np.float64)
        ref = self.held.get(name)
        if ref is None or len(ref) == 0:
            return np.ones(len(v))
        above = len(ref) - np.searchsorted(ref, v, side="left")
        p = (1.0 + above) / (len(ref) + 1.0)
        return np.where(np.isnan(v), 1.0, p)

    def summary(self, tails: dict[str, np.ndarray]) -> np.ndarray:
        """The summary scores' ``tails`` (name: ``(q,)``) as one tail probability ``(q,)``
        (Fisher's method against the held-out clips' own)."""
        fisher = -np.sum([np.log(tails[k]) for k in summary_scores(self.held)], axis=0)
        return self.tails("summary", np.atleast_1d(fisher))

    def flags(self, p: float) -> bool:
        """Whether a summary tail probability ``p`` flags (the distance's: :meth:`by_distance`)."""
        return p <= self.threshold

    @property
    def distance_threshold(self) -> float:
        """The distance's tail probability at or below which it flags: its share of the
        threshold, and at least beyond every held-out clip's distance."""
        n = len(self.held.get("distance", ()))
        return max(self.distance_weight * self.threshold, 1.0 / (n + 1.0))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Combined):
            return NotImplemented
        return (
            self.held.keys() == other.held.keys()
            and all(np.array_equal(v, other.held[k]) for k, v in self.held.items())
            and (self.threshold, self.budget, self.distance_weight)
            == (other.threshold, other.budget, other.distance_weight)
        )

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        return {"held": {k: [float(x) for x in v] for k, v in self.held.items()},
                "threshold": self.threshold, "budget": self.budget,
                "distance_weight": self.distance_weight}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Combined:
        """Refuses (ValueError, with the reason) what a damaged store would hold."""
        held = {str(k): np.array(v, dtype=np.float64) for k, v in dict(d["held"]).items()}
        for k, v in held.items():
            if v.ndim != 1 or np.isnan(v).any() or (np.diff(v) < 0).any():
                raise ValueError(f"the held-out {k} scores must be an increasing list")
        threshold, budget = float(d["threshold"]), float(d["budget"])
        weight = float(d["distance_weight"])
        if not (0.0 <= threshold <= 1.0 and 0.0 < budget < 1.0 and 0.0 < weight <= 1.0):
            raise ValueError("the combined flag's threshold, budget and distance weight must be "
                             "probabilities")  # fmt: skip
        return cls(held, threshold, budget, weight)


def combine(
    held: dict[str, np.ndarray],
    sample: np.ndarray,
    budget: float = FLAG_BUDGET,
    weight: float = DISTANCE_WEIGHT,
) -> Combined:
    """The combined statistic from each score's held-out values ``held`` (name: ``(n,)``,
    the distance's at the clips ``sample`` ``(q,)`` positions, the summary scores' at every
    clip): the held-out Fisher statistic of the summary scores is added as ``"summary"``
    and the threshold is the largest at which at most ``budget`` of the held-out clips are
    flagged (:func:`flag_threshold`: the summary's share counted on every clip, the
    distance's on the clips it was measured on; 0 when fewer than ``1 / budget - 1`` clips
    were held out: they cannot tell a 1-in-50 clip)."""
    ref = {k: np.sort(v[np.isfinite(v)]) for k, v in held.items()}  # JSON has no inf
    found = Combined(ref, 0.0, budget, weight)
    joined = summary_scores(held)
    fisher = -np.sum([np.log(found.tails(k, held[k])) for k in joined], axis=0)
    found = Combined({**ref, "summary": np.sort(fisher)}, 0.0, budget, weight)
    if len(sample) == 0:
        return found
    every = found.summary({k: found.tails(k, held[k]) for k in joined})
    if budget * (len(every) + 1) < 1.0:  # too few clips: a new ordinary clip is less usual
        # than all n held-out ones with chance 1 / (n + 1), above the budget; the summary does
        # not flag (the distance still flags beyond every held-out clip's)
        return found
    near = found.tails("distance", held["distance"])
    floor = 1.0 / (len(ref["distance"]) + 1.0)  # Combined.distance_threshold's least
    threshold = flag_threshold(every, near, np.asarray(sample), budget, weight, floor)
    return dataclasses.replace(found, threshold=threshold)


def flag_threshold(
    summary: np.ndarray,
    distance: np.ndarray,
    sample: np.ndarray,
    budget: float,
    weight: float,
    floor: float = 0.0,
) -> float:
    """The largest threshold ``t`` on the summary's tail probabilities ``summary`` ``(n,)``
    (every held-out clip) at which the held-out clips flagged (summary tail at most ``t``, or
    the distance's tail ``distance`` ``(q,)``, measured at the clips ``sample`` ``(q,)``, at
    most ``max(weight t, floor)``) are at most ``budget`` of them, rounded as the ``budget``
    quantile rounds (``floor(budget (n - 1)) + 1`` of ``n`` clips): ``t`` and every smaller
    candidate keep within it.

    The share is the summary's own share over all ``n`` clips plus the share of the sampled
    clips that the distance alone flags: the distance is measured on a sample (a full scan of
    the measure per clip: 256 sequences), the summary scores on every clip, so the summary's
    part, nearly all of the flags, is counted on ``n`` clips instead of ``q`` (at 2 % of 256
    clips the 6th smallest decided; of 1,200, the 24th)."""
    ps = np.asarray(summary, dtype=np.float64)
    pd = np.asarray(distance, dtype=np.float64)
    mine = ps[np.asarray(sample, dtype=np.int64)]
    n, q = len(ps), max(len(pd), 1)
    allowed = (np.floor(budget * (n - 1)) + 1.0) / n
    # a sampled clip is flagged by the distance alone for t in [from_t, its summary tail):
    # from the least t whose weight t, as Combined computes it, reaches its distance tail
    # (every t when the floor does)
    reach = pd / weight
    for _ in range(2):  # weight * (pd / weight) may round below pd: the next float up
        reach = np.where(weight * reach < pd, np.nextafter(reach, np.inf), reach)
    from_t = np.where(pd <= floor, -np.inf, reach)
    candidates = np.unique(np.concatenate([ps, from_t[np.isfinite(from_t)]]))
    by_summary = np.searchsorted(np.sort(ps), candidates, side="right") / n
    started = np.searchsorted(np.sort(from_t), candidates, side="right")
    ended = np.searchsorted(np.sort(np.maximum(from_t, mine)), candidates, side="right")
    rate = by_summary + (started - ended) / q
    over = np.flatnonzero(rate > allowed + 1e-12)
    first = int(over[0]) if len(over) else len(candidates)
    return float(candidates[first - 1]) if first > 0 else 0.0


@dataclass(frozen=True)
class NoveltyCalibration:
    """scale: median held-out nearest-case distance (exact matches left out); unlike_ratio:
    the ``quantile`` of the held-out distances, in units of ``scale``, above which a clip is
    flagged; basis: how the training clips were held out; n: how many were; skeletons: the
    skeletons (sensors) the training clips were recorded with (empty: not known); features:
    the summary features' ranges (None: the distance alone, as case bases stored before
    them); neighbours and combined: the nearest training clip in summary space and the one
    statistic that combines the scores (:class:`Combined`; None: each score at its own
    quantile, as case bases stored before it are judged); activities: each activity's spread
    in summary space, the fourth summary score (None: the three alone, as case bases stored
    before it are judged)."""

    scale: float
    unlike_ratio: float
    quantile: float
    basis: str
    n: int
    skeletons: tuple[str, ...] = ()
    features: FeatureRanges | None = field(default=None, compare=True)
    neighbours: SummaryNeighbours | None = None
    combined: Combined | None = None
    activities: ActivitySpread | None = None

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
        (its summary features are less usual than the held-out clips' by :meth:`tails`, with
        a combined calibration; before it, they leave the cases' ranges more than held-out
        clips of its answer ``label`` do; only with ``values``, the clip's
        :attr:`FeatureRanges.description` when the ranges have one, else its problem) or
        ``""`` (neither)."""
        by_distance, by_features = self.scores(distance, values, label)
        return "distance" if by_distance else "features" if by_features else ""

    def scores(
        self, distance: float, values: np.ndarray | None = None, label: str | None = None
    ) -> tuple[bool, bool]:
        """Whether each score alone flags the clip (:meth:`measured`): the nearest-case
        ``distance`` and the summary features of ``values`` for the answer ``label``."""
        by_distance = self.ratio(distance) > self.unlike_ratio
        if self.combined is not None:
            tails = self.tails(values)
            return by_distance, bool(tails) and self.combined.flags(tails["summary"])
        by_features = (
            self.features is not None
            and values is not None
            and label is not None
            and self.features.unlike(summary(values), label)
        )
        return by_distance, bool(by_features)

    def tails(self, values: np.ndarray | None) -> dict[str, float]:
        """The held-out tail probability of each summary score of the clip whose problem (or
        description) is ``values`` (:data:`SUMMARY_SCORES`, and :data:`ACTIVITY_SCORE` when
        calibrated) and of their Fisher statistic
        (``"summary"``; empty without ``values`` or a combined calibration). None of them
        depends on the answer: the same clip scores the same under every measure."""
        c, f, n = self.combined, self.features, self.neighbours
        if c is None or f is None or n is None or values is None:
            return {}
        s = summary(values)
        outside = f.outside(s)
        distance, label = n.nearest(s)
        scale = f.scale(label) if label else f.default
        tails = {"outside": c.tail("outside", outside / f.default),
                 "outside_label": c.tail("outside_label", outside / scale),
                 "neighbour": c.tail("neighbour", distance)}  # fmt: skip
        if self.activities is not None:
            tails[ACTIVITY_SCORE] = c.tail(ACTIVITY_SCORE, self.activities.score(s))
        summed = c.summary({k: np.array([v]) for k, v in tails.items()})
        return {**tails, "summary": float(summed[0])}

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
        if self.neighbours is not None and self.combined is not None:
            d["neighbours"] = self.neighbours.to_dict()
            d["combined"] = self.combined.to_dict()
        if self.activities is not None:
            d["activities"] = self.activities.to_dict()
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
        if self.neighbours is not None and self.combined is not None:
            c = self.combined
            d["neighbours"] = {"cases": int(self.neighbours.cases.shape[0])}
            d["combined"] = {"threshold": c.threshold, "budget": c.budget,
                             "scores": {k: len(v) for k, v in c.held.items()}}  # fmt: skip
        if self.activities is not None:
            d["activities"] = {"labels": list(self.activities.labels),
                               "features": int(self.activities.centres.shape[1])}  # fmt: skip
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
            *_combined_of(d),
            _activities_of(d),
        )


def _combined_of(d: dict[str, Any]) -> tuple[SummaryNeighbours | None, Combined | None]:
    """The stored combined flag (both parts, or neither: stored before it); a half-stored
    one is refused."""
    if not d.get("neighbours") and not d.get("combined"):
        return None, None
    if not (d.get("neighbours") and d.get("combined") and d.get("features")):
        raise ValueError("the combined flag needs its feature ranges, neighbours and "
                         "held-out scores together")  # fmt: skip
    return SummaryNeighbours.from_dict(d["neighbours"]), Combined.from_dict(d["combined"])


def _activities_of(d: dict[str, Any]) -> ActivitySpread | None:
    """The stored activity spread (None: stored before it); one stored without its held-out
    scores in the combined flag, or held-out scores without it, is refused."""
    held = dict(d.get("combined") or {}).get("held", {})
    if bool(d.get("activities")) != (ACTIVITY_SCORE in held):
        raise ValueError("the activity spread and its held-out scores must be stored together")
    return ActivitySpread.from_dict(d["activities"]) if d.get("activities") else None


def distance_limit(ratios: np.ndarray, threshold: float) -> float:
    """The held-out distance ratio beyond which a clip's tail probability among ``ratios``
    ``(n,)`` (:meth:`Combined.tail`) is at most ``threshold``: the distance alone flags
    exactly what it flags in the combined statistic (``inf``: never)."""
    r = np.sort(np.asarray(ratios, dtype=np.float64))
    r = r[~np.isnan(r)]
    k = int(np.floor(threshold * (len(r) + 1) - 1.0 + 1e-9))  # held-out clips at or above
    return float("inf") if k < 0 or len(r) == 0 else float(r[max(len(r) - 1 - k, 0)])


def combined_calibration(
    novelty: NoveltyCalibration,
    nearest: np.ndarray,
    ranges: FeatureRanges,
    outside: np.ndarray,
    neighbours: SummaryNeighbours,
    neighbour: np.ndarray,
    near_labels: np.ndarray,
    pick: np.ndarray,
    budget: float = FLAG_BUDGET,
    activities: tuple[ActivitySpread, np.ndarray] | None = None,
) -> NoveltyCalibration:
    """``novelty`` (the distance's calibration) with the feature scores and one statistic of
    them all (:class:`Combined`): the held-out training clips' ``outside`` shares ``(n,)``
    (:func:`ranges_and_held`), distances to the nearest clip in summary space ``neighbour``
    and that clip's label ``near_labels`` ``(n,)`` (:func:`fit_neighbours`), and the
    nearest-case distances ``nearest`` ``(q,)`` of the clips at positions ``pick`` ``(q,)``,
    on which the threshold is set; ``activities``: the activity spread and the held-out
    clips' scores ``(n,)`` (:func:`fit_activities`), the fourth summary score (None: the three
    alone). The distance alone flags beyond the ratio at which it
    flags in the combination (:func:`distance_limit`: what :meth:`NoveltyCalibration.unlike`
    judges when only a distance is known)."""
    ratio = np.asarray(nearest, dtype=np.float64) / novelty.scale
    unit = np.array([ranges.scale(str(v)) if str(v) else ranges.default for v in near_labels])
    held = {"distance": ratio, "outside": outside / ranges.default,
            "outside_label": outside / unit, "neighbour": neighbour}  # fmt: skip
    if activities is not None:
        held[ACTIVITY_SCORE] = np.asarray(activities[1], dtype=np.float64)
    combined = combine(held, np.asarray(pick), budget)
    held["distance"] = ratio[np.isfinite(ratio)]
    limit = distance_limit(held["distance"], combined.distance_threshold)
    within = float(np.mean(held["distance"] <= limit)) if len(held["distance"]) else 1.0
    spread = None if activities is None else activities[0]
    return dataclasses.replace(novelty, unlike_ratio=limit, quantile=within, features=ranges,
                               neighbours=neighbours, combined=combined,
                               activities=spread)  # fmt: skip


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
