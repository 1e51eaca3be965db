"""UI-PRMD readers: Kinect v2 (relative positions + angles, forward kinematics) and Vicon.

Kinect files (``m01_s01_e01_positions.txt[.gz]`` with its ``..._angles.txt[.gz]``): 30 Hz,
22 joints x 3 comma-separated columns per row, centimetres, y up. The Waist row is absolute;
every other row is the offset of a joint from its parent in the parent's rotated frame, and the
angles file holds three Euler angles (degrees) per joint. The rotation order is not documented
upstream. Of all 12 Euler orders (intrinsic and extrinsic, on the columns as stored), and for
the plausible ones also the offset rotated by the joint's own rotation instead of its
parent's and the inverse rotations, the one kept below, ``R = Rz(c3) @ Ry(c2) @ Rx(c1)``
applied as ``pos(child) = R_global(parent) @ offset + pos(parent)`` with
``R_global(child) = R_global(parent) @ R(child)``, is the only one that passed every check:
the shoulders on the side the toes say, the bent knees of a deep squat forward of the
hip-ankle line, the ankles still while standing, the feet on the floor and the head above
them (docs/measurements.md, "Figures behind the code's rules: UI-PRMD Kinect's rotation
order and Vicon's gaps"; ``tests/test_readers_uiprmd.py`` repeats these checks).

Bone lengths are not a discriminator: a rotated offset keeps its length, and Kinect
re-estimates the offsets every frame.

Kinect -> BlazePose (a joint Kinect does not track stays NaN):

==================  ================  =====================================================
BlazePose           Kinect (UI-PRMD)  why
==================  ================  =====================================================
left_shoulder       LeftUpperArm      the upper arm's origin is the shoulder joint
left_elbow          LeftForeArm       the forearm's origin is the elbow
left_wrist          LeftHand          Kinect's hand joint sits at the wrist
left_hip            LeftUpperLeg      the thigh's origin is the hip joint
left_knee           LeftLowerLeg      the shank's origin is the knee
left_ankle          LeftFoot          the foot's origin is the ankle
left_foot_index     LeftLegToes       the toe end point is the front of the foot
(right the same)
nose, eyes, ears,   (none)            Kinect's Head/HeadTip are the skull centre and top,
mouth                                 not a face landmark: left NaN
heels, fingers      (none)            not tracked: NaN
==================  ================  =====================================================

Vicon files (``Segmented Movements/Vicon/Positions``): 39 markers x 3 absolute coordinates,
millimetres, z up, x forward, y to the subject's left (right-handed); about 100 Hz (inferred
upstream from repetition lengths, not documented). The marker order is the standard
Plug-in-Gait full-body set (:data:`VICON_MARKERS`); it is an inference that
``tests/test_readers_uiprmd.py`` checks from heights and sides. Joint centres:

==================  ================================  ==========================================
BlazePose           markers                           why
==================  ================================  ==========================================
left_hip            LASI RASI LPSI RPSI               Harrington et al. 2007 regression from
                                                      pelvis width and depth (one occluded
                                                      pelvis marker is filled rigidly)
left_shoulder       LSHO                              acromion marker (~4 cm above the centre)
left_elbow          LELB                              lateral epicondyle (~3 cm lateral)
left_wrist          mean of LWRA, LWRB                the wrist bar spans the two styloids
left_index          LFIN                              2nd metacarpal head = BlazePose's index
                                                      knuckle
left_knee           LKNE                              lateral femoral epicondyle (~5 cm lateral)
left_ankle          LANK                              lateral malleolus (~3 cm lateral)
left_heel           LHEE                              calcaneus marker
left_foot_index     LTOE                              2nd metatarsal head
(right the same)
face, pinky, thumb  (none)                            no such marker: NaN
==================  ================================  ==========================================
"""

from __future__ import annotations

import gzip
import re
import zlib
from pathlib import Path

import numpy as np

from features.errors import DataError

from ..handedness import right_handed
from ..poses import PoseSequence
from ..skeleton import BLAZEPOSE_33, JOINT_INDEX
from ._common import gzipped, read_csv_matrix, to_canonical

KINECT_JOINTS: tuple[str, ...] = (
    "Waist", "Spine", "Chest", "Neck", "Head", "HeadTip",
    "LeftCollar", "LeftUpperArm", "LeftForeArm", "LeftHand",
    "RightCollar", "RightUpperArm", "RightForeArm", "RightHand",
    "LeftUpperLeg", "LeftLowerLeg", "LeftFoot", "LeftLegToes",
    "RightUpperLeg", "RightLowerLeg", "RightFoot", "RightLegToes",
)  # fmt: skip
KINECT_PARENTS: tuple[int, ...] = (
    -1, 0, 1, 2, 3, 4, 2, 6, 7, 8, 2, 10, 11, 12, 0, 14, 15, 16, 0, 18, 19, 20,
)  # fmt: skip
KINECT_FPS = 30.0
# Extrinsic x, y, z with the stored columns (c1, c2, c3) gives Rz(c3) @ Ry(c2) @ Rx(c1); see
# the module docstring for how the alternatives were ruled out.
KINECT_EULER_ORDER = "xyz"

KINECT_TO_BLAZEPOSE: dict[str, str] = {
    "left_shoulder": "LeftUpperArm",
    "left_elbow": "LeftForeArm",
    "left_wrist": "LeftHand",
    "left_hip": "LeftUpperLeg",
    "left_knee": "LeftLowerLeg",
    "left_ankle": "LeftFoot",
    "left_foot_index": "LeftLegToes",
    "right_shoulder": "RightUpperArm",
    "right_elbow": "RightForeArm",
    "right_wrist": "RightHand",
    "right_hip": "RightUpperLeg",
    "right_knee": "RightLowerLeg",
    "right_ankle": "RightFoot",
    "right_foot_index": "RightLegToes",
}

VICON_MARKERS: tuple[str, ...] = (
    "LFHD", "RFHD", "LBHD", "RBHD", "C7", "T10", "CLAV", "STRN", "RBAK",
    "LSHO", "LUPA", "LELB", "LFRM", "LWRA", "LWRB", "LFIN",
    "RSHO", "RUPA", "RELB", "RFRM", "RWRA", "RWRB", "RFIN",
    "LASI", "RASI", "LPSI", "RPSI",
    "LTHI", "LKNE", "LTIB", "LANK", "LHEE", "LTOE",
    "RTHI", "RKNE", "RTIB", "RANK", "RHEE", "RTOE",
)  # fmt: skip
# Inferred upstream from repetition lengths; the files carry no time stamps.
VICON_FPS = 100.0

# BlazePose joint -> markers averaged for it ("HJC" = hip joint centre from the pelvis).
VICON_TO_BLAZEPOSE: dict[str, tuple[str, ...]] = {
    "left_shoulder": ("LSHO",),
    "left_elbow": ("LELB",),
    "left_wrist": ("LWRA", "LWRB"),
    "left_index": ("LFIN",),
    "left_knee": ("LKNE",),
    "left_ankle": ("LANK",),
    "left_heel": ("LHEE",),
    "left_foot_index": ("LTOE",),
    "right_shoulder": ("RSHO",),
    "right_elbow": ("RELB",),
    "right_wrist": ("RWRA", "RWRB"),
    "right_index": ("RFIN",),
    "right_knee": ("RKNE",),
    "right_ankle": ("RANK",),
    "right_heel": ("RHEE",),
    "right_foot_index": ("RTOE",),
}


def uiprmd_sensor(positions_path: Path) -> str:
    """``"kinect"`` or ``"vicon"``: which sensor a UI-PRMD positions file is from, by the width
    of its first row (Kinect 66 numbers, Vicon 117), whatever folder it was copied to; by its
    folder (a path part ``Vicon``) when the first row is neither, so that reader names the
    problem. Raises DataError naming the file when it cannot be read."""
    widths = {len(KINECT_JOINTS) * 3: "kinect", len(VICON_MARKERS) * 3: "vicon"}
    try:
        opener = gzip.open if gzipped(positions_path) else open
        with opener(positions_path, "rb") as fh:
            first = b""
            while not first.strip():
                first = fh.readline(100_000)
                if not first:
                    break
    except (OSError, EOFError, zlib.error) as exc:
        raise DataError(f"cannot read ({type(exc).__name__}: {exc})", positions_path) from None
    sensor = widths.get(len(first.split(b",")) if first.strip() else 0)
    if sensor is not None:
        return sensor
    return "vicon" if any(p.lower() == "vicon" for p in positions_path.parts) else "kinect"


def angles_path_for(positions_path: Path) -> Path:
    """The angles file that belongs to a Kinect positions file.

    Looks beside it, then in the sibling ``Angles`` folder (the UI-PRMD layout); in each, the
    name with the positions file's compression first, then the same file gzipped or not
    (``..._angles.txt`` for ``..._positions.txt.gz``: one of the two decompressed). When there
    is none, the name beside it (for the message that says so).
    """
    name = positions_path.name.replace("_positions", "_angles")
    other = name.removesuffix(".gz") if name.endswith(".gz") else name + ".gz"
    folders = [positions_path.parent]
    if positions_path.parent.name == "Positions":
        folders.append(positions_path.parent.parent / "Angles")
    for folder in folders:
        for candidate in (folder / name, folder / other):
            if candidate.exists():
                return candidate
    if len(folders) > 1:
        return folders[1] / name
    return positions_path.with_name(name)


def kinect_forward_kinematics(offsets: np.ndarray, angles_deg: np.ndarray) -> np.ndarray:
    """Absolute joint positions from UI-PRMD's parent-relative offsets and Euler angles.

    offsets: ``(frames, 22, 3)`` (row 0 absolute Waist position, others parent-relative);
    angles_deg: ``(frames, 22, 3)``. Returns ``(frames, 22, 3)`` in the input's units.
    Vectorised over frames; the loop runs over the 22 joints in parent-first order.
    """
    from scipy.spatial.transform import Rotation  # scipy loads when a file is read

    frames = offsets.shape[0]
    local = (
        Rotation.from_euler(KINECT_EULER_ORDER, angles_deg.reshape(-1, 3), degrees=True)
        .as_matrix()
        .reshape(frames, len(KINECT_JOINTS), 3, 3)
    )
    glob = np.empty_like(local)
    pos = np.empty_like(offsets)
    for j, parent in enumerate(KINECT_PARENTS):
        if parent < 0:
            glob[:, j] = local[:, j]
            pos[:, j] = offsets[:, j]
        else:
            pos[:, j] = pos[:, parent] + np.einsum("fab,fb->fa", glob[:, parent], offsets[:, j])
            glob[:, j] = glob[:, parent] @ local[:, j]
    return pos


def read_uiprmd_kinect_joints(
    positions_path: str | Path, angles_path: str | Path | None = None
) -> np.ndarray:
    """Absolute Kinect joint positions in metres, ``(frames, 22, 3)`` in :data:`KINECT_JOINTS`."""
    ppath = Path(positions_path)
    apath = Path(angles_path) if angles_path is not None else angles_path_for(ppath)
    if not apath.exists():
        raise DataError(
            f"no angles file {apath.name} beside it (Kinect positions are parent-relative and"
            " need the angles for forward kinematics)",
            ppath,
        )
    n = len(KINECT_JOINTS) * 3
    offsets = read_csv_matrix(ppath, n)
    angles = read_csv_matrix(apath, n)
    if offsets.shape[0] != angles.shape[0]:
        raise DataError(
            f"{offsets.shape[0]} frames but its angles file {apath.name} has {angles.shape[0]}"
            " (truncated?)",
            ppath,
        )
    frames = offsets.shape[0]
    cm = kinect_forward_kinematics(offsets.reshape(frames, -1, 3), angles.reshape(frames, -1, 3))
    return cm / 100.0


UIPRMD_MOVEMENTS: dict[str, str] = {
    "m01": "deep_squat",
    "m02": "hurdle_step",
    "m03": "inline_lunge",
    "m04": "side_lunge",
    "m05": "sit_to_stand",
    "m06": "standing_active_straight_leg_raise",
    "m07": "standing_shoulder_abduction",
    "m08": "standing_shoulder_extension",
    "m09": "standing_shoulder_internal_external_rotation",
    "m10": "standing_shoulder_scaption",
}
"""The label of each UI-PRMD movement code."""


#: the columns :func:`read_uiprmd_kinect` and :func:`read_uiprmd_vicon` give every clip's
#: metadata besides those its file's name gives (:func:`uiprmd_metadata`): what a target can be,
#: told before a clip is read
UIPRMD_COLUMNS = frozenset({"dataset", "sensor", "fps_source"})


def uiprmd_metadata(path: Path) -> dict[str, object]:
    """label (the movement's name, :data:`UIPRMD_MOVEMENTS`; the code when unknown),
    movement/subject/episode/correct from a UI-PRMD file name (empty when it does not fit)."""
    m = re.match(r"^m(\d+)_s(\d+)_e(\d+)_[a-z]+(_inc)?\.txt(\.gz)?$", path.name)
    if not m:
        return {}
    movement = f"m{int(m.group(1)):02d}"
    return {
        "label": UIPRMD_MOVEMENTS.get(movement, movement),
        "movement": movement,
        "subject": f"s{int(m.group(2)):02d}",
        "episode": int(m.group(3)),
        "correct": m.group(4) is None,
    }


def read_uiprmd_kinect(
    positions_path: str | Path, angles_path: str | Path | None = None
) -> PoseSequence:
    """A UI-PRMD Kinect repetition as a canonical :class:`PoseSequence` (30 Hz, metres).

    ``angles_path`` defaults to the matching ``..._angles`` file beside the positions file or
    in the sibling ``Angles`` folder. Metadata: movement, subject, episode, correct (from the
    file name), dataset "ui-prmd", sensor "kinect".
    """
    ppath = Path(positions_path)
    joints = read_uiprmd_kinect_joints(ppath, angles_path)
    meta: dict[str, object] = {
        "dataset": "ui-prmd",
        "sensor": "kinect",
        "fps_source": "assumed: UI-PRMD's Kinect rate; the files carry no time",
        **uiprmd_metadata(ppath),
    }
    seq = PoseSequence(
        positions=to_canonical(joints, KINECT_JOINTS, KINECT_TO_BLAZEPOSE),
        joint_names=BLAZEPOSE_33,
        fps=KINECT_FPS,
        skeleton="uiprmd_kinect",
        source=str(ppath),
        metadata=meta,
    )
    return right_handed(seq)


def read_uiprmd_vicon_markers(path: str | Path) -> np.ndarray:
    """Vicon markers in the canonical frame: ``(frames, 39, 3)`` metres, y up, x to the left.

    NaN where the marker was occluded.
    The files are z up, x forward, y left (mm); (y, z, x) is a cyclic permutation of the axes,
    so it is a proper rotation and keeps the frame right-handed.
    """
    path = Path(path)
    raw = read_csv_matrix(path, len(VICON_MARKERS) * 3).reshape(-1, len(VICON_MARKERS), 3)
    # Vicon writes an occluded marker as exactly (0, 0, 0): a gap, not a point at the origin.
    raw[(raw == 0).all(axis=2)] = np.nan
    return raw[..., [1, 2, 0]] / 1000.0


PELVIS_MARKERS: tuple[str, ...] = ("LASI", "RASI", "LPSI", "RPSI")


def fill_rigid_gaps(markers: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Fill frames where exactly one of ``names`` (markers on one rigid segment) is missing.

    markers: ``(frames, 39, 3)``, NaN = occluded; returns a copy. The standard rigid-body gap
    fill: a template of the segment (the fully visible frame whose inter-marker distances are
    closest to their medians) is fitted to the visible markers by least squares (Kabsch,
    vectorised over frames), and the missing marker is taken from the fitted template. Frames
    with two or more of them missing, or a segment never fully visible, stay NaN. A few
    millimetres off while standing, up to centimetres at full hip flexion, where the skin over
    the ASIS slides (docs/measurements.md, "Figures behind the code's rules: UI-PRMD Kinect's
    rotation order and Vicon's gaps").
    """
    out = markers.copy()
    ix = [VICON_MARKERS.index(n) for n in names]
    seg = markers[:, ix]  # (frames, k, 3)
    missing = np.isnan(seg).any(axis=2)  # (frames, k)
    complete = np.flatnonzero(~missing.any(axis=1))
    if complete.size == 0:
        return out
    dist = np.linalg.norm(seg[complete, :, None] - seg[complete, None, :], axis=3)
    typical = complete[np.argmin(np.abs(dist - np.median(dist, axis=0)).sum(axis=(1, 2)))]
    template = seg[typical]  # (k, 3)
    for m in range(len(ix)):
        gap = np.flatnonzero(missing[:, m] & (missing.sum(axis=1) == 1))
        if gap.size == 0:
            continue
        keep = [j for j in range(len(ix)) if j != m]
        src = template[keep]  # (k-1, 3)
        dst = seg[gap][:, keep]  # (g, k-1, 3)
        src_c = src - src.mean(axis=0)
        dst_mean = dst.mean(axis=1, keepdims=True)
        h = np.einsum("ki,gkj->gij", src_c, dst - dst_mean)  # (g, 3, 3) covariance
        u, _, vt = np.linalg.svd(h)
        d = np.sign(np.linalg.det(np.swapaxes(vt, 1, 2) @ np.swapaxes(u, 1, 2)))
        fix = np.ones((gap.size, 3))
        fix[:, 2] = d  # no reflections
        rot = np.swapaxes(vt, 1, 2) @ (fix[:, :, None] * np.swapaxes(u, 1, 2))
        out[gap, ix[m]] = dst_mean[:, 0] + rot @ (template[m] - src.mean(axis=0))
    return out


def harrington_hip_centres(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Left and right hip joint centres, each ``(frames, 3)``, from the four pelvis markers.

    markers: ``(frames, 39, 3)`` canonical metres; a frame missing a pelvis marker gives NaN.
    Harrington et al., J Biomech 40(3) 2007:
    in the pelvis frame (origin mid-ASIS, x anterior, y superior, z right), with pelvis width PW
    (ASIS to ASIS) and depth PD (mid-ASIS to mid-PSIS) in mm: x = -0.24 PD - 9.9,
    y = -0.30 PW - 10.9, z = +-(0.33 PW + 7.3).
    """
    ix = {n: i for i, n in enumerate(VICON_MARKERS)}
    lasi, rasi = markers[:, ix["LASI"]], markers[:, ix["RASI"]]
    mid_asis = (lasi + rasi) / 2
    mid_psis = (markers[:, ix["LPSI"]] + markers[:, ix["RPSI"]]) / 2
    right = rasi - lasi
    pw = np.linalg.norm(right, axis=1, keepdims=True)
    ant = mid_asis - mid_psis
    pd = np.linalg.norm(ant, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):  # a missing marker gives NaN, no warning
        z = right / pw
        x = ant - (ant * z).sum(1, keepdims=True) * z  # anterior, orthogonal to the lateral axis
        x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(z, x)  # superior: z (right) x x (anterior) = up in a right-handed frame
    pw_mm, pd_mm = pw * 1000, pd * 1000
    dx = (-0.24 * pd_mm - 9.9) / 1000
    dy = (-0.30 * pw_mm - 10.9) / 1000
    dz = (0.33 * pw_mm + 7.3) / 1000
    base = mid_asis + dx * x + dy * y
    return base - dz * z, base + dz * z


def read_uiprmd_vicon(path: str | Path) -> PoseSequence:
    """A UI-PRMD Vicon repetition as a canonical :class:`PoseSequence` (joint centres, metres).

    A joint is NaN in frames where a marker it is computed from was occluded, except the hips:
    a single occluded pelvis marker is filled from the other three (:func:`fill_rigid_gaps`).
    """
    path = Path(path)
    markers = read_uiprmd_vicon_markers(path)
    meta: dict[str, object] = {
        "dataset": "ui-prmd",
        "sensor": "vicon",
        "fps_source": "assumed: UI-PRMD's Vicon rate, inferred upstream; the files carry no time",
        **uiprmd_metadata(path),
    }
    seq = PoseSequence(
        positions=vicon_joints(markers),
        joint_names=BLAZEPOSE_33,
        fps=VICON_FPS,
        skeleton="uiprmd_vicon",
        source=str(path),
        metadata=meta,
    )
    # a left-handed file: its joints placed again from the markers reflected back (the hips'
    # pelvis frame is right-handed only then)
    return right_handed(
        seq, reflected_back=lambda: vicon_joints(markers * np.array([-1.0, 1.0, 1.0]))
    )


def vicon_joints(markers: np.ndarray) -> np.ndarray:
    """The canonical joints ``(frames, 33, 3)`` placed from Vicon markers ``(frames, 39, 3)``
    (canonical frame, metres; NaN where occluded), :data:`VICON_TO_BLAZEPOSE` and the hips."""
    ix = {n: i for i, n in enumerate(VICON_MARKERS)}
    out = np.full((markers.shape[0], len(JOINT_INDEX), 3), np.nan)
    for joint, names in VICON_TO_BLAZEPOSE.items():
        # a plain mean: a joint is NaN in a frame where any of its markers is missing
        out[:, JOINT_INDEX[joint]] = markers[:, [ix[n] for n in names]].mean(axis=1)
    left_hip, right_hip = harrington_hip_centres(fill_rigid_gaps(markers, PELVIS_MARKERS))
    out[:, JOINT_INDEX["left_hip"]] = left_hip
    out[:, JOINT_INDEX["right_hip"]] = right_hip
    return out
