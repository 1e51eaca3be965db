"""Fluents: qualitative posture states with confidences (paper §"Low level", SPEC.md).

The paper's threshold table is :data:`DEFAULT_TABLE`: one :class:`FluentSpec` per fluent,
evaluated in bulk over all frames by :func:`evaluate`. Users override any parameter from a
JSON or TOML file (:meth:`FluentTable.from_file`), by family (``arm_bent`` sets both sides) or
by fluent (``left_arm_bent``). Angles may be written as numbers (radians) or as ``"5pi/8"``.

Instantaneous confidence (paper eqs. 2-4): a lower state s0 holds below τ (1 under τ-δ, 0
over τ+δ, logistic with slope ln((1-ε)/ε)/δ between), an upper state is its mirror image, a
middle state is (1-C(s0))(1-C(s2)), and a two-state fluent's confidences sum to 1.

Locally temporal confidence (eqs. 5-6): Δθ compared as a two-state fluent with τ = ∓π/72,
δ = π/72 (near: ∓0.05 hl, 0.05 hl), multiplied over a window of r = 5 with exponents
1/(age+1); no motion is (1-C(→s0))(1-C(→sn)). The thresholds are per frame at
``reference_fps`` (30, the rate of the smartphone video the paper used): at another frame rate
Δθ is taken over one reference frame interval (``fps / reference_fps`` source frames, linearly
interpolated) and the window spans ``r`` reference intervals, so a movement gets the same
confidence whatever the camera's rate.
"""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from collections.abc import Callable, Iterator, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from features.errors import ConfigError, DataError

from .config import read_config
from .poses import MAX_FPS, MIN_FPS, PoseSequence, expect_sequence
from .signals import ANGLE_SIGNALS, NEAR_SIGNALS, StateSignals, near_pairs, state_signals
from .text import did_you_mean

__all__ = [
    "CHUNK_FRAMES",
    "DEFAULT_TABLE",
    "FluentResult",
    "FluentSpec",
    "FluentTable",
    "StateSignals",
    "Threshold",
    "confidence_lower",
    "confidence_upper",
    "evaluate",
    "evaluate_chunks",
    "history_frames",
    "state_columns",
    "state_signals",
]

PI = math.pi


@dataclass(frozen=True)
class Threshold:
    """A state boundary: τ (radians, or head-lengths for distances) and half-width δ."""

    tau: float
    delta: float


@dataclass(frozen=True)
class FluentSpec:
    """One row of the paper's table.

    ``states`` are the instantaneous states s0..sn in angle order (s0 holds at small values).
    ``lower`` is the s0|s1 boundary; ``upper`` the s(n-1)|sn boundary of a three-state fluent.
    ``motion`` words: toward s0, toward sn, no motion. ``paired_with``: the other direction of a
    tilt; the pair shares one middle ("upright") state and one no-motion state (paper §Tilted).
    For distance fluents ``obj`` is the second joint and a binary "touching" state is added.
    """

    name: str
    family: str
    subject: str
    signal: str
    states: tuple[str, ...]
    lower: Threshold
    upper: Threshold | None
    motion: tuple[str, str, str]
    motion_threshold: Threshold
    kind: Literal["angle", "distance"] = "angle"
    obj: str = ""
    paired_with: str | None = None
    secondary: bool = False  # the second fluent of a tilt pair: no middle / no-motion state

    def phrase(self, state: str) -> str:
        """Words for one of this fluent's states: "left knee bent", "left index near nose"."""
        return f"{self.subject} {state} {self.obj}".strip()


def _joint_words(joint: str) -> str:
    """``left_foot_index`` -> ``left big toe``; ``mouth_left`` -> ``left mouth corner``."""
    if joint.startswith("mouth_"):
        return f"{joint.removeprefix('mouth_')} mouth corner"
    words = joint.replace("_", " ")
    return words.replace("foot index", "big toe").replace("index", "index finger")


def _default_specs() -> tuple[FluentSpec, ...]:
    q1 = Threshold(7 * PI / 16, PI / 16)  # in front / outward / tilted / twisted: s0|s1
    q3 = Threshold(9 * PI / 16, PI / 16)  # s1|s2
    motion = Threshold(PI / 72, PI / 72)
    front3 = ("in front", "centered", "behind")
    front_m = ("moving forward", "moving backward", "front-back steady")
    out3 = ("outward", "at side", "inward")
    out_m = ("moving outward", "moving inward", "sideways steady")
    specs: list[FluentSpec] = []
    Row = tuple[str, str, str, tuple[str, ...], Threshold, Threshold | None, tuple[str, str, str]]
    # family, subject, signal, states s0..sn, lower, upper, motion words (->s0, ->sn, none)
    sided: list[Row] = [
        ("arm_bent", "{side} elbow", "{side}_elbow", ("bent", "straight"),
         Threshold(5 * PI / 8, PI / 8), None, ("bending", "straightening", "bend steady")),
        ("leg_bent", "{side} knee", "{side}_knee", ("bent", "straight"),
         Threshold(19 * PI / 24, PI / 24), None, ("bending", "straightening", "bend steady")),
        ("arm_in_front", "{side} arm", "{side}_upper_arm_sagittal", front3, q1, q3, front_m),
        ("leg_in_front", "{side} leg", "{side}_upper_leg_sagittal", front3, q1, q3, front_m),
        ("arm_raised", "{side} arm", "{side}_armpit", ("lowered", "chest-level", "raised"),
         Threshold(3 * PI / 8, PI / 8), q3, ("lowering", "raising", "height steady")),
        ("leg_raised", "{side} leg", "{side}_hip", ("raised", "lowered"),
         Threshold(13 * PI / 16, PI / 16), None, ("raising", "lowering", "height steady")),
        ("arm_outward", "{side} arm", "{side}_upper_arm_frontal", out3, q1, q3, out_m),
        ("leg_outward", "{side} leg", "{side}_upper_leg_frontal", out3, q1, q3, out_m),
    ]  # fmt: skip
    for family, subject, signal, states, lower, upper, words in sided:
        for side in ("left", "right"):
            specs.append(
                FluentSpec(
                    name=f"{side}_{family}",
                    family=family,
                    subject=subject.format(side=side),
                    signal=signal.format(side=side),
                    states=states,
                    lower=lower,
                    upper=upper,
                    motion=words,
                    motion_threshold=motion,
                )
            )
    for part, neck in (("head", "neck"), ("torso", "torso")):
        for direction, plane, states, words in (
            ("forward", "sagittal", ("tilted forward", "upright", "tilted backward"),
             ("tilting forward", "tilting backward", "tilt steady")),
            ("left", "frontal", ("tilted left", "upright", "tilted right"),
             ("tilting left", "tilting right", "tilt steady")),
        ):  # fmt: skip
            other = "left" if direction == "forward" else "forward"
            specs.append(
                FluentSpec(
                    name=f"{part}_tilted_{direction}",
                    family=f"{part}_tilted_{direction}",
                    subject=part,
                    signal=f"{neck}_{plane}",
                    states=states,
                    lower=q1,
                    upper=q3,
                    motion=words,
                    motion_threshold=motion,
                    paired_with=f"{part}_tilted_{other}",
                    secondary=direction == "left",
                )
            )
    for part, neck in (("head", "neck"), ("torso", "torso")):
        specs.append(
            FluentSpec(
                name=f"{part}_twisted",
                family=f"{part}_twisted",
                subject=part,
                signal=f"{neck}_transverse",
                states=("twisted left", "centered", "twisted right"),
                lower=q1,
                upper=q3,
                motion=("twisting left", "twisting right", "twist steady"),
                motion_threshold=motion,
            )
        )
    for a, b in near_pairs():
        specs.append(
            FluentSpec(
                name=f"near:{a}~{b}",
                family="near",
                subject=_joint_words(a),
                signal=f"{a}~{b}",
                states=("near", "far from"),
                lower=Threshold(0.5, 0.25),
                upper=None,
                motion=("approaching", "moving away from", "keeping distance to"),
                motion_threshold=Threshold(0.05, 0.05),
                kind="distance",
                obj=_joint_words(b),
            )
        )
    return tuple(specs)


_ANGLE_RE = re.compile(
    r"^\s*(?P<num>[0-9]*\.?[0-9]*)\s*\*?\s*(?P<pi>pi|π)?\s*(?:/\s*(?P<den>[0-9]*\.?[0-9]+))?\s*$"
)


_MAX_VALUE_TEXT = 64  # longer text is no number; and the regular expression stays fast


def parse_value(value: Any, where: str) -> float:
    """A number, or an angle written like ``"5pi/8"``, ``"pi/72"``, ``"0.25"``."""
    if isinstance(value, bool):
        raise ConfigError(f"expected a number, got {value!r}", where)
    if isinstance(value, int | float):
        try:
            out = float(value)
        except OverflowError:
            raise ConfigError("value is too large", where) from None
    elif isinstance(value, str):
        m = _ANGLE_RE.match(value) if len(value) <= _MAX_VALUE_TEXT else None
        if not m or m["num"] == "." or not (m["num"] or m["pi"]):
            raise ConfigError(
                f"cannot read {value[:_MAX_VALUE_TEXT]!r} as a number or a multiple of pi", where
            )
        out = float(m["num"]) if m["num"] else 1.0
        if m["pi"]:
            out *= PI
        if m["den"]:
            den = float(m["den"])
            if den == 0:
                raise ConfigError(f"division by zero in {value!r}", where)
            out /= den
    else:
        raise ConfigError(f"expected a number, got {str(value)[:40]}", where)
    if not math.isfinite(out):
        raise ConfigError(f"value must be finite, got {value!r}", where)
    return out


TAU_DELTA = ("tau", "delta")
"""The keys of a threshold's table."""

MIN_DELTA = 1e-300
"""The smallest ``delta``: ln((1 - ε)/ε) is at most 745 for any ε a float holds, so the
slope stays finite (a delta of 1e-320 overflowed to an infinite slope, with a RuntimeWarning
for every command that used the table)."""


def _threshold(raw: Any, where: str) -> Threshold:
    if not isinstance(raw, Mapping) or not raw:
        raise ConfigError("expected a table with keys tau and/or delta", where)
    unknown = sorted(set(raw) - {"tau", "delta"})
    if unknown:  # named: "expected a table with keys tau and/or delta" left 'tua' to find
        raise ConfigError(
            f"unknown key {unknown[0]!r} (known: tau, delta){did_you_mean(unknown[0], TAU_DELTA)}",
            where,
        )
    tau = parse_value(raw["tau"], f"{where}.tau") if "tau" in raw else math.nan
    delta = parse_value(raw["delta"], f"{where}.delta") if "delta" in raw else math.nan
    if "delta" in raw and delta <= 0:
        raise ConfigError(f"delta must be positive, got {raw['delta']!r}", f"{where}.delta")
    if "delta" in raw and delta < MIN_DELTA:  # the logistic's slope ln(..)/delta overflows
        raise ConfigError(
            f"delta must be at least {MIN_DELTA:g} (the confidence's slope would be "
            f"infinite), got {raw['delta']!r}",
            f"{where}.delta",
        )
    return Threshold(tau, delta)


def _merge(old: Threshold | None, new: Threshold, where: str) -> Threshold:
    if old is None:
        raise ConfigError("this fluent has no such boundary", where)
    return Threshold(
        old.tau if math.isnan(new.tau) else new.tau,
        old.delta if math.isnan(new.delta) else new.delta,
    )


MAX_WINDOW = 100  # reference frames of the temporal window (the paper's r = 5)
MAX_TOUCHING_M = 10.0

# Keys `posecbr thresholds` prints for reading, not for changing: accepted back as printed.
_DESCRIPTIVE_KEYS = ("signal", "states")


def _descriptive(s: FluentSpec) -> dict[str, Any]:
    """What :meth:`FluentTable.to_dict` prints about a fluent besides its thresholds."""
    return {"signal": s.signal if s.kind == "angle" else "distance_hl", "states": list(s.states)}


def _check_descriptive(s: FluentSpec, params: Mapping[str, Any], where: str) -> None:
    """``signal`` and ``states`` may come back as printed (a round trip) but not changed."""
    fixed = _descriptive(s)
    for key in _DESCRIPTIVE_KEYS:
        if key in params and params[key] != fixed[key]:
            raise ConfigError(
                f"{key} is fixed by the fluent ({json.dumps(fixed[key])}) and cannot be changed",
                where,
            )


def _check_ranges(s: FluentSpec, where: str) -> None:
    """Thresholds where the signal can reach them: angles in [0, pi], distances >= 0, and a
    motion threshold >= 0 (it is compared as -tau and +tau)."""
    top = PI if s.kind == "angle" else math.inf
    unit = "radians in [0, pi]" if s.kind == "angle" else "head-lengths >= 0"
    bounds = (("lower", s.lower), ("upper", s.upper), ("motion", s.motion_threshold))
    for name, th in bounds:
        if th is not None and not 0.0 <= th.tau <= top:
            raise ConfigError(f"{name} tau must be {unit}, got {th.tau:g}", where)


def _parse_epsilon(value: Any, source: str) -> float:
    eps = parse_value(value, f"{source}: epsilon")
    if not 0 < eps < 0.5:
        raise ConfigError(f"epsilon must be in (0, 0.5), got {eps}", source)
    return eps


def _parse_window(value: Any, source: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not 1 <= value <= MAX_WINDOW:
        raise ConfigError(
            f"window must be a whole number from 1 to {MAX_WINDOW}, got {value!r}", source
        )
    return value


def _parse_reference_fps(value: Any, source: str) -> float:
    fps = parse_value(value, f"{source}: reference_fps")
    if not MIN_FPS <= fps <= MAX_FPS:
        raise ConfigError(
            f"reference_fps must be between {MIN_FPS:g} and {MAX_FPS:g}, got {fps:g}", source
        )
    return fps


def _parse_touching_m(value: Any, source: str) -> float:
    touching = parse_value(value, f"{source}: touching_m")
    if not 0 < touching <= MAX_TOUCHING_M:
        raise ConfigError(
            f"touching_m must be a distance in metres in (0, {MAX_TOUCHING_M:g}], got {touching:g}",
            source,
        )
    return touching


# The table-wide settings of an overrides file, each read and checked in this order.
_SETTINGS: dict[str, Callable[[Any, str], float | int]] = {
    "epsilon": _parse_epsilon,
    "window": _parse_window,
    "reference_fps": _parse_reference_fps,
    "touching_m": _parse_touching_m,
}


def _fluents_named(specs: list[FluentSpec], key: str, params: Any, source: str) -> list[int]:
    """Indices of the fluents an overrides entry names (by fluent or by family), once its
    parameters are known to be a table of known keys."""
    hits = [i for i, s in enumerate(specs) if key in (s.name, s.family)]
    if not hits:
        names = dict.fromkeys(n for s in specs for n in (s.family, s.name))
        raise ConfigError(f"unknown fluent {key!r}{did_you_mean(key, names)}", source)
    if not isinstance(params, Mapping):
        raise ConfigError(f"fluent {key!r}: expected a table", source)
    bad = set(params) - {"lower", "upper", "motion"} - set(_DESCRIPTIVE_KEYS)
    if bad:
        raise ConfigError(
            f"fluent {key!r}: unknown key {sorted(bad)[0]!r} (known: lower, upper,"
            " motion; signal and states as `posecbr thresholds` prints them)",
            source,
        )
    return hits


def _overridden(s: FluentSpec, key: str, params: Mapping[str, Any], source: str) -> FluentSpec:
    """``s`` with the boundaries ``params`` gives (lower, upper, motion; an omitted tau or
    delta kept), checked."""
    where = f"{source}: fluents.{key}"
    _check_descriptive(s, params, where)
    if "lower" in params:
        s = replace(s, lower=_merge(s.lower, _threshold(params["lower"], f"{where}.lower"), where))
    if "upper" in params:
        s = replace(s, upper=_merge(s.upper, _threshold(params["upper"], f"{where}.upper"), where))
    if "motion" in params:
        motion = _threshold(params["motion"], f"{where}.motion")
        s = replace(s, motion_threshold=_merge(s.motion_threshold, motion, where))
    if s.upper is not None and s.upper.tau < s.lower.tau:
        raise ConfigError(f"fluent {key!r}: upper tau is below lower tau", source)
    _check_ranges(s, where)
    return s


@dataclass(frozen=True)
class FluentTable:
    """Every fluent and every parameter, one declared table (the paper's Table 1 and text)."""

    specs: tuple[FluentSpec, ...] = field(default_factory=_default_specs)
    epsilon: float = 1e-3
    window: int = 5
    reference_fps: float = 30.0
    touching_m: float = 0.1

    def spec(self, name: str) -> FluentSpec:
        for s in self.specs:
            if s.name == name:
                return s
        known = [s.name for s in self.specs]
        raise ConfigError(
            f"unknown fluent {name!r} (known: {', '.join(known[:5])}"
            f"{', ...' if len(known) > 5 else ''})",
            "fluent",
        )

    def with_overrides(self, raw: Mapping[str, Any], source: str = "thresholds") -> FluentTable:
        """A copy with parameters replaced from a parsed JSON/TOML mapping (see module doc)."""
        known = {*_SETTINGS, "fluents"}
        unknown = set(raw) - known
        if unknown:
            raise ConfigError(
                f"unknown setting {sorted(unknown)[0]!r} (known: {', '.join(sorted(known))})",
                source,
            )
        # each setting's own type (the window a whole number, the rest floats), checked
        settings: dict[str, Any] = {
            name: parse(raw[name], source) for name, parse in _SETTINGS.items() if name in raw
        }
        table = replace(self, **settings)
        fluents = raw.get("fluents", {})
        if not isinstance(fluents, Mapping):
            raise ConfigError("'fluents' must be a table of fluent names", source)
        specs = list(table.specs)
        # families first, then single fluents: a fluent's own entry wins whatever the order
        names = {s.name for s in specs}
        for key, params in sorted(fluents.items(), key=lambda kv: kv[0] in names):
            for i in _fluents_named(specs, key, params, source):
                specs[i] = _overridden(specs[i], key, params, source)
        return replace(table, specs=tuple(specs))

    @classmethod
    def from_file(cls, path: str | Path) -> FluentTable:
        """The default table with overrides from a ``.json`` or ``.toml`` file."""
        path = Path(path)
        raw = read_config(path, "thresholds file")
        return cls().with_overrides(raw, str(path))

    def to_dict(self) -> dict[str, Any]:
        """The whole table as plain data (what a user edits to override it). The near pairs
        are one ``near`` entry, with the thresholds most of them have, and an entry of its
        own for each pair whose thresholds differ: read back, it gives the same table."""

        def entry(s: FluentSpec) -> dict[str, Any]:
            out: dict[str, Any] = {
                **_descriptive(s),
                "lower": asdict(s.lower),
                "motion": asdict(s.motion_threshold),
            }
            if s.upper is not None:
                out["upper"] = asdict(s.upper)
            return out

        entries = {s.name: entry(s) for s in self.specs}
        texts = {s.name: json.dumps(entries[s.name]) for s in self.specs if s.family == "near"}
        common = Counter(texts.values()).most_common(1)[0][0] if texts else ""
        fluents: dict[str, Any] = {}
        for s in self.specs:
            if s.family != "near":
                fluents[s.name] = entries[s.name]
                continue
            fluents.setdefault("near", json.loads(common))  # the family, where its first was
            if texts[s.name] != common:
                fluents[s.name] = entries[s.name]
        return {
            "epsilon": self.epsilon,
            "window": self.window,
            "reference_fps": self.reference_fps,
            "touching_m": self.touching_m,
            "fluents": fluents,
        }


DEFAULT_TABLE = FluentTable()


def confidence_lower(x: np.ndarray, tau: np.ndarray | float, delta: np.ndarray | float,
                     epsilon: float) -> np.ndarray:  # fmt: skip
    """Paper eq. 2: confidence of a state that holds below τ. NaN in, NaN out."""
    k = math.log((1.0 - epsilon) / epsilon) / np.asarray(delta, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        c = 1.0 / (1.0 + np.exp(k * (x - tau)))
    c = np.where(x < tau - delta, 1.0, c)
    return np.where(x > tau + delta, 0.0, c)


def confidence_upper(x: np.ndarray, tau: np.ndarray | float, delta: np.ndarray | float,
                     epsilon: float) -> np.ndarray:  # fmt: skip
    """Paper eq. 3: the mirror image, a state that holds above τ."""
    return 1.0 - confidence_lower(x, tau, delta, epsilon)


def _lagged_deltas(x: np.ndarray, lag: float, window: int) -> tuple[np.ndarray, np.ndarray]:
    """Δ over one reference interval for each of the last ``window`` intervals.

    x: ``(frames, n)``. Returns ``(window, frames, n)`` deltas (age 0 = the newest) and a
    ``(window, frames)`` mask of which are defined (enough history).
    """
    frames = x.shape[0]
    f = np.arange(frames, dtype=np.float64)
    samples = []
    valid = []
    for m in range(window + 1):
        pos = f - m * lag
        ok = pos >= -1e-9
        pos = np.clip(pos, 0.0, frames - 1)
        lo = np.floor(pos).astype(np.intp)
        hi = np.minimum(lo + 1, frames - 1)
        w = (pos - lo)[:, None]
        # Linear interpolation for a fractional lag; exact samples where the weight is 0 (so a
        # NaN in the next frame does not leak into a defined one).
        samples.append(np.where(w == 0.0, x[lo], x[lo] * (1.0 - w) + x[hi] * w))
        valid.append(ok)
    deltas = np.stack([samples[k] - samples[k + 1] for k in range(window)])
    mask = np.stack([valid[k + 1] for k in range(window)])
    return deltas, mask


def _windowed_product(c: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Paper eq. 5: ∏ over ages a of C_a^(1/(a+1)); undefined ages count as 1 (no evidence).

    c: ``(window, frames, n)``; mask: ``(window, frames)``. The newest age must be defined.
    """
    out = np.ones(c.shape[1:])
    for age in range(c.shape[0]):
        factor = np.where(mask[age][:, None], c[age], 1.0)
        out *= factor if age == 0 else np.power(factor, 1.0 / (age + 1))
    return np.where(mask[0][:, None], out, np.nan)


@dataclass(frozen=True, eq=False)
class FluentResult:
    """Confidences of every state of every fluent, per frame.

    confidence: ``(frames, n_states)`` in [0, 1], NaN where unavailable. ``state_names`` are
    stable machine names (``left_leg_bent.bent``, ``left_leg_bent.bending``); ``words`` the
    phrases people read; ``temporal[i]`` tells whether state i is locally temporal and
    ``steady[i]`` whether it is a no-motion state;
    ``fluent[i]`` the index into ``table.specs``.
    """

    state_names: tuple[str, ...]
    words: tuple[str, ...]
    temporal: np.ndarray
    steady: np.ndarray
    fluent: np.ndarray
    confidence: np.ndarray
    fps: float
    table: FluentTable

    @property
    def n_frames(self) -> int:
        return int(self.confidence.shape[0])

    def column(self, state_name: str) -> np.ndarray:
        return self.confidence[:, self.state_names.index(state_name)]

    def available(self) -> np.ndarray:
        """``(n_states,)`` bool: the state is defined in at least one frame."""
        missing: np.ndarray = np.all(np.isnan(self.confidence), axis=0)
        return ~missing


def _slug(state: str) -> str:
    return state.replace(" ", "_").replace("-", "_")


def _layout(table: FluentTable) -> list[tuple[int, str, str, bool]]:
    """(spec index, machine state, words, temporal) for every output column."""
    cols: list[tuple[int, str, str, bool]] = []
    for i, s in enumerate(table.specs):
        states = list(s.states)
        if s.secondary:
            states.pop(1)
        for st in states:
            cols.append((i, st, s.phrase(st), False))
        if s.kind == "distance":
            cols.append((i, "touching", s.phrase("touching"), False))
        motions = list(s.motion if not s.secondary else s.motion[:2])
        for st in motions:
            cols.append((i, st, s.phrase(st), True))
    return cols


Backend = Literal["numba", "numpy"]

# Column codes of the fused kernel (features._fluent_kernels): which block a state comes from.
_CODES = ("lo", "mid", "hi", "two_hi", "touch", "m_lo", "m_hi", "still")


@dataclass(frozen=True, eq=False)
class _Prepared:
    """Everything :func:`evaluate` derives from a table alone (built once per table)."""

    state_names: tuple[str, ...]
    words: tuple[str, ...]
    temporal: np.ndarray  # (n_states,) bool
    steady: np.ndarray  # (n_states,) bool
    fluent: np.ndarray  # (n_states,) spec index
    code: np.ndarray  # (n_states,) index into _CODES
    signals: tuple[str, ...]  # (n,) signal name of each fluent
    distance: np.ndarray  # (n,) bool: a near fluent (its signal is a joint pair)
    partner: np.ndarray  # (n,) the other fluent of a tilt pair, or itself
    inst: np.ndarray  # (n, 8) lower (τ-δ, τ+δ, τ, k), upper (τ-δ, τ+δ, τ, k)
    motion: np.ndarray  # (n, 8) toward s0 (τ-δ, τ+δ, τ, k), toward sn (same)
    three: np.ndarray  # (n,) bool


_PREPARED: dict[int, tuple[FluentTable, _Prepared]] = {}


def _prepare(table: FluentTable) -> _Prepared:
    hit = _PREPARED.get(id(table))
    if hit is not None and hit[0] is table:
        return hit[1]
    specs = table.specs
    n = len(specs)
    cols = _layout(table)
    keys: list[str] = []
    for i, st, _, temporal in cols:
        s = specs[i]
        if temporal:
            keys.append(("m_lo", "m_hi", "still")[s.motion.index(st)])
        elif st == "touching":
            keys.append("touch")
        else:
            pos = s.states.index(st)
            if pos == 0:
                keys.append("lo")
            elif s.upper is None:
                keys.append("two_hi")
            else:
                keys.append("mid" if pos == 1 else "hi")
    index_of = {s.name: i for i, s in enumerate(specs)}
    logit = math.log((1.0 - table.epsilon) / table.epsilon)

    def band(tau: float, delta: float) -> list[float]:
        # The same float operations as confidence_lower, so both backends cut at the same x.
        return [tau - delta, tau + delta, tau, logit / delta]

    inst = np.array(
        [
            band(s.lower.tau, s.lower.delta)
            + (band(s.upper.tau, s.upper.delta) if s.upper else [np.inf, np.inf, np.inf, 0.0])
            for s in specs
        ]  # fmt: skip
    ).reshape(n, 8)
    motion = np.array(
        [
            band(-s.motion_threshold.tau, s.motion_threshold.delta)
            + band(s.motion_threshold.tau, s.motion_threshold.delta)
            for s in specs
        ]  # fmt: skip
    ).reshape(n, 8)
    prepared = _Prepared(
        state_names=tuple(f"{specs[i].name}.{_slug(st)}" for i, st, _, _ in cols),
        words=tuple(w for _, _, w, _ in cols),
        temporal=np.array([t for _, _, _, t in cols], dtype=bool),
        steady=np.array([k == "still" for k in keys], dtype=bool),
        fluent=np.array([i for i, _, _, _ in cols], dtype=np.intp),
        code=np.array([_CODES.index(k) for k in keys], dtype=np.intp),
        signals=tuple(s.signal for s in specs),
        distance=np.array([s.kind == "distance" for s in specs], dtype=bool),
        partner=np.array(
            [index_of.get(s.paired_with or "", i) for i, s in enumerate(specs)], dtype=np.intp
        ),  # fmt: skip
        inst=inst,
        motion=motion,
        three=np.array([s.upper is not None for s in specs], dtype=bool),
    )
    for arr in (prepared.temporal, prepared.steady, prepared.fluent, prepared.code):
        arr.setflags(write=False)  # shared by every FluentResult of this table
    if len(_PREPARED) >= 16:
        _PREPARED.clear()
    _PREPARED[id(table)] = (table, prepared)
    return prepared


_COLUMNS: dict[tuple[int, tuple[str, ...]], tuple[_Prepared, np.ndarray, np.ndarray]] = {}


def _signal_columns(sig: StateSignals, prep: _Prepared) -> tuple[np.ndarray, np.ndarray]:
    """Column of each fluent's signal in ``sig.values`` and of its distance in
    ``sig.distances_m`` (-1 for angle fluents), both ``(n,)`` (cached: a short clip would
    otherwise spend more time here than in the kernel)."""
    key = (id(prep), sig.names)
    hit = _COLUMNS.get(key)
    if hit is not None and hit[0] is prep:
        return hit[1], hit[2]
    col = {name: i for i, name in enumerate(sig.names)}
    pair_index = {name: k for k, name in enumerate(NEAR_SIGNALS)}
    try:
        sig_col = np.array([col[name] for name in prep.signals], dtype=np.intp)
    except KeyError as exc:
        raise ConfigError(f"fluent table names an unknown signal {exc.args[0]!r}") from None
    dist_col = np.array([pair_index.get(name, -1) for name in prep.signals], dtype=np.intp)
    if np.any(prep.distance & (dist_col < 0)):
        bad = prep.signals[int(np.flatnonzero(prep.distance & (dist_col < 0))[0])]
        raise ConfigError(f"distance fluent on {bad!r}, which is not a near joint pair")
    dist_col[~prep.distance] = -1
    if len(_COLUMNS) >= 16:
        _COLUMNS.clear()
    _COLUMNS[key] = (prep, sig_col, dist_col)
    return sig_col, dist_col


def _confidence_numpy(
    x: np.ndarray, dist_m: np.ndarray, fps: float, table: FluentTable, prep: _Prepared
) -> np.ndarray:
    """Reference implementation: whole-array numpy. x: ``(frames, n)`` each fluent's signal;
    dist_m: ``(frames, n)`` its distance in metres (NaN for angle fluents).
    Returns ``(frames, n_states)``."""
    specs = table.specs
    n = len(specs)
    eps = table.epsilon
    lo_tau = np.array([s.lower.tau for s in specs])
    lo_delta = np.array([s.lower.delta for s in specs])
    three = prep.three
    up_tau = np.array([s.upper.tau if s.upper else np.inf for s in specs])
    up_delta = np.array([s.upper.delta if s.upper else 1.0 for s in specs])

    c_lo = confidence_lower(x, lo_tau, lo_delta, eps)
    c_up = np.where(three, confidence_upper(x, up_tau, up_delta, eps), 0.0)
    c_up = np.where(np.isnan(x), np.nan, c_up)
    # Middle state (eq. 4); a tilt pair's upright state uses both directions (paper §Tilted).
    partner = prep.partner
    paired = partner != np.arange(n)
    not_extreme = (1.0 - c_lo) * (1.0 - c_up)
    c_mid = np.where(paired, not_extreme * not_extreme[:, partner], not_extreme)

    # Locally temporal fluents (eqs. 5-6).
    lag = fps / table.reference_fps
    deltas, mask = _lagged_deltas(x, lag, table.window)
    m_tau = np.array([s.motion_threshold.tau for s in specs])
    m_delta = np.array([s.motion_threshold.delta for s in specs])
    toward_lo = _windowed_product(confidence_lower(deltas, -m_tau, m_delta, eps), mask)
    toward_hi = _windowed_product(confidence_upper(deltas, m_tau, m_delta, eps), mask)
    still = (1.0 - toward_lo) * (1.0 - toward_hi)
    still = np.where(paired, still * still[:, partner], still)

    touching = np.where(np.isnan(dist_m), np.nan, (dist_m <= table.touching_m) * 1.0)
    blocks = (c_lo, c_mid, c_up, 1.0 - c_lo, touching, toward_lo, toward_hi, still)
    out = np.empty((x.shape[0], len(prep.state_names)))
    for code, block in enumerate(blocks):
        sel = prep.code == code
        if sel.any():
            out[:, sel] = block[:, prep.fluent[sel]]
    return out


def state_columns(
    table: FluentTable | None = None,
) -> tuple[tuple[str, ...], tuple[str, ...], np.ndarray]:
    """The columns :func:`evaluate` gives for ``table`` (default: the paper's), without a clip:
    machine state names, words and ``(n_states,)`` whether each is locally temporal."""
    prep = _prepare(table or DEFAULT_TABLE)
    return prep.state_names, prep.words, prep.temporal


def _confidence_numba(
    sig: StateSignals,
    sig_col: np.ndarray,
    dist_col: np.ndarray,
    fps: float,
    table: FluentTable,
    prep: _Prepared,
) -> np.ndarray:
    """The compiled kernel (:func:`features._fluent_kernels.fluent_columns`): every state's
    confidence ``(frames, n_states)`` as float32, column-major (each state's series
    contiguous), within 1e-6 of the float64 reference."""
    from ._fluent_kernels import all_nan_columns, fluent_columns

    # one compiled specialisation: row-major float64 (what state_signals gives; any other
    # layout or type is copied into it, where numba would compile the kernel again, ~40 s)
    values = np.ascontiguousarray(sig.values, dtype=np.float64)
    distances = np.ascontiguousarray(sig.distances_m, dtype=np.float64)
    # A fluent whose signal (and, for near, distance in metres) is missing in every frame is
    # NaN throughout: leave it out of the kernel (e.g. no face on Kinect or mocap).
    skip = all_nan_columns(values)[sig_col]
    near = dist_col >= 0
    skip[near] &= all_nan_columns(distances)[dist_col[near]]
    skip &= skip[prep.partner]  # a tilt pair is kept whole
    keep = np.flatnonzero(~skip)
    new_index = np.cumsum(~skip) - 1
    kept_cols = ~skip[prep.fluent]
    cols = np.flatnonzero(kept_cols)
    out_col = np.full((len(keep), len(_CODES)), -1, dtype=np.intp)
    out_col[new_index[prep.fluent[cols]], prep.code[cols]] = cols
    touching = keep[out_col[:, _CODES.index("touch")] >= 0]
    out = np.empty((len(prep.state_names), values.shape[0]), dtype=np.float32)
    fluent_columns(
        values, distances, sig_col[keep].astype(np.uintp), dist_col[touching].astype(np.uintp),
        prep.inst[keep], prep.motion[keep],
        prep.three[keep], new_index[prep.partner[keep]], float(table.touching_m),
        float(fps / table.reference_fps), int(table.window), out_col, out,
    )  # fmt: skip
    if not kept_cols.all():
        out[~kept_cols] = np.nan
    return out.T


def evaluate(
    seq: PoseSequence,
    table: FluentTable | None = None,
    signals: StateSignals | None = None,
    backend: Backend = "numba",
) -> FluentResult:
    """Every fluent state's confidence for every frame of ``seq`` (all frames at once).

    ``backend``: ``"numba"`` the compiled single-pass kernel (:mod:`features._fluent_kernels`),
    ``"numpy"`` the whole-array reference it is tested against (for the state signals too,
    unless ``signals`` are given). The kernel's confidences are float32 and column-major
    (each state's series contiguous), the reference's float64; they agree within 1e-6, with
    the same NaN and the same exact 0 and 1.
    """
    expect_sequence(seq)
    table = table or DEFAULT_TABLE
    sig = signals if signals is not None else state_signals(seq, backend)
    prep = _prepare(table)
    frames = sig.values.shape[0] if sig.values.ndim == 2 else -1
    if sig.values.shape != (frames, len(sig.names)) or sig.distances_m.shape != (
        frames,
        len(NEAR_SIGNALS),
    ):
        raise DataError(
            f"state signals have shapes {sig.values.shape} and {sig.distances_m.shape}, expected "
            f"(frames, {len(sig.names)}) and (frames, {len(NEAR_SIGNALS)})",
            seq.source or None,
        )
    sig_col, dist_col = _signal_columns(sig, prep)
    if backend == "numba":
        out = _confidence_numba(sig, sig_col, dist_col, seq.fps, table, prep)
    elif backend == "numpy":
        x = sig.values[:, sig_col]
        dist_m = np.full(x.shape, np.nan)
        near = dist_col >= 0
        dist_m[:, near] = sig.distances_m[:, dist_col[near]]
        out = _confidence_numpy(x, dist_m, seq.fps, table, prep)
    else:
        raise ConfigError(f"unknown fluent backend {backend!r} (known: numba, numpy)")
    return FluentResult(
        state_names=prep.state_names,
        words=prep.words,
        temporal=prep.temporal,
        steady=prep.steady,
        fluent=prep.fluent,
        confidence=out,
        fps=seq.fps,
        table=table,
    )


# Frames evaluated at once by evaluate_chunks: every state's confidence is 566 x 8 bytes per
# frame, 4.5 GB for a million frames, so long clips go through in pieces of about 90 MB.
CHUNK_FRAMES = 20_000


def history_frames(table: FluentTable, fps: float) -> int:
    """Frames before a frame that its temporal states read (``window`` reference intervals of
    ``fps / reference_fps`` frames, and one more for the interpolation)."""
    return int(math.ceil(table.window * fps / table.reference_fps)) + 1


def evaluate_chunks(
    seq: PoseSequence,
    table: FluentTable | None = None,
    chunk_frames: int = CHUNK_FRAMES,
    margin: int = 0,
    backend: Backend = "numba",
) -> Iterator[tuple[int, int, int, FluentResult]]:
    """:func:`evaluate` in consecutive pieces, for clips too long to hold at once.

    Yields ``(start, stop, first, result)`` for ``start``, ``stop`` = 0..chunk_frames,
    chunk_frames..2*chunk_frames, ...: ``result`` covers frames ``first`` .. (``stop`` +
    ``margin``, clipped to the clip), with ``first = max(0, start - margin)``. Each piece is
    evaluated with the history its temporal states need, so the confidences are those of
    ``evaluate(seq, table, backend=backend)`` for the same frames.
    """
    table = table or DEFAULT_TABLE
    for name, value, least in (("chunk_frames", chunk_frames, 1), ("margin", margin, 0)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least:
            raise ConfigError(f"must be a whole number >= {least}, got {value!r}", name)
    n = seq.n_frames
    history = history_frames(table, seq.fps)
    for start in range(0, n, chunk_frames):
        stop = min(n, start + chunk_frames)
        first, last = max(0, start - margin), min(n, stop + margin)
        read_from = max(0, first - history)
        result = evaluate(seq.slice_frames(read_from, last), table, backend=backend)
        kept = result.confidence[first - read_from :]
        yield start, stop, first, replace(result, confidence=kept)


# Guard: the table refers only to signals that exist.
assert {s.signal for s in DEFAULT_TABLE.specs} <= set(ANGLE_SIGNALS) | set(NEAR_SIGNALS)
