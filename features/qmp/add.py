"""The Action Description Database (ADD): QMP criteria and activities, as data.

The ADD is a TOML file (default: ``features/qmp/add.toml``; schema below). Loading validates every
entry and raises :class:`~features.errors.ConfigError` naming the file, the entry and the field.

Schema (``schema = 1``)::

    [qmp.<name>]                 # a QMP criterion: a function of fitted QMP parameters
    words = "knees bending and straightening in rhythm"   # required, shown to people
    sides = "both"               # optional: "both" | "either"; signals may then use the
                                 #   templates {side} and {other} (left/right, mirrored)
    conditions = [               # required, >= 1; all must hold in a window
      { signal = "{side}_knee", quantity = "amplitude", min = 0.3 },     # min and/or max
      { signals = ["left_knee", "right_knee"], relation = "in_phase",   # pair relation:
        max_phase_diff_rad = 0.8, max_period_ratio = 1.3, min_amplitude = 0.2 },
    ]

    [activity.<name>]
    words = "squat"              # required
    labels = ["squat", "squat1Reps"]   # required, >= 1: dataset labels it stands for
    sequence = [                 # required, >= 2 steps, in the order they are performed
      { qmp = "knee_oscillation", weight = 10 },   # weight: integer 1-10
      ...
    ]

Quantities are those of :data:`features.qmp.fit.QUANTITIES` (amplitude and range in signal
units: radians for angles, head-lengths for distances ``a~b``; period_s in seconds; trend per
second). Relations: ``in_phase`` (phase difference at most ``max_phase_diff_rad``) and
``anti_phase`` (difference from pi at most that), both requiring the two periods to agree
within ``max_period_ratio`` and both amplitudes to reach ``min_amplitude``. The phase gap is
measured between the two fitted oscillations over the window (see :func:`phase_gap`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from collections.abc import Set as AbstractSet
from dataclasses import dataclass
from functools import cache, partial
from pathlib import Path
from typing import Any, cast

import numpy as np

from features.config import read_config
from features.errors import ConfigError

from .fit import NOT_ENOUGH_DATA, QUANTITIES, QMPFits, quantity_key, signal_unit
from .library import ExplicitTimeLibrary


def default_add_path() -> Path:
    """The shipped ADD, ``features/qmp/add.toml`` (package data of ``features.qmp``)."""
    from importlib.resources import files

    return Path(str(files("features.qmp") / "add.toml"))


RELATIONS: tuple[str, ...] = ("in_phase", "anti_phase")
SIDE_MODES: tuple[str, ...] = ("both", "either")


@dataclass(frozen=True)
class Condition:
    """One test on one signal's quantity: ``min <= value <= max`` (either bound optional)."""

    signal: str
    quantity: str
    min: float | None = None
    max: float | None = None

    @property
    def signals(self) -> tuple[str, ...]:
        return (self.signal,)

    def describe(self, extra: int = 0) -> str:
        """What the test asks, in words; ``extra``: digits beyond the usual three."""
        what = f"{_signal_words(self.signal)} {self.quantity.replace('_', ' ')}"

        def shown(v: float) -> str:
            return shown_value(v, self.signal, self.quantity, extra)

        if self.min is not None and self.max is not None:
            return f"{what} between {shown(self.min)} and {shown(self.max)}"
        if self.min is not None:
            return f"{what} at least {shown(self.min)}"
        assert self.max is not None
        return f"{what} at most {shown(self.max)}"


@dataclass(frozen=True)
class Relation:
    """Two signals oscillating together (in phase) or against each other (anti-phase)."""

    signal_a: str
    signal_b: str
    relation: str
    max_phase_diff_rad: float = 0.8
    max_period_ratio: float = 1.3
    min_amplitude: float = 0.1

    @property
    def signals(self) -> tuple[str, ...]:
        return (self.signal_a, self.signal_b)

    def describe(self) -> str:
        how = "in phase with" if self.relation == "in_phase" else "in anti-phase with"
        return f"{_signal_words(self.signal_a)} oscillating {how} {_signal_words(self.signal_b)}"


Test = Condition | Relation


@dataclass(frozen=True)
class Criterion:
    """A QMP criterion: every test must hold in a window. ``variants`` holds the concrete
    tests per side ("both": all variants must hold; "either": one suffices; no sides: one
    variant)."""

    name: str
    words: str
    sides: str | None
    variants: tuple[tuple[Test, ...], ...]

    @property
    def signals(self) -> tuple[str, ...]:
        seen: dict[str, None] = {}
        for variant in self.variants:
            for test in variant:
                for s in test.signals:
                    seen[s] = None
        return tuple(seen)


@dataclass(frozen=True)
class Step:
    qmp: str
    weight: int


@dataclass(frozen=True)
class Activity:
    """An activity: an ordered sequence of weighted QMPs and the dataset labels it stands for."""

    name: str
    words: str
    labels: tuple[str, ...]
    sequence: tuple[Step, ...]


@dataclass(frozen=True)
class ADD:
    """A loaded, validated Action Description Database."""

    criteria: Mapping[str, Criterion]
    activities: Mapping[str, Activity]
    source: str

    @property
    def signals(self) -> tuple[str, ...]:
        """Every state signal some criterion reads, in a stable order."""
        seen: dict[str, None] = {}
        for crit in self.criteria.values():
            for s in crit.signals:
                seen[s] = None
        return tuple(seen)


def _signal_words(signal: str) -> str:
    return signal.replace("~", " to ").replace("_", " ")


def _unit_words(signal: str, quantity: str) -> str:
    """The unit of ``quantity`` of ``signal`` as the ADD states it: radians for angles,
    head-lengths ("hl") for joint distances."""
    if quantity in ("period_s",):
        return " s"
    if quantity in ("r2",):
        return ""
    unit = signal_unit(signal)
    if quantity in ("trend", "residual_rms"):
        return f" {unit}/s"
    if quantity == "accel":
        return f" {unit}/s^2"
    return f" {unit}"


def _digits(v: float, extra: int = 0) -> str:
    """Three significant digits (``extra`` more), no exponent below 100,000."""
    return f"{v:.{extra}f}" if abs(v) >= 100 else f"{v:.{3 + extra}g}"


def shown_value(value: float, signal: str, quantity: str, extra: int = 0) -> str:
    """``value`` of ``quantity`` of ``signal`` in the words and units every other output
    uses: an angle (radians in the ADD) in degrees ("115°", "17.2°/s"), a joint distance in
    head lengths; the rest as the ADD states it. ``extra``: digits beyond the usual three."""
    unit = _unit_words(signal, quantity)
    if unit.startswith(" rad"):
        return f"{_digits(math.degrees(value), extra)}°{unit[len(' rad') :]}"
    if unit.startswith(" hl"):
        return f"{_digits(value, extra)} head lengths{unit[len(' hl') :]}"
    return f"{_digits(value, extra)}{unit}"


@cache
def known_signals() -> frozenset[str]:
    """Names of every state signal the fluent engine computes."""
    from features.signals import ANGLE_SIGNALS, NEAR_SIGNALS

    return frozenset(ANGLE_SIGNALS) | frozenset(NEAR_SIGNALS)


def _canonical_signal(name: str) -> str | None:
    """The engine's name for ``name`` (a distance may be written either way round)."""
    known = known_signals()
    if name in known:
        return name
    if "~" in name:
        a, _, b = name.partition("~")
        if f"{b}~{a}" in known:
            return f"{b}~{a}"
    return None


def _number(raw: Any, where: str, src: str) -> float:
    if isinstance(raw, bool) or not isinstance(raw, int | float):
        raise ConfigError(f"{where}: expected a number, got {raw!r}", src)
    try:  # TOML's integers may be of any length: past 1e308 there is no float
        value = float(raw)
    except OverflowError:
        value = math.inf
    if not math.isfinite(value):
        raise ConfigError(f"{where}: expected a finite number, got {_quoted(raw)}", src)
    return value


def _quoted(raw: Any) -> str:
    """``raw`` as the message quotes it: a number of hundreds of digits is cut short."""
    text = repr(raw)
    return text if len(text) <= 40 else f"{text[:20]}...({len(text)} characters)"


def _table(raw: Any, where: str, src: str) -> dict[str, Any]:
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: expected a table, got {type(raw).__name__}", src)
    return raw


def _known_fields(raw: Mapping[str, Any], known: AbstractSet[str], where: str, src: str) -> None:
    extra = set(raw) - known
    if extra:
        raise ConfigError(f"{where}: unknown field(s) {sorted(extra)}", src)


def _text(raw: Mapping[str, Any], key: str, where: str, src: str) -> str:
    if key not in raw:
        raise ConfigError(f"{where}: missing field '{key}'", src)
    value = raw[key]
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"{where}: field '{key}' must be a non-empty string", src)
    return value


def _resolve(template: str, side: str | None, where: str, src: str) -> str:
    if ("{side}" in template or "{other}" in template) and side is None:
        raise ConfigError(f"{where}: signal {template!r} uses {{side}} but 'sides' is not set", src)
    name = template
    if side is not None:
        other = "right" if side == "left" else "left"
        name = template.replace("{side}", side).replace("{other}", other)
    canonical = _canonical_signal(name)
    if canonical is None:
        raise ConfigError(f"{where}: unknown signal {name!r}", src)
    return canonical


_CONDITION_KEYS = {"signal", "quantity", "min", "max"}
_RELATION_KEYS = {
    "signals",
    "relation",
    "max_phase_diff_rad",
    "max_period_ratio",
    "min_amplitude",
}


def _parse_test(raw: Any, side: str | None, where: str, src: str) -> Test:
    raw = _table(raw, where, src)
    if "relation" in raw or "signals" in raw:
        _known_fields(raw, _RELATION_KEYS, where, src)
        rel = raw.get("relation")
        if rel not in RELATIONS:
            raise ConfigError(f"{where}: field 'relation' must be one of {RELATIONS}", src)
        pair = raw.get("signals")
        if (
            not isinstance(pair, list)
            or len(pair) != 2
            or not all(isinstance(s, str) for s in pair)
        ):
            raise ConfigError(f"{where}: field 'signals' must be a list of two signal names", src)
        opts = {
            k: _number(raw[k], f"{where}: field '{k}'", src)
            for k in ("max_phase_diff_rad", "max_period_ratio", "min_amplitude")
            if k in raw
        }
        if opts.get("max_period_ratio", 1.0) < 1.0:
            raise ConfigError(f"{where}: field 'max_period_ratio' must be >= 1", src)
        # the phase gap lies in [0, pi] and amplitudes are >= 0: bounds outside never hold
        if not 0.0 <= opts.get("max_phase_diff_rad", 0.0) <= np.pi:
            raise ConfigError(f"{where}: field 'max_phase_diff_rad' must be in [0, pi]", src)
        if opts.get("min_amplitude", 0.0) < 0.0:
            raise ConfigError(f"{where}: field 'min_amplitude' must be >= 0", src)
        return Relation(
            _resolve(pair[0], side, where, src), _resolve(pair[1], side, where, src), rel, **opts
        )
    _known_fields(raw, _CONDITION_KEYS, where, src)
    signal = _text(raw, "signal", where, src)
    quantity = _text(raw, "quantity", where, src)
    if quantity not in QUANTITIES:
        raise ConfigError(
            f"{where}: unknown quantity {quantity!r} (known: {', '.join(QUANTITIES)})", src
        )
    lo = _number(raw["min"], f"{where}: field 'min'", src) if "min" in raw else None
    hi = _number(raw["max"], f"{where}: field 'max'", src) if "max" in raw else None
    if lo is None and hi is None:
        raise ConfigError(f"{where}: needs a field 'min' or 'max'", src)
    if lo is not None and hi is not None and lo > hi:
        raise ConfigError(f"{where}: 'min' ({lo}) is above 'max' ({hi})", src)
    return Condition(_resolve(signal, side, where, src), quantity, lo, hi)


def _parse_criterion(name: str, raw: Any, src: str) -> Criterion:
    where = f"qmp '{name}'"
    raw = _table(raw, where, src)
    _known_fields(raw, {"words", "sides", "conditions"}, where, src)
    words = _text(raw, "words", where, src)
    sides = raw.get("sides")
    if sides is not None and sides not in SIDE_MODES:
        raise ConfigError(f"{where}: field 'sides' must be one of {SIDE_MODES}", src)
    conds = raw.get("conditions")
    if conds is None:
        raise ConfigError(f"{where}: missing field 'conditions'", src)
    if not isinstance(conds, list) or not conds:
        raise ConfigError(f"{where}: field 'conditions' must be a non-empty list", src)
    side_list: tuple[str | None, ...] = ("left", "right") if sides else (None,)
    variants = tuple(
        tuple(_parse_test(c, side, f"{where}: conditions[{i}]", src) for i, c in enumerate(conds))
        for side in side_list
    )
    return Criterion(name, words, sides, variants)


def _parse_activity(name: str, raw: Any, criteria: Mapping[str, Criterion], src: str) -> Activity:
    where = f"activity '{name}'"
    raw = _table(raw, where, src)
    _known_fields(raw, {"words", "labels", "sequence"}, where, src)
    words = _text(raw, "words", where, src)
    labels = raw.get("labels")
    if labels is None:
        raise ConfigError(f"{where}: missing field 'labels'", src)
    if not isinstance(labels, list) or not labels or not all(isinstance(x, str) for x in labels):
        raise ConfigError(f"{where}: field 'labels' must be a non-empty list of strings", src)
    if not all(x.strip() for x in labels):  # no clip's label is empty: it would match none
        raise ConfigError(f"{where}: field 'labels' holds an empty label", src)
    seq = raw.get("sequence")
    if seq is None:
        raise ConfigError(f"{where}: missing field 'sequence'", src)
    if not isinstance(seq, list) or len(seq) < 2:
        raise ConfigError(f"{where}: field 'sequence' must list at least two QMPs", src)
    steps = tuple(
        _parse_step(item, criteria, f"{where}: sequence[{i}]", src) for i, item in enumerate(seq)
    )
    return Activity(name, words, tuple(labels), steps)


def _parse_step(raw: Any, criteria: Mapping[str, Criterion], where: str, src: str) -> Step:
    """One ``{ qmp = ..., weight = ... }`` of an activity's sequence: a known QMP, a weight
    from 1 to 10."""
    item = _table(raw, where, src)
    _known_fields(item, {"qmp", "weight"}, where, src)
    qmp = _text(item, "qmp", where, src)
    if qmp not in criteria:
        raise ConfigError(f"{where}: unknown qmp {qmp!r}", src)
    if "weight" not in item:
        raise ConfigError(f"{where}: missing field 'weight'", src)
    weight = item["weight"]
    if isinstance(weight, bool) or not isinstance(weight, int) or not 1 <= weight <= 10:
        raise ConfigError(f"{where}: field 'weight' must be an integer from 1 to 10", src)
    return Step(qmp, weight)


def parse_add(raw: Mapping[str, Any], source: str = "ADD") -> ADD:
    """Validate a parsed ADD document (see the module docstring for the schema)."""
    src = source
    if raw.get("schema", 1) != 1 or isinstance(raw.get("schema"), bool):  # true == 1
        raise ConfigError(f"unsupported ADD schema {raw.get('schema')!r} (expected 1)", src)
    extra = set(raw) - {"schema", "qmp", "activity"}
    if extra:
        raise ConfigError(f"unknown top-level field(s) {sorted(extra)}", src)
    qmps = _table(raw.get("qmp", {}), "qmp", src)
    acts = _table(raw.get("activity", {}), "activity", src)
    if not qmps:
        raise ConfigError("no [qmp.<name>] entries", src)
    if not acts:
        raise ConfigError("no [activity.<name>] entries", src)
    criteria = {name: _parse_criterion(name, v, src) for name, v in qmps.items()}
    activities = {name: _parse_activity(name, v, criteria, src) for name, v in acts.items()}
    return ADD(criteria, activities, src)


def load_add(path: str | Path | None = None) -> ADD:
    """Load and validate an ADD file (TOML); None loads the shipped default."""
    if path is None:
        return _default_add()
    return _load(Path(path))


@cache
def _default_add() -> ADD:
    return _load(default_add_path())


def _load(p: Path) -> ADD:
    return parse_add(read_config(p, "ADD file", "toml"), str(p))


@dataclass(frozen=True)
class CriteriaResult:
    """Criteria evaluated per window.

    names ``(Q,)``; met / observable ``(W, Q)`` bool; fraction ``(W, Q)`` the share of tests
    passed by the best variant; closest ``(Q,)`` the observable window where a criterion that
    was missed came closest (-1: never missed or never observable); failed ``(Q,)`` the tests
    that failed there, as readable strings with the observed values.
    """

    names: tuple[str, ...]
    met: np.ndarray
    observable: np.ndarray
    fraction: np.ndarray
    closest: np.ndarray
    failed: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class _Tested:
    """Every distinct test of an ADD over all windows at once (columns in ``tests`` order):
    passed and observable ``(W, U)`` bool, and what was observed (``values``: a condition's
    quantity ``(W, U)``; for a relation its phase gap, from anti-phase for ``anti_phase``, its
    period ratio and smaller amplitude, each ``(W, U)``; NaN in the other kind's columns)."""

    tests: tuple[Test, ...]
    passed: np.ndarray
    observable: np.ndarray
    values: np.ndarray
    gap: np.ndarray
    ratio: np.ndarray
    amplitude: np.ndarray

    def observed(self, u: int) -> list[np.ndarray]:
        """The observed values of test ``u``, each ``(W,)``."""
        if isinstance(self.tests[u], Condition):
            return [self.values[:, u]]
        return [self.gap[:, u], self.ratio[:, u], self.amplitude[:, u]]


def _bounds(values: list[float | None], missing: float) -> np.ndarray:
    return np.array([missing if v is None else v for v in values], dtype=np.float64)


def _test_all(tests: tuple[Test, ...], fits: QMPFits) -> _Tested:
    """:class:`_Tested` of ``tests`` on ``fits``: array work per kind of test, not per test."""
    n_win, n_tests = len(fits.windows), len(tests)
    where = {s: fits.index(s) for t in tests for s in t.signals}
    passed = np.zeros((n_win, n_tests), dtype=bool)
    observed = np.full((n_win, n_tests, 4), np.nan)  # value, gap, ratio, amplitude
    cond = [u for u, t in enumerate(tests) if isinstance(t, Condition)]
    rel = [u for u, t in enumerate(tests) if isinstance(t, Relation)]
    if cond:
        conditions = [cast(Condition, tests[u]) for u in cond]
        sig = np.array([where[c.signal] for c in conditions], dtype=np.int64)
        v = np.empty((n_win, len(cond)))
        quantity = np.array([c.quantity for c in conditions], dtype=object)
        for q in dict.fromkeys(quantity.tolist()):
            at = np.flatnonzero(quantity == q)
            v[:, at] = fits.quantity(q)[:, sig[at]]
        lo = _bounds([c.min for c in conditions], -np.inf)
        hi = _bounds([c.max for c in conditions], np.inf)
        with np.errstate(invalid="ignore"):
            passed[:, cond] = np.isfinite(v) & (v >= lo) & (v <= hi)
        observed[:, cond, 0] = v
    if rel:
        relations = [cast(Relation, tests[u]) for u in rel]
        a = np.array([where[r.signal_a] for r in relations], dtype=np.int64)
        b = np.array([where[r.signal_b] for r in relations], dtype=np.int64)
        amp, per = fits.quantity("amplitude"), fits.quantity("period_s")
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.maximum(per[:, a], per[:, b]) / np.minimum(per[:, a], per[:, b])
            gap = _phase_gaps(fits, a, b)
            anti = np.array([r.relation == "anti_phase" for r in relations])
            gap = np.where(anti, np.pi - gap, gap)
            smaller = np.minimum(amp[:, a], amp[:, b])
            least = np.array([r.min_amplitude for r in relations])
            ok = (
                (amp[:, a] >= least)
                & (amp[:, b] >= least)
                & (ratio <= np.array([r.max_period_ratio for r in relations]))
                & (gap <= np.array([r.max_phase_diff_rad for r in relations]))
            )
        passed[:, rel] = ok & np.isfinite(gap)
        observed[:, rel, 1], observed[:, rel, 2], observed[:, rel, 3] = gap, ratio, smaller
    signals = [[where[s] for s in t.signals] for t in tests]
    enough = fits.status != NOT_ENOUGH_DATA  # (W, S)
    observable = np.stack([enough[:, idx].all(axis=1) for idx in signals], axis=1).reshape(
        n_win, n_tests
    )
    return _Tested(tests, passed, observable, *np.moveaxis(observed, 2, 0))


def _oscillations(fits: QMPFits, signals: np.ndarray, samples: int) -> np.ndarray:
    """Each of ``signals``' fitted oscillation rebuilt over the window, less its mean
    ``(W, len(signals), samples)``: the derivative's cos/sin parts at its own T; 0 where the
    signal has no oscillation (no T)."""
    lib = ExplicitTimeLibrary()
    # Windows of one fit all have the same length, so one time grid serves them all.
    t = np.linspace(0.0, (fits.windows[0, 1] - fits.windows[0, 0]) / fits.fps, samples)
    curves = np.empty((len(fits.windows), len(signals), samples))
    for j, s in enumerate(signals.tolist()):
        T = fits.period_T_s[:, s]
        theta = lib.matrices(t, np.where(np.isfinite(T), T, 1.0))  # (W, samples, 6)
        osc = np.einsum("wfk,wk->wf", theta[..., 2:], fits.coefficients[:, s, 2:])
        osc = np.where(np.isfinite(T)[:, None], osc, 0.0)  # no sinusoid: no oscillation
        curves[:, j] = osc - osc.mean(axis=1, keepdims=True)
    return curves


def _phase_gaps(fits: QMPFits, a: np.ndarray, b: np.ndarray, samples: int = 64) -> np.ndarray:
    """:func:`phase_gap` of the signal pairs ``(a[i], b[i])`` ``(W, len(a))``, each signal's
    oscillation rebuilt once."""
    signals, inverse = np.unique(np.r_[a, b], return_inverse=True)
    curves = _oscillations(fits, signals, samples)
    ca, cb = curves[:, inverse[: len(a)]], curves[:, inverse[len(a) :]]
    num = (ca * cb).sum(axis=2)
    den = np.sqrt((ca**2).sum(axis=2) * (cb**2).sum(axis=2))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.where(den > 0, num / den, np.nan)
    gap: np.ndarray = np.arccos(np.clip(corr, -1.0, 1.0))
    return gap


def phase_gap(fits: QMPFits, a: int, b: int, samples: int = 64) -> np.ndarray:
    """Phase gap in [0, pi] between the fitted oscillations of signals a and b, per window.

    Each signal's oscillation is rebuilt from its fitted sinusoidal terms over the window (the
    derivative's cos/sin parts at its own T) and the gap is ``arccos`` of their correlation:
    0 = in phase, pi = in anti-phase. Comparing the rebuilt curves rather than the two phase
    numbers stays right when the two fits chose different T (one whole-period, one
    half-period) for the same motion. NaN where either signal has no oscillation.
    """
    gap: np.ndarray = _phase_gaps(fits, np.array([a]), np.array([b]), samples)[:, 0]
    return gap


def _failure_text(test: Test, values: list[np.ndarray], w: int) -> str:
    """Why ``test`` failed in window ``w``: what it asks and what :func:`_test_values`
    observed there (a relation: every part it checks, the amplitude included)."""
    if isinstance(test, Condition):
        v = values[0][w]
        if np.isfinite(v):
            return _failed_condition(test, float(v))
        seen = "no oscillation" if test.quantity in ("period_s", "phase_rad") else "undefined"
        return f"{test.describe()} (observed {seen})"
    diff, ratio, amp = values[0][w], values[1][w], values[2][w]
    if not np.isfinite(diff):
        return f"{test.describe()} (observed: not oscillating)"
    return (
        f"{test.describe()} (observed phase gap {math.degrees(diff):.0f}°, period ratio"
        f" {ratio:.2f}, smaller amplitude {shown_value(float(amp), test.signal_a, 'amplitude')})"
    )


def _failed_condition(test: Condition, value: float) -> str:
    """The condition ``value`` failed and ``value``, with as many digits as it takes for the
    value and the bound it crossed to read differently: "at most 115° (observed 115°)" read
    as met (the bound 114.6°, the value 114.8°)."""
    crossed = test.min if test.min is not None and value < test.min else test.max
    extra = 0
    while crossed is not None and extra < 4:
        show = partial(shown_value, signal=test.signal, quantity=test.quantity, extra=extra)
        if show(value) != show(crossed):
            break
        extra += 1
    seen = shown_value(value, test.signal, test.quantity, extra)
    return f"{test.describe(extra)} (observed {seen})"


def evaluate_criteria(add: ADD, fits: QMPFits) -> CriteriaResult:
    """Evaluate every ADD criterion in every window of ``fits``: every distinct test at once
    (:func:`_test_all`), then each variant's tests and each criterion's variants combined by
    counting (a variant holds when none of its tests fails)."""
    names = tuple(add.criteria)
    crits = [add.criteria[n] for n in names]
    n_q = len(names)
    tests = tuple(dict.fromkeys(t for c in crits for v in c.variants for t in v))
    column = {t: u for u, t in enumerate(tests)}
    tested = _test_all(tests, fits)
    # incidence of tests (rows) in the variants of all criteria (columns), criteria in order
    variants = [v for c in crits for v in c.variants]
    member = np.zeros((len(tests), len(variants)))
    for j, variant in enumerate(variants):
        member[[column[t] for t in variant], j] = 1.0
    size = member.sum(axis=0)
    passes = tested.passed.astype(np.float64) @ member  # (W, variants): tests passed
    seen = tested.observable.astype(np.float64) @ member
    v_obs = seen == size
    v_met = (passes == size) & v_obs
    v_frac = np.where(v_obs, passes / size, 0.0)
    first = np.cumsum([0] + [len(c.variants) for c in crits])[:-1]
    both = np.array([c.sides == "both" for c in crits])
    n_var = np.array([len(c.variants) for c in crits], dtype=np.float64)
    met = np.where(
        both, np.logical_and.reduceat(v_met, first, axis=1),
        np.logical_or.reduceat(v_met, first, axis=1),
    )  # fmt: skip
    observable = np.where(
        both, np.logical_and.reduceat(v_obs, first, axis=1),
        np.logical_or.reduceat(v_obs, first, axis=1),
    )  # fmt: skip
    fraction = np.where(
        both, np.add.reduceat(v_frac, first, axis=1) / n_var,
        np.maximum.reduceat(v_frac, first, axis=1),
    )  # fmt: skip
    closest = np.full(n_q, -1, dtype=np.int64)
    failed: list[tuple[str, ...]] = [() for _ in range(n_q)]
    for q, crit in enumerate(crits):
        # Explain a miss once, in the observable window where the criterion came closest.
        missed = ~met[:, q] & observable[:, q]
        if not missed.any():
            continue
        w = int(np.argmax(np.where(missed, fraction[:, q], -1.0)))
        closest[q] = w
        # "both": every failing side counts; "either": explain the closest side.
        chosen = range(len(crit.variants))
        if crit.sides != "both":
            best = int(np.argmax(v_frac[w, first[q] : first[q] + len(crit.variants)]))
            chosen = range(best, best + 1)
        texts = [
            _failure_text(test, tested.observed(column[test]), w)
            for v in chosen
            for test in crit.variants[v]
            if not tested.passed[w, column[test]]
        ]
        failed[q] = tuple(dict.fromkeys(texts))
    return CriteriaResult(names, met, observable, fraction, closest, tuple(failed))


def feature_columns(add: ADD) -> tuple[tuple[str, str], ...]:
    """The (signal, quantity) pairs the criteria read, in a stable order."""
    seen: dict[tuple[str, str], None] = {}
    for crit in add.criteria.values():
        for variant in crit.variants:
            for test in variant:
                if isinstance(test, Condition):
                    seen[(test.signal, test.quantity)] = None
                else:
                    for s in test.signals:
                        for qn in ("amplitude", "period_s", "phase_rad"):
                            seen[(s, qn)] = None
    return tuple(seen)


def feature_name(signal: str, quantity: str) -> str:
    """Readable, stable name of a continuous QMP feature: ``left_knee.amplitude_rad``."""
    return f"{signal}.{quantity_key(quantity, signal_unit(signal))}"


def criteria_words(add: ADD, names: Sequence[str]) -> tuple[str, ...]:
    return tuple(add.criteria[n].words for n in names)
