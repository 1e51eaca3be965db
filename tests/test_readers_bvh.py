"""BVH reader: hand-made hierarchies with hand-computed joint positions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.readers.bvh import read_bvh
from features.skeleton import JOINT_INDEX


def bvh_text(leg_channels: str, frames: list[str], thigh: float = 40.0) -> str:
    return (
        f"""HIERARCHY
ROOT Hips
{{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT mixamorig:LeftUpLeg
  {{
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {{
      OFFSET 0 -{thigh} 0
      CHANNELS 3 {leg_channels}
      JOINT LeftFoot
      {{
        OFFSET 0 -40 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT LeftToeBase
        {{
          OFFSET 0 0 10
          CHANNELS 3 Zrotation Xrotation Yrotation
          End Site
          {{
            OFFSET 0 0 5
          }}
        }}
      }}
    }}
  }}
}}
MOTION
Frames: {len(frames)}
Frame Time: 0.02
"""
        + "\n".join(frames)
        + "\n"
    )


ZERO = "0 90 0 0 0 0  0 0 0  {a} {b} 0  0 0 0  0 0 0"


def test_knee_rotation_channel_order(tmp_path: Path) -> None:
    # Frame 1 at rest; frame 2 rotates LeftLeg by 90 deg about its first listed axis and 90
    # about its second. Rest: hip (10, 90, 0) cm, knee (10, 50, 0), ankle (10, 10, 0).
    frames = [ZERO.format(a=0, b=0), ZERO.format(a=90, b=90)]
    f = tmp_path / "zxy.bvh"
    f.write_text(bvh_text("Zrotation Xrotation Yrotation", frames))
    seq = read_bvh(f, unit="cm")
    p = {n: seq.positions[:, JOINT_INDEX[n]] for n in JOINT_INDEX}
    np.testing.assert_allclose(p["left_hip"][0], [0.1, 0.9, 0], atol=1e-12)
    np.testing.assert_allclose(p["left_knee"][0], [0.1, 0.5, 0], atol=1e-12)
    np.testing.assert_allclose(p["left_ankle"][0], [0.1, 0.1, 0], atol=1e-12)
    # toe tip = End Site: ankle + (0, 0, 10) + (0, 0, 5)
    np.testing.assert_allclose(p["left_foot_index"][0], [0.1, 0.1, 0.15], atol=1e-12)
    # Rz(90) @ Rx(90) applied to (0, -40, 0): Rx(90) gives (0, 0, -40), Rz(90) keeps it.
    np.testing.assert_allclose(p["left_ankle"][1], [0.1, 0.5, -0.4], atol=1e-12)
    # Toe offset (0, 0, 10) + (0, 0, 5) under Rz(90) @ Rx(90): Rx(90) maps +z to -y,
    # Rz(90) maps -y to +x, so the foot points along +x.
    np.testing.assert_allclose(p["left_foot_index"][1], [0.25, 0.5, -0.4], atol=1e-12)
    assert seq.fps == pytest.approx(50.0)

    g = tmp_path / "xzy.bvh"
    g.write_text(bvh_text("Xrotation Zrotation Yrotation", frames))
    seq2 = read_bvh(g, unit="cm")
    # Rx(90) @ Rz(90) applied to (0, -40, 0): Rz(90) gives (40, 0, 0), Rx(90) keeps it.
    np.testing.assert_allclose(seq2.positions[1, JOINT_INDEX["left_ankle"]], [0.5, 0.5, 0],
                               atol=1e-12)  # fmt: skip


def test_unmapped_joints_stay_nan(tmp_path: Path) -> None:
    f = tmp_path / "a.bvh"
    f.write_text(bvh_text("Zrotation Xrotation Yrotation", [ZERO.format(a=0, b=0)]))
    seq = read_bvh(f, unit="cm")
    for name in ("nose", "left_heel", "right_knee", "left_shoulder"):
        assert np.isnan(seq.positions[:, JOINT_INDEX[name]]).all()


def test_auto_unit(tmp_path: Path) -> None:
    # A 170-unit-high rest pose (90 + 80 above the toe) reads as centimetres.
    f = tmp_path / "a.bvh"
    f.write_text(bvh_text("Zrotation Xrotation Yrotation", [ZERO.format(a=0, b=0)], thigh=130))
    seq = read_bvh(f)
    assert seq.metadata["bvh_unit"] == "cm"
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_knee"]], [0.1, -0.4, 0],
                               atol=1e-12)  # fmt: skip


def test_z_up_file_is_turned_to_y_up(tmp_path: Path) -> None:
    # read as z up, a file point (x, y, z) is at (y, z, x): the rest knee, (10, 50, 0) cm in
    # the file, at (50, 0, 10) cm; the toe tip (10, 10, 15) at (10, 15, 10)
    f = tmp_path / "a.bvh"
    f.write_text(bvh_text("Zrotation Xrotation Yrotation", [ZERO.format(a=0, b=0)]))
    seq = read_bvh(f, unit="cm", up="z")
    np.testing.assert_allclose(
        seq.positions[0, JOINT_INDEX["left_knee"]], [0.5, 0, 0.1], atol=1e-12
    )
    np.testing.assert_allclose(
        seq.positions[0, JOINT_INDEX["left_foot_index"]], [0.1, 0.15, 0.1], atol=1e-12
    )
    with pytest.raises(DataError, match="up must be 'y' or 'z', got 'x'"):
        read_bvh(f, unit="cm", up="x")


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda t: t.rsplit("\n", 2)[0], "truncated"),
        (lambda t: t.replace("Frame Time: 0.02", "Frame Time: x"), "malformed"),
        (lambda t: t.replace("OFFSET 10 0 0", "OFFSET 10 a 0"), "expected numbers"),
        (
            lambda t: t.replace(
                "Zrotation Xrotation Yrotation\n    JOINT LeftLeg",
                "Zrotation Xrotation Wrotation\n    JOINT LeftLeg",
            ),
            "channel",
        ),
        (lambda t: t.split("MOTION")[0], "MOTION"),
        (lambda t: "hello", "HIERARCHY"),
        # 18 channels a frame: the second frame's second value is value 20
        (
            lambda t: t[::-1].replace(" 09 ", " o9 ", 1)[::-1],
            r"motion value '9o' \(value 20 after the header\) is not a number",
        ),
        # comma-separated values: one token per frame, a count that cannot match
        (
            lambda t: t.replace("0 90 0 0 0 0  0 0 0", "0,90,0,0,0,0,0,0,0", 1),
            r"motion value '0,90,0,0,0,0,0,0,0' \(value 1 after the header\)",
        ),
    ],
)
def test_malformed_names_file(tmp_path: Path, mutate, message: str) -> None:
    f = tmp_path / "bad.bvh"
    text = bvh_text("Zrotation Xrotation Yrotation", [ZERO.format(a=0, b=0)] * 2)
    f.write_text(mutate(text))
    with pytest.raises(DataError, match=message) as info:
        read_bvh(f, unit="cm")
    assert info.value.source == str(f)


def test_position_channels_on_every_joint_keep_the_rest_pose_of_the_offsets(
    tmp_path: Path,
) -> None:
    """Hunt 49h: some exporters give every joint position channels as well as rotations,
    each frame's positions its OFFSET again. The rest pose was read with those channels at
    0, every joint at its parent's origin: "rest pose has no height: cannot guess the unit",
    the file refused. Its rest pose is the offsets', and the file reads as the same skeleton
    with rotation channels alone: the unit guessed alike, the same positions."""
    frames = [ZERO.format(a=0, b=0), ZERO.format(a=90, b=90)]
    rotations = tmp_path / "rotations.bvh"
    rotations.write_text(bvh_text("Zrotation Xrotation Yrotation", frames))
    six = "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
    text = bvh_text("Zrotation Xrotation Yrotation", [])
    text = text.replace("CHANNELS 3 Zrotation Xrotation Yrotation", six)
    offsets = ["10 0 0", "0 -40 0", "0 -40 0", "0 0 10"]  # LeftUpLeg .. LeftToeBase
    rows = []
    for a, b in ((0, 0), (90, 90)):
        rots = ["0 0 0", f"{a} {b} 0", "0 0 0", "0 0 0"]
        rows.append(
            "0 90 0 0 0 0  " + "  ".join(f"{o} {r}" for o, r in zip(offsets, rots, strict=True))
        )
    both = tmp_path / "positions.bvh"
    both.write_text(text.replace("Frames: 0\n", "Frames: 2\n") + "\n".join(rows) + "\n")
    want, got = read_bvh(rotations), read_bvh(both)
    assert got.metadata["bvh_unit"] == want.metadata["bvh_unit"]
    np.testing.assert_allclose(got.positions, want.positions, atol=1e-12)
