"""Acclaim ASF/AMC reader (HDM05, CMU) with forward kinematics to the canonical skeleton.

The ASF file holds the skeleton: per bone a direction (unit vector in the world frame at rest),
a length, an ``axis`` (Euler angles and order defining the bone's local frame) and its degrees
of freedom; the AMC file holds, per frame, the root translation and rotation and each bone's
rotation in its local frame. Forward kinematics (the Acclaim convention):

    L(bone)      = C @ M(values) @ C^-1          C from ``axis``, M from the dof values
    R(bone)      = R(parent) @ L(bone)
    end(bone)    = end(parent) + R(bone) @ (direction * length)

Euler letters are applied in the order they are written (``XYZ`` / ``rx ry rz``: x first),
i.e. ``M = Rz @ Ry @ Rx``. Lengths and the root translation are in inches divided by the
``:units length`` scale, so metres = value x 0.0254 / length (HDM05 and CMU: 0.45). The world
frame is y up with the skeleton's left along +x and forward along +z at rest, right-handed,
which is already the canonical frame.

ASF bone -> BlazePose (a bone's end point is the joint below it; the rest stays NaN):

==================  ===============  ==========================================================
BlazePose           end of bone      why
==================  ===============  ==========================================================
left_hip            lhipjoint        the pelvis-to-hip bone ends at the hip joint
left_knee           lfemur           femur end = knee
left_ankle          ltibia           tibia end = ankle
left_foot_index     ltoes            tip of the toes
left_shoulder       lclavicle        clavicle end = shoulder joint
left_elbow          lhumerus         humerus end = elbow
left_wrist          lradius          radius end = wrist
left_index          lhand            hand end = finger base knuckles; BlazePose's index landmark is
                                     the index knuckle
(right the same)
nose, eyes, ears    (none)           the ``head`` bone ends at the top of the skull, not a face
                                     landmark
heels, pinky,       (none)           no bone ends there (``lthumb`` ends at the thumb tip, not
thumb                                BlazePose's thumb knuckle)
==================  ===============  ==========================================================
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from features.errors import DataError

from ..poses import PoseSequence
from ..skeleton import BLAZEPOSE_33
from ._common import read_text, to_canonical

INCH_M = 0.0254

ASF_TO_BLAZEPOSE: dict[str, str] = {
    "left_hip": "lhipjoint",
    "left_knee": "lfemur",
    "left_ankle": "ltibia",
    "left_foot_index": "ltoes",
    "left_shoulder": "lclavicle",
    "left_elbow": "lhumerus",
    "left_wrist": "lradius",
    "left_index": "lhand",
    "right_hip": "rhipjoint",
    "right_knee": "rfemur",
    "right_ankle": "rtibia",
    "right_foot_index": "rtoes",
    "right_shoulder": "rclavicle",
    "right_elbow": "rhumerus",
    "right_wrist": "rradius",
    "right_index": "rhand",
}

_DOF_AXES = {"rx": "x", "ry": "y", "rz": "z", "tx": "X", "ty": "Y", "tz": "Z", "l": "l"}


@dataclass
class Bone:
    """One ASF bone: direction ``(3,)`` unit, length (ASF units), local axis, dofs."""

    name: str
    direction: np.ndarray
    length: float
    axis_deg: np.ndarray
    axis_order: str
    dof: tuple[str, ...] = ()
    parent: str = "root"


@dataclass
class Skeleton:
    """A parsed ASF file. Bones are listed parents first."""

    path: Path
    length_scale: float
    angle_deg: bool
    root_order: tuple[str, ...]
    root_axis: str
    root_orientation_deg: np.ndarray
    bones: dict[str, Bone] = field(default_factory=dict)

    @property
    def metres_per_unit(self) -> float:
        return INCH_M / self.length_scale


@dataclass
class Motion:
    """A parsed AMC file: per bone (and ``root``) its values ``(frames, n_dof)``."""

    path: Path
    values: dict[str, np.ndarray]
    n_frames: int
    angle_deg: bool | None


def _floats(tokens: list[str], path: Path, line_no: int, n: int | None = None) -> np.ndarray:
    try:
        out = np.array([float(t) for t in tokens])
    except ValueError:
        got = " ".join(tokens)
        raise DataError(f"line {line_no}: expected numbers, got {got!r}", path) from None
    if n is not None and out.size != n:
        raise DataError(f"line {line_no}: expected {n} numbers, got {out.size}", path)
    if not np.isfinite(out).all():
        raise DataError(f"line {line_no}: expected finite numbers, got {' '.join(tokens)!r}", path)
    return out


_AXIS_ORDER = re.compile(r"[XYZ]{3}")
_ROOT_CHANNELS = frozenset({"TX", "TY", "TZ", "RX", "RY", "RZ"})


def _axis_order(token: str, path: Path, line_no: int) -> str:
    """A rotation order such as ``XYZ``: three of X, Y, Z, no two in a row the same."""
    order = token.upper()
    if not _AXIS_ORDER.fullmatch(order) or order[0] == order[1] or order[1] == order[2]:
        raise DataError(f"line {line_no}: {token[:20]!r} is not a rotation order like XYZ", path)
    return order


def _root_order(tokens: list[str], path: Path, line_no: int) -> tuple[str, ...]:
    """The root's channels: each of TX TY TZ RX RY RZ at most once."""
    order = tuple(t.upper() for t in tokens)
    bad = [t for t in order if t not in _ROOT_CHANNELS]
    if bad or len(set(order)) != len(order):
        what = f"unknown channel {bad[0][:20]!r}" if bad else "a channel repeated"
        raise DataError(f"line {line_no}: root order has {what} (TX TY TZ RX RY RZ)", path)
    return order


def read_asf(path: str | Path) -> Skeleton:
    """Parse an ASF skeleton file. Raises DataError naming the file and line if malformed."""
    path = Path(path)
    lines = read_text(path).split("\n")
    skel = Skeleton(path, 1.0, True, ("TX", "TY", "TZ", "RX", "RY", "RZ"), "XYZ", np.zeros(3))
    section = ""
    bone: dict[str, object] | None = None
    parsed: list[dict[str, object]] = []
    hierarchy: list[tuple[int, list[str]]] = []
    for i, raw in enumerate(lines, start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tokens = line.split()
        head = tokens[0].lower()
        if len(tokens) < 2 and head in ("name", "axis", "order", "direction", "length"):
            raise DataError(f"line {i}: {head!r} without a value", path)
        if head.startswith(":"):
            section = head[1:]
            if section in ("name", "version", "documentation"):
                section = "skip:" + section
            continue
        if section == "units" and len(tokens) >= 2:
            if head == "length":
                skel.length_scale = float(_floats(tokens[1:2], path, i)[0])
            elif head == "angle":
                skel.angle_deg = tokens[1].lower().startswith("deg")
        elif section == "root":
            if head == "order":
                skel.root_order = _root_order(tokens[1:], path, i)
            elif head == "axis":
                skel.root_axis = _axis_order(tokens[1], path, i)
            elif head == "orientation":
                skel.root_orientation_deg = _floats(tokens[1:4], path, i, 3)
        elif section == "bonedata":
            if head == "begin":
                bone = {"line": i}
            elif head == "end":
                if bone is None:
                    raise DataError(f"line {i}: 'end' without 'begin'", path)
                parsed.append(bone)
                bone = None
            elif bone is not None:
                if head == "name":
                    bone["name"] = tokens[1]
                elif head == "direction":
                    bone["direction"] = _floats(tokens[1:4], path, i, 3)
                elif head == "length":
                    bone["length"] = float(_floats(tokens[1:2], path, i, 1)[0])
                elif head == "axis":
                    bone["axis"] = _floats(tokens[1:4], path, i, 3)
                    bone["order"] = _axis_order(tokens[4], path, i) if len(tokens) > 4 else "XYZ"
                elif head == "dof":
                    bone["dof"] = tuple(t.lower() for t in tokens[1:])
        elif section == "hierarchy":
            if head not in ("begin", "end"):
                hierarchy.append((i, tokens))
    if bone is not None:
        raise DataError("bone definition not closed with 'end' (truncated?)", path)
    if not parsed:
        raise DataError("no :bonedata bones (not an ASF file?)", path)
    defined: dict[str, Bone] = {}
    for b in parsed:
        missing = [k for k in ("name", "direction", "length") if k not in b]
        if missing:
            raise DataError(f"line {b['line']}: bone lacks {', '.join(missing)}", path)
        dof: tuple[str, ...] = tuple(b.get("dof", ()))  # type: ignore[arg-type]
        bad = [d for d in dof if d not in _DOF_AXES]
        if bad:
            raise DataError(f"line {b['line']}: unknown dof {bad[0]!r}", path)
        name = str(b["name"])
        direction = np.asarray(b["direction"], dtype=float)
        norm = np.linalg.norm(direction)
        defined[name] = Bone(
            name=name,
            direction=direction / norm if norm > 0 else direction,
            length=float(b["length"]),  # type: ignore[arg-type]
            axis_deg=np.asarray(b.get("axis", np.zeros(3)), dtype=float),
            axis_order=str(b.get("order", "XYZ")),
            dof=dof,
        )
    parent_of: dict[str, str] = {}
    for line_no, tokens in hierarchy:
        for child in tokens[1:]:
            if child not in defined:
                raise DataError(f"line {line_no}: hierarchy names unknown bone {child!r}", path)
            parent_of[child] = tokens[0]
    # Order bones parents first so forward kinematics can run in one pass.
    ordered: dict[str, Bone] = {}
    pending = [n for n in defined if n in parent_of]
    orphans = [n for n in defined if n not in parent_of]
    if orphans:
        raise DataError(f"bone {orphans[0]!r} is not in the :hierarchy", path)
    while pending:
        progressed = False
        for n in list(pending):
            p = parent_of[n]
            if p == "root" or p in ordered:
                defined[n].parent = p
                ordered[n] = defined[n]
                pending.remove(n)
                progressed = True
        if not progressed:
            raise DataError(f"hierarchy has a cycle or unknown parent near {pending[0]!r}", path)
    skel.bones = ordered
    return skel


def _read_amc_fast(
    path: Path, lines: list[str], n_dof: dict[str, int], angle_deg: bool | None
) -> Motion | None:
    """Every frame lists the same bones in the same order (AMC exporters write it so):
    parse each bone's column of lines at once. None when the file does not fit that shape,
    so the line by line parser can name the problem."""
    if not lines or not lines[0].isdigit():
        return None
    k = 1
    while k < len(lines) and not lines[k].isdigit():
        k += 1
    if len(lines) % k:
        return None
    n_frames = len(lines) // k
    if not all(line.isdigit() for line in lines[::k]):
        return None
    values: dict[str, np.ndarray] = {}
    for j in range(1, k):
        column = lines[j::k]
        name = column[0].split(None, 1)[0]
        if name not in n_dof or name in values:
            return None
        tokens = " ".join(column).split()
        width = n_dof[name] + 1
        if len(tokens) != n_frames * width:
            return None
        table = np.array(tokens, dtype=object).reshape(n_frames, width)
        if not (table[:, 0] == name).all():
            return None
        try:
            values[name] = table[:, 1:].astype(np.float64)
        except ValueError:
            return None
    if "root" not in values:
        return None
    return Motion(path, values, n_frames, angle_deg)


def read_amc(path: str | Path, skeleton: Skeleton) -> Motion:
    """Parse an AMC motion file against its skeleton. Frames must be complete."""
    path = Path(path)
    lines = read_text(path).split("\n")
    n_dof_fast = {name: len(b.dof) for name, b in skeleton.bones.items()}
    n_dof_fast["root"] = len(skeleton.root_order)
    body = [ln.strip() for ln in lines]
    body = [ln for ln in body if ln and not ln.startswith("#")]
    header = [ln[1:].upper() for ln in body if ln.startswith(":")]
    deg = True if any(h.startswith("DEG") for h in header) else None
    deg = False if any(h.startswith("RAD") for h in header) else deg
    fast = _read_amc_fast(path, [ln for ln in body if not ln.startswith(":")], n_dof_fast, deg)
    if fast is not None:
        return _finite(fast)
    n_dof = {name: len(b.dof) for name, b in skeleton.bones.items()}
    n_dof["root"] = len(skeleton.root_order)
    rows: dict[str, list[list[str]]] = {}
    angle_deg: bool | None = None
    n_frames = 0
    seen_in_frame: set[str] = set()
    first_frame_bones: set[str] | None = None
    for i, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith(":"):
            key = line[1:].upper()
            if key.startswith("DEG"):
                angle_deg = True
            elif key.startswith("RAD"):
                angle_deg = False
            continue
        tokens = line.split()
        if len(tokens) == 1 and tokens[0].isdigit():
            if n_frames == 1:
                first_frame_bones = set(seen_in_frame)
            elif first_frame_bones is not None and seen_in_frame != first_frame_bones:
                raise DataError(f"line {i}: frame {n_frames} is incomplete", path)
            n_frames += 1
            seen_in_frame = set()
            continue
        if n_frames == 0:
            raise DataError(f"line {i}: data before the first frame number", path)
        name = tokens[0]
        if name not in n_dof:
            raise DataError(
                f"line {i}: bone {name!r} is not in the skeleton {skeleton.path.name}", path
            )
        if len(tokens) - 1 != n_dof[name]:
            raise DataError(
                f"line {i}: bone {name!r} has {len(tokens) - 1} values, the skeleton says"
                f" {n_dof[name]}",
                path,
            )
        rows.setdefault(name, []).append(tokens[1:])
        seen_in_frame.add(name)
    if n_frames == 0:
        raise DataError("no frames (not an AMC file?)", path)
    if first_frame_bones is None:
        first_frame_bones = set(seen_in_frame)
    if seen_in_frame != first_frame_bones:
        raise DataError(f"last frame {n_frames} is incomplete (truncated file?)", path)
    if "root" not in rows:
        raise DataError("no root values", path)
    values: dict[str, np.ndarray] = {}
    for name, r in rows.items():
        if len(r) != n_frames:
            raise DataError(f"bone {name!r} appears in {len(r)} of {n_frames} frames", path)
        try:
            values[name] = np.array(r, dtype=float)
        except ValueError:
            raise DataError(f"bone {name!r}: a value is not a number", path) from None
    return _finite(Motion(path, values, n_frames, angle_deg))


def _finite(motion: Motion) -> Motion:
    """AMC has no missing values: nan or inf is a damaged file."""
    for name, values in motion.values.items():
        if not np.isfinite(values).all():
            frame = int(np.flatnonzero(~np.isfinite(values).all(axis=1))[0]) + 1
            raise DataError(f"bone {name!r}: not a finite number in frame {frame}", motion.path)
    return motion


def _euler(letters: str, angles: np.ndarray, degrees: bool) -> np.ndarray:
    """Rotation matrices ``(frames, 3, 3)`` applying the axes in the order written."""
    from scipy.spatial.transform import Rotation  # scipy loads when a file is read

    matrices: np.ndarray = Rotation.from_euler(letters.lower(), angles, degrees=degrees).as_matrix()
    return matrices


def forward_kinematics(skel: Skeleton, motion: Motion) -> tuple[tuple[str, ...], np.ndarray]:
    """End points of every bone in metres: names ``(bones,)`` and ``(frames, bones, 3)``."""
    frames = motion.n_frames
    degrees = skel.angle_deg if motion.angle_deg is None else motion.angle_deg
    scale = skel.metres_per_unit
    root_vals = motion.values["root"]
    order = [t.upper() for t in skel.root_order]
    trans = np.zeros((frames, 3))
    rot_letters, rot_cols = "", []
    for col, tok in enumerate(order):
        if tok.startswith("T"):
            trans[:, "XYZ".index(tok[1])] = root_vals[:, col]
        elif tok.startswith("R"):
            rot_letters += tok[1].lower()
            rot_cols.append(col)
    c_root = _euler(skel.root_axis, skel.root_orientation_deg[None], True)[0]
    m_root = (
        _euler(rot_letters, root_vals[:, rot_cols], degrees)
        if rot_letters
        else np.broadcast_to(np.eye(3), (frames, 3, 3))
    )
    glob: dict[str, np.ndarray] = {"root": c_root @ m_root @ c_root.T}
    end: dict[str, np.ndarray] = {"root": trans * scale}
    names = tuple(skel.bones)
    out = np.empty((frames, len(names), 3))
    for k, (name, bone) in enumerate(skel.bones.items()):
        c = _euler(bone.axis_order, bone.axis_deg[None], True)[0]
        rot_dofs = [(i, d) for i, d in enumerate(bone.dof) if d.startswith("r")]
        if rot_dofs and name in motion.values:
            vals = motion.values[name][:, [i for i, _ in rot_dofs]]
            m = _euler("".join(_DOF_AXES[d] for _, d in rot_dofs), vals, degrees)
            local = c @ m @ c.T
        else:
            local = np.broadcast_to(np.eye(3), (frames, 3, 3))
        g = glob[bone.parent] @ local
        glob[name] = g
        end[name] = end[bone.parent] + g @ (bone.direction * bone.length * scale)
        out[:, k] = end[name]
    return names, out


#: AMC files carry no frame rate; the CMU database and HDM05 record at 120 Hz.
ACCLAIM_FPS = 120.0


def amc_frame_rate(path: Path) -> tuple[float, str]:
    """The frame rate of an AMC file and where it comes from.

    Only a full HDM05 name states a rate (``HDM_<actor>_<action>_<take>_<fps>``); any other
    number in a name is not one (a CMU name ``13_29`` is subject 13, trial 29), so the rate is
    then the CMU/HDM05 capture rate, :data:`ACCLAIM_FPS`.
    """
    m = re.match(r"^HDM_[a-z]+_.+_\d+_(\d+)$", path.stem, flags=re.IGNORECASE)
    if m and 10 <= int(m.group(1)) <= 1000:
        return float(m.group(1)), f"from the HDM05 file name (..._{m.group(1)})"
    return ACCLAIM_FPS, f"assumed: AMC files carry no rate, CMU and HDM05 record at {ACCLAIM_FPS:g}"


def hdm05_metadata(path: Path) -> dict[str, object]:
    """label/subject/take from an HDM05 name ``HDM_<actor>_<action>_<take>_<fps>.amc``."""
    m = re.match(r"^HDM_([a-z]+)_(.+)_(\d+)_(\d+)$", path.stem, flags=re.IGNORECASE)
    if not m:
        return {}
    return {"label": m.group(2), "subject": m.group(1), "take": int(m.group(3)),
            "dataset": "hdm05"}  # fmt: skip


def read_asf_amc(
    asf_path: str | Path, amc_path: str | Path, fps: float | None = None
) -> PoseSequence:
    """An ASF/AMC pair as a canonical :class:`PoseSequence` (metres, y up).

    ``fps``: the frame rate; None takes it from an HDM05 name, else 120 Hz
    (:func:`amc_frame_rate`). Where the rate came from is in the metadata (``fps_source``).
    HDM05 names also fill label, subject and take in the metadata.
    """
    amc = Path(amc_path)
    skel = read_asf(asf_path)
    motion = read_amc(amc, skel)
    names, ends = forward_kinematics(skel, motion)
    joint_map = {k: v for k, v in ASF_TO_BLAZEPOSE.items() if v in skel.bones}
    rate, rate_source = (float(fps), "given") if fps is not None else amc_frame_rate(amc)
    return PoseSequence(
        positions=to_canonical(ends, names, joint_map),
        joint_names=BLAZEPOSE_33,
        fps=rate,
        skeleton="asf_amc",
        source=str(amc),
        metadata={"asf": str(asf_path), "fps_source": rate_source, **hdm05_metadata(amc)},
    )
