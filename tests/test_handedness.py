"""Recordings written left-handed (x reflected, left/right names kept) are read back.

Before, such a recording was read as it was: the body frame built from the named shoulders and
hips faced backwards, so HDM05 bd's squat, arms held out in front, read "left arm behind" in
every frame and its legs "moving backward" as they rose. Now the readers and ``load_clip`` tell
it from the toes and the nose (:mod:`features.handedness`) and negate x, with a note.
"""

from __future__ import annotations

import dataclasses
import gzip
from pathlib import Path

import numpy as np
import pytest

from features.body import mirrored
from features.datasets import load_clip
from features.handedness import METADATA_KEY, reflected_evidence
from features.poses import PoseSequence, load_pose, save_pose
from features.readers.asfamc import read_asf_amc
from features.readers.bvh import read_bvh
from features.skeleton import JOINT_INDEX
from posecbr.cli import main
from tests.bodies import standing, to_sequence

SQUAT = "hdm05/train/10/HDM_bd_squat1Reps_001_120.amc"
UIPRMD = "ui-prmd/data/Segmented Movements/{}/Positions/m01_s01_e01_positions.txt.gz"


def _real(shared_data: Path, which: str) -> PoseSequence:
    if which == "hdm05":
        amc = shared_data / SQUAT
        return read_asf_amc(amc.parent / "HDM_bd.asf", amc)
    if which == "cmu":
        amc = shared_data / "cmu-mocap6/amc/13_30.amc"
        return read_asf_amc(shared_data / "hdm05/train/3/HDM_bd.asf", amc)
    return load_clip(shared_data / UIPRMD.format(which))


def _reflected(seq: PoseSequence, axis: int = 0) -> PoseSequence:
    pos = seq.positions.copy()
    pos[..., axis] *= -1.0
    return dataclasses.replace(seq, positions=pos)


@pytest.mark.parametrize("which", ["hdm05", "cmu", "Kinect", "Vicon"])
def test_real_recordings_read_as_they_are_and_reflected_read_back(
    shared_data: Path, tmp_path: Path, which: str, capsys: pytest.CaptureFixture[str]
) -> None:
    seq = _real(shared_data, which)
    assert METADATA_KEY not in seq.metadata
    assert capsys.readouterr().err == ""  # no note for a recording as it was recorded
    # the same recording written left-handed, as a pose file: read back to the original
    path = save_pose(_reflected(seq), tmp_path / "reflected.npz")
    back = load_clip(path)
    np.testing.assert_array_equal(back.positions, seq.positions)
    assert "read with x negated" in back.metadata[METADATA_KEY]
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"note: {path}: read with x negated: written")
    # the legitimate mirror image (left and right swapped with x) is a body: not touched
    assert reflected_evidence(mirrored(seq).positions)[0] > 0.25


@pytest.mark.parametrize("axis", [0, 2])  # x or z reflected
def test_reflected_squat_describes_as_the_original(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], axis: int
) -> None:
    seq = _real(shared_data, "hdm05")
    # hand check of the scene: at the bottom of the squat (frame 70) both wrists are ahead of
    # their shoulders the way the toes point (about 0.5 m), so "arm in front" is right
    p = seq.positions[70]
    toes = p[JOINT_INDEX["left_foot_index"]] - p[JOINT_INDEX["left_ankle"]]
    ahead = np.array([toes[0], 0.0, toes[2]]) / np.hypot(toes[0], toes[2])
    for side in ("left", "right"):
        reach = p[JOINT_INDEX[f"{side}_wrist"]] - p[JOINT_INDEX[f"{side}_shoulder"]]
        assert reach @ ahead > 0.3
    plain = save_pose(seq, tmp_path / "squat.npz")
    flipped = save_pose(_reflected(seq, axis), tmp_path / "flipped.npz")
    assert main(["describe", str(plain)]) == 0
    want = capsys.readouterr().out.splitlines()
    assert main(["describe", str(flipped)]) == 0
    got = capsys.readouterr()
    assert got.out.splitlines()[1:] == want[1:]  # the first line names the file
    # before: "frames 0-139: ..., left arm behind 1.00, right arm behind 1.00, ..."
    assert any("left arm in front" in line and line.startswith("frames 0–139") for line in want)
    assert "arm behind" not in got.out
    assert got.err.count("note: ") == 1


def _bvh(left_x: float, sign: float) -> str:
    """A body facing +z (left along +x when ``left_x`` > 0) with toes; ``sign`` -1 writes the
    same motion reflected in x: x offsets and positions negated, y and z rotations negated
    (reflecting x keeps rotations about x and reverses those about y and z)."""
    x = left_x

    def leg(side: str, sx: float) -> str:
        return f"""  JOINT {side}UpLeg
  {{
    OFFSET {sx * 10} 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT {side}Leg
    {{
      OFFSET 0 -45 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT {side}Foot
      {{
        OFFSET 0 -45 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT {side}ToeBase
        {{
          OFFSET 0 -5 12
          CHANNELS 3 Zrotation Xrotation Yrotation
          End Site
          {{
            OFFSET 0 0 4
          }}
        }}
      }}
    }}
  }}
"""

    def arm(side: str, sx: float) -> str:
        return f"""    JOINT {side}Arm
    {{
      OFFSET {sx * 18} 45 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT {side}ForeArm
      {{
        OFFSET 0 -30 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {{
          OFFSET 0 -25 0
        }}
      }}
    }}
"""

    hierarchy = (
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n"
        "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        + leg("Left", x)
        + leg("Right", -x)
        + "  JOINT Spine\n  {\n    OFFSET 0 10 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
        + arm("Left", x)
        + arm("Right", -x)
        + "  }\n}\n"
    )
    # root at (3, 95, 1) turned 30 degrees about y; left knee bent 40 degrees (about x, the
    # knee's axis); left arm raised 60 degrees forward and 20 about z; right hip 15 about z
    root = [3.0 * sign, 95.0, 1.0, 0.0, 0.0, 30.0 * sign]
    # channels: Hips 0-5, left leg 6-17 (LeftLeg 9-11), right leg 18-29, Spine 30-32,
    # LeftArm 33-35, LeftForeArm 36-38, right arm 39-44; each joint's Z, X, Y
    frames = []
    for k in range(4):
        ch = root + [0.0] * 39
        ch[10] = -40.0 * k / 3  # LeftLeg Xrotation
        ch[18] = 15.0 * sign  # RightUpLeg Zrotation
        ch[33] = 20.0 * sign  # LeftArm Zrotation
        ch[34] = -60.0  # LeftArm Xrotation
        frames.append(" ".join(f"{v:g}" for v in ch))
    return hierarchy + "MOTION\nFrames: 4\nFrame Time: 0.04\n" + "\n".join(frames) + "\n"


def test_reflected_bvh_reads_as_the_original(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plain = tmp_path / "plain.bvh"
    plain.write_text(_bvh(1.0, 1.0))
    flipped = tmp_path / "flipped.bvh"
    flipped.write_text(_bvh(-1.0, -1.0))
    want = read_bvh(plain, unit="cm")
    assert METADATA_KEY not in want.metadata
    # the left toes are ahead of the left ankle along +z, the left hip at +x: right-handed
    toe = want.positions[0, JOINT_INDEX["left_foot_index"]]
    ankle = want.positions[0, JOINT_INDEX["left_ankle"]]
    assert toe[2] - ankle[2] > 0.1
    assert capsys.readouterr().err == ""
    got = read_bvh(flipped, unit="cm")
    np.testing.assert_allclose(got.positions, want.positions, atol=1e-9)
    assert METADATA_KEY in got.metadata
    capsys.readouterr()
    # posecbr convert writes the pose file read back, saying so once
    assert main(["convert", str(flipped), "--out", str(tmp_path / "out"), "--bvh-unit", "cm"]) == 0
    err = capsys.readouterr().err
    assert err.count("note: ") == 1 and "read with x negated" in err
    out = load_pose(tmp_path / "out" / "flipped.npz")
    np.testing.assert_allclose(out.positions, want.positions, atol=1e-9)
    assert METADATA_KEY in out.metadata
    # the pose file says it, not a column of labels.csv (a sentence in every row)
    header = (tmp_path / "out" / "labels.csv").read_text().splitlines()[0]
    assert header == "path,label,subject,bvh_unit"


def test_too_little_evidence_is_left_alone(capsys: pytest.CaptureFixture[str]) -> None:
    body = standing()
    flipped = {k: v * np.array([-1.0, 1.0, 1.0]) for k, v in body.items()}
    assert reflected_evidence(to_sequence(flipped).positions)[0] == pytest.approx(-0.98, abs=0.01)
    # no toes, heels or nose seen: nothing tells the reflection, nothing is changed
    for name in ("left_foot_index", "right_foot_index", "left_heel", "right_heel", "nose"):
        flipped[name] = np.full(3, np.nan)
    seq = to_sequence(flipped)
    assert reflected_evidence(seq.positions) == (pytest.approx(np.nan, nan_ok=True), 0)
    from features.handedness import right_handed

    assert right_handed(seq) is seq
    assert capsys.readouterr().err == ""


def test_reflected_vicon_markers_give_the_hips_of_the_original(
    shared_data: Path, tmp_path: Path
) -> None:
    # A UI-PRMD Vicon file with its x column reflected (every marker's first coordinate
    # negated). The hip centres are placed from the pelvis markers in a frame whose "up" is a
    # cross product, so they must be placed after the reflection is undone, not before: read
    # back before that, they stood about 17 cm above the true ones (up pointed down).
    src = shared_data / UIPRMD.format("Vicon")
    rows = [r for r in gzip.decompress(src.read_bytes()).decode().splitlines() if r.strip()]
    flipped = []
    for row in rows:
        values = row.split(",")
        for k in range(0, len(values), 3):  # the file's x (forward) of each marker
            values[k] = repr(-float(values[k])) if float(values[k]) != 0 else values[k]
        flipped.append(",".join(values))
    path = tmp_path / src.name
    path.write_bytes(gzip.compress(("\n".join(flipped) + "\n").encode()))
    want = load_clip(src)
    got = load_clip(path)
    assert METADATA_KEY in got.metadata
    # the file's x is canonical z: negated back through canonical x, the body comes back
    # turned half way round the vertical, (x, y, z) -> (-x, y, -z), hips included
    turned = want.positions * np.array([-1.0, 1.0, -1.0])
    np.testing.assert_allclose(got.positions, turned, atol=1e-9)


def _negated(value: str) -> str:
    return repr(-float(value))


def test_hdm05_take_written_reflected_reads_as_the_original(
    shared_data: Path, tmp_path: Path
) -> None:
    # HDM05 bd's squat as an exporter reflecting x writes it: bone directions' x, the root's x
    # translation and every rotation about y and z negated (reflecting x conjugates a rotation:
    # about x it stays, about y and z it turns the other way), axes and dofs in XYZ order.
    amc = shared_data / SQUAT
    asf = amc.parent / "HDM_bd.asf"
    asf_lines, dof, bone = [], {"root": ["tx", "ty", "tz", "rx", "ry", "rz"]}, ""
    for line in asf.read_text(encoding="latin-1").splitlines():
        t = line.split()
        if t[:1] == ["name"]:
            bone = t[1]
        elif t[:1] == ["dof"]:
            dof[bone] = t[1:]
        elif t[:1] == ["direction"]:
            line = f"direction {_negated(t[1])} {t[2]} {t[3]}"
        elif t[:1] == ["axis"] and len(t) == 5:
            assert t[4] == "XYZ"
            line = f"axis {t[1]} {_negated(t[2])} {_negated(t[3])} XYZ"
        asf_lines.append(line)
    assert "order TX TY TZ RX RY RZ" in " ".join(" ".join(line.split()) for line in asf_lines)
    amc_lines = []
    for line in amc.read_text(encoding="latin-1").splitlines():
        t = line.split()
        if len(t) > 1 and not line.startswith(("#", ":")):
            flip = [c in ("tx", "ry", "rz") for c in dof[t[0]]]
            values = [_negated(v) if f else v for f, v in zip(flip, t[1:], strict=True)]
            line = " ".join([t[0], *values])
        amc_lines.append(line)
    (tmp_path / "HDM_bd.asf").write_text("\n".join(asf_lines) + "\n", encoding="latin-1")
    (tmp_path / amc.name).write_text("\n".join(amc_lines) + "\n", encoding="latin-1")
    want = read_asf_amc(asf, amc)
    got = read_asf_amc(tmp_path / "HDM_bd.asf", tmp_path / amc.name)
    assert METADATA_KEY in got.metadata
    np.testing.assert_allclose(got.positions, want.positions, atol=1e-12)


def test_kinect_take_written_reflected_reads_as_the_original(
    shared_data: Path, tmp_path: Path
) -> None:
    # UI-PRMD Kinect: every offset's x negated, and each joint's rotations about y and z (its
    # second and third angle: R = Rz(c3) Ry(c2) Rx(c1)) turned the other way
    positions = shared_data / UIPRMD.format("Kinect")
    angles = positions.parent.parent / "Angles" / positions.name.replace("_positions", "_angles")
    for src, columns in ((positions, (0,)), (angles, (1, 2))):
        table = np.loadtxt(gzip.open(src, "rt"), delimiter=",", ndmin=2)
        for c in columns:
            table[:, c::3] *= -1.0
        with gzip.open(tmp_path / src.name, "wt") as fh:
            np.savetxt(fh, table, delimiter=",", fmt="%.17g")
    got = load_clip(tmp_path / positions.name)
    assert METADATA_KEY in got.metadata
    np.testing.assert_allclose(got.positions, load_clip(positions).positions, atol=1e-12)
