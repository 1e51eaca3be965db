"""Training cases held out from their case base as a new recording will be (by subject, by
recording or by time), each with its distances to the nearest case of every activity left:
what the judges of "unknown" are calibrated on (:mod:`cbr.unknown_judges`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from features.body import MIRRORED

from .casebase import CaseBase, frame_array, overlapping
from .weights import MIRROR_FLAG

MARGIN_SAMPLE = 2048
"""Training cases held out to calibrate the margin (a seeded sample when there are more): a 5 %
quantile read from a few hundred lies a dozen cases from the top and moves with the sample
(docs/measurements.md, "Figures behind the code's rules: The margin's held-out sample"); each
costs one scan of the case base."""


def activity_codes(labels: Any, classes: Any) -> np.ndarray:
    """Each case's index among ``classes`` ``(n,)`` (compared as text; -1 for a label not
    among them). Both are sequences or 1-D arrays."""
    where = {str(c): i for i, c in enumerate(classes)}
    return np.array([where.get(str(v), -1) for v in labels], dtype=np.int64)


def per_activity(d: np.ndarray, codes: np.ndarray, n_classes: int) -> np.ndarray:
    """``(n_classes,)``: the smallest of the distances ``d`` ``(n_cases,)`` per activity
    (``codes``: each case's activity index); inf where an activity has no finite distance."""
    out = np.full(n_classes, np.inf)
    known = codes >= 0
    np.minimum.at(out, codes[known], np.asarray(d, dtype=np.float64)[known])
    return out


def held_out_basis(cb: CaseBase) -> tuple[str, np.ndarray]:
    """How a training case is held out as a new recording will be, and the group of every
    case ``(n,)``: by subject when all cases name one and two or more are named (with an
    activity done by two of them); else by source recording when an activity comes from two
    or more recordings; else by time (the cases of its own recording that overlap it are left
    out: repeated movements of one recording, the best the case base can do).

    A case without a source (a clip given as arrays, :class:`features.poses.PoseSequence` of
    a tracker's numbers, or its mirror image) is a recording of its own, as the classifier's
    own calibration counts it: taken as one recording together, every such clip overlapped
    every other (each starts at frame 0), so none had a case left to compare with and the
    default judge could not be calibrated on a case base of them."""
    labels = np.asarray(cb.labels).astype(str)
    subjects = [s or "" for s in cb.subjects]
    sources = [
        s if s.removesuffix(MIRRORED) else f"\0case {i} (no source)"
        for i, s in enumerate(s or "" for s in cb.sources)
    ]
    for basis, groups in (("subject", subjects), ("recording", sources)):
        g = np.array(groups, dtype=object)
        if basis == "subject" and "" in set(groups):
            continue
        if any(len(set(g[labels == a].tolist())) >= 2 for a in set(labels.tolist())):
            return basis, g
    return "time", np.array(sources, dtype=object)


def _left_out(cb: CaseBase, basis: str, groups: np.ndarray, i: int) -> np.ndarray:
    """``(n,)`` bool: the cases not seen when case ``i`` is held out."""
    same = groups == groups[i]
    if basis != "time":
        return np.asarray(same)
    # a case whose frames are not known overlaps nothing but itself
    frames = frame_array(cb.frames)
    overlap = overlapping(frames[i], frames)
    left_out: np.ndarray = np.asarray(same & overlap) | (np.arange(len(cb)) == i)
    return left_out


Held = tuple[np.ndarray, np.ndarray, str, np.ndarray]
"""What :func:`held_out_activities` measures: distances, activities, basis and groups."""


def calibration_order(cb: Any) -> tuple[str, ...]:
    """The activities of the case base ``cb`` (anything with ``labels``) in the order the
    judges are calibrated in: its labels as text, sorted (:func:`held_out_activities`)."""
    return tuple(sorted(set(np.asarray(cb.labels).astype(str).tolist())))


def held_out_rows(cb: Any, sample: int = MARGIN_SAMPLE, seed: int = 0) -> np.ndarray:
    """The positions of the cases :func:`held_out_activities` holds out ``(m,)``, sorted: the
    real cases of ``cb`` (not mirror images), a seeded sample of ``sample`` when more."""
    real = np.arange(len(cb))
    if cb.names and cb.names[-1] == MIRROR_FLAG:
        real = real[np.asarray(cb.problems)[:, -1] == 0]
    if len(real) > sample:
        real = np.sort(np.random.default_rng(seed).choice(real, sample, replace=False))
    return real


def held_out_activities(cb: CaseBase, sample: int = MARGIN_SAMPLE, seed: int = 0) -> Held:
    """Training cases held out (:func:`held_out_basis`) as a new recording is: each one's
    distance to the nearest case of every activity that is left ``(n, n_classes)`` (inf
    where none is), each one's activity ``(n,)`` (its index among the sorted labels), the
    basis and each one's group ``(n,)`` (its subject or recording). A seeded sample of at
    most ``sample`` real cases (not mirror images) is held out, each against all cases."""
    classes = list(calibration_order(cb))
    codes = activity_codes(cb.labels, classes)
    basis, groups = held_out_basis(cb)
    index = cb.index  # builds the representations
    reps = cb.reps
    assert reps is not None
    real = held_out_rows(cb, sample, seed)
    seen = np.full((len(real), len(classes)), np.inf)
    for row, i in enumerate(real.tolist()):  # one scan of the case base per held-out case
        d = cb.measure.distances(reps[i], index)
        out = _left_out(cb, basis, groups, i)
        seen[row] = per_activity(np.where(out, np.inf, d), codes, len(classes))
    return seen, codes[real], basis, groups[real]


def known_rows(seen: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: the held-out cases (distances to every activity ``(n, n_classes)``, own
    activity ``codes`` ``(n,)``) whose own activity is within reach and another too."""
    finite = np.isfinite(seen)
    own = finite[np.arange(len(seen)), codes]
    return np.asarray(own & (finite.sum(axis=1) >= 2))


def known_and_novel(seen: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """From held-out cases' distances to every activity ``(n, n_classes)`` and their own
    activity ``(n,)``: the rows where the own activity is within reach and another too
    (``known``), and the rows without the own activity where two others are (``novel``), as
    ``(k, n_classes)`` arrays (the own activity's column set to inf in ``novel``)."""
    known = seen[known_rows(seen, codes)]
    without = seen.copy()
    without[np.arange(len(seen)), codes] = np.inf
    novel = without[np.isfinite(without).sum(axis=1) >= 2]
    return known, novel
