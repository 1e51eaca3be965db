"""The clips of a comparison (``Prepared``): their targets, subjects and model groups, classes
with a single clip left out."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from features.clips import Clip
from features.errors import DataError
from features.poses import PoseSequence
from features.targets import clip_column, clip_target
from features.text import counted

from .settings import CompareSettings


@dataclass
class Prepared:
    """The clips of one comparison and what is predicted for each.

    seqs ``(n,)`` pose sequences; ids ``(n,)`` clip names; y ``(n,)`` target values (str);
    subjects ``(n,)`` (None when unknown); labels ``(n,)`` activity labels; within ``(n,)``
    the per-model group (or None); classes: sorted target values; frames ``(n,)``: a clip's
    frames in its file (start, end exclusive) when it is a piece of it (a labels CSV's
    ``start,end``), else None (empty: none known); left_out: each clip left out of the
    comparison, as (name, subject, why: "shows no person", "shorter than one movement can be
    (0.4 s)", ...).
    """

    seqs: list[PoseSequence]
    ids: list[str]
    y: np.ndarray
    subjects: list[str | None]
    labels: np.ndarray
    within: np.ndarray | None
    classes: list[str]
    notes: list[str] = field(default_factory=list)
    frames: list[tuple[int, int] | None] = field(default_factory=list)
    left_out: list[tuple[str, str | None, str]] = field(default_factory=list)

    def frames_of(self, i: int) -> tuple[int, int] | None:
        """Clip ``i``'s frames in its file when it is a piece of it, else None."""
        return self.frames[i] if i < len(self.frames) else None


def clip_frames(clip: Clip) -> tuple[int, int] | None:
    """A clip's frames in its file (start, end exclusive) when it is a piece of it, as
    ``classify`` tells one (its ``frame_offset``), else None."""
    from ..casebase import frames_of

    return frames_of(clip.seq) if "frame_offset" in clip.seq.metadata else None


def clip_id(clip: Clip, i: int) -> str:
    """A clip's name for people: its file name, else its position."""
    src = clip.seq.source or clip.extras.get("origin") or ""
    return Path(str(src)).name if src else f"clip {i}"


def _targets(clips: Sequence[Clip], target: str, source: str) -> np.ndarray:
    """Every clip's target value ``(n,)``; a clip without one is an error naming it."""
    values = [clip_target(c, target) for c in clips]
    missing = [i for i, v in enumerate(values) if v is None]
    if missing:
        columns = {k for c in clips for k in c.extras}
        eg = clip_id(clips[missing[0]], missing[0])
        raise no_target_error(len(missing), len(clips), eg, columns, target, source)
    return np.array(values, dtype=object)


def no_target_error(
    missing: int, n: int, eg: str, columns: set[str], target: str, source: str
) -> DataError:
    """``missing`` of ``n`` clips without a value of ``target`` (``eg`` the first one's
    name), with the columns the clips have (besides label and subject)."""
    from features.text import did_you_mean

    cols = sorted({"label", "subject"} | columns)
    return DataError(
        f"{missing} of {n} clips have no value for target {target!r} (e.g. {eg}); "
        f"columns available: {', '.join(cols)}" + did_you_mean(target, cols),
        source,
    )


def too_few_classes(target: str, counts: Counter[str], source: str) -> DataError | None:
    """The refusal of targets (their clips counted in ``counts``) with fewer than two classes
    of two or more clips each; None when there are two."""
    if sum(n >= 2 for n in counts.values()) >= 2:
        return None
    return DataError(
        f"need at least two classes of {target!r} with two or more clips each; "
        f"found {dict(counts)}",
        source,
    )


def _groups(clips: Sequence[Clip], column: str | None, source: str) -> np.ndarray | None:
    """Every clip's model group ``(n,)`` (None when one model serves all clips)."""
    if column is None:
        return None
    return model_groups([clip_column(c, column) for c in clips], column, source)


def model_groups(values: Sequence[Any], column: str, source: str) -> np.ndarray:
    """The clips' model groups ``(n,)`` from their values of ``column``; one without is
    refused."""
    if any(v is None for v in values):
        raise DataError(f"some clips have no {column!r} to group the models by", source)
    return np.array([str(v) for v in values], dtype=object)


def _shown(clips: Sequence[Clip]) -> tuple[list[Clip], list[str], dict[int, str]]:
    """The clips that show a person (some frame shows the torso) for as long as one movement
    can last, and notes naming the others (left out for every method alike: a clip nothing
    can be computed from failed the methods that describe clips, and the comparison crowned
    the others; a clip of a frame or two is what ``classify`` calls unclassifiable). One that
    shows some of the torso's joints, the others in no frame, is said to show no torso,
    naming them (:func:`features.body.no_torso`), as ``classify`` and ``segment`` say it: a
    clip of the shoulders and arms, the hips out of view, was said to show no person. Also
    why each clip left out is, by its position."""
    from features.body import no_torso
    from features.repetitions import MIN_PERIOD_S

    from ..estimator import unusable

    nobody = set(unusable([c.seq for c in clips]))
    short = {i for i, c in enumerate(clips) if c.seq.duration_s < MIN_PERIOD_S} - nobody
    why_none: dict[str, set[int]] = {}
    for i in sorted(nobody):
        why_none.setdefault(no_torso(clips[i].seq) or "shows no person", set()).add(i)
    gone = [
        (ids, "that " + (why if len(ids) == 1 else why.replace("shows ", "show ", 1)))
        for why, ids in why_none.items()
    ]
    shorter = f"shorter than one movement can be ({MIN_PERIOD_S:g} s)"
    if short:
        gone.append((short, shorter))
    notes = [_left_out(clips, ids, why) for ids, why in gone]
    whys = {i: why for why, ids in why_none.items() for i in ids} | dict.fromkeys(short, shorter)
    return [c for i, c in enumerate(clips) if i not in nobody | short], notes, whys


def _left_out(clips: Sequence[Clip], gone: set[int], why: str) -> str:
    names = [clips[i].seq.source or str(clips[i].label) for i in sorted(gone)]
    more = " ..." if len(names) > 5 else ""
    return f"left out {counted(len(names), 'clip')} {why}: {', '.join(names[:5])}{more}"


#: why a clip of a class of a single clip is left out (:attr:`Prepared.left_out`)
SINGLE = "the single clip of its class"


def _single_clip_note(single: list[str]) -> str:
    many = len(single) > 1
    return (
        f"class{'es' if many else ''} {', '.join(single)} ha{'ve' if many else 's'} a single "
        "clip and cannot be cross-validated (a held-out single clip is never in training); "
        "left out of the comparison"
    )


def prepare(clips: Sequence[Clip], settings: CompareSettings, source: str = "dataset") -> Prepared:
    """Targets, subjects and groups of ``clips``; classes with a single clip are dropped with
    a note. Every clip left out (:func:`_shown`) is refused with the notes that say why: it
    was "no clip shows a person", of clips that show the shoulders and arms, the hips out of
    view."""
    if not clips:
        raise DataError("no clips found", source)
    listed = clips
    clips, nobody, whys = _shown(clips)
    left_out = [(clip_id(c, i), c.subject, whys[i]) for i, c in enumerate(listed) if i in whys]
    if not clips:
        raise DataError(f"no clip to compare: {'; '.join(nobody)}", source)
    y = _targets(clips, settings.target, source)
    within = _groups(clips, settings.within_column, source)
    counts = Counter(y)
    single = sorted(c for c, n in counts.items() if n < 2)
    idx = [i for i, v in enumerate(y) if counts[v] >= 2]
    alone = [i for i, v in enumerate(y) if counts[v] < 2]
    classes = sorted({str(v) for v in y[idx]})
    refused = too_few_classes(settings.target, counts, source)
    if refused is not None:
        raise refused
    return Prepared(
        seqs=[clips[i].seq for i in idx],
        ids=[clip_id(clips[i], i) for i in idx],
        y=y[idx],
        subjects=[clips[i].subject for i in idx],
        labels=np.array([str(clips[i].label) for i in idx], dtype=object),
        within=None if within is None else within[idx],
        classes=classes,
        notes=nobody + ([_single_clip_note(single)] if single else []),
        frames=[clip_frames(clips[i]) for i in idx],
        left_out=left_out + [(clip_id(clips[i], i), clips[i].subject, SINGLE) for i in alone],
    )


def example_clips(data: Prepared) -> dict[str, PoseSequence]:
    """One example clip per activity (the first in dataset order), by activity name."""
    out: dict[str, PoseSequence] = {}
    for i, lab in enumerate(data.labels):
        out.setdefault(str(lab), data.seqs[i])
    return dict(sorted(out.items()))
