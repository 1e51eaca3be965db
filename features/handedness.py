"""Recordings written left-handed: x reflected, left and right joint names kept.

Some exporters (a left-handed coordinate convention in mocap or Kinect tools, a pose file made
from a mirrored video by negating x) write a recording whose x axis is reflected while every
joint keeps its name. Read as it is, the body frame built from the named shoulders and hips
(:func:`features.geometry.body_frame`) faces backwards: arms in front read "behind", a leg
swinging forward reads as moving backward, a turn to the left as one to the right.

Such a recording is told from anatomy that does not depend on names: per leg, the toes point
forward of the ankle and of the heel in the leg's own frame, and the nose is in front of the
ears. Each cue is the normalised triple product ``det[named left - named right, up the limb,
the anatomical forward]`` (hips for the legs, ears for the face), +1 for a right-handed body
whatever the pose (lying, bending, legs raised: a rotation of the limb about the left-right axis
keeps it), -1 for a reflected one. A recording is read with x negated when the median over all
its frames' cues is at most ``-MARGIN`` from at least ``MIN_CUES`` values, and says so in its
metadata (``x_reflected``) and in one note line on stderr.

A reflection of z instead is read back by the same negation of x as the same body turned half
way round the vertical, which changes no description (every direction is the body's own or
about the vertical); one of y (upside down as well) is not told from lying exercises (a glute
bridge's shoulders are below its hips) and stays upside down.

On motion capture, depth-camera and video recordings the median lies well above 0 as read
and well below it reflected; knees bending forward were a weaker cue (a depth camera's knees
are noisy) and are not used (docs/measurements.md, "Figures behind the code's rules: Left-handed
recordings").
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable

import numpy as np

from .geometry import unit
from .poses import PoseSequence
from .skeleton import JOINT_INDEX
from .text import shown

# The median cue a recording must reach, below zero, to be read back; and how many cue values
# (frames x cues seen) at least.
MARGIN = 0.25
MIN_CUES = 5

METADATA_KEY = "x_reflected"


def _det(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Per row, ``det[a, b, c]`` of the unit vectors of ``(frames, 3)`` rows (NaN where one is
    degenerate or missing)."""
    return np.asarray(np.einsum("ij,ij->i", unit(a), np.cross(unit(b), unit(c))))


def handedness_cues(positions: np.ndarray) -> np.ndarray:
    """The finite cue values of canonical positions ``(frames, 33, 3)``: per frame and leg,
    toes ahead of the ankle and of the heel, and the nose ahead of the ears, each a normalised
    triple product (+1 right-handed, -1 reflected; see the module docstring)."""

    def joint(name: str) -> np.ndarray:
        return np.asarray(positions[:, JOINT_INDEX[name]])

    left = joint("left_hip") - joint("right_hip")
    cues = []
    for side in ("left", "right"):
        knee, ankle = joint(f"{side}_knee"), joint(f"{side}_ankle")
        toe, heel = joint(f"{side}_foot_index"), joint(f"{side}_heel")
        shank = knee - ankle
        cues += [_det(left, shank, toe - ankle), _det(left, shank, toe - heel)]
    l_ear, r_ear = joint("left_ear"), joint("right_ear")
    mid_ear = 0.5 * (l_ear + r_ear)
    neck = 0.5 * (joint("left_shoulder") + joint("right_shoulder"))
    cues.append(_det(l_ear - r_ear, mid_ear - neck, joint("nose") - mid_ear))
    values = np.concatenate(cues)
    return np.asarray(values[np.isfinite(values)])


def reflected_evidence(positions: np.ndarray) -> tuple[float, int]:
    """(median cue, number of cue values) of canonical positions; (NaN, 0) without cues."""
    values = handedness_cues(positions)
    return (float(np.median(values)) if values.size else float("nan")), int(values.size)


def _clear(median: float, n: int) -> bool:
    """Whether a recording's (median cue, number of cue values) (:func:`reflected_evidence`)
    is clear evidence of a reflected (left-handed) body: median at most ``-MARGIN`` over at
    least ``MIN_CUES`` values."""
    return n >= MIN_CUES and median <= -MARGIN


def right_handed(
    seq: PoseSequence,
    *,
    announce: bool = True,
    reflected_back: Callable[[], np.ndarray] | None = None,
) -> PoseSequence:
    """``seq`` as it is, or, when it is reflected (:func:`_clear` evidence from its canonical
    positions), with x negated: the metadata's ``x_reflected`` says why, and (``announce``)
    one note line on stderr names the file.

    ``reflected_back``: the positions read again from the source with x negated, for a reader
    whose joints are not its source's points reflected alike (UI-PRMD Vicon's hip centres are
    placed in a pelvis frame whose up is a cross product: placed before the reflection is
    undone, they land above the pelvis instead of below it)."""
    median, n = reflected_evidence(seq.to_canonical().positions)
    if not _clear(median, n):
        return seq
    why = (
        "read with x negated: written left-handed (x or z reflected, left/right names kept), its"
        " toes,"
        " heels and nose (those it has) pointed behind its body (median cue"
        f" {median:+.2f} of {n}; -1 = reflected)"
    )
    if reflected_back is not None:
        pos = reflected_back()
    else:
        pos = seq.positions.copy()
        pos[..., 0] *= -1.0
    if announce:
        print(f"note: {shown(seq.source)}: {why}", file=sys.stderr)
    return dataclasses.replace(seq, positions=pos, metadata={**seq.metadata, METADATA_KEY: why})
