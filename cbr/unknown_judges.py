"""The judges of "unknown": each a rule over a window's distances to the nearest case of every
activity ``(n_classes,)``, calibrated on the case base itself, with its words for why a window
is unknown.

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
  point where both err equally, :func:`cbr.unknown_thresholds.equal_error_threshold`, depends on
  which activities happen to be left out and, set there, called a third of new people's known
  movements unknown.) A ratio of distances needs no common unit, so a new person who lies farther
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
  known cases' do (not the default: on people not in the case base it caught more left-out
  blocks on one dataset for some of its seen ones, and none more on another;
  docs/measurements.md, "Figures behind the code's rules: Unknown: the far bound and loose
  activities").
- With a case base of one person (held out by recording or by time, not by person), the two
  margin judges also have a floor (:func:`one_person_floor`) and see each recording's
  distances less how much farther its person lies from every case than the case base's own
  held-out cases (:func:`cbr.unknown.for_person`, :class:`cbr.unknown.Offset`): a threshold read
  from one person cannot know how far the next one lies, but the recording's nearest windows can
  tell.
- :class:`HeldOut`: the classifier's stored calibration (:mod:`cbr.novelty`, the distance
  score of the flag ``classify`` gives; its feature score needs a clip's answer): the nearest
  case lies farther than held-out training clips nearly ever do.
- :class:`Familiarity`: the nearest case lies as far as the case base's activities lie from
  each other.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from features.errors import DataError
from features.text import percent

from .casebase import CaseBase
from .novelty import NoveltyCalibration
from .unknown_held_out import (
    Held,
    calibration_order,
    held_out_activities,
    known_and_novel,
    known_rows,
)
from .unknown_person import person_reach
from .unknown_records import ADDED, Calibrated
from .unknown_thresholds import (
    ACTIVITY_PRIOR,
    FALSE_UNKNOWN,
    activity_thresholds,
    false_unknown_threshold,
    joint_thresholds,
    margin_of,
    margins_of,
    one_person_floor,
)
from .unknown_weights import (
    activity_spreads,
    choose_spread,
    choose_weight,
    rightly_named,
    spread_scores,
)


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


def two_nearest(nearest: np.ndarray, classes: Sequence[str]) -> tuple[str, str]:
    """The nearest and next nearest activities of a window with distances ``nearest``
    ``(n_classes,)`` to each activity's nearest case (the nearest twice when there is one)."""
    order = np.argsort(nearest, kind="stable")
    first = classes[int(order[0])]
    return first, classes[int(order[1])] if len(order) > 1 else first


HELD_OUT_ADVICE = "use `name='held-out'`"
"""What a refusal to calibrate a margin judge advises: :func:`cbr.unknown.judge_of`'s ``name`` (the
commands say ``--unknown held-out``); a Python caller given the default judge is told the
call instead (:func:`cbr.unknown.default_judge`)."""


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


@dataclass(frozen=True)
class Margin(Calibrated):
    """Unknown when the nearest activity is hardly nearer than the next: margin ``d1 / d2``
    above ``threshold``, which at most a share ``false_unknown`` of the case base's own
    held-out known margins exceed (module docstring), and at least ``floor`` (when the case
    base cannot hold out a person: :func:`one_person_floor`; 0 otherwise, and in a record
    stored before it); ``basis``: how training cases were held out; ``known``/``novel``: how
    many margins of each kind were measured; ``reach``: how near held-out known cases lie to
    their nearest case, against which a recording's person offset is measured
    (:func:`person_reach`, :func:`cbr.unknown.for_person`; inf, no offset, when the case base
    holds out people, and in a record stored before it)."""

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
        known, novel = margins_of(known_rows), margins_of(novel_rows)
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
        margins, distances = margins_of(known), known.min(axis=1)
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
    as text when calibrated; the classifier's class order once :func:`cbr.unknown.judge_of`
    gives it), so that another classifier's judge is refused
    (:func:`cbr.segmentation.check_judge`); empty in a record stored before it
    (:func:`cbr.unknown.judge_of` names them: a stored judge was calibrated on the classifier's
    own cases)."""

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
        novel = margins_of(known_and_novel(seen, codes)[1])
        if not right.any() or not len(novel):
            raise _no_apart()
        rate, prior = (
            choose_weight(seen, codes, groups, false_unknown)
            if prior is None
            else (false_unknown, prior)
        )
        margins = margins_of(known[right])
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
    (where every activity's cases lie loosely, as a noisy sensor's do).

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
        right = rightly_named(seen, codes)
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
    person offset (:func:`cbr.unknown.for_person`): the bound is compared with those. ``far``
    inf (the judge is :class:`SpreadMargin`) in a record without it or when no held-out case is
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
