"""Body frame, plane projections and law-of-cosines angles, vectorised over all frames.
A clip that shows neither hip has its frame from the shoulders and the world's up
(:func:`shoulder_axes`).

Conventions (canonical skeleton): metres, right-handed, y up. For a person, the unit vectors
(forward, left, up) form a right-handed basis: ``left = up x forward``.

The paper's torso normal ``⊥torso = (LS→LH) × (LS→RS)`` points out of the person's back in a
right-handed frame; SPEC.md asks that meaning win over the literal vector, so ``forward`` is
its negation and points the way the chest faces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .skeleton import JOINT_INDEX

# A link (or a projected link) shorter than this is degenerate: its angle is unavailable.
MIN_LINK_M = 1e-6

WORLD_UP = np.array([0.0, 1.0, 0.0])


def _joint(positions: np.ndarray, name: str) -> np.ndarray:
    """One canonical joint, ``(frames, 3)``, from positions ``(frames, 33, 3)``."""
    joint: np.ndarray = positions[:, JOINT_INDEX[name], :]
    return joint


def midpoint(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    mid: np.ndarray = 0.5 * (a + b)
    return mid


def norm(v: np.ndarray) -> np.ndarray:
    """Euclidean length along the last axis: ``(..., 3) -> (...)``."""
    length: np.ndarray = np.sqrt(np.einsum("...i,...i->...", v, v))
    return length


def unit(v: np.ndarray) -> np.ndarray:
    """``v`` scaled to unit length along the last axis; NaN where it is degenerate."""
    n = norm(v)[..., None]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n >= MIN_LINK_M, v / n, np.nan)


def project(v: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Project vectors onto the plane with unit ``normal``: ``v - (v·n) n``; shapes ``(..., 3)``."""
    projected: np.ndarray = v - np.einsum("...i,...i->...", v, normal)[..., None] * normal
    return projected


def angle_between(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Angle in radians between vectors ``u`` and ``v`` (``(..., 3)`` each) -> ``(...)``.

    This is the paper's law of cosines (eq. 1) for the triangle A B C with u = B→A and v = B→C:
    ``|AB|² + |BC|² - |CA|² = 2 (B→A)·(B→C)``, so ``∠B = arccos(u·v / (|u||v|))``. NaN when a
    link is degenerate (shorter than :data:`MIN_LINK_M`) or missing.
    """
    nu = norm(u)
    nv = norm(v)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.einsum("...i,...i->...", u, v) / (nu * nv)
    ok = (nu >= MIN_LINK_M) & (nv >= MIN_LINK_M)
    return np.where(ok, np.arccos(np.clip(cos, -1.0, 1.0)), np.nan)


def joint_angle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Angle at joint ``b`` of the triangle a-b-c (law of cosines); points ``(..., 3)``."""
    return angle_between(a - b, c - b)


@dataclass(frozen=True)
class BodyFrame:
    """Per-frame body axes, each ``(frames, 3)`` unit vectors (NaN where undefined).

    forward: where the chest faces (negated paper ⊥torso); up: mid-hip → neck; left: the
    person's left (``up × forward``); heading: ``forward`` with the pitch removed — the
    horizontal direction the body faces, derived from the horizontal part of ``left`` so that
    it stays defined when the person bends over; level_left: horizontal left.
    """

    forward: np.ndarray
    up: np.ndarray
    left: np.ndarray
    heading: np.ndarray
    level_left: np.ndarray
    neck: np.ndarray
    mid_hip: np.ndarray
    mid_ear: np.ndarray


def body_frame(positions: np.ndarray, hipless: bool = False) -> BodyFrame:
    """Body axes from canonical positions ``(frames, 33, 3)``.

    ``hipless``: the frame of a clip that shows neither hip (:func:`hips_unseen`), from the
    shoulders and the world's up (:func:`shoulder_axes`); its ``mid_hip`` stays NaN, so
    nothing measured from the hips is stated."""
    ls = _joint(positions, "left_shoulder")
    rs = _joint(positions, "right_shoulder")
    lh = _joint(positions, "left_hip")
    rh = _joint(positions, "right_hip")
    neck = midpoint(ls, rs)
    mid_hip = midpoint(lh, rh)
    mid_ear = midpoint(_joint(positions, "left_ear"), _joint(positions, "right_ear"))
    if hipless:
        forward, up, left = shoulder_axes(ls, rs, mid_ear)
    else:
        # -⊥torso = (LS→RS) × (LS→LH): the chest-facing normal in a right-handed frame.
        forward = unit(np.cross(rs - ls, lh - ls))
        up = unit(neck - mid_hip)
        left = unit(np.cross(up, forward))
    level_left = unit(project(left, WORLD_UP))
    heading = unit(np.cross(level_left, WORLD_UP))
    return BodyFrame(forward, up, left, heading, level_left, neck, mid_hip, mid_ear)


UPRIGHT_HEAD = np.radians(60.0)
"""The farthest the head's line (neck to mid-ear) leans from the world's up in a frame whose
trunk :func:`shoulder_axes` takes to be upright: an upright person's neck bends the head
less far forward or back (about 45-50 degrees either way); a head further over is one of a
trunk lying or bent over, whose arms the upright frame would state wrongly (arms by the
sides of a person lying on their back read "in front")."""


def shoulder_axes(
    ls: np.ndarray, rs: np.ndarray, mid_ear: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body axes (forward, up, left) ``(frames, 3)`` each from the shoulders ``(frames, 3)``
    and the world's up, for a clip without hips: ``left`` along the shoulder line (right to
    left shoulder), ``up`` the world's up less its part along that line (the trunk taken to
    be upright: a patient seated, or standing, filmed by an upright camera), ``forward`` their
    cross product (``left × up``, the way the chest faces). The hips' frame has ``left``
    along the shoulders too (``up × forward`` of the torso's plane); what the shoulders cannot
    give is the trunk's lean forward or back, which this frame reads as none. NaN where a
    shoulder is missing, the shoulder line is vertical, or the head (``mid_ear``, the
    midpoint of the ears) leans more than :data:`UPRIGHT_HEAD` from the world's up (the
    trunk is not upright: a person lying or bent over); a frame without the ears is taken
    to be upright."""
    left = unit(ls - rs)
    up = unit(project(np.broadcast_to(WORLD_UP, left.shape), left))
    forward = unit(np.cross(left, up))
    over = angle_between(mid_ear - midpoint(ls, rs), WORLD_UP) > UPRIGHT_HEAD  # NaN: False
    keep = ~over[..., None]
    return np.where(keep, forward, np.nan), np.where(keep, up, np.nan), np.where(keep, left, np.nan)


def hips_unseen(positions: np.ndarray) -> bool:
    """Whether canonical positions ``(frames, 33, 3)`` show neither hip in any frame (the
    hips out of view below a close-up's bottom edge): the body frame is then taken from the
    shoulders (:func:`shoulder_axes`). One hip seen in some frame is no such clip."""
    hips = positions[:, [JOINT_INDEX["left_hip"], JOINT_INDEX["right_hip"]], :]
    return not bool(np.isfinite(hips).all(axis=-1).any())
