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
