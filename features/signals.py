"""State signals: every angle and distance the fluents (and QMPs) are computed from.

One call computes all of them for all frames at once. Angles are radians in [0, π]; near
distances are in head-lengths (1 hl = 2·|neck→mid-ear|). NaN means unavailable: a joint the
skeleton lacks, a missing detection, or a degenerate (zero-length) link.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Literal

import numpy as np

from features.errors import ConfigError

from .geometry import (
    MIN_LINK_M,
    UPRIGHT_HEAD,
    angle_between,
    body_frame,
    hips_unseen,
    joint_angle,
    norm,
    project,
)
from .poses import PoseSequence, expect_sequence
from .skeleton import JOINT_INDEX

SIDES = ("left", "right")

# Near pairs (SPEC "Near pairs"): from the index fingers and heels to that set plus the face,
# arm, hip, knee and big-toe joints, without the same-side tautologies and reflexive pairs.
NEAR_FROM = ("left_index", "right_index", "left_heel", "right_heel")
NEAR_TO_EXTRA = (
    "nose",
    "left_eye",
    "right_eye",
    "left_ear",
    "right_ear",
    "mouth_left",
    "mouth_right",
    "left_shoulder",
    "left_elbow",
    "left_wrist",
    "right_shoulder",
    "right_elbow",
    "right_wrist",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_foot_index",
    "right_foot_index",
)
_OMITTED_SAME_SIDE = {
    ("index", "wrist"),
    ("index", "elbow"),
    ("heel", "knee"),
    ("heel", "foot_index"),
}


@cache
def near_pairs() -> tuple[tuple[str, str], ...]:
    """The unordered joint pairs of the near fluents, in a stable order (74 pairs)."""
    pairs: list[tuple[str, str]] = []
    seen: set[frozenset[str]] = set()
    for a in NEAR_FROM:
        side_a, _, part_a = a.partition("_")
        for b in NEAR_FROM + NEAR_TO_EXTRA:
            side_b, _, part_b = b.partition("_")
            if a == b or (side_a == side_b and (part_a, part_b) in _OMITTED_SAME_SIDE):
                continue
            key = frozenset((a, b))
            if key not in seen:
                seen.add(key)
                pairs.append((a, b))
    return tuple(pairs)


def near_signal_name(a: str, b: str) -> str:
    return f"{a}~{b}"


ANGLE_SIGNALS: tuple[str, ...] = tuple(
    f"{side}_{part}"
    for part in (
        "elbow",
        "knee",
        "armpit",
        "hip",
        "upper_arm_sagittal",
        "upper_leg_sagittal",
        "upper_arm_frontal",
        "upper_leg_frontal",
    )
    for side in SIDES
) + (
    "neck_sagittal",
    "neck_frontal",
    "torso_sagittal",
    "torso_frontal",
    "neck_transverse",
    "torso_transverse",
)


HIPLESS: tuple[str, ...] = tuple(
    f"{side}_{part}"
    for part in ("armpit", "upper_arm_sagittal", "upper_arm_frontal")
    for side in SIDES
) + ("neck_sagittal", "neck_frontal", "neck_transverse")
"""The angles stated of a clip that shows neither hip, in the frame of its shoulders and the
world's up (:func:`features.geometry.shoulder_axes`: the trunk taken to be upright), where
the hips' body frame has none: the arm's raise (the armpit angle from the frame's down, the
trunk's line without a hip to draw it to), its direction forward and outward, and the head's
tilts and twist. The elbows and the near distances need no frame and are stated as for any
clip; the legs, the hip angles and the trunk's tilts and twist need the hips and stay
unavailable."""


@dataclass(frozen=True, eq=False)
class StateSignals:
    """Angles (rad) and near distances (head-lengths), ``values``: ``(frames, len(names))``.

    ``head_length_m``: ``(frames,)`` the head-length in metres; ``distances_m``: the near
    distances in metres ``(frames, n_pairs)`` (the touching fluent uses raw units).
    """

    names: tuple[str, ...]
    values: np.ndarray
    fps: float
    head_length_m: np.ndarray
    distances_m: np.ndarray

    @property
    def angle_names(self) -> tuple[str, ...]:
        return self.names[: len(ANGLE_SIGNALS)]

    def column(self, name: str) -> np.ndarray:
        return self.values[:, self.names.index(name)]


def _angles(p: np.ndarray, hipless: bool) -> np.ndarray:
    """All angle signals, ``(frames, len(ANGLE_SIGNALS))``, from positions ``(frames, 33, 3)``;
    ``hipless``: in the frame of the shoulders and the world's up (:data:`HIPLESS`)."""
    bf = body_frame(p, hipless)

    def j(name: str) -> np.ndarray:
        return p[:, JOINT_INDEX[name], :]

    cols: dict[str, np.ndarray] = {}
    for side, sign in (("left", 1.0), ("right", -1.0)):
        sh, el, wr = j(f"{side}_shoulder"), j(f"{side}_elbow"), j(f"{side}_wrist")
        hip, knee, ankle = j(f"{side}_hip"), j(f"{side}_knee"), j(f"{side}_ankle")
        # The outward axis: the body's left-right axis, pointing away from the body on this
        # side. Not the paper's ⊥²torso of the side, (shoulder→hip) × ⊥torso, which leans
        # with that side's shoulder-to-hip line (the shoulders wider than the hip joints;
        # docs/measurements.md, "Figures behind the code's rules: A limb's outward axis") and
        # would read an arm hanging straight down as half "outward" (SPEC: meaning wins over
        # the literal vector).
        outward = sign * bf.left
        upper_arm, upper_leg = el - sh, knee - hip
        cols[f"{side}_elbow"] = joint_angle(sh, el, wr)
        cols[f"{side}_knee"] = joint_angle(hip, knee, ankle)
        # without the hips, the trunk's line from the shoulder is the frame's down
        cols[f"{side}_armpit"] = (
            angle_between(upper_arm, -bf.up) if hipless else joint_angle(el, sh, hip)
        )
        cols[f"{side}_hip"] = joint_angle(knee, hip, sh)
        cols[f"{side}_upper_arm_sagittal"] = angle_between(project(upper_arm, bf.left), bf.forward)
        cols[f"{side}_upper_leg_sagittal"] = angle_between(project(upper_leg, bf.left), bf.forward)
        cols[f"{side}_upper_arm_frontal"] = angle_between(project(upper_arm, bf.forward), outward)
        cols[f"{side}_upper_leg_frontal"] = angle_between(project(upper_leg, bf.forward), outward)
    head = bf.mid_ear - bf.neck
    torso = bf.neck - bf.mid_hip
    cols["neck_sagittal"] = angle_between(project(head, bf.left), bf.forward)
    cols["neck_frontal"] = angle_between(project(head, bf.forward), bf.left)
    # The torso normal is perpendicular to the torso by construction, so the torso's own tilt is
    # measured against gravity: in the world's vertical plane through the heading.
    cols["torso_sagittal"] = angle_between(project(torso, bf.level_left), bf.heading)
    cols["torso_frontal"] = angle_between(project(torso, bf.heading), bf.level_left)
    cols["neck_transverse"] = angle_between(
        project(j("nose") - bf.neck, bf.up), project(j("left_shoulder") - bf.neck, bf.up)
    )
    # mid-hip → left hip (not the paper's left hip → mid-hip) so that shoulders turned to the
    # person's left read "twisted left" with the chest-facing normal (SPEC: meaning wins).
    cols["torso_transverse"] = angle_between(
        project(j("left_hip") - bf.mid_hip, bf.up), project(bf.forward, bf.up)
    )
    return np.stack([cols[name] for name in ANGLE_SIGNALS], axis=1)


_NEAR_A = np.array([JOINT_INDEX[a] for a, _ in near_pairs()])
_NEAR_B = np.array([JOINT_INDEX[b] for _, b in near_pairs()])
NEAR_SIGNALS: tuple[str, ...] = tuple(near_signal_name(a, b) for a, b in near_pairs())


_KERNEL_JOINTS = np.array(
    [JOINT_INDEX[name] for name in ("nose", "left_ear", "right_ear")]
    + [JOINT_INDEX[f"{side}_{part}"]
       for part in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle") for side in SIDES],
    dtype=np.intp,
)  # fmt: skip


def state_signals(
    seq: PoseSequence, backend: Literal["numba", "numpy"] = "numba", shoulders: bool = True
) -> StateSignals:
    """Every fluent's angle and distance for every frame of ``seq`` (any joint set). A clip
    that shows neither hip in any frame (:func:`features.geometry.hips_unseen`) is measured
    in the frame of its shoulders and the world's up (:data:`HIPLESS`); with ``shoulders``
    False it is not (every angle that needs the body frame unavailable, as for any clip
    without the hips before that frame existed: DAD's rules, written for the whole body).

    ``backend``: ``"numba"`` one compiled pass over the frames
    (:func:`features._fluent_kernels.state_signal_values`), ``"numpy"`` the whole-array
    reference built from :mod:`features.geometry`.
    """
    p = expect_sequence(seq).to_canonical().positions
    hipless = shoulders and hips_unseen(p)
    if backend == "numba":
        from ._fluent_kernels import state_signal_values

        p = np.ascontiguousarray(p, dtype=np.float64)
        frames = p.shape[0]
        values = np.empty((frames, len(ANGLE_SIGNALS) + len(NEAR_SIGNALS)))
        head_length = np.empty(frames)
        dist_m = np.empty((frames, len(NEAR_SIGNALS)))
        state_signal_values(
            p,
            _KERNEL_JOINTS,
            _NEAR_A,
            _NEAR_B,
            MIN_LINK_M,
            hipless,
            float(UPRIGHT_HEAD),
            values,
            head_length,
            dist_m,
        )
        return StateSignals(ANGLE_SIGNALS + NEAR_SIGNALS, values, seq.fps, head_length, dist_m)
    if backend != "numpy":
        raise ConfigError(f"unknown signal backend {backend!r} (known: numba, numpy)")
    angles = _angles(p, hipless)
    mid_ear = 0.5 * (p[:, JOINT_INDEX["left_ear"]] + p[:, JOINT_INDEX["right_ear"]])
    neck = 0.5 * (p[:, JOINT_INDEX["left_shoulder"]] + p[:, JOINT_INDEX["right_shoulder"]])
    # a degenerate neck -> mid-ear link (shorter than MIN_LINK_M, as for every angle's links)
    # gives no unit: the distances in head-lengths are unavailable
    link = norm(mid_ear - neck)
    head_length = np.where(link >= MIN_LINK_M, 2.0 * link, np.nan)
    dist_m = norm(p[:, _NEAR_A, :] - p[:, _NEAR_B, :])
    dist_hl = dist_m / head_length[:, None]
    values = np.concatenate([angles, dist_hl], axis=1)
    return StateSignals(ANGLE_SIGNALS + NEAR_SIGNALS, values, seq.fps, head_length, dist_m)


__all__ = [
    "ANGLE_SIGNALS",
    "NEAR_SIGNALS",
    "StateSignals",
    "near_pairs",
    "state_signals",
]
