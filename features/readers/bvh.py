"""Biovision BVH reader with forward kinematics to the canonical skeleton.

A BVH file declares a joint tree (``ROOT``/``JOINT``/``End Site`` with an ``OFFSET`` from the
parent and a ``CHANNELS`` list) and then one line of channel values per frame. Rotation
channels compose in the order the file lists them, each about the joint's already rotated
axes: ``CHANNELS 3 Zrotation Xrotation Yrotation`` means ``R = Rz @ Rx @ Ry`` (intrinsic). A
joint's position is ``pos(parent) + R_global(parent) @ t`` where ``t`` is the offset, or the
position channels when the joint has them; ``R_global = R_global(parent) @ R``.

BVH has no declared units or up axis. ``unit`` may be given (metres per file unit or a name
in :data:`UNITS`); ``"auto"`` picks the unit that makes the rest-pose height closest to
1.7 m and records the guess in the metadata (``bvh_unit``). The rest pose is the OFFSETs
with no rotation, a joint's position channels at its offset (:func:`_rest_motion`).
``up="y"`` (the common case) or ``"z"``; a z-up file is turned by the cyclic axis
permutation (x, y, z) -> (y, z, x), a proper rotation, so handedness is kept.

Joint names differ between exporters; :data:`BVH_TO_BLAZEPOSE` lists per BlazePose joint the
BVH names tried in turn (compared in lower case, after any ``prefix:``), each with whether the
joint's origin or its End Site is meant. Joint origins are joint centres (``LeftUpLeg`` origin
= hip, ``LeftLeg`` = knee, ``LeftFoot`` = ankle, ``LeftArm`` = shoulder, ``LeftForeArm`` =
elbow, ``LeftHand`` = wrist, ``LeftHandIndex1`` = index knuckle); the toe joint's End Site is
the tip of the foot (``left_foot_index``). A skeleton without ``LeftArm`` names its shoulder
joint otherwise: Poser/DAZ's ``lShldr`` (after the clavicle ``lCollar``) or a skeleton named by
joints (``LeftShoulder``, ``LeftElbow``, ``LeftWrist``); the shoulder is that joint's origin.
The Biovision example skeleton of the format's own description names its limbs ``LeftUpArm``,
``LeftLowArm``, ``LeftUpLeg``, ``LeftLowLeg`` (shoulder, elbow, hip, knee at their origins).
No common BVH skeleton has face landmarks or heels: they stay NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from features.errors import DataError

from ..handedness import right_handed
from ..poses import PoseSequence
from ..skeleton import BLAZEPOSE_33, JOINT_INDEX
from ._common import read_text

# "cmu": the CMU motion capture database's ASF unit (inches / 0.45, its ``:units length
# 0.45``), which the widely used BVH conversions of that database keep: a CMU subject stands
# about 25-30 of them tall, which read as inches would be a person of 0.65-0.75 m.
UNITS: dict[str, float] = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "inch": 0.0254,
    "cmu": 0.0254 / 0.45,
}


def _side_map(side: str) -> dict[str, tuple[tuple[str, str], ...]]:
    s, c = side, side[0]  # "left", "l"
    return {
        f"{s}_hip": ((f"{s}upleg", "joint"), (f"{s}hip", "joint"), (f"{s}thigh", "joint"),
                     (f"{c}thigh", "joint")),
        f"{s}_knee": ((f"{s}knee", "joint"), (f"{s}leg", "joint"), (f"{s}shin", "joint"),
                      (f"{c}shin", "joint"), (f"{s}lowleg", "joint")),
        f"{s}_ankle": ((f"{s}ankle", "joint"), (f"{s}foot", "joint"), (f"{c}foot", "joint")),
        f"{s}_foot_index": ((f"{s}toebase", "end"), (f"{s}toe", "end"), (f"{s}toes", "end"),
                            (f"{s}toe_end", "joint"), (f"{s}toebase_end", "joint")),
        f"{s}_shoulder": ((f"{s}arm", "joint"), (f"{s}upperarm", "joint"),
                          (f"{s}shoulder", "joint"), (f"{c}shldr", "joint"),
                          (f"{c}uparm", "joint"), (f"{s}uparm", "joint")),
        f"{s}_elbow": ((f"{s}forearm", "joint"), (f"{s}elbow", "joint"), (f"{c}forearm", "joint"),
                       (f"{s}lowerarm", "joint"), (f"{s}lowarm", "joint")),
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
    if not tokens or tokens[0].upper() != "HIERARCHY":
        raise DataError("does not start with HIERARCHY (not a BVH file?)", path)
    return _Hierarchy(tokens, path).parse()


_CHANNELS = frozenset(
    {"xposition", "yposition", "zposition", "xrotation", "yrotation", "zrotation"}
)


class _Hierarchy:
    """The ``HIERARCHY`` section read token by token from ``tokens[1]``: joints as they
    open (``ROOT``/``JOINT`` name ``{``), their ``OFFSET`` and ``CHANNELS``, ``End Site``
    blocks, and ``}`` closing the innermost open block."""

    def __init__(self, tokens: list[str], path: Path) -> None:
        self.tokens = tokens
        self.path = path
        self.i = 1
        self.joints: list[BvhJoint] = []
        self.stack: list[int] = []  # the open joints, innermost last
        self.in_end_site = False

    def parse(self) -> tuple[list[BvhJoint], int]:
        while self.i < len(self.tokens):
            word = self.tokens[self.i]
            up = word.upper()
            if up == "MOTION":
                if self.stack:
                    raise DataError("hierarchy not closed before MOTION (truncated?)", self.path)
                return self.joints, self.i + 1
            if up in ("ROOT", "JOINT"):
                self._joint(up)
            elif up == "END":
                self._end_site()
            elif up == "OFFSET":
                self._offset()
            elif up == "CHANNELS":
                self._channels()
            elif word == "}":
                self._close()
            else:
                raise DataError(f"unexpected word {word!r} in the hierarchy", self.path)
        raise DataError("no MOTION section (truncated file?)", self.path)

    def _need(self, n: int) -> list[str]:
        """The next ``n`` tokens from the current one (a truncated file has fewer)."""
        if self.i + n > len(self.tokens):
            raise DataError("hierarchy ends early (truncated file?)", self.path)
        return self.tokens[self.i : self.i + n]

    def _open_brace(self, after: str) -> None:
        if self._need(1)[0] != "{":
            raise DataError(f"expected '{{' after {after}", self.path)
        self.i += 1

    def _joint(self, up: str) -> None:
        """``ROOT name {`` or ``JOINT name {``: a joint under the innermost open one."""
        name = self._need(2)[1]
        if self.in_end_site:
            raise DataError(
                f"{up} {name} inside an End Site (an End Site has no joints)", self.path
            )
        if up == "ROOT" and self.joints:
            raise DataError("more than one ROOT is not supported", self.path)
        parent = self.stack[-1] if self.stack else -1
        self.joints.append(BvhJoint(name, parent, np.zeros(3), ()))
        self.i += 2
        self._open_brace(f"{up} {name}")
        self.stack.append(len(self.joints) - 1)

    def _end_site(self) -> None:
        """``End Site {``: the open joint's end point follows."""
        if not self.stack or self.in_end_site:
            raise DataError("End Site outside a joint", self.path)
        self.i += 2  # "End Site"
        self._open_brace("End Site")
        self.in_end_site = True

    def _offset(self) -> None:
        """``OFFSET x y z`` of the open joint or of its End Site."""
        offset = self._floats(self._need(4)[1:])
        self.i += 4
        if self.in_end_site:
            self.joints[self.stack[-1]].end_offset = offset
        elif self.stack:
            self.joints[self.stack[-1]].offset = offset

    def _floats(self, words: list[str]) -> np.ndarray:
        got = " ".join(words)[:60]
        try:
            out = np.array([float(w) for w in words])
        except ValueError:
            raise DataError(f"expected numbers after OFFSET, got {got!r}", self.path) from None
        if not np.isfinite(out).all():
            raise DataError(f"expected finite numbers after OFFSET, got {got!r}", self.path)
        return out

    def _channels(self) -> None:
        """``CHANNELS n name ...`` of the open joint: known channels, each at most once."""
        if self.in_end_site:
            # they would replace the joint's own channels, and its values be read wrongly
            raise DataError("CHANNELS inside an End Site (an End Site has no channels)", self.path)
        try:
            n = int(self._need(2)[1])
        except ValueError:
            bad = self.tokens[self.i + 1]
            raise DataError(f"CHANNELS count is not a number: {bad!r}", self.path) from None
        channels = tuple(w.lower() for w in self._need(2 + n)[2:])
        unknown = [c for c in channels if c not in _CHANNELS]
        if unknown:
            raise DataError(f"unknown channel {unknown[0]!r}", self.path)
        if len(set(channels)) != len(channels):
            # each channel at most once: a rotation is three distinct axes in turn
            raise DataError(f"a channel listed twice in CHANNELS {' '.join(channels)}", self.path)
        if self.stack:
            self.joints[self.stack[-1]].channels = channels
        self.i += 2 + n

    def _close(self) -> None:
        """``}``: closes the End Site block, else the innermost open joint."""
        if self.in_end_site:
            self.in_end_site = False
        elif self.stack:
            self.stack.pop()
        else:
            raise DataError("unbalanced '}' in the hierarchy", self.path)
        self.i += 1


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


def _rest_motion(joints: list[BvhJoint], n_chan: int) -> np.ndarray:
    """The motion values of the rest pose ``(1, n_chan)``: no rotation, and a joint's own
    OFFSET in any position channels it has (every joint has them in some exporters' files,
    each frame's positions the offsets again: zeros there put every joint at its parent's
    origin, a rest pose of no height); the root's position channels at 0."""
    rest = np.zeros((1, n_chan))
    col = 0
    for jt in joints:
        for k, c in enumerate(jt.channels):
            if c.endswith("position") and jt.parent >= 0:
                rest[0, col + k] = jt.offset["xyz".index(c[0])]
        col += len(jt.channels)
    return rest


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
    if len(joints) == 1:  # named LeftUpLeg or not: one point, no limb, "no person" later
        raise DataError(
            f"the skeleton has only its root ({joints[0].name}); there are no limbs to draw", path
        )
    n_frames, frame_time = _motion_header(tokens, i, path)
    text_time = tokens[i + 4]
    n_chan = sum(len(j.channels) for j in joints)
    motion = _motion(tokens[i + 5 :], n_frames, n_chan, path)
    _check_names(joints, path)
    pos, ends = _forward(joints, motion)
    rest, rest_ends = _forward(joints, _rest_motion(joints, n_chan))
    pos, ends, rest, rest_ends = _y_up((pos, ends, rest, rest_ends), up, path)
    unit_name, scale = _unit(unit, rest[0], rest_ends[0], path)
    seq = PoseSequence(
        positions=_to_blazepose(joints, pos, ends) * scale,
        joint_names=BLAZEPOSE_33,
        fps=frame_rate(frame_time, text_time),
        skeleton="bvh",
        source=str(path),
        metadata={"bvh_unit": unit_name},
    )
    return right_handed(seq)


def _motion_header(tokens: list[str], i: int, path: Path) -> tuple[int, float]:
    """``Frames: N`` and ``Frame Time: T`` from ``tokens[i]`` on: (N, T seconds)."""
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
    if n_frames < 1:
        raise DataError(f"Frames must be at least 1, got {n_frames}", path)
    if not (math.isfinite(frame_time) and frame_time > 0):  # nan or inf: no frame rate
        raise DataError(f"Frame Time must be positive, got {frame_time}", path)
    return n_frames, frame_time


def frame_rate(frame_time: float, written: str) -> float:
    """Frames per second of a ``Frame Time`` of ``frame_time`` seconds, as ``written`` in the
    file: the whole number of frames per second within the precision it was written to, when
    there is one and it lies within 0.01 % (``0.0333333``, 30.00003 as written, is 30 to its
    seven decimals: 1/30 s lies within half a unit of its last digit; ``0.03`` stays 33.3, and
    ``0.0333`` 30.03, 0.1 % off), else ``1 / frame_time``."""
    mantissa = written.lower().split("e")[0]
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    exponent = int(written.lower().split("e")[1]) if "e" in written.lower() else 0
    half = 0.5 * 10.0 ** (exponent - decimals)
    whole = round(1.0 / frame_time)
    off = abs(1.0 / whole - frame_time) if whole >= 1 else math.inf
    if off <= half and off <= 1e-4 * frame_time:
        return float(whole)
    return 1.0 / frame_time


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _motion(data: list[str], n_frames: int, n_chan: int, path: Path) -> np.ndarray:
    """The channel values ``(frames, channels)``: exactly as many finite numbers as the
    header and the hierarchy promise."""
    try:
        values = np.array(data, dtype=float)
    except ValueError:
        i, token = next((i, t) for i, t in enumerate(data) if not _is_number(t))
        raise DataError(
            f"motion value {token!r} (value {i + 1} after the header) is not a number", path
        ) from None
    if len(data) != n_frames * n_chan:
        raise DataError(
            f"{len(data)} numbers after the header, expected {n_frames} frames x {n_chan}"
            " channels (truncated file?)",
            path,
        )
    if n_frames < 1:
        raise DataError("no frames", path)
    motion = values.reshape(n_frames, n_chan)
    if not np.isfinite(motion).all():
        frame = int(np.flatnonzero(~np.isfinite(motion).all(axis=1))[0]) + 1
        raise DataError(f"a motion value in frame {frame} is not a finite number", path)
    return motion


def _y_up(points: tuple[np.ndarray, ...], up: str, path: Path) -> tuple[np.ndarray, ...]:
    """Points ``(..., 3)`` of a file whose ``up`` axis is y or z, in the y-up frame (z up:
    the cyclic permutation (x, y, z) -> (y, z, x), a proper rotation)."""
    if up == "z":
        return tuple(p[..., [1, 2, 0]] for p in points)
    if up != "y":
        raise DataError(f"up must be 'y' or 'z', got {up!r}", path)
    return points


def _unit(
    unit: str | float, rest: np.ndarray, rest_ends: np.ndarray, path: Path
) -> tuple[str, float]:
    """(name, metres per file unit) of ``unit``; for ``"auto"``, the unit of :data:`UNITS`
    that makes the rest pose (joints ``(joints, 3)`` and End Sites, NaN where none, y up)
    closest to 1.7 m tall."""
    if unit == "auto":
        pts = np.concatenate([rest, rest_ends[~np.isnan(rest_ends[:, 0])]])
        height = float(np.ptp(pts[:, 1]))
        if height <= 0:
            raise DataError("rest pose has no height: cannot guess the unit", path)
        name = min(UNITS, key=lambda u: abs(np.log(height * UNITS[u] / 1.7)))
        return name, UNITS[name]
    if isinstance(unit, str):
        if unit not in UNITS:
            raise DataError(f"unknown unit {unit!r} (known: {', '.join(UNITS)})", path)
        return unit, UNITS[unit]
    return f"{unit} m", float(unit)


def _check_names(joints: list[BvhJoint], path: Path) -> None:
    """Refuse a skeleton none of whose joints :data:`BVH_TO_BLAZEPOSE` names: every joint of
    the clip would be NaN, a clip that "shows no person" though it holds one."""
    names = {_normalise(j.name) for j in joints}
    if not any(name in names for tried in BVH_TO_BLAZEPOSE.values() for name, _ in tried):
        raise DataError(
            "none of its joint names is one the BVH reader knows (LeftUpLeg, LeftLeg, LeftArm,"
            " LeftForeArm, LeftHand, ...; features.readers.bvh.BVH_TO_BLAZEPOSE): it has "
            + ", ".join(j.name for j in joints[:8])
            + (", ..." if len(joints) > 8 else ""),
            path,
        )


def _to_blazepose(joints: list[BvhJoint], pos: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Joint origins and End Sites ``(frames, joints, 3)`` on the canonical skeleton
    ``(frames, 33, 3)`` by :data:`BVH_TO_BLAZEPOSE` (the first name found); NaN elsewhere."""
    index = {_normalise(j.name): k for k, j in enumerate(joints)}
    out = np.full((pos.shape[0], len(BLAZEPOSE_33), 3), np.nan)
    for target, candidates in BVH_TO_BLAZEPOSE.items():
        for name, where in candidates:
            k = index.get(name)
            if k is None or (where == "end" and joints[k].end_offset is None):
                continue
            out[:, JOINT_INDEX[target]] = (pos if where == "joint" else ends)[:, k]
            break
    return out
