"""Explanations in words a person can check.

The default text (:attr:`Explanation.text`) is at most four lines:

1. the answer and its confidence (a probability, calibrated in fit), and whether the clip is
   unlike the stored cases;
2. why: the few features whose value in the clip is typical of that answer's cases and
   unlike the other activities' (per-feature evidence: how much likelier the clip's value is
   among the answer's cases than among the others'), in units, with the answer's usual range;
   for a repetition check (a case base of correct and incorrect repetitions), what the clip
   did outside the range of the correct repetitions;
3. the nearest case of the answer and the nearest case of another label (a clip's mirror
   image is the same clip, not a second neighbour);
4. the fewest changes, in units, that make the classifier answer that other label, computed
   and checked (:mod:`cbr.counterfactual`).

:attr:`Explanation.verbose` adds the vote, every retrieved case, what the clip shares with
the similar cases and what not (a fluent state held less than half of the time is said to
hold "at times"; a difference smaller than the state's spread among cases of one activity is
not reported as presence against absence), the differences from the nearest case of the other
label and the counterfactual's checks. Every statement is also kept as a :class:`Claim`, so
:mod:`cbr.consistency` can check it against the data.

When the clip moves its left side more and is compared as its mirror image
(``Problem.mirrored``), the words name the clip's sides as recorded.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from features.body import swap_side
from features.targets import truth_value

from .calibration import UNCALIBRATED
from .casebase import CaseBase
from .counterfactual import MAX_CHANGES, Counterfactual, counterfactual
from .problem import ANGLE_PREFIX, POSITION_PREFIX, RATE_PREFIX, Problem
from .profiles import Profiles, View, profiles_of, view_of
from .retrieve import Retrieval, nearest_of_other_label
from .reuse import Weights
from .weights import MIRROR_FLAG
from .words import MIRRORED as MIRRORED
from .words import class_noun as class_noun

if TYPE_CHECKING:
    from .estimator import Solved

SEEN_FRACTION = 0.15
#: a QMP is shown by the similar cases when at least this share of them detect it
SHARED_BY = 0.5
#: a fluent state held at least this share of the clip is a steady property of it
STEADY_FRACTION = 0.5
MAX_LISTED = 6
MAX_TEXT = 400
#: the likelihood ratio a feature's value must reach to be said to decide the answer
MIN_EVIDENCE = float(np.log(4.0))
#: features named on the "why" line and changes shown on the counterfactual line at most
SHORT_ITEMS = 3


def presence(values: np.ndarray) -> np.ndarray:
    """Share of frames where each feature's confidence >= 0.5.

    values: ``(..., frames, n_features)`` fluent sequences -> ``(..., n_features)``, or
    ``(..., n_features)`` QMP vectors (pass ``values[..., None, :]``).
    """
    shares: np.ndarray = np.asarray(np.asarray(values) >= 0.5, dtype=np.float64).mean(axis=-2)
    return shares


def state_columns(names: tuple[str, ...]) -> tuple[np.ndarray, bool] | None:
    """The columns "seen" is judged on, and whether they are clip-summary means: the fluent
    states (not joint angles or positions, which are no yes/no features); None when that is
    every column."""
    summary = any("@" in n for n in names)
    keep = [
        i
        for i, n in enumerate(names)
        if not n.startswith((ANGLE_PREFIX, POSITION_PREFIX))
        and n != MIRROR_FLAG
        and (not summary or n.endswith("@mean"))
    ]
    if not summary and len(keep) == len(names):
        return None
    return np.array(keep, dtype=np.int64), summary


def quantity(name: str, value: float) -> tuple[float, str]:
    """A problem column's value in its own unit: joint angles in degrees (stored as radians /
    pi), positions in torso lengths; a fluent state's mean (over the clip or a phase of it) is
    its mean confidence ("share": near the share of the frames it holds when its confidences
    are near 0 or 1, but not where the angle stays near a threshold, so it is said as a mean
    confidence, not as a share of the time), its lowest and highest values are confidences,
    its variation a plain number."""
    base, _, stat = name.partition("@")
    if stat.startswith(RATE_PREFIX):
        return float(value), ""  # a rate of change per clip length: a plain number
    if base.startswith(ANGLE_PREFIX):
        return float(value) * 180.0, "degrees"
    if base.startswith(POSITION_PREFIX):
        return float(value), "torso lengths"
    if stat == "mean" or stat.startswith("phase"):
        return float(value), "share"
    if stat == "std":
        return float(value), ""  # the spread of a confidence
    return float(value), "confidence"


def said(value: float, unit: str) -> str:
    """A value in its unit as people write it: 62°, mean confidence 0.40, 0.36 torso lengths."""
    if unit == "degrees":
        return f"{value:.0f}°"
    if unit == "share":
        return f"mean confidence {value:.2f}"
    if unit == "confidence":
        return f"confidence {value:.2f}"
    if unit == "detected":
        return "shown" if value >= 0.5 else "not shown"
    return f"{value:.2f} {unit}".rstrip()


def _span(low: float, high: float, unit: str) -> str:
    """A range in a unit: 45–80°, 0.20–0.60 (mean confidences; torso lengths, said with the
    value); one value when both ends read alike (159°, not 159–159°); "-0.85 to -0.84" when
    an end is negative ("-0.85–-0.84" read as a double minus)."""
    if unit == "degrees":
        a, b = f"{low:.0f}", f"{high:.0f}"
        return f"{a}°" if a == b else f"{a}–{b}°"
    a, b = f"{low:.2f}", f"{high:.2f}"
    if a == b:
        return a
    return f"{a} to {b}" if a.startswith("-") or b.startswith("-") else f"{a}–{b}"


def label_words(label: str, target: str | None = None, article: bool = True) -> str:
    """A solution as people say it: for a repetition check (``target`` "correct", or labels
    "correct" / "incorrect") a correct / an incorrect repetition (``article`` False: correct
    repetition); else the label itself."""
    if target == "correct" or label in ("correct", "incorrect"):
        truth = truth_value(label)
        if truth is not None:
            words = "correct repetition" if truth else "incorrect repetition"
            return (("a " if truth else "an ") + words) if article else words
    return label


@dataclass(frozen=True)
class Claim:
    """One statement about one readable column (:mod:`cbr.profiles`): ``part`` the list it
    belongs to ("why", "outside", "change", "matched", "not_seen", "only_here",
    "difference"), ``column`` its machine name and ``feature`` its feature's, the clip's value
    ``here`` (None: the clip did not show it, a change claim's only) and what it is compared
    with: ``there`` (a case's value or a label's mean), the
    ``low``-``high`` usual range of ``label``'s cases; ``steady``: said to hold for most of the
    clip (fluent states in the presence lists)."""

    part: str
    column: str
    feature: str
    words: str
    here: float | None
    unit: str
    there: float | None = None
    low: float | None = None
    high: float | None = None
    label: str | None = None
    steady: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass(frozen=True)
class Contrast:
    """The nearest case of another label (``position`` in the case base, store ``case_id``),
    and the counterfactual toward that label: ``changes`` (claims, one per changed feature,
    the guide's value as ``there``), whether it holds (``valid``: the classifier answers
    ``label`` for the changed clip; ``answer`` what it answers), the case whose values were
    copied (``guide`` its position, ``guide_case_id``) and ``plausibility`` (see
    :mod:`cbr.counterfactual`)."""

    label: str
    case_id: int
    source: str
    distance: float
    changes: tuple[Claim, ...] = ()
    valid: bool = False
    answer: str = ""
    guide_case_id: int | None = None
    plausibility: float = float("nan")
    position: int = -1
    guide: int | None = None
    guide_source: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "case_id": self.case_id,
            "source": self.source,
            "mirrored": self.source.endswith(MIRRORED),  # as each neighbour's
            "distance": self.distance,
            "changes": [c.to_dict() for c in self.changes],
            "valid": self.valid,
            "answer": self.answer,
            "guide_case_id": self.guide_case_id,
            "guide_source": self.guide_source,
            # NaN when no counterfactual was found: null in JSON
            "plausibility": self.plausibility if np.isfinite(self.plausibility) else None,
        }


@dataclass(frozen=True)
class Explanation:
    """One clip's explanation: the answer (``label``, calibrated ``confidence``,
    ``vote_share``; ``confidence_calibrated`` False when the case base could not calibrate
    it and the confidence is the vote share), the retrieved cases one per clip
    (``neighbours``: ``case_id``, -1 for a case not stored, ``position`` in the case base,
    ``label``, ``distance``, ``source``), the fluent states (or QMPs) shared with the similar
    cases and not (``matched``, ``not_seen``, ``only_here``; "(at times)" when held under half
    the clip), the nearest case of another label with the checked counterfactual
    (``contrast``), the four-line ``text``, the ``verbose`` text, every statement as a
    :class:`Claim` and whether the clip was compared as its mirror image."""

    label: str
    confidence: float
    neighbours: tuple[dict[str, Any], ...]
    matched: tuple[str, ...]
    not_seen: tuple[str, ...]
    only_here: tuple[str, ...]
    contrast: Contrast | None
    text: str = field(default="")
    verbose: str = field(default="")
    claims: tuple[Claim, ...] = ()
    vote_share: float = float("nan")
    mirrored: bool = False
    # for the few features that set the clip apart from the nearest case of the other label:
    # {"feature", "here", "there", "unit"} in the feature's own units
    differences: tuple[dict[str, Any], ...] = ()
    confidence_calibrated: bool = True

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "confidence": self.confidence,
            "confidence_calibrated": self.confidence_calibrated,
            "vote_share": self.vote_share,
            "neighbours": list(self.neighbours),
            "matched": list(self.matched),
            "not_seen": list(self.not_seen),
            "only_here": list(self.only_here),
            "contrast": None if self.contrast is None else self.contrast.to_dict(),
            "text": self.text,
            "verbose": self.verbose,
            "claims": [c.to_dict() for c in self.claims],
            "mirrored": self.mirrored,
            "differences": list(self.differences),
        }


# -------------------------------------------------------------------------- reading columns


@dataclass(frozen=True)
class _Reading:
    """One clip read against a case base: its view values ``x``, the view, the profiles, the
    learned importance of each view column (``importance``, 0 where the measure ignores it)
    and whether words must name the other side (the clip was mirrored)."""

    cb: CaseBase
    view: View
    prof: Profiles
    x: np.ndarray
    importance: np.ndarray
    mirrored: bool
    readable: np.ndarray  # (m,) bool: in degrees, torso lengths, a share of the time, or a QMP
    angles: np.ndarray  # (m,) bool: joint angles (degrees)
    states: np.ndarray  # (m,) bool: the share of the time a fluent state holds
    state_means: np.ndarray  # the columns of fluent states' clip means (presence lists)
    qmps: np.ndarray  # the columns of a QMP vector's QMPs, each detected or not (presence lists)
    seen: np.ndarray  # (m,) the share of all cases at or above SEEN_FRACTION
    known: np.ndarray  # (m,) bool: measured in the clip (False: a fill, Problem.unseen)

    def prefer_angles(self, score: np.ndarray) -> np.ndarray:
        """``score`` with joint angles ahead of near-equal others: people check an angle most
        easily (with a goniometer, by eye), a position or a share of the time less so."""
        return np.where(self.angles & (score > 0), score * ANGLE_PREFERENCE, score)

    def words(self, j: int) -> str:
        w = self.view.words[j]
        return swap_side(w) if self.mirrored else w

    def unit(self, j: int) -> tuple[float, str]:
        if self.view.binary[j] and "@" not in self.view.names[j]:
            return float(self.x[j]), "detected"
        return quantity(self.view.names[j], float(self.x[j]))

    def value(self, j: int, v: float) -> float:
        return float(v) if self.view.binary[j] and "@" not in self.view.names[j] else (
            quantity(self.view.names[j], float(v))[0]
        )  # fmt: skip

    def claim(
        self,
        part: str,
        j: int,
        *,
        there: float | None = None,
        low: float | None = None,
        high: float | None = None,
        label: str | None = None,
        steady: bool = False,
    ) -> Claim:
        """A claim about view column ``j``, the compared values in the column's unit."""
        here, unit = self.unit(j)

        def conv(v: float | None) -> float | None:
            return None if v is None else self.value(j, v)

        feature = self.view.features[self.view.feature[j]]
        return Claim(part, self.view.names[j], feature, self.words(j), here, unit,
                     conv(there), conv(low), conv(high), label, steady)  # fmt: skip


def _importance(cb: CaseBase, view: View) -> np.ndarray:
    """How much each view column counts in the measure: its learned weight (z-normalised
    multiplier times spread, squared) where the measure has weights, else 1."""
    mult = getattr(cb.measure, "multiplier", None)
    if mult is None or view.sequence or len(mult) != cb.problems.shape[-1]:
        return np.ones(len(view.names))
    m = np.asarray(mult, dtype=np.float64)[view.columns]
    spread = cb.problems[:, view.columns].std(axis=0)
    w = (m * spread) ** 2
    return np.asarray(w / w.mean() if w.mean() > 0 else w, dtype=np.float64)


def read(cb: CaseBase, problem: Problem) -> _Reading:
    """The clip's problem read through the case base's view."""
    view = view_of(cb)
    x = view.of(np.asarray(problem.values, dtype=np.float64)[None])[0]
    if "importance" not in cb.cache:
        # filled aside and put in the cache at once: another thread explaining with the same
        # case base (watch's verdicts, judged on a thread of their own, while the frame loop
        # explains a segment) finds all of it or none
        units = [quantity(n, 0.0)[1] for n in view.names]
        filled = {
            "importance": _importance(cb, view),
            "angles": np.array([u == "degrees" for u in units]),
            "readable": np.array(
                [(view.binary[j] and "@" not in n) or (units[j] in READABLE and "@std" not in n)
                 for j, n in enumerate(view.names)]
            ),
            "states": np.array([u == "share" for u in units]),
            "state_means": np.array(
                [j for j, nm in enumerate(view.names)
                 if nm.endswith("@mean") and not nm.startswith((ANGLE_PREFIX, POSITION_PREFIX))],
                dtype=np.intp,
            ),
            "qmps": np.flatnonzero(
                view.binary & np.array(["@" not in n for n in view.names], dtype=bool)
            ),
            # of the whole case base, the same for every clip: read once, not per explanation
            "seen": (view.of(cb.problems) >= SEEN_FRACTION).mean(axis=0),
        }  # fmt: skip
        cb.cache.update(filled)
    known = np.array([n.split("@", 1)[0] not in problem.unseen for n in view.names], dtype=bool)
    return _Reading(
        cb, view, profiles_of(cb), x, cb.cache["importance"], bool(problem.mirrored),
        cb.cache["readable"], cb.cache["angles"], cb.cache["states"], cb.cache["state_means"],
        cb.cache["qmps"], cb.cache["seen"], known,
    )  # fmt: skip


#: how much more an angle counts than another feature when choosing what to say
ANGLE_PREFERENCE = 1.25
#: units people read without a legend (a confidence's extremes and any variation are left to
#: --verbose)
READABLE = ("degrees", "torso lengths", "share")


# -------------------------------------------------------------------------- the "why" line


def _rest(prof: Profiles, row: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of every column over the cases of all labels but
    ``row``'s."""
    others = [i for i in range(len(prof.labels)) if i != row]
    if not others:  # a case base of one activity (feedback relabelled the other's last case)
        unknown = np.full(prof.mean.shape[1:], np.nan)
        return unknown, unknown.copy()  # as 0 / 0 gave, without its RuntimeWarning
    n = prof.count[others][:, None]
    mean = (n * prof.mean[others]).sum(axis=0) / n.sum()
    var = (n * (prof.sd[others] ** 2 + (prof.mean[others] - mean) ** 2)).sum(axis=0) / n.sum()
    return mean, np.sqrt(var)


def evidence(r: _Reading, label: str) -> np.ndarray:
    """Per view column, the log likelihood ratio of the clip's value among ``label``'s cases
    against the other labels' cases (normal densities, spreads no narrower than half the
    spread within one label; binary columns: smoothed shares, and only for a QMP the clip
    shows); -inf where the value is not typical of ``label`` (outside the usual range of its
    cases, :data:`cbr.profiles.TYPICAL`), the measure ignores the column or people cannot
    read it."""
    prof = r.prof
    row = prof.row(label)
    mean_r, sd_r = _rest(prof, row)
    floor = np.maximum(np.maximum(0.5 * prof.within, 0.05 * prof.overall), 1e-6)
    sd_l = np.maximum(prof.sd[row], floor)
    sd_o = np.maximum(sd_r, floor)
    x = r.x
    cont = (
        -np.log(sd_l) - 0.5 * ((x - prof.mean[row]) / sd_l) ** 2
        + np.log(sd_o) + 0.5 * ((x - mean_r) / sd_o) ** 2
    )  # fmt: skip
    n_l, n_o = prof.count[row], prof.count.sum() - prof.count[row]
    p_l = (np.clip(prof.mean[row], 0.0, 1.0) * n_l + 1.0) / (n_l + 2.0)
    p_o = (np.clip(mean_r, 0.0, 1.0) * n_o + 1.0) / (n_o + 2.0)
    binary = np.where(x >= 0.5, np.log(p_l / p_o), -np.inf)
    e = np.where(r.view.binary, binary, cont)
    typical = r.view.binary | ((x >= prof.low[row]) & (x <= prof.high[row]))
    # a fluent state the clip holds (almost) never is no feature of the clip
    shown = ~r.states | (x >= SEEN_FRACTION)
    return np.where(typical & shown & (r.importance > 0) & r.readable & r.known, e, -np.inf)


def margin(r: _Reading, own: np.ndarray, other: np.ndarray) -> np.ndarray | None:
    """Per view column, how much it brings the clip nearer to case ``own`` than to case
    ``other`` under the measure (weighted squared differences; they add up to the difference
    of the squared distances); None for sequence problems, whose distance does not split."""
    if r.view.sequence:
        return None
    cols = r.view.columns
    q, a, b = r.x, np.asarray(own)[cols], np.asarray(other)[cols]
    mult = getattr(r.cb.measure, "multiplier", None)
    w = np.ones(len(cols)) if mult is None else np.asarray(mult, dtype=np.float64)[cols] ** 2
    return np.asarray(w * ((q - b) ** 2 - (q - a) ** 2), dtype=np.float64)


def _best_per_feature(r: _Reading, score: np.ndarray, n: int, minimum: float) -> list[int]:
    """The best-scoring column of each of the ``n`` best features (score >= ``minimum``)."""
    out: list[int] = []
    taken: set[int] = set()
    for j in np.argsort(-score, kind="stable"):
        if not score[j] >= minimum or len(out) == n:
            break
        f = int(r.view.feature[j])
        if f not in taken:
            taken.add(f)
            out.append(int(j))
    return out


def why_claims(
    r: _Reading, label: str, near: tuple[int, int] | None, n: int = SHORT_ITEMS
) -> list[Claim]:
    """The features that decided ``label``: characteristic of its cases, shown here
    (:func:`evidence`) and, for vector problems, bringing the clip nearer to the nearest case
    of ``label`` than to the nearest case of another label (``near``: their positions)."""
    e = evidence(r, label)
    if near is not None:
        m = margin(r, r.cb.problems[near[0]], r.cb.problems[near[1]])
        if m is not None:
            e = np.where(m > 0, e, -np.inf)
    row = r.prof.row(label)
    # ranked by evidence times the column's weight in the measure: what decided it
    score = np.full(len(e), -np.inf)
    ok = e >= MIN_EVIDENCE
    score[ok] = e[ok] * np.sqrt(r.importance[ok])
    score = r.prefer_angles(score)
    return [
        r.claim(
            "why",
            j,
            low=r.prof.low[row, j],
            high=r.prof.high[row, j],
            label=label,
            there=r.prof.mean[row, j],
        )  # fmt: skip
        for j in _best_per_feature(r, score, n, 0.0)
    ]


def outside_claims(r: _Reading, reference: str, n: int = SHORT_ITEMS) -> list[Claim]:
    """Where the clip lies outside the usual range of ``reference``'s cases (the correct
    repetitions) by more than the spread within one label, the most important first."""
    prof = r.prof
    row = prof.row(reference)
    spread = np.maximum(prof.within, np.maximum(0.05 * prof.overall, 1e-6))
    beyond = np.maximum(prof.low[row] - r.x, r.x - prof.high[row])
    # how far outside, in spreads; features the measure weighs below average count for less
    score = np.where(r.view.binary, 0.0, beyond / spread) * np.sqrt(np.minimum(r.importance, 1))
    ok = (beyond / spread >= 1.0) & r.readable & r.known
    score = np.where(ok, r.prefer_angles(score), -np.inf)
    return [
        r.claim(
            "outside",
            j,
            low=prof.low[row, j],
            high=prof.high[row, j],
            label=reference,
            there=prof.mean[row, j],
        )  # fmt: skip
        for j in _best_per_feature(r, score, n, 0.0)
    ]


# -------------------------------------------------------------------------- presence lists


def presence_claims(
    r: _Reading, label: str, similar: np.ndarray
) -> tuple[list[Claim], list[Claim], list[Claim]]:
    """What the clip shares with its similar cases of ``label`` (``similar``: positions) and
    what not: fluent states (clip-summary means; for sequences, the mean over the clip) the
    clip holds at least :data:`SEEN_FRACTION` of the time against the similar cases' mean, and
    a QMP vector's QMPs, detected in the clip or not, against whether most of the similar
    cases (at least :data:`SHARED_BY`) show them. A feature is in one list only, and a
    difference within the spread of the feature among cases of one label is no presence
    against absence."""
    cols = np.concatenate([r.state_means, r.qmps]).astype(np.intp)
    if not len(cols):
        return [], [], []
    cases = r.view.of(r.cb.problems[similar])[:, cols].mean(axis=0)
    here = r.x[cols]
    spread = r.prof.within[cols]
    distinct = 1.0 - r.seen[cols]
    apart = np.abs(here - cases) > spread
    # a fluent state is shown by the similar cases when their mean share of the time reaches
    # SEEN_FRACTION; a QMP (detected or not in each case) when most of them detect it
    shared_by = np.where(np.arange(len(cols)) < len(r.state_means), SEEN_FRACTION, SHARED_BY)
    q_seen, c_seen = here >= SEEN_FRACTION, cases >= shared_by
    known = r.known[cols]  # a state the clip could not show is neither shared nor missed
    lists: list[list[Claim]] = []
    for mask, score in (
        (known & q_seen & c_seen, distinct * here),
        (known & ~q_seen & c_seen & apart, distinct * cases),
        (known & q_seen & ~c_seen & apart, distinct * here),
    ):
        idx = np.flatnonzero(mask)
        idx = idx[np.argsort(-score[idx], kind="stable")][:MAX_LISTED]
        lists.append(
            [
                r.claim(
                    "",
                    int(cols[i]),
                    there=float(cases[i]),
                    label=label,
                    steady=bool(here[i] >= STEADY_FRACTION),
                )  # fmt: skip
                for i in idx
            ]
        )
    parts = ("matched", "not_seen", "only_here")
    matched, not_seen, only_here = (
        [
            Claim(
                p,
                c.column,
                c.feature,
                c.words,
                c.here,
                c.unit,
                c.there,
                c.low,
                c.high,
                c.label,
                c.steady if p != "not_seen" else False,
            )
            for c in lst
        ]  # fmt: skip
        for p, lst in zip(parts, lists, strict=True)
    )
    return matched, not_seen, only_here


def _held(c: Claim) -> str:
    """A fluent state in a presence list: "left knee bent" or "left knee bent (at times)"."""
    return c.words if c.steady or c.part == "not_seen" else f"{c.words} (at times)"


# -------------------------------------------------------------------------- counterfactual


def change_claims(r: _Reading, cf: Counterfactual, guide: np.ndarray) -> list[Claim]:
    """One claim per changed feature (a joint: every column measured at it takes the guide
    case's value): the column of it that differs most (weighted, angles first when near) between
    the clip and the guide, with the guide's value."""
    g = r.view.of(np.asarray(guide)[None])[0]
    out = []
    for f in cf.features:
        cols = np.flatnonzero(r.view.feature == f)
        if r.known[cols].any():  # the clip's value of an unseen column is a fill
            cols = cols[r.known[cols]]
        if r.readable[cols].any():
            cols = cols[r.readable[cols]]
        spread = np.maximum(r.prof.within[cols], 1e-9)
        gap = np.abs(r.x[cols] - g[cols]) / spread * np.sqrt(np.maximum(r.importance[cols], 1e-12))
        j = int(cols[int(np.argmax(np.where(r.angles[cols], gap * ANGLE_PREFERENCE, gap)))])
        claim = r.claim("change", j, there=float(g[j]), label=cf.label)
        out.append(claim if r.known[j] else dataclasses.replace(claim, here=None))
    return out


_SIDEWAYS = re.compile(r"(?P<joint>.+) to the (?P<side>left|right)(?P<stat> \(.+\))?")
_TURNED = {" (lowest)": " (highest)", " (highest)": " (lowest)"}


def _sideways(words: str, unit: str, *values: float | None) -> tuple[str, float]:
    """A sideways position said the way its values point: "right knee to the left" with
    every value at or below 0 (-0.31, its cases -0.35 to -0.24) reads "right knee to the
    right" with the values negated (0.31, 0.24-0.35), as people say where a joint is; its
    lowest is then its highest. The words and the sign to multiply the values by (1: as
    they were)."""
    known = [v for v in values if v is not None]
    m = _SIDEWAYS.fullmatch(words)
    if unit != "torso lengths" or m is None or not known or any(v > 0 for v in known):
        return words, 1.0
    stat = m["stat"] or ""
    if stat == " (variation)" or all(v == 0 for v in known):
        return words, 1.0
    side = "right" if m["side"] == "left" else "left"
    return f"{m['joint']} to the {side}{_TURNED.get(stat, stat)}", -1.0


def _change_text(c: Claim) -> str:
    if c.unit == "detected":
        return f"{'not ' if c.there is not None and c.there < 0.5 else ''}show {c.words}"
    words, sign = _sideways(c.words, c.unit, c.here, c.there)
    there = sign * c.there if c.there is not None else float("nan")
    if c.here is None:
        return f"{words} not seen → {said(there, c.unit)}"
    return f"{words} {_pair(sign * c.here, there, c.unit, ' → ', '')}"


def _pair(a: float, b: float, unit: str, between: str, after: str = "") -> str:
    """Two values in one unit, the unit's words said once: "mean confidence 0.96 → 0.79",
    "-0.32 → -0.54 torso lengths", "0.20 torso lengths here, 0.06 there" (``after``
    follows the second value); degrees keep their sign on each ("62° → 80°")."""
    if unit in ("degrees", "detected"):  # a sign on each value, or words that are the value
        return f"{said(a, unit)}{between}{said(b, unit)}{after}"
    if unit in ("share", "confidence") or after:  # the unit with the first value
        return f"{said(a, unit)}{between}{b:.2f}{after}"
    return f"{a:.2f}{between}{said(b, unit)}"  # the unit after the last value


def _difference_text(d: dict[str, Any]) -> str:
    """One of the features that differ most from the nearest case of another label: "left
    knee angle (lowest) 62° here, 80° there"."""
    words, sign = _sideways(d["feature"], d["unit"], d["here"], d["there"])
    return f"{words} {_pair(sign * d['here'], sign * d['there'], d['unit'], ' here, ', ' there')}"


def _claim_text(c: Claim, whose: str) -> str:
    """``left knee angle (lowest) 62° (its cases: 45–80°)``: ``whose`` names the cases the
    range is of."""
    if c.unit == "detected":
        share = "" if c.there is None else f" (in {100 * c.there:.0f} % of {whose})"
        return f"{c.words}{share}"
    words, sign = _sideways(c.words, c.unit, c.here, c.low, c.high)
    rng = ""
    if c.low is not None and c.high is not None and whose:
        low, high = sorted((sign * c.low, sign * c.high))
        rng = f" ({whose}: {_span(low, high, c.unit)})"
    return f"{words} {'not seen' if c.here is None else said(sign * c.here, c.unit)}{rng}"


# -------------------------------------------------------------------------- neighbours


def clip_of(source: str) -> str:
    """The clip a case comes from: its source without the mirror-image mark."""
    return source.removesuffix(MIRRORED)


def distinct_neighbours(cb: CaseBase, retrieval: Retrieval) -> list[int]:
    """Positions in ``retrieval`` of its cases, one per clip: a clip's mirror image (a case
    whose source is the clip's source and " (mirrored)") is the same clip, not a second
    neighbour."""
    plain: set[str] = set()
    images: set[str] = set()
    keep = []
    for pos, i in enumerate(retrieval.indices.tolist()):
        source = cb.sources[i]
        clip = clip_of(source)
        image = source.endswith(MIRRORED)
        if clip and clip in (plain if image else images):
            continue
        (images if image else plain).add(clip)
        keep.append(pos)
    return keep


def _short_source(source: str, position: int | None = None) -> str:
    """The file name of a case's clip; a clip given as arrays (the Python API: no source) is
    named by the case's ``position`` in the case base (``case 3``: ``case_base_`` row 3)."""
    mirrored = source.endswith(MIRRORED)
    name = Path(clip_of(source)).name
    if not name:
        name = "?" if position is None else f"case {position}"
    return name + (MIRRORED if mirrored else "")


def _line_items(head: str, items: Sequence[str], budget: int) -> str:
    """``head`` and as many ``items`` (at least one) as fit in ``budget`` characters."""
    out = head + items[0]
    for it in items[1:]:
        if len(out) + 2 + len(it) > budget:
            break
        out += "; " + it
    return out


def _reference(labels: Sequence[str], target: str | None) -> str | None:
    """In a repetition check (two labels read as correct / incorrect: ``target`` "correct",
    or labels "correct" and "incorrect"), the label of the correct repetitions."""
    if len(labels) != 2 or not (target == "correct" or set(labels) == {"correct", "incorrect"}):
        return None
    return next((lab for lab in labels if truth_value(lab) is True), None)


def _cf_line(contrast: Contrast, name: str, shown: int) -> str:
    """The counterfactual in words, with at most ``shown`` of its changes."""
    changes = contrast.changes
    if not contrast.answer:  # not searched
        return f"Nearest other label: {name}."
    if not contrast.valid or not changes:
        return f"No change of up to {MAX_CHANGES} features makes it {name}."
    said_ = "; ".join(_change_text(c) for c in changes[:shown])
    if len(changes) <= shown:
        return f"To be {name}: {said_}."
    return f"To be {name}, {_count(len(changes), 'change')}, e.g. {said_}."


def explain(
    cb: CaseBase,
    solved: Solved,
    answer: Callable[[np.ndarray | Problem], str],
    *,
    target: str | None = None,
    unlike_ratio: float | None = None,
    k: int = 5,
    weights: Weights = "distance",
    balanced: bool = False,
    counterfactual_search: bool = True,
    confidence: str,
    calibrated: bool = True,
) -> Explanation:
    """Explain one classification (:meth:`cbr.estimator.CaseBaseClassifier.solve`);
    ``answer`` classifies a problem the way the classifier does (to check counterfactuals);
    ``target`` the column the labels come from ("correct": repetition words); ``k`` and
    ``weights`` the classifier's vote, ``balanced`` whether it divides each class's votes by
    its share of the cases (the counterfactual search follows it);
    ``counterfactual_search`` False leaves the counterfactual out (callers that need the
    neighbours only: it costs a few retrievals per feature changed); ``confidence`` what the
    confidence is (:attr:`cbr.calibration.ConfidenceCalibration.words`), for the verbose
    lines; ``calibrated`` False: it is the vote share, not calibrated, and the first line says
    so."""
    problem, label = solved.problem, solved.solution.label
    r = read(cb, problem)
    near = _nearest(cb, solved)
    outside, why = _reasons(r, label, target, near)
    contrast = (
        None
        if near.other is None
        else _contrast(
            cb, r, problem, near.other, answer, k, weights, counterfactual_search, balanced
        )
    )
    lines = _short(cb, solved, target, outside, why, near.own, contrast, calibrated)
    retrieval = solved.retrieval
    win = retrieval.indices[retrieval.labels.astype(str) == label]
    presence_ = presence_claims(r, label, win if len(win) else retrieval.indices)
    differences = _differences(r, contrast, cb)
    verbose = _verbose(lines, solved, near.neighbours, *presence_, contrast, differences,
                       unlike_ratio, confidence)  # fmt: skip
    return _explanation(
        solved, near, (*outside, *why), presence_, contrast, lines, verbose, differences,
        calibrated,
    )  # fmt: skip


@dataclass(frozen=True)
class _Nearest:
    """The retrieved cases one per clip (``neighbours``, the records an explanation lists),
    the nearest of them with the answer's label (``own``: its position in the case base) and
    the nearest case of another label (``other``: position and distance)."""

    neighbours: tuple[dict[str, Any], ...]
    own: int | None
    other: tuple[int, float] | None

    @property
    def pair(self) -> tuple[int, int] | None:
        """The positions of ``own`` and ``other`` when there are both."""
        return None if self.own is None or self.other is None else (self.own, self.other[0])


def _nearest(cb: CaseBase, solved: Solved) -> _Nearest:
    """The clip's neighbours, a clip's mirror image not counted as a second one."""
    retrieval, label = solved.retrieval, solved.solution.label
    keep = distinct_neighbours(cb, retrieval)
    own = next((int(retrieval.indices[p]) for p in keep if retrieval.labels[p] == label), None)
    neighbours = tuple(
        {
            "case_id": int(retrieval.case_ids[p]),
            "position": int(retrieval.indices[p]),
            "label": str(retrieval.labels[p]),
            "distance": float(retrieval.distances[p]),
            "source": cb.sources[int(retrieval.indices[p])],
            # whether the case is its clip's mirror image: ``source`` then ends " (mirrored)"
            "mirrored": cb.sources[int(retrieval.indices[p])].endswith(MIRRORED),
        }
        for p in keep
    )
    return _Nearest(neighbours, own, nearest_of_other_label(cb, solved.problem, label))


def _reasons(
    r: _Reading, label: str, target: str | None, near: _Nearest
) -> tuple[list[Claim], list[Claim]]:
    """What the clip did outside the correct repetitions (a repetition judged incorrect:
    it leads), and the features that decided ``label``."""
    reference = _reference(r.prof.labels, target)
    judged_off = reference is not None and label != reference
    outside = outside_claims(r, reference) if judged_off and reference is not None else []
    why = why_claims(r, label, near.pair) if label in r.prof.labels else []
    return outside, why


def _explanation(
    solved: Solved,
    near: _Nearest,
    reasons: tuple[Claim, ...],
    presence_: tuple[list[Claim], list[Claim], list[Claim]],
    contrast: Contrast | None,
    lines: list[str],
    verbose: str,
    differences: list[dict[str, Any]],
    calibrated: bool = True,
) -> Explanation:
    """The explanation's record: every statement also kept as a claim (``reasons``: the
    "outside" and "why" claims)."""
    matched, not_seen, only_here = presence_
    changes = contrast.changes if contrast else ()
    return Explanation(
        label=solved.solution.label,
        confidence=solved.solution.confidence,
        neighbours=near.neighbours,
        matched=tuple(_held(c) for c in matched),
        not_seen=tuple(_held(c) for c in not_seen),
        only_here=tuple(_held(c) for c in only_here),
        contrast=contrast,
        text="\n".join(lines),
        verbose=verbose,
        claims=(*reasons, *changes, *matched, *not_seen, *only_here),
        vote_share=float(solved.solution.vote_share),
        mirrored=bool(solved.problem.mirrored),
        differences=tuple(differences),
        confidence_calibrated=bool(calibrated),
    )


def _contrast(
    cb: CaseBase,
    r: _Reading,
    problem: Problem,
    other: tuple[int, float],
    answer: Callable[[np.ndarray | Problem], str],
    k: int,
    weights: Weights,
    search: bool = True,
    balanced: bool = False,
) -> Contrast:
    """The nearest case of another label (``other``: position, distance) and the checked
    counterfactual toward its label (``search`` False: none)."""
    assert cb.ids is not None
    pos, dist = other
    other_label = str(cb.labels[pos])
    if not search:
        return Contrast(other_label, int(cb.ids[pos]), cb.sources[pos], float(dist), position=pos)
    # the counterfactual compares what the classification compared: a feature the clip never
    # showed is left out of its distances (Problem.measured), checked by answer the same way
    measured = problem.measured() if cb.measure.leaves_out else None

    def checked(values: np.ndarray) -> str:
        return answer(values if measured is None else dataclasses.replace(problem, values=values))

    cf = counterfactual(
        cb, np.asarray(problem.values), other_label, checked, k, weights, balanced, measured
    )
    changes = [] if cf.guide is None else change_claims(r, cf, cb.problems[cf.guide])
    return Contrast(
        other_label, int(cb.ids[pos]), cb.sources[pos], float(dist), tuple(changes), cf.valid,
        cf.answer, None if cf.guide is None else int(cb.ids[cf.guide]), cf.plausibility, pos,
        cf.guide, "" if cf.guide is None else cb.sources[cf.guide],
    )  # fmt: skip


def _short(
    cb: CaseBase,
    solved: Solved,
    target: str | None,
    outside: list[Claim],
    why: list[Claim],
    own: int | None,
    contrast: Contrast | None,
    calibrated: bool = True,
) -> list[str]:
    """The default text's lines, shortened (fewer changes shown, fewer reasons, no file
    names, no nearest cases or ranges) until they fit :data:`MAX_TEXT` characters; the
    confidence said to be the vote share when it is not ``calibrated``."""
    label = solved.solution.label
    name = label_words(label, target)
    head = _head(solved, name, calibrated)
    # a repetition check's reasons against "correct ones" (or "incorrect ones"), as its
    # "Done differently" line says it, not "its cases"
    check = label_words(label, target, article=False)
    whose = f"{check.removesuffix(' repetition')} ones" if check != label else "its cases"
    # fewer changes shown, fewer reasons, no file names, then no case names or ranges at all
    levels = ((3, 3, 2), (3, 1, 2), (2, 1, 2), (2, 1, 1), (1, 1, 1), (1, 1, 0))
    for items, shown, names in levels:
        if outside:
            said_ = [_claim_text(c, "correct ones" if names else "") for c in outside[:items]]
            why_line = _line_items("Done differently from correct repetitions: ", said_, 400)
        elif why:
            said_ = [_claim_text(c, whose if names else "") for c in why[:items]]
            why_line = _line_items("Why: ", said_, 400)
        else:
            plain = label_words(label, target, article=False)
            why_line = f"Why: nearest to the {plain} cases overall; no one feature sets it apart."
        near = []
        if own is not None and names:
            near.append("Nearest case of this label " + _case_ref(cb, own, names))
        if contrast is not None and names:
            near.append("of another label " + _case_ref(cb, contrast.position, names))
        lines = [head, why_line]
        if near:
            lines.append("; ".join(near) + ".")
        if contrast is not None:
            lines.append(_cf_line(contrast, label_words(contrast.label, target), shown))
        if len("\n".join(lines)) <= MAX_TEXT:
            break
    return lines


def _head(solved: Solved, name: str, calibrated: bool) -> str:
    """The first line: the answer (``name``), its confidence (said to be the vote share when
    not ``calibrated``: no probability, the case base had nothing to calibrate it on), the
    flag, and how little of the clip showed the person when under half (that it was judged on
    the arms alone when no frame showed the hips)."""
    head = f"{name}, confidence {solved.solution.confidence:.2f}"
    if not calibrated:
        head += f" ({UNCALIBRATED.words})"
    head += unlike_words(solved)
    if solved.arms_alone:
        head += f"; {ARMS_ALONE}"
    elif solved.torso_share < 0.5:
        head += f"; person seen in {100 * solved.torso_share:.0f} % of the frames"
    return head


ARMS_ALONE = "judged on the arms alone (the hips are seen in no frame)"
"""What the answer for a clip without hips says (:attr:`cbr.estimator.Solved.arms_alone`)."""


def unlike_words(solved: Solved) -> str:
    """ "; unlike the stored cases (...)" when the clip is, else nothing."""
    if not solved.unlike_cases:
        return ""
    if solved.unlike_reason == "sensor":
        return "; unlike the stored cases (recorded with a skeleton none of them has)"
    if solved.unlike_reason == "features":
        return "; unlike the stored cases (features unlike the cases')"
    return f"; unlike the stored cases (nearest at {solved.novelty:.1f}x the usual distance)"


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _case_ref(cb: CaseBase, i: int, names: int) -> str:
    """``#5 (squat_03.npz)`` (``names`` 2) or ``#5`` (1); a case not stored (no id) is
    named by its clip, or by its position (``case 3``) when its clip was given as arrays."""
    assert cb.ids is not None
    if int(cb.ids[i]) < 0:
        return _short_source(cb.sources[i], i)
    # a stored case of a clip given as arrays has no file to name: its id alone
    named = names == 2 and bool(clip_of(cb.sources[i]))
    where = f" ({_short_source(cb.sources[i])})" if named else ""
    return f"#{int(cb.ids[i])}{where}"


def _differences(r: _Reading, contrast: Contrast | None, cb: CaseBase) -> list[dict[str, Any]]:
    """The few columns (one per feature) that, weighted, differ most between the clip and the
    nearest case of the other label, in their units; of those the clip measured (the value
    of a joint it never showed is a fill, not what it did)."""
    if contrast is None:
        return []
    o = r.view.of(cb.problems[contrast.position][None])[0]
    spread = np.maximum(r.prof.within, 1e-9)
    gap = np.where(r.readable & r.known, (np.abs(r.x - o) / spread) ** 2 * r.importance, 0.0)
    out: list[dict[str, Any]] = []
    taken: set[int] = set()
    for j in np.argsort(-gap, kind="stable"):
        if not gap[j] >= 1e-12 or len(out) == SHORT_ITEMS:
            break
        f = int(r.view.feature[j])
        if f in taken:
            continue
        here, unit = r.unit(j)
        there = r.value(j, o[j])
        # a state no case of either label holds differs by a hair, which the cases' tiny
        # spread magnifies: "mean confidence 0.00 here, 0.00 there" is no difference to show
        if said(here, unit) == said(there, unit):
            continue
        taken.add(f)
        out.append({"feature": r.words(j), "here": here, "there": there, "unit": unit})
    return out


def _verbose(
    lines: list[str],
    solved: Solved,
    neighbours: tuple[dict[str, Any], ...],
    matched: list[Claim],
    not_seen: list[Claim],
    only_here: list[Claim],
    contrast: Contrast | None,
    differences: list[dict[str, Any]],
    unlike_ratio: float | None,
    confidence: str,
) -> str:
    label = solved.solution.label
    share = float(solved.solution.vote_share)
    out = list(lines)
    n_label = sum(n["label"] == label for n in neighbours)
    out.append(
        f"Vote: {n_label} of the {len(neighbours)} most similar cases"
        f" {'is' if n_label == 1 else 'are'} {label} (vote share "
        f"{share:.2f}; the confidence is {confidence})."
    )
    flag = "" if unlike_ratio is None else f"; flagged beyond {unlike_ratio:.2f}x"
    out.append(f"Nearest case at {solved.novelty:.2f}x the usual held-out distance{flag}.")
    for n in neighbours:  # a case not stored has no id: its position in the case base
        case = f"case #{n['case_id']} " if n["case_id"] >= 0 else f"case {n['position']} "
        out.append(f"  {case}{n['label']}  distance {n['distance']:.4g}  {n['source']}")
    if solved.problem.mirrored:
        out.append("The clip moves its left side more: it was compared as its mirror image "
                   "(sides above are the clip's own).")  # fmt: skip
    out.append(
        "Shown here and in the similar cases: "
        + (", ".join(_held(c) for c in matched) or "none")
        + "."
    )
    out.append(
        "In the similar cases, not here: " + (", ".join(_held(c) for c in not_seen) or "none") + "."
    )
    out.append(
        "Here, not in the similar cases: "
        + (", ".join(_held(c) for c in only_here) or "none")
        + "."
    )
    if contrast is not None:
        out += _verbose_contrast(contrast, differences, bool(solved.problem.mirrored))
    return "\n".join(out)


def _verbose_contrast(
    contrast: Contrast, differences: list[dict[str, Any]], mirrored: bool = False
) -> list[str]:
    """The verbose lines on the nearest case of the other label and the counterfactual's
    checks. ``mirrored``: the clip was compared as its mirror image, so the changed features
    (named in the compared, mirrored frame) are named by the clip's own sides, as every other
    word is."""
    out: list[str] = []
    out.append(
        f"Nearest other label: {contrast.label}"
        + (f" case #{contrast.case_id}" if contrast.case_id >= 0 else f" case {contrast.position}")
        + f" (distance {contrast.distance:.3g}) {contrast.source}."
    )
    if differences:
        said_ = [_difference_text(d) for d in differences]
        out.append("Differs from it most in: " + "; ".join(said_) + ".")
    if contrast.changes:
        status = (
            "checked: the classifier then answers " if contrast.valid
            else "not enough: the classifier still answers "
        ) + contrast.answer  # fmt: skip
        out.append(
            f"Counterfactual ({_count(len(contrast.changes), 'feature')}: "
            + ", ".join(
                swap_side(name) if mirrored else name
                for name in (c.feature.removeprefix("joint:") for c in contrast.changes)
            )
            + ", every value measured there as in "
            + (
                f"case #{contrast.guide_case_id}"
                if (contrast.guide_case_id or -1) >= 0
                else _short_source(contrast.guide_source, contrast.guide)
            )
            + f"; {status}; plausibility "
            f"{contrast.plausibility:.2f}x the usual distance between {contrast.label} "
            "cases): " + "; ".join(_change_text(c) for c in contrast.changes) + "."
        )
    return out
