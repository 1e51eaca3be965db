"""Readers for motion capture formats, each converting to the canonical skeleton.

Every reader returns a :class:`features.poses.PoseSequence` on the 33 BlazePose joints
(metres, right-handed, y up, NaN where the source has no such joint) and raises
:class:`features.errors.DataError` naming the file for malformed or truncated input.

- :mod:`features.readers.uiprmd`: UI-PRMD Kinect (forward kinematics) and Vicon (markers)
- :mod:`features.readers.asfamc`: Acclaim ASF/AMC (HDM05, CMU)
- :mod:`features.readers.bvh`: Biovision BVH
"""

from __future__ import annotations

from .asfamc import read_amc, read_asf, read_asf_amc
from .bvh import read_bvh
from .uiprmd import read_uiprmd_kinect, read_uiprmd_vicon

__all__ = [
    "read_amc",
    "read_asf",
    "read_asf_amc",
    "read_bvh",
    "read_uiprmd_kinect",
    "read_uiprmd_vicon",
]
