"""Training a stored case base from labelled clips (the work behind ``posecbr train``).

The classifier is fitted exactly as ``CaseBaseClassifier.fit`` fits it in Python (it is the same
call), then stored whole (:mod:`cbr.stored`) in ONE transaction: an interrupted or failed train
leaves the store as it was, and a store file that did not exist before appears only complete
(:func:`casebase_store.write_store`).
Appending adds cases to a stored case base without learning anything anew; several processes
may append to one case base at once.

Each clip is reduced to what the fit needs as it is read (:mod:`cbr.described`), one clip in
memory at a time: :func:`describe_entries` reads the clips of a dataset in this process or,
with a ``scheduler``, on a Dask cluster (one task per clip), and the same records reach the
same fit either way.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from casebase_store import (
    CaseBaseInfo,
    Seen,
    SourcedCase,
    StoreError,
    check_case_base_name,
    check_url_or_path,
)
from features.cluster import connect, gather, map_outcomes
from features.datasets import DatasetEntry
from features.errors import ConfigError, DataError, InputError, PosecbrError
from features.interrupts import stored_before
from features.poses import PoseSequence
from features.progress import progress
from features.targets import clip_target
from features.text import counted, did_you_mean, spelt_as

from .casebase import CaseBase, piece_name, subject_of
from .described import DescribedClip, describe_case, describe_clip
from .estimator import CaseBaseClassifier, as_sequences, check_labels, check_two_activities
from .estimator_protocol import check_fitted, unfitted_copy
from .judges import JUDGES
from .maintenance import MaintenanceReport, record_trim
from .problem import FeatureConfig
from .stored import (
    calibrate_stored_judges,
    case_records,
    judges_after_change,
    load_classifier,
    model_document,
    write_matrices,
)
from .stored import stored_case_base as to_store
from .words import CASE_KINDS

if TYPE_CHECKING:
    from casebase_store import StoreTransaction


@dataclass(frozen=True)
class TrainResult:
    """What ``train`` stored: ``n_cases`` cases (``n_active`` after editing), how many of
    those active cases of each label (mirror images and windows counted as the cases they
    are), the clips skipped because they show no person or are too short, and what fit
    learned."""

    name: str
    n_cases: int
    n_active: int
    label_counts: dict[str, int]
    config: FeatureConfig
    #: the similarity measure as stored with the case base (:meth:`SimilarityMeasure.params`)
    similarity: dict[str, Any]
    maintenance: MaintenanceReport | None
    learned: dict[str, Any]
    skipped: list[str] = field(default_factory=list)
    #: the clips skipped because they last less than one movement can, with their lengths
    too_short: list[str] = field(default_factory=list)
    #: whether the default judge of unknown (``segment``, ``watch``) could be calibrated on it
    judges_unknown: bool = True
    #: cases whose features equal a case's of another activity (:func:`same_features`)
    indistinct: list[str] = field(default_factory=list)
    #: ``--append``: the activities added that the case base did not hold as they were added
    new_labels: list[str] = field(default_factory=list)
    #: those of ``new_labels`` that are the file name of one of their clips (a pose file
    #: converted alone is labelled so: a name, not an activity, likely)
    file_named_labels: list[str] = field(default_factory=list)
    #: how many training clips (or pieces) of each label were fitted: the ones held out to
    #: calibrate the confidence, before any editing or mirroring (empty for ``--append``)
    trained_counts: dict[str, int] = field(default_factory=dict)
    #: the labels given whose every clip was skipped (:func:`usable`): no case holds them
    lost_labels: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Plan:
    """What each training clip is reduced to: for a new fit, the estimator's
    :meth:`~cbr.estimator.CaseBaseClassifier.describe_plan` (``candidates``, ``mirror``,
    ``sides``); for ``--append``, the stored case base's columns (``casebase``, no cases)."""

    candidates: FeatureConfig | None = None
    mirror: bool = False
    sides: bool = False
    casebase: CaseBase | None = None


def fit_plan(estimator: CaseBaseClassifier) -> Plan:
    """The plan of a new fit with ``estimator`` (bad parameters refused before any clip)."""
    candidates, mirror, sides = estimator.describe_plan()
    return Plan(candidates, mirror, sides)


def describe(seq: PoseSequence, plan: Plan) -> DescribedClip:
    """One clip reduced by ``plan`` (:func:`cbr.described.describe_clip` or
    :func:`cbr.described.describe_case`)."""
    if plan.casebase is not None:
        return describe_case(seq, plan.casebase)
    assert plan.candidates is not None
    return describe_clip(seq, plan.candidates, plan.mirror, plan.sides)


def no_target_value(clip: Any, target: str) -> DataError:
    """The error for a clip without a value of the ``target`` column: the columns it has a
    value of, and the one meant when ``target`` is a mistyped one of them. A clip without a
    label (a pose file ``extract`` made of one video, given alone) is told where a label
    comes from, not offered the column it lacks."""
    if target == "label":
        return DataError(
            "no label: its metadata has none (give it in a labels CSV, path,label, or put"
            " the file in a folder named after its activity)",
            clip.seq.source,
        )
    columns = [
        *(c for c, v in (("label", clip.label), ("subject", clip.subject)) if v),
        *sorted(clip.extras),
    ]
    return DataError(
        f"no value for `target` {target!r} (columns: {', '.join(columns) or 'none'})"
        + did_you_mean(target, [c for c in columns if c != target]),
        clip.seq.source,
    )


def describe_entry(entry: DatasetEntry, plan: Plan, target: str) -> list[tuple[DescribedClip, str]]:
    """The work unit of ``train``: read one file of a dataset (decode, and pose estimation for
    a video), reduce each of its clips by ``plan`` (usually one; one per labelled stretch of a
    recording labelled over time; none when the filters leave it out), each with its value of
    ``target``. Runs in this process or on a cluster's worker."""
    out = []
    for clip in entry.read():
        value = clip_target(clip, target)
        if value is None:
            raise no_target_value(clip, target)
        _check_stored_text(clip.seq, value, target)
        out.append((describe(clip.seq, plan), value))
    return out


def _check_stored_text(seq: PoseSequence, value: str, target: str) -> None:
    """Refuse a clip whose subject or ``target`` value (a pose file's metadata) holds a NUL,
    which no case base can store, as it is read: not after every clip and the fit."""
    for what, text in (("subject", subject_of(seq)), (target, value)):
        if text is not None and "\x00" in str(text):
            raise DataError(
                f"{what} {str(text)!r} contains a NUL character (a case base cannot store it)",
                seq.source,
            )


def describe_entries(
    entries: Sequence[DatasetEntry], plan: Plan, target: str, scheduler: str | None = None
) -> tuple[list[DescribedClip], list[str]]:
    """Every entry through :func:`describe_entry`, in entry order: clip after clip in this
    process (one clip in memory at a time; the first bad clip stops it), or on the Dask
    cluster ``scheduler`` names (:mod:`features.cluster`: every clip runs, and the failed ones
    are reported together, each by name). Either way the same records, in the same order."""
    if scheduler is None:
        units = (
            describe_entry(e, plan, target)
            for e in progress(entries, desc="features", total=len(entries), unit="clip")
        )
        kept = [d for unit in units for d in unit]
    else:
        with connect(scheduler) as client:
            outcomes = map_outcomes(client, describe_entry, entries, [e.name for e in entries],
                                    plan, target, desc="features", unit="clip")  # fmt: skip
            values, failed = gather(outcomes, len(entries))
        if failed:
            raise ClipsFailed([f"{o.name}: {o.error}" for o in failed])
        kept = [d for unit in values for d in unit or []]
    return [d for d, _ in kept], [t for _, t in kept]


class ClipsFailed(DataError):
    """Clips that could not be read or described on a cluster: one line each in ``lines``;
    nothing was written."""

    def __init__(self, lines: list[str]) -> None:
        self.lines = lines
        super().__init__(
            f"{counted(len(lines), 'clip')} failed (listed above); nothing was written"
        )


def _unusable_why(clips: Sequence[DescribedClip]) -> str:
    """Why none of ``clips`` can be a case (:func:`usable`), in the words of ``train``'s
    "skipped" lines: no frame shows the person's torso, or it lasts less than one movement
    can (a piece of ``--split repetitions`` or ``windows``, a clip shorter than a window kept
    whole), or some one and some the other."""
    from features.repetitions import MIN_PERIOD_S

    nobody = {c.torso_share == 0.0 for c in clips}
    no_torso = "shows no person's torso (both shoulders and hips)"
    short = f"is shorter than one movement can be ({MIN_PERIOD_S:g} s)"
    if nobody == {True}:
        return no_torso
    if nobody == {False}:
        return short
    return f"{no_torso} or {short}"


def _no_case(clips: Sequence[DescribedClip], what: str) -> DataError:
    """No clip can be a case (:func:`usable`): ``what`` there is then nothing to do; the error
    says why (:func:`_unusable_why`)."""
    return DataError(f"every clip {_unusable_why(clips)}: nothing to {what}", "training set")


def _one_left(
    clips: Sequence[DescribedClip], labels: Sequence[str], keep: Sequence[int], target: str
) -> DataError:
    """Of two or more activities (``labels`` of ``clips``), only one is left in the clips
    :func:`usable` keeps (positions ``keep``): the error names the others, why their clips
    are no case (:func:`_unusable_why`) and the clips."""
    from .explain import class_noun

    left = labels[keep[0]]
    lost = sorted(set(labels) - {left})
    gone = [i for i, label in enumerate(labels) if label in lost]
    dropped = list(  # each file once: a recording cut into windows is many clips
        dict.fromkeys(clips[i].source or f"clip {i}" for i in gone)
    )
    more = " ..." if len(dropped) > 5 else ""
    return DataError(
        f"only one {class_noun(target)} ({left!r}) is left to learn from, a classifier needs "
        f"two or more: every clip of {', '.join(repr(v) for v in lost)} "
        f"{_unusable_why([clips[i] for i in gone])}: {', '.join(dropped[:5])}{more}",
        "training set",
    )


def usable(clips: Sequence[DescribedClip]) -> tuple[list[int], list[str], list[str]]:
    """Positions of the clips that can be learned from, the names of those in which no frame
    shows the person's torso, and of those that last less than one movement can
    (:data:`features.repetitions.MIN_PERIOD_S`, each named with its length: ``classify``
    calls such a clip unclassifiable, so it is no case either)."""
    from features.repetitions import MIN_PERIOD_S

    nobody: dict[int, str] = {}
    short: dict[int, str] = {}
    for i, c in enumerate(clips):
        name = c.source or f"clip {i}"
        if c.torso_share == 0.0:
            nobody[i] = name
        elif c.duration_s < MIN_PERIOD_S:
            short[i] = f"{name} (lasts {c.duration_s:.2f} s)"
    keep = [i for i in range(len(clips)) if i not in nobody and i not in short]
    return keep, list(nobody.values()), list(short.values())


def lost_labels(labels: Sequence[str], keep: Sequence[int]) -> list[str]:
    """The ``labels`` (one per clip) none of whose clips is among those kept (``keep``,
    :func:`usable`): every clip of them shows no person or is too short, and no case will
    hold them."""
    return sorted(set(labels) - {labels[i] for i in keep})


def _learned(clf: CaseBaseClassifier) -> dict[str, Any]:
    return {
        "side": clf.side_,
        "feature_weights": clf.weighting_,
        "phases": clf.phases_,
        "mirror_cases": clf.mirror_cases_,
        "inner_loso_accuracy": dict(clf.selection_),
        "unlike_cases": clf.novelty_.describe(),
        # 0: no training clip could be classified held out, the confidence is the vote share
        "confidence_calibrated_on": int(clf.confidence_.n),
        # the share of those clips answered right (None when none could be held out)
        "held_out_accuracy": float(clf.confidence_.accuracy) if clf.confidence_.n else None,
        # the mean of each class's share answered right (the vote is class-balanced: always
        # answering one class scores one over the classes)
        "held_out_balanced_accuracy": (
            float(clf.confidence_.balanced_accuracy)
            if clf.confidence_.n and np.isfinite(clf.confidence_.balanced_accuracy)
            else None
        ),
    }


def _counts(labels: Sequence[str]) -> dict[str, int]:
    values, counts = np.unique(np.asarray(labels, dtype=str), return_counts=True)
    return {str(v): int(c) for v, c in zip(values, counts, strict=True)}


def _check_name(name: Any) -> None:
    """Refuse a case base name that is not text, empty, or one no store can hold (too long,
    a NUL), before any clip is read: an :class:`InputError` naming the argument ``name``, as
    the other arguments' (it named the command's option, "--name: the case base name is
    empty"; ``posecbr train`` checks ``--name`` itself)."""
    if not isinstance(name, str):
        raise InputError(f"the case base name must be text, got {name!r}", "name")
    if not name.strip():
        raise InputError("the case base name is empty", "name")
    try:
        check_case_base_name(name, "name")
    except StoreError as exc:
        raise InputError(exc.message, "name") from None


def _check_what(estimator: Any, target: Any, cases: Any) -> None:
    """Refuse, before any clip is read, an ``estimator`` that is no CaseBaseClassifier (the
    class itself, not one made of it, or None), a ``target`` that is no column's name and a
    ``cases`` that is none of :data:`cbr.words.CASE_KINDS`: stored as given, every later
    summary of the case base would call its cases by it ("18 held-out frames")."""
    if not isinstance(estimator, CaseBaseClassifier):
        got = (
            "the class itself: give one, CaseBaseClassifier()"
            if estimator is CaseBaseClassifier
            else type(estimator).__name__
        )
        raise InputError(f"a CaseBaseClassifier is expected, got {got}", "estimator")
    if not isinstance(target, str) or not target.strip():
        raise InputError(f"must be the name of a column, got {target!r}", "target")
    if not isinstance(cases, str) or cases not in CASE_KINDS:
        raise InputError(
            f"must be one of {', '.join(map(repr, CASE_KINDS))}, got {cases!r}", "cases"
        )


def train(
    db: str | Path,
    name: str,
    clips: Iterable[PoseSequence],
    labels: Sequence[Any] | np.ndarray,
    estimator: CaseBaseClassifier,
    *,
    target: str = "label",
    cases: str = "clips",
    replace: bool = False,
) -> TrainResult:
    """Fit ``estimator`` on the usable ``clips`` and store it as case base ``name`` in ``db``
    (a SQLite file or SQLAlchemy URL), recording what each clip is (``cases``: ``"clips"``,
    ``"repetitions"`` or ``"windows"``, as ``train --split`` cut them) and what its label is
    (``target``: the column's name, as ``train --target``). Clips that show no person, or
    last less than one movement can (which ``fit`` refuses), are skipped and named.
    ``clips`` that are not PoseSequences, an ``estimator`` that is not a
    :class:`~cbr.estimator.CaseBaseClassifier`, a ``cases`` or ``target`` of another kind,
    ``labels`` missing one or of one activity only: :class:`features.errors.InputError`,
    before any clip is read. ``cases`` records what
    the clips are, it cuts nothing: :func:`cut` and :func:`cut_recording` cut them as
    ``train --split`` does (windows for ``segment`` and ``watch``)."""
    check_url_or_path(db, "db")  # None made a case base file "None", after the fit
    _check_name(name)
    clips = as_sequences(clips, "clips")
    text = check_labels(labels, len(clips), "labels")
    _check_what(estimator, target, cases)
    check_two_activities(text, "labels")  # as the fit would, before any clip is described
    plan = fit_plan(estimator)
    described = [
        describe(s, plan) for s in progress(clips, desc="features", total=len(clips), unit="clip")
    ]
    return train_described(
        db, name, described, labels, estimator, target=target, cases=cases, replace=replace
    )


def _check_split(split: Any) -> str:
    """``split`` one of :data:`features.repetitions.SPLITS`, else an InputError naming it."""
    from features.repetitions import SPLITS

    if not isinstance(split, str) or split not in SPLITS:
        raise InputError(f"must be one of {', '.join(map(repr, SPLITS))}, got {split!r}", "split")
    return split


def cut(
    clips: Iterable[PoseSequence], labels: Sequence[Any] | np.ndarray | None, split: str
) -> tuple[list[PoseSequence], list[Any]]:
    """``clips`` cut into the cases ``posecbr train --split`` makes of them (the same
    :func:`features.repetitions.cut_clips`), each piece with its clip's label as given:
    ``split="windows"``, the 2-s windows every 0.5 s that ``segment`` and ``watch`` classify
    (the case base for long recordings and live use; a clip shorter than a window stays
    whole), ``"repetitions"``, each repetition found (of a movement that alternates sides in turns
    shorter than one repetition can be, a jog, each left-and-right cycle,
    :func:`features.repetitions.case_spans`; a clip with none stays whole), or
    ``"clips"``, each whole. Each piece is a :class:`PoseSequence` sharing its clip's frames,
    its ``frames`` where it lies in the clip. ``labels`` None: clips not labelled (a new
    session, to classify and explain repetition by repetition, as ``classify --split
    repetitions`` does), each piece's label None. Give the result to :func:`train` with
    ``cases=split`` (for windows with ``CaseBaseClassifier(feature_weights="none")``, as
    ``train --split windows``). Bad ``clips``, ``labels`` or ``split``:
    :class:`features.errors.InputError` naming the argument."""
    from features.clips import Clip
    from features.repetitions import cut_clips

    seqs = as_sequences(clips, "clips")
    if labels is None:
        labels = [None] * len(seqs)
    else:
        check_labels(labels, len(seqs), "labels")
    _check_split(split)
    out: list[PoseSequence] = []
    out_labels: list[Any] = []
    for seq, label in zip(seqs, np.asarray(labels, dtype=object), strict=True):
        named = "" if label is None else str(label)
        pieces = cut_clips([Clip(seq, named, subject_of(seq), {})], split).clips
        out += [c.seq for c in pieces]
        out_labels += [label] * len(pieces)
    return out, out_labels


def _given_labels(frame_labels: Any, names: dict[str, str] | None) -> list[str]:
    """Labels given in memory (one per frame or block) as text, each through ``names``: text
    or whole numbers (as a label file's codes; 6.0, a float, as 6), else an InputError naming
    ``frame_labels`` (a NaN said to be a missing label)."""
    if isinstance(frame_labels, bytes) or not hasattr(frame_labels, "__iter__"):
        raise InputError(
            "must be a label file's path or a sequence of labels (one per frame or"
            f" block), got {type(frame_labels).__name__}",
            "frame_labels",
        )
    values = np.asarray(list(frame_labels), dtype=object)
    if values.ndim != 1:
        raise InputError(
            f"must be one label per frame or block, got shape {values.shape}",
            "frame_labels",
        )
    out = []
    for i, v in enumerate(values):
        if isinstance(v, float | np.floating) and float(v).is_integer():
            v = int(v)  # a code read as a number of a float type, as np.loadtxt reads it
        whole = isinstance(v, int | np.integer) and not isinstance(v, bool | np.bool_)
        if not (whole or isinstance(v, str)) or not str(v).strip() or "\x00" in str(v):
            shown = v.item() if isinstance(v, np.generic) else v  # 6.5, not np.float64(6.5)
            why = (
                "a label is missing (every frame or block needs one)"
                if v is None or (isinstance(v, float | np.floating) and np.isnan(v))
                else "a label is text or a whole number (a code)"
            )
            raise InputError(f"frame_labels[{i}] is {shown!r}: {why}", "frame_labels")
        out.append(str(v).strip())
    if names is not None:
        unknown = sorted({v for v in out if v not in names})
        if unknown:
            raise InputError(
                f"label code(s) {', '.join(unknown[:5])} not in the label names", "frame_labels"
            )
        out = [names[v] for v in out]
    return out


def _label_names(names: Any) -> dict[str, str] | None:
    """``names``: None, a label names file (read as ``--label-names``) or a mapping of code to
    name; anything else is an InputError naming it."""
    from features.label_tracks import read_label_names

    if names is None:
        return None
    if isinstance(names, str | Path):
        return read_label_names(names)
    if isinstance(names, dict):
        return {str(k): str(v) for k, v in names.items()}
    raise InputError(
        f"must be a label names file or a dict of code to name, got {type(names).__name__}",
        "names",
    )


def cut_recording(
    recording: PoseSequence,
    frame_labels: str | Path | Sequence[Any] | np.ndarray,
    split: str = "windows",
    *,
    block_s: float | None = None,
    names: str | Path | dict[str, str] | None = None,
) -> tuple[list[PoseSequence], list[str]]:
    """The cases ``posecbr train RECORDING --frame-labels FILE`` makes of one recording
    labelled over time: its labelled stretches (``frame_labels``: a label file, as
    ``--frame-labels``, or the labels in memory, text or whole-number codes (of an integer
    or a float type: ``np.loadtxt``'s 6.0 is code 6); one per frame,
    or one per ``block_s`` seconds as ``--label-block``; ``names`` maps codes to names, a
    file as ``--label-names`` or a dict), those shorter than the shortest repetition
    (:data:`features.repetitions.MIN_PERIOD_S`: a label that flickers) left out, each cut as
    :func:`cut` cuts (``split``: ``"windows"`` by default, as ``train`` of such a recording).
    Returns the pieces and their labels, to give to :func:`train` with ``cases=split``.
    Bad arguments are an :class:`features.errors.InputError` naming the argument; a label
    file that cannot be read or whose count does not fit the recording, a DataError naming
    it, as the command says it."""
    from features.label_tracks import read_label_track
    from features.repetitions import MIN_PERIOD_S, cut_clips, long_enough
    from features.stretches import split_by_labels, stretch_clips

    if not isinstance(recording, PoseSequence):
        raise InputError(f"must be a PoseSequence, got {type(recording).__name__}", "recording")
    _check_split(split)
    if block_s is not None and (
        isinstance(block_s, bool)
        or not isinstance(block_s, int | float | np.integer | np.floating)
        or not (np.isfinite(block_s) and block_s > 0)
    ):
        raise InputError(f"must be a finite number of seconds > 0, got {block_s!r}",
                         "block_s")  # fmt: skip
    block = None if block_s is None else float(block_s)
    mapping = _label_names(names)
    if isinstance(frame_labels, str | Path):
        path = Path(frame_labels)
        stretches = split_by_labels(recording, read_label_track(path, mapping), block, path)
    else:
        given = _given_labels(frame_labels, mapping)
        try:
            stretches = split_by_labels(recording, given, block, "frame_labels")
        except DataError as exc:
            raise InputError(exc.message, "frame_labels") from None
    kept, _ = long_enough(list(stretch_clips(stretches, subject_of(recording))))
    if not kept:
        raise InputError(f"no labelled stretch of {MIN_PERIOD_S:g} s or more", "frame_labels")
    pieces = cut_clips(kept, split).clips
    return [c.seq for c in pieces], [c.label for c in pieces]


def train_described(
    db: str | Path,
    name: str,
    clips: Sequence[DescribedClip],
    labels: Sequence[Any] | np.ndarray,
    estimator: CaseBaseClassifier,
    *,
    target: str = "label",
    cases: str = "clips",
    replace: bool = False,
    seen: Seen | None = None,
) -> TrainResult:
    """:func:`train` on clips already reduced by :func:`fit_plan` (:func:`describe_entries`).
    ``seen``: what was read of case base ``name`` before the clips were (``replace``
    refuses to drop one changed since, :meth:`StoreTransaction.create_case_base`).

    The classifier is fitted on ``labels`` as given, so its classes keep their type (whole
    numbers, true/false, other numbers: stored with the model, and answered as such once it
    is loaded back); the cases hold them as text."""
    check_url_or_path(db, "db")
    _check_name(name)
    _check_what(estimator, target, cases)
    text = [str(v) for v in check_labels(labels, len(clips), "labels")]
    given = list(np.asarray(labels, dtype=object))
    keep, skipped, too_short = usable(clips)
    if len({text[i] for i in keep}) == 1 < len(set(text)):
        raise _one_left(clips, text, keep, target)
    if not keep:
        raise _no_case(clips, "learn from")
    lost = lost_labels(text, keep)
    clips, text = [clips[i] for i in keep], [text[i] for i in keep]
    _check_unique(clips, "training set")
    _check_no_copies(clips, text)
    with _said_of_arguments():
        fitted: CaseBaseClassifier = unfitted_copy(estimator).fit_described(
            clips, [given[i] for i in keep]
        )
    _check_trimmed(fitted)
    return store_fitted(
        db,
        name,
        fitted,
        text,
        target=target,
        cases=cases,
        replace=replace,
        seen=seen,
        skipped=skipped,
        too_short=too_short,
        lost=lost,
    )


@contextmanager
def _said_of_arguments() -> Iterator[None]:
    """A refusal of the estimator's ``fit`` inside, which names its own arguments (``X``,
    ``y``: "y: the training set has only one activity"), said of this module's (``clips``,
    ``labels``), as :func:`train` and :func:`train_described` name them."""
    try:
        yield
    except PosecbrError as exc:
        ours = {"X": "clips", "y": "labels"}.get(exc.source or "")
        if ours is not None:
            exc.source = ours
            exc.args = (f"{ours}: {exc.message}",)
        raise


def _check_trimmed(fitted: CaseBaseClassifier) -> None:
    """Refuse a case base its own trimming left with fewer active cases than it votes with
    (k), as ``casebase trim`` refuses it: every answer would be the vote of all its cases."""
    report = fitted.maintenance_
    if report is not None and report.size_after < int(fitted.k):
        shares = fitted.editor in (None, "novelty-benefit")  # trim is its share kept
        how = "keep more with `trim`" if shares else f"another `editor` than {fitted.editor}"
        raise DataError(
            f"trimming would leave {report.size_after} cases, fewer than the {int(fitted.k)}"
            f" the case base votes with (k): nothing stored ({how}, or give a smaller `k`)",
            "training set",
        )


def store_fitted(
    db: str | Path,
    name: str,
    fitted: CaseBaseClassifier,
    labels: Sequence[str],
    *,
    target: str = "label",
    cases: str = "clips",
    replace: bool = False,
    seen: Seen | None = None,
    skipped: Sequence[str] = (),
    too_short: Sequence[str] = (),
    lost: Sequence[str] = (),
) -> TrainResult:
    """Store the fitted classifier as case base ``name`` in ``db`` in one transaction
    (``labels``: its training clips' solutions, for the summary; ``seen``: what was read of
    ``name`` before the fit, checked by a ``replace``)."""
    from casebase_store import write_store

    check_url_or_path(db, "db")
    check_fitted(fitted, "case_base_")
    cb = to_store(fitted)
    calibrate_stored_judges(fitted)

    def write(tx: StoreTransaction) -> None:
        info = tx.create_case_base(
            name,
            fitted.feature_config_.to_dict(),
            cb.names,
            cb.words,
            fitted.measure_.params(),
            model=model_document(fitted, target, cases),
            replace=replace,
            seen=seen,
        )
        records = progress(case_records(cb), desc="storing", total=len(cb), unit="case")
        ids = np.asarray(tx.add_cases(info, records))
        _cache_representations(tx, fitted, cb, ids)
        tx.log(info, "build", reason=_build_reason(fitted, len(labels), labels))
        if fitted.maintenance_ is not None:
            record_trim(tx, info, fitted.maintenance_, ids)

    write_store(db, write)
    done = f"case base {name!r} was stored before it ({len(cb)} cases)"
    with stored_before(done, "casebase info shows it"):
        _refresh_matrices(db, name)
        return _fitted_result(name, fitted, cb, labels, skipped, too_short, lost)


def _added_before(n: int, name: str) -> str:
    """What an append had stored when the work after its commit was stopped."""
    return f"the {counted(n, 'case')} {'was' if n == 1 else 'were'} added to {name!r} before it"


def _fitted_result(
    name: str,
    fitted: CaseBaseClassifier,
    cb: CaseBase,
    labels: Sequence[str],
    skipped: Sequence[str],
    too_short: Sequence[str],
    lost: Sequence[str] = (),
) -> TrainResult:
    return TrainResult(
        name,
        len(cb),
        len(fitted.case_base_),
        _counts([str(v) for v in fitted.case_base_.labels]),  # its cases, as counted above
        fitted.feature_config_,
        fitted.measure_.params(),
        fitted.maintenance_,
        _learned(fitted),
        list(skipped),
        list(too_short),
        JUDGES[0] in fitted.judges_,
        same_features(cb),
        trained_counts=_counts([str(v) for v in labels]),
        lost_labels=list(lost),
    )


SAME_TOLERANCE = 1e-3
"""Features within this of each other, every one, are the same (:func:`same_features`): a
thousandth of a fluent's confidence, of a metre, of a degree."""


def same_features(cb: CaseBase) -> list[str]:
    """The cases whose features are those of an earlier case of another activity (each
    within :data:`SAME_TOLERANCE`; NaN where the same features are missing), each told as
    ``"A (label) = B (label)"`` with one such case: nothing can tell them apart (a still or
    unseen stretch labelled as several activities, a file copied under another label).

    Candidates come from eight random projections of the rows (a pair within the tolerance
    in every feature lies within ``tolerance * sum |w|`` in each projection ``w``), checked
    feature by feature a few hundred at a time until one matches."""
    n = len(cb)
    if n < 2:
        return []
    rows = cb.problems.reshape(n, -1).astype(float)
    rows = np.where(np.isnan(rows), 1e9, rows)  # missing matches missing only
    w = np.random.default_rng(0).normal(size=(rows.shape[1], 8))
    proj, bound = rows @ w, SAME_TOLERANCE * np.abs(w).sum(axis=0) * 1.01  # and rounding
    labels = cb.labels
    codes = np.unique(labels.astype(str), return_inverse=True)[1].reshape(-1)
    order = np.argsort(proj[:, 0], kind="stable")
    key = proj[order, 0]
    lows = np.searchsorted(key, key - bound[0], side="left")
    highs = np.searchsorted(key, key + bound[0], side="right")
    found: dict[int, int] = {}
    for t in range(n):
        i = int(order[t])
        near = order[lows[t] : highs[t]]
        near = near[(near < i) & (codes[near] != codes[i])]
        for a in range(0, len(near), 256):  # a few at a time: most stills match at once
            chunk = near[a : a + 256]
            chunk = chunk[np.all(np.abs(proj[chunk] - proj[i]) <= bound, axis=1)]
            same = chunk[np.all(np.abs(rows[chunk] - rows[i]) <= SAME_TOLERANCE, axis=1)]
            if len(same):
                found[i] = int(same[0])
                break

    def told(i: int) -> str:
        a, b = cb.frames[i]
        where = cb.sources[i] or f"case {i + 1}"
        return f"{_shown_frames((where, a, b))} ({labels[i]})"

    return [f"{told(i)} = {told(j)}" for i, j in sorted(found.items())]


def _cache_representations(
    tx: StoreTransaction, clf: CaseBaseClassifier, cb: CaseBase, ids: np.ndarray
) -> None:
    kind = clf.measure_.cache_kind(tuple(cb.problems.shape[1:]))
    if kind is not None:
        reps = clf.measure_.represent(cb.problems)
        tx.put_representations(kind, {int(cid): reps[i] for i, cid in enumerate(ids)})


def _build_reason(clf: CaseBaseClassifier, n_clips: int, labels: Sequence[str]) -> str:
    return (
        f"{len(to_store(clf))} cases from {n_clips} clips of {len(set(labels))} activities, "
        f"features {clf.feature_config_.describe()}, similarity {clf.measure_.name}, side "
        f"handling {clf.side_}, feature weights {clf.weighting_}, {clf.phases_} phases"
    )


def append_plan(
    db: str | Path,
    name: str,
    target: str | None = None,
    cases: str | None = None,
    data_columns: Sequence[str] = (),
) -> tuple[Plan, str, str, str]:
    """The plan of ``--append`` to case base ``name`` (its columns), its identity (``uid``:
    the append is refused if the case base is replaced meanwhile), what the added clips
    must be cut into: the case base's own kind of case (``"clips"`` for one stored before
    this was recorded), and what their solution is: the case base's target. ``cases`` or
    ``target`` given otherwise (as :func:`train`'s) is refused: windows added to a case base
    of whole clips would be cases of another kind, labels added to one of correct/incorrect
    another solution; a ``target`` close to the case base's or to one of ``data_columns``
    (the added clips') is guessed as mistyped. Refused with ConfigError naming the argument
    (``target``, ``cases``; ``train --append`` says ``--target``, ``--split``)."""
    from casebase_store import open_store

    store = open_store(db, create=False, readonly=True)
    try:
        stored = load_classifier(store, name)
    finally:
        store.close()
    if target is not None and stored.target != target:
        raise ConfigError(
            f"case base {name!r} predicts {stored.target!r}, not {target!r}: its cases "
            f"cannot take `target={target!r}`"
            + did_you_mean(target, [stored.target, *(c for c in data_columns if c != target)]),
            "target",
        )
    if cases is not None and stored.cases is not None and stored.cases != cases:
        raise ConfigError(
            f"case base {name!r} holds {stored.cases} (trained with `cases={stored.cases!r}`),"
            f" not {cases}: add to it with `cases={stored.cases!r}`",
            "cases",
        )
    cb = stored.classifier.case_base_
    columns = CaseBase(cb.config, cb.measure, cb.problems[:0], cb.labels[:0], cb.names, cb.words)
    plan = Plan(casebase=columns)
    return plan, stored.uid, cases or stored.cases or "clips", stored.target


def append(
    db: str | Path,
    name: str,
    clips: Iterable[PoseSequence],
    labels: Sequence[Any] | np.ndarray,
    *,
    target: str | None = None,
) -> TrainResult:
    """Add the usable ``clips`` as cases of the stored case base ``name``, described with its
    stored configuration (nothing is learned anew), in one transaction checked against the
    case base that was read. ``target``: what ``labels`` are (refused unless the case base's
    own; None: whatever it predicts)."""
    check_url_or_path(db, "db")
    clips = as_sequences(clips, "clips")  # a set's order is not the labels'
    text = [str(v) for v in check_labels(labels, len(clips), "labels")]
    plan, uid, _, _ = append_plan(db, name, target)
    described = [
        describe(s, plan) for s in progress(clips, desc="features", total=len(clips), unit="clip")
    ]
    return append_described(db, name, described, text, plan, uid)


def _provenance(clip: DescribedClip) -> tuple[str, int, int]:
    return clip.source, int(clip.frames[0]), int(clip.frames[1])


def _shown_frames(key: tuple[str, int | None, int | None]) -> str:
    """A clip named as ``classify`` and ``segment`` name it (its frames end inclusive)."""
    source, a, b = key
    return piece_name(source, None if a is None or b is None else (a, b))


def _check_unique(clips: Sequence[DescribedClip], where: str) -> None:
    """Refuse training clips of which two are the same stretch of the same file (a labels
    CSV listing a file twice): their cases would vote twice. Clips without a source (the
    Python API's arrays) are not compared."""
    check_listed_once([_provenance(c) for c in clips], where, "its cases would vote twice")


def check_listed_once(keys: Sequence[tuple[str, int, int]], where: str, consequence: str) -> None:
    """Refuse two of ``keys`` (source, first frame, end frame) that are the same stretch of
    the same file, saying the ``consequence``; keys without a source are not compared."""
    seen: set[tuple[str, int, int]] = set()
    for key in keys:
        if not key[0]:
            continue
        if key in seen:
            raise DataError(f"{_shown_frames(key)} is listed twice: {consequence}", where)
        seen.add(key)


def _check_new(
    tx: StoreTransaction, info: CaseBaseInfo, clips: Sequence[DescribedClip], where: str
) -> None:
    """Refuse an append of a stretch the case base already holds (the same file's same
    frames: appended before), in the transaction that would add it. A file is the same
    however its path is written (relative or absolute, through a link): each clip's source
    is looked for as given, resolved, and resolved relative to the working folder; and a
    case stored under a path written from another working folder (which no longer
    resolves) is the clip when its file name, frames and poses are the clip's
    (:func:`_check_new_content`)."""
    names = {c.source: _spellings(c.source) for c in clips if c.source}
    stored = tx.cases_from(info, [n for spelt in names.values() for n in spelt])
    for clip in clips:
        _, a, b = _provenance(clip)
        for name in names.get(clip.source, ()):
            if (name, a, b) in stored:
                raise StoreError(
                    f"{_shown_frames((clip.source, a, b))} is already case "
                    f"{stored[(name, a, b)]} of {info.name!r} (added before?): nothing added",
                    where,
                )
    _check_new_content(tx, info, clips, where)
    pair = copies_within(clips)
    if pair is not None:
        raise _given_twice(clips[pair[0]], clips[pair[1]], where)


#: features within this of a stored case's (relative and absolute) are the same
#: computation on the same poses: floating-point rounding (another summation order) moves
#: them by some 1e-13; the poses of another recording move them by far more. What tells a
#: copy of a case stored without its clip's poses digest (:func:`_check_new_content`)
SAME_CONTENT_TOLERANCE = 1e-9


def _check_new_content(
    tx: StoreTransaction, info: CaseBaseInfo, clips: Sequence[DescribedClip], where: str
) -> None:
    """Refuse an append of a clip a stored case was made of, whatever either file is called:
    the same clip stored under a path that no longer resolves (one relative to another
    working folder), or a copy of its file under another name; its case would vote twice.
    A case stored with its clip's poses digest (:func:`cbr.described.poses_digest`) is the
    clip when its frames and poses are the clip's, byte for byte (its features need not be:
    another posecbr may have computed them; two takes described alike are two clips). One
    stored without it (before the digest was kept, or in a store made before, which has no
    place for it; or a clip whose poses are not known) is compared by its frames and
    features, each within :data:`SAME_CONTENT_TOLERANCE`. A case stored without its frames
    (before they were kept) is compared by its poses or features alone. Clips without a
    source (the Python API's arrays) are not compared."""
    sourced = [c for c in clips if c.source]
    if not sourced:
        return
    values = np.stack([c.values for c in sourced]).reshape(len(sourced), -1)
    digests = np.array([c.poses for c in sourced], dtype=object)
    at: dict[tuple[int | None, int | None], list[int]] = {}
    for k, clip in enumerate(sourced):
        at.setdefault(_provenance(clip)[1:], []).append(k)
    every = list(range(len(sourced)))
    for chunk in tx.cases_framed(info, at):
        pairs = [
            (r, k)
            for r, case in enumerate(chunk)
            for k in (
                every
                if None in (case.frame_start, case.frame_end)
                else at.get((case.frame_start, case.frame_end), [])
            )
        ]
        if not pairs:
            continue
        rows, ks = (np.asarray(p) for p in zip(*pairs, strict=True))
        stored = np.array([c.poses or "" for c in chunk], dtype=object)
        told = (stored[rows] != "") & (digests[ks] != "")  # both digests known: they decide
        same = told & (stored[rows] == digests[ks])
        width = values.shape[1]
        rest = np.flatnonzero(~told & np.array([chunk[r].features.size == width for r in rows]))
        if len(rest):
            features = np.stack([c.features.reshape(-1) if c.features.size == width
                                 else np.full(width, np.inf) for c in chunk])  # fmt: skip
            of, by = rows[rest], ks[rest]
            like = _close(values[by, :8], features[of, :8]).all(axis=1)  # most differ there
            rest, of, by = rest[like], of[like], by[like]
            same[rest[_close(values[by], features[of]).all(axis=1)]] = True
        if same.any():
            first = int(np.argmax(same))  # pairs are in case order: the first case repeated
            case, clip = chunk[rows[first]], sourced[ks[first]]
            raise _repeated(clip, case, info.name, where, "poses" if told[first] else "features")


def copies_within(clips: Sequence[DescribedClip]) -> tuple[int, int] | None:
    """The first two of ``clips`` (their indices, in order) that are copies of one clip: the
    same frames and the same poses byte for byte (:attr:`DescribedClip.poses`), whatever
    their files are called; None when no two are. Clips whose poses are not known (records
    made by hand) are not compared; nor are clips merely described alike (a few columns, or
    QMP vectors, of two takes can agree)."""
    first: dict[tuple[str, int, int], int] = {}
    for k, clip in enumerate(clips):
        if not clip.poses:
            continue
        key = (clip.poses, int(clip.frames[0]), int(clip.frames[1]))
        if key in first:
            return first[key], k
        first[key] = k
    return None


def _check_no_copies(clips: Sequence[DescribedClip], labels: Sequence[str]) -> None:
    """Refuse training clips two of which are copies of one clip (:func:`copies_within`), as
    an append refuses them: with one label its case would vote twice, with two it would be a
    case of each (one clip labelled two activities). Before, both were stored."""
    pair = copies_within(clips)
    if pair is None:
        return
    i, j = pair
    why = (
        "its case would vote twice"
        if labels[i] == labels[j]
        else f"one clip labelled both {labels[i]!r} and {labels[j]!r}"
    )
    raise DataError(
        f"{_shown_frames(_provenance(clips[j]))} has the same frames and poses as "
        f"{_shown_frames(_provenance(clips[i]))} (a copy of its file?): {why}; nothing stored",
        "training set",
    )


def _given_twice(first: DescribedClip, second: DescribedClip, where: str) -> StoreError:
    """The refusal of an append that gives ``second``, the same clip as ``first``."""
    return StoreError(
        f"{_shown_frames(_provenance(second))} has the same frames and poses as "
        f"{_shown_frames(_provenance(first))}, given in this append too (a copy of its file?):"
        " its case would vote twice; nothing added",
        where,
    )


def _repeated(
    clip: DescribedClip, case: SourcedCase, name: str, where: str, told: str
) -> StoreError:
    """The refusal of ``clip``, which repeats the stored ``case``, as ``told`` (``"poses"``
    or ``"features"``)."""
    shown = _shown_frames(_provenance(clip))
    stored = _shown_frames((case.source, case.frame_start, case.frame_end))
    framed = case.frame_start is not None
    if _file_name(case.source) == _file_name(clip.source):
        why = f"the same file name{', frames' * framed} and {told}: added before from another"
        why += " folder?"
    else:
        why = f"the same {'frames and ' * framed}{told} under another file name: a copy of"
        why += " its file?"
    return StoreError(
        f"{shown} is already case {case.id} of {name!r}, stored as {stored} ({why}): nothing added",
        where,
    )


def _file_name(source: str) -> str:
    """A source's file name: what follows its last ``/`` or ``\\`` (a source stored on
    Windows is split alike)."""
    return source.replace("\\", "/").rpartition("/")[2]


def _close(values: np.ndarray, stored: np.ndarray) -> np.ndarray:
    """Which of ``values`` are ``stored``'s up to rounding (missing alike)."""
    tol = SAME_CONTENT_TOLERANCE
    close: np.ndarray = np.isclose(values, stored, rtol=tol, atol=tol, equal_nan=True)
    return close


def _spellings(source: str) -> tuple[str, ...]:
    """The ways a case's source may have been written: as given, the file's resolved path,
    and that path relative to the working folder (when it lies below it)."""
    out = [source]
    try:
        real = Path(source).resolve()
        out.append(str(real))
        out.append(os.path.relpath(real))
    except (OSError, ValueError):  # another drive (Windows), a path that cannot resolve
        pass
    return tuple(dict.fromkeys(out))


def append_described(
    db: str | Path,
    name: str,
    clips: Sequence[DescribedClip],
    labels: Sequence[Any],
    plan: Plan,
    uid: str,
) -> TrainResult:
    """:func:`append` on clips already reduced by :func:`append_plan`'s plan. Several
    processes may append to one case base at once: each commits its cases in one transaction
    (ids from the database, never reused), so none is lost or duplicated."""
    from casebase_store import open_store

    text = [str(v) for v in check_labels(labels, len(clips), "labels")]
    keep, skipped, too_short = usable(clips)
    if not keep:
        raise _no_case(clips, "add")
    lost = lost_labels(text, keep)
    clips, text = [clips[i] for i in keep], [text[i] for i in keep]
    columns = plan.casebase
    assert columns is not None
    cb = CaseBase(
        columns.config,
        columns.measure,
        np.stack([c.values for c in clips]),
        np.array(text, dtype=object),
        columns.names,
        columns.words,
        sources=tuple(c.source for c in clips),
        subjects=tuple(c.subject for c in clips),
        frames=tuple(c.frames for c in clips),
        skeletons=tuple(c.skeleton for c in clips),
        poses=tuple(c.poses for c in clips),
    )
    _check_unique(clips, "training set")
    store = open_store(db, create=False)
    try:
        with store.transaction() as tx:
            info = tx.expect(name, uid)
            held = set(info.label_counts)  # another append may have added some since read
            # an activity the case base holds, spelt in other Unicode characters (a label
            # from a macOS file name beside one typed), is that activity: it was a second
            # one, printed the same
            text = spelt_as(text, info.label_counts)
            cb.labels = np.array(text, dtype=object)
            _check_new(tx, info, clips, store.where)
            ids = np.asarray(tx.add_cases(info, case_records(cb)))
            judges_after_change(tx, info)
            kind = cb.measure.cache_kind(tuple(cb.problems.shape[1:]))
            if kind is not None:
                reps = cb.measure.represent(cb.problems)
                tx.put_representations(kind, {int(c): reps[i] for i, c in enumerate(ids)})
            tx.log(info, "append", reason=f"{len(cb)} cases from {len(clips)} clips")
        with stored_before(_added_before(len(cb), name), _APPEND_AGAIN):
            write_matrices(store, name)
            total = store.count_cases(name)
    finally:
        store.close()
    with stored_before(_added_before(len(cb), name), _APPEND_AGAIN):
        return _appended_result(name, cb, total, text, held, skipped, too_short, lost)


_APPEND_AGAIN = "run again, the append is refused as held already (casebase info shows them)"


def _appended_result(
    name: str,
    cb: CaseBase,
    total: int,
    text: Sequence[str],
    held: set[str],
    skipped: Sequence[str],
    too_short: Sequence[str],
    lost: Sequence[str] = (),
) -> TrainResult:
    """What an append did; ``held``: the activities the case base held as the cases were
    added (what is new is new then, not when the case base was read: another append may have
    added an activity meanwhile)."""
    new = sorted(set(text) - held)
    return TrainResult(
        name, len(cb), total, _counts([str(v) for v in cb.labels]), cb.config, cb.measure.params(),
        None, {}, list(skipped), list(too_short),
        indistinct=same_features(cb), new_labels=new,
        file_named_labels=_file_named(cb, new), lost_labels=list(lost),
    )  # fmt: skip


def _file_named(cb: CaseBase, labels: Sequence[str]) -> list[str]:
    """The ``labels`` that are the file name (without its ending) of one of their cases'
    clips (a mirror image's source ends in " (mirrored)")."""
    named = {
        str(label)
        for label, source in zip(cb.labels, cb.sources, strict=True)
        if Path(source.removesuffix(" (mirrored)")).stem == str(label)
    }
    return sorted(named & set(labels))


def _refresh_matrices(db: str | Path, name: str) -> None:
    """A large case base's memory-mapped matrices, written for the state just stored."""
    from casebase_store import open_store

    store = open_store(db, create=False)
    try:
        write_matrices(store, name)
    finally:
        store.close()
