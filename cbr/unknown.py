"""When a stretch of a recording is none of the case base's activities ("unknown"): the judge a
fitted classifier segments with (the one stored with it or calibrated now, in its classes'
order, taken for one recording's person) and its word on a window and on a stretch.

The judges and their calibration are modules of their own: the held-out scan
(:mod:`cbr.unknown_held_out`), the thresholds read from it (:mod:`cbr.unknown_thresholds`) and
their weights chosen on it (:mod:`cbr.unknown_weights`), a one-person case base's person offset
(:mod:`cbr.unknown_person`), the judges (:mod:`cbr.unknown_judges`, whose docstring tells them
apart), a judge as a stored record (:mod:`cbr.unknown_records`) and the judges stored with a
model (:mod:`cbr.unknown_stored`). The names of them that the README, the tests and
:mod:`cbr.live` take from here are imported here too; other code imports each from its own
module.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from features.errors import DataError, ParameterError

from .estimator_protocol import check_case_base_classifier
from .judges import JUDGES
from .unknown_held_out import (
    activity_codes,
    calibration_order,
    held_out_activities,
    held_out_basis,
    known_and_novel,
    known_rows,
)
from .unknown_judges import (
    HELD_OUT_ADVICE,
    ActivityMargin,
    HeldOut,
    Judge,
    Margin,
    MarginDistance,
    SpreadFar,
    SpreadMargin,
    two_nearest,
)
from .unknown_person import PERSON_PRIOR, person_offset
from .unknown_records import Calibrated
from .unknown_stored import (
    AT_FIT,
    STORED,
    calibrate_judges,
    judges_apart,
    judges_from_dict,
    judges_to_dict,
)
from .unknown_thresholds import (
    ACTIVITY_PRIOR,
    FALSE_UNKNOWN,
    NOVEL_CATCH,
    activity_thresholds,
    calibration_margins,
    equal_error_threshold,
    false_unknown_threshold,
    joint_thresholds,
    margin_of,
    one_person_floor,
    threshold_grid,
)
from .unknown_weights import (
    SPREAD_POWERS,
    activity_spreads,
    choose_spread,
    choose_weight,
    inner_grid,
    inner_scores,
    spread_scores,
)


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
    person's case base segmenting other people (and :data:`NOVEL_CATCH` raised with it), more
    of their seen blocks are named rightly and more left-out blocks called unknown
    (docs/measurements.md, "Segmentation with one person's case base, and on other labs'
    people, measured"). A recording of nothing
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
    "judges_apart",
    "judges_from_dict",
    "judges_to_dict",
    "HeldOut",
    "Judge",
    "Margin",
    "MarginDistance",
    "Offset",
    "PERSON_PRIOR",
    "for_person",
    "person_offset",
    "activity_codes",
    "activity_thresholds",
    "choose_weight",
    "inner_scores",
    "known_rows",
    "held_out_activities",
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
    "tell_unknown",
    "unknown_evidence",
    "two_nearest",
    "NOVEL_CATCH",
    "one_person_floor",
    "threshold_grid",
    "inner_grid",
    "in_class_order",
]
