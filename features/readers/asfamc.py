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
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from features.errors import DataError

from ..handedness import right_handed
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
    """One ASF bone: direction ``(3,)`` unit, length (ASF units), local axis (Euler angles in
    the skeleton's angle unit), dofs."""

    name: str
    direction: np.ndarray
    length: float
    axis: np.ndarray
    axis_order: str
    dof: tuple[str, ...] = ()
    parent: str = "root"


@dataclass
class Skeleton:
    """A parsed ASF file. Bones are listed parents first; every angle in it (the root's
    orientation, the bones' axes) is in degrees when ``angle_deg``, else radians (``:units
    angle``)."""

    path: Path
    length_scale: float
    angle_deg: bool
    root_order: tuple[str, ...]
    root_axis: str
    root_orientation: np.ndarray
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
    first_number: int = 1  # the first frame's number in the file (0 or 1, usually)


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
    skel = Skeleton(path, 1.0, True, ("TX", "TY", "TZ", "RX", "RY", "RZ"), "XYZ", np.zeros(3))
    blocks = _BoneBlocks(path)
    hierarchy: list[tuple[int, list[str]]] = []
    root_seen = False
    for section, line_no, tokens in _asf_sections(read_text(path).split("\n"), path):
        if section == "units":
            _units_line(skel, tokens, line_no)
        elif section == "root":
            root_seen = True
            _root_line(skel, tokens, line_no)
        elif section == "bonedata":
            blocks.line(tokens, line_no)
        elif section == "hierarchy" and tokens[0].lower() not in ("begin", "end"):
            hierarchy.append((line_no, tokens))
    defined = {bone.name: bone for bone in blocks.bones(root_seen)}
    skel.bones = _parents_first(defined, _parent_of(hierarchy, defined, path), path)
    return skel


_NEEDS_VALUE = frozenset({"name", "axis", "order", "direction", "length"})
_STATEMENTS = frozenset({"units", "root", "bonedata"})  # not free text (``:documentation``)


def _asf_sections(lines: list[str], path: Path) -> Iterator[tuple[str, int, list[str]]]:
    """Each statement of an ASF file as (section, line number, tokens): comments and blank
    lines dropped, the ``:section`` lines consumed (``units``, ``root``, ``bonedata``, ...)."""
    section = ""
    for line_no, raw in enumerate(lines, start=1):
        tokens = raw.split("#", 1)[0].split()
        if not tokens:
            continue
        head = tokens[0].lower()
        if len(tokens) < 2 and head in _NEEDS_VALUE and section in _STATEMENTS:
            raise DataError(f"line {line_no}: {head!r} without a value", path)
        if head.startswith(":"):
            section = head[1:]
            if section == "units":  # ``:units mass 1.0 length 0.45 angle deg`` on one line
                yield from _unit_pairs(tokens[1:], path, line_no)
            continue
        yield section, line_no, tokens


def _unit_pairs(
    tokens: list[str], path: Path, line_no: int
) -> Iterator[tuple[str, int, list[str]]]:
    """The ``name value`` statements written on the ``:units`` line itself, as if each had
    a line of its own (as they usually do)."""
    if len(tokens) % 2:
        raise DataError(
            f"line {line_no}: :units {' '.join(tokens)[:40]!r} is not name value pairs", path
        )
    for k in range(0, len(tokens), 2):
        yield "units", line_no, tokens[k : k + 2]


def _units_line(skel: Skeleton, tokens: list[str], line_no: int) -> None:
    """A ``:units`` statement: the length scale or the angle unit (others, like mass, unused)."""
    if len(tokens) < 2:
        return
    head = tokens[0].lower()
    if head == "length":
        scale = float(_floats(tokens[1:2], skel.path, line_no)[0])
        if scale <= 0:  # metres = value x 0.0254 / scale
            raise DataError(
                f"line {line_no}: units length must be positive, got {scale:g}", skel.path
            )
        skel.length_scale = scale
    elif head == "angle":
        skel.angle_deg = tokens[1].lower().startswith("deg")


def _root_line(skel: Skeleton, tokens: list[str], line_no: int) -> None:
    """A ``:root`` statement: channel order, axis order or orientation (position unused)."""
    head = tokens[0].lower()
    if head == "order":
        skel.root_order = _root_order(tokens[1:], skel.path, line_no)
    elif head == "axis":
        skel.root_axis = _axis_order(tokens[1], skel.path, line_no)
    elif head == "orientation":
        skel.root_orientation = _floats(tokens[1:4], skel.path, line_no, 3)


@dataclass
class _BoneDraft:
    """One ``begin`` ... ``end`` block of ``:bonedata`` as read, before it is checked."""

    line: int
    name: str | None = None
    direction: np.ndarray | None = None
    length: float | None = None
    axis: np.ndarray | None = None
    order: str = "XYZ"
    dof: tuple[str, ...] = ()


class _BoneBlocks:
    """The ``:bonedata`` section, statement by statement: ``begin`` opens a bone, ``end``
    closes it; statements outside a block are ignored."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.open: _BoneDraft | None = None
        self.closed: list[_BoneDraft] = []

    def line(self, tokens: list[str], line_no: int) -> None:
        head = tokens[0].lower()
        if head == "begin":
            self.open = _BoneDraft(line_no)
        elif head == "end":
            if self.open is None:
                raise DataError(f"line {line_no}: 'end' without 'begin'", self.path)
            self.closed.append(self.open)
            self.open = None
        elif self.open is not None:
            _bone_field(self.open, tokens, self.path, line_no)

    def bones(self, root_seen: bool) -> list[Bone]:
        """The bones read, checked (every block closed, name, direction and length given,
        known dofs), in file order. ``root_seen``: the file has a ``:root`` section, so a
        file without bones is a skeleton of its root alone, not another kind of file."""
        if self.open is not None:
            raise DataError("bone definition not closed with 'end' (truncated?)", self.path)
        if not self.closed and root_seen:
            raise DataError(
                "the skeleton has only its root (no :bonedata bones); there are no limbs to draw",
                self.path,
            )
        if not self.closed:
            raise DataError("no :bonedata bones (not an ASF file?)", self.path)
        return [_bone(draft, self.path) for draft in self.closed]


def _bone_field(draft: _BoneDraft, tokens: list[str], path: Path, line_no: int) -> None:
    """One statement inside a bone block (``id`` and ``limits`` are not needed)."""
    head = tokens[0].lower()
    if head == "name":
        draft.name = tokens[1]
    elif head == "direction":
        draft.direction = _floats(tokens[1:4], path, line_no, 3)
    elif head == "length":
        draft.length = float(_floats(tokens[1:2], path, line_no, 1)[0])
        if draft.length < 0:  # the bone would point the other way: the joint below it flipped
            raise DataError(f"line {line_no}: a bone's length must be >= 0, got {tokens[1]}", path)
    elif head == "axis":
        draft.axis = _floats(tokens[1:4], path, line_no, 3)
        draft.order = _axis_order(tokens[4], path, line_no) if len(tokens) > 4 else "XYZ"
    elif head == "dof":
        draft.dof = tuple(t.lower() for t in tokens[1:])


def _bone(draft: _BoneDraft, path: Path) -> Bone:
    """A checked :class:`Bone` from its block; its direction scaled to unit length."""
    missing = [k for k in ("name", "direction", "length") if getattr(draft, k) is None]
    if missing:
        raise DataError(f"line {draft.line}: bone lacks {', '.join(missing)}", path)
    assert draft.name is not None and draft.direction is not None and draft.length is not None
    bad = [d for d in draft.dof if d not in _DOF_AXES]
    if bad:
        raise DataError(f"line {draft.line}: unknown dof {bad[0]!r}", path)
    norm = np.linalg.norm(draft.direction)
    return Bone(
        name=draft.name,
        direction=draft.direction / norm if norm > 0 else draft.direction,
        length=draft.length,
        axis=draft.axis if draft.axis is not None else np.zeros(3),
        axis_order=draft.order,
        dof=draft.dof,
    )


def _parent_of(
    hierarchy: list[tuple[int, list[str]]], defined: Mapping[str, Bone], path: Path
) -> dict[str, str]:
    """Each bone's parent from the ``:hierarchy`` lines ``parent child child ...``."""
    parent_of: dict[str, str] = {}
    for line_no, tokens in hierarchy:
        for child in tokens[1:]:
            if child not in defined:
                raise DataError(f"line {line_no}: hierarchy names unknown bone {child!r}", path)
            parent_of[child] = tokens[0]
    return parent_of


def _parents_first(
    defined: dict[str, Bone], parent_of: Mapping[str, str], path: Path
) -> dict[str, Bone]:
    """The bones ordered parents first (so forward kinematics runs in one pass), each with
    its parent set; every bone must hang from the root."""
    orphans = [n for n in defined if n not in parent_of]
    if orphans:
        raise DataError(f"bone {orphans[0]!r} is not in the :hierarchy", path)
    ordered: dict[str, Bone] = {}
    pending = list(defined)
    while pending:
        waiting = []
        for n in pending:  # in file order; a child may follow its parent in the same pass
            if parent_of[n] == "root" or parent_of[n] in ordered:
                defined[n].parent = parent_of[n]
                ordered[n] = defined[n]
            else:
                waiting.append(n)
        if len(waiting) == len(pending):
            raise DataError(f"hierarchy has a cycle or unknown parent near {pending[0]!r}", path)
        pending = waiting
    return ordered


def _read_amc_fast(
    path: Path, lines: list[str], n_dof: dict[str, int], angle_deg: bool | None
) -> Motion | None:
    """Every frame lists the same bones in the same order (AMC exporters write it so):
    parse each bone's column of lines at once. None when the file does not fit that shape,
    so the line by line parser can name the problem."""
    k = _frame_stride(lines)
    if k is None:
        return None
    n_frames = len(lines) // k
    values: dict[str, np.ndarray] = {}
    for j in range(1, k):
        column = _bone_column(lines[j::k], n_dof, n_frames)
        if column is None or column[0] in values:
            return None
        values[column[0]] = column[1]
    if "root" not in values:
        return None
    return Motion(path, values, n_frames, angle_deg, int(lines[0]))


def _is_frame_number(text: str) -> bool:
    """Whether a line is a frame number: ASCII digits (``"²"``, a latin-1 byte read as a
    superscript, is a digit to ``str.isdigit`` but no number to ``int``)."""
    return text.isascii() and text.isdigit()


def _frame_stride(lines: list[str]) -> int | None:
    """Lines per frame (its number and its bones) when every frame has as many lines, each
    starting with its frame number, numbered one after another; None otherwise."""
    if not lines or not _is_frame_number(lines[0]):
        return None
    k = 1
    while k < len(lines) and not _is_frame_number(lines[k]):
        k += 1
    if len(lines) % k or not all(_is_frame_number(line) for line in lines[::k]):
        return None
    if any(int(b) != int(a) + 1 for a, b in zip(lines[:-k:k], lines[k::k], strict=True)):
        return None  # frames missing or out of order: the line by line parser names them
    return k


def _bone_column(
    column: list[str], n_dof: Mapping[str, int], n_frames: int
) -> tuple[str, np.ndarray] | None:
    """One bone's line in every frame as (bone, values ``(frames, n_dof)``); None when the
    lines name different or unknown bones or hold the wrong count of numbers."""
    name = column[0].split(None, 1)[0]
    if name not in n_dof:
        return None
    tokens = " ".join(column).split()
    width = n_dof[name] + 1
    if len(tokens) != n_frames * width:
        return None
    table = np.array(tokens, dtype=object).reshape(n_frames, width)
    if not (table[:, 0] == name).all():
        return None
    try:
        return name, table[:, 1:].astype(np.float64)
    except ValueError:
        return None


def read_amc(path: str | Path, skeleton: Skeleton) -> Motion:
    """Parse an AMC motion file against its skeleton. Frames must be complete."""
    path = Path(path)
    lines = read_text(path).split("\n")
    n_dof = {name: len(b.dof) for name, b in skeleton.bones.items()}
    n_dof["root"] = len(skeleton.root_order)
    body = [ln.strip() for ln in lines]
    body = [ln for ln in body if ln and not ln.startswith("#")]
    deg = _amc_angle_unit(ln for ln in body if ln.startswith(":"))
    fast = _read_amc_fast(path, [ln for ln in body if not ln.startswith(":")], n_dof, deg)
    if fast is not None:
        return _finite(fast)
    return _finite(_read_amc_by_line(path, lines, skeleton, n_dof, deg))


def _amc_angle_unit(headers: Iterable[str]) -> bool | None:
    """True for ``:DEGREES``, False for ``:RADIANS`` (which wins if both appear), None when
    the header says neither (the skeleton's unit then holds)."""
    keys = [h[1:].upper() for h in headers]
    if any(k.startswith("RAD") for k in keys):
        return False
    return True if any(k.startswith("DEG") for k in keys) else None


def _read_amc_by_line(
    path: Path, lines: list[str], skeleton: Skeleton, n_dof: Mapping[str, int], deg: bool | None
) -> Motion:
    """The AMC file line by line, naming the first line that does not fit ``skeleton``."""
    frames = _AmcFrames(path)
    for line_no, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith(("#", ":")):
            continue
        tokens = line.split()
        if len(tokens) == 1 and _is_frame_number(tokens[0]):
            frames.next_frame(line_no, int(tokens[0]))
        else:
            frames.add(tokens, line_no, n_dof, skeleton.path.name)
    return Motion(path, frames.values(), frames.n_frames, deg, frames.first_number)


class _AmcFrames:
    """The bones' rows of an AMC file as they are read, frame after frame; every frame must
    list the bones the first one lists."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.rows: dict[str, list[list[str]]] = {}
        self.n_frames = 0
        self.seen: set[str] = set()
        self.first: set[str] | None = None
        self.number: int | None = None  # the frame number last read, as the file has it
        self.first_number = 1
        self.opening: str | None = None  # the bone the current frame began with

    def next_frame(self, line_no: int, number: int) -> None:
        """A frame number: one more than the frame before it (a gap would join the frames
        around it as if no time passed between them), and the frame before it must list the
        bones the first one lists."""
        if self.n_frames == 1:
            self.first = set(self.seen)
        elif self.first is not None and self.seen != self.first:
            raise DataError(f"line {line_no}: {self._mismatch()}", self.path)
        if self.number is None:
            self.first_number = number
        elif number != self.number + 1:
            raise DataError(
                f"line {line_no}: frame {number} follows frame {self.number} (AMC frames are"
                " numbered one after another: frames missing or out of order?)",
                self.path,
            )
        self.number = number
        self.n_frames += 1
        self.seen = set()

    def _mismatch(self) -> str:
        """How the current frame's bones differ from the first frame's, in words (frames by
        their numbers in the file)."""
        assert self.first is not None
        lacks, extra = sorted(self.first - self.seen), sorted(self.seen - self.first)
        if lacks:
            return f"frame {self.number} is incomplete: no {', '.join(lacks[:5])}"
        return (
            f"frame {self.number} lists {', '.join(extra[:5])}, which frame"
            f" {self.first_number} does not (every frame must list the same bones)"
        )

    def add(
        self, tokens: list[str], line_no: int, n_dof: Mapping[str, int], skeleton_name: str
    ) -> None:
        """One bone's line ``name value ...`` of the current frame."""
        if self.n_frames == 0:
            raise DataError(f"line {line_no}: data before the first frame number", self.path)
        name = tokens[0]
        if name not in n_dof:
            raise DataError(
                f"line {line_no}: bone {name!r} is not in the skeleton {skeleton_name}", self.path
            )
        if len(tokens) - 1 != n_dof[name]:
            raise DataError(
                f"line {line_no}: bone {name!r} has {len(tokens) - 1} values, the skeleton says"
                f" {n_dof[name]}",
                self.path,
            )
        if name in self.seen:
            raise DataError(f"line {line_no}: {self._twice(name)}", self.path)
        if not self.seen:
            self.opening = name
        self.rows.setdefault(name, []).append(tokens[1:])
        self.seen.add(name)

    def _twice(self, name: str) -> str:
        """Bone ``name`` comes again in the current frame, in words. When it is the bone the
        frame began with and the frame has listed every bone the first frame lists, the next
        frame's bones follow without their frame number (a line lost)."""
        complete = self.first is None or self.seen >= self.first
        if complete and name == self.opening:
            return (
                f"bone {name!r} again after every bone of frame {self.number}: the frame number"
                f" after frame {self.number} is missing"
            )
        return f"bone {name!r} is listed twice in frame {self.number}"

    def values(self) -> dict[str, np.ndarray]:
        """Per bone its values ``(frames, n_dof)``, once every frame is checked complete."""
        if self.n_frames == 0:
            raise DataError("no frames (not an AMC file?)", self.path)
        if self.first is not None and self.seen != self.first:
            truncated = " (truncated file?)" if self.seen < self.first else ""
            raise DataError(f"last {self._mismatch()}{truncated}", self.path)
        if "root" not in self.rows:
            raise DataError("no root values", self.path)
        return {name: self._array(name, rows) for name, rows in self.rows.items()}

    def _array(self, name: str, rows: list[list[str]]) -> np.ndarray:
        if len(rows) != self.n_frames:
            raise DataError(
                f"bone {name!r} appears in {len(rows)} of {self.n_frames} frames", self.path
            )
        try:
            return np.array(rows, dtype=float)
        except ValueError:
            raise DataError(f"bone {name!r}: a value is not a number", self.path) from None


def _finite(motion: Motion) -> Motion:
    """AMC has no missing values: nan or inf is a damaged file."""
    for name, values in motion.values.items():
        if not np.isfinite(values).all():
            frame = int(np.flatnonzero(~np.isfinite(values).all(axis=1))[0])
            frame += motion.first_number  # as the file numbers it
            raise DataError(f"bone {name!r}: not a finite number in frame {frame}", motion.path)
    return motion


def _euler(letters: str, angles: np.ndarray, degrees: bool) -> np.ndarray:
    """Rotation matrices ``(frames, 3, 3)`` applying the axes in the order written."""
    from scipy.spatial.transform import Rotation  # scipy loads when a file is read

    matrices: np.ndarray = Rotation.from_euler(letters.lower(), angles, degrees=degrees).as_matrix()
    return matrices


def forward_kinematics(skel: Skeleton, motion: Motion) -> tuple[tuple[str, ...], np.ndarray]:
    """End points of every bone in metres: names ``(bones,)`` and ``(frames, bones, 3)``.

    A bone with rotation dofs that the AMC file never lists has an unknown rotation: its end
    point and those of the bones below it are NaN."""
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
    c_root = _euler(skel.root_axis, skel.root_orientation[None], skel.angle_deg)[0]
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
        c = _euler(bone.axis_order, bone.axis[None], skel.angle_deg)[0]
        rot_dofs = [(i, d) for i, d in enumerate(bone.dof) if d.startswith("r")]
        if rot_dofs and name in motion.values:
            vals = motion.values[name][:, [i for i, _ in rot_dofs]]
            m = _euler("".join(_DOF_AXES[d] for _, d in rot_dofs), vals, degrees)
            local = c @ m @ c.T
        elif rot_dofs:
            # the bone turns but the AMC gives it no values: its end and everything below it
            # are unknown (NaN), not the rest pose
            local = np.full((frames, 3, 3), np.nan)
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


#: the columns :func:`read_asf_amc` gives every clip's metadata besides those its file's name
#: gives (:func:`hdm05_metadata`): what a target can be, told before a clip is read
ASF_AMC_COLUMNS = frozenset({"asf", "fps_source"})


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
    joint_map = _joint_map(skel)
    motion = read_amc(amc, skel)
    names, ends = forward_kinematics(skel, motion)
    positions = to_canonical(ends, names, joint_map)
    _check_limbs_given(skel, motion, positions)
    rate, rate_source = (float(fps), "given") if fps is not None else amc_frame_rate(amc)
    seq = PoseSequence(
        positions=positions,
        joint_names=BLAZEPOSE_33,
        fps=rate,
        skeleton="asf_amc",
        source=str(amc),
        metadata={"asf": str(asf_path), "fps_source": rate_source, **hdm05_metadata(amc)},
    )
    return right_handed(seq)


def _joint_map(skel: Skeleton) -> dict[str, str]:
    """:data:`ASF_TO_BLAZEPOSE` for the bones ``skel`` has. Raises DataError naming the ASF
    file when it has none of them: every joint of every frame would be missing, a clip that
    converts and then "shows no person" to every command."""
    joint_map = {k: v for k, v in ASF_TO_BLAZEPOSE.items() if v in skel.bones}
    if not joint_map:
        bones = list(skel.bones)
        raise DataError(
            "none of its bones is one a joint is placed at (lhipjoint, lfemur, ltibia, lclavicle,"
            " lhumerus, lradius, ...; features.readers.asfamc.ASF_TO_BLAZEPOSE): it has "
            + ", ".join(bones[:8])
            + (", ..." if len(bones) > 8 else "")
            + "; there are no limbs to draw",
            skel.path,
        )
    return joint_map


def _check_limbs_given(skel: Skeleton, motion: Motion, positions: np.ndarray) -> None:
    """Refuse, naming the AMC file, a motion that gives no values for the skeleton's turning
    bones (it lists the root alone) or places no joint in any frame: the limbs hang from those
    bones, so the clip would convert and then "show no person" to every command (a real
    skeleton's hip bones do not turn, so the root alone still places the two hips)."""
    turning = [n for n, b in skel.bones.items() if any(d.startswith("r") for d in b.dof)]
    unlisted = [n for n in turning if n not in motion.values]
    only_root = set(motion.values) == {"root"}
    if not ((only_root and turning) or np.isnan(positions).all()):
        return
    listed = sorted(motion.values)
    what = (
        "only root" if only_root else ", ".join(listed[:5]) + (", ..." if len(listed) > 5 else "")
    )
    raise DataError(
        f"lists {what}, no values for {', '.join(unlisted[:5])}"
        f"{', ...' if len(unlisted) > 5 else ''} (bones of {skel.path.name} that turn): there"
        " are no limbs to draw",
        motion.path,
    )
