"""Defects found hunting the readers (UI-PRMD, ASF/AMC, BVH) with odd but valid inputs."""

from __future__ import annotations

import gzip
import shutil
from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_clip
from features.readers.asfamc import read_asf_amc
from features.readers.bvh import read_bvh
from features.skeleton import JOINT_INDEX

KINECT = "ui-prmd/data/Segmented Movements/Kinect"
TAKE = "m01_s01_e01"


def _gunzip(src: Path, dst: Path) -> None:
    dst.write_bytes(gzip.decompress(src.read_bytes()))


@pytest.mark.parametrize("decompressed", ["angles", "positions"])
def test_kinect_angles_found_when_one_of_the_pair_is_decompressed(
    shared_data: Path, tmp_path: Path, decompressed: str
) -> None:
    # A UI-PRMD Kinect positions file with its angles file, one of the two gunzipped: the
    # reader looked only for the angles file compressed as the positions file is, and refused
    # "no angles file m01_s01_e01_angles.txt.gz beside it" with the angles file right there.
    root = shared_data / KINECT
    positions = root / "Positions" / f"{TAKE}_positions.txt.gz"
    angles = root / "Angles" / f"{TAKE}_angles.txt.gz"
    want = load_clip(positions)
    (tmp_path / "Positions").mkdir()
    (tmp_path / "Angles").mkdir()
    if decompressed == "angles":  # beside the positions file
        path = tmp_path / "Positions" / positions.name
        shutil.copy(positions, path)
        _gunzip(angles, tmp_path / "Positions" / f"{TAKE}_angles.txt")
    else:  # the positions file gunzipped, the angles file in the sibling Angles folder
        path = tmp_path / "Positions" / f"{TAKE}_positions.txt"
        _gunzip(positions, path)
        shutil.copy(angles, tmp_path / "Angles" / angles.name)
    got = load_clip(path)
    np.testing.assert_array_equal(got.positions, want.positions)


def _biovision_names_bvh() -> str:
    """A standing skeleton named as the Biovision example of the BVH description (Hips, Chest,
    LeftCollar, LeftUpArm, LeftLowArm, LeftHand, LeftUpLeg, LeftLowLeg, LeftFoot), in cm, at
    rest with the hips 92 cm up."""

    def arm(side: str, x: int) -> str:
        chain = [("Collar", f"{x} 16 2"), ("UpArm", f"{15 * x} 0 0"), ("LowArm", "0 -28 0"),
                 ("Hand", "0 -25 0")]  # fmt: skip
        return _chain(side, chain, "0 -7 0")

    def leg(side: str, x: int) -> str:
        chain = [("UpLeg", f"{10 * x} 0 0"), ("LowLeg", "0 -45 0"), ("Foot", "0 -43 0")]
        return _chain(side, chain, "0 -4 0")

    def _chain(side: str, chain: list[tuple[str, str]], end: str) -> str:
        text = "".join(
            f"JOINT {side}{name}\n{{\nOFFSET {offset}\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
            for name, offset in chain
        )
        return text + f"End Site\n{{\nOFFSET {end}\n}}\n" + "}\n" * len(chain)

    hierarchy = (
        "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\n"
        "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        "JOINT Chest\n{\nOFFSET 0 30 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
        + arm("Left", 1)
        + arm("Right", -1)
        + "}\n"
        + leg("Left", 1)
        + leg("Right", -1)
        + "}\n"
    )
    frame = " ".join(["0", "92"] + ["0"] * (6 + 3 + 2 * 12 + 2 * 9 - 2))
    return hierarchy + f"MOTION\nFrames: 2\nFrame Time: 0.033333\n{frame}\n{frame}\n"


def test_bvh_with_the_biovision_example_names_has_shoulders_elbows_and_knees(
    tmp_path: Path,
) -> None:
    # Before: LeftUpArm, LeftLowArm and LeftLowLeg matched no name the reader knew, so the
    # clip had no shoulders, elbows or knees: no torso, and every fluent "unavailable".
    path = tmp_path / "example.bvh"
    path.write_text(_biovision_names_bvh())
    seq = read_bvh(path, unit="cm")
    # by hand: shoulder = hips (0, 92, 0) + chest (0, 30, 0) + collar (1, 16, 2) + (15, 0, 0)
    want = {
        "left_shoulder": (0.16, 1.38, 0.02),
        "left_elbow": (0.16, 1.10, 0.02),
        "left_wrist": (0.16, 0.85, 0.02),
        "right_shoulder": (-0.16, 1.38, 0.02),
        "right_elbow": (-0.16, 1.10, 0.02),
        "left_hip": (0.10, 0.92, 0.0),
        "left_knee": (0.10, 0.47, 0.0),
        "right_knee": (-0.10, 0.47, 0.0),
        "left_ankle": (0.10, 0.04, 0.0),
    }
    for joint, xyz in want.items():
        np.testing.assert_allclose(seq.positions[:, JOINT_INDEX[joint]], [xyz, xyz], atol=1e-12)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-be"])
def test_utf16_text_files_read_as_their_utf8_twins(
    shared_data: Path, tmp_path: Path, encoding: str
) -> None:
    # Windows tools write text as UTF-16 with a byte order mark (PowerShell's ">", Notepad's
    # "Unicode"). Read as latin-1, every other character was a NUL: the BVH file "does not
    # start with HIERARCHY (not a BVH file?)", the ASF had "no :bonedata bones".
    def utf16(text: str, name: str) -> Path:
        body = text.encode("utf-16-be") if encoding == "utf-16-be" else text.encode("utf-16")
        path = tmp_path / name
        path.write_bytes((b"\xfe\xff" if encoding == "utf-16-be" else b"") + body)
        return path

    bvh = tmp_path / "plain.bvh"
    bvh.write_text(_biovision_names_bvh())
    want = read_bvh(bvh, unit="cm")
    got = read_bvh(utf16(_biovision_names_bvh().replace("\n", "\r\n"), "wide.bvh"), unit="cm")
    np.testing.assert_array_equal(got.positions, want.positions)
    # a real HDM05 take, its ASF and AMC (latin-1 header bytes: "für") both in UTF-16
    amc = shared_data / "hdm05/train/10/HDM_bd_squat1Reps_001_120.amc"
    asf = amc.parent / "HDM_bd.asf"
    wide_asf = utf16(asf.read_text(encoding="latin-1"), "HDM_bd.asf")
    wide_amc = utf16(amc.read_text(encoding="latin-1"), amc.name)
    np.testing.assert_array_equal(
        read_asf_amc(wide_asf, wide_amc).positions, read_asf_amc(asf, amc).positions
    )
