"""Hunt 32b: a skeleton with no limbs refused at convert time; compare --trim with fewer cases
than k in a fold; casebase trim's held-out accuracy with mirror twins; Ctrl-C of a Dask
LocalCluster run."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused

# ---- 1. a skeleton with no limbs ----------------------------------------------------------

_ROOT = """:units
  length 0.45
  angle deg
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
"""

_BONE = """  begin
     name {name}
     direction 0 1 0
     length 10
     axis 0 0 0 XYZ
    dof rx
  end
"""


def _asf(folder: Path, *bones: str) -> Path:
    path = folder / "s.asf"
    blocks = "".join(_BONE.format(name=b) for b in bones)
    tree = f"    root {' '.join(bones)}\n" if bones else ""
    path.write_text(f"{_ROOT}:bonedata\n{blocks}:hierarchy\n  begin\n{tree}  end\n")
    return path


def _amc(folder: Path, *bones: str, name: str = "m.amc") -> Path:
    path = folder / name
    frames = "".join(
        f"{i}\nroot {i} 17 0 0 0 0\n" + "".join(f"{b} 5\n" for b in bones) for i in (1, 2, 3)
    )
    path.write_text(":FULLY-SPECIFIED\n:DEGREES\n" + frames)
    return path


def test_asf_of_the_root_alone_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    # it was refused before as "no :bonedata bones (not an ASF file?)": it is one, of a root
    asf, amc = _asf(tmp_path), _amc(tmp_path)
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, "s.asf: the skeleton has only its root", "no limbs to draw")


def test_a_file_without_root_nor_bones_is_still_not_an_asf(tmp_path: Path) -> None:
    from features.errors import DataError
    from features.readers.asfamc import read_asf

    path = tmp_path / "x.asf"
    path.write_text("hello\n")
    with pytest.raises(DataError, match="not an ASF file"):
        read_asf(path)


def test_asf_whose_bones_place_no_joint_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    # lowerback and head place no BlazePose joint: the clip converted, every joint missing in
    # every frame, and every later command said it "shows no person"
    asf = _asf(tmp_path, "lowerback", "head")
    amc = _amc(tmp_path, "lowerback", "head")
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, "s.asf: none of its bones", "it has lowerback, head")


def test_amc_listing_only_the_root_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    asf = _asf(tmp_path, "lhipjoint", "rhipjoint")
    amc = _amc(tmp_path)  # root lines only
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")]
    line = refused(argv, tmp_path, capsys, "m.amc: lists only root")
    assert "no values for lhipjoint, rhipjoint (bones of s.asf that turn)" in line


def test_real_hdm05_skeleton_with_an_amc_of_the_root_alone_is_refused(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture
) -> None:
    # HDM05's hip bones do not turn: the root alone placed the two hips, and nothing else, so
    # the clip converted (2 of 33 joints) and then showed no person to every command
    folder = shared_data / "hdm05" / "train" / "3"
    source = sorted(folder.glob("HDM_bd_*.amc"))[0]
    kept = [
        line
        for line in source.read_text(encoding="latin-1").split("\n")
        if line.startswith((":", "#", "root ")) or line.strip().isdigit()
    ]
    amc = tmp_path / "root_only.amc"
    amc.write_text("\n".join(kept[: kept.index("11")]) + "\n", encoding="latin-1")  # 10 frames
    argv = ["convert", str(amc), "--asf", str(folder / "HDM_bd.asf"), "--out", str(tmp_path / "o")]
    refused(argv, tmp_path, capsys, "root_only.amc: lists only root", "lfemur")


_BVH = """HIERARCHY
ROOT {root}
{{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
{end}}}
MOTION
Frames: 2
Frame Time: 0.0333333
0 90 0 0 0 0
1 90 0 0 0 0
"""


@pytest.mark.parametrize("root", ["Hips", "LeftUpLeg"])
@pytest.mark.parametrize("end", ["", "  End Site\n  {\n    OFFSET 0 10 0\n  }\n"])
def test_bvh_of_the_root_alone_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture, root: str, end: str
) -> None:
    # a root named as a hip (LeftUpLeg) converted: one joint of 33, no person to any command
    bvh = tmp_path / "r.bvh"
    bvh.write_text(_BVH.format(root=root, end=end))
    argv = ["convert", str(bvh), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, f"r.bvh: the skeleton has only its root ({root})")
