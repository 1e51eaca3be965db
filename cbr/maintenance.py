"""Case base maintenance: novelty/benefit trimming at build time, and the classic editors
(CNN, RENN, ICF) for comparison. Every method reports size and accuracy before and after.

Novelty/benefit trimming (per activity, so every activity keeps the same share of its cases
and its feature distribution stays comparable):

- novelty of a case = distance to its nearest case of the same activity (leave-one-out),
  divided by that activity's median: a case with a near twin adds little;
- benefit = coverage - liability (Smyth & Keane 1995): how many other cases have it among
  their k nearest with the same label, minus those where it votes for a wrong label;
- per activity, the cases with the lowest combined rank (novelty rank + benefit rank, equal
  values sharing their mean rank) go; equal combined ranks: the later case goes.

Editors (Wilson & Martinez 2000, Brighton & Mellish 2002) work on the leave-one-out pairwise
distance matrix: CNN (Hart 1968) keeps a consistent subset for 1-NN; RENN repeats Wilson's
edited nearest neighbour (drop cases their k nearest misclassify) until nothing changes; ICF
runs ENN, then repeatedly drops cases whose reachable set is larger than their coverage set.

Mirror images (``--mirror augment``: every clip and its left-right image, :func:`mirror_twins`):
every editor judges a case without its own image (its nearest same-activity case otherwise,
the same movement on the other side: a case looked redundant, covered or, its image relabelled,
noisy because of its own reflection), and keeps or drops a case and its image together
(:func:`twin_groups`), so the case base stays mirror-symmetric: novelty-benefit ranks the pair
by its two cases' mean rank and keeps ``keep`` of each activity's pairs; CNN adds both when
either is misclassified; RENN and ICF drop the pair only when they would drop both.

Accuracy before/after: on an evaluation set when given, otherwise leave-one-out over the
original cases (each case classified by the other cases of the edited case base).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from features.body import MIRRORED
from features.progress import progress
from features.text import percent

from .casebase import CaseBase, frame_array
from .retrieve import retrieve
from .reuse import Weights, decide, vote
from .words import DROPPED as DROPPED

if TYPE_CHECKING:  # the store itself only for a trim recorded in it (record_trim)
    from casebase_store import CaseBaseInfo, StoreTransaction


@dataclass(frozen=True)
class MaintenanceReport:
    """What a maintenance method did: ``kept`` positions into the original case base."""

    method: str
    size_before: int
    size_after: int
    accuracy_before: float
    accuracy_after: float
    kept: np.ndarray
    casebase: CaseBase
    novelty: np.ndarray | None = None  # (size_before,)
    benefit: np.ndarray | None = None  # (size_before,)
    distribution_shift: float | None = None  # max over activities, in pooled std units
    original_ids: np.ndarray | None = None  # (size_before,) store ids (-1: not stored)
    before: CaseBase | None = None  # the case base that was edited
    #: what the accuracies were measured on, in words
    measured: str = ""
    #: activities the editor dropped every case of, one kept (:func:`keep_every_activity`)
    kept_alone: tuple[str, ...] = ()
    #: the case kept of each such activity was kept with its mirror image
    kept_alone_with_image: bool = False

    def summary(self) -> str:
        text = (
            f"{self.method}: {self.size_before} -> {self.size_after} cases, accuracy "
            f"{percent(self.accuracy_before)} -> {percent(self.accuracy_after)}"
        )
        if self.measured:
            text += f" ({self.measured})"
        if self.kept_alone:
            names = ", ".join(repr(a) for a in self.kept_alone)
            one = "one case (and its mirror image)" if self.kept_alone_with_image else "one case"
            text += f"; {one} kept of {names}, every case of which the editor dropped"
        return text


def pairwise_distances(cb: CaseBase, desc: str = "distances") -> np.ndarray:
    """``(n, n)`` distances between all cases under the case base's measure."""
    index = cb.index
    assert cb.reps is not None
    rows = [
        cb.measure.distances(cb.reps[i], index)
        for i in progress(range(len(cb)), desc=desc, total=len(cb), unit="case")
    ]
    return np.asarray(rows)


def _knn_vote(
    dist: np.ndarray, labels: np.ndarray, classes: np.ndarray, k: int, weights: Weights
) -> np.ndarray:
    """Predicted label per row of ``dist`` ``(m, n_cand)`` (inf = not a candidate), by the
    classifier's vote (:func:`cbr.reuse.vote`)."""
    k = min(k, dist.shape[1])
    order = np.argsort(dist, axis=1, kind="stable")[:, :k]
    d = np.take_along_axis(dist, order, axis=1)
    codes = np.searchsorted(classes, labels[order].astype(str))
    return np.asarray(classes[decide(vote(d, codes, len(classes), weights))], dtype=object)


def loo_accuracy(
    dist: np.ndarray, labels: np.ndarray, kept: np.ndarray, k: int, weights: Weights = "distance"
) -> float:
    """Leave-one-out accuracy of every original case against the ``kept`` cases."""
    d = np.where(kept[None, :], dist, np.inf)
    np.fill_diagonal(d, np.inf)
    classes = np.unique(labels.astype(str))
    pred = _knn_vote(d, labels, classes, k, weights)
    return float(np.mean(pred == labels.astype(str)))


def _eval_accuracy(cb: CaseBase, X: np.ndarray, y: np.ndarray, k: int, weights: Weights) -> float:
    from .reuse import reuse

    classes = np.unique(np.concatenate([cb.labels.astype(str), np.asarray(y, dtype=str)]))
    pred = [reuse(retrieve(cb, x, k), classes, weights).label for x in X]
    return float(np.mean(np.asarray(pred) == np.asarray(y, dtype=str)))


def _report(
    method: str,
    cb: CaseBase,
    kept: np.ndarray,
    dist: np.ndarray | None,
    k: int,
    weights: Weights,
    eval_set: tuple[np.ndarray, np.ndarray] | None,
    **extra: object,
) -> MaintenanceReport:
    before_alone = kept
    kept, alone = keep_every_activity(cb, kept, dist)
    groups = twin_groups(cb)
    kept = with_twins(kept, groups)
    with_image = bool(alone) and int((kept & ~before_alone).sum()) > len(alone)
    after = cb.subset(kept)
    if eval_set is not None:
        acc_b = _eval_accuracy(cb, eval_set[0], eval_set[1], k, weights)
        acc_a = _eval_accuracy(after, eval_set[0], eval_set[1], k, weights)
        measured = f"{k}-NN on the {len(eval_set[1])} evaluation clips"
    else:
        if dist is None:
            dist = pairwise_distances(cb)
        overlap = overlapping_pieces(cb)
        twins = mirror_twins(cb)
        apart = np.where(overlap | twins, np.inf, dist)
        acc_b = loo_accuracy(apart, cb.labels, np.ones(len(cb), bool), k, weights)
        acc_a = loo_accuracy(apart, cb.labels, kept, k, weights)
        measured = f"{k}-NN, each of the {len(cb)} cases before left out in turn"
        with_it = [
            *(["its mirror image"] if twins.any() else []),
            *(["the cases overlapping it in its recording"] if overlap.any() else []),
        ]
        if with_it:
            measured += " with " + " and ".join(with_it)
    assert cb.ids is not None
    return MaintenanceReport(
        method,
        len(cb),
        int(kept.sum()),
        acc_b,
        acc_a,
        kept,
        after,
        original_ids=cb.ids.copy(),
        before=cb,
        measured=measured,
        kept_alone=alone,
        kept_alone_with_image=with_image,
        **extra,  # type: ignore[arg-type]
    )


def overlapping_pieces(cb: CaseBase) -> np.ndarray:
    """``(n, n)`` bool: the pairs of cases that are overlapping pieces of one recording (the
    same named source, frame ranges that share a frame; a case whose frames are not known
    overlaps none, nor do the cases of a source two of which have the same frames: whole
    clips that share a name, all from frame 0). Windows cut every 0.5 s are near copies of
    their neighbours: left out alone, a window is answered by them and every answer is
    right."""
    frames = frame_array(cb.frames)
    names = np.array([str(x) for x in cb.sources], dtype=object)
    known = (frames[:, 0] >= 0) & ~np.isin(names, ["", "None"])
    for name in set(names.tolist()):
        group = names == name
        if len({tuple(f) for f in frames[group].tolist()}) < int(group.sum()):
            known &= ~group  # not pieces of it
    _, source = np.unique(names, return_inverse=True)
    same = source[:, None] == source[None, :]
    meet = (frames[:, None, 0] < frames[None, :, 1]) & (frames[None, :, 0] < frames[:, None, 1])
    out: np.ndarray = same & meet & known[:, None] & known[None, :]
    np.fill_diagonal(out, False)
    return out


def mirror_twins(cb: CaseBase) -> np.ndarray:
    """``(n, n)`` bool: the pairs of cases that are a clip and its mirror image (``--mirror
    augment``; the image's source is the clip's with :data:`features.body.MIRRORED` added, its
    frames the clip's). Left out alone, a case is answered by its own mirror image, the same
    movement on the other side: near, and always of its activity. Two clips of one name and
    the same frames (whole clips from two folders, say) pair with each other's image too:
    held out the more, never the less."""
    names = [str(x) for x in cb.sources]
    image = np.array([n.endswith(MIRRORED) for n in names])
    if not image.any() or image.all():
        return np.zeros((len(cb), len(cb)), dtype=bool)
    key = np.array(
        [repr((n.removesuffix(MIRRORED), tuple(f))) for n, f in zip(names, cb.frames, strict=True)],
        dtype=object,
    )
    return np.asarray((key[:, None] == key[None, :]) & (image[:, None] != image[None, :]))


def twin_groups(cb: CaseBase, twins: np.ndarray | None = None) -> np.ndarray:
    """``(n,)`` group numbers: a case and its mirror image (:func:`mirror_twins`) of the same
    activity share one, which the editors keep or drop together; a case without an image (a
    case added by feedback, or whose image was relabelled) is a group of its own."""
    if twins is None:
        twins = mirror_twins(cb)
    labels = cb.labels.astype(str)
    pairs = twins & (labels[:, None] == labels[None, :])
    if not pairs.any():
        return np.arange(len(cb))
    # imported here: classifying imports this module but edits no case base
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    _, groups = connected_components(csr_matrix(pairs), directed=False)
    return np.asarray(groups)


def with_twins(kept: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """``kept`` with every case of a group one of whose cases it keeps."""
    return np.asarray(np.isin(groups, groups[kept]))


def _apart(cb: CaseBase, dist: np.ndarray) -> np.ndarray:
    """``dist`` with each case's mirror image out of its reach (inf): the editors judge a case
    by the other clips, not by its own image."""
    twins = mirror_twins(cb)
    return np.where(twins, np.inf, dist) if twins.any() else dist


def _editing(cb: CaseBase, method: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What an editor (CNN, RENN, ICF) works on, for a case base not empty: the distances
    between all cases ``(n, n)``, the same with each case's mirror image out of reach
    (:func:`_apart`), the twin groups ``(n,)`` and the labels as text ``(n,)``."""
    cb.check_not_empty()
    dist = pairwise_distances(cb, desc=method)
    return dist, _apart(cb, dist), twin_groups(cb), cb.labels.astype(str)


def keep_every_activity(
    cb: CaseBase, kept: np.ndarray, dist: np.ndarray | None
) -> tuple[np.ndarray, tuple[str, ...]]:
    """``kept`` with one case of every activity it lost whole (RENN and ICF drop a case its
    neighbours misclassify, so an activity of one case, or of a few among others, goes
    entirely, and the case base could no longer answer it): its medoid, the case with the
    least summed distance to its activity's others. The activities so kept, in order."""
    labels = cb.labels.astype(str)
    lost = [a for a in np.unique(labels) if not kept[labels == a].any()]
    if not lost:
        return kept, ()
    if dist is None:
        dist = pairwise_distances(cb)
    kept = kept.copy()
    for a in lost:
        idx = np.flatnonzero(labels == a)
        kept[idx[int(np.argmin(dist[np.ix_(idx, idx)].sum(axis=1)))]] = True
    return kept, tuple(str(a) for a in lost)


def distribution_shift(cb: CaseBase, kept: np.ndarray) -> float:
    """Largest per-activity shift of the mean problem, in units of the pooled per-feature
    standard deviation (RMS over features): 0 = same distribution centre."""
    flat = cb.problems.reshape(len(cb), -1)
    sd = flat.std(axis=0) + 1e-9
    worst = 0.0
    for lab in np.unique(cb.labels.astype(str)):
        m = cb.labels == lab
        if not (m & kept).any():
            return float("inf")
        shift = (flat[m].mean(axis=0) - flat[m & kept].mean(axis=0)) / sd
        worst = max(worst, float(np.sqrt(np.mean(shift**2))))
    return worst


def novelty_benefit(
    cb: CaseBase, k: int, dist: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Per-case novelty and benefit, ``(n,)`` each (see the module docstring)."""
    n = len(cb)
    labels = cb.labels.astype(str)
    if dist is None:
        dist = pairwise_distances(cb, desc="novelty/benefit")
    d = np.array(_apart(cb, dist))
    np.fill_diagonal(d, np.inf)
    same = labels[:, None] == labels[None, :]
    nearest_same = np.where(same, d, np.inf).min(axis=1)
    novelty = np.zeros(n)
    for lab in np.unique(labels):
        m = labels == lab
        vals = nearest_same[m]
        finite = vals[np.isfinite(vals)]
        med = float(np.median(finite)) if len(finite) else 1.0
        novelty[m] = np.where(np.isfinite(vals), vals / (med if med > 0 else 1.0), 1e6)
    kk = min(k, n - 1)
    nbrs = np.argsort(d, axis=1, kind="stable")[:, :kk]  # (n, kk): j's neighbours
    reach = np.isfinite(np.take_along_axis(d, nbrs, axis=1))  # not the case's own image
    helps = same[np.arange(n)[:, None], nbrs]  # neighbour shares j's label
    coverage = np.bincount(nbrs[helps & reach], minlength=n)
    liability = np.bincount(nbrs[~helps & reach], minlength=n)
    return novelty, (coverage - liability).astype(np.float64)


def trim_novelty_benefit(
    cb: CaseBase,
    keep: float,
    k: int = 5,
    weights: Weights = "distance",
    eval_set: tuple[np.ndarray, np.ndarray] | None = None,
) -> MaintenanceReport:
    """Keep ``keep`` (a fraction) of every activity's cases, dropping the least novel and
    least beneficial first; a case and its mirror image are one unit, ranked by their mean
    rank, and ``keep`` is of the activity's units."""
    from scipy.stats import rankdata  # imported here, as twin_groups imports SciPy's graphs

    cb.check_not_empty()
    dist = pairwise_distances(cb, desc="trim")
    nov, ben = novelty_benefit(cb, k, dist)
    labels = cb.labels.astype(str)
    groups = twin_groups(cb)
    kept = np.zeros(len(cb), dtype=bool)
    for lab in np.unique(labels):
        idx = np.flatnonzero(labels == lab)
        # equal values (benefit is a count: often equal) share their mean rank, so a case's
        # place in the case base does not decide which of them goes
        rank = rankdata(nov[idx]) + rankdata(ben[idx])
        units, first, unit_of = np.unique(groups[idx], return_index=True, return_inverse=True)
        score = np.bincount(unit_of, rank) / np.bincount(unit_of)  # a pair: its mean rank
        n_keep = max(1, int(np.ceil(keep * len(units))))
        order = np.lexsort((idx[first], -score))  # highest rank first; ties: lower index
        kept[idx[np.isin(unit_of, order[:n_keep])]] = True
    return _report(
        "novelty-benefit",
        cb,
        kept,
        dist,
        k,
        weights,
        eval_set,
        novelty=nov,
        benefit=ben,
        distribution_shift=distribution_shift(cb, kept),
    )


def cnn(
    cb: CaseBase,
    k: int = 1,
    weights: Weights = "distance",
    eval_set: tuple[np.ndarray, np.ndarray] | None = None,
) -> MaintenanceReport:
    """Hart's condensed nearest neighbour: a subset that classifies every case right by 1-NN
    (a case is judged without its mirror image, and added with it)."""
    dist, apart, groups, labels = _editing(cb, "CNN")
    kept = np.zeros(len(cb), dtype=bool)
    for lab in np.unique(labels):
        kept[groups == groups[np.flatnonzero(labels == lab)[0]]] = True
    changed = True
    while changed:
        changed = False
        for i in range(len(cb)):  # Hart's algorithm is sequential by definition
            if kept[i]:
                continue
            cand = np.where(kept, apart[i], np.inf)
            if not np.isfinite(cand).any() or labels[int(np.argmin(cand))] != labels[i]:
                kept[groups == groups[i]] = True
                changed = True
    return _report("CNN", cb, kept, dist, k, weights, eval_set)


def _enn_pass(
    dist: np.ndarray, labels: np.ndarray, kept: np.ndarray, k: int, groups: np.ndarray
) -> np.ndarray:
    """Wilson's pass: ``kept`` without the cases their k nearest kept cases misclassify
    (``dist``: each case's mirror image out of reach); a case and its image go only together
    (both misclassified)."""
    d = np.where(kept[None, :], dist, np.inf)
    np.fill_diagonal(d, np.inf)
    classes = np.unique(labels)
    pred = _knn_vote(d, labels, classes, k, "uniform")
    still: np.ndarray = kept & with_twins(kept & (pred == labels), groups)
    return still


def renn(
    cb: CaseBase,
    k: int = 3,
    weights: Weights = "distance",
    eval_set: tuple[np.ndarray, np.ndarray] | None = None,
) -> MaintenanceReport:
    """Repeated edited nearest neighbour: drop cases their k nearest misclassify, until stable."""
    dist, apart, groups, labels = _editing(cb, "RENN")
    kept = np.ones(len(cb), dtype=bool)
    while True:
        new = _enn_pass(apart, labels, kept, k, groups)
        if new.sum() == kept.sum() or new.sum() == 0:
            kept = new if new.sum() else kept
            break
        kept = new
    return _report("RENN", cb, kept, dist, k, weights, eval_set)


def icf(
    cb: CaseBase,
    k: int = 3,
    weights: Weights = "distance",
    eval_set: tuple[np.ndarray, np.ndarray] | None = None,
) -> MaintenanceReport:
    """Iterative case filtering (Brighton & Mellish 2002)."""
    dist, apart, groups, labels = _editing(cb, "ICF")
    kept = _enn_pass(apart, labels, np.ones(len(cb), dtype=bool), k, groups)
    if not kept.any():
        kept = np.ones(len(cb), dtype=bool)
    diff = labels[:, None] != labels[None, :]
    while True:
        d = np.where(kept[None, :] & kept[:, None], apart, np.inf)
        np.fill_diagonal(d, np.inf)
        enemy = np.where(diff, d, np.inf).min(axis=1)  # distance to nearest other-label case
        # local set of c: same-label cases closer than c's nearest enemy
        local = (d < enemy[:, None]) & ~diff  # local[c, j]: j in LocalSet(c)
        coverage = local.sum(axis=0)  # coverage(j) = #cases whose local set holds j
        reachable = local.sum(axis=1)  # reachable(c) = |LocalSet(c)|
        drop = kept & (reachable > coverage)
        drop &= ~with_twins(kept & ~drop, groups)  # a case and its image: both or neither
        if not drop.any():
            break
        kept = kept & ~drop
    return _report("ICF", cb, kept, dist, k, weights, eval_set)


EDITORS: dict[str, Callable[..., MaintenanceReport]] = {
    "novelty-benefit": trim_novelty_benefit,
    "cnn": cnn,
    "renn": renn,
    "icf": icf,
}


def record_trim(
    tx: StoreTransaction,
    info: CaseBaseInfo,
    report: MaintenanceReport,
    ids: np.ndarray | None = None,
) -> None:
    """Inside ``tx``: deactivate the cases ``report`` dropped (``ids``: their store ids,
    default ``report.original_ids``) and log each with its novelty, benefit and reason."""
    full_ids = ids if ids is not None else report.original_ids
    assert full_ids is not None
    dropped = np.flatnonzero(~report.kept)
    tx.deactivate_cases(info, (int(full_ids[i]) for i in dropped if full_ids[i] >= 0))
    for i in dropped:
        tx.log(
            info,
            "trim",
            case_id=int(full_ids[i]) if full_ids[i] >= 0 else None,
            novelty=None if report.novelty is None else float(report.novelty[i]),
            benefit=None if report.benefit is None else float(report.benefit[i]),
            reason=f"{report.method}{DROPPED}",
        )
    tx.log(info, "trim", reason=report.summary())
