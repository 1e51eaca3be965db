"""How much farther one recording's person lies from every case than the held-out cases of a
case base of one person do: what its margin judges take off every distance first
(:class:`cbr.unknown.Offset`)."""

from __future__ import annotations

import math

import numpy as np

PERSON_QUANTILE = 0.1
"""Where a recording's distances to the case base and the case base's own held-out ones are
compared (:func:`person_reach`, :func:`person_offset`): their nearest tenth, which a
left-out movement inside the recording hardly reaches. Tried against 0.25 on the one-person
runs of :data:`cbr.unknown_thresholds.NOVEL_CATCH` (unshrunk): the 25th percentile called fewer
left-out blocks unknown (docs/measurements.md, "Figures behind the code's rules: The tenth
quantile of a person's distances")."""


PERSON_PRIOR = 8
"""How many windows' worth of no offset :func:`person_offset` starts from: a stream's first
few windows (4 s at one every half second) show too little of the person to tell how far
they lie, and in a short recording of nothing but a movement the case base lacks that
movement would be taken for how far the person lies. It costs other people a few points of
seen blocks (docs/measurements.md, "Segmentation with one person's case base, and on other
labs' people, measured")."""


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
