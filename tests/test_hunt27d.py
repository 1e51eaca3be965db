"""What hunt 27d found in the readers, skeletons and pose files: a BVH skeleton that names its
shoulder joint ``lShldr`` (Poser/DAZ) or ``LeftShoulder`` (named by joints, as a CMU
conversion does) lost both shoulders; CMU BVH conversions (inches / 0.45) were read as inches, a
0.64 m person, and a BVH with no joint name the reader knows read as all NaN ("shows no
person"); a ``kinect_v2`` pose file naming Kinect's joints, or any pose file naming
MediaPipe's ``LEFT_SHOULDER``, was refused (and such a sequence given to the Python API showed
"no person"), as was a skeleton name in another case; an AMC file that never lists a bone drew
it in the rest pose, and one whose first frame lacks a bone blamed a complete frame; a UI-PRMD
file's sensor was guessed from "vicon" in its path; hidden ``._name`` files were read as clips,
takes and skeletons; an HDM05 or CMU take was read on another subject's skeleton; a labels
CSV's frame range or label block was ignored beside (or without) a label file; a folder given
for one clip was called an unknown clip format; a BVH's negative frame count or CHANNELS
inside an End Site were blamed on its data. Each test says what happened before its fix; the
expected values are worked out by hand from the offsets, angles and positions written here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_clip, load_dataset
from features.errors import DataError, PoseFileError
from features.poses import PoseSequence, load_pose, save_pose
from features.readers import read_asf_amc, read_bvh
from features.skeleton import JOINT_INDEX, KINECT_V2_TO_BLAZEPOSE
from posecbr.cli import main
from tests.badinput import good_pose_file, refused

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


# ---- Kinect v2 pose files ----------------------------------------------------------------

# A person 2.5 m in front of a Kinect v2, facing it (-z in Kinect's camera space, where x is
# the sensor's left): the person's left is -x. Left arm straight up, right arm hanging.
_KINECT_POSE = {
    "SpineBase": (0.0, 1.0, 2.5),
    "SpineMid": (0.0, 1.25, 2.5),
    "SpineShoulder": (0.0, 1.5, 2.5),
    "Neck": (0.0, 1.55, 2.5),
    "Head": (0.0, 1.7, 2.5),
    "ShoulderLeft": (-0.2, 1.5, 2.5),
    "ElbowLeft": (-0.2, 1.8, 2.5),
    "WristLeft": (-0.2, 2.05, 2.5),
    "HandLeft": (-0.2, 2.12, 2.5),
    "ShoulderRight": (0.2, 1.5, 2.5),
    "ElbowRight": (0.2, 1.2, 2.5),
    "WristRight": (0.2, 0.95, 2.5),
    "HandRight": (0.2, 0.88, 2.5),
    "HipLeft": (-0.1, 0.95, 2.5),
    "KneeLeft": (-0.1, 0.5, 2.5),
    "AnkleLeft": (-0.1, 0.08, 2.5),
    "FootLeft": (-0.1, 0.03, 2.38),
    "HipRight": (0.1, 0.95, 2.5),
    "KneeRight": (0.1, 0.5, 2.5),
    "AnkleRight": (0.1, 0.08, 2.5),
    "FootRight": (0.1, 0.03, 2.38),
}


def _kinect_file(path: Path, frames: int = 20) -> Path:
    names = tuple(_KINECT_POSE)
    pos = np.repeat(np.array([list(_KINECT_POSE.values())]), frames, axis=0)
    conf = np.full(pos.shape[:2], 0.9)
    conf[:, names.index("ShoulderLeft")] = 0.5
    seq = PoseSequence(pos, names, 30.0, confidence=conf, skeleton="kinect_v2")
    return save_pose(seq, path)


def test_kinect_v2_pose_file_maps_onto_blazepose(tmp_path: Path) -> None:
    """Before: a pose file of skeleton ``kinect_v2`` (a known skeleton) naming Kinect's joints
    was refused: "joint names are not BlazePose landmark names: SpineBase, ..."; the spec's
    declared Kinect v2 joint map did not exist."""
    seq = load_pose(_kinect_file(tmp_path / "kinect.npz")).to_canonical()
    p = seq.positions[0]
    np.testing.assert_allclose(p[JOINT_INDEX["left_shoulder"]], [-0.2, 1.5, 2.5])
    np.testing.assert_allclose(p[JOINT_INDEX["right_wrist"]], [0.2, 0.95, 2.5])
    np.testing.assert_allclose(p[JOINT_INDEX["left_foot_index"]], [-0.1, 0.03, 2.38])
    # Kinect has no face landmarks, knuckles or heels: NaN, and their confidence unknown
    for missing in ("nose", "left_index", "left_thumb", "right_heel"):
        assert np.isnan(p[JOINT_INDEX[missing]]).all(), missing
        assert np.isnan(seq.confidence[0, JOINT_INDEX[missing]]), missing
    assert seq.confidence[0, JOINT_INDEX["left_shoulder"]] == 0.5
    assert seq.confidence[0, JOINT_INDEX["right_shoulder"]] == 0.9


def test_kinect_v2_left_arm_raised_reads_left(tmp_path: Path, capsys) -> None:
    """Before: ``describe`` refused the file (see above). The person's left arm (Kinect's
    ``ElbowLeft``/``WristLeft``, above the shoulder) is the one raised."""
    path = _kinect_file(tmp_path / "kinect.npz")
    assert main(["describe", str(path)]) == 0
    out = capsys.readouterr().out
    assert "left arm raised" in out and "right arm lowered" in out, out
    assert "right arm raised" not in out and "left arm lowered" not in out, out


def test_other_skeleton_with_foreign_joint_names_is_still_refused(tmp_path: Path) -> None:
    """Kinect's names belong to ``kinect_v2`` only: a BlazePose file naming them is refused."""
    names = tuple(_KINECT_POSE)
    seq = PoseSequence(np.zeros((2, len(names), 3)), names, 30.0)
    with pytest.raises(PoseFileError, match="not BlazePose landmark names: SpineBase"):
        seq.to_canonical()


# ---- ASF/AMC -----------------------------------------------------------------------------

# One left arm: clavicle 0.2 m along +x (the skeleton's left), humerus 0.3 m and radius
# 0.25 m down. ``length 0.0254`` makes one ASF unit one metre (metres = value x 0.0254 / 0.0254).
_ASF = """:version 1.10
:name arm
:units
  mass 1.0
  length 0.0254
  angle deg
:root
  order TX TY TZ RX RY RZ
  axis XYZ
  position 0 0 0
  orientation 0 0 0
:bonedata
  begin
    id 1
    name lclavicle
    direction 1 0 0
    length 0.2
    axis 0 0 0 XYZ
    dof rx ry rz
  end
  begin
    id 2
    name lhumerus
    direction 0 -1 0
    length 0.3
    axis 0 0 0 XYZ
    dof rx ry rz
  end
  begin
    id 3
    name lradius
    direction 0 -1 0
    length 0.25
    axis 0 0 0 XYZ
    dof rx
  end
:hierarchy
  begin
    root lclavicle
    lclavicle lhumerus
    lhumerus lradius
  end
"""


def _amc(bones: str, frames: int = 3) -> str:
    return ":FULLY-SPECIFIED\n:DEGREES\n" + "".join(
        f"{f}\nroot 0 1 0 0 0 0\n{bones}" for f in range(1, frames + 1)
    )


def test_amc_without_a_bone_leaves_it_and_below_nan(tmp_path: Path) -> None:
    """Before: an AMC file that never lists ``lhumerus`` (a bone the skeleton says turns) drew
    the arm in the ASF's rest pose: an elbow at (0.2, 0.7, 0) and a wrist below it that no
    frame recorded."""
    asf = tmp_path / "arm.asf"
    asf.write_text(_ASF)
    full = tmp_path / "full.amc"
    full.write_text(_amc("lclavicle 0 0 0\nlhumerus 0 0 0\nlradius 0\n"))
    seq = read_asf_amc(asf, full)
    # root at (0, 1, 0); the clavicle ends 0.2 m to the left, the humerus 0.3 m below it
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_shoulder"]], [0.2, 1.0, 0.0])
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_elbow"]], [0.2, 0.7, 0.0])
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_wrist"]], [0.2, 0.45, 0.0])
    partial = tmp_path / "partial.amc"
    partial.write_text(_amc("lclavicle 0 0 0\nlradius 0\n"))
    seq = read_asf_amc(asf, partial)
    np.testing.assert_allclose(
        seq.positions[:, JOINT_INDEX["left_shoulder"]], [[0.2, 1.0, 0.0]] * 3
    )
    assert np.isnan(seq.positions[:, JOINT_INDEX["left_elbow"]]).all()
    assert np.isnan(seq.positions[:, JOINT_INDEX["left_wrist"]]).all()


# ---- UI-PRMD files outside their folders -------------------------------------------------


def _rows(width: int, value: float, n: int = 4) -> str:
    return "\n".join(",".join([f"{value:g}"] * width) for _ in range(n)) + "\n"


def test_uiprmd_sensor_is_told_by_the_file_not_its_folder(tmp_path: Path) -> None:
    """Before: a UI-PRMD positions file was read as Vicon when "vicon" appeared anywhere in its
    path, else as Kinect. A Vicon file copied to ``clips/`` was refused for lacking a Kinect
    angles file; a Kinect file in ``vicon_study/`` for having 66 numbers, not 117. The width
    of a row tells them apart: Kinect 22 joints x 3, Vicon 39 markers x 3."""
    clips = tmp_path / "clips"
    clips.mkdir()
    (clips / "m01_s01_e01_positions.txt").write_text(_rows(117, 500.0))
    seq = load_clip(clips / "m01_s01_e01_positions.txt")
    assert (seq.skeleton, seq.fps, seq.n_frames) == ("uiprmd_vicon", 100.0, 4)
    # every marker at (500, 500, 500) mm: the knee marker at 0.5 m on each canonical axis
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_knee"]], [0.5, 0.5, 0.5])
    study = tmp_path / "vicon_study"
    study.mkdir()
    (study / "m01_s01_e01_positions.txt").write_text(_rows(66, 0.0))
    (study / "m01_s01_e01_angles.txt").write_text(_rows(66, 0.0))
    seq = load_clip(study / "m01_s01_e01_positions.txt")
    assert (seq.skeleton, seq.fps, seq.n_frames) == ("uiprmd_kinect", 30.0, 4)


# ---- joint names in MediaPipe's spelling -------------------------------------------------


def test_mediapipe_upper_case_joint_names_are_blazepose_joints(tmp_path: Path, capsys) -> None:
    """Before: a pose file naming its joints as MediaPipe's ``PoseLandmark`` does
    (``LEFT_SHOULDER``, the names the canonical skeleton says it follows) was refused: "joint
    names are not BlazePose landmark names: LEFT_SHOULDER, ..."."""
    names = tuple(n.upper() for n in KINECT_V2_TO_BLAZEPOSE)
    pos = np.array([[_KINECT_POSE[k] for k in KINECT_V2_TO_BLAZEPOSE.values()]] * 20)
    path = save_pose(PoseSequence(pos, names, 30.0), tmp_path / "mediapipe.npz")
    seq = load_pose(path).to_canonical()
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_elbow"]], [-0.2, 1.8, 2.5])
    assert np.isnan(seq.positions[0, JOINT_INDEX["nose"]]).all()
    assert main(["describe", str(path)]) == 0
    out = capsys.readouterr().out
    assert "left arm raised" in out and "right arm lowered" in out, out


def test_two_names_for_one_joint_are_refused(tmp_path: Path, capsys) -> None:
    """``nose`` and ``NOSE`` in one file name one joint twice, now that names are read in any
    case: refused in one line naming both, neither silently dropped. (Before: refused as "not
    BlazePose landmark names: NOSE".)"""
    names = ("nose", "NOSE", "left_shoulder")
    path = save_pose(PoseSequence(np.zeros((3, 3, 3)), names, 30.0), tmp_path / "twice.npz")
    refused(["describe", str(path)], tmp_path, capsys, "twice.npz", "'nose' and 'NOSE'")


def test_skeleton_name_in_another_case_is_the_known_skeleton(tmp_path: Path) -> None:
    """Before: ``skeleton="Kinect_V2"`` (or ``"BlazePose33"``) was refused as an unknown
    skeleton, though the message listed it as known in lower case."""
    names = tuple(_KINECT_POSE)
    pos = np.array([list(_KINECT_POSE.values())] * 3)
    path = tmp_path / "kinect.npz"
    save_pose(PoseSequence(pos, names, 30.0, skeleton="kinect_v2"), path)
    np.savez(tmp_path / "k2.npz", **{**np.load(path), "skeleton": np.array("Kinect_V2")})
    seq = load_pose(tmp_path / "k2.npz")
    assert seq.skeleton == "kinect_v2"
    np.testing.assert_allclose(
        seq.to_canonical().positions[0, JOINT_INDEX["left_knee"]], [-0.1, 0.5, 2.5]
    )
    assert (
        PoseSequence(pos[:, :1], ("nose",), 30.0, skeleton="BlazePose33").skeleton == "blazepose33"
    )


# ---- hidden files beside the clips -------------------------------------------------------

_APPLE_DOUBLE = b"\x00\x05\x16\x07\x00\x02\x00\x00" + b"\x00" * 80  # a macOS "._name" file


def test_classify_reads_a_folder_of_clips_as_train_does(tmp_path: Path) -> None:
    """Before: ``classify FOLDER`` read every name ending in .npz/.bvh/a video suffix,
    hidden or not, file or not: a folder copied from a Mac (``._a.npz`` beside ``a.npz``) was
    refused ("._a.npz: cannot read pose file: not an .npz archive"), though ``train`` reads
    the same folder without it."""
    from posecbr.commands.classify import load_inputs

    clips = tmp_path / "clips"
    clips.mkdir()
    good_pose_file(clips / "a.npz", frames=20, label="stand")
    (clips / "._a.npz").write_bytes(_APPLE_DOUBLE)
    (clips / "old.npz").mkdir()
    got = load_inputs([clips], "kinect")
    assert [(Path(s.source).name, label) for s, label in got] == [("a.npz", "stand")]


def test_hidden_amc_and_asf_files_are_not_takes_or_skeletons(tmp_path: Path) -> None:
    """Before: in a CMU-style folder (``arm.asf`` with its takes) copied from a Mac, the
    hidden ``._arm.asf`` counted as a second skeleton ("2 .asf files beside it and none named
    for its actor: cannot pick one") and ``._take.amc`` as a take to read."""
    folder = tmp_path / "reach"
    folder.mkdir()
    (folder / "arm.asf").write_text(_ASF)
    (folder / "take.amc").write_text(_amc("lclavicle 0 0 0\nlhumerus 0 0 0\nlradius 0\n"))
    (folder / "._arm.asf").write_bytes(_APPLE_DOUBLE)
    (folder / "._take.amc").write_bytes(_APPLE_DOUBLE)
    seq = load_clip(folder / "take.amc")
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_elbow"]], [0.2, 0.7, 0.0])
    clips = load_dataset(tmp_path)
    assert [(Path(c.seq.source).name, c.label) for c in clips] == [("take.amc", "reach")]


def test_kinect_v2_and_mediapipe_named_sequences_show_their_torso() -> None:
    """The torso check (which refuses a clip with "shows no person") looked the torso joints
    up by BlazePose name in the sequence as given; a Kinect-named or MediaPipe-named sequence
    handed to the Python API (``DADClassifier``, ``CaseBaseClassifier``) showed no torso in
    any frame, though every frame has both shoulders and both hips."""
    from features.body import torso_share

    names = tuple(_KINECT_POSE)
    pos = np.array([list(_KINECT_POSE.values())] * 5)
    assert torso_share(PoseSequence(pos, names, 30.0, skeleton="kinect_v2")) == 1.0
    upper = tuple(n.upper() for n in KINECT_V2_TO_BLAZEPOSE)
    pos = np.array([[_KINECT_POSE[k] for k in KINECT_V2_TO_BLAZEPOSE.values()]] * 5)
    assert torso_share(PoseSequence(pos, upper, 30.0)) == 1.0


# ---- labels CSV ----------------------------------------------------------------------------


def test_frame_range_with_a_label_file_is_refused(tmp_path: Path, capsys) -> None:
    """Before: a labels CSV row with both a ``label_file`` and ``start``/``end`` read the
    whole recording (frames 0-19 labelled a, b), the range 0-5 silently ignored."""
    data = tmp_path / "data"
    data.mkdir()
    good_pose_file(data / "rec.npz", frames=20)
    (data / "rec.txt").write_text(" ".join(["a"] * 10 + ["b"] * 10))
    (data / "labels.csv").write_text("path,label_file,start,end\nrec.npz,rec.txt,0,5\n")
    refused(
        ["train", str(data), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
        "labels.csv", "line 2: start and end do not go with a label_file",
    )  # fmt: skip


def test_label_block_without_a_label_file_is_refused(tmp_path: Path, capsys) -> None:
    """Before: ``label_block_s`` on a row with a plain ``label`` (no ``label_file``) was
    dropped without a word: the user meant a recording labelled over time."""
    data = tmp_path / "data"
    data.mkdir()
    good_pose_file(data / "rec.npz", frames=20)
    (data / "labels.csv").write_text("path,label,label_block_s\nrec.npz,walk,0.5\n")
    refused(
        ["train", str(data), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
        "labels.csv", "line 2: label_block_s goes with a label_file",
    )  # fmt: skip


def test_hdm05_take_is_not_read_on_another_actors_skeleton(tmp_path: Path, capsys) -> None:
    """Before: an HDM05 take of actor dg with only actor bd's skeleton beside it was read on
    bd's bones (the only .asf there), another person's limb lengths, without a word."""
    (tmp_path / "HDM_bd.asf").write_text(_ASF)
    amc = tmp_path / "HDM_dg_reach_001_120.amc"
    amc.write_text(_amc("lclavicle 0 0 0\nlhumerus 0 0 0\nlradius 0\n"))
    refused(["describe", str(amc)], tmp_path, capsys, amc.name, "no HDM_dg.asf", "HDM_bd.asf")
    (tmp_path / "HDM_dg.asf").write_text(_ASF)  # its own skeleton: read
    assert np.isfinite(load_clip(amc).positions[:, JOINT_INDEX["left_wrist"]]).all()


@pytest.mark.parametrize("command", ["describe", "dad", "reps"])
def test_a_folder_given_for_one_clip_is_called_a_folder(tmp_path: Path, capsys, command) -> None:
    """Before: "clips: unknown clip format (expected .npz pose file, .bvh, ...)" for a folder
    of clips given where one clip goes: the refusal blamed a format the folder does not have."""
    folder = tmp_path / "clips"
    folder.mkdir()
    good_pose_file(folder / "a.npz", frames=20)
    refused([command, str(folder)], tmp_path, capsys, "clips: is a folder, not a clip file")


# ---- BVH in the CMU database's unit ------------------------------------------------------

# The legs and head of a CMU database BVH conversion (offsets as those files write them: the
# ASF's unit, inches / 0.45). Rest height: head end 2.03559 + 2.04885 + 1.74624 + 1.76136 +
# 1.77044 = 9.36248 above the hips, toe end 1.79463 + 6.72613 + 7.03959 + 0.43311 = 15.99346
# below: 25.35594 units.
_CMU_BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT LeftHip
  {
    OFFSET 1.36306 -1.79463 0.83929
    CHANNELS 3 Zrotation Yrotation Xrotation
    JOINT LeftKnee
    {
      OFFSET 2.44811 -6.72613 0.00000
      CHANNELS 3 Zrotation Yrotation Xrotation
      JOINT LeftAnkle
      {
        OFFSET 2.56220 -7.03959 0.00000
        CHANNELS 3 Zrotation Yrotation Xrotation
        JOINT LeftToe
        {
          OFFSET 0.15764 -0.43311 2.32255
          CHANNELS 3 Zrotation Yrotation Xrotation
          End Site
          {
            OFFSET 0 0 1.18966
          }
        }
      }
    }
  }
  JOINT Chest
  {
    OFFSET 0.02827 2.03559 -0.19338
    CHANNELS 3 Zrotation Yrotation Xrotation
    JOINT Chest2
    {
      OFFSET 0.05672 2.04885 -0.04275
      CHANNELS 3 Zrotation Yrotation Xrotation
      JOINT Neck
      {
        OFFSET -0.05417 1.74624 0.17202
        CHANNELS 3 Zrotation Yrotation Xrotation
        JOINT Head
        {
          OFFSET 0.10407 1.76136 -0.12397
          CHANNELS 3 Zrotation Yrotation Xrotation
          End Site
          {
            OFFSET 0.03720 1.77044 -0.06241
          }
        }
      }
    }
  }
}
MOTION
Frames: 1
Frame Time: .0083333
9.3722 17.8693 -17.3198 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0
"""


def test_cmu_bvh_reads_in_the_cmu_unit(tmp_path: Path) -> None:
    """Before: the rest pose of a CMU database BVH, 25.36 units tall, was read as inches (the
    unit that made it closest to 1.7 m among m, cm, mm, inch: 0.64 m), a person of a child's
    size: a 0.19 m shin. In the CMU unit (0.0254 / 0.45 m) it stands 1.43 m."""
    path = tmp_path / "13_29.bvh"
    path.write_text(_CMU_BVH)
    seq = read_bvh(path)
    assert seq.metadata["bvh_unit"] == "cmu"
    knee = seq.positions[0, JOINT_INDEX["left_knee"]]
    ankle = seq.positions[0, JOINT_INDEX["left_ankle"]]
    # the LeftAnkle offset (2.56220, -7.03959, 0) is 7.4914 units: 7.4914 x 0.0254 / 0.45 m
    assert np.linalg.norm(ankle - knee) == pytest.approx(0.42285, abs=1e-4)
    # the root position channel (9.3722, 17.8693, -17.3198) units, in metres
    np.testing.assert_allclose(
        seq.positions[0, JOINT_INDEX["left_hip"]],
        (np.array([9.3722, 17.8693, -17.3198]) + [1.36306, -1.79463, 0.83929]) * 0.0254 / 0.45,
    )


def test_amc_frame_with_a_bone_the_first_frame_lacks_is_named(tmp_path: Path) -> None:
    """Before: when frame 1 lacked ``lhumerus`` and frame 2 listed it, the refusal said
    "last frame 2 is incomplete (truncated file?)": frame 2 is the complete one, the file not
    truncated. Now it names the bone and the frames."""
    asf = tmp_path / "arm.asf"
    asf.write_text(_ASF)
    amc = tmp_path / "take.amc"
    amc.write_text(
        ":DEGREES\n1\nroot 0 1 0 0 0 0\nlclavicle 0 0 0\nlradius 0\n"
        "2\nroot 0 1 0 0 0 0\nlclavicle 0 0 0\nlhumerus 0 0 0\nlradius 0\n"
    )
    with pytest.raises(DataError, match="frame 2 lists lhumerus, which frame 1 does not") as info:
        read_asf_amc(asf, amc)
    assert "truncated" not in info.value.message
    amc.write_text(
        ":DEGREES\n1\nroot 0 1 0 0 0 0\nlclavicle 0 0 0\nlhumerus 0 0 0\nlradius 0\n"
        "2\nroot 0 1 0 0 0 0\nlclavicle 0 0 0\nlradius 0\n3\nroot 0 1 0 0 0 0\n"
    )
    with pytest.raises(DataError, match=r"line 11: frame 2 is incomplete: no lhumerus"):
        read_asf_amc(asf, amc)


def test_bvh_with_no_known_joint_name_is_refused_as_such(tmp_path: Path, capsys) -> None:
    """Before: a BVH whose joints the reader has no names for (Unreal's ``thigh_l``,
    ``upperarm_l``, ...) read as a clip with every joint NaN: ``describe`` said it "shows no
    person", and ``convert`` wrote an all-NaN pose file without a word."""
    text = _bvh(("", "{S}Shoulder", "{S}Elbow", "{S}Wrist"), [[0.0, 1.0, 0.0] + [0.0] * 45])
    for old, new in (("LeftUpLeg", "thigh_l"), ("RightUpLeg", "thigh_r"), ("LeftLeg", "calf_l"),
                     ("RightLeg", "calf_r"), ("LeftFoot", "foot_l"), ("RightFoot", "foot_r"),
                     ("LeftShoulder", "upperarm_l"), ("RightShoulder", "upperarm_r"),
                     ("LeftElbow", "lowerarm_l"), ("RightElbow", "lowerarm_r"),
                     ("LeftWrist", "hand_l"), ("RightWrist", "hand_r")):  # fmt: skip
        text = text.replace(old, new)
    path = tmp_path / "unreal.bvh"
    path.write_text(text)
    refused(["describe", str(path)], tmp_path, capsys, "unreal.bvh", "none of its joint names")
    refused(["convert", str(path), "--out", str(tmp_path / "out")], tmp_path, capsys,
            "unreal.bvh", "it has Hips, Spine, Chest, upperarm_l")  # fmt: skip


def test_bvh_negative_frame_count_is_named(tmp_path: Path) -> None:
    """Before: ``Frames: -2`` with no data lines was refused as "0 numbers after the header,
    expected -2 frames x 48 channels (truncated file?)", blaming the data, not the count."""
    text = _bvh(("", "{S}Shoulder", "{S}Elbow", "{S}Wrist"), [])
    path = tmp_path / "neg.bvh"
    path.write_text(text.replace("Frames: 0", "Frames: -2"))
    with pytest.raises(DataError, match="Frames must be at least 1, got -2"):
        read_bvh(path)


def test_bvh_channels_inside_an_end_site_are_refused(tmp_path: Path) -> None:
    """Before: ``CHANNELS 1 Xrotation`` inside the left wrist's End Site replaced the wrist's
    own three channels, and the file was refused as "48 numbers after the header, expected 1
    frames x 46 channels (truncated file?)"; with the values counted to fit, the wrist's
    rotation would have been read from one value and every later joint's shifted."""
    rest = [0.0, 1.0, 0.0] + [0.0] * 45
    text = _bvh(("", "{S}Shoulder", "{S}Elbow", "{S}Wrist"), [rest])
    first_end = "End Site\n{\nOFFSET 0 -0.1 0\n}\n"
    assert first_end in text
    path = tmp_path / "bad.bvh"
    path.write_text(
        text.replace(first_end, "End Site\n{\nOFFSET 0 -0.1 0\nCHANNELS 1 Xrotation\n}\n", 1)
    )
    with pytest.raises(DataError, match="CHANNELS inside an End Site"):
        read_bvh(path)


def test_cmu_take_is_read_on_its_subjects_skeleton(tmp_path: Path, capsys) -> None:
    """Before: a CMU take ``13_29.amc`` with only subject 14's ``14.asf`` beside it was read
    on 14's bones without a word; with ``13.asf`` and ``14.asf`` both there it was refused
    ("2 .asf files beside it and none named for its actor"), though 13.asf is named for it."""
    (tmp_path / "14.asf").write_text(_ASF.replace("length 0.3", "length 0.5"))
    amc = tmp_path / "13_29.amc"
    amc.write_text(_amc("lclavicle 0 0 0\nlhumerus 0 0 0\nlradius 0\n"))
    refused(["describe", str(amc)], tmp_path, capsys, "13_29.amc", "no 13.asf", "14.asf")
    (tmp_path / "13.asf").write_text(_ASF)
    # 13.asf's humerus is 0.3 m (14.asf's 0.5 m): the elbow 0.3 m below the shoulder
    np.testing.assert_allclose(
        load_clip(amc).positions[0, JOINT_INDEX["left_elbow"]], [0.2, 0.7, 0.0]
    )
