"""Defects found hunting the readers (UI-PRMD, ASF/AMC, BVH) with odd but valid inputs."""

from __future__ import annotations

import gzip
import shutil
from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_clip

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
