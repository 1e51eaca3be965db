"""``convert FILE.bvh --bvh-up z``: a BVH file whose up axis is z (3ds Max, MotionBuilder set
to z up) turned so that y is up, checked against joint positions worked out by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.poses import load_pose
from features.skeleton import JOINT_INDEX
from posecbr.cli import main
from tests.badinput import refused

# the hips 95 cm above the floor, the left hip 10 cm to the side (+x), the knee 45 cm below
# it, the foot's end 45 cm further: z up
_BVH_Z_UP = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 95
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 0 -45
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 0 -45
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.04
0 0 95 0 0 0 0 0 0 0 0 0
0 0 95 0 0 0 0 0 0 0 0 0
"""


def _converted(tmp_path: Path, *options: str) -> np.ndarray:
    src = tmp_path / "legs.bvh"
    src.write_text(_BVH_Z_UP)
    out = tmp_path / f"out{len(list(tmp_path.iterdir()))}"
    assert main(["convert", str(src), "--out", str(out), "--bvh-unit", "cm", *options]) == 0
    return load_pose(out / "legs.npz").positions


def test_a_z_up_bvh_file_is_turned_so_that_y_is_up(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # (x, y, z) -> (y, z, x), a proper rotation: the height (file z) becomes y, the side
    # (file x) becomes z
    positions = _converted(tmp_path, "--bvh-up", "z")
    hip, knee = JOINT_INDEX["left_hip"], JOINT_INDEX["left_knee"]
    np.testing.assert_allclose(positions[:, hip], [[0.0, 0.95, 0.10]] * 2, atol=1e-12)
    np.testing.assert_allclose(positions[:, knee], [[0.0, 0.50, 0.10]] * 2, atol=1e-12)
    # read as y up (the default), the legs lie along z on the floor: the knee is level with
    # the hip
    flat = _converted(tmp_path)
    assert flat[0, knee, 1] == pytest.approx(flat[0, hip, 1])


def test_bvh_up_with_an_amc_file_or_a_dataset_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], shared_data: Path
) -> None:
    amc = shared_data / "hdm05" / "train" / "10" / "HDM_bd_squat1Reps_001_120.amc"
    refused(["convert", str(amc), "--out", str(tmp_path / "o"), "--bvh-up", "z"], tmp_path,
            capsys, "--bvh-up", "goes with BVH files")  # fmt: skip
    data = tmp_path / "data"
    (data / "squat").mkdir(parents=True)
    (data / "squat" / "legs.bvh").write_text(_BVH_Z_UP)
    refused(["convert", str(data), "--out", str(tmp_path / "o"), "--bvh-up", "z"], tmp_path,
            capsys, "--bvh-up", "goes with one .bvh file")  # fmt: skip


@pytest.mark.parametrize(
    ("written", "fps"),
    [
        ("0.0333333", 30.0),  # 1/30 = 0.03333333...: within half a unit of the 7th decimal
        ("0.00833333", 120.0),
        ("0.0416667", 24.0),
        ("0.04", 25.0),
        ("0.0333334", 1 / 0.0333334),  # 1/30 lies 6.7e-8 below: more than half a unit
        ("0.03", 1 / 0.03),  # 33.3 frames per second, not 33
        ("0.0333", 1 / 0.0333),  # 30 lies 0.1 % away: what was written is kept
    ],
)
def test_a_frame_time_written_to_its_precision_gives_the_whole_frame_rate_it_means(
    tmp_path: Path, written: str, fps: float
) -> None:
    # a BVH exporter writes 1/30 s as 0.0333333: the clip was said to be 30.00003 fps
    from features.readers.bvh import read_bvh

    path = tmp_path / "legs.bvh"
    path.write_text(_BVH_Z_UP.replace("Frame Time: 0.04", f"Frame Time: {written}"))
    assert read_bvh(path, unit="cm").fps == fps
