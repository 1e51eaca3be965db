"""Cross-validation folds of a comparison: leave one subject out, or stratified k-fold when
asked for or when subjects cannot be left out."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

import numpy as np

from features.clips import FRAME_COLUMNS, ListedClip
from features.errors import ConfigError, DataError
from features.targets import clip_target_of, column_of
from features.text import counted

from .data import SINGLE, Prepared, model_groups, no_target_error, too_few_classes
from .settings import CompareSettings

_OPTIMISTIC = "(optimistic: {} in training and test)"


def loso_impossible(subjects: Sequence[str | None]) -> str | None:
    """Why leave-one-subject-out is impossible for clips of these subjects ("only one
    subject (s01)", "18 clips have no subject"; None if it is possible)."""
    unknown = sum(s is None for s in subjects)
    distinct = sorted({s for s in subjects if s is not None})
    if unknown:
        return f"{counted(unknown, 'clip')} {'has' if unknown == 1 else 'have'} no subject"
    if len(distinct) < 2:
        return f"only one subject ({distinct[0]})" if distinct else "no clip"
    return None


def loso_refusal(
    subjects: Sequence[str | None],
    source: str,
    left_out: Sequence[tuple[str, str | None, str]] = (),
) -> ConfigError | None:
    """The refusal of leave-one-subject-out asked for by name (``cv="loso"``) on clips of
    these ``subjects`` (None when it is possible): k-fold over clips, the fallback, would give
    figures of the same person in training and test. ``left_out``: the clips the comparison
    left out (name, subject, why: :attr:`cbr.evaluation.data.Prepared.left_out`); those of
    the subjects no clip is left of are named, with why, under each reason."""
    why = loso_impossible(subjects)
    if why is None:
        return None
    left = {s for s in subjects if s is not None}
    gone = [(name, s, reason) for name, s, reason in left_out if s is not None and s not in left]
    if gone:
        others = sorted({s for _, s, _ in gone})
        by_why: dict[str, list[str]] = {}
        for name, _, reason in gone:
            by_why.setdefault(reason, []).append(name)
        said = "; ".join(
            f"{reason}: {', '.join(names[:5])}{' ...' if len(names) > 5 else ''}"
            for reason, names in by_why.items()
        )
        why += (
            f", once every clip of the {counted(len(others), 'other subject')}"
            f" ({', '.join(others)}) is left out ({said})"
        )
    return ConfigError(
        f"leave-one-subject-out is impossible in {source}: {why}; `cv='kfold'` cross-validates"
        " over clips (the same person can be in training and test)",
        "cv",
    )


def _loso_fallback(subjects: list[str | None], k: int) -> str | None:
    """Why leave-one-subject-out is impossible for these clips, and the fallback (None if it
    is possible)."""
    why = loso_impossible(subjects)
    if why is None:
        return None
    person = "a person can be" if any(s is None for s in subjects) else "the same person is"
    return (
        f"{why}, so leave-one-subject-out is impossible; falling back to stratified {k}-fold"
        f" cross-validation over clips {_OPTIMISTIC.format(person)}"
    )


def _by_subject(subjects: list[str | None]) -> np.ndarray:
    """Fold of every clip ``(n,)``: the index of its subject in sorted order."""
    index = {s: i for i, s in enumerate(sorted({str(s) for s in subjects}))}
    return np.array([index[str(s)] for s in subjects], dtype=np.int64)


def _stratified(
    y: np.ndarray, within: np.ndarray | None, k: int, seed: int
) -> tuple[np.ndarray, list[str]]:
    """Fold of every clip ``(n,)`` by shuffled stratified k-fold (strata: target ``y`` within
    group ``within``, both ``(n,)``), with fewer folds, and a note, when the smallest stratum
    is smaller than ``k``."""
    from sklearn.model_selection import StratifiedKFold

    strat = y if within is None else np.array([f"{w}|{v}" for w, v in zip(within, y, strict=True)])
    smallest = min(Counter(strat).values())
    notes = []
    if smallest < k:
        if smallest < 2:
            raise DataError(
                "a class has a single clip in some group; stratified k-fold (`cv='kfold'`) is"
                " impossible",
                "cv",
            )
        notes.append(f"the smallest class has {smallest} clips: using {smallest} folds, not {k}")
        k = smallest
    fold = np.zeros(len(y), dtype=np.int64)
    skf = StratifiedKFold(n_splits=k, shuffle=True, random_state=seed)
    for i, (_, test) in enumerate(skf.split(np.zeros((len(strat), 1)), strat)):
        fold[test] = i
    return fold, notes


def make_folds(
    data: Prepared, settings: CompareSettings, source: str = "dataset"
) -> tuple[str, np.ndarray, list[str]]:
    """The scheme actually used, the fold number of every clip ``(n,)``, and notes.

    LOSO: one fold per subject. Stratified k-fold (shuffled, seeded) is used when asked for, or
    as the fallback when LOSO is impossible (a clip without subject, or a single subject) and
    not asked for by name (``cv=None``); asked for by name, that is refused
    (:func:`loso_refusal`, naming ``source`` and the clips left out of the subjects gone).
    """
    return fold_numbers(data.y, data.subjects, data.within, settings, source, data.left_out)


def fold_numbers(
    y: np.ndarray,
    subjects: Sequence[str | None],
    within: np.ndarray | None,
    settings: CompareSettings,
    source: str = "dataset",
    left_out: Sequence[tuple[str, str | None, str]] = (),
) -> tuple[str, np.ndarray, list[str]]:
    """:func:`make_folds` of clips of targets ``y``, subjects and model groups ``within``
    (each ``(n,)``): what the folds depend on, known before the clips are read; ``left_out``
    the clips left out of them (:func:`loso_refusal`)."""
    notes: list[str] = []
    if settings.cv == "loso":
        refused = loso_refusal(subjects, source, left_out)
        if refused is not None:
            raise refused
    if settings.cv != "kfold":
        why = _loso_fallback(list(subjects), int(settings.folds))
        if why is None:
            return "loso", _by_subject(list(subjects)), notes
        notes.append(why)
    fold, k_notes = _stratified(y, within, int(settings.folds), int(settings.seed))
    return "kfold", fold, notes + k_notes


def unseen_class_notes(data: Prepared, folds: np.ndarray) -> list[str]:
    """For leave-one-subject-out: the classes only the held-out subject has, per fold."""
    notes = []
    for f in sorted(set(folds.tolist())):
        test = folds == f
        unseen = sorted(set(data.y[test]) - set(data.y[~test]))
        if unseen:
            notes.append(
                f"subject {data.subjects[int(np.flatnonzero(test)[0])]}: class(es) "
                f"{', '.join(unseen)} occur in no other subject, so they cannot be "
                "predicted when that subject is held out"
            )
    return notes


def check_k(settings: CompareSettings, folds: np.ndarray) -> None:
    """Refuse a ``k`` larger than a fold's training clips: the vote would take every case
    there is, and the accuracy change with the fold's size, not with ``k``."""
    _, held = np.unique(folds, return_counts=True)
    fewest = int(len(folds) - held.max())
    if int(settings.k) > fewest:
        raise ConfigError(
            f"must be at most {fewest}, the training clips of the smallest fold, got "
            f"{settings.k} (5 unless given): give `k={fewest}` or less",
            "k",
        )


def check_within(within: np.ndarray | None, folds: np.ndarray, column: str | None) -> None:
    """Refuse model groups (``within`` ``(n,)``, the values of ``column``) each inside one
    of the ``folds`` ``(n,)``: when a group's clips are held out, no clip of it is left to
    train its model on (``within="subject"`` under leave-one-subject-out), and every figure
    would count a fixed fallback answer."""
    if within is None:
        return
    trained = any(
        bool(np.any((folds != f) & (within == g)))
        for f, g in set(zip(folds.tolist(), within, strict=True))
    )
    if not trained:
        raise ConfigError(
            f"every {column!r} value's clips lie in one fold, so no model per value is ever"
            " trained on any clip (each is tested when its fold is held out); use"
            " `cv='kfold'` or another `within`",
            "within",
        )


def check_listed(listed: Sequence[ListedClip], settings: CompareSettings, source: str) -> bool:
    """Refuse, from the clips as their dataset lists them (:class:`ListedClip`, nothing decoded),
    what :func:`cbr.evaluation.compare.run_compare` would refuse once every clip is read, in its
    words: a target no clip has a value of (nor can be given by reading it: :func:`_may_add`),
    fewer than two classes of two clips, a ``k`` above the training clips of the smallest fold.
    The clips a read leaves out (no person shown, too short) only make classes smaller, but may
    leave more folds (a class of two then gone no longer caps them): ``k`` is refused here only
    above what a fold of the clips read could train on (:func:`_most_trained`); and may take a
    group's class of a single clip away with its clip, so k-fold's refusal of one is left to the
    read. Refused here too: leave-one-subject-out asked for by name (``cv="loso"``) when the
    classes of a single clip listed leave one subject (:func:`loso_refusal`), and under it
    model groups (``within``) each inside one subject's clips (:func:`check_within`):
    whichever clips the read leaves out, each group stays inside its subject, or one subject
    is left, refused. Not asked for by name, a read that leaves one subject falls back to
    k-fold, which trains every group: that refusal is left to the read. A refusal here is one
    the read clips get, the counts it names those of the clips listed. Returns whether the
    listing told all it checks (False: a clip's target or group only a read can tell, or a
    group's class of a single clip)."""
    if not listed:
        return True
    target = settings.target
    values = [clip_target_of(c.label, c.subject, c.extras, target) for c in listed]
    if all(v is None for v in values):
        if not any(_may_add(c, target) for c in listed):
            columns = {k for c in listed for k in (*c.extras, *(c.adds or ()))}
            n = len(listed)
            raise no_target_error(n, n, listed[0].name, columns, target, source)
        return False
    if any(v is None for v in values):
        return False  # which of them a read leaves out, or gives a value, only reading tells
    y = np.array(values, dtype=object)
    column = settings.within_column
    within = None
    if column is not None:
        groups = [column_of(c.label, c.subject, c.extras, column) for c in listed]
        if any(g is None for g in groups):
            return False
        within = model_groups(groups, column, source)
    return _check_folds(listed, y, within, settings, source)


def _check_folds(
    listed: Sequence[ListedClip],
    y: np.ndarray,
    within: np.ndarray | None,
    settings: CompareSettings,
    source: str,
) -> bool:
    """:func:`check_listed` of the classes and folds of the clips ``listed``, of targets
    ``y`` and model groups ``within`` (each ``(n,)``)."""
    counts = Counter(y.tolist())
    refused = too_few_classes(settings.target, counts, source)
    if refused is not None:
        raise refused
    kept = np.array([counts[v] >= 2 for v in y])
    subjects = [c.subject for c, keep in zip(listed, kept, strict=True) if keep]
    groups_kept = None if within is None else within[kept]
    alone = [(c.name, c.subject, SINGLE) for c, keep in zip(listed, kept, strict=True) if not keep]
    try:
        scheme, folds, _ = fold_numbers(y[kept], subjects, groups_kept, settings, source, alone)
    except DataError:  # k-fold over a group's class of a single clip listed: the read may
        return False  # leave that clip out (no person shown, too short), and the class with it
    if int(settings.k) > _most_trained(scheme, folds, int(settings.folds)):
        check_k(settings, folds)
    if settings.cv == "loso":
        check_within(groups_kept, folds, settings.within_column)
    return True


def _may_add(clip: ListedClip, column: str) -> bool:
    """Whether reading ``clip`` may give it a value of ``column`` (named in any case) that its
    listing does not: a column its reader adds (:attr:`ListedClip.adds`; any when only reading
    it tells) or finds in its frames (:data:`features.clips.FRAME_COLUMNS`)."""
    if clip.adds is None:
        return True
    low = column.strip().lower()
    return any(k.strip().lower() == low for k in (*clip.adds, *FRAME_COLUMNS))


def _most_trained(scheme: str, folds: np.ndarray, k_folds: int) -> int:
    """The most training clips the smallest fold can have once the clips listed in ``folds``
    (a fold each, by ``scheme``) are read, whichever of them the read leaves out: ``n`` clips
    in ``f`` folds leave at most ``n - ceil(n / f)`` to train on, ``n`` and ``f`` at most the
    listing's (``k_folds`` folds of k-fold; under leave-one-subject-out its subjects, or the
    k-fold that one subject left falls back to)."""

    def most(n: int, f: int) -> int:
        return n - -(-n // f)

    n = len(folds)
    if scheme != "loso":
        return most(n, k_folds)
    held = np.unique(folds, return_counts=True)[1]
    return max(most(n, len(held)), most(int(held.max()), k_folds))
