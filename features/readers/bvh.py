"""Biovision BVH reader with forward kinematics to the canonical skeleton.

A BVH file declares a joint tree (``ROOT``/``JOINT``/``End Site`` with an ``OFFSET`` from the
parent and a ``CHANNELS`` list) and then one line of channel values per frame. Rotation
channels compose in the order the file lists them, each about the joint's already rotated
axes: ``CHANNELS 3 Zrotation Xrotation Yrotation`` means ``R = Rz @ Rx @ Ry`` (intrinsic). A
joint's position is ``pos(parent) + R_global(parent) @ t`` where ``t`` is the offset, or the
position channels when the joint has them; ``R_global = R_global(parent) @ R``.

BVH has no declared units or up axis. ``unit`` may be given (metres per file unit or a name
in :data:`UNITS`); ``"auto"`` picks the unit that makes the rest-pose height closest to
1.7 m and records the guess in the metadata (``bvh_unit``). ``up="y"`` (the common case) or
``"z"``; a z-up file is turned by the cyclic axis permutation (x, y, z) -> (y, z, x), a proper
rotation, so handedness is kept.

Joint names differ between exporters; :data:`BVH_TO_BLAZEPOSE` lists per BlazePose joint the
BVH names tried in turn (compared in lower case, after any ``prefix:``), each with whether the
joint's origin or its End Site is meant. Joint origins are joint centres (``LeftUpLeg`` origin
= hip, ``LeftLeg`` = knee, ``LeftFoot`` = ankle, ``LeftArm`` = shoulder, ``LeftForeArm`` =
elbow, ``LeftHand`` = wrist, ``LeftHandIndex1`` = index knuckle); the toe joint's End Site is
the tip of the foot (``left_foot_index``). No common BVH skeleton has face landmarks or heels:
they stay NaN.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from features.errors import DataError

from ..poses import PoseSequence
from ..skeleton import BLAZEPOSE_33, JOINT_INDEX
from ._common import read_text

UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "inch": 0.0254}


def _side_map(side: str) -> dict[str, tuple[tuple[str, str], ...]]:
    s, c = side, side[0]  # "left", "l"
    return {
        f"{s}_hip": ((f"{s}upleg", "joint"), (f"{s}hip", "joint"), (f"{s}thigh", "joint"),
                     (f"{c}thigh", "joint")),
        f"{s}_knee": ((f"{s}knee", "joint"), (f"{s}leg", "joint"), (f"{s}shin", "joint"),
                      (f"{c}shin", "joint")),
        f"{s}_ankle": ((f"{s}ankle", "joint"), (f"{s}foot", "joint"), (f"{c}foot", "joint")),
        f"{s}_foot_index": ((f"{s}toebase", "end"), (f"{s}toe", "end"), (f"{s}toes", "end"),
                            (f"{s}toe_end", "joint"), (f"{s}toebase_end", "joint")),
        f"{s}_shoulder": ((f"{s}arm", "joint"), (f"{s}upperarm", "joint"),
                          (f"{s}shoulder", "end"), (f"{c}shldr", "end"), (f"{c}uparm", "joint")),
        f"{s}_elbow": ((f"{s}forearm", "joint"), (f"{s}elbow", "joint"), (f"{c}forearm", "joint"),
                       (f"{s}lowerarm", "joint")),
        f"{s}_wrist": ((f"{s}hand", "joint"), (f"{s}wrist", "joint"), (f"{c}hand", "joint")),
        f"{s}_index": ((f"{s}handindex1", "joint"), (f"{s}index1", "joint")),
    }  # fmt: skip


# BlazePose joint -> BVH joint names tried in turn, with "joint" (its origin) or "end" (its
# End Site). Data, not code: add an exporter's names here.
BVH_TO_BLAZEPOSE: dict[str, tuple[tuple[str, str], ...]] = {
    **_side_map("left"),
    **_side_map("right"),
}


@dataclass
class BvhJoint:
    name: str
    parent: int
    offset: np.ndarray  # (3,)
    channels: tuple[str, ...]
    end_offset: np.ndarray | None = None  # End Site offset (3,) when the joint has one


def _parse_hierarchy(tokens: list[str], path: Path) -> tuple[list[BvhJoint], int]:
    """Joints parents first, and the index of the token after the hierarchy (``MOTION``)."""
    joints: list[BvhJoint] = []
    stack: list[int] = []
    i = 0
    if not tokens or tokens[0].upper() != "HIERARCHY":
        raise DataError("does not start with HIERARCHY (not a BVH file?)", path)
    i = 1
    pending_end = False

    def need(n: int) -> list[str]:
        if i + n > len(tokens):
            raise DataError("hierarchy ends early (truncated file?)", path)
        return tokens[i : i + n]

    def floats(words: list[str]) -> np.ndarray:
        got = " ".join(words)[:60]
        try:
            out = np.array([float(w) for w in words])
        except ValueError:
            raise DataError(f"expected numbers after OFFSET, got {got!r}", path) from None
        if not np.isfinite(out).all():
            raise DataError(f"expected finite numbers after OFFSET, got {got!r}", path)
        return out

    while i < len(tokens):
        t = tokens[i]
        up = t.upper()
        if up in ("ROOT", "JOINT"):
            name = need(2)[1]
            parent = stack[-1] if stack else -1
            if up == "ROOT" and joints:
                raise DataError("more than one ROOT is not supported", path)
            joints.append(BvhJoint(name, parent, np.zeros(3), ()))
            i += 2
            if need(1)[0] != "{":
                raise DataError(f"expected '{{' after {up} {name}", path)
            stack.append(len(joints) - 1)
            i += 1
        elif up == "END":
            if not stack or pending_end:
                raise DataError("End Site outside a joint", path)
            i += 2  # "End Site"
            if need(1)[0] != "{":
                raise DataError("expected '{' after End Site", path)
            i += 1
            pending_end = True
        elif up == "OFFSET":
            off = floats(need(4)[1:])
            i += 4
            if pending_end:
                joints[stack[-1]].end_offset = off
            elif stack:
                joints[stack[-1]].offset = off
        elif up == "CHANNELS":
            try:
                n = int(need(2)[1])
            except ValueError:
                bad = tokens[i + 1]
                raise DataError(f"CHANNELS count is not a number: {bad!r}", path) from None
            chans = tuple(w.lower() for w in need(2 + n)[2:])
            for c in chans:
                if c not in ("xposition", "yposition", "zposition",
                             "xrotation", "yrotation", "zrotation"):  # fmt: skip
                    raise DataError(f"unknown channel {c!r}", path)
            if len(set(chans)) != len(chans):
                # each channel at most once: a rotation is three distinct axes in turn
                raise DataError(f"a channel listed twice in CHANNELS {' '.join(chans)}", path)
            if stack:
                joints[stack[-1]].channels = chans
            i += 2 + n
        elif t == "}":
            if pending_end:
                pending_end = False
            elif stack:
                stack.pop()
            else:
                raise DataError("unbalanced '}' in the hierarchy", path)
            i += 1
        elif up == "MOTION":
            if stack:
                raise DataError("hierarchy not closed before MOTION (truncated?)", path)
            return joints, i + 1
        else:
            raise DataError(f"unexpected word {t!r} in the hierarchy", path)
    raise DataError("no MOTION section (truncated file?)", path)


def _forward(joints: list[BvhJoint], motion: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint origins ``(frames, joints, 3)`` and End Site points (NaN where none), file units."""
    from scipy.spatial.transform import Rotation  # scipy loads when a file is read

    frames = motion.shape[0]
    pos = np.empty((frames, len(joints), 3))
    ends = np.full((frames, len(joints), 3), np.nan)
    glob = np.empty((frames, len(joints), 3, 3))
    col = 0
    for j, jt in enumerate(joints):
        vals = motion[:, col : col + len(jt.channels)]
        col += len(jt.channels)
        trans = np.broadcast_to(jt.offset, (frames, 3)).copy()
        rot_letters, rot_cols = "", []
        for k, c in enumerate(jt.channels):
            if c.endswith("position"):
                trans[:, "xyz".index(c[0])] = vals[:, k]
            else:
                rot_letters += c[0].upper()  # upper case: intrinsic, in the listed order
                rot_cols.append(k)
        local = (
            Rotation.from_euler(rot_letters, vals[:, rot_cols], degrees=True).as_matrix()
            if rot_letters
            else np.broadcast_to(np.eye(3), (frames, 3, 3))
        )
        if jt.parent < 0:
            pos[:, j] = trans
            glob[:, j] = local
        else:
            pos[:, j] = pos[:, jt.parent] + np.einsum("fab,fb->fa", glob[:, jt.parent], trans)
            glob[:, j] = glob[:, jt.parent] @ local
        if jt.end_offset is not None:
            ends[:, j] = pos[:, j] + glob[:, j] @ jt.end_offset
    return pos, ends


def _normalise(name: str) -> str:
    return name.rsplit(":", 1)[-1].lower().replace(" ", "")


def read_bvh(path: str | Path, *, unit: str | float = "auto", up: str = "y") -> PoseSequence:
    """A BVH file as a canonical :class:`PoseSequence`.

    unit: metres per file unit, a name in :data:`UNITS`, or ``"auto"`` (see module docstring).
    up: ``"y"`` or ``"z"``. Raises DataError naming the file for malformed or truncated input.
    """
    path = Path(path)
    tokens = read_text(path).split()
    joints, i = _parse_hierarchy(tokens, path)
    if not joints:
        raise DataError("no joints in the hierarchy", path)
    try:
        if (
            tokens[i].lower() != "frames:"
            or tokens[i + 2].lower() != "frame"
            or tokens[i + 3].lower() != "time:"
        ):
            raise DataError("MOTION must be followed by 'Frames: N' and 'Frame Time: T'", path)
        n_frames = int(tokens[i + 1])
        frame_time = float(tokens[i + 4])
    except (IndexError, ValueError):
        raise DataError("MOTION header is malformed or truncated", path) from None
    if frame_time <= 0:
        raise DataError(f"Frame Time must be positive, got {frame_time}", path)
    n_chan = sum(len(j.channels) for j in joints)
    data = tokens[i + 5 :]
    if len(data) != n_frames * n_chan:
        raise DataError(
            f"{len(data)} numbers after the header, expected {n_frames} frames x {n_chan}"
            " channels (truncated file?)",
            path,
        )
    if n_frames < 1:
        raise DataError("no frames", path)
    try:
        motion = np.array(data, dtype=float).reshape(n_frames, n_chan)
    except ValueError:
        raise DataError("a motion value is not a number", path) from None
    if not np.isfinite(motion).all():
        frame = int(np.flatnonzero(~np.isfinite(motion).all(axis=1))[0]) + 1
        raise DataError(f"a motion value in frame {frame} is not a finite number", path)
    pos, ends = _forward(joints, motion)
    rest, rest_ends = _forward(joints, np.zeros((1, n_chan)))
    if up == "z":
        pos, ends = pos[..., [1, 2, 0]], ends[..., [1, 2, 0]]
        rest, rest_ends = rest[..., [1, 2, 0]], rest_ends[..., [1, 2, 0]]
    elif up != "y":
        raise DataError(f"up must be 'y' or 'z', got {up!r}", path)
    if unit == "auto":
        pts = np.concatenate([rest[0], rest_ends[0][~np.isnan(rest_ends[0][:, 0])]])
        height = float(np.ptp(pts[:, 1]))
        if height <= 0:
            raise DataError("rest pose has no height: cannot guess the unit", path)
        unit_name = min(UNITS, key=lambda u: abs(np.log(height * UNITS[u] / 1.7)))
        scale = UNITS[unit_name]
    elif isinstance(unit, str):
        if unit not in UNITS:
            raise DataError(f"unknown unit {unit!r} (known: {', '.join(UNITS)})", path)
        unit_name, scale = unit, UNITS[unit]
    else:
        unit_name, scale = f"{unit} m", float(unit)
    index = {_normalise(j.name): k for k, j in enumerate(joints)}
    out = np.full((n_frames, len(BLAZEPOSE_33), 3), np.nan)
    for target, candidates in BVH_TO_BLAZEPOSE.items():
        for name, where in candidates:
            k = index.get(name)
            if k is None or (where == "end" and joints[k].end_offset is None):
                continue
            out[:, JOINT_INDEX[target]] = (pos if where == "joint" else ends)[:, k] * scale
            break
    return PoseSequence(
        positions=out,
        joint_names=BLAZEPOSE_33,
        fps=1.0 / frame_time,
        skeleton="bvh",
        source=str(path),
        metadata={"bvh_unit": unit_name},
    )
