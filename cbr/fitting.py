"""The learned parts of a vector case base, as pure functions of the training matrices.

:func:`assemble_cases` turns the training clips' problem vectors into the case matrix for one
side handling and one feature weighting; :func:`inner_loso_accuracy` scores such a choice by
leave-one-subject-out inside the training clips, so :class:`cbr.estimator.CaseBaseClassifier`
can choose without looking at its test clips.

Side handlings (people favour one side: a subject who raises the left arm should find the
right-arm cases):

- ``"off"``: clips as recorded;
- ``"canonical"``: a clip that moves its left side more is described by its mirror image,
  cases and queries alike (:func:`features.body.moves_left_more`);
- ``"augment"``: the mirror image of every training clip is a further case, at a distance
  penalty (a flagged column, :func:`cbr.weights.mirror_penalty`), with the images that mimic
  another activity (side twins such as "kick left" / "kick right") left out
  (:func:`cbr.weights.confusing_mirrors`).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from .reuse import Weights, decide, vote
from .weights import FeatureWeights, confusing_mirrors, learn_weights, mirror_penalty

# in order of preference when inner cross-validation ties: training subjects who all favour
# the same side cannot show that a new person may use the other one, so the side-invariant
# handlings come first
SIDES = ("canonical", "augment", "off")
# clip summaries may add the mean over each third of the clip (start, middle, end): the
# phases "auto" tries, against none
AUTO_PHASES = 3
_QUERY_CHUNK = 512
# learned weights are judged by inner leave-one-subject-out only when every inner training fold
# still has two or more people in it
MIN_SUBJECTS_TO_JUDGE_WEIGHTS = 3
#: the inner selection scores its choices on at most this many training clips (a seeded sample,
#: every activity and subject in proportion): its all-pairs distances cost the square of the
#: clips, and beyond a few thousand clips the choice it makes no longer moves
INNER_SAMPLE = 2000
#: with more subjects than this, the inner selection holds out groups of subjects (this many
#: folds, subjects dealt round-robin in sorted order) rather than one subject at a time
INNER_FOLDS = 10


def subject_folds(subjects: np.ndarray, folds: int = INNER_FOLDS) -> np.ndarray:
    """The inner fold of every clip ``(n,)``: its subject, or with more than ``folds``
    subjects, one of ``folds`` groups of them."""
    names, inverse = np.unique(np.asarray(subjects).astype(str), return_inverse=True)
    if len(names) <= folds:
        return np.asarray(subjects)
    return np.asarray(inverse % folds)


def inner_sample(labels: np.ndarray, subjects: np.ndarray, cap: int = INNER_SAMPLE,
                 seed: int = 0) -> np.ndarray:  # fmt: skip
    """Positions of at most ``cap`` clips ``(m,)`` (sorted) drawn evenly from every
    (activity, subject) group of ``labels`` and ``subjects`` ``(n,)``; all of them when
    ``n <= cap``."""
    n = len(labels)
    if n <= cap:
        return np.arange(n)
    groups = np.unique(
        np.char.add(np.asarray(labels).astype(str), np.char.add("\0", subjects.astype(str))),
        return_inverse=True,
    )[1]
    counts = np.bincount(groups)
    # a random order, in which each group's members are spread evenly over (0, 1): the first
    # `cap` by that spread keep every group's share
    order = np.random.default_rng(seed).permutation(n)
    g = groups[order]
    by_group = np.argsort(g, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    within = np.arange(n) - starts[g[by_group]]
    spread = np.empty(n)
    spread[order[by_group]] = (within + 0.5) / counts[g[by_group]]
    rank = spread
    return np.sort(np.argsort(rank, kind="stable")[:cap])


def side_name(value: object) -> str:
    """The side handling named by a ``mirror`` parameter value (True/False or a name)."""
    if value is True or value == "augment":
        return "augment"
    if value is False or value == "off":
        return "off"
    return str(value)


@dataclass(frozen=True)
class Cases:
    """values ``(m, D)`` (``D + 1`` with the mirror flag column), labels ``(m,)``, origin
    ``(m,)`` (``i`` = training clip i, ``n + i`` = its mirror image), the learned weights
    (None: raw values) and whether the last column is the mirror flag."""

    values: np.ndarray
    labels: np.ndarray
    origin: np.ndarray
    weights: FeatureWeights | None
    flag: bool


def canonical(R: np.ndarray, M: np.ndarray | None, left: np.ndarray | None) -> np.ndarray:
    """Rows of ``R`` with the left-moving clips replaced by their mirror images (``M``)."""
    if M is None or left is None:
        raise ValueError("the canonical side needs the mirror images and the side of each clip")
    shape = (-1,) + (1,) * (R.ndim - 1)
    return np.where(left.reshape(shape), M, R)


def assemble_cases(
    R: np.ndarray,
    M: np.ndarray | None,
    left: np.ndarray | None,
    y: np.ndarray,
    side: str,
    weighting: str,
    vectors: bool = True,
) -> Cases:
    """The case matrix of training clips ``R`` ``(n, ...)`` with mirror images ``M``.

    left: ``(n,)`` which clips move their left side more (``"canonical"``); y: ``(n,)`` labels.
    Weights (``weighting="fisher"`` or ``"none"`` z-normalisation) are learned from the real
    clips only; with ``"augment"`` on vectors the images get the penalised flag column.
    """
    n = len(R)
    y = np.asarray(y, dtype=object)
    real = canonical(R, M, left) if side == "canonical" else R
    if side != "augment":
        fw = learn_weights(real, y, weighting) if vectors and weighting != "none" else None
        return Cases(real, y, np.arange(n), fw, False)
    if M is None:
        raise ValueError("mirror augmentation needs the mirror images")
    values = np.concatenate([R, M])
    labels = np.concatenate([y, y])
    origin = np.arange(2 * n)
    if not vectors:
        return Cases(values, labels, origin, None, False)
    # weights from the real clips only: with the images in, features that tell a left-side
    # activity from its right-side twin would look uninformative
    base = learn_weights(R, y, weighting)
    fw = mirror_penalty(base, R, y)
    bad = confusing_mirrors(base, R, M, y, float(np.sqrt(fw.weight[-1])))
    flags = np.concatenate([np.zeros(n), np.ones(n)])[:, None]
    keep = np.concatenate([np.ones(n, dtype=bool), ~bad])
    values = np.concatenate([values, flags], axis=1)
    return Cases(values[keep], labels[keep], origin[keep], fw, True)


def knn_predict(
    cases: Cases, queries: np.ndarray, k: int, weights: Weights = "distance"
) -> np.ndarray:
    """Labels of ``queries`` ``(q, D)`` by the k nearest cases under the weighted euclidean
    distance, voting as the classifier does (:func:`cbr.reuse.vote`)."""
    classes, proba = knn_proba(cases, queries, k, weights)
    return np.asarray(classes[decide(proba)])


def knn_proba(
    cases: Cases, queries: np.ndarray, k: int, weights: Weights = "distance"
) -> tuple[np.ndarray, np.ndarray]:
    """The cases' classes ``(C,)`` (sorted) and the vote shares of ``queries`` ``(q, D)``
    over them ``(q, C)``: the k nearest cases under the weighted euclidean distance voting as
    the classifier does (:func:`cbr.reuse.vote`)."""
    classes, codes = np.unique(cases.labels.astype(str), return_inverse=True)
    out = np.empty((len(queries), len(classes)))
    for s, idx, dk in _nearest_chunks(cases, queries, k, ordered=False):
        out[s : s + len(dk)] = vote(dk, codes[idx], len(classes), weights)
    return classes, out


def knn_neighbours(cases: Cases, queries: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` nearest cases of every query ``(q, D)`` under the weighted euclidean
    distance, nearest first (ties to the lower case): distances and positions ``(q, k)``."""
    k = min(int(k), len(cases.values))
    dist, where = np.empty((len(queries), k)), np.empty((len(queries), k), dtype=np.int64)
    for s, idx, dk in _nearest_chunks(cases, queries, k, ordered=True):
        dist[s : s + len(dk)], where[s : s + len(dk)] = dk, idx
    return dist, where


def _nearest_chunks(
    cases: Cases, queries: np.ndarray, k: int, ordered: bool
) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """The k nearest cases of the ``queries`` ``(q, D)``, a chunk of queries at a time (bounded
    memory: ``(chunk, n cases)`` distances): each chunk's first row, case positions and
    distances ``(chunk, k)``, nearest first when ``ordered``."""
    Q = np.asarray(queries, dtype=np.float64)
    if cases.flag:
        Q = np.concatenate([Q, np.zeros((len(Q), 1))], axis=1)
    A = np.asarray(cases.values, dtype=np.float64)
    if cases.weights is not None:
        A, Q = cases.weights.apply(A), cases.weights.apply(Q)
    k = min(int(k), len(A))
    sq_a = np.einsum("ij,ij->i", A, A)
    for s in range(0, len(Q), _QUERY_CHUNK):
        q = Q[s : s + _QUERY_CHUNK]
        d = np.sqrt(np.maximum(np.einsum("ij,ij->i", q, q)[:, None] + sq_a - 2.0 * q @ A.T, 0.0))
        if ordered:
            idx = np.argsort(d, axis=1, kind="stable")[:, :k]
        elif k < len(A):
            idx = np.argpartition(d, k - 1, axis=1)[:, :k]
        else:
            idx = np.argsort(d, axis=1)
        yield s, idx, np.take_along_axis(d, idx, axis=1)


def _inner_folds(
    R: np.ndarray,
    M: np.ndarray | None,
    left: np.ndarray | None,
    y: np.ndarray,
    subjects: np.ndarray,
    side: str,
    weighting: str,
) -> Iterator[tuple[np.ndarray, Cases, np.ndarray]]:
    """Leave-one-subject-out inside the training clips (many subjects: over
    :func:`subject_folds`): each fold's held-out clips ``(n,)`` (a mask), the case base of the
    other subjects' clips, weights and all, and the held-out clips as queries. A fold whose
    other subjects lack a second activity is skipped."""
    queries = canonical(R, M, left) if side == "canonical" else R
    folds = subject_folds(subjects)
    for s in np.unique(folds):
        test = folds == s
        train = ~test
        if len(np.unique(y[train])) < 2:
            continue
        cases = assemble_cases(
            R[train],
            None if M is None else M[train],
            None if left is None else left[train],
            y[train],
            side,
            weighting,
        )
        yield test, cases, queries[test]


def inner_loso_votes(
    R: np.ndarray,
    M: np.ndarray | None,
    left: np.ndarray | None,
    y: np.ndarray,
    subjects: np.ndarray,
    side: str,
    weighting: str,
    k: int,
    weights: Weights = "distance",
) -> tuple[np.ndarray, np.ndarray]:
    """Each training clip classified by a case base built, weights and all, from the OTHER
    subjects' clips (as :func:`inner_loso_accuracy` does): its winning vote share ``(n,)``
    and whether the winner was its label ``(n,)``. A subject whose fold lacks a second
    activity is left out (share NaN). With many subjects, leave-subjects-out over
    :func:`subject_folds`."""
    y = np.asarray(y).astype(str)
    share = np.full(len(y), np.nan)
    right = np.zeros(len(y), dtype=bool)
    for test, cases, queries in _inner_folds(R, M, left, y, subjects, side, weighting):
        classes, proba = knn_proba(cases, queries, k, weights)
        win = decide(proba)
        share[test] = proba[np.arange(len(win)), win]
        right[test] = classes[win] == y[test]
    return share, right


def inner_loso_neighbours(
    R: np.ndarray,
    M: np.ndarray | None,
    left: np.ndarray | None,
    y: np.ndarray,
    subjects: np.ndarray,
    side: str,
    weighting: str,
    k: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``k`` nearest cases of each training clip in a case base built, weights and all,
    from the OTHER subjects' clips (as :func:`inner_loso_votes`): distances ``(n, k)``
    (nearest first; ``inf`` where fewer, and for the clips of a skipped fold), their class
    codes ``(n, k)`` into ``classes`` ``(C,)``, the sorted labels of ``y``."""
    y = np.asarray(y).astype(str)
    classes = np.unique(y)
    dist = np.full((len(y), int(k)), np.inf)
    codes = np.zeros((len(y), int(k)), dtype=np.int64)
    for test, cases, queries in _inner_folds(R, M, left, y, subjects, side, weighting):
        d, where = knn_neighbours(cases, queries, k)
        found = np.searchsorted(classes, cases.labels.astype(str))
        dist[test, : d.shape[1]], codes[test, : d.shape[1]] = d, found[where]
    return dist, codes, classes


def inner_loso_accuracy(
    R: np.ndarray,
    M: np.ndarray | None,
    left: np.ndarray | None,
    y: np.ndarray,
    subjects: np.ndarray,
    side: str,
    weighting: str,
    k: int,
    weights: Weights = "distance",
) -> float:
    """Leave-one-subject-out accuracy of one side handling and weighting within the training
    clips ``R`` ``(n, D)`` (mirror images ``M``, sides ``left``, labels ``y``, ``subjects``);
    with many subjects, leave-subjects-out over :func:`subject_folds`."""
    _, right = inner_loso_votes(R, M, left, y, subjects, side, weighting, k, weights)
    return float(right.sum()) / len(right)
