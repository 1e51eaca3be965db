"""How unlike the stored cases a clip is, calibrated on the case base itself.

A new clip's *novelty* is the distance to its nearest case divided by the case base's usual
held-out nearest-case distance (the ``scale``); it is *unlike the stored cases* when that ratio
exceeds what held-out training clips reach in all but ``1 - quantile`` of the cases.

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


@dataclass(frozen=True)
class NoveltyCalibration:
    """scale: median held-out nearest-case distance; unlike_ratio: the ``quantile`` of the
    held-out ratios (distance / scale) above which a clip is flagged; basis: how the training
    clips were held out; n: how many were."""

    scale: float
    unlike_ratio: float
    quantile: float
    basis: str
    n: int

    def ratio(self, distance: float) -> float:
        """Nearest-case distance in units of the case base's usual one."""
        return float(distance) / self.scale if self.scale > 0 else float("inf")

    def unlike(self, distance: float) -> bool:
        return self.ratio(distance) > self.unlike_ratio

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NoveltyCalibration:
        return cls(
            float(d["scale"]),
            float(d["unlike_ratio"]),
            float(d["quantile"]),
            str(d["basis"]),
            int(d["n"]),
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


def calibrate(
    cb: CaseBase,
    queries: np.ndarray,
    query_groups: np.ndarray,
    case_groups: np.ndarray,
    basis: str,
    *,
    quantile: float = UNLIKE_QUANTILE,
    sample: int = CALIBRATION_SAMPLE,
    seed: int = 0,
) -> NoveltyCalibration:
    """Calibrate on the training clips ``queries`` ``(n, *problem_shape)`` as the classifier
    sees them: each is held out from the cases of its own group (``query_groups`` ``(n,)``
    against ``case_groups`` ``(n_cases,)``: subjects, or clip indices); ``basis`` names the
    grouping."""
    pick = np.arange(len(queries))
    if len(pick) > sample:
        pick = np.sort(np.random.default_rng(seed).choice(len(pick), sample, replace=False))
    groups = np.asarray(query_groups, dtype=object)
    d = held_out_distances(cb, queries[pick], groups[pick], np.asarray(case_groups, dtype=object))
    d = d[np.isfinite(d)]
    if len(d) == 0:
        return NoveltyCalibration(1.0, float("inf"), quantile, basis, 0)
    scale = float(np.median(d)) or float(np.mean(d)) or 1.0
    unlike = float(np.quantile(d / scale, quantile))
    return NoveltyCalibration(scale, unlike, quantile, basis, len(d))
