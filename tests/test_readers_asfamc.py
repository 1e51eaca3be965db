"""ASF/AMC reader: hand-made chains with hand-computed end points, and real HDM05 clips."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.readers.asfamc import read_asf, read_asf_amc
from features.skeleton import JOINT_INDEX

INCH = 0.0254

# A root with a chain lhipjoint -> lfemur -> ltibia, every bone 10 inches along +x. lfemur's
# local frame is turned 90 degrees about z (axis 0 0 90), so its rx rotates about world y.
ASF = """# hand-made
:version 1.10
:name test
:units
  mass 1.0
  length 0.5
  angle deg
:documentation
  t\xe9st
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     id 1
     name lhipjoint
     direction 1 0 0
     length 10
     axis 0 0 0 XYZ
    dof rz
    limits (-180 180)
  end
  begin
     id 2
     name lfemur
     direction 1 0 0
     length 10
     axis 0 0 90 XYZ
    dof rx
    limits (-180 180)
  end
  begin
     id 3
     name ltibia
     direction 1 0 0
     length 10
     axis 0 0 0 XYZ
    dof rz
  end
:hierarchy
  begin
    root lhipjoint
    lhipjoint lfemur
    lfemur ltibia
  end
"""

AMC = """#!OML:ASF X:\\f\xfcr Bonn\\test.ASF
:FULLY-SPECIFIED
:DEGREES
1
root 0 0 0 0 0 0
lhipjoint 0
lfemur 0
ltibia 0
2
root 1 2 3 0 0 0
lhipjoint 90
lfemur 0
ltibia -90
3
root 0 0 0 0 0 0
lhipjoint 0
lfemur 90
ltibia 0
"""

M = INCH / 0.5  # metres per ASF unit with ":units length 0.5"


def _write(tmp_path: Path, asf: str = ASF, amc: str = AMC, amc_name: str = "t_60.AMC"):
    a = tmp_path / "t.asf"
    b = tmp_path / amc_name
    # latin-1 bytes and CRLF line ends, as in HDM05
    a.write_bytes(asf.replace("\n", "\r\n").encode("latin-1"))
    b.write_bytes(amc.replace("\n", "\r\n").encode("latin-1"))
    return a, b


def test_two_bone_chain_end_points(tmp_path: Path) -> None:
    asf, amc = _write(tmp_path)
    seq = read_asf_amc(asf, amc)
    hip = seq.positions[:, JOINT_INDEX["left_hip"]]
    knee = seq.positions[:, JOINT_INDEX["left_knee"]]
    ankle = seq.positions[:, JOINT_INDEX["left_ankle"]]
    L = 10 * M
    # frame 1: straight along +x
    np.testing.assert_allclose(hip[0], [L, 0, 0], atol=1e-12)
    np.testing.assert_allclose(ankle[0], [3 * L, 0, 0], atol=1e-12)
    # frame 2: root moved by (1, 2, 3) units; lhipjoint turned +90 about z points its bone
    # along +y; lfemur follows it; ltibia -90 about z brings the last bone back to +x.
    root = np.array([1, 2, 3]) * M
    np.testing.assert_allclose(hip[1], root + [0, L, 0], atol=1e-12)
    np.testing.assert_allclose(knee[1], root + [0, 2 * L, 0], atol=1e-12)
    np.testing.assert_allclose(ankle[1], root + [L, 2 * L, 0], atol=1e-12)
    # frame 3: lfemur's rx=90 in a frame turned 90 about z is a rotation about world y:
    # Ry(90) maps +x to -z, for lfemur and the ltibia below it.
    np.testing.assert_allclose(knee[2], [L, 0, -L], atol=1e-12)
    np.testing.assert_allclose(ankle[2], [L, 0, -2 * L], atol=1e-12)
    assert seq.fps == 120.0  # "_60" in a name that is not HDM05's is no frame rate
    assert np.isnan(seq.positions[:, JOINT_INDEX["nose"]]).all()
    assert np.isnan(seq.positions[:, JOINT_INDEX["right_knee"]]).all()


def test_units_and_latin1_header(tmp_path: Path) -> None:
    asf, _ = _write(tmp_path)
    skel = read_asf(asf)
    assert skel.length_scale == 0.5
    assert skel.metres_per_unit == pytest.approx(0.0508)
    assert list(skel.bones) == ["lhipjoint", "lfemur", "ltibia"]


def test_radians_amc(tmp_path: Path) -> None:
    amc = AMC.replace(":DEGREES", ":RADIANS").replace(" 90", f" {np.pi / 2}")
    asf, amcp = _write(tmp_path, amc=amc)
    seq = read_asf_amc(asf, amcp)
    np.testing.assert_allclose(seq.positions[1, JOINT_INDEX["left_knee"]],
                               np.array([1, 2, 3]) * M + [0, 20 * M, 0], atol=1e-9)  # fmt: skip


def test_a_skeleton_in_radians_has_its_axes_in_radians(tmp_path: Path) -> None:
    """``:units angle rad`` makes every angle of the ASF radians, the bones' axes too (the
    Acclaim definition: one angle unit for the file). lfemur's axis "0 0 1.5708" was read as
    1.57 degrees, so frame 3's rx = 90 turned about x, not y: the knee stayed at [L, 0, 0]
    instead of [L, 0, -L]. The AMC says :DEGREES for its own values."""
    asf = ASF.replace("angle deg", "angle rad").replace("axis 0 0 90 XYZ",
                                                          f"axis 0 0 {np.pi / 2} XYZ")  # fmt: skip
    seq = read_asf_amc(*_write(tmp_path, asf=asf))
    L = 10 * M
    np.testing.assert_allclose(seq.positions[2, JOINT_INDEX["left_knee"]], [L, 0, -L], atol=1e-9)
    np.testing.assert_allclose(seq.positions[2, JOINT_INDEX["left_ankle"]], [L, 0, -2 * L],
                               atol=1e-9)  # fmt: skip


@pytest.mark.parametrize(
    ("amc", "message"),
    [
        (AMC.rsplit("ltibia", 1)[0], "incomplete"),
        (AMC.replace("lfemur 90", "lfemur 90 4"), "has 2 values"),
        (AMC.replace("lfemur 90", "lfemur abc"), "not a number"),
        (AMC.replace("ltibia -90", "lhand 3"), "not in the skeleton"),
        ("# nothing\n", "no frames"),
    ],
)
def test_malformed_amc_names_file(tmp_path: Path, amc: str, message: str) -> None:
    asf, amcp = _write(tmp_path, amc=amc)
    with pytest.raises(DataError, match=message) as info:
        read_asf_amc(asf, amcp)
    assert info.value.source == str(amcp)


def test_malformed_asf_names_file(tmp_path: Path) -> None:
    asf, amcp = _write(tmp_path, asf=ASF.split(":hierarchy")[0].rsplit("end", 1)[0])
    with pytest.raises(DataError) as info:
        read_asf_amc(asf, amcp)
    assert info.value.source == str(asf)
    with pytest.raises(DataError, match="no such file"):
        read_asf_amc(tmp_path / "missing.asf", amcp)


def _bone_blocks(asf: str) -> tuple[str, list[str], str]:
    """The ASF text before the first bone, its bone blocks (each ``begin`` ... ``end``), and the
    text from ``:hierarchy`` on."""
    head, rest = asf.split("  begin\n", 1)
    bones, tail = ("  begin\n" + rest).split(":hierarchy", 1)
    blocks = ["  begin\n" + b for b in bones.split("  begin\n") if b]
    return head, blocks, ":hierarchy" + tail


def test_bones_listed_children_first_are_ordered_parents_first(tmp_path: Path) -> None:
    head, blocks, tail = _bone_blocks(ASF)
    asf, amc = _write(tmp_path, asf=head + "".join(reversed(blocks)) + tail)
    skel = read_asf(asf)
    assert list(skel.bones) == ["lhipjoint", "lfemur", "ltibia"]
    assert [b.parent for b in skel.bones.values()] == ["root", "lhipjoint", "lfemur"]
    # the same end points as the file in parents-first order (checked by hand above)
    (tmp_path / "ordered").mkdir()
    listed_in_order = read_asf_amc(*_write(tmp_path / "ordered")).positions
    np.testing.assert_array_equal(read_asf_amc(asf, amc).positions, listed_in_order)


@pytest.mark.parametrize(
    ("asf", "message"),
    [
        (
            ASF.replace("  begin\n     id 2", "  end\n  begin\n     id 2"),
            "line 25: 'end' without 'begin'",
        ),
        (ASF.split(":hierarchy")[0] + "  begin\n     name x\n", "not closed with 'end'"),
        (
            ASF.replace(
                "     direction 1 0 0\n     length 10\n     axis 0 0 90", "     axis 0 0 90"
            ),
            "line 25: bone lacks direction, length",
        ),
        (ASF.replace("dof rx", "dof rx rw"), "line 25: unknown dof 'rw'"),
        (
            ASF.replace("lhipjoint lfemur", "ltibia lfemur"),
            "a cycle or unknown parent near 'lfemur'",
        ),
        (
            ASF.replace("lfemur ltibia", "lfemur ltibia lknee"),
            "line 46: hierarchy names unknown bone 'lknee'",
        ),
        (
            ASF.replace(":bonedata", ":bonedata\n  name strayed outside a block\n").split(
                "  begin"
            )[0],
            "no :bonedata bones",
        ),
    ],
)
def test_malformed_bone_blocks_and_hierarchy_name_the_line(
    tmp_path: Path, asf: str, message: str
) -> None:
    path, _ = _write(tmp_path, asf=asf)
    with pytest.raises(DataError) as info:
        read_asf(path)
    assert message in str(info.value) and info.value.source == str(path)


def test_amc_values_before_the_first_frame_number(tmp_path: Path) -> None:
    asf, amc = _write(tmp_path, amc=AMC.replace(":DEGREES\n1\n", ":DEGREES\n"))
    with pytest.raises(DataError, match="line 4: data before the first frame number"):
        read_asf_amc(asf, amc)


# ---- real HDM05 clips -------------------------------------------------------------------


def _hdm05(shared_data: Path, folder: str, pattern: str) -> tuple[Path, Path]:
    d = shared_data / "hdm05" / "train" / folder
    amc = sorted(d.glob(pattern))[0]
    actor = amc.name.split("_")[1]
    return d / f"HDM_{actor}.asf", amc


def test_hdm05_squat_geometry(shared_data: Path) -> None:
    # Folder 10 holds squat1Reps (HDM05 numbering of this cut); find it by name instead.
    amcs = sorted((shared_data / "hdm05" / "train").glob("*/HDM_bd_squat1Reps_*.amc"))
    assert amcs, "no HDM05 squat clip"
    amc = amcs[0]
    asf = amc.parent / "HDM_bd.asf"
    seq = read_asf_amc(asf, amc)
    skel = read_asf(asf)
    scale = 0.0254 / 0.45  # the HDM05 ASF says ":units length 0.45"
    assert skel.metres_per_unit == pytest.approx(scale)
    p = {n: seq.positions[:, JOINT_INDEX[n]] for n in JOINT_INDEX}
    # bone lengths equal the ASF lengths in every frame
    for a, b, bone in [("left_hip", "left_knee", "lfemur"), ("left_knee", "left_ankle", "ltibia"),
                       ("right_shoulder", "right_elbow", "rhumerus")]:  # fmt: skip
        length = np.linalg.norm(p[a] - p[b], axis=1)
        np.testing.assert_allclose(length, skel.bones[bone].length * scale, rtol=1e-9)
    # y is up: shoulders above hips above knees above ankles at the start (standing)
    y0 = {n: v[0, 1] for n, v in p.items()}
    assert y0["left_shoulder"] > y0["left_hip"] > y0["left_knee"] > y0["left_ankle"]
    assert 1.2 < y0["left_shoulder"] - y0["left_ankle"] < 1.7
    # feet near the floor throughout a squat (feet stay planted)
    toes = np.minimum(p["left_foot_index"][:, 1], p["right_foot_index"][:, 1])
    assert np.all(np.abs(toes) < 0.1)
    # the hips drop by more than 25 cm at the deepest point of a squat
    hips = (p["left_hip"][:, 1] + p["right_hip"][:, 1]) / 2
    assert hips[0] - hips.min() > 0.25
    assert seq.metadata["label"] == "squat1Reps" and seq.metadata["subject"] == "bd"
    assert seq.fps == 120.0


def test_hdm05_left_is_left(shared_data: Path) -> None:
    asf, amc = _hdm05(shared_data, "1", "HDM_bd_*.amc")
    seq = read_asf_amc(asf, amc)
    p = {n: seq.positions[:, JOINT_INDEX[n]] for n in JOINT_INDEX}
    forward = p["left_foot_index"] + p["right_foot_index"] - p["left_ankle"] - p["right_ankle"]
    left = np.cross([0.0, 1.0, 0.0], forward)  # right-handed, y up: left = up x forward
    assert np.mean(np.sum((p["left_hip"] - p["right_hip"]) * left, axis=1) > 0) > 0.95
    assert np.mean(np.sum((p["left_shoulder"] - p["right_shoulder"]) * left, axis=1) > 0) > 0.95


def test_hdm05_upper_case_amc(shared_data: Path) -> None:
    amcs = [p for p in (shared_data / "hdm05" / "train").glob("*/*") if p.suffix == ".AMC"]
    assert amcs
    amc = amcs[0]
    seq = read_asf_amc(amc.parent / f"HDM_{amc.name.split('_')[1]}.asf", amc)
    assert seq.n_frames > 10 and np.isfinite(seq.positions[:, JOINT_INDEX["left_knee"]]).all()
