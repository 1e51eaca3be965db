"""How unlike the stored cases a clip is, calibrated on the case base itself.

A new clip's *novelty* is the distance to its nearest case divided by the case base's usual
held-out nearest-case distance (the ``scale``: the median over held-out training clips, exact
matches left out, so binary QMP vectors, whose held-out clips often match a case exactly, get a
usable unit); it is *unlike the stored cases* when its nearest case is farther than the
``quantile`` (0.99) of the held-out training clips' nearest-case distances, or when it was
recorded with a skeleton (sensor) none of the training clips was recorded with: the joints of
another sensor sit elsewhere on the body, so its clips are not comparable with the cases
however near they look.

Held out means what a new person is: with subjects known, each training clip's nearest case
among the OTHER subjects' cases (leave-one-subject-out); otherwise among the cases of other
clips (leave-one-out; a clip's own mirror image does not count). The calibration is learned in
``fit`` for whatever feature level and measure the case base uses, and stored with it, so the
flag means the same for every configuration.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .casebase import CaseBase

#: held-out clips whose nearest-case distance is below this quantile are "like the cases"
UNLIKE_QUANTILE = 0.99
#: training clips used to calibrate (a seeded sample: the distances cost a full scan each)
CALIBRATION_SAMPLE = 256
#: held-out distances below this share of the largest one are exact matches
EXACT_SHARE = 1e-3


@dataclass(frozen=True)
class NoveltyCalibration:
    """scale: median held-out nearest-case distance (exact matches left out); unlike_ratio:
    the ``quantile`` of the held-out distances, in units of ``scale``, above which a clip is
    flagged; basis: how the training clips were held out; n: how many were; skeletons: the
    skeletons (sensors) the training clips were recorded with (empty: not known)."""

    scale: float
    unlike_ratio: float
    quantile: float
    basis: str
    n: int
    skeletons: tuple[str, ...] = ()

    def ratio(self, distance: float) -> float:
        """Nearest-case distance in units of the case base's usual one."""
        return float(distance) / self.scale if self.scale > 0 else float("inf")

    def reason(self, distance: float, skeleton: str | None = None) -> str:
        """Why a clip is unlike the stored cases: ``"sensor"`` (recorded with a skeleton no
        training clip was), ``"distance"`` (its nearest case is farther than held-out clips'
        are), or ``""`` (it is not)."""
        if skeleton is not None and self.skeletons and skeleton not in self.skeletons:
            return "sensor"
        return "distance" if self.ratio(distance) > self.unlike_ratio else ""

    def unlike(self, distance: float, skeleton: str | None = None) -> bool:
        return bool(self.reason(distance, skeleton))

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["skeletons"] = list(self.skeletons)
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
