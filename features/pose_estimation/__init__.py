"""Video to 3D pose: MediaPipe BlazePose (full) on onnxruntime + OpenCV, no MediaPipe needed.

- :func:`estimate_poses` (video file -> canonical :class:`~features.poses.PoseSequence`),
  :func:`estimate_video` (the same plus image landmarks and missing frames),
  :func:`stream_poses` (webcam index / stream URL / path -> per-frame results),
- :class:`PoseEstimator` for frame-by-frame use on RGB arrays.

Models: ``models/`` (converted from the ``mediapipe==0.10.21`` wheel, Apache-2.0; see
``models/PROVENANCE.md``).
"""

from .model import model_version
from .tracker import FramePose, PoseEstimator
from .video import (
    StreamFrame,
    VideoInfo,
    VideoPoses,
    estimate_poses,
    estimate_video,
    iter_frames,
    open_video,
    served_file_rate,
    stream_poses,
)

__all__ = [
    "FramePose",
    "PoseEstimator",
    "StreamFrame",
    "VideoInfo",
    "VideoPoses",
    "estimate_poses",
    "estimate_video",
    "iter_frames",
    "model_version",
    "open_video",
    "served_file_rate",
    "stream_poses",
]
