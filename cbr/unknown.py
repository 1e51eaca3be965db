"""When a stretch of a recording is none of the case base's activities ("unknown"), judged from
a window's distances to the nearest case of every activity, ``(n_classes,)``.

The judges, each calibrated on the case base itself, never on what is being segmented:

- :class:`Margin`: the nearest activity is
  hardly nearer than the next one. A window of a known activity lies much nearer to that
  activity's cases than to any other's; a window of an activity the case base lacks lies
  about as far from the two activities it resembles most. The margin ``d1 / d2`` (nearest
  activity over next nearest) is compared with a threshold learned on the training cases:
  each case held out from its own recording (or subject) gives the margin of a *known*
  activity, and the threshold is the one that at most :data:`FALSE_UNKNOWN` of them exceed
  (:func:`false_unknown_threshold`): a budget of false "unknown" on people the case base
  has not seen. (Held out from its own activity too, a case gives a *novel* margin; the
  point where both err equally, :func:`equal_error_threshold`, depends on which activities
  happen to be left out and, set there, called a third of new people's known movements
  unknown.) A ratio of distances needs no common unit, so a new person who lies farther
  from every case is not called unknown for that alone.
- :class:`ActivityMargin` (``--unknown activity-margin``; the default before
  :class:`SpreadMargin`): the margin
  against a threshold of the nearest activity's own: the
  quantile of the held-out known cases of that activity that its nearest case names rightly
  (a case named wrongly is wrong whether called unknown or not), shrunk towards the pooled
  quantile; the quantile's rate and the shrink weight are chosen on the held-out cases so that
  a held-out subject's known cases keep the budget against the others' thresholds
  (:func:`choose_weight`). An activity whose known cases are clear gets a low threshold; one
  that resembles another keeps its own high one. Its evidence is graded between its
  threshold and the one read at the whole budget (:meth:`ActivityMargin.evidence`). On
  people not in the case base it calls more of a left-out movement's blocks unknown than
  the pooled threshold and keeps as many known blocks right, or more (README, "Long
  recordings", for the figures).
- :class:`SpreadMargin` (the default of ``posecbr segment`` and ``watch``): the margin times how
  far the window lies from its nearest activity in that activity's own spread (the median
  distance of its held-out known cases), to a power chosen on the held-out cases with the
  rate and the prior; per-activity thresholds as :class:`ActivityMargin`'s. With a case base
  of one person it is :class:`ActivityMargin`.
- :class:`SpreadFar` (``--unknown spread-far``): :class:`SpreadMargin`, or unknown when the
  window's nearest case lies farther than all but :data:`FALSE_UNKNOWN` of the held-out
  known cases' do (not the default: on people not in the case base it caught more of
  UI-PRMD Kinect's left-out blocks for 1.4 points of its seen ones, and none more of
  HDM05's; README, "The far bound as a judge").
- With a case base of one person (held out by recording or by time, not by person), the two
  margin judges also have a floor (:func:`one_person_floor`) and see each recording's
  distances less how much farther its person lies from every case than the case base's own
  held-out cases (:func:`for_person`, :class:`Offset`): a threshold read from one person
  cannot know how far the next one lies, but the recording's nearest windows can tell.
- :class:`HeldOut`: the classifier's stored calibration (:mod:`cbr.novelty`, the distance
  score of the flag ``classify`` gives; its feature score needs a clip's answer): the nearest
  case lies farther than held-out training clips nearly ever do.
- :class:`Familiarity`: the nearest case lies as far as the case base's activities lie from
  each other.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar

import numpy as np

from features.body import MIRRORED
from features.errors import DataError, ParameterError
from features.text import percent

from .casebase import CaseBase, frame_array, overlapping
from .estimator_protocol import check_case_base_classifier
from .judges import JUDGES
from .novelty import NoveltyCalibration
from .weights import MIRROR_FLAG

FALSE_UNKNOWN = 0.05
"""The share of held-out training cases of a known activity the margin judge may call
unknown: its threshold is their margins' ``1 - FALSE_UNKNOWN`` quantile."""
ACTIVITY_PRIOR = 1.0 / FALSE_UNKNOWN
"""How many held-out cases the pooled threshold counts for in an activity's own threshold
(:func:`activity_thresholds`) when the case base cannot choose it (:func:`choose_weight`: no
activity has held-out cases in two groups): 1 / :data:`FALSE_UNKNOWN` (20), the number of
cases at which the budget reaches one case. Also the weight of :class:`ActivityMargin`
records stored before the weight was chosen."""
PRIOR_GRID = (0.0, 5.0, 10.0, 20.0, 40.0, 80.0, 160.0, 320.0, math.inf)
"""The weights :func:`choose_weight` tries, least shrinkage first (``inf``: the pooled
threshold for every activity)."""
RATE_SHARES = (1.0, 0.8, 0.6, 0.4, 0.2)
"""The shares of the false-unknown budget at which :func:`choose_weight` tries reading the
thresholds' quantiles, the whole budget first."""
MARGIN_SAMPLE = 2048
"""Training cases held out to calibrate the margin (a seeded sample when there are more): a 5 %
quantile read from 256 lies 13 cases from the top and moved by 10 points of UI-PRMD Vicon's
seen blocks from one sample to another; each costs one scan of the case base."""


class Judge(Protocol):
    """What says a window is unlike every activity of the case base, from its distances to the
    nearest case of each activity ``(n_classes,)`` (inf for an activity without cases)."""

    def ratio(self, nearest: np.ndarray) -> float:
        """How unlike the case base the window is, in the judge's own unit."""
        ...

    def unlike(self, nearest: np.ndarray) -> bool: ...

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        """Why a window with these distances is unknown, in words."""
        ...


def margin_of(nearest: np.ndarray) -> float:
    """``d1 / d2``: the distance to the nearest activity over that to the next nearest, from
    the distances to each activity's nearest case ``(n_classes,)``; 1 when the two are equally
    near (or no second activity is there to compare with), 0 when the window is a case."""
    finite = np.sort(np.asarray(nearest, dtype=np.float64)[np.isfinite(nearest)])
    if len(finite) < 2 or finite[1] <= 0.0:
        return 1.0
    return float(finite[0] / finite[1])


def two_nearest(nearest: np.ndarray, classes: Sequence[str]) -> tuple[str, str]:
    """The nearest and next nearest activities of a window with distances ``nearest``
    ``(n_classes,)`` to each activity's nearest case (the nearest twice when there is one)."""
    order = np.argsort(nearest, kind="stable")
    first = classes[int(order[0])]
    return first, classes[int(order[1])] if len(order) > 1 else first


def equal_error_threshold(known: np.ndarray, novel: np.ndarray) -> float:
    """The threshold ``t`` at which as large a share of ``known`` values lies above ``t`` as
    of ``novel`` values at or below it (the equal error rate; the first such value of the
    samples when they allow no exact equality). Both ``(n,)``, non-empty."""
    k, n = np.sort(known), np.sort(novel)
    candidates = np.unique(np.r_[k, n])
    known_above = 1.0 - np.searchsorted(k, candidates, side="right") / len(k)
    novel_below = np.searchsorted(n, candidates, side="right") / len(n)
    return float(candidates[int(np.argmin(np.abs(known_above - novel_below)))])


def false_unknown_threshold(known: np.ndarray, rate: float = FALSE_UNKNOWN) -> float:
    """The smallest of the ``known`` values ``(n,)`` (non-empty) that at most a share ``rate``
    of them exceed: the ``1 - rate`` quantile, taken at a sample value (never between two).
    A ``rate`` outside [0, 1) is refused with ParameterError naming it."""
    if not 0.0 <= rate < 1.0:
        raise ParameterError(f"the false-unknown rate must be in [0, 1), got {rate!r}", "rate")
    k = np.sort(np.asarray(known, dtype=np.float64))
    # the first sorted value with at most rate * n values above it
    return float(k[max(0, int(np.ceil(len(k) * (1.0 - rate) - 1e-9)) - 1)])


def activity_codes(labels: Any, classes: Any) -> np.ndarray:
    """Each case's index among ``classes`` ``(n,)`` (compared as text; -1 for a label not
    among them). Both are sequences or 1-D arrays."""
    where = {str(c): i for i, c in enumerate(classes)}
    return np.array([where.get(str(v), -1) for v in labels], dtype=np.int64)


def per_activity(d: np.ndarray, codes: np.ndarray, n_classes: int) -> np.ndarray:
    """``(n_classes,)``: the smallest of the distances ``d`` ``(n_cases,)`` per activity
    (``codes``: each case's activity index); inf where an activity has no finite distance."""
    out = np.full(n_classes, np.inf)
    known = codes >= 0
    np.minimum.at(out, codes[known], np.asarray(d, dtype=np.float64)[known])
    return out


def held_out_basis(cb: CaseBase) -> tuple[str, np.ndarray]:
    """How a training case is held out as a new recording will be, and the group of every
    case ``(n,)``: by subject when all cases name one and two or more are named (with an
    activity done by two of them); else by source recording when an activity comes from two
    or more recordings; else by time (the cases of its own recording that overlap it are left
    out: repeated movements of one recording, the best the case base can do).

    A case without a source (a clip given as arrays, :class:`features.poses.PoseSequence` of
    a tracker's numbers, or its mirror image) is a recording of its own, as the classifier's
    own calibration counts it: taken as one recording together, every such clip overlapped
    every other (each starts at frame 0), so none had a case left to compare with and the
    default judge could not be calibrated on a case base of them."""
    labels = np.asarray(cb.labels).astype(str)
    subjects = [s or "" for s in cb.subjects]
    sources = [
        s if s.removesuffix(MIRRORED) else f"\0case {i} (no source)"
        for i, s in enumerate(s or "" for s in cb.sources)
    ]
    for basis, groups in (("subject", subjects), ("recording", sources)):
        g = np.array(groups, dtype=object)
        if basis == "subject" and "" in set(groups):
            continue
        if any(len(set(g[labels == a].tolist())) >= 2 for a in set(labels.tolist())):
            return basis, g
    return "time", np.array(sources, dtype=object)


def _left_out(cb: CaseBase, basis: str, groups: np.ndarray, i: int) -> np.ndarray:
    """``(n,)`` bool: the cases not seen when case ``i`` is held out."""
    same = groups == groups[i]
    if basis != "time":
        return np.asarray(same)
    # a case whose frames are not known overlaps nothing but itself
    frames = frame_array(cb.frames)
    overlap = overlapping(frames[i], frames)
    left_out: np.ndarray = np.asarray(same & overlap) | (np.arange(len(cb)) == i)
    return left_out


Held = tuple[np.ndarray, np.ndarray, str, np.ndarray]
"""What :func:`held_out_activities` measures: distances, activities, basis and groups."""


def calibration_order(cb: Any) -> tuple[str, ...]:
    """The activities of the case base ``cb`` (anything with ``labels``) in the order the
    judges are calibrated in: its labels as text, sorted (:func:`held_out_activities`)."""
    return tuple(sorted(set(np.asarray(cb.labels).astype(str).tolist())))


def held_out_rows(cb: Any, sample: int = MARGIN_SAMPLE, seed: int = 0) -> np.ndarray:
    """The positions of the cases :func:`held_out_activities` holds out ``(m,)``, sorted: the
    real cases of ``cb`` (not mirror images), a seeded sample of ``sample`` when more."""
    real = np.arange(len(cb))
    if cb.names and cb.names[-1] == MIRROR_FLAG:
        real = real[np.asarray(cb.problems)[:, -1] == 0]
    if len(real) > sample:
        real = np.sort(np.random.default_rng(seed).choice(real, sample, replace=False))
    return real


def held_out_activities(cb: CaseBase, sample: int = MARGIN_SAMPLE, seed: int = 0) -> Held:
    """Training cases held out (:func:`held_out_basis`) as a new recording is: each one's
    distance to the nearest case of every activity that is left ``(n, n_classes)`` (inf
    where none is), each one's activity ``(n,)`` (its index among the sorted labels), the
    basis and each one's group ``(n,)`` (its subject or recording). A seeded sample of at
    most ``sample`` real cases (not mirror images) is held out, each against all cases."""
    classes = list(calibration_order(cb))
    codes = activity_codes(cb.labels, classes)
    basis, groups = held_out_basis(cb)
    index = cb.index  # builds the representations
    reps = cb.reps
    assert reps is not None
    real = held_out_rows(cb, sample, seed)
    seen = np.full((len(real), len(classes)), np.inf)
    for row, i in enumerate(real.tolist()):  # one scan of the case base per held-out case
        d = cb.measure.distances(reps[i], index)
        out = _left_out(cb, basis, groups, i)
        seen[row] = per_activity(np.where(out, np.inf, d), codes, len(classes))
    return seen, codes[real], basis, groups[real]


def known_rows(seen: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: the held-out cases (distances to every activity ``(n, n_classes)``, own
    activity ``codes`` ``(n,)``) whose own activity is within reach and another too."""
    finite = np.isfinite(seen)
    own = finite[np.arange(len(seen)), codes]
    return np.asarray(own & (finite.sum(axis=1) >= 2))


def known_and_novel(seen: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """From held-out cases' distances to every activity ``(n, n_classes)`` and their own
    activity ``(n,)``: the rows where the own activity is within reach and another too
    (``known``), and the rows without the own activity where two others are (``novel``), as
    ``(k, n_classes)`` arrays (the own activity's column set to inf in ``novel``)."""
    known = seen[known_rows(seen, codes)]
    without = seen.copy()
    without[np.arange(len(seen)), codes] = np.inf
    novel = without[np.isfinite(without).sum(axis=1) >= 2]
    return known, novel


def calibration_margins(
    cb: CaseBase, sample: int = MARGIN_SAMPLE, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, str]:
    """The margins of training cases held out (:func:`held_out_basis`) with their activity in
    the case base (``known``) and without it (``novel``), and the basis. A seeded sample of at
    most ``sample`` real cases (not mirror images) is held out, each against all cases."""
    seen, codes, basis, _ = held_out_activities(cb, sample, seed)
    known, novel = known_and_novel(seen, codes)
    return _margins(known), _margins(novel), basis


def _margins(nearest: np.ndarray) -> np.ndarray:
    """:func:`margin_of` of every row ``(n, n_classes)``: ``(n,)``."""
    if not len(nearest):
        return np.zeros(0)
    two = np.sort(np.asarray(nearest, dtype=np.float64), axis=1)[:, :2]
    if two.shape[1] < 2:
        return np.ones(len(two))
    apart = np.isfinite(two[:, 1]) & (two[:, 1] > 0.0)
    return np.where(apart, two[:, 0] / np.where(apart, two[:, 1], 1.0), 1.0)


HELD_OUT_ADVICE = "use `name='held-out'`"
"""What a refusal to calibrate a margin judge advises: :func:`judge_of`'s ``name`` (the
commands say ``--unknown held-out``); a Python caller given the default judge is told the
call instead (:func:`default_judge`)."""


def _check_margin_calibration(cb: CaseBase) -> None:
    """DataError when a case base has fewer than three activities (a held-out activity leaves
    one to compare with)."""
    if len(set(np.asarray(cb.labels).astype(str).tolist())) < 3:
        raise DataError(
            "fewer than three activities to calibrate the margin between the two nearest on"
            f" ({HELD_OUT_ADVICE}, or train with three or more)",
            "case base",
        )


def _no_apart() -> DataError:
    return DataError(
        f"no activity has cases apart from each other to calibrate the margin on ("
        f"{HELD_OUT_ADVICE}, or train with `cases='windows'` and two or more recordings of an"
        " activity)",
        "case base",
    )


_C = TypeVar("_C", bound="Calibrated")


class Calibrated:
    """A judge calibrated on a case base: a frozen dataclass stored with the fitted model as a
    plain record of its fields (:meth:`to_dict`, :meth:`from_dict`), so that ``segment`` and
    ``watch`` read it instead of scanning the case base each run. Generic over the fields: a
    new field (with a default, which a record stored before it takes) or a new judge (one
    line in :data:`STORED`) needs no code here. Fields are ``float`` (>= 0, not NaN; +inf is
    written ``"inf"``: JSON has none), ``int`` (>= 0), ``str``, ``tuple[float, ...]`` (a
    list of such numbers) or ``tuple[str, ...]`` (a list of texts).

    A field added once posecbr stored judges, which a reader that does not know it can do
    without, is marked ``metadata={ADDED: True}``: it is stored apart from the record
    (:func:`judges_apart`), where an older posecbr does not look (its reader refuses a record
    with a field it does not know: "unknown field 'activities'"), and a field stored apart
    that this reader does not know (a newer posecbr's) is ignored (:meth:`from_dict`)."""

    @classmethod
    def of(cls: type[_C], cb: CaseBase, *, held: Held | None = None) -> _C:
        """Calibrated on ``cb`` (``held``: its :func:`held_out_activities`, when measured)."""
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        """The fields as JSON-ready values."""
        return {
            f.name: _plain(getattr(self, f.name))
            for f in dataclasses.fields(typing.cast(Any, self))
        }

    @classmethod
    def from_dict(cls: type[_C], d: Mapping[str, Any], added: Any = None) -> _C:
        """The judge :meth:`to_dict` wrote (``d``), with the fields stored apart from it
        (``added``: :func:`judges_apart`; a field of it this reader does not know, a newer
        posecbr's, is ignored). ValueError naming the field for a record that is not one: an
        unknown field in ``d``, a missing one without a default, a wrong type, a negative or
        NaN number, a field stored both in ``d`` and apart or apart though not marked so."""
        if not isinstance(d, Mapping):
            raise ValueError(f"a stored judge must be a record of fields, got {d!r}")
        fields = {f.name: f for f in dataclasses.fields(typing.cast(Any, cls))}
        extra = sorted(set(d) - set(fields))
        if extra:
            raise ValueError(f"unknown field {extra[0]!r}")
        d = {**d, **_added_known(cls, fields, d, added)}
        types = typing.get_type_hints(cls)
        values = {}
        for name, f in fields.items():
            if name in d:
                values[name] = _field(name, types[name], d[name])
            elif f.default is dataclasses.MISSING:
                raise ValueError(f"field {name!r} is missing")
        return cls(**values)


ADDED = "added"
"""The metadata key marking a judge's field stored apart from its record
(:class:`Calibrated`)."""


def added_fields(cls: Any) -> tuple[str, ...]:
    """The fields of the judge (or judge class) ``cls`` stored apart from its record (marked
    :data:`ADDED`), in their order."""
    return tuple(f.name for f in dataclasses.fields(cls) if f.metadata.get(ADDED))


def _added_known(
    cls: Any, fields: Mapping[str, Any], d: Mapping[str, Any], added: Any
) -> dict[str, Any]:
    """The fields stored apart (``added``) that ``cls`` knows, checked against its record
    ``d`` (:meth:`Calibrated.from_dict`); the others, a newer posecbr's, left out."""
    if added is None:
        return {}
    if not isinstance(added, Mapping):
        raise ValueError(f"the fields stored apart must be a record of fields, got {added!r}")
    apart = set(added_fields(cls))
    out = {}
    for name in sorted(set(added) & set(fields)):
        if name in d:
            raise ValueError(f"field {name!r} is stored twice (in the record and apart)")
        if name not in apart:
            raise ValueError(f"field {name!r} is stored apart, where it is not kept")
        out[name] = added[name]
    return out


def _plain(value: Any) -> Any:
    """A field's value for JSON: +inf as ``"inf"``."""
    if isinstance(value, float) and math.isinf(value) and value > 0:
        return "inf"
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _field(name: str, kind: Any, value: Any) -> Any:
    """A stored field's value as its type ``kind`` (ValueError naming ``name`` when it is not
    one)."""
    if kind is float:
        number = math.inf if value == "inf" else value
        if isinstance(number, int | float) and not isinstance(number, bool) and number >= 0:
            return float(number)  # NaN fails the comparison
        raise ValueError(f"field {name!r} must be a number >= 0, got {value!r}")
    if kind is int:
        if isinstance(value, int) and not isinstance(value, bool) and value >= 0:
            return value
        raise ValueError(f"field {name!r} must be a whole number >= 0, got {value!r}")
    if kind is str:
        if isinstance(value, str) and value:
            return value
        raise ValueError(f"field {name!r} must be a non-empty text, got {value!r}")
    if typing.get_origin(kind) is tuple:  # tuple[float, ...], tuple[str, ...]
        (item, _) = typing.get_args(kind)
        if isinstance(value, list):
            return tuple(_field(name, item, v) for v in value)
        words = "numbers >= 0" if item is float else "texts"
        raise ValueError(f"field {name!r} must be a list of {words}, got {value!r}")
    raise ValueError(f"field {name!r} is of a type that is not stored ({kind!r})")


@dataclass(frozen=True)
class Margin(Calibrated):
    """Unknown when the nearest activity is hardly nearer than the next: margin ``d1 / d2``
    above ``threshold``, which at most a share ``false_unknown`` of the case base's own
    held-out known margins exceed (module docstring), and at least ``floor`` (when the case
    base cannot hold out a person: :func:`one_person_floor`; 0 otherwise, and in a record
    stored before it); ``basis``: how training cases were held out; ``known``/``novel``: how
    many margins of each kind were measured; ``reach``: how near held-out known cases lie to
    their nearest case, against which a recording's person offset is measured
    (:func:`person_reach`, :func:`for_person`; inf, no offset, when the case base holds out
    people, and in a record stored before it)."""

    threshold: float
    basis: str
    known: int
    novel: int
    false_unknown: float = FALSE_UNKNOWN
    floor: float = 0.0
    reach: float = math.inf

    @classmethod
    def of(
        cls, cb: CaseBase, false_unknown: float = FALSE_UNKNOWN, held: Held | None = None
    ) -> Margin:
        """Calibrated on ``cb`` for a false-unknown rate ``false_unknown`` (``held``: its
        :func:`held_out_activities`, when already measured). DataError when it cannot be:
        fewer than three activities (a held-out activity leaves one to compare with), or no
        activity whose cases can be held out from each other."""
        _check_margin_calibration(cb)
        seen, codes, basis, *_ = held if held is not None else held_out_activities(cb)
        known_rows, novel_rows = known_and_novel(seen, codes)
        known, novel = _margins(known_rows), _margins(novel_rows)
        if not len(known) or not len(novel):
            raise _no_apart()
        floor = one_person_floor(novel, basis)
        threshold = max(false_unknown_threshold(known, false_unknown), floor)
        reach = person_reach(known_rows, basis)
        return cls(threshold, basis, len(known), len(novel), false_unknown, floor, reach)

    def ratio(self, nearest: np.ndarray) -> float:
        return margin_of(nearest)

    def unlike(self, nearest: np.ndarray) -> bool:
        return margin_of(nearest) > self.threshold

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        first, second = two_nearest(nearest, classes)
        return (
            f"like no stored activity: the nearest ({first}) is {margin_of(nearest):.2f} as far"
            f" as the next ({second}); a known activity comes nearer than {self.threshold:.2f}"
            f" (in {percent(1.0 - self.false_unknown, 0)} of the case base's held-out cases)"
        )


JOINT_GRID = np.linspace(0.5, 1.0, 101)
"""The quantiles tried for the joint rule of :class:`MarginDistance`, lowest first."""


def joint_thresholds(
    margins: np.ndarray, distances: np.ndarray, above: float, budget: float
) -> tuple[float, float]:
    """The margin and distance ``(a, b)`` of the joint rule "margin above ``a`` and nearest
    case farther than ``b``": both the same quantile ``q`` of held-out known ``margins`` and
    ``distances`` (``(n,)`` each, paired; taken at sample values as
    :func:`false_unknown_threshold` takes them), the lowest ``q`` of :data:`JOINT_GRID` for
    which at most a share ``budget`` of the known cases that the margin alone (``above``)
    leaves known fall in the rule. ``(inf, inf)`` (the rule never fires) when none does."""
    alone = margins > above
    for q in JOINT_GRID.tolist():
        a = false_unknown_threshold(margins, 1.0 - q)
        b = false_unknown_threshold(distances, 1.0 - q)
        if np.mean((margins > a) & (distances > b) & ~alone) <= budget:
            return a, b
    return float("inf"), float("inf")


@dataclass(frozen=True)
class MarginDistance(Calibrated):
    """Unknown when the nearest activity is hardly nearer than the next (margin above
    ``margin``), or when it is only somewhat so (above ``joint_margin``) and the nearest case
    lies far (farther than ``joint_distance``): a window of a left-out movement is often both
    farther than usual and more ambiguous than usual, where a new person's known movement is
    farther but clear, or ambiguous but near. The case base's held-out known cases
    (:func:`held_out_activities`) share the budget ``false_unknown``: half to the margin
    alone (its ``1 - false_unknown / 2`` quantile), half to the joint rule
    (:func:`joint_thresholds`)."""

    margin: float
    joint_margin: float
    joint_distance: float
    basis: str
    known: int
    false_unknown: float = FALSE_UNKNOWN

    @classmethod
    def of(
        cls, cb: CaseBase, false_unknown: float = FALSE_UNKNOWN, held: Held | None = None
    ) -> MarginDistance:
        """Calibrated on ``cb``; ``held`` and DataError as :meth:`Margin.of`."""
        _check_margin_calibration(cb)
        seen, codes, basis, *_ = held if held is not None else held_out_activities(cb)
        known, novel = known_and_novel(seen, codes)
        if not len(known) or not len(novel):
            raise _no_apart()
        margins, distances = _margins(known), known.min(axis=1)
        alone = false_unknown_threshold(margins, false_unknown / 2.0)
        a, b = joint_thresholds(margins, distances, alone, false_unknown / 2.0)
        return cls(alone, a, b, basis, len(known), false_unknown)

    def ratio(self, nearest: np.ndarray) -> float:
        return margin_of(nearest)

    def unlike(self, nearest: np.ndarray) -> bool:
        m = margin_of(nearest)
        far = float(np.min(nearest)) > self.joint_distance
        return m > self.margin or (m > self.joint_margin and far)

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        first, second = two_nearest(nearest, classes)
        m = margin_of(nearest)
        text = f"like no stored activity: the nearest ({first}) is {m:.2f} as far as the next"
        if m > self.margin:
            return text + f" ({second}); a known activity comes nearer than {self.margin:.2f}"
        return text + (
            f" ({second}) and lies {float(np.min(nearest)) / self.joint_distance:.1f}x as far as"
            f" held-out cases of known activities with a margin above {self.joint_margin:.2f} do"
        )


NOVEL_CATCH = 0.8
"""With one person in the case base, the share of its held-out cases of a left-out activity
that the margin judge's thresholds still call unknown (:func:`one_person_floor`): the least
threshold is the margin that this share of them exceed. Chosen with the person offset taken
(:func:`for_person`) on case bases of one person (HDM05's actors, UI-PRMD's s01) segmenting
the others (``python -m benchmarks.segment_people --train-people 1``), never on CMU; seen
blocks named rightly / left-out blocks called unknown, with the offset unshrunk: 0.8 gave
the best mean (HDM05 97 / 67 %, Vicon 92 / 87 %, Kinect 62 / 62 %), 0.7 less (97 / 52,
98 / 83, 67 / 46 %), 0.9 lost HDM05's seen blocks (87 % right). As shipped (the offset
shrunk, :data:`PERSON_PRIOR`): HDM05 97 / 68 %, Vicon 86 / 89 %, Kinect 62 / 64 %. Without
the offset 0.5 was best: a new person's known margins rise towards the novel ones."""


def one_person_floor(novel: np.ndarray, basis: str) -> float:
    """The least threshold of :class:`ActivityMargin` and :class:`Margin` when the case base
    cannot hold out a person (``basis`` not "subject": its cases are held out from their own
    recording, or from the frames of their own that overlap them): the margin that
    :data:`NOVEL_CATCH` of the held-out cases with their own activity left out exceed (their
    margins ``novel`` ``(n,)``, of :func:`known_and_novel`); 0 when it can (basis "subject")
    or no such case is there.

    Held out from the same person, a known case lies nearer its activity than a new person's
    will: the budget of false unknowns read there is spent many times over on anyone else
    (with one person's cases, another person's known blocks called unknown: HDM05 67 %,
    UI-PRMD Vicon 100 %, Kinect 95 %). How far a new person's known movements lie the case
    base cannot tell; how unlike a movement it lacks looks it can: its thresholds are raised
    until they call only :data:`NOVEL_CATCH` of those unknown."""
    if basis == "subject":
        return 0.0
    return false_unknown_threshold(novel, NOVEL_CATCH) if len(novel) else 0.0


PERSON_QUANTILE = 0.1
"""Where a recording's distances to the case base and the case base's own held-out ones are
compared (:func:`person_reach`, :func:`person_offset`): their nearest tenth, which a
left-out movement inside the recording hardly reaches. Tried 0.1 and 0.25 on the one-person
runs of :data:`NOVEL_CATCH` (unshrunk): the same on HDM05; UI-PRMD Vicon's seen blocks right
/ left-out blocks unknown at catch 0.8 92 / 87 % at 0.1, 95 / 83 % at 0.25 (at 0.7: 98 / 83,
98 / 79 %)."""
PERSON_PRIOR = 8
"""How many windows' worth of no offset :func:`person_offset` starts from: a stream's first
few windows (4 s at one every half second) show too little of the person to tell how far
they lie, and in a short recording of nothing but a movement the case base lacks that
movement would be taken for how far the person lies (CMU 13_30's 4.3 s of squats, with a
case base of 13_29 and 13_31 without squats: 56 % of its blocks unknown unshrunk, at least
80 % shrunk). It costs UI-PRMD Vicon's other people 6 points of seen blocks (92 -> 86 %)."""


def person_reach(known: np.ndarray, basis: str) -> float:
    """How near the case base's held-out known cases lie (distances to every activity
    ``(n, n_classes)``, their own activity within reach): the :data:`PERSON_QUANTILE` quantile
    of their distances to the nearest case. inf (no offset is taken) when the case base holds
    out people (``basis`` "subject": its held-out cases already lie as far as a new person's)
    or has no such case."""
    if basis == "subject" or not len(known):
        return math.inf
    return float(np.quantile(np.min(known, axis=1), PERSON_QUANTILE))


def person_offset(nearest: np.ndarray, reach: float) -> float:
    """How much farther a recording lies from every case than the case base's own held-out
    cases do (``reach``, :func:`person_reach`), from its windows' distances to their nearest
    case ``nearest`` ``(n,)``: their :data:`PERSON_QUANTILE` quantile less ``reach``, at least
    0, shrunk towards 0 by :data:`PERSON_PRIOR` windows (``n / (n + PERSON_PRIOR)`` of it); 0
    when ``reach`` is inf or no window's distance is finite."""
    d = np.asarray(nearest, dtype=np.float64)
    d = d[np.isfinite(d)]
    if math.isinf(reach) or not len(d):
        return 0.0
    raw = max(float(np.quantile(d, PERSON_QUANTILE)) - reach, 0.0)
    return raw * len(d) / (len(d) + PERSON_PRIOR)


@dataclass(frozen=True)
class Offset:
    """A margin judge (:class:`Margin`, :class:`ActivityMargin`) of one recording's windows:
    their distances to every activity less ``offset`` (at least 0), how much farther this
    recording's person lies from every case than the case base's own held-out cases
    (:func:`person_offset`).

    Held out from one person's own recordings, a case lies nearer its activity than another
    person's movement will: a new person lies farther from every case, and the margin ``d1 /
    d2`` of a known movement rises towards 1, unlike but for the person. Taking the offset
    off every distance (the nearest tenth of the recording's windows brought to where the
    case base's own lie) gives back the margins the thresholds were read from. With one
    person's case base segmenting other people (and :data:`NOVEL_CATCH` raised with it), the
    seen blocks of UI-PRMD Vicon's people named rightly go from 75 to 86 %, HDM05's left-out
    blocks called unknown from 43 to 68 % (README, "Long recordings"). A recording of nothing
    but movements the case base lacks is taken in part for a far person: the offset cannot
    tell the two apart."""

    judge: Margin | ActivityMargin
    offset: float

    def less(self, nearest: np.ndarray) -> np.ndarray:
        """``nearest`` ``(n_classes,)`` less the offset, at least 0."""
        return np.maximum(np.asarray(nearest, dtype=np.float64) - self.offset, 0.0)

    def ratio(self, nearest: np.ndarray) -> float:
        return self.judge.ratio(self.less(nearest))

    def unlike(self, nearest: np.ndarray) -> bool:
        return self.judge.unlike(self.less(nearest))

    def evidence(self, nearest: np.ndarray) -> float:
        """:func:`unknown_evidence` of the inner judge, of the distances less the offset."""
        return unknown_evidence(self.judge, self.less(nearest))

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        text = self.judge.describe(self.less(nearest), classes)
        if self.offset <= 0.0:
            return text
        # "every distance less 2" read as "every distance below 2": say what was done
        return text + (
            f"; each distance taken {self.offset:.3g} shorter first: this person lies that"
            " much farther from every case than the case base's own held-out cases"
        )


def for_person(judge: Judge, nearest: np.ndarray) -> Judge:
    """``judge`` for the recording whose windows lie ``nearest`` ``(n,)`` from their nearest
    case: a margin judge with a ``reach`` (calibrated on a case base that cannot hold out a
    person) as :class:`Offset` of the recording's :func:`person_offset`; any other judge as
    it is."""
    if not isinstance(judge, Margin | ActivityMargin) or math.isinf(judge.reach):
        return judge
    return Offset(judge, person_offset(nearest, judge.reach))


def activity_thresholds(
    margins: np.ndarray, activities: np.ndarray, n_classes: int, rate: float, prior: float
) -> tuple[np.ndarray, float]:
    """Per activity ``(n_classes,)``, the threshold of :class:`ActivityMargin`, and the pooled
    one: from held-out known ``margins`` ``(n,)`` (non-empty) of cases of ``activities``
    ``(n,)`` (indices), the pooled threshold ``t`` (:func:`false_unknown_threshold` at
    ``rate``) and each activity's own ``t_a`` from its ``n_a`` margins, shrunk:
    ``(n_a t_a + prior t) / (n_a + prior)``; ``t`` for an activity without margins, and for
    every activity when ``prior`` is inf."""
    pooled = false_unknown_threshold(margins, rate)
    out = np.full(n_classes, pooled)
    if math.isinf(prior):
        return out, pooled
    for a in np.unique(activities).tolist():  # over activities (a few dozen at most)
        mine = margins[activities == a]
        own = false_unknown_threshold(mine, rate)
        # (n_a t_a + prior t) / (n_a + prior), written so that prior 0 gives t_a exactly
        # and t_a = t gives t (a margin equal to its threshold is not above it)
        w = len(mine) / (len(mine) + prior)
        out[a] = own if own == pooled else w * own + (1.0 - w) * pooled
    return out, pooled


def _quantile_at(counts: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """Where :func:`false_unknown_threshold` reads its quantile among ``counts`` sorted values
    at each rate of ``rates`` (each in [0, 1)): ``(len(rates), len(counts))``."""
    at = np.ceil(counts[None, :] * (1.0 - rates[:, None]) - 1e-9).astype(np.int64) - 1
    return np.maximum(at, 0)


def threshold_grid(
    margins: np.ndarray, activities: np.ndarray, n_classes: int, weights: Sequence[Weight]
) -> np.ndarray:
    """``(len(weights), n_classes)``: for every ``(rate, prior)`` of ``weights``, the
    per-activity thresholds of :func:`activity_thresholds` (arguments as there), the margins
    sorted once for all of them and every activity at once; the same numbers, computed
    alike."""
    rates = np.array([w[0] for w in weights], dtype=np.float64)
    priors = np.array([w[1] for w in weights], dtype=np.float64)
    for rate in rates.tolist():
        if not 0.0 <= rate < 1.0:
            raise ParameterError(
                f"the false-unknown rate must be in [0, 1), got {rate!r}", "weights"
            )
    margins = np.asarray(margins, dtype=np.float64)
    pooled = np.sort(margins)[_quantile_at(np.array([len(margins)]), rates)[:, 0]]
    out = np.repeat(pooled[:, None], n_classes, axis=1)
    order = np.lexsort((margins, activities))  # by activity, then margin
    present, starts, counts = np.unique(activities[order], return_index=True, return_counts=True)
    own = margins[order][starts[None, :] + _quantile_at(counts, rates)]  # (weights, present)
    w = counts[None, :] / (counts[None, :] + priors[:, None])
    with np.errstate(invalid="ignore"):  # 0 * inf, as activity_thresholds' floats give
        mixed = np.where(own == pooled[:, None], own, w * own + (1.0 - w) * pooled[:, None])
    shrunk = ~np.isinf(priors)  # an inf prior: the pooled threshold for every activity
    out[np.ix_(shrunk, present)] = mixed[shrunk]
    return out


def _rightly_named(seen: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: the held-out known cases (:func:`known_rows`) whose nearest activity is
    their own."""
    return np.asarray(known_rows(seen, codes) & (np.argmin(seen, axis=1) == codes))


Weight = tuple[float, float]
"""The quantile rate and the prior of :func:`activity_thresholds`."""


def inner_scores(
    seen: np.ndarray,
    codes: np.ndarray,
    groups: np.ndarray,
    weights: Sequence[Weight],
    power: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """For each ``(rate, prior)`` of ``weights``, how :class:`ActivityMargin`'s thresholds set
    from the other groups' held-out cases fare on each group's own, every group (subject or
    recording) held out in turn, as a new person is; from held-out cases' distances to every
    activity ``(n, n_classes)``, their activities and groups ``(n,)`` each. ``over``: the
    share of the held-out group's rightly named known cases above their activity's
    threshold; ``caught``: the share of its cases of an activity ``a`` above the threshold
    of their nearest other activity when ``a`` is gone (its column and its cases left out of
    the thresholds too, as from a case base without it). Both ``(len(weights),)``; 0 where
    there is nothing to count. ``power``: the margins are :class:`SpreadMargin`'s scores of
    that power (:func:`spread_scores`), each activity's spread read from the other groups'
    cases as the thresholds are; 0, the margins themselves."""
    over, caught = inner_grid(seen, codes, groups, weights, (power,))
    return over[0], caught[0]


def inner_grid(
    seen: np.ndarray,
    codes: np.ndarray,
    groups: np.ndarray,
    weights: Sequence[Weight],
    powers: Sequence[float] = (0.0,),
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`inner_scores` at every power of ``powers``, ``over`` and ``caught`` each
    ``(len(powers), len(weights))``: what the powers share (the groups held out, the
    activities gone, the spreads) is found once."""
    n_classes = seen.shape[1]
    over, caught = np.zeros((len(powers), len(weights))), np.zeros((len(powers), len(weights)))
    n_known = n_novel = 0
    spread = any(powers)
    right, margins = _rightly_named(seen, codes), _margins(seen)
    for g in np.unique(groups).tolist():  # over groups (subjects or recordings: a few)
        mine = groups == g
        train, test = right & ~mine, right & mine
        if not train.any():
            continue
        far = _spread_far(seen, activity_spreads(seen, codes, train)) if spread else margins
        n_known += int(test.sum())
        for i, power in enumerate(powers):
            scores = _scored(margins, far, power)
            per = threshold_grid(scores[train], codes[train], n_classes, weights)
            over[i] += np.sum(scores[test][None, :] > per[:, codes[test]], axis=1)
        for a in np.unique(codes[mine]).tolist():  # the group's activities, each gone in turn
            without = seen.copy()
            without[:, a] = np.inf
            kept = _rightly_named(without, codes) & ~mine & (codes != a)
            novel = mine & (codes == a) & (np.isfinite(without).sum(axis=1) >= 2)
            if not kept.any() or not novel.any():
                continue
            m, near = _margins(without), np.argmin(without[novel], axis=1)
            far = _spread_far(without, activity_spreads(without, codes, kept)) if spread else m
            n_novel += int(novel.sum())
            for i, power in enumerate(powers):
                scores = _scored(m, far, power)
                per = threshold_grid(scores[kept], codes[kept], n_classes, weights)
                caught[i] += np.sum(scores[novel][None, :] > per[:, near], axis=1)
    return over / max(n_known, 1), caught / max(n_novel, 1)


def choose_weight(
    seen: np.ndarray, codes: np.ndarray, groups: np.ndarray, budget: float = FALSE_UNKNOWN
) -> Weight:
    """The quantile rate (a share of ``budget``, :data:`RATE_SHARES`) and the prior
    (:data:`PRIOR_GRID`) of :class:`ActivityMargin`'s thresholds, chosen on the held-out cases
    themselves (:func:`inner_scores`; arguments as there): of those whose thresholds, set from
    the other groups, the held-out group's known cases exceed no more often than ``budget``,
    the one that calls most of a gone activity's cases unknown (on a tie the larger rate,
    then the larger prior: the less tuned). An activity's own quantile, read from a few
    people, is exceeded more often by the next person than the pooled one: the prior and the
    rate are what keep the budget on people the thresholds were not set from. The least
    over-call when none keeps it; ``(budget, ACTIVITY_PRIOR)`` when no activity has
    held-out cases in two groups (no held-out group then has an own threshold to test)."""
    right = _rightly_named(seen, codes)
    if not any(len(np.unique(groups[right & (codes == a)])) >= 2 for a in np.unique(codes)):
        return budget, ACTIVITY_PRIOR
    weights = [(budget * share, prior) for share in RATE_SHARES for prior in PRIOR_GRID]
    over, caught = inner_scores(seen, codes, groups, weights)
    within = [w for w in range(len(weights)) if over[w] <= budget]
    if within:
        best = max(within, key=lambda w: (caught[w], *weights[w]))
    else:
        best = min(range(len(weights)), key=lambda w: (over[w], -weights[w][0], -weights[w][1]))
    return weights[best]


@dataclass(frozen=True)
class ActivityMargin(Calibrated):
    """Unknown when the margin ``d1 / d2`` lies above the threshold of the nearest activity:
    ``thresholds[a]`` (``a`` the index among the case base's sorted activities) is the margin
    that a share ``rate`` of the held-out known cases of activity ``a`` exceed, among those
    whose nearest activity is their own (a case named wrongly is a wrong answer whether
    called unknown or not: it spends no budget), shrunk towards the pooled threshold
    ``pooled`` by ``prior`` cases' worth (:func:`activity_thresholds`). ``rate`` (at most the
    budget ``false_unknown``) and ``prior`` are chosen on the held-out cases so that a held-out
    subject's or recording's known cases keep the budget against thresholds set from the
    others' (:func:`choose_weight`); a record stored before they were chosen has the budget
    and 20. One pooled threshold is set by the activities that resemble each other most; an
    activity whose known cases are clear keeps a low one, so a window of a left-out movement
    nearest to it is caught. ``basis`` and ``known`` as :class:`Margin`'s (``known``: the
    rightly named cases). ``budget_thresholds``: the thresholds read at the whole budget
    ``false_unknown`` with the same prior, where the windows' graded evidence starts
    (:meth:`evidence`); empty in a record stored before (its evidence all or nothing).
    ``floor``: when the case base cannot hold out a person, no threshold (nor budget
    threshold) lies below it (:func:`one_person_floor`); 0 otherwise, and in a record stored
    before it. ``reach``: as :class:`Margin`'s. ``activities``: the names (as text) of the
    activities the values per activity are of, in their order (the case base's labels sorted
    as text when calibrated; the classifier's class order once :func:`judge_of` gives it), so
    that another classifier's judge is refused (:func:`cbr.segmentation.check_judge`); empty
    in a record stored before it (:func:`judge_of` names them: a stored judge was calibrated
    on the classifier's own cases)."""

    thresholds: tuple[float, ...]
    pooled: float
    basis: str
    known: int
    false_unknown: float = FALSE_UNKNOWN
    prior: float = ACTIVITY_PRIOR
    rate: float = FALSE_UNKNOWN
    budget_thresholds: tuple[float, ...] = ()
    floor: float = 0.0
    reach: float = math.inf
    activities: tuple[str, ...] = dataclasses.field(default=(), metadata={ADDED: True})

    def __post_init__(self) -> None:
        for name in ("budget_thresholds", "activities"):
            values = getattr(self, name)
            if values and len(values) != len(self.thresholds):
                raise ValueError(
                    f"field {name!r} has {len(values)} values for {len(self.thresholds)} activities"
                )

    @classmethod
    def of(
        cls,
        cb: CaseBase,
        false_unknown: float = FALSE_UNKNOWN,
        prior: float | None = None,
        held: Held | None = None,
    ) -> ActivityMargin:
        """Calibrated on ``cb``; ``held`` as :meth:`Margin.of`; the rate and the prior chosen on
        the held-out cases (:func:`choose_weight`) unless ``prior`` is given (then the rate is
        ``false_unknown``); DataError as :meth:`Margin.of`, and when no held-out known case is
        named rightly."""
        _check_margin_calibration(cb)
        seen, codes, basis, groups = held if held is not None else held_out_activities(cb)
        keep = known_rows(seen, codes)
        known, own = seen[keep], codes[keep]
        right = np.argmin(known, axis=1) == own if len(known) else np.zeros(0, dtype=bool)
        novel = _margins(known_and_novel(seen, codes)[1])
        if not right.any() or not len(novel):
            raise _no_apart()
        rate, prior = (
            choose_weight(seen, codes, groups, false_unknown)
            if prior is None
            else (false_unknown, prior)
        )
        margins = _margins(known[right])
        per, pooled = activity_thresholds(margins, own[right], seen.shape[1], rate, prior)
        budget, _ = activity_thresholds(margins, own[right], seen.shape[1], false_unknown, prior)
        floor = one_person_floor(novel, basis)
        per, budget = np.maximum(per, floor), np.maximum(budget, floor)
        known_n, reach = int(right.sum()), person_reach(known, basis)
        return cls(tuple(per.tolist()), pooled, basis, known_n, false_unknown, prior, rate,
                   tuple(budget.tolist()), floor, reach, calibration_order(cb))  # fmt: skip

    def threshold(self, nearest: np.ndarray) -> float:
        """The threshold of the window's nearest activity."""
        return self.thresholds[int(np.argmin(nearest))]

    def ratio(self, nearest: np.ndarray) -> float:
        return margin_of(nearest)

    def unlike(self, nearest: np.ndarray) -> bool:
        return self.ratio(nearest) > self.threshold(nearest)

    def evidence(self, nearest: np.ndarray) -> float:
        """How much the window says unknown, 0 to 1: 1 above its nearest activity's
        threshold (:meth:`unlike`), 0 at or below that activity's threshold at the whole
        budget (``budget_thresholds``: the margin ``false_unknown`` of its held-out known
        cases exceed), linear in the margin between. The threshold is read at a rate below
        the budget when the held-out groups say an activity's own quantile is exceeded more
        often by a new person (:func:`choose_weight`); a margin between the two is unlike by
        the case base's own cases but not by that safer threshold: half-way evidence, not
        none. All or nothing without ``budget_thresholds`` (a record stored before them) or
        when the rate is the budget (the two thresholds are one)."""
        m, high = self.ratio(nearest), self.threshold(nearest)
        if m > high:
            return 1.0
        if not self.budget_thresholds:
            return 0.0
        low = min(self.budget_thresholds[int(np.argmin(nearest))], high)
        return 0.0 if m <= low else (m - low) / (high - low)

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        first, second = two_nearest(nearest, classes)
        return (
            f"like no stored activity: the nearest ({first}) is {margin_of(nearest):.2f} as far"
            f" as the next ({second}); a known {first} comes nearer than"
            f" {self.threshold(nearest):.2f} (in {percent(1.0 - self.rate, 0)} of the case"
            " base's held-out cases)"
        )


SPREAD_POWERS = (0.0, 0.5, 1.0, 2.0, 4.0)
"""The powers of the spread :func:`choose_spread` tries (0: the margin alone, as
:class:`ActivityMargin`'s)."""


def activity_spreads(seen: np.ndarray, codes: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``(n_classes,)``: how far a held-out known case of each activity usually lies from
    that activity's nearest case, the median of the distances to their own activity of the
    held-out cases ``rows`` (``(n,)`` bool; distances to every activity ``seen`` ``(n,
    n_classes)``, activities ``codes`` ``(n,)``) of that activity; their pooled median for an
    activity without such a case (1 when there is none at all)."""
    own = seen[np.arange(len(seen)), codes]
    pooled = float(np.median(own[rows])) if rows.any() else 1.0
    out = np.full(seen.shape[1], pooled)
    for a in np.unique(codes[rows]).tolist():  # over activities (a few dozen at most)
        out[a] = float(np.median(own[rows & (codes == a)]))
    return out


def spread_scores(nearest: np.ndarray, spreads: np.ndarray, power: float) -> np.ndarray:
    """:class:`SpreadMargin`'s score of every row of ``nearest`` ``(n, n_classes)`` (distances
    to every activity): the margin ``d1 / d2`` times ``(d1 / s) ** power``, ``s`` the spread
    (:func:`activity_spreads`, ``(n_classes,)``) of the row's nearest activity. ``(n,)``."""
    nearest = np.asarray(nearest, dtype=np.float64)
    m = _margins(nearest)
    if not power or not len(nearest):
        return m
    return _scored(m, _spread_far(nearest, spreads), power)


def _spread_far(nearest: np.ndarray, spreads: np.ndarray) -> np.ndarray:
    """``(n,)``: the distance of every row of ``nearest`` ``(n, n_classes)`` (non-empty) to
    its nearest activity in that activity's spread ``spreads`` ``(n_classes,)`` (inf for a
    spread of 0, 1 when the distance is 0 too)."""
    a1 = np.argmin(nearest, axis=1)
    d1, s = nearest[np.arange(len(nearest)), a1], spreads[a1]
    return np.where(s > 0.0, d1 / np.where(s > 0.0, s, 1.0), np.where(d1 > 0.0, np.inf, 1.0))


def _scored(margins: np.ndarray, far: np.ndarray, power: float) -> np.ndarray:
    """:func:`spread_scores` from the rows' margins and :func:`_spread_far` ``(n,)`` each."""
    return margins if not power else np.asarray(margins * far**power)


def choose_spread(
    seen: np.ndarray, codes: np.ndarray, groups: np.ndarray, budget: float = FALSE_UNKNOWN
) -> tuple[float, float, float]:
    """The quantile rate, the prior and the power of :class:`SpreadMargin`, chosen on the
    held-out cases as :func:`choose_weight` chooses the first two (arguments as there), over
    the powers of :data:`SPREAD_POWERS` too: of the triples whose thresholds the held-out
    group's known cases exceed no more often than ``budget``, the one that calls most of a
    gone activity's cases unknown (on a tie the larger rate, prior, then the smaller power);
    the least over-call when none keeps it. ``(budget, ACTIVITY_PRIOR, 0)`` when no activity
    has held-out cases in two groups."""
    right = _rightly_named(seen, codes)
    if not any(len(np.unique(groups[right & (codes == a)])) >= 2 for a in np.unique(codes)):
        return budget, ACTIVITY_PRIOR, 0.0
    weights = [(budget * share, prior) for share in RATE_SHARES for prior in PRIOR_GRID]
    over, caught = inner_grid(seen, codes, groups, weights, SPREAD_POWERS)
    tried = [(p, w, over[i, w], caught[i, w]) for i, p in enumerate(SPREAD_POWERS)
             for w in range(len(weights))]  # fmt: skip
    within = [t for t in tried if t[2] <= budget]
    if within:
        p, w, *_ = max(within, key=lambda t: (t[3], *weights[t[1]], -t[0]))
    else:
        p, w, *_ = min(tried, key=lambda t: (t[2], -weights[t[1]][0], -weights[t[1]][1], t[0]))
    return weights[w][0], weights[w][1], p


@dataclass(frozen=True)
class SpreadMargin(ActivityMargin):
    """:class:`ActivityMargin` whose margin also weighs how far the window lies from its
    nearest activity in units of that activity's own spread (``--unknown spread-margin``):
    the score ``d1 / d2 * (d1 / spreads[a]) ** power``, ``a`` the nearest activity and
    ``spreads[a]`` the median distance of its rightly named held-out known cases to it
    (:func:`activity_spreads`), against per-activity thresholds of the score read as
    :class:`ActivityMargin` reads them from the margin. The power (0 to 4; 0: the margin
    alone), the rate and the prior are chosen on the held-out cases, every group held out in
    turn with the spreads read from the others (:func:`choose_spread`). A movement the case
    base lacks is often as clearly nearer one activity as a known one is, but farther from it
    than that activity's own cases lie from each other; the margin alone sees only the first
    (UI-PRMD Kinect, where every activity's cases lie loosely: README, "Unknown").

    Only with a case base that holds out people (basis "subject"): a spread read from one
    person's held-out cases says nothing of how far the next person's known movement lies,
    so a case base of one person gets the power 0 and ``spreads`` empty, the judge
    :class:`ActivityMargin` is (its floor and its person offset included)."""

    spreads: tuple[float, ...] = ()
    power: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.spreads and len(self.spreads) != len(self.thresholds):
            raise ValueError(
                f"field 'spreads' has {len(self.spreads)} values for"
                f" {len(self.thresholds)} activities"
            )

    @classmethod
    def of(  # type: ignore[override]
        cls,
        cb: CaseBase,
        false_unknown: float = FALSE_UNKNOWN,
        held: Held | None = None,
    ) -> SpreadMargin:
        """Calibrated on ``cb``; ``held`` and DataError as :meth:`ActivityMargin.of`."""
        held = held if held is not None else held_out_activities(cb)
        seen, codes, basis, groups = held
        if basis != "subject":
            plain = ActivityMargin.of(cb, false_unknown, held=held)
            return cls(**{f.name: getattr(plain, f.name) for f in dataclasses.fields(plain)})
        # ActivityMargin's DataErrors only: choose_spread chooses the weight (power 0 among)
        ActivityMargin.of(cb, false_unknown, ACTIVITY_PRIOR, held)
        rate, prior, power = choose_spread(seen, codes, groups, false_unknown)
        right = _rightly_named(seen, codes)
        spreads = activity_spreads(seen, codes, right)
        scores = spread_scores(seen[right], spreads, power)
        n_classes = seen.shape[1]
        per, pooled = activity_thresholds(scores, codes[right], n_classes, rate, prior)
        budget, _ = activity_thresholds(scores, codes[right], n_classes, false_unknown, prior)
        return cls(tuple(per.tolist()), pooled, basis, int(right.sum()), false_unknown, prior,
                   rate, tuple(budget.tolist()), 0.0, math.inf, calibration_order(cb),
                   tuple(spreads.tolist()), power)  # fmt: skip

    def ratio(self, nearest: np.ndarray) -> float:
        """The score: the margin times the nearest distance in spreads of the nearest
        activity to the power ``power`` (the margin when ``spreads`` is empty)."""
        if not self.spreads:
            return margin_of(nearest)
        row = np.asarray(nearest, dtype=np.float64)[None, :]
        return float(spread_scores(row, np.asarray(self.spreads), self.power)[0])

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        if not self.spreads or not self.power:
            return super().describe(nearest, classes)
        first, second = two_nearest(nearest, classes)
        a = int(np.argmin(nearest))
        return (
            f"like no stored activity: the nearest ({first}) is {margin_of(nearest):.2f} as far"
            f" as the next ({second}) and {float(np.min(nearest)) / self.spreads[a]:.1f}x as far"
            f" as a known {first} usually lies; together {self.ratio(nearest):.2f}, where a"
            f" known {first} stays below {self.threshold(nearest):.2f} (in"
            f" {percent(1.0 - self.rate, 0)} of the case base's held-out cases)"
        )


@dataclass(frozen=True)
class SpreadFar(SpreadMargin):
    """:class:`SpreadMargin` with a far bound on the window's distance to its nearest case
    (``--unknown spread-far``): unknown when ``d1`` lies beyond ``far``, as
    :class:`SpreadMargin` judges at or below it. ``far``: the nearest distance that at most
    a share ``false_unknown`` of the case base's held-out known cases exceed
    (:func:`false_unknown_threshold` of their distances to their nearest case, from the same
    held-out scan as the thresholds). A window farther from every case than nearly every
    held-out known case lies is unlike them, however clearly nearer one activity than the
    next (a margin judge sees only the ratio). With a case base of one person the bound is
    read the same way and the judge, as :class:`ActivityMargin`, sees the distances less the
    person offset (:func:`for_person`): the bound is compared with those. ``far`` inf (the
    judge is :class:`SpreadMargin`) in a record without it or when no held-out case is
    known."""

    far: float = math.inf

    @classmethod
    def of(  # type: ignore[override]
        cls,
        cb: CaseBase,
        false_unknown: float = FALSE_UNKNOWN,
        held: Held | None = None,
    ) -> SpreadFar:
        """Calibrated on ``cb``; ``held`` and DataError as :meth:`SpreadMargin.of`."""
        held = held if held is not None else held_out_activities(cb)
        return cls.bounding(SpreadMargin.of(cb, false_unknown, held=held), held)

    @classmethod
    def bounding(cls, inner: SpreadMargin, held: Held) -> SpreadFar:
        """``inner`` (calibrated on the held-out scan ``held``) with the far bound read from
        that scan at its budget ``false_unknown``."""
        fields = {f.name: getattr(inner, f.name) for f in dataclasses.fields(inner)}
        known, _ = known_and_novel(held[0], held[1])
        if not len(known):
            return cls(**fields)
        far = false_unknown_threshold(np.min(known, axis=1), inner.false_unknown)
        return cls(**fields, far=far)

    def beyond(self, nearest: np.ndarray) -> bool:
        """Whether the window's nearest distance lies beyond ``far``."""
        return float(np.min(nearest)) > self.far

    def unlike(self, nearest: np.ndarray) -> bool:
        return self.beyond(nearest) or super().unlike(nearest)

    def evidence(self, nearest: np.ndarray) -> float:
        """1 beyond ``far``, else :meth:`SpreadMargin.evidence`."""
        return 1.0 if self.beyond(nearest) else super().evidence(nearest)

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        if not self.beyond(nearest) or super().unlike(nearest):
            return super().describe(nearest, classes)
        first, _ = two_nearest(nearest, classes)
        return (
            f"like no stored activity: its nearest case ({first}) lies"
            f" {float(np.min(nearest)):.3g} away, farther than {self.far:.3g} (which"
            f" {percent(self.false_unknown, 0)} of the case base's held-out cases exceed)"
        )


@dataclass(frozen=True)
class HeldOut:
    """The classifier's stored calibration (:class:`cbr.novelty.NoveltyCalibration`): unknown
    when the nearest case lies farther than held-out training clips nearly ever do."""

    calibration: NoveltyCalibration

    def ratio(self, nearest: np.ndarray) -> float:
        return self.calibration.ratio(float(np.min(nearest)))

    def unlike(self, nearest: np.ndarray) -> bool:
        return self.calibration.unlike(float(np.min(nearest)))

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        first = classes[int(np.argmin(nearest))]
        return (
            f"unlike every stored case: even the nearest ({first}) lies "
            f"{self.ratio(nearest):.1f}x the case base's usual nearest-case distance away"
        )


@dataclass(frozen=True)
class Familiarity(Calibrated):
    """Unknown when the nearest case lies as far as different activities of the case base
    lie from each other (then it is no more that case's activity than the others are).

    ``threshold``: the median, over the cases, of the distance to the nearest case of another
    activity; ``reference`` (the unit of the ratio): the median distance from a case to its
    nearest case of the same activity from another source (another recording or video:
    what a new recording of a known activity is to the case base; cases cut from one
    recording are near copies), or, where no activity has two sources, to its nearest other
    case."""

    reference: float
    threshold: float

    @classmethod
    def of(cls, cb: CaseBase, *, held: Held | None = None) -> Familiarity:
        """Calibrated on ``cb``. DataError for one activity."""
        del held  # the margins' scan: this judge measures its own distances
        if len(cb.classes) < 2:
            raise DataError("a case base of one activity cannot say what is unlike it", "case base")
        within, between = _neighbour_distances(cb)
        reference = float(np.median(within)) or float(np.mean(within)) or 1.0
        return cls(reference, float(np.median(between)))

    def ratio(self, nearest: np.ndarray) -> float:
        """Nearest-case distance in units of the case base's usual neighbour distance."""
        return float(np.min(nearest)) / self.reference

    def unlike(self, nearest: np.ndarray) -> bool:
        return float(np.min(nearest)) > self.threshold

    def describe(self, nearest: np.ndarray, classes: Sequence[str]) -> str:
        first = classes[int(np.argmin(nearest))]
        return (
            f"unlike every stored case: even the nearest ({first}) lies as far as the case "
            f"base's activities lie from each other ({self.ratio(nearest):.1f}x its usual "
            "nearest-case distance)"
        )


def _neighbour_distances(cb: CaseBase) -> tuple[np.ndarray, np.ndarray]:
    """Per case: the distance to its nearest same-activity case from another source (``within``;
    every case's nearest other case when no activity has two sources) and to its nearest case
    of another activity (``between``)."""
    sources = np.array(cb.sources, dtype=object)
    labels = cb.labels
    index = cb.index
    assert cb.reps is not None
    within, nearest, between = [], [], []
    for i in range(len(cb)):  # one query against the whole case base per case
        d = cb.measure.distances(cb.reps[i], index)
        same = labels == labels[i]
        between.append(float(d[~same].min()))
        nearest.append(float(np.delete(d, i).min()))
        peers = same & (sources != sources[i])
        if peers.any():
            within.append(float(d[peers].min()))
    return np.asarray(within or nearest), np.asarray(between)


STORED: dict[str, type[Calibrated]] = {
    "margin": Margin,
    "margin-distance": MarginDistance,
    "activities": Familiarity,
    "activity-margin": ActivityMargin,
    "spread-margin": SpreadMargin,
    "spread-far": SpreadFar,
}
"""The judges calibrated on the case base, by name: calibrated when a model is stored
(:func:`calibrate_judges`) and stored with it. (``held-out`` reads the classifier's novelty
calibration, already stored.)"""


AT_FIT = ("margin", "margin-distance", "activity-margin", "spread-margin", "spread-far")
"""The judges calibrated when a model is stored: the margins, from one held-out scan of the
case base for at most :data:`MARGIN_SAMPLE` cases (grows linearly with the case base);
``spread-margin``'s choice of power, rate and prior adds about 0.05-0.2 s of CPU to it
(:func:`inner_grid`; UI-PRMD case bases of 120 to 4,252 cases); ``spread-far`` takes
``spread-margin``'s and the held-out cases' nearest distances (:meth:`SpreadFar.bounding`).
``activities`` measures every case against every other (grows with the square: 4 s of CPU
on 4,252 cases, hours on the 100,000 of a 50,000-clip training set) and is calibrated when
asked for, as before."""


def calibrate_judges(cb: CaseBase, names: Sequence[str] = tuple(STORED)) -> dict[str, Calibrated]:
    """The judges ``names`` (of :data:`STORED`) calibrated on ``cb``, by name; the margin
    judges share one held-out scan of the case base. A judge the case base cannot calibrate
    (fewer than three activities, no activity with cases apart) is left out: ``segment``
    then says why, as it did before judges were stored."""
    three = len(set(np.asarray(cb.labels).astype(str).tolist())) >= 3
    held = held_out_activities(cb) if three and set(AT_FIT) & set(names) else None
    out: dict[str, Calibrated] = {}
    for name in names:
        inner = out.get("spread-margin")
        if name == "spread-far" and isinstance(inner, SpreadMargin) and held is not None:
            out[name] = SpreadFar.bounding(inner, held)  # one choice of the spread, not two
            continue
        try:
            out[name] = STORED[name].of(cb, held=held)
        except DataError:
            continue
    return out


def judges_to_dict(judges: Mapping[str, Calibrated]) -> dict[str, dict[str, Any]]:
    """The calibrated judges as JSON-ready records, by name."""
    return {name: judge.to_dict() for name, judge in judges.items()}


def judges_apart(
    judges: Mapping[str, Calibrated],
) -> tuple[dict[str, dict[str, Any]], dict[str, dict[str, Any]]]:
    """The calibrated judges as JSON-ready records by name (:func:`judges_to_dict`) without
    the fields marked :data:`ADDED`, and those fields by name (judges with none left out):
    what a posecbr stores, so that one older than such a field reads the records (it refuses
    a field it does not know) and ignores the rest. :func:`judges_from_dict` joins them."""
    records: dict[str, dict[str, Any]] = {}
    apart: dict[str, dict[str, Any]] = {}
    for name, judge in judges.items():
        record = judge.to_dict()
        moved = {f: record.pop(f) for f in added_fields(judge) if f in record}
        records[name] = record
        if moved:
            apart[name] = moved
    return records, apart


def judges_from_dict(d: Mapping[str, Any], added: Any = None) -> dict[str, Calibrated]:
    """The judges :func:`judges_to_dict` wrote (``d``), or :func:`judges_apart` (``d`` its
    records, ``added`` the fields stored apart: those of a judge not in ``d``, as those a
    judge does not know, are what a reader may do without, and are left out). ValueError
    naming the judge and the field for a record that is not one (an unknown judge's name
    included)."""
    if not isinstance(d, Mapping):
        raise ValueError(f"the stored judges must be a record by name, got {d!r}")
    if added is None:
        added = {}
    if not isinstance(added, Mapping):
        raise ValueError(f"the judges' fields stored apart must be a record by name, got {added!r}")
    out: dict[str, Calibrated] = {}
    for name, record in d.items():
        if name not in STORED:
            raise ValueError(f"unknown judge {name!r}")
        try:
            out[name] = STORED[name].from_dict(record, added.get(name))
        except ValueError as exc:
            raise ValueError(f"{name}: {exc.args[0]}") from None
    return out


def unknown_evidence(judge: Judge, nearest: np.ndarray) -> float:
    """How much a window whose distances to every activity are ``nearest`` ``(n_classes,)``
    says it is like none, 0 to 1: graded by :meth:`ActivityMargin.evidence`, all or nothing
    (:meth:`Judge.unlike`) by every other judge."""
    if isinstance(judge, ActivityMargin | Offset):
        return judge.evidence(nearest)
    return 1.0 if judge.unlike(nearest) else 0.0


def tell_unknown(judged: Sequence[tuple[Judge, np.ndarray]], classes: Sequence[str]) -> str:
    """Why a stretch decoded unknown is, in words, from its windows: each one's judge and
    distances to the nearest case of every activity ``(n_classes,)``. Told by the median
    (by the judge's ratio; the upper one of two) of the windows the judge calls unlike
    every activity. When none of them is, the stretch is unknown on the evidence around it
    (a block no window within one activity covers takes its neighbours' evidence, and every
    change of label needs :data:`cbr.segmentation.MIN_SEGMENT_S` of it): the words say so
    instead of quoting a window the judge finds like an activity. "" without windows."""
    if not judged:
        return ""
    unlike = [(j, n) for j, n in judged if j.unlike(n)]
    told_by = unlike or list(judged)
    ratios = [j.ratio(n) for j, n in told_by]
    judge, nearest = told_by[int(np.argsort(ratios, kind="stable")[len(ratios) // 2])]
    if unlike:
        return judge.describe(nearest, classes)
    first, _ = two_nearest(nearest, classes)
    return (
        f"unknown on the evidence around it; its own windows (nearest: {first}) are not"
        " unlike every stored activity"
    )


def judge_of(clf: Any, name: str) -> Judge:
    """The judge called ``name`` (:data:`JUDGES`) for the fitted classifier ``clf``: the one
    stored with it (``clf.judges_``, calibrated when it was stored on the cases it holds) when
    there is one, else calibrated now on its case base (a model stored before judges were, or
    after its cases changed, or one fitted in memory). An unfitted ``clf`` is refused with
    scikit-learn's ``NotFittedError``, anything else that is no case base classifier (None,
    ``load_classifier``'s ``StoredClassifier``) with InputError naming ``clf``; a ``name`` not
    of :data:`JUDGES` with ParameterError (a ConfigError and a ValueError) naming the argument
    (before, "--unknown", the option of the commands, whose own choices refuse it first)."""
    if name not in JUDGES:
        raise ParameterError(f"unknown judge {name!r}: one of {', '.join(JUDGES)}", "name")
    check_case_base_classifier(clf, "fit it (or load a stored one) before judging with it")
    stored = getattr(clf, "judges_", None) or {}
    if name in stored:
        judge: Judge = stored[name]
        return in_class_order(judge, clf)
    if name == "held-out":
        return HeldOut(clf.novelty_)
    return in_class_order(STORED[name].of(clf.case_base_), clf)  # type: ignore[arg-type]


def in_class_order(judge: Judge, clf: Any) -> Judge:
    """``judge`` with its values per activity (:class:`ActivityMargin`'s thresholds, budget
    thresholds and spreads: calibrated in the order of the case base's labels sorted as text,
    :func:`held_out_activities`) in the order of ``clf.classes_``, the order of the columns
    of the distances it is given (:func:`cbr.segmentation.segment`), its ``activities`` with
    them. They differ for labels fitted as numbers (``classes_`` 2, 10; as text "10" < "2").
    A judge stored without its activities' names (before they were stored) is named from
    ``clf``'s case base, which it was calibrated on."""
    if not isinstance(judge, ActivityMargin):
        return judge
    if not judge.activities:
        judge = dataclasses.replace(judge, activities=calibration_order(clf.case_base_))
    mine, theirs = [str(c) for c in clf.classes_], list(judge.activities)
    if mine == theirs or sorted(mine) != sorted(theirs):
        return judge  # in order already, or not of these activities (check_judge says so)
    order = [theirs.index(c) for c in mine]
    fields: dict[str, Any] = {}
    for f in ("thresholds", "budget_thresholds", "spreads", "activities"):
        values = getattr(judge, f, ())
        if values:
            fields[f] = tuple(values[i] for i in order)
    return dataclasses.replace(judge, **fields)


def default_judge(clf: Any) -> Judge:
    """The judge :func:`cbr.segmentation.segment` and :class:`cbr.live.LiveSegmenter` use when
    given none: :func:`judge_of` ``clf``'s ``spread-margin`` (:data:`JUDGES` [0]). A case base
    it cannot be calibrated on (fewer than three activities, or none with cases apart) is
    refused with the DataError :func:`judge_of` raises, advising the Python call that judges
    it instead (``judge=judge_of(clf, "held-out")``) where :func:`judge_of`'s words advise its
    ``name='held-out'`` (the commands' ``--unknown held-out``)."""
    try:
        return judge_of(clf, JUDGES[0])
    except DataError as exc:
        if HELD_OUT_ADVICE not in exc.message:
            raise
        advice = 'pass judge=cbr.unknown.judge_of(clf, "held-out")'
        raise DataError(exc.message.replace(HELD_OUT_ADVICE, advice), exc.source) from None


__all__ = [
    "ACTIVITY_PRIOR",
    "HELD_OUT_ADVICE",
    "default_judge",
    "AT_FIT",
    "ActivityMargin",
    "JUDGES",
    "SPREAD_POWERS",
    "SpreadMargin",
    "SpreadFar",
    "activity_spreads",
    "choose_spread",
    "spread_scores",
    "STORED",
    "Calibrated",
    "calibrate_judges",
    "ADDED",
    "added_fields",
    "judges_apart",
    "judges_from_dict",
    "judges_to_dict",
    "MARGIN_SAMPLE",
    "Familiarity",
    "HeldOut",
    "Judge",
    "Margin",
    "MarginDistance",
    "Offset",
    "PERSON_PRIOR",
    "PERSON_QUANTILE",
    "for_person",
    "person_offset",
    "person_reach",
    "activity_codes",
    "activity_thresholds",
    "choose_weight",
    "inner_scores",
    "PRIOR_GRID",
    "RATE_SHARES",
    "known_rows",
    "held_out_activities",
    "held_out_rows",
    "joint_thresholds",
    "known_and_novel",
    "calibration_margins",
    "calibration_order",
    "equal_error_threshold",
    "false_unknown_threshold",
    "FALSE_UNKNOWN",
    "held_out_basis",
    "judge_of",
    "margin_of",
    "per_activity",
    "tell_unknown",
    "unknown_evidence",
]
