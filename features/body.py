"""Pose geometry in the person's own terms, per clip: the left-right mirror image, the plane in
which each upper arm is raised, the limb joints' positions in the body frame at the start of
the clip, and which side moves more. Each is computed once per sequence object
(:mod:`features.derived`).

positions are ``(frames, joints, 3)`` metres, y up, on the canonical skeleton.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from functools import cache

import numpy as np

from .derived import derived, signals_of
from .errors import DataError
from .geometry import (
    MIN_LINK_M,
    WORLD_UP,
    angle_between,
    body_frame,
    hips_unseen,
    midpoint,
    norm,
    project,
    unit,
)
from .nanstats import over_seen
from .poses import PoseSequence
from .skeleton import BLAZEPOSE_33, JOINT_INDEX

# Joints whose body-frame positions :func:`body_positions` gives (three columns each).
_POSITION_PARTS = ("shoulder", "elbow", "wrist", "index", "hip", "knee", "ankle", "heel")
POSITION_JOINTS = ("nose",) + tuple(
    f"{side}_{part}" for part in (*_POSITION_PARTS, "foot_index") for side in ("left", "right")
)
POSITION_AXES = ("left", "height", "forward")

# Extra named angles not among the state signals: the plane of elevation of each upper arm
# (its direction in the horizontal plane: 0 = forward, pi/2 = straight out to the side, pi =
# backward), defined while the arm is raised at least 45 degrees from the trunk (elsewhere the
# horizontal projection is too short to have a direction). It tells shoulder abduction (pi/2)
# from scaption (between forward and sideways), which the sagittal / frontal angles blur.
ARM_PLANE_SIGNALS = ("left_upper_arm_plane", "right_upper_arm_plane")
_ARM_PLANE_MIN_ELEVATION = np.radians(45.0)


def swap_side(name: str) -> str:
    """``name`` with left and right exchanged (``"left_knee"`` -> ``"right_knee"``)."""
    return name.replace("left", "\0").replace("right", "left").replace("\0", "right")


MIRRORED = " (mirrored)"


def mirror_source(source: str) -> str:
    """The source of the mirror image of a sequence from ``source``: `` (mirrored)`` added, or
    taken off a mirror image's (the mirror of a mirror image is the original)."""
    if source.endswith(MIRRORED):
        return source.removesuffix(MIRRORED)
    return source + MIRRORED


def mirrored(seq: PoseSequence) -> PoseSequence:
    """The left-right mirror image of ``seq``: x negated (a reflection, y stays up) and every
    left joint swapped with its right twin, so the left arm's movement becomes the right arm's.
    Canonical joints; cached per sequence object."""

    def compute(s: PoseSequence) -> PoseSequence:
        c = s.to_canonical()
        swap = np.array([JOINT_INDEX[swap_side(n)] for n in BLAZEPOSE_33])
        pos = c.positions[:, swap, :].copy()
        pos[..., 0] *= -1.0
        conf = None if c.confidence is None else c.confidence[:, swap]
        return dataclasses.replace(
            c, positions=pos, confidence=conf, source=mirror_source(c.source)
        )

    return derived(seq, "mirror", compute)


def arm_planes(seq: PoseSequence) -> np.ndarray:
    """Plane-of-elevation angles (radians) of the left and right upper arm, ``(frames, 2)``;
    NaN where the arm is raised less than 45 degrees or joints are missing. A clip without
    hips: in the frame of its shoulders and the world's up, raised from that frame's down
    (:data:`features.signals.HIPLESS`)."""

    def compute(s: PoseSequence) -> np.ndarray:
        p = s.to_canonical().positions
        hipless = hips_unseen(p)  # the frame of the shoulders and the world's up
        bf = body_frame(p, hipless)
        cols = []
        for side in ("left", "right"):
            sh, el, hip = (p[:, JOINT_INDEX[f"{side}_{j}"]] for j in ("shoulder", "elbow", "hip"))
            plane = angle_between(project(el - sh, bf.up), bf.forward)
            trunk = -bf.up if hipless else hip - sh  # as the armpit angle reads it
            raised = angle_between(el - sh, trunk) >= _ARM_PLANE_MIN_ELEVATION
            cols.append(np.where(raised, plane, np.nan))
        return np.stack(cols, axis=1)

    return derived(seq, "arm_planes", compute)


def body_positions(seq: PoseSequence) -> np.ndarray:
    """Positions of :data:`POSITION_JOINTS` in the person's frame at the start of the clip,
    ``(frames, 3 * len(POSITION_JOINTS))``, joint-major, axes :data:`POSITION_AXES`.

    Origin: the mid-hip over the first tenth of the clip (at least 3 frames, from the first
    that shows the hips: :func:`start_rows`); axes: "left"
    along the level left-right line of the body there, "height" straight up, "forward"
    completing a right-handed frame (the way the chest faces); unit: the person's torso length
    (median neck to mid-hip), so people of different sizes compare. How far the hips drop in a
    squat, how high and how far forward a wrist goes, a knee drifting inwards: the range and
    path of a movement, which joint angles alone do not give. NaN where joints are missing."""
    return derived(seq, "body_positions", _body_positions)


def _body_positions(s: PoseSequence) -> np.ndarray:
    rows = frame_rows(s)
    at = start_rows(rows[:, :3], start_frames(s.n_frames))
    frame = frame_from(rows[at, :3], rows[at, 3:6], rows[:, 6], lambda: rows[:, 3:6])
    return positions_in_frame(s.to_canonical().positions, frame)


def start_rows(mid_hip: np.ndarray, k: int) -> slice:
    """The ``k`` frames that set a clip's :func:`position_frame`, of its mid-hips ``(frames,
    3)``: from the first in which the hips are seen (from the first frame when none is).
    Before, the clip's first ``k`` whatever they showed: a clip whose first tenth lacks the
    person (a window of a recording that starts before the pose model finds them) had no
    position at all, and was unlike every case."""
    seen = np.flatnonzero(~np.isnan(mid_hip).any(axis=1))
    first = int(seen[0]) if len(seen) else 0
    return slice(first, first + k)


def frame_rows(seq: PoseSequence) -> np.ndarray:
    """What :func:`position_frame` reads of every frame of the canonical clip, ``(frames,
    7)``: the mid-hip (3), the level left direction (3) and the neck to mid-hip length (1).
    Per frame, so a stretch of a clip shares its clip's rows (:func:`features.derived.stretch`)
    and a recording's windows each set their own frame without computing body axes again."""

    def compute(s: PoseSequence) -> np.ndarray:
        p = s.to_canonical().positions
        bf = body_frame(p)
        return np.concatenate([bf.mid_hip, bf.level_left, neck_to_hip(p)[:, None]], axis=1)

    return derived(seq, "frame_rows", compute)


def start_frames(frames: int) -> int:
    """How many frames at the start of a clip set its body frame: a tenth, at least 3
    (from the first that shows the hips, :func:`start_rows`)."""
    return max(3, frames // 10)


def neck_to_hip(p: np.ndarray) -> np.ndarray:
    """``(frames,)`` neck to mid-hip length of canonical positions ``(frames, 33, 3)``."""
    neck = 0.5 * (p[:, JOINT_INDEX["left_shoulder"]] + p[:, JOINT_INDEX["right_shoulder"]])
    mid_hip = 0.5 * (p[:, JOINT_INDEX["left_hip"]] + p[:, JOINT_INDEX["right_hip"]])
    return np.asarray(norm(neck - mid_hip))


def mid_hips(p: np.ndarray) -> np.ndarray:
    """``(frames, 3)`` mid-hip of canonical positions ``(frames, 33, 3)`` (NaN where a hip is
    missing), as :func:`features.geometry.body_frame` gives it."""
    return midpoint(p[:, JOINT_INDEX["left_hip"]], p[:, JOINT_INDEX["right_hip"]])


def position_frame(
    start: np.ndarray, torso_lengths: np.ndarray, level_left: Callable[[], np.ndarray]
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The frame :func:`body_positions` measures in: origin ``(3,)``, axes ``(3, 3)`` (rows:
    left, height, forward) and unit (the torso length), or None where the clip has none.

    start: the :func:`start_frames` frames from the first that shows the hips ``(k, 33, 3)``
    (:func:`start_rows`); torso_lengths: every frame's
    :func:`neck_to_hip` ``(frames,)``; level_left: the whole clip's level left directions
    ``(frames, 3)``, asked for only when the start has none (so a long clip can give them a
    piece at a time)."""
    bf = body_frame(start)  # the frame is set at the start; later frames need no axes
    return frame_from(bf.mid_hip, bf.level_left, torso_lengths, level_left)


def frame_from(
    mid_hip: np.ndarray,
    left: np.ndarray,
    torso_lengths: np.ndarray,
    level_left: Callable[[], np.ndarray],
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """:func:`position_frame` from the start's mid-hips and level left directions ``(k,
    3)`` (of :func:`features.geometry.body_frame`). NaN-skipping means and median written
    out: numpy's ``nanmean``/``nanmedian`` cost more than the arithmetic on a window's few
    frames, and a recording's windows each set a frame."""
    origin = _nanmean_rows(mid_hip)
    mean_left = _nanmean_rows(left)
    if not np.isfinite(mean_left).all():
        mean_left = _nanmean_rows(level_left())
    torso = _nanmedian(torso_lengths)
    unit_left = unit(mean_left)  # a mean of level directions: level already
    axes = np.stack([unit_left, WORLD_UP, _cross(unit_left, WORLD_UP)])  # left, height, forward
    if not (np.isfinite(axes).all() and np.isfinite(origin).all() and torso > 0):
        return None
    return origin, axes, torso


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of two ``(3,)`` vectors, the same products and differences written
    out (``np.cross`` costs a hundred times the arithmetic on one pair)."""
    return np.array([
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ])  # fmt: skip


def _nanmean_rows(a: np.ndarray) -> np.ndarray:
    """``np.nanmean(a, axis=0)`` of ``(n, 3)`` without its warning: NaN for a column without
    a number."""
    seen = ~np.isnan(a)
    count = seen.sum(axis=0)
    total = np.where(seen, a, 0.0).sum(axis=0)
    return np.asarray(np.divide(total, count, out=np.full(a.shape[1], np.nan), where=count > 0))


def _nanmedian(x: np.ndarray) -> float:
    """``np.nanmedian(x)`` of ``(n,)``: the middle number (the mean of the two middle ones),
    NaN without numbers."""
    x = x[~np.isnan(x)]
    n = x.size
    if n == 0:
        return float("nan")
    k = n // 2
    if n % 2:
        return float(np.partition(x, k)[k])
    part = np.partition(x, (k - 1, k))
    return float((part[k - 1] + part[k]) / 2.0)


def positions_in_frame(
    p: np.ndarray, frame: tuple[np.ndarray, np.ndarray, float] | None
) -> np.ndarray:
    """:func:`body_positions` of canonical positions ``(frames, 33, 3)`` in ``frame`` (a
    :func:`position_frame`; None: all NaN), ``(frames, 3 * len(POSITION_JOINTS))``."""
    if frame is None:
        return np.full((p.shape[0], 3 * len(POSITION_JOINTS)), np.nan)
    origin, axes, torso = frame
    joints = np.take(p, _POSITION_INDEX, axis=1)  # a new array: shifted in place
    joints -= origin
    # one (frames * joints, 3) product per block of frames, not one small product per frame
    rows = joints.reshape(-1, 3)
    out = np.empty_like(rows)
    step = _PRODUCT_FRAMES * len(_POSITION_INDEX)
    for a in range(0, len(rows), step):
        np.matmul(rows[a : a + step], axes.T, out=out[a : a + step])
    out /= torso
    return out.reshape(p.shape[0], -1)


_PRODUCT_FRAMES = 1024
"""Frames of :func:`positions_in_frame`'s product at a time. BLAS (OpenBLAS, as numpy ships
it) hands a product of more than 2^18 multiply-adds to all its threads, and a 3 x 3 rotation
of a 20,000-frame piece's joints split that way took 630 ms on a busy 2-core machine against
42 ms on one thread (a 10-minute recording at 120 fps computes four such pieces twice). The
blocks stay under that size; each row's product is the same arithmetic either way."""


_POSITION_INDEX = np.array([JOINT_INDEX[j] for j in POSITION_JOINTS])


@cache
def position_names() -> tuple[str, ...]:
    """Column names of :func:`body_positions`: ``"left_wrist.height"``, ..."""
    return tuple(f"{j}.{a}" for j in POSITION_JOINTS for a in POSITION_AXES)


def position_word(name: str) -> str:
    """A :func:`position_names` column in words: ``"left wrist height"``."""
    joint, axis = name.split(".")
    return f"{joint.replace('_', ' ')} {'to the left' if axis == 'left' else axis}"


def moves_left_more(seq: PoseSequence) -> bool:
    """Whether the clip's left limbs move more than its right ones: the summed standard
    deviation over time of the left elbow, knee, armpit, hip and upper-limb angles against
    that of their right twins (NaN frames ignored; a missing side counts as still)."""

    def compute(s: PoseSequence) -> bool:
        sig = signals_of(s)
        return left_moves_more(sig.values[:, : len(sig.angle_names)], sig.angle_names)

    return derived(seq, "left_side", compute)


def left_moves_more(angles: np.ndarray, names: tuple[str, ...]) -> bool:
    """:func:`moves_left_more` from the angle signals ``(frames, len(names))``."""
    left = [i for i, n in enumerate(names) if n.startswith("left_")]
    right = [names.index("right_" + names[i][len("left_") :]) for i in left]
    spread = np.nan_to_num(over_seen(np.nanstd, angles, 0), nan=0.0)  # all-NaN columns: 0
    return bool(spread[left].sum() > spread[right].sum())


TORSO_JOINTS = ("left_shoulder", "right_shoulder", "left_hip", "right_hip")


def torso_share(seq: PoseSequence) -> float:
    """Share of the frames in which the torso (both shoulders and both hips) is seen, with
    distinct shoulders and hips: without a torso there is no body frame, so no fluent, angle or
    position of that frame can be computed. 0 for a clip with no person in it."""

    return float(np.mean(torso_rows(seq)))


def long_runs(mask: np.ndarray, length: float) -> np.ndarray:
    """``mask`` ``(n,)`` kept only in its runs of at least ``length`` samples."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    out = np.zeros(len(mask), dtype=bool)
    for a, b in zip(edges[::2], edges[1::2], strict=True):  # over the runs, not the frames
        if b - a >= length:
            out[a:b] = True
    return out


def majority(mask: np.ndarray, width: int) -> np.ndarray:
    """``mask`` ``(n,)`` with each sample the majority of the ``width`` samples (odd) centred
    on it: a running median of a yes/no signal, which drops its runs shorter than half
    ``width`` and keeps where a longer run begins and ends. Within half ``width`` of an end,
    the majority of the ``width`` samples nearest that end (of a shorter ``mask``, of the
    most it holds, an odd number): a run at an end goes or stays by its length as one
    inside does (before, of as many samples on either side as there were on both, the first
    and last alone: the pose model "seeing" the person in the first frames of a stretch
    with nobody in view stayed)."""
    n = len(mask)
    half = min(width // 2, (n - 1) // 2)
    count = np.concatenate([[0], np.cumsum(mask, dtype=np.int64)])
    centre = np.clip(np.arange(n), half, n - 1 - half)
    return np.asarray(2 * (count[centre + half + 1] - count[centre - half]) > 2 * half + 1)


def torso_rows(seq: PoseSequence) -> np.ndarray:
    """``(frames,)`` whether each frame shows the torso as :func:`torso_share` counts it. Per
    frame, so a stretch of a clip shares its clip's rows (:func:`features.derived.stretch`):
    a recording's windows each ask."""

    return derived(seq, "torso_rows", lambda s: torso_seen(s.to_canonical().joints(TORSO_JOINTS)))


def torso_seen(torso: np.ndarray) -> np.ndarray:
    """``(...)`` whether each pose of ``torso`` ``(..., 4, 3)`` (the :data:`TORSO_JOINTS`, in
    order) shows the torso as :func:`torso_share` counts it: all four seen, the shoulders
    distinct and the hips distinct (at least :data:`~features.geometry.MIN_LINK_M` apart, as
    the body frame needs)."""
    seen = np.isfinite(torso).all(axis=(-2, -1))
    shoulders = norm(torso[..., 0, :] - torso[..., 1, :]) >= MIN_LINK_M
    hips = norm(torso[..., 2, :] - torso[..., 3, :]) >= MIN_LINK_M
    return np.asarray(seen & shoulders & hips)


def no_person(seq: PoseSequence) -> str:
    """Why ``seq``, no frame of which shows the torso (:func:`torso_share` 0), shows no person,
    in words: its torso joints are missing, or they are all there but the shoulders or the hips
    lie within :data:`~features.geometry.MIN_LINK_M` of each other (a pose at micrometre
    scale, not in metres, or every joint at one point). Torso joints missing in every frame
    while the others are seen in some (the hips out of view below a close-up's bottom edge)
    are named: "shows no person" said of a clip showing a person's shoulders and arms was
    wrong."""
    if np.isfinite(seq.to_canonical().joints(TORSO_JOINTS)).all(axis=(-2, -1)).any():
        return (
            f"shows no person (its shoulders or hips lie within {MIN_LINK_M * 1e6:g} µm of each"
            " other in every frame: positions must be metres)"
        )
    return no_torso(seq) or "shows no person (no frame with a torso)"


def no_torso(seq: PoseSequence) -> str | None:
    """How ``seq`` shows no torso when some :data:`TORSO_JOINTS` are missing in every frame
    and the others are seen in some (the hips out of view below a close-up's bottom edge, or
    not recorded), naming them ("shows no torso (no frame shows its left hip, right hip)");
    None when every one is missing throughout, or none is."""
    missing = torso_missing(seq)
    if 0 < len(missing) < len(TORSO_JOINTS):  # the rest seen: out of view, or not recorded
        named = ", ".join(j.replace("_", " ") for j in missing)
        return f"shows no torso (no frame shows its {named})"
    return None


def torso_missing(seq: PoseSequence) -> list[str]:
    """The :data:`TORSO_JOINTS` of ``seq`` missing in every frame (a skeleton without hips,
    a pose model that never found the shoulders), in order."""
    seen = np.isfinite(seq.to_canonical().joints(TORSO_JOINTS)).all(axis=-1).any(axis=0)
    return [j for j, s in zip(TORSO_JOINTS, seen, strict=True) if not s]


def arms_alone(seq: PoseSequence) -> bool:
    """Whether ``seq`` shows neither hip in any frame but the upper body in some: both
    shoulders, distinct as the torso's must be, and an elbow (the hips out of view: a patient
    filmed seated or close to the camera). Its arms' movement can be followed, from the
    shoulders, elbows and wrists alone, where nothing that needs the body frame can. One hip
    seen is no such clip: a hip missing throughout beside the other is a defect of the data."""
    p = seq.to_canonical().joints(TORSO_JOINTS + ("left_elbow", "right_elbow"))
    seen = np.isfinite(p).all(axis=-1)  # (frames, 6)
    if seen[:, 2:4].any():
        return False
    shoulders = norm(p[:, 0] - p[:, 1]) >= MIN_LINK_M  # NaN (not seen): False
    return bool((shoulders & seen[:, 4:].any(axis=-1)).any())


def shoulders_only(torso: np.ndarray) -> np.ndarray:
    """``(...)`` whether each pose of ``torso`` ``(..., 4, 3)`` (the :data:`TORSO_JOINTS`, in
    order) shows both shoulders, distinct as the torso's must be, and neither hip (the hips
    out of view): the person seen from the shoulders up, whose arms the frame of the
    shoulders and the world's up follows (:func:`features.geometry.shoulder_axes`). A pose
    with one hip seen is not (:func:`arms_alone`)."""
    hips = np.isfinite(torso[..., 2:, :]).all(axis=-1).any(axis=-1)
    shoulders = norm(torso[..., 0, :] - torso[..., 1, :]) >= MIN_LINK_M  # NaN: False
    return np.asarray(shoulders & ~hips)


def shown_rows(seq: PoseSequence, alone: bool) -> np.ndarray:
    """``(frames,)`` whether each frame shows the person: the torso (:func:`torso_rows`),
    or, of a recording shown from the shoulders up (``alone``: :func:`arms_alone` with no
    frame showing the torso), both shoulders, distinct, as the frame of the shoulders and the
    world's up needs (:func:`features.geometry.shoulder_axes`)."""
    if not alone:
        return torso_rows(seq)
    sh = seq.to_canonical().joints(("left_shoulder", "right_shoulder"))
    return np.asarray(norm(sh[:, 0] - sh[:, 1]) >= MIN_LINK_M)  # NaN (not seen): False


def check_person(seq: PoseSequence, nothing_to: str, arms: bool = False) -> None:
    """Refuse ``seq`` (a DataError naming its source) when no frame of it shows the person:
    the torso, without which no angle or position has a body frame (:func:`torso_share` 0;
    :func:`no_person` says why). The one check ``segment`` and ``reps`` make of a recording
    (before, ``reps`` counted one with no hips from an elbow, one with no shoulders from the
    knees, one at micrometre scale from the hips' height, where ``segment`` refused it);
    ``nothing_to``: what the refusal says cannot be done ("segment", "count"). ``arms``:
    a recording that shows the arms without the hips (:func:`arms_alone`) passes, ``reps``
    counting an arm exercise filmed close up from the arms alone, ``segment`` labelling it
    from its arms (it was refused as showing no person)."""
    if torso_share(seq) == 0.0 and not (arms and arms_alone(seq)):
        raise DataError(f"{no_person(seq)}: nothing to {nothing_to}", seq.source or None)
