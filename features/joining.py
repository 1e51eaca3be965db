"""Joining single repetitions into one recording whose count and labels are known exactly.

Datasets of segmented repetitions (UI-PRMD: one file per repetition; HDM05: one-repetition
clips) give an exact ground truth for repetition counting when K repetitions of one person
and one movement are played one after the other, and for segmentation when the repetitions
of several movements follow one another (each frame labelled with the movement of the
repetition it comes from). Each repetition starts and ends near rest,
but the person stood elsewhere in the room and faced another way in each take, and the rest
postures differ a little: every repetition is turned about the vertical and shifted along
the floor so that its first frame stands where and faces as the previous one's last frame
did (the joint angles are untouched), and the remaining jump between the two postures is
bridged by :data:`BLEND_S` of linear blending (frames added, nothing of a repetition lost).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .errors import DataError
from .poses import PoseSequence
from .skeleton import JOINT_INDEX

BLEND_S = 0.1
"""Seconds of linear blending inserted between two repetitions (3 frames at 30 fps)."""


@dataclass(frozen=True)
class Joined:
    """The joined recording, the frame where each repetition starts in it ``(K,)`` (the
    blends lie before them, from the second on), and the largest joint jump (metres) that
    the blends bridged between consecutive repetitions ``(K - 1,)``; ``labels``: when the
    repetitions were labelled, the label of every frame ``(frames,)`` (object): each
    repetition's own, a blend's first half that of the repetition before it, its second
    half that of the one after (a change of movement lies mid-blend)."""

    seq: PoseSequence
    starts: np.ndarray
    jumps_m: np.ndarray
    labels: np.ndarray | None = None


def _heading(frame: np.ndarray) -> float:
    """The angle about the vertical (y) of the left-to-right hip line of one canonical frame
    ``(33, 3)`` (radians)."""
    d = frame[JOINT_INDEX["right_hip"]] - frame[JOINT_INDEX["left_hip"]]
    return float(np.arctan2(d[2], d[0]))


def _mid_hip(frame: np.ndarray) -> np.ndarray:
    return np.asarray(0.5 * (frame[JOINT_INDEX["left_hip"]] + frame[JOINT_INDEX["right_hip"]]))


def _hips_known(p: np.ndarray) -> np.ndarray:
    """The frames of ``p`` ``(frames, 33, 3)`` whose hips are both known, ``(k,)``."""
    hips = p[:, [JOINT_INDEX["left_hip"], JOINT_INDEX["right_hip"]]]
    return np.flatnonzero(np.isfinite(hips).all(axis=(1, 2)))


def _rest_frame(p: np.ndarray, last: bool) -> np.ndarray:
    """The first (or last) frame of ``p`` ``(frames, 33, 3)`` whose hips are both known."""
    ok = _hips_known(p)
    return np.asarray(p[ok[-1] if last else ok[0]])


def _placed(p: np.ndarray, after: np.ndarray) -> np.ndarray:
    """``p`` ``(frames, 33, 3)`` turned about the vertical and shifted along the floor so that
    its first frame faces and stands as the frame ``after`` ``(33, 3)`` does."""
    first = _rest_frame(p, last=False)
    turn = _heading(after) - _heading(first)
    c, s = np.cos(turn), np.sin(turn)
    # rotation about y taking heading h to h + turn (x, z plane; y stays)
    rot = np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])
    pivot = _mid_hip(first)
    out = (p - pivot) @ rot.T + pivot
    shift = _mid_hip(after) - pivot
    shift[1] = 0.0  # along the floor only: the height of the hips is the posture's own
    return np.asarray(out + shift)


def join_repetitions(
    reps: Sequence[PoseSequence], blend_s: float = BLEND_S, labels: Sequence[str] | None = None
) -> Joined:
    """``reps`` (canonical :class:`PoseSequence` s of one frame rate, positions
    ``(frames, 33, 3)``) played one after the other (see the module docstring), of one
    movement or several; ``labels``: the movement of each repetition ``(K,)``, to label
    every frame of the result (:attr:`Joined.labels`). The recording keeps the metadata its
    repetitions hold alike (:func:`_shared_metadata`): the first repetition's label of
    correct or incorrect, its episode and the file it was converted from were the whole
    recording's. Its ``source`` is every repetition's, in order, joined by :data:`JOINED_BY`
    (:func:`joined_source`): it was the first repetition's, so the recording was named by
    one file it holds a part of, saved as made from it, and two recordings that begin with
    the same repetition were taken for one (a training case's source is the recording its
    held-out checks leave out). Name it otherwise with ``dataclasses.replace(seq,
    source=...)``; ``with_metadata(source=...)`` sets a metadata key, not the source.

    Raises DataError for no repetitions, differing frame rates, a repetition without a
    frame that shows both hips, or as many labels as repetitions not given."""
    if not reps:
        raise DataError("no repetitions to join")
    if labels is not None and len(labels) != len(reps):
        raise DataError(f"{len(labels)} labels for {len(reps)} repetitions to join")
    fps = reps[0].fps
    if any(abs(r.fps - fps) > 1e-6 for r in reps):
        raise DataError("repetitions to join differ in frame rate")
    for rep in reps:
        if not len(_hips_known(rep.to_canonical().positions)):
            raise DataError(
                "no frame shows both hips: cannot place the repetition", rep.source or None
            )
    n_blend = max(1, int(round(blend_s * fps)))
    weights = (np.arange(1, n_blend + 1) / (n_blend + 1))[:, None, None]
    parts = [reps[0].to_canonical().positions]
    starts, jumps = [0], []
    length = len(parts[0])
    for rep in reps[1:]:
        prev = _rest_frame(parts[-1], last=True)
        p = _placed(rep.to_canonical().positions, prev)
        first = p[0]
        jumps.append(float(np.nanmax(np.linalg.norm(first - parts[-1][-1], axis=1))))
        blend = (1.0 - weights) * parts[-1][-1] + weights * first
        parts += [blend, p]
        length += n_blend
        starts.append(length)
        length += len(p)
    seq = replace(
        reps[0].to_canonical(),
        source=joined_source(reps),
        positions=np.concatenate(parts),
        confidence=None,
        metadata={**_shared_metadata(reps), "joined_repetitions": len(reps)},
    )
    starts_a = np.asarray(starts)
    per_frame = (
        None if labels is None else _frame_labels(labels, starts_a, n_blend, len(seq.positions))
    )
    return Joined(seq, starts_a, np.asarray(jumps), per_frame)


JOINED_BY = " + "
"""What separates the repetitions' sources in a joined recording's source."""


def joined_source(reps: Sequence[PoseSequence]) -> str:
    """The source of ``reps`` joined: each one's, in order, those without one left out
    (empty when none has one: a recording without a source, as each of its parts was)."""
    return JOINED_BY.join(r.source for r in reps if r.source)


PIECE_KEYS = ("frame_offset", "origin")
"""Metadata that places a clip in the recording it was cut from: the joined frames lie in
none, so no joined recording keeps it."""


def _shared_metadata(reps: Sequence[PoseSequence]) -> dict[str, Any]:
    """The metadata every repetition of ``reps`` holds alike (the subject, the sensor, the
    movement), without what places a clip in its recording (:data:`PIECE_KEYS`): what one
    repetition alone says (its episode, its label of correct or incorrect, the file it came
    from) is not said of the whole recording."""
    first = reps[0].metadata
    return {
        k: v
        for k, v in first.items()
        if k not in PIECE_KEYS and all(k in r.metadata and r.metadata[k] == v for r in reps[1:])
    }


def _frame_labels(
    labels: Sequence[str], starts: np.ndarray, n_blend: int, n_frames: int
) -> np.ndarray:
    """``(n_frames,)`` object: repetition i's label from the middle of the blend before it
    (the first frame, for the first) to the middle of the blend after it (``n_blend``
    frames before each start but the first)."""
    cuts = np.r_[0, starts[1:] - n_blend + (n_blend + 1) // 2, n_frames]
    return np.repeat(np.asarray(list(labels), dtype=object), np.diff(cuts))
