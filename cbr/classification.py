"""Classifying clips with a stored case base (the work behind ``posecbr classify``), and
learning from feedback: the stored classifier's :meth:`~cbr.estimator.CaseBaseClassifier.solve`
for every clip, an explanation, and with the true label a retain or revise step.

Each clip's feedback is ONE transaction, checked against the case base that was read: a case
base replaced meanwhile is refused (nothing written), a revised case is changed as it is in the
store at that moment (so concurrent revisions all take effect), and when another process
changed the case base meanwhile it is read again before the next clip. A clip that shows no
person is reported as unclassifiable and never stored.
"""

from __future__ import annotations

import difflib
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from casebase_store import CaseBaseGone, StaleCaseError
from features.errors import DataError, ParameterError, PosecbrError
from features.poses import PoseSequence
from features.progress import progress
from features.text import shown, spelt_as

from .casebase import frames_of, piece_fields, piece_name, skeleton_of, subject_of
from .described import poses_digest
from .estimator import CaseBaseClassifier, Solved, too_short, unclassifiable
from .explain import Explanation
from .retain import RetainDecision, decide_retention, record_retention
from .revise import Revision, observed, plan_revision, record_revision
from .stored import StoredClassifier, judges_after_change, load_classifier, write_matrices

if TYPE_CHECKING:
    from casebase_store import CaseStore

SOLVE_CHUNK = 256  # clips per batched solve (one block of queries of the matrix product)


@dataclass(frozen=True)
class Classification:
    """One clip's answer: ``solved`` and ``explanation`` (None when the clip could not be
    classified: ``unclassifiable`` says why), and what feedback changed; ``source`` the file
    passed and ``made_from`` what that pose file was made from (a video), if anything;
    ``frames`` the clip's frames in that file (start, end exclusive) when it is a piece of it
    (a labels CSV's ``start,end`` row, a labelled stretch), else None; ``origin`` the
    recording a file was cut from (``convert`` of a labelled recording), whose frames
    ``frames`` then counts."""

    source: str
    true_label: str | None
    solved: Solved | None
    explanation: Explanation | None
    unclassifiable: str | None = None
    revision: Revision | None = None
    retention: RetainDecision | None = None
    made_from: str | None = None
    frames: tuple[int, int] | None = None
    origin: str | None = None

    @property
    def label(self) -> str | None:
        return None if self.solved is None else self.solved.solution.label

    @property
    def name(self) -> str:
        """The file passed, with the frames of it the clip is when a piece (end inclusive)."""
        return piece_name(self.source, self.frames, self.origin)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"clip": self.source}
        out.update(piece_fields(self.frames))
        if self.frames is not None and self.origin:
            out["origin"] = self.origin  # the recording whose frames ``frames`` counts
        if self.made_from:
            out["made_from"] = self.made_from
        if self.explanation is not None and self.solved is not None:
            out.update(self.explanation.to_dict())
            # nearest-case distance over the usual held-out one, and the calibrated flag
            out["novelty"] = self.solved.novelty
            out["unlike_cases"] = self.solved.unlike_cases
            out["unlike_reason"] = self.solved.unlike_reason or None
            out["torso_share"] = self.solved.torso_share
            out["arms_alone"] = self.solved.arms_alone
        else:
            out.update(label=None, unclassifiable=self.unclassifiable)
        # null when the clip has no label, so every record holds both keys (a script reading
        # r["true_label"] failed on the first unlabelled clip, the key absent)
        out["true_label"] = self.true_label
        # an unclassifiable clip is not judged (the summary counts it as not labelled)
        judged = self.true_label is not None and self.solved is not None
        out["correct"] = self.true_label == self.label if judged else None
        # the same under a name no repetition check can read as a verdict ("label":
        # "incorrect", "correct": true was an incorrect repetition answered right)
        out["right"] = out["correct"]
        if self.revision is not None:
            r = self.revision
            out["revision"] = {
                "action": r.action,
                "case_id": r.case_id,
                "old_label": r.old_label,
                "new_label": r.new_label,
                "reason": r.reason,
            }
        if self.retention is not None:
            d = self.retention
            out["retention"] = {
                "retained": d.retained,
                "novelty": d.novelty,
                "benefit": d.benefit,
                "reason": d.reason,
            }
        return out


def _solve_all(clf: CaseBaseClassifier, clips: Sequence[PoseSequence]) -> list[Solved | str]:
    """Every clip through :meth:`~cbr.estimator.CaseBaseClassifier.solve`, the usable ones in
    one call (one batched retrieval); a clip that cannot be classified gets the reason."""
    short = {i: why for i, c in enumerate(clips) if (why := too_short(c)) is not None}
    if short:
        rest = [i for i in range(len(clips)) if i not in short]
        solved = iter(_solve_all(clf, [clips[i] for i in rest]) if rest else [])
        return [short[i] if i in short else next(solved) for i in range(len(clips))]
    bad = set(unclassifiable(clips))
    good = [c for i, c in enumerate(clips) if i not in bad]
    try:
        solved = iter(clf.solve(good) if good else [])
    except DataError:  # a clip the batch cannot take: one call per clip, so only it is refused
        return [_solve_one(clf, c) for c in clips]
    return [_solve_one(clf, c) if i in bad else next(solved) for i, c in enumerate(clips)]


def _solve_one(clf: CaseBaseClassifier, clip: PoseSequence) -> Solved | str:
    why = too_short(clip)
    if why is not None:
        return why
    try:
        return clf.solve([clip])[0]
    except DataError as exc:
        return exc.message


def classify_clips(
    stored: StoredClassifier,
    clips: Sequence[PoseSequence],
    truths: Sequence[str | None],
    target: str = "label",
) -> list[Classification]:
    """Classify and explain every clip (nothing is written); ``target`` the column the
    labels come from (``"correct"``: read as correct / incorrect repetitions)."""
    clf = stored.classifier
    triples = zip(clips, truths, _solved_in_chunks(clf, clips), strict=True)
    return [
        _classification(clf, clip, truth, s, target)
        for clip, truth, s in progress(triples, desc="classifying", total=len(clips), unit="clip")
    ]


def _solved_in_chunks(
    clf: CaseBaseClassifier, clips: Sequence[PoseSequence]
) -> Iterator[Solved | str]:
    """:func:`_solve_all` over chunks of :data:`SOLVE_CHUNK` clips, so progress shows."""
    for a in range(0, len(clips), SOLVE_CHUNK):
        yield from _solve_all(clf, clips[a : a + SOLVE_CHUNK])


def _classification(
    clf: CaseBaseClassifier,
    clip: PoseSequence,
    truth: str | None,
    solved: Solved | str,
    target: str,
) -> Classification:
    """One clip's answer from its :meth:`solve` result (or the reason it has none), explained;
    ``truth`` as the case base writes it when it is one of its classes in other Unicode
    characters (:func:`features.text.spelt_as`), so the clip is judged against that class."""
    if truth is not None:
        truth = spelt_as([truth], clf.classes_)[0]
    made_from = clip.metadata.get("made_from")
    made = None if made_from is None else str(made_from)
    piece = frames_of(clip) if "frame_offset" in clip.metadata else None
    cut_from = clip.metadata.get("origin")
    origin = None if cut_from is None else str(cut_from)
    if isinstance(solved, str):
        return Classification(
            clip.source, truth, None, None, unclassifiable=solved, made_from=made, frames=piece,
            origin=origin,
        )  # fmt: skip
    exp = clf.explain_solved(solved, target)
    return Classification(
        clip.source, truth, solved, exp, made_from=made, frames=piece, origin=origin
    )


def classify_clip(
    stored: StoredClassifier, clip: PoseSequence, truth: str | None, target: str = "label"
) -> Classification:
    """One clip classified and explained as :func:`classify_clips` classifies each, without
    a progress bar (``watch --split repetitions``: a stream's repetitions, one as each
    finishes)."""
    clf = stored.classifier
    return _classification(clf, clip, truth, _solve_one(clf, clip), target)


def summarise(results: Sequence[Classification], target: str = "label") -> dict[str, Any]:
    """What a run of :func:`classify_clips` comes to: clips, classified, how many got each
    answer (``answers``, ``{label: clips}``: of a session's repetitions, how many were judged
    correct and incorrect, labelled or not), the clips unlike the stored cases and the
    unclassifiable ones; with true labels, the accuracy, the recall per
    class (``{label: {"right", "clips", "recall"}}``), the mean confidence (what the
    accuracy should be if the confidences are probabilities; ``confidence_calibrated`` False
    when they are vote shares the case base could not calibrate, None when no clip was
    classified) and the wrong clips."""
    done = [r for r in results if r.solved is not None]
    labelled = [r for r in done if r.true_label is not None]
    right = [r for r in labelled if r.true_label == r.label]
    recall: dict[str, dict[str, Any]] = {}
    for lab in sorted({str(r.true_label) for r in labelled}):
        mine = [r for r in labelled if r.true_label == lab]
        hits = sum(r.label == lab for r in mine)
        recall[lab] = {"right": hits, "clips": len(mine), "recall": hits / len(mine)}
    conf = [r.solved.solution.confidence for r in labelled if r.solved is not None]
    explained = [r.explanation for r in done if r.explanation is not None]
    calibrated = all(e.confidence_calibrated for e in explained) if explained else None
    return {
        "target": target,
        "clips": len(results),
        "classified": len(done),
        "answers": dict(sorted(Counter(str(r.label) for r in done).items())),
        "labelled": len(labelled),
        "right": len(right),
        "accuracy": len(right) / len(labelled) if labelled else None,
        "expected_accuracy": float(np.mean(conf)) if conf else None,
        "confidence_calibrated": calibrated,
        "recall": recall,
        "wrong": [
            {"clip": r.source, "label": r.label, "true_label": r.true_label} | _piece(r)
            for r in labelled
            if r.true_label != r.label
        ],
        "unlike_cases": [
            {"clip": r.source} | _piece(r)
            for r in done
            if r.solved is not None and r.solved.unlike_cases
        ],
        "unclassifiable": [{"clip": r.source} | _piece(r) for r in results if r.solved is None],
    }


def _piece(r: Classification) -> dict[str, Any]:
    """What names the clip ``r`` in the summary's lists beside its file (``clip``): when it is
    a piece of the file (a labels CSV's ``start,end`` row), its frames as the clip's own JSON
    gives them (:func:`cbr.casebase.piece_fields`), and ``origin`` the recording they count in
    when the file was cut from one; nothing for a whole file."""
    out = piece_fields(r.frames)
    if r.frames is not None and r.origin:
        out["origin"] = r.origin
    return out


def check_feedback_label(
    label: str, known: Sequence[str], new_label: bool, target: str | None = None
) -> str:
    """The feedback label, refused when empty, or (without ``new_label``) when it is no
    activity of the case base (no class of it, for a case base predicting another ``target``
    column): a typo must not relabel a trained case or start a class. Refused with
    ParameterError naming the argument ``label`` (``classify`` says ``--feedback``, and
    ``--new-label`` for ``new_label``). A label that is an activity written in other Unicode
    characters (:func:`features.text.spelt_as`) is that activity, as the case base spells it:
    "Plié" typed was refused beside a stored "Plié" saved decomposed, and with ``new_label``
    stored as a second activity that prints the same."""
    from .explain import class_noun

    text = spelt_as([str(label).strip()], known)[0]
    noun = class_noun(target)
    if not text:
        raise ParameterError("the feedback label is empty", "label")
    if text not in known and not new_label:
        close = difflib.get_close_matches(text, list(known), n=1)
        hint = f"; did you mean {close[0]!r}? " if close else ". "
        raise ParameterError(
            f"{text!r} is not {'an' if noun[0] in 'aeiou' else 'a'} {noun} of this case base"
            f" (known: {', '.join(known)}){hint}To add a new {noun}, pass `new_label=True` as"
            " well",
            "label",
        )
    return text


def check_feedback_cases(stored: StoredClassifier) -> None:
    """Refuse feedback to a case base of repetitions or windows (``train --split``): the clip
    would be retained whole, a case of another kind than every other; ``train --append``
    cuts it as the case base was cut. ParameterError naming the argument ``stored``
    (``classify`` says ``--feedback``)."""
    if stored.cases in (None, "clips"):
        return
    raise ParameterError(
        f"case base {stored.name!r} holds {stored.cases} (trained with "
        f"`cases={stored.cases!r}`): feedback would retain the clip whole, a case of another "
        f"kind; add the clip with posecbr train CLIP --append (a pose file carrying its label, or"
        f" a labels CSV), which cuts it into {stored.cases} as the case base was; nothing written",
        "stored",
    )


@dataclass(frozen=True)
class FeedbackSettings:
    """Retain thresholds (novelty in units of the case base's usual held-out distance,
    benefit in [0, 1]) and the revision step."""

    novelty_threshold: float = 0.5
    benefit_threshold: float = 0.2
    rate: float = 0.25
    relabel_margin: float = 0.5

    def __post_init__(self) -> None:
        if not (np.isfinite(self.novelty_threshold) and self.novelty_threshold >= 0):
            raise ParameterError(
                f"must be a number >= 0, got {self.novelty_threshold!r}", "novelty_threshold"
            )
        if not (np.isfinite(self.benefit_threshold) and 0 <= self.benefit_threshold <= 1):
            raise ParameterError(
                f"must be in [0, 1], got {self.benefit_threshold!r}", "benefit_threshold"
            )


def classify_with_feedback(
    store: CaseStore,
    stored: StoredClassifier,
    clips: Sequence[PoseSequence],
    label: str,
    settings: FeedbackSettings = FeedbackSettings(),
    target: str = "label",
) -> list[Classification]:
    """Classify every clip, then learn from its true ``label`` (checked by
    :func:`check_feedback_label` first): retain it as a new case when it is novel and
    beneficial (always, for the first clip of a new activity; never when its case is stored
    already, the same frames and poses: it would vote twice), otherwise revise the case base
    toward it. One transaction per clip. Refused for a case base of repetitions or windows
    (:func:`check_feedback_cases`). Each answer is judged against ``label`` (the user's word,
    whatever label the clip's file carries: it is the one stored)."""
    check_feedback_cases(stored)
    out = []
    truth = label
    learnt: list[str] = []  # the clips whose feedback is stored, in order
    try:
        for clip in progress(clips, desc="classifying", total=len(clips), unit="clip"):
            out.append(_feedback(store, stored, clip, truth, target, label, settings, learnt))
        # a large case base: its matrices follow the change (an error here, after every
        # clip's feedback committed, says it is stored, as one between the clips does)
        write_matrices(store, stored.name)
    except KeyboardInterrupt:
        raise FeedbackInterrupted(learnt, len(clips)) from None
    except CaseBaseGone:  # what was stored went with the case base: nothing of it is left
        raise
    except PosecbrError as exc:  # the store locked or lost: said alone, the feedback stored
        # before it was taken for none, and run again its clips were learnt from twice
        if learnt:
            exc.add(f"before it, {feedback_stored(learnt, len(clips))}")
        raise
    return out


def _feedback(
    store: CaseStore,
    stored: StoredClassifier,
    clip: PoseSequence,
    truth: str,
    target: str,
    label: str,
    settings: FeedbackSettings,
    learnt: list[str],
) -> Classification:
    """One clip of :func:`classify_with_feedback`: classified, then learnt from."""
    c = classify_clip(stored, clip, truth, target)
    if c.solved is not None:
        try:
            dec, rev = _learn(store, stored, clip, c.solved, label, settings, learnt)
        except StaleCaseError:  # a case changed under us: read again, decide again
            stored = _reload(store, stored)
            c = classify_clip(stored, clip, truth, target)
            assert c.solved is not None
            dec, rev = _learn(store, stored, clip, c.solved, label, settings, learnt)
        c = Classification(
            c.source, truth, c.solved, c.explanation, None, rev, dec, c.made_from, c.frames,
            c.origin,
        )  # fmt: skip
    return c


class FeedbackInterrupted(KeyboardInterrupt):
    """Ctrl-C during ``classify --feedback``: says whose feedback is stored (each clip's is one
    transaction: those before are in the case base, the one under way is not)."""

    def __init__(self, learnt: Sequence[str], n_clips: int) -> None:
        super().__init__(feedback_stored(learnt, n_clips))
        self.learnt = tuple(learnt)


def feedback_stored(learnt: Sequence[str], n_clips: int) -> str:
    """Whose feedback of ``n_clips`` clips is stored: ``learnt``'s (each clip's is one
    transaction: those before are in the case base, the one under way is not)."""
    if len(learnt) == n_clips:
        return f"the feedback of every clip ({n_clips}) is stored in the case base"
    if learnt:
        return (
            f"the feedback of {len(learnt)} of the {n_clips} clips is stored in the case "
            f"base (the last: {shown(Path(learnt[-1]).name)}); the others' is not"
        )
    return "no clip's feedback is stored: the case base is as it was"


def _revised(rev: Revision | None) -> bool:
    """Whether the revision changes a stored case (moves its problem or relabels it)."""
    return rev is not None and rev.case_id >= 0 and rev.action in ("moved", "relabelled")


def _reload(store: CaseStore, stored: StoredClassifier) -> StoredClassifier:
    """The stored classifier read again (in place, so callers holding it see the new one),
    voting with the k it voted with (``classify -k``), not the one stored."""
    fresh = load_classifier(store, stored.name)
    fresh.classifier.set_params(k=stored.classifier.k)
    if fresh.uid != stored.uid:
        raise CaseBaseGone(
            f"case base {stored.name!r} was replaced by another process while classifying; "
            "nothing more was written",
            store.where,
        )
    stored.classifier, stored.version, stored.info = fresh.classifier, fresh.version, fresh.info
    return stored


def _learn(
    store: CaseStore,
    stored: StoredClassifier,
    clip: PoseSequence,
    solved: Solved,
    label: str,
    settings: FeedbackSettings,
    learnt: list[str],
) -> tuple[RetainDecision, Revision | None]:
    """Decide on the in-memory case base, write in one checked transaction, then follow the
    committed change in memory."""
    clf = stored.classifier
    cb = clf.case_base_
    values = np.asarray(solved.problem.values)
    new_class = label not in set(cb.labels.tolist())
    dec = decide_retention(
        cb,
        solved.problem,  # its fills of features never shown left out, as solve leaves them
        label,
        scale=clf.novelty_.scale,
        k=int(clf.k),
        novelty_threshold=settings.novelty_threshold,
        benefit_threshold=settings.benefit_threshold,
        weights=clf.weights,  # type: ignore[arg-type]
    )
    if new_class and not dec.retained:  # a new activity's first clip: nothing else to revise
        dec = RetainDecision(True, dec.novelty, dec.benefit, f"retained: first case of {label!r}")
    rev = None
    if not dec.retained:
        rev = plan_revision(
            cb, solved.problem, label, rate=settings.rate, relabel_margin=settings.relabel_margin
        )
    digest = poses_digest(clip)  # what tells a copy of it (train --append)
    with store.transaction() as tx:
        info = tx.expect(stored.name, stored.uid)
        twin = tx.case_of_poses(info, digest, frames_of(clip)) if dec.retained else None
        if twin is not None:  # its case would vote twice: revised as a clip not retained is
            why = f"not retained: the same frames and poses as case #{twin}, stored already"
            dec = RetainDecision(False, dec.novelty, dec.benefit, why)
            rev = plan_revision(
                cb,
                solved.problem,
                label,
                rate=settings.rate,
                relabel_margin=settings.relabel_margin,
            )
        case_id = record_retention(
            tx,
            info,
            dec,
            values,
            label,
            source=clip.source,
            subject=subject_of(clip),
            frames=frames_of(clip),
            skeleton=skeleton_of(clip),
            poses=digest,
        )
        new = (  # the case not moved toward the fills of features the clip never showed
            record_revision(tx, info, rev, observed(solved.problem)) if rev is not None else None
        )
        changed = case_id is not None or _revised(rev)
        if changed:
            judges_after_change(tx, info)
    learnt.append(clip.source)  # committed
    if case_id is not None:
        cb.add(
            values,
            label,
            case_id=case_id,
            source=clip.source,
            subject=subject_of(clip),
            frames=frames_of(clip),
            skeleton=skeleton_of(clip),
            poses=digest,
        )
    if rev is not None and rev.action == "relabelled":
        cb.set_label(rev.index, rev.new_label)
    elif rev is not None and new is not None:
        cb.set_problem(rev.index, new)
    if changed:
        clf.judges_ = {}  # calibrated on the cases as they were
    clf.refresh()
    if info.version != stored.version:  # another process changed the cases meanwhile
        _reload(store, stored)
    else:
        stored.version = info.version + 1
    return dec, rev
