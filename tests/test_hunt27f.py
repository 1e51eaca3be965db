"""pose-file leftovers fixed in session 27 (27f): a joint the pose file says it did not see
(confidence exactly 0, written as (0, 0, 0) by OpenPose and COCO-style tools) was used as a
real position, a knee at the origin; an AMC frame listing a bone twice was "bone appears in 4
of 3 frames"; a ``metadata["source"]`` replaced the sequence's source when saved; the mirror
image of a mirror image was named "... (mirrored) (mirrored)". Each test says what happened
before its fix; the expected values are worked out by hand from the positions written
here."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from features.body import mirrored
from features.fluents import evaluate
from features.poses import PoseSequence, load_pose, save_pose
from features.signals import state_signals
from features.skeleton import BLAZEPOSE_33, JOINT_INDEX
from tests.badinput import refused
from tests.test_hunt27d import _ASF

# A COCO-style subset: the left leg bent at a right angle (thigh straight down from the hip to
# the knee, shin forward along +z), the right leg straight.
LEGS = ("left_hip", "left_knee", "left_ankle", "right_hip", "right_knee", "right_ankle")
LEG_POSE = [
    [0.1, 1.0, 0.0],
    [0.1, 0.5, 0.0],
    [0.1, 0.5, 0.5],
    [-0.1, 1.0, 0.0],
    [-0.1, 0.5, 0.0],
    [-0.1, 0.0, 0.0],
]


def _legs_file(path: Path, unseen_frames: slice | None) -> Path:
    pos = np.tile(np.array(LEG_POSE), (4, 1, 1))
    conf = np.ones((4, len(LEGS)))
    if unseen_frames is not None:
        pos[unseen_frames, 1] = 0.0  # the left knee, not seen: (0, 0, 0) with confidence 0
        conf[unseen_frames, 1] = 0.0
    np.savez(path, positions=pos, joint_names=np.array(LEGS), fps=30.0, confidence=conf)
    return path


def test_unseen_joint_is_missing_not_at_the_origin(tmp_path: Path) -> None:
    """Before: frames 1-2's left knee at (0, 0, 0) read as a position, a knee angle of
    0.78 rad (hip-knee-ankle through the origin) and confident "left knee bent" there."""
    whole = load_pose(_legs_file(tmp_path / "seen.npz", None))
    # hip - knee = (0, 0.5, 0), ankle - knee = (0, 0, 0.5): a right angle
    np.testing.assert_allclose(state_signals(whole).column("left_knee"), [math.pi / 2] * 4)

    seq = load_pose(_legs_file(tmp_path / "coco.npz", slice(1, 3)))
    knee = state_signals(seq).column("left_knee")
    np.testing.assert_allclose(knee[[0, 3]], [math.pi / 2] * 2)
    assert np.isnan(knee[1:3]).all()
    bent = evaluate(seq).column("left_leg_bent.bent")
    assert np.isnan(bent[1:3]).all()
    assert not np.isnan(bent[[0, 3]]).any()
    # the right knee (straight, pi) is untouched by the left knee's gaps
    np.testing.assert_allclose(state_signals(seq).column("right_knee"), [math.pi] * 4)
    # the sequence as read keeps what the file holds
    np.testing.assert_array_equal(seq.positions[1:3, 1], 0.0)


def test_unseen_joint_is_missing_on_the_full_skeleton(tmp_path: Path) -> None:
    """Before: the same on a file naming all 33 BlazePose joints (which the features read as
    they are): the knee at the origin gave 0.78 rad."""
    pos = np.full((4, 33, 3), np.nan)
    conf = np.full((4, 33), 0.9)
    for name, xyz in zip(LEGS, LEG_POSE, strict=True):
        pos[:, JOINT_INDEX[name]] = xyz
    pos[2, JOINT_INDEX["left_knee"]] = 0.0
    conf[2, JOINT_INDEX["left_knee"]] = 0.0
    path = tmp_path / "full.npz"
    np.savez(path, positions=pos, joint_names=np.array(BLAZEPOSE_33), fps=30.0, confidence=conf)
    knee = state_signals(load_pose(path)).column("left_knee")
    np.testing.assert_allclose(knee[[0, 1, 3]], [math.pi / 2] * 3)
    assert np.isnan(knee[2])


# ---- ASF/AMC -----------------------------------------------------------------------------

# hunt 27d's left arm (clavicle, humerus, radius); the frames below list the clavicle alone
# (the bones below it are then unknown, NaN)
_FRAME = "root 0 1 0 0 0 0\nlclavicle 0 0 0\n"


def _amc_pair(root: Path, frames: list[str]) -> tuple[Path, Path]:
    (root / "arm.asf").write_text(_ASF)
    amc = root / "arm.amc"
    amc.write_text(
        ":FULLY-SPECIFIED\n:DEGREES\n" + "".join(f"{i}\n{f}" for i, f in enumerate(frames, start=1))
    )
    return root / "arm.asf", amc


@pytest.mark.parametrize("twice", [1, 2])
def test_amc_bone_listed_twice_in_a_frame_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], twice: int
) -> None:
    """Before: ``lclavicle`` twice in frame 2 of 3 was "bone 'lclavicle' appears in 4 of 3
    frames" (in frame 1: "4 of 3" too), naming neither the frame nor the line."""
    frames = [_FRAME] * 3
    frames[twice - 1] = _FRAME + "lclavicle 0 0 0\n"
    asf, amc = _amc_pair(tmp_path, frames)
    # frame k's lines start at 3 + 3 (k - 1) (two header lines, then number, root, bone); the
    # second lclavicle follows frame k's first one
    line = 3 + 3 * (twice - 1) + 3
    refused(
        ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")],
        tmp_path,
        capsys,
        "arm.amc",
        f"line {line}: bone 'lclavicle' is listed twice in frame {twice}",
    )


def test_metadata_source_does_not_hide_the_sequence_source(tmp_path: Path) -> None:
    """Before: saved, ``metadata={"source": "notes.txt"}`` overwrote the sequence's source
    ``walk.mp4`` in the file: read back, made_from was notes.txt and walk.mp4 was lost."""
    seq = PoseSequence(
        np.zeros((2, 1, 3)),
        ("nose",),
        30.0,
        source="walk.mp4",
        metadata={"source": "notes.txt", "label": "walk"},
    )
    back = load_pose(save_pose(seq, tmp_path / "walk.npz"))
    assert back.metadata == {
        "label": "walk",
        "made_from": "walk.mp4",
        "metadata_source": "notes.txt",
    }
    # the same text in both: nothing to keep apart
    same = PoseSequence(
        np.zeros((2, 1, 3)), ("nose",), 30.0, source="walk.mp4", metadata={"source": "walk.mp4"}
    )
    assert load_pose(save_pose(same, tmp_path / "same.npz")).metadata == {"made_from": "walk.mp4"}


def test_mirror_of_a_mirror_is_named_as_the_original() -> None:
    """Before: mirrored twice, the source was "walk.npz (mirrored) (mirrored)" though the
    positions are the original's (x negated twice, left and right swapped back)."""
    pos = np.array([[[0.2, 1.4, 0.1], [-0.2, 1.4, 0.0]]])  # left shoulder, right shoulder
    seq = PoseSequence(pos, ("left_shoulder", "right_shoulder"), 30.0, source="walk.npz")
    once = mirrored(seq)
    assert once.source == "walk.npz (mirrored)"
    # once: the right shoulder (-0.2, 1.4, 0) becomes the left one at (0.2, 1.4, 0)
    np.testing.assert_array_equal(once.positions[0, JOINT_INDEX["left_shoulder"]], [0.2, 1.4, 0])
    twice = mirrored(once)
    assert twice.source == "walk.npz"
    np.testing.assert_array_equal(twice.positions[0, JOINT_INDEX["left_shoulder"]], pos[0, 0])
    np.testing.assert_array_equal(twice.positions[0, JOINT_INDEX["right_shoulder"]], pos[0, 1])
