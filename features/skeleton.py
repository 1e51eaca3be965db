"""The canonical skeleton: the 33 BlazePose landmarks, named as MediaPipe's ``PoseLandmark``.

Positions are metres in a right-handed frame with y up (gravity along -y). Every reader maps
its source onto these names; a landmark a source lacks stays NaN.
"""

from __future__ import annotations

BLAZEPOSE_33: tuple[str, ...] = (
    "nose",
    "left_eye_inner",
    "left_eye",
    "left_eye_outer",
    "right_eye_inner",
    "right_eye",
    "right_eye_outer",
    "left_ear",
    "right_ear",
    "mouth_left",
    "mouth_right",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_pinky",
    "right_pinky",
    "left_index",
    "right_index",
    "left_thumb",
    "right_thumb",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
    "left_heel",
    "right_heel",
    "left_foot_index",
    "right_foot_index",
)

CANONICAL_SKELETON = "blazepose33"
JOINT_INDEX: dict[str, int] = {name: i for i, name in enumerate(BLAZEPOSE_33)}

# Skeleton names a pose file may declare. Readers convert to the canonical joint set, so the
# name records where the data came from; joints the source lacks are NaN.
KNOWN_SKELETONS: frozenset[str] = frozenset(
    {
        CANONICAL_SKELETON,
        "kinect_v2",
        "uiprmd_kinect",
        "uiprmd_vicon",
        "asf_amc",
        "bvh",
        "coco17",
    }
)

# Kinect v2's 25 joints as its SDK names them (``JointType``). Its camera space is already
# the canonical frame: metres, right-handed, y up; ``...Left`` is the person's left.
KINECT_V2_JOINTS: tuple[str, ...] = (
    "SpineBase", "SpineMid", "Neck", "Head",
    "ShoulderLeft", "ElbowLeft", "WristLeft", "HandLeft",
    "ShoulderRight", "ElbowRight", "WristRight", "HandRight",
    "HipLeft", "KneeLeft", "AnkleLeft", "FootLeft",
    "HipRight", "KneeRight", "AnkleRight", "FootRight",
    "SpineShoulder", "HandTipLeft", "ThumbLeft", "HandTipRight", "ThumbRight",
)  # fmt: skip

# BlazePose joint -> Kinect v2 joint. Kinect's Head is the skull's centre (no face landmark),
# HandLeft the middle of the hand and HandTip/Thumb the finger tips (not BlazePose's knuckles):
# those BlazePose joints stay NaN. FootLeft is the front of the foot, as UI-PRMD's toes.
KINECT_V2_TO_BLAZEPOSE: dict[str, str] = {
    f"{side}_{part}": f"{kinect}{side.capitalize()}"
    for side in ("left", "right")
    for part, kinect in (
        ("shoulder", "Shoulder"),
        ("elbow", "Elbow"),
        ("wrist", "Wrist"),
        ("hip", "Hip"),
        ("knee", "Knee"),
        ("ankle", "Ankle"),
        ("foot_index", "Foot"),
    )
}

# The declared joint maps of the skeletons whose pose files name their own joints (any other
# skeleton's file names BlazePose joints): the skeleton's joints, and BlazePose joint -> its
# joint. COCO-17's keypoint names are BlazePose's own.
SKELETON_JOINTS: dict[str, tuple[tuple[str, ...], dict[str, str]]] = {
    "kinect_v2": (KINECT_V2_JOINTS, KINECT_V2_TO_BLAZEPOSE),
}
