"""Feature weights learned from the training cases (CBR feature weighting).

Each feature column gets a centre and a scale (z-normalisation over the training cases) and a
weight, the Fisher ratio of its between-activity to its within-activity variance::

    w_j = sum_c n_c (mean_c,j - mean_j)^2 / sum_c sum_{i in c} (x_ij - mean_c,j)^2

normalised so the weights average 1. A measure then compares ``(x - centre) / scale *
sqrt(w)``: the weighted squared distance ``sum_j w_j ((a_j - b_j) / scale_j)^2``. Everything is
computed from the cases given to :func:`learn_weights` (the training data of one fit), so a
cross-validation fold never sees its test clips; explanations can cite the top weights
("weighted most: left knee angle (lowest)").
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from features.errors import ConfigError, DataError
from features.text import did_you_mean

MIRROR_FLAG = "mirror_image"
_PENALTY_SAMPLE = 2000
_MIRROR_REFERENCE = 2000

WEIGHTINGS = ("fisher", "none")


def fisher_ratio(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Between-class over within-class variance of every column.

    X: ``(n, D)`` feature vectors; y: ``(n,)`` labels. Returns ``(D,)`` >= 0 (a column constant
    within every class but not across classes gets a large finite ratio, not inf).
    """
    X = np.asarray(X, dtype=np.float64)
    y = np.asarray(y)
    if X.ndim != 2 or len(X) != len(y):
        raise DataError(f"need (n, D) features and n labels, got {X.shape} and {y.shape}", "fit")
    _, inv = np.unique(y, return_inverse=True)
    counts = np.bincount(inv).astype(np.float64)
    sums = np.zeros((len(counts), X.shape[1]))
    np.add.at(sums, inv, X)
    means = sums / counts[:, None]
    grand = X.mean(axis=0)
    between = (counts[:, None] * (means - grand) ** 2).sum(axis=0)
    within = ((X - means[inv]) ** 2).sum(axis=0)
    total = between + within
    # a floor relative to the column's total variance keeps constant-within-class columns finite
    return np.asarray(between / (within + 1e-3 * total + 1e-12), dtype=np.float64)


@dataclass(frozen=True)
class FeatureWeights:
    """Per-column ``centre``, ``scale`` and ``weight``, each ``(D,)``."""

    centre: np.ndarray
    scale: np.ndarray
    weight: np.ndarray

    def multiplier(self) -> np.ndarray:
        """``sqrt(weight) / scale``, ``(D,)``: what a measure multiplies centred columns by."""
        return np.asarray(np.sqrt(self.weight) / self.scale, dtype=np.float64)

    def apply(self, X: np.ndarray) -> np.ndarray:
        """``(..., D)`` -> ``(..., D)`` weighted, z-normalised columns."""
        out: np.ndarray = (np.asarray(X, dtype=np.float64) - self.centre) * self.multiplier()
        return out

    def top(self, names: tuple[str, ...], n: int = 5) -> tuple[str, ...]:
        """The ``n`` names with the largest weights, largest first."""
        order = np.argsort(-self.weight, kind="stable")[:n]
        return tuple(names[i] for i in order if i < len(names))


def learn_weights(
    X: np.ndarray, y: np.ndarray, method: str = "fisher", *, min_scale: float = 1e-3
) -> FeatureWeights:
    """Centre, scale and weight of every column of ``X`` ``(n, D)`` from labels ``y`` ``(n,)``.

    method: ``"fisher"`` (between/within variance ratio) or ``"none"`` (z-normalisation only,
    equal weights). Columns constant in the training data get scale ``min_scale`` and weight 0
    (they cannot tell activities apart there).
    """
    if method not in WEIGHTINGS:
        raise ConfigError(
            f"feature weighting must be one of {', '.join(WEIGHTINGS)}, got {method!r}"
            f"{did_you_mean(str(method), WEIGHTINGS)}",
            "feature_weights",
        )
    X = np.asarray(X, dtype=np.float64)
    if X.ndim != 2 or len(X) < 2:
        raise DataError(f"need at least two (n, D) training vectors, got {X.shape}", "fit")
    centre = X.mean(axis=0)
    sd = X.std(axis=0)
    constant = sd < min_scale
    scale = np.where(constant, min_scale, sd)
    if method == "fisher":
        w = fisher_ratio(X, np.asarray(y))
    else:
        w = np.ones(X.shape[1])
    w = np.where(constant, 0.0, w)
    mean = w.mean()
    w = w / mean if mean > 0 else np.where(constant, 0.0, 1.0)
    return FeatureWeights(centre, scale, w)


def with_mirror_flag(problem: Any, value: float) -> Any:
    """``problem`` (a vector :class:`cbr.problem.Problem`) with one more column, ``value``: 1 for
    the mirror image of a training clip, 0 for a real clip (every query)."""
    return dataclasses.replace(
        problem,
        values=np.append(np.asarray(problem.values, dtype=np.float64), value),
        names=(*problem.names, MIRROR_FLAG),
        words=(*problem.words, "mirror image of a training clip"),
    )


def mirror_penalty(fw: FeatureWeights, real: np.ndarray, y: np.ndarray) -> FeatureWeights:
    """Weights whose last column (the mirror flag) adds a fixed distance to every mirror image.

    fw: weights learned on the real clips' columns, ``D - 1`` of them (the flag is appended);
    real: ``(n, D - 1)`` the real training clips' vectors; y: ``(n,)`` their labels. The penalty
    is the median distance (weighted, z-normalised) from a real clip to its nearest other clip
    of the same activity (on a sample of at most 2000 clips): a mirror image then has to be
    about as close as a typical same-activity neighbour to win over the real cases.
    """
    n = len(real)
    pick = np.arange(n)
    if n > _PENALTY_SAMPLE:
        pick = np.sort(np.random.default_rng(0).choice(n, _PENALTY_SAMPLE, replace=False))
    z = fw.apply(real[pick])
    sq = np.einsum("ij,ij->i", z, z)
    d2 = sq[:, None] + sq[None, :] - 2.0 * (z @ z.T)
    lab = np.asarray(y)[pick]
    same = (lab[:, None] == lab[None, :]) & ~np.eye(len(pick), dtype=bool)
    nearest = np.where(same, d2, np.inf).min(axis=1)
    nearest = nearest[np.isfinite(nearest)]
    penalty = float(np.sqrt(max(np.median(nearest), 0.0))) if len(nearest) else 1.0
    # centre 0 and scale 1 on the flag: the multiplier sqrt(weight) is the penalty itself
    centre = np.append(fw.centre, 0.0)
    scale = np.append(fw.scale, 1.0)
    weight = np.append(fw.weight, penalty**2)
    return FeatureWeights(centre, scale, weight)


def confusing_mirrors(
    fw: FeatureWeights, real: np.ndarray, mirror: np.ndarray, y: np.ndarray, penalty: float
) -> np.ndarray:
    """Which mirror images look like another activity: ``(n,)`` bool.

    real / mirror: ``(n, D)`` the real training clips and their mirror images; y: ``(n,)``
    labels; fw: weights over the D columns. Two rules, both from the training data:

    - side twins: when most mirror images of activity A are nearest (weighted distance) to real
      clips of one other activity B, within twice ``penalty`` (median), and the same holds for
      B's images and A, then A and B differ by side (a left-arm raise mirrored is a right-arm
      raise): all their images are confusing;
    - single images whose nearest real clip is of another activity and closer than
      ``penalty`` are confusing too.

    Nearest real clips are sought among at most 2000 of them (a seeded sample), so the cost
    grows linearly with the clips.
    """
    lab = np.asarray(y).astype(str)
    # each image's nearest real clip among at most _MIRROR_REFERENCE of them (a seeded sample):
    # all pairs would cost the square of the clips
    ref = np.arange(len(real))
    if len(real) > _MIRROR_REFERENCE:
        ref = np.sort(np.random.default_rng(0).choice(len(real), _MIRROR_REFERENCE, replace=False))
    a, ref_lab = fw.apply(real[ref]), lab[ref]
    sq_a = np.einsum("ij,ij->i", a, a)
    nearest_label = np.empty(len(mirror), dtype=object)
    nearest_dist = np.empty(len(mirror))
    out = np.zeros(len(mirror), dtype=bool)
    for s in range(0, len(mirror), 1000):  # chunks keep the distance block small at any size
        blk = fw.apply(mirror[s : s + 1000])
        d2 = np.einsum("ij,ij->i", blk, blk)[:, None] + sq_a[None, :] - 2.0 * (blk @ a.T)
        j = np.argmin(d2, axis=1)
        near = np.sqrt(np.maximum(d2[np.arange(len(blk)), j], 0.0))
        nearest_label[s : s + len(blk)] = ref_lab[j]
        nearest_dist[s : s + len(blk)] = near
        out[s : s + len(blk)] = (ref_lab[j] != lab[s : s + len(blk)]) & (near < penalty)
    twin: dict[str, str] = {}
    for c in np.unique(lab):
        got, count = np.unique(nearest_label[lab == c].astype(str), return_counts=True)
        top = int(np.argmax(count))
        close = np.median(nearest_dist[lab == c]) < 2.0 * penalty
        if got[top] != c and count[top] > 0.5 * count.sum() and close:
            twin[str(c)] = str(got[top])
    for c, t in twin.items():
        if twin.get(t) == c:
            out[lab == c] = True
    return out
