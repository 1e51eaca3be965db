"""A training clip reduced to what fitting a case base needs of it, computed in one pass.

Fitting used to keep every clip's per-frame fluents (566 states, and those of its mirror image)
in the per-clip caches for the whole fit: about 1.7 MB a clip. :func:`describe_clip` computes a
clip's problem over every candidate column (:func:`cbr.problem.candidate_config`), its mirror
image's, which columns it has, and its provenance, then drops what it computed for the clip
(unless the caller had warmed it and keeps it, as the ``compare`` workers do). What is left is
a :class:`DescribedClip` of a few kilobytes. The fit then chooses the columns from the
availability counts and slices them out (:func:`cbr.problem.column_index`): the same values
:func:`cbr.problem.extract_problem` gives under the resolved configuration, since every step
from confidences to summaries works column by column.

:func:`describe_clip` is a plain function of a clip and a configuration, so it can run where
the clip is read: in this process, clip after clip, or on the workers of a Dask cluster
(``posecbr train --scheduler``); the fit gets the same records either way.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from features.body import mirror_source, moves_left_more, no_torso, torso_share
from features.derived import forget, is_cached
from features.errors import InputError
from features.label_tracks import assumed_rate
from features.poses import PoseSequence

from . import long_clip
from .casebase import CaseBase, frames_of, skeleton_of, subject_of
from .novelty import DESCRIPTION, own_description
from .problem import FeatureConfig, availability, candidate_config, extract_problem, mirror_problem


@dataclass(frozen=True)
class DescribedClip:
    """One clip as the fit sees it.

    values: its problem over the candidate columns (``(n,)`` vector or ``(length, n)``
    sequence); mirror: its mirror image's (None when no side handling needs it); left: whether
    it moves its left side more (None when not needed); available: ``(n_candidates,)`` which
    candidate columns it has (fluent level; empty for QMPs); torso_share: the share of its
    frames that show the person (0: nothing can be learned from it); duration_s: how long it
    lasts (shorter than one movement can be: nothing can be learned from it); provenance:
    ``source``, ``subject``, ``frames`` (start, end) and ``skeleton``; summary: the clip's
    fluent summary over the candidate columns of :data:`cbr.novelty.DESCRIPTION` (what the
    "unlike the stored cases" feature score judges; None when the problem is a fluent summary
    itself) and summary_available which of them it has; columns: the :func:`columns_key` of
    the candidates it was described over ("" when unknown: a record made by hand, or before
    the key was kept), checked by :func:`check_described`; poses: :func:`poses_digest` of the
    clip, what tells a copy of a clip from another clip described alike ("" when unknown);
    rate: the frame rate its file's reader assumed and where from
    (:func:`features.label_tracks.assumed_rate`: an AMC file carries none), None when read
    from the file or given, for the command to say (a library prints nothing); no_torso: of
    a clip no frame of which shows the torso, :func:`features.body.no_torso`'s words when it
    shows some of the torso's joints ("shows no torso (no frame shows its left hip, right
    hip)": the hips out of view), "" otherwise, for the command to say it, not "no person".
    """

    values: np.ndarray
    mirror: np.ndarray | None
    left: bool | None
    available: np.ndarray
    torso_share: float
    source: str
    subject: str | None
    frames: tuple[int, int]
    skeleton: str
    names: tuple[str, ...] | None = None
    words: tuple[str, ...] | None = None
    summary: np.ndarray | None = None
    summary_available: np.ndarray | None = None
    duration_s: float = math.inf
    columns: str = ""
    poses: str = ""
    rate: tuple[float, str] | None = None
    no_torso: str = ""

    @property
    def mirror_source(self) -> str:
        """The provenance of the clip's mirror image (as :func:`features.body.mirrored` names
        it)."""
        return mirror_source(self.source)


def describe_clip(
    seq: PoseSequence, candidates: FeatureConfig, mirror: bool, sides: bool
) -> DescribedClip:
    """``seq`` ``(frames, joints, 3)`` described over ``candidates`` (a
    :func:`cbr.problem.candidate_config`), with its mirror image's problem when ``mirror`` and
    its favoured side when ``sides``. Per-clip caches the caller had not filled are dropped."""
    keep = is_cached(seq, "fluents") or is_cached(seq, "qmp")
    share = torso_share(seq)
    try:
        if share == 0.0:  # no person: nothing to compute, the fit refuses or skips it
            empty = np.zeros(0)
            return DescribedClip(empty, None, None, empty.astype(bool), share,
                                 *_provenance(seq), duration_s=seq.duration_s,
                                 columns=columns_key(candidates),
                                 poses=poses_digest(seq), rate=assumed_fps(seq),
                                 no_torso=no_torso(seq) or "")  # fmt: skip
        plain = candidates if candidates.side == "as_recorded" else _as_recorded(candidates)
        # a long clip is described a piece at a time (cbr.long_clip): problem, mirror image,
        # favoured side and available columns, none of them over the whole clip at once
        chunk = long_clip.chunk_for(seq, None, plain.level)
        problem = extract_problem(seq, plain, chunk)
        image = mirror_problem(seq, plain, chunk).values if mirror else None
        left = None
        if sides:
            left = long_clip.moves_left_more(seq, chunk) if chunk else moves_left_more(seq)
        if plain.level == "fluents":  # columns known from the configuration alone
            has, names, words = availability(seq, plain, chunk), None, None
        else:  # QMP columns come from the action database: a few, shared by every clip
            has = np.zeros(0, dtype=bool)
            names, words = _interned(problem.names), _interned(problem.words)
        return DescribedClip(
            problem.values, image, left, has, share, *_provenance(seq), names, words,
            *_summary(seq, plain), duration_s=seq.duration_s, columns=columns_key(candidates),
            poses=poses_digest(seq), rate=assumed_fps(seq),
        )  # fmt: skip
    finally:
        if not keep:
            forget(seq)


def poses_digest(seq: PoseSequence) -> str:
    """A SHA-256 of ``seq``'s poses: its joints, frame rate, positions and confidences, byte
    for byte. Two clips of one digest are copies of one clip; two clips described alike need
    not be (a few columns, or QMP vectors, of two takes can agree)."""
    digest = hashlib.sha256(json.dumps([list(seq.joint_names), float(seq.fps)]).encode())
    digest.update(np.ascontiguousarray(seq.positions, dtype=np.float64).tobytes())
    if seq.confidence is not None:
        digest.update(np.ascontiguousarray(seq.confidence, dtype=np.float64).tobytes())
    return digest.hexdigest()


def columns_key(candidates: FeatureConfig) -> str:
    """A short key of the candidate columns ``candidates`` names, the same in every process
    (a description made on a cluster's worker is checked by it against the fit's plan)."""
    text = json.dumps(candidates.to_dict(), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def check_described(
    clips: Sequence[object], candidates: FeatureConfig, mirror: bool, sides: bool
) -> None:
    """Refuse, as an :class:`~features.errors.InputError` naming ``clips[i]``, a record that is
    no :class:`DescribedClip` or was described for another fit's plan (other candidate
    columns, or without the mirror image or favoured side this one chooses with): its values
    would be read as columns they are not, a model fitted silently wrong or a raw error."""
    key = columns_key(candidates)
    how = "describe them with this estimator's plan, cbr.training.fit_plan(estimator)"
    for i, c in enumerate(clips):
        if not isinstance(c, DescribedClip):
            raise InputError(
                f"clips[{i}] is a {type(c).__name__}, not a DescribedClip: {how}", "clips"
            )
        if c.torso_share == 0.0:  # no person: described as nothing, refused by the fit
            continue
        if c.columns and c.columns != key:
            why = "over other feature columns than this estimator's"
        elif mirror and c.mirror is None:
            why = "without its mirror image, which this estimator needs"
        elif sides and c.left is None:
            why = "without the side it moves more, which this estimator needs"
        else:
            continue
        raise InputError(f"clips[{i}] was described {why}: {how}", "clips")


def _summary(
    seq: PoseSequence, plain: FeatureConfig
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The clip's :data:`~cbr.novelty.DESCRIPTION` over its candidate columns and which of
    them it has, when its problem under ``plain`` is not a fluent summary already (the
    fluents computed for a fluent sequence are reused from the clip's cache)."""
    if own_description(plain):
        return None, None
    candidates = candidate_config(DESCRIPTION)
    chunk = long_clip.chunk_for(seq, None, "fluents")
    values = extract_problem(seq, candidates, chunk).values
    return values, availability(seq, candidates, chunk)


_INTERNED: dict[tuple[str, ...], tuple[str, ...]] = {}


def _interned(names: tuple[str, ...]) -> tuple[str, ...]:
    """One tuple object per distinct column list, however many clips name it."""
    return _INTERNED.setdefault(names, names)


def _as_recorded(config: FeatureConfig) -> FeatureConfig:
    return dataclasses.replace(config, side="as_recorded")


def assumed_fps(seq: PoseSequence) -> tuple[float, str] | None:
    """``seq``'s frame rate and where it came from when its file's reader assumed it
    (:func:`features.label_tracks.assumed_rate`), else None."""
    why = assumed_rate(seq.metadata)
    return (float(seq.fps), why) if why else None


def _provenance(seq: PoseSequence) -> tuple[str, str | None, tuple[int, int], str]:
    return str(seq.source), subject_of(seq), frames_of(seq), skeleton_of(seq)


def describe_clips(
    seqs: Iterable[PoseSequence], candidates: FeatureConfig, mirror: bool, sides: bool
) -> Iterator[DescribedClip]:
    """:func:`describe_clip` of every clip, one at a time (a stream stays a stream)."""
    for seq in seqs:
        yield describe_clip(seq, candidates, mirror, sides)


def describe_case(seq: PoseSequence, casebase: CaseBase) -> DescribedClip:
    """``seq`` ``(frames, joints, 3)`` described as a new case of ``casebase`` (its stored
    columns, nothing chosen anew: ``train --append``); caches the caller had not filled are
    dropped."""
    keep = is_cached(seq, "fluents") or is_cached(seq, "qmp")
    share = torso_share(seq)
    try:
        values = casebase.problem_of(seq).values if share > 0.0 else np.zeros(0)
        return DescribedClip(values, None, None, np.zeros(0, dtype=bool), share,
                             *_provenance(seq), duration_s=seq.duration_s,
                             poses=poses_digest(seq), rate=assumed_fps(seq),
                             no_torso="" if share > 0.0 else no_torso(seq) or "")  # fmt: skip
    finally:
        if not keep:
            forget(seq)
