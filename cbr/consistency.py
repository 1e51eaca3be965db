"""Checking an explanation against the data it speaks of: no claim contradicts another, the
clip, or the case base.

:func:`contradictions` recomputes every value from the problem and the cases (it does not
trust the numbers written into the claims) and lists what does not hold:

- a claimed value that is not the clip's (or, for a counterfactual change, not the guide
  case's);
- two mutually exclusive states of one fluent both said to hold steadily (bent and straight,
  bending and straightening, upright and tilted), or a state said to hold steadily that the
  clip holds less than half of the time, or one said to be shown that the clip does not show;
- one feature in two of the lists "shown here and in the similar cases", "in the similar
  cases, not here", "here, not in the similar cases";
- a presence against an absence ("in the similar cases, not here") whose difference is
  within the spread of that state among the cases of one label;
- a value said to be typical of a label that lies outside that label's usual range, or one
  said to lie outside the correct repetitions' range that does not.
"""

from __future__ import annotations

from functools import cache
from itertools import combinations

import numpy as np

from features.fluents import DEFAULT_TABLE

from .casebase import CaseBase
from .explain import SEEN_FRACTION, STEADY_FRACTION, Claim, Explanation, quantity
from .problem import Problem
from .profiles import profiles_of, view_of

_TOLERANCE = 1e-6
PRESENCE = ("matched", "not_seen", "only_here")


@cache
def _states() -> dict[str, tuple[str, str, str, bool]]:
    """Every fluent state's machine name (``left_leg_bent.bent``): its fluent, the fluent's
    tilt partner (or itself), its kind (instantaneous or motion) and whether it is a pair's
    shared state (upright, tilt steady)."""
    out = {}
    for spec in DEFAULT_TABLE.specs:
        partner = spec.paired_with or spec.name
        states = list(spec.states) if not spec.secondary else [spec.states[0], spec.states[2]]
        motions = list(spec.motion) if not spec.secondary else list(spec.motion[:2])
        for kind, names in (("state", states), ("motion", motions)):
            for i, st in enumerate(names):
                shared = spec.paired_with is not None and not spec.secondary and (
                    (kind == "state" and i == 1) or (kind == "motion" and i == 2)
                )  # fmt: skip
                slug = st.replace(" ", "_").replace("-", "_")
                out[f"{spec.name}.{slug}"] = (spec.name, partner, kind, shared)
    return out


def exclusive(a: str, b: str) -> bool:
    """Whether fluent states ``a`` and ``b`` (machine names, statistic suffix allowed) cannot
    hold at once: two states of one fluent and one kind, or a tilt pair's shared state
    (upright, tilt steady) and a state of either direction of the same kind."""
    sa, sb = _states().get(a.partition("@")[0]), _states().get(b.partition("@")[0])
    if sa is None or sb is None or a.partition("@")[0] == b.partition("@")[0] or sa[2] != sb[2]:
        return False
    if sa[0] == sb[0]:
        return True
    pair = {sa[0], sa[1]} == {sb[0], sb[1]}
    return pair and (sa[3] or sb[3])


def _value(view_value: float, name: str, unit: str) -> float:
    return float(view_value) if unit == "detected" else quantity(name, view_value)[0]


def contradictions(exp: Explanation, cb: CaseBase, problem: Problem) -> list[str]:
    """What in ``exp`` (an explanation of ``problem`` against ``cb``) does not hold."""
    view, prof = view_of(cb), profiles_of(cb)
    index = {n: j for j, n in enumerate(view.names)}
    x = view.of(np.asarray(problem.values, dtype=np.float64)[None])[0]
    out: list[str] = []
    for c in exp.claims:
        j = index.get(c.column)
        if j is None:
            out.append(f"{c.words}: no such column {c.column!r} in the case base")
            continue
        if c.here is None:  # said not seen: the clip must not have shown it
            if c.column.split("@", 1)[0] not in problem.unseen:
                out.append(f"{c.words}: said not seen, the clip has {x[j]:.4g}")
        elif abs(_value(x[j], c.column, c.unit) - c.here) > _TOLERANCE * max(1.0, abs(c.here)):
            out.append(f"{c.words}: said to be {c.here:.4g}, the clip has {x[j]:.4g}")
        out += _range(c, j, x, prof)
    out += _changes(exp, cb, view, index)
    out += _presence(exp.claims, x, index, prof)
    return out


def _range(c: Claim, j: int, x: np.ndarray, prof: object) -> list[str]:
    """A "typical of" claim inside the label's range; an "outside" claim outside the range
    of the correct repetitions by more than the spread within one label."""
    from .profiles import Profiles

    assert isinstance(prof, Profiles)
    if c.part not in ("why", "outside") or c.label is None or c.label not in prof.labels:
        return []
    row = prof.row(c.label)
    low, high = prof.low[row, j], prof.high[row, j]
    if c.part == "why" and not (low - _TOLERANCE <= x[j] <= high + _TOLERANCE):
        return [f"{c.words}: said to be typical of {c.label} but outside its usual range"]
    if c.part == "outside" and max(low - x[j], x[j] - high) < prof.within[j] - _TOLERANCE:
        return [f"{c.words}: said to differ from {c.label} by less than their spread"]
    return []


def _changes(exp: Explanation, cb: CaseBase, view: object, index: dict[str, int]) -> list[str]:
    """Every counterfactual change takes the guide case's value."""
    from .profiles import View

    assert isinstance(view, View)
    contrast = exp.contrast
    if contrast is None or not contrast.changes:
        return []
    if contrast.guide is None:
        return ["a counterfactual with changes but no guide case"]
    g = view.of(cb.problems[contrast.guide][None])[0]
    out = []
    for c in contrast.changes:
        j = index[c.column]
        there = _value(g[j], c.column, c.unit)
        if c.there is None or abs(there - c.there) > _TOLERANCE * max(1.0, abs(there)):
            out.append(f"{c.words}: the change says {c.there}, the guide case has {there:.4g}")
        if str(cb.labels[contrast.guide]) != contrast.label:
            out.append(f"the counterfactual's guide case is no {contrast.label} case")
    return out


def _presence(
    claims: tuple[Claim, ...], x: np.ndarray, index: dict[str, int], prof: object
) -> list[str]:
    """The presence lists: shares as claimed, one list per feature, exclusive states never
    both steady, presence against absence only beyond the spread within one label."""
    from .profiles import Profiles

    assert isinstance(prof, Profiles)
    out = []
    listed = [c for c in claims if c.part in PRESENCE]
    for c in listed:
        share = x[index[c.column]]
        if c.part in ("matched", "only_here") and share < SEEN_FRACTION - _TOLERANCE:
            out.append(f"{c.words}: said to be shown, mean confidence {share:.2f}")
        if c.part == "not_seen" and share >= SEEN_FRACTION:
            out.append(f"{c.words}: said not to be shown, mean confidence {share:.2f}")
        if c.steady and share < STEADY_FRACTION - _TOLERANCE:
            out.append(f"{c.words}: said to hold steadily, mean confidence {share:.2f}")
        if c.part in ("not_seen", "only_here") and c.there is not None:
            if abs(share - c.there) <= prof.within[index[c.column]]:
                out.append(
                    f"{c.words}: reported as present against absent, but the difference is "
                    "within its spread among the cases of one activity"
                )
    for a, b in combinations(listed, 2):
        if a.column == b.column and a.part != b.part:
            out.append(f"{a.words}: in two lists ({a.part}, {b.part})")
        if a.steady and b.steady and exclusive(a.column, b.column):
            out.append(f"{a.words} and {b.words}: exclusive states both said to hold steadily")
    return out
