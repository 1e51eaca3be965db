"""Reuse: the solution from the retrieved cases by a similarity-weighted vote.

:func:`vote` is THE vote of posecbr: the classifier's reuse step, the inner cross-validation
of fit and the maintenance editors all call it, so they agree on weights and ties.

- ``"distance"``: each retrieved case votes 1 / distance; a case at distance 0 (an exact match)
  decides alone, as in scikit-learn's ``KNeighborsClassifier``;
- ``"uniform"``: each retrieved case votes 1;
- ties go to the first class in the caller's order (classes are kept sorted);
- ``balance``: the number of cases of every class; given, a case's vote is divided by its
  class's share of the cases (times the mean share), so a class with five times the cases of
  another does not win by numbers alone: with 50 correct and 10 incorrect repetitions, a
  query whose five nearest cases are three correct and two incorrect at equal distances gets
  incorrect 2/10 against 3/50 (:func:`class_balance`; scikit-learn's
  ``class_weight="balanced"``). Equal counts change nothing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .retrieve import Retrieval

Weights = Literal["distance", "uniform"]
WEIGHTINGS: tuple[str, ...] = ("distance", "uniform")
#: distances at or below this count as exact matches
EXACT = 1e-12


@dataclass(frozen=True)
class Solution:
    """label, proba ``(n_classes,)`` the vote shares, ``vote_share`` the winner's share and
    ``confidence`` in [0, 1]: the winner's share as voted, or, from a fitted classifier, the
    probability that the label is right (its soft vote calibrated, :mod:`cbr.calibration`)."""

    label: str
    confidence: float
    proba: np.ndarray
    vote_share: float = float("nan")


def class_balance(case_labels: np.ndarray, classes: np.ndarray) -> np.ndarray:
    """The vote factor of every class of ``classes`` ``(C,)`` given the labels of the cases
    that vote ``(n,)``: the mean count over the class's count (1 for every class when the
    counts are equal; a class without a case 1, it never votes)."""
    labels = np.asarray(case_labels).astype(str)
    counts = np.array([np.sum(labels == str(c)) for c in classes], dtype=np.float64)
    have = counts > 0
    if not have.any():
        return np.ones(len(classes))
    mean = counts[have].mean()
    return np.where(have, mean / np.where(have, counts, 1.0), 1.0)


def vote(
    distances: np.ndarray,
    codes: np.ndarray,
    n_classes: int,
    weights: Weights = "distance",
    balance: np.ndarray | None = None,
) -> np.ndarray:
    """Vote shares of ``q`` queries over ``n_classes`` classes, ``(q, n_classes)``.

    distances: ``(q, k)`` distances to the retrieved cases (``inf``: no case in that slot);
    codes: ``(q, k)`` the class index (0 .. n_classes - 1) of each retrieved case. A row with
    no case gets equal shares. balance: ``(n_classes,)`` a factor on every class's votes
    (:func:`class_balance`), None: none.
    """
    d = np.asarray(distances, dtype=np.float64)
    c = np.asarray(codes, dtype=np.int64)
    if d.shape != c.shape or d.ndim != 2:
        raise ValueError(f"distances {d.shape} and class codes {c.shape} must be (q, k) alike")
    present = np.isfinite(d)
    if weights == "uniform":
        w = present.astype(np.float64)
    else:
        exact = present & (d <= EXACT)
        inverse = np.where(present, 1.0 / np.maximum(d, EXACT), 0.0)
        w = np.where(exact.any(axis=1, keepdims=True), exact.astype(np.float64), inverse)
    rows = np.repeat(np.arange(len(d)), d.shape[1])
    proba = np.zeros((len(d), n_classes))
    np.add.at(proba, (rows, np.where(present, c, 0).ravel()), w.ravel())
    if balance is not None:
        proba = proba * np.asarray(balance, dtype=np.float64)[None, :]
    total = proba.sum(axis=1, keepdims=True)
    return np.where(total > 0, proba / np.where(total > 0, total, 1.0), 1.0 / n_classes)


def decide(proba: np.ndarray) -> np.ndarray:
    """The winning class index of every row of ``proba`` ``(q, n_classes)``: the largest
    share, ties to the first class."""
    return np.asarray(np.argmax(proba, axis=1), dtype=np.int64)


def reuse(
    retrieval: Retrieval,
    classes: np.ndarray,
    weights: Weights = "distance",
    balance: np.ndarray | None = None,
) -> Solution:
    """The solution voted by the retrieved cases over ``classes`` (labels as str, sorted;
    ``balance`` as :func:`vote`)."""
    where = {str(c): i for i, c in enumerate(classes)}
    codes = np.array([where[str(lab)] for lab in retrieval.labels], dtype=np.int64)
    return solutions(retrieval.distances[None, :], codes[None, :], classes, weights, balance)[0]


def solutions(
    distances: np.ndarray,
    codes: np.ndarray,
    classes: np.ndarray,
    weights: Weights = "distance",
    balance: np.ndarray | None = None,
) -> list[Solution]:
    """:func:`reuse` of ``q`` queries at once, their retrieved cases given as ``distances``
    and class ``codes`` ``(q, k)`` (of ``classes``): one vote over every row."""
    proba = vote(distances, codes, len(classes), weights, balance)
    return [
        Solution(str(classes[b]), float(p[b]), p, float(p[b]))
        for p, b in zip(proba, decide(proba).tolist(), strict=True)
    ]
