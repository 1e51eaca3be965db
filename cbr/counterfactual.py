"""Counterfactuals that hold: the fewest feature changes that make the classifier answer
another label, checked by running the changed problem through the same retrieve and reuse.

Nearest-unlike-neighbour counterfactuals (Native Guide, Delaney et al. 2021, for time series;
Keane and Smyth 2020 for case-based explanation): take the nearest real cases of the wanted
label X as *guides*; copy into the clip's problem, one feature at a time, the guide's values
of the feature that helps the guide most against the nearest cases of other labels (so every
changed value is one a real case of X has), until the classifier answers X; then undo every
change it does not need. A feature is one measured signal with everything computed from it
(:func:`cbr.profiles.signal_of`: a joint angle over the clip and the fluent states read from
it, "left knee"; a joint's position), or one QMP; under DTW or signatures each of them is
its channels over time.

Measured as the literature does: *validity* (the changed problem is classified X),
*sparsity* (features changed) and *plausibility* (the changed problem's distance to its
nearest case of X, over the usual distance between a case of X and its nearest other case of
X: about 1 for a problem that looks like the cases of X, large for one that looks like none).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .casebase import CaseBase
from .profiles import View, view_of
from .reuse import Weights, class_balance, vote
from .weights import MIRROR_FLAG

#: nearest cases of the wanted label tried as guides
GUIDES = 8
#: guides tried for sequence problems, whose search runs the classifier for every step
SEQUENCE_GUIDES = 3
#: nearest cases of other labels the guide must beat
RIVALS = 5
#: sets of features the search of vector problems keeps at each size
BEAM = 6
#: the most features one counterfactual may change before the search gives up on a guide
MAX_CHANGES = 6

Answer = Callable[[np.ndarray], str]


@dataclass(frozen=True)
class Counterfactual:
    """``label`` the answer wanted; ``guide`` the case position whose values were copied
    (None: no guide made it within :data:`MAX_CHANGES` features); ``features`` the view's
    feature indices changed, most important first; ``values`` the changed problem; ``valid``:
    the classifier answers ``label`` for it; ``answer`` what it answers; ``plausibility`` its
    nearest-case-of-``label`` distance over the label's usual one."""

    label: str
    guide: int | None
    features: tuple[int, ...]
    values: np.ndarray
    valid: bool
    answer: str
    plausibility: float


def _squared(cb: CaseBase, diff: np.ndarray, measured: np.ndarray | None = None) -> np.ndarray:
    """Squared differences ``(..., *problem_shape)`` under the measure's learned weights (when
    it has them); 0 where the problem's value is not ``measured`` (a fill the distance leaves
    out, :meth:`cbr.problem.Problem.measured`)."""
    mult = getattr(cb.measure, "multiplier", None)
    shape = cb.problems.shape[1:]
    if mult is not None and len(mult) == int(np.prod(shape)):
        diff = diff * np.asarray(mult, dtype=np.float64).reshape(shape)
    if measured is not None:
        diff = diff * np.asarray(measured, dtype=np.float64).reshape(shape)
    return np.asarray(diff**2, dtype=np.float64)


def _distances(cb: CaseBase, values: np.ndarray, measured: np.ndarray | None) -> np.ndarray:
    """``(n_cases,)`` distances from problem ``values`` over its ``measured`` values (None:
    all), as retrieval ranks them (:func:`cbr.retrieve.query_distances`)."""
    measure = cb.measure
    query = measure.represent_query(np.asarray(values))
    if measured is None:
        return measure.distances(query, cb.index)
    return measure.distances_measured(query, cb.index, measured)


def _per_feature(view: View, sq: np.ndarray) -> np.ndarray:
    """Entries of one problem's ``sq`` summed per feature ``(n_features,)``."""
    per_column = sq.sum(axis=0) if view.sequence else sq
    out = np.zeros(len(view.features))
    ok = view.channel_feature >= 0
    np.add.at(out, view.channel_feature[ok], per_column[ok])
    return out


def gains(
    cb: CaseBase,
    view: View,
    q: np.ndarray,
    g: np.ndarray,
    rivals: np.ndarray,
    measured: np.ndarray | None = None,
) -> np.ndarray:
    """How much copying each feature of guide ``g`` into problem ``q`` helps the guide win
    over the ``rivals`` ``(r, *problem_shape)`` (the nearest cases of other labels): the
    squared distance to the guide falls by ``(q - g)^2`` and to a rival grows by
    ``(g - n)^2 - (q - n)^2`` (weighted, summed per feature, averaged over the rivals; over
    the ``measured`` values alone: a feature the clip never showed gains nothing)."""
    toward = _per_feature(view, _squared(cb, q - g, measured))
    if len(rivals) == 0:
        return toward
    away = np.mean(
        [
            _per_feature(view, _squared(cb, g - n, measured) - _squared(cb, q - n, measured))
            for n in rivals
        ],
        axis=0,
    )
    return np.asarray(toward + away, dtype=np.float64)


def _changed(view: View, q: np.ndarray, g: np.ndarray, features: list[int]) -> np.ndarray:
    out = np.array(q, dtype=np.float64, copy=True)
    for f in features:
        mask = view.feature_mask(q.shape, f)
        out[mask] = g[mask]
    return out


def _label_scale(cb: CaseBase, label: str) -> float:
    """The usual distance from a case of ``label`` to its nearest other case of that label
    (median over a sample of the label's cases; cached)."""
    key = f"scale:{label}"
    if key in cb.cache:
        return float(cb.cache[key])
    own = np.flatnonzero(cb.labels.astype(str) == label)
    pick = own if len(own) <= 64 else np.random.default_rng(0).choice(own, 64, replace=False)
    measure, index = cb.measure, cb.index
    d = []
    for i in pick:
        row = measure.distances(measure.represent_query(cb.problems[i]), index)
        row = np.where(cb.labels.astype(str) == label, row, np.inf)
        row[i] = np.inf
        m = float(row.min())
        if np.isfinite(m) and m > 0:
            d.append(m)
    scale = float(np.median(d)) if d else 1.0
    cb.cache[key] = scale
    return scale


def plausibility(
    cb: CaseBase, values: np.ndarray, label: str, measured: np.ndarray | None = None
) -> float:
    """Distance of problem ``values`` (over its ``measured`` values: :func:`_distances`) to
    its nearest case of ``label`` over the label's usual nearest-case distance."""
    d = _distances(cb, values, measured)
    d = np.where(cb.labels.astype(str) == label, d, np.inf)
    return float(d.min()) / _label_scale(cb, label)


def _nearest(
    cb: CaseBase,
    values: np.ndarray,
    label: str,
    n_guides: int = GUIDES,
    measured: np.ndarray | None = None,
) -> tuple[list[int], np.ndarray]:
    """Positions of the ``n_guides`` nearest real cases of ``label`` (mirror images of
    training clips, flagged in the last column, are no real case) and of the :data:`RIVALS`
    nearest cases of other labels (over the ``measured`` values: :func:`_distances`)."""
    d = _distances(cb, values, measured)
    is_label = cb.labels.astype(str) == label
    real = np.ones(len(cb), dtype=bool)
    if cb.names and cb.names[-1] == MIRROR_FLAG and cb.problems.ndim == 2:
        real = cb.problems[:, -1] == 0.0
    mine = np.where(is_label & real, d, np.inf)
    order = np.argsort(mine, kind="stable")[:n_guides]
    rivals = np.argsort(np.where(is_label, np.inf, d), kind="stable")[:RIVALS]
    return [int(i) for i in order if np.isfinite(mine[i])], rivals[np.isfinite(d[rivals])]


def _search(
    cb: CaseBase,
    view: View,
    q: np.ndarray,
    g: np.ndarray,
    rivals: np.ndarray,
    label: str,
    answer: Answer,
    measured: np.ndarray | None = None,
) -> list[int] | None:
    """The fewest features (toward guide ``g``, most helpful first: :func:`gains`) after
    which the classifier answers ``label``, with every unneeded change undone; None within
    :data:`MAX_CHANGES`."""
    gain = gains(cb, view, q, g, cb.problems[rivals], measured)
    order = [int(f) for f in np.argsort(-gain, kind="stable") if gain[f] > 0]
    chosen: list[int] | None = None
    for n in range(1, min(MAX_CHANGES, len(order)) + 1):
        if answer(_changed(view, q, g, order[:n])) == label:
            chosen = order[:n]
            break
    if chosen is None:
        return None
    for f in list(reversed(chosen)):  # undo what is not needed, least separating first
        rest = [c for c in chosen if c != f]
        if rest and answer(_changed(view, q, g, rest)) == label:
            chosen = rest
    return chosen


class _Vectors:
    """Exact search for vector problems under (weighted) euclidean distance: the squared
    distance of every case to the problem with feature f copied from the guide is the current
    one plus ``delta[:, f]``, so the vote after each possible change is computed for all
    features of every kept set at once, one vote a step (the classifier's own vote,
    :func:`cbr.reuse.vote`; each candidate's k nearest cases chosen alone, as the vote of
    that problem chooses them). ``measured`` (None: all): the query's values its distances
    compare, the rest weighted 0 and the sum scaled by ``D / m``, as
    :meth:`cbr.similarity.euclidean.Euclidean.distances_measured` scales it."""

    def __init__(
        self,
        cb: CaseBase,
        view: View,
        q: np.ndarray,
        k: int,
        weights: Weights,
        balanced: bool,
        measured: np.ndarray | None = None,
    ):
        mult = getattr(cb.measure, "multiplier", None)
        centre = getattr(cb.measure, "centre", None)
        D = cb.problems.shape[1]
        w = np.ones(D) if mult is None else np.asarray(mult, dtype=np.float64) ** 2
        if measured is not None:
            keep = np.asarray(measured, dtype=bool).reshape(D)
            w = np.where(keep, w * (D / max(int(keep.sum()), 1)), 0.0)
        shift = np.zeros(D) if centre is None else np.asarray(centre, dtype=np.float64)
        self.C = cb.problems - shift
        self.q = q - shift
        self.k, self.weights = min(int(k), len(cb)), weights
        self.classes, self.codes = np.unique(cb.labels.astype(str), return_inverse=True)
        self.balance = class_balance(cb.labels, self.classes) if balanced else None
        self.d2 = np.asarray(((self.C - self.q) ** 2) @ w, dtype=np.float64)
        # the view's columns grouped by feature (every feature has one at least), so a
        # feature's sum over its columns is a run of np.add.reduceat: no matrix product with
        # a feature indicator, whose BLAS threads cost more than its arithmetic at this size
        order = np.argsort(view.feature, kind="stable")
        self.cols = view.columns[order]
        self.starts = np.searchsorted(view.feature[order], np.arange(len(view.features)))
        self.w = w[self.cols]
        self.Cw = self.C[:, self.cols] * self.w

    def deltas(self, guide: int) -> np.ndarray:
        """``(n, n_features)``: the change of every case's squared distance when the
        problem's feature f takes the values of case ``guide``:
        ``sum_j w_j [(g_j - c_j)^2 - (q_j - c_j)^2] = sum_j w_j (g_j - q_j)(g_j + q_j - 2 c_j)``
        over the feature's columns j."""
        g, q = self.C[guide, self.cols], self.q[self.cols]
        a = np.add.reduceat(self.w * (g**2 - q**2), self.starts)
        return np.asarray(
            a[None, :] - 2.0 * np.add.reduceat(self.Cw * (g - q), self.starts, axis=1)
        )

    def margins(self, d2: np.ndarray, target: int) -> np.ndarray:
        """For squared distances ``(n, F)`` (one column per candidate problem), the target's
        vote share minus the best other share ``(F,)``."""
        k = self.k
        rows = np.ascontiguousarray(d2.T)  # one candidate a row: each selection runs in place
        top = (np.argpartition(rows, k - 1, axis=1)[:, :k] if k < len(d2)
               else np.argsort(rows, axis=1))  # fmt: skip
        d = np.sqrt(np.maximum(np.take_along_axis(rows, top, axis=1), 0.0))
        proba = vote(d, self.codes[top], len(self.classes), self.weights, self.balance)
        others = np.delete(proba, target, axis=1).max(axis=1)
        return np.asarray(proba[:, target] - others, dtype=np.float64)

    def search(self, guide: int, label: str) -> list[int] | None:
        """Beam search (:data:`BEAM` sets of features kept at each size): extend every kept
        set by each feature of case ``guide`` not in it; keep the extensions that help the
        target label's vote most (while the vote does not move, those that bring the guide
        nearest relative to the nearest cases of other labels); stop at the first size at
        which the label wins (ties go to the first class, as in the vote). Then undo every
        change the winner does not need."""
        target = int(np.searchsorted(self.classes, label))
        other = self.codes != target
        delta = self.deltas(guide)
        n, n_features = delta.shape
        beam: list[tuple[tuple[int, ...], np.ndarray]] = [((), self.d2)]
        for _ in range(MAX_CHANGES):
            # every kept set's extensions at once: column b * n_features + f is set b with f
            cand = np.stack([d2 for _, d2 in beam], axis=1)[:, :, None] + delta[:, None, :]
            cand = cand.reshape(n, -1)
            m = self.margins(cand, target).reshape(len(beam), n_features)
            rivals = np.sort(cand[other], axis=0)[: self.k].mean(axis=0)
            gap = (cand[guide] - rivals).reshape(len(beam), n_features)
            best = np.argsort(-m, axis=1, kind="stable")[:, : 4 * BEAM].tolist()
            scored: dict[frozenset[int], tuple[float, float, tuple[int, ...], int]] = {}
            for b, (chosen, _) in enumerate(beam):
                for f in best[b]:
                    key = frozenset((*chosen, f))
                    if f in chosen or key in scored:
                        continue
                    scored[key] = (float(m[b, f]), float(gap[b, f]), (*chosen, f),
                                   b * n_features + f)  # fmt: skip
            ranked = sorted(scored.values(), key=lambda t: (-t[0], t[1]))[:BEAM]
            if not ranked:  # every feature changed and the label does not win
                return None
            beam = [(c, cand[:, j]) for _, _, c, j in ranked]
            winner = next((i for i, t in enumerate(ranked) if _won(t[0], target)), None)
            if winner is not None:
                return self._undo(list(beam[winner][0]), beam[winner][1], delta, target)
        return None

    def _undo(self, chosen: list[int], d2: np.ndarray, delta: np.ndarray, target: int) -> list[int]:
        """``chosen`` without the changes the label wins without (least helpful first)."""
        for f in list(reversed(chosen)):
            rest = [c for c in chosen if c != f]
            if rest and self._wins(d2 - delta[:, f], target):
                chosen, d2 = rest, d2 - delta[:, f]
        return chosen

    def _wins(self, d2: np.ndarray, target: int) -> bool:
        return _won(float(self.margins(d2[:, None], target)[0]), target)


def _won(margin: float, target: int) -> bool:
    """Whether the ``target`` class wins a vote by ``margin`` (its share minus the best other
    one): a tie goes to the first class in order."""
    return margin > 0 or (margin == 0 and target == 0)


def counterfactual(
    cb: CaseBase,
    values: np.ndarray,
    label: str,
    answer: Answer,
    k: int = 5,
    weights: Weights = "distance",
    balanced: bool = False,
    measured: np.ndarray | None = None,
) -> Counterfactual:
    """The sparsest valid counterfactual of problem ``values`` toward ``label`` over the
    :data:`GUIDES` (sequences: :data:`SEQUENCE_GUIDES`) nearest real cases of ``label``.
    ``answer`` classifies a problem as the classifier does (its retrieve and reuse: the final
    check); ``k`` and ``weights`` are its vote, which the search of vector problems under
    euclidean distance follows exactly (``balanced``: each class's votes divided by its share
    of the cases, :func:`cbr.reuse.class_balance`); ``measured`` (None: all) the values the
    classifier's distances compare (:meth:`cbr.problem.Problem.measured`: the fills of
    features the clip never showed left out, by the search too, and by ``answer``)."""
    view = view_of(cb)
    q = np.asarray(values, dtype=np.float64)
    exact = (
        _Vectors(cb, view, q, k, weights, balanced, measured)
        if q.ndim == 1 and getattr(cb.measure, "name", "") == "euclidean"
        else None
    )
    best: tuple[int, float, int, list[int], np.ndarray] | None = None
    guides, rivals = _nearest(
        cb, q, label, GUIDES if exact is not None else SEQUENCE_GUIDES, measured
    )
    for g in guides:
        if exact is not None:
            found = exact.search(g, label)
        else:
            found = _search(cb, view, q, cb.problems[g], rivals, label, answer, measured)
        if found is None:
            continue
        changed = _changed(view, q, cb.problems[g], found)
        if answer(changed) != label:
            continue
        plaus = plausibility(cb, changed, label, measured)
        if best is None or (len(found), plaus) < (best[0], best[1]):
            best = (len(found), plaus, g, found, changed)
    if best is None:
        return Counterfactual(label, None, (), q, False, answer(q), float("nan"))
    _, plaus, g, found, changed = best
    got = answer(changed)
    return Counterfactual(label, g, tuple(found), changed, got == label, got, plaus)
