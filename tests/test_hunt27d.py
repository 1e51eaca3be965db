"""What hunt 27d found in the readers, skeletons and pose files: a BVH skeleton that names its
shoulder joint ``lShldr`` (Poser/DAZ) or ``LeftShoulder`` (named by joints) lost both shoulders.
Each test says what happened before its fix; the expected values are worked out by hand from
the offsets and angles written here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.readers import read_bvh
from features.skeleton import JOINT_INDEX

# ---- BVH ---------------------------------------------------------------------------------


def _bvh_joint(name: str, offset: tuple[float, float, float], kids: list[str], end: bool) -> str:
    body = f"OFFSET {offset[0]} {offset[1]} {offset[2]}\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
    body += "".join(kids)
    if end:
        body += "End Site\n{\nOFFSET 0 -0.1 0\n}\n"
    return f"JOINT {name}\n{{\n{body}}}\n"


def _bvh(arm: tuple[str, str, str, str], frames: list[list[float]]) -> str:
    """A person facing +z (left = +x), hips at 1 m: spine to the chest at 1.4 m, on each side
    ``arm`` = (collar or "", shoulder, elbow, wrist) joints with the shoulder 0.2 m out at
    1.6 m, and legs ``LeftUpLeg``/``LeftLeg``/``LeftFoot``. ``frames``: per frame the values
    of the channels in file order (root: 6, every joint: 3)."""
    collar, shoulder, elbow, wrist = arm
    arms = []
    for side, sx in (("Left", 1.0), ("Right", -1.0)):
        letter = side[0].lower()

        def named(n: str, side: str = side, letter: str = letter) -> str:
            return n.replace("{S}", side).replace("{s}", letter)

        hand = _bvh_joint(named(wrist), (0.0, -0.25, 0.0), [], True)
        fore = _bvh_joint(named(elbow), (0.0, -0.3, 0.0), [hand], False)
        if collar:
            upper = _bvh_joint(named(shoulder), (sx * 0.15, 0.0, 0.0), [fore], False)
            arms.append(_bvh_joint(named(collar), (sx * 0.05, 0.2, 0.0), [upper], False))
        else:
            arms.append(_bvh_joint(named(shoulder), (sx * 0.2, 0.2, 0.0), [fore], False))
    legs = []
    for side, sx in (("Left", 1.0), ("Right", -1.0)):
        foot = _bvh_joint(f"{side}Foot", (0.0, -0.45, 0.0), [], True)
        knee = _bvh_joint(f"{side}Leg", (0.0, -0.45, 0.0), [foot], False)
        legs.append(_bvh_joint(f"{side}UpLeg", (sx * 0.1, 0.0, 0.0), [knee], False))
    chest = _bvh_joint("Chest", (0.0, 0.3, 0.0), arms, True)
    spine = _bvh_joint("Spine", (0.0, 0.1, 0.0), [chest], False)
    root = (
        "ROOT Hips\n{\nOFFSET 0 0 0\n"
        "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        + spine
        + "".join(legs)
        + "}\n"
    )
    motion = "\n".join(" ".join(f"{v:g}" for v in row) for row in frames)
    return f"HIERARCHY\n{root}MOTION\nFrames: {len(frames)}\nFrame Time: 0.04\n{motion}\n"


_BVH_JOINTS = 1 + 2 + 2 * 3 + 2 * 3  # root, spine, chest, arms (no collar), legs
_BVH_JOINTS_COLLAR = _BVH_JOINTS + 2


@pytest.mark.parametrize(
    "arm",
    [
        ("{s}Collar", "{s}Shldr", "{s}ForeArm", "{s}Hand"),  # Poser / DAZ
        ("", "{S}Shoulder", "{S}Elbow", "{S}Wrist"),  # named by joints
    ],
)
def test_bvh_shoulder_joint_named_shldr_or_shoulder_is_read(tmp_path: Path, arm: tuple) -> None:
    """Before: ``lShldr`` and ``LeftShoulder`` were looked up as End Sites, which a joint
    with a child never has: both shoulders were NaN, and with them every arm fluent
    ("left arm raised", "bent", ...) unavailable."""
    n_joints = _BVH_JOINTS_COLLAR if arm[0] else _BVH_JOINTS
    rest = [0.0, 1.0, 0.0] + [0.0] * (3 * n_joints)
    path = tmp_path / "poser.bvh"
    path.write_text(_bvh(arm, [rest, rest]))
    seq = read_bvh(path, unit="m")
    # hips (0, 1, 0) + spine 0.1 + chest 0.3 -> chest at (0, 1.4, 0); the shoulder is 0.2 m
    # to the side (+x left) and 0.2 m up, whether through the collar or directly
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_shoulder"]], [0.2, 1.6, 0.0])
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["right_shoulder"]], [-0.2, 1.6, 0.0])
    # the elbow 0.3 m below the shoulder, the wrist 0.25 m further
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_elbow"]], [0.2, 1.3, 0.0])
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_wrist"]], [0.2, 1.05, 0.0])
