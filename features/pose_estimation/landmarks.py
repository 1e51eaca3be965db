"""BlazePose landmark model: region of interest, crop, decoding, heatmap refinement, projection.

Mirrors MediaPipe 0.10.21's ``pose_landmark_by_roi_cpu`` graph and its ROI calculators:

- ROI from two points (the detector's keypoints 0 and 1, or the landmark model's auxiliary
  landmarks 33 and 34 when tracking): centre = point 0; side = 2 |p1 - p0| x 1.25 (square);
  rotation = pi/2 - atan2(-(y1 - y0), x1 - x0), so the body's hip->head axis points up in the
  crop.
- Crop: the rotated square is warped to 256 x 256 with MediaPipe's own sampling (see
  :func:`warp_rect`), border pixels replicated as MediaPipe does (a black border changed
  depth by 65-95 px here), RGB in [0, 1].
- Output: 39 landmarks x (x, y, z, visibility logit, presence logit) in crop pixels; x, y
  refined from the 64 x 64 heatmap (sigmoid-weighted mean over a 9 x 9 window when its peak is
  >= 0.5); world landmarks 39 x 3 in metres, rotated back by the ROI's rotation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

INPUT_SIZE = 256
NUM_LANDMARKS = 39
NUM_POSE = 33
# 9, not the 7 of the graph text in MediaPipe's repository: with 9 the landmarks match
# MediaPipe 0.10.21's own output to ~0.01 px on the reference images (7 leaves 0.4-0.6 px).
HEATMAP_KERNEL = 9
MIN_HEATMAP_CONFIDENCE = 0.5
ROI_SCALE = 1.25


@dataclass(frozen=True)
class Roi:
    """A rotated square in image pixels: centre, side, rotation (radians, MediaPipe's sign)."""

    cx: float
    cy: float
    size: float
    rotation: float


@dataclass(frozen=True)
class RawLandmarks:
    """Landmark model output mapped to the image.

    image: ``(39, 5)`` x px, y px, z px (image-width scale, MediaPipe's normalised z times the
    width), visibility, presence (both probabilities); world: ``(39, 3)`` metres in MediaPipe's
    world frame (x right, y down, z away from the camera, origin at the hip centre);
    flag: probability that a person is in the crop.
    """

    image: np.ndarray
    world: np.ndarray
    flag: float


def _normalize_radians(angle: float) -> float:
    return angle - 2.0 * math.pi * math.floor((angle + math.pi) / (2.0 * math.pi))


def roi_from_points(p0: np.ndarray, p1: np.ndarray) -> Roi:
    """The landmark model's ROI from the centre point ``p0`` and the scale point ``p1`` (px)."""
    dx, dy = float(p1[0] - p0[0]), float(p1[1] - p0[1])
    rotation = _normalize_radians(math.pi / 2.0 - math.atan2(-dy, dx))
    size = 2.0 * math.hypot(dx, dy) * ROI_SCALE
    return Roi(float(p0[0]), float(p0[1]), size, rotation)


@lru_cache(maxsize=4)
def _axis(size: int) -> np.ndarray:
    return np.arange(size, dtype=np.float64)


def warp_rect(
    image: np.ndarray, box: np.ndarray, size: int, border: int
) -> tuple[np.ndarray, np.ndarray]:
    """Sample the quadrilateral ``box`` (4 x 2 corners in OpenCV ``boxPoints`` order) of an
    image into a ``size x size`` patch, exactly as MediaPipe 0.10.21 does on CPU.

    MediaPipe maps the corners with ``getPerspectiveTransform`` and ``warpPerspective``
    (bilinear) of the OpenCV it bundles, whose sampling positions are rounded to 1/32 pixel
    and whose weights are those of the rounded position. Newer OpenCV warps sample at the
    exact position; the difference moves the detector's keypoints by ~0.3 px and the
    landmarks by ~1 px, so the classic sampling is reproduced here: positions computed and
    rounded in numpy, then ``cv2.remap`` with fixed-point maps (which interpolates with the
    classic 1/32 weight table). Returns the uint8 patch and the 3 x 3 image->patch matrix.
    """
    dst = np.array([[0, size], [0, 0], [size, 0], [size, size]], dtype=np.float32)
    matrix = cv2.getPerspectiveTransform(box.astype(np.float32), dst)
    inv = np.linalg.inv(matrix)
    inv = inv / inv[2, 2]
    u = _axis(size)
    if abs(inv[2, 0]) < 1e-12 and abs(inv[2, 1]) < 1e-12:
        # A rotated rectangle is an affine map: rows and columns separate (scaling by 32 is
        # exact in floating point, so this rounds like the per-pixel form).
        xs = np.rint(
            (inv[0, 0] * 32.0) * u[None, :] + (inv[0, 1] * 32.0 * u + inv[0, 2] * 32.0)[:, None]
        )
        ys = np.rint(
            (inv[1, 0] * 32.0) * u[None, :] + (inv[1, 1] * 32.0 * u + inv[1, 2] * 32.0)[:, None]
        )
    else:
        uu, vv = u[None, :], u[:, None]
        scale = 32.0 / (inv[2, 0] * uu + inv[2, 1] * vv + inv[2, 2])
        xs = np.rint((inv[0, 0] * uu + inv[0, 1] * vv + inv[0, 2]) * scale)
        ys = np.rint((inv[1, 0] * uu + inv[1, 1] * vv + inv[1, 2]) * scale)
    # cvRound (half to even) as saturate_cast<int> does; int16 maps hold +-32767 px.
    xs = np.clip(xs, -32767 * 32, 32767 * 32).astype(np.int32)
    ys = np.clip(ys, -32767 * 32, 32767 * 32).astype(np.int32)
    map1 = np.stack([xs >> 5, ys >> 5], axis=-1).astype(np.int16)
    map2 = ((ys & 31) * 32 + (xs & 31)).astype(np.uint16)
    patch = cv2.remap(image, map1, map2, cv2.INTER_LINEAR, borderMode=border, borderValue=0)
    return patch, matrix


def crop(rgb: np.ndarray, roi: Roi) -> tuple[np.ndarray, np.ndarray]:
    """Landmark model input ``(1, 256, 256, 3)`` float32 in [0, 1] and the 3 x 3 matrix.

    The rotated square is sampled as MediaPipe does (:func:`warp_rect`), border pixels
    replicated; the warp runs on uint8 and the result is scaled, as in MediaPipe.
    """
    box = cv2.boxPoints(((roi.cx, roi.cy), (roi.size, roi.size), math.degrees(roi.rotation)))
    out, matrix = warp_rect(rgb, box, INPUT_SIZE, cv2.BORDER_REPLICATE)
    tensor = out.astype(np.float32) * np.float32(1.0 / 255.0)
    return tensor[None], matrix


def refine_from_heatmap(xy: np.ndarray, heatmap: np.ndarray) -> np.ndarray:
    """Heatmap refinement of crop-normalised ``xy`` ``(39, 2)``; heatmap ``(64, 64, 39)`` logits.

    For each landmark, the sigmoid of the heatmap over a 9 x 9 window around the landmark's
    cell (cut at the edges) gives weights; if the window's peak is >= 0.5 the landmark moves to
    the weighted mean cell index / 64. Landmarks whose cell is outside the map stay as they are.
    """
    hm_h, hm_w, n = heatmap.shape
    # C++ float->int conversion truncates toward zero, which MediaPipe relies on.
    cols = np.trunc(xy[:, 0] * hm_w).astype(np.int64)
    rows = np.trunc(xy[:, 1] * hm_h).astype(np.int64)
    inside = (cols >= 0) & (cols < hm_w) & (rows >= 0) & (rows < hm_h)
    half = (HEATMAP_KERNEL - 1) // 2
    offs = np.arange(-half, half + 1)
    rr = rows[:, None] + offs  # (n, k)
    cc = cols[:, None] + offs
    valid = ((rr >= 0) & (rr < hm_h))[:, :, None] & ((cc >= 0) & (cc < hm_w))[:, None, :]
    vals = heatmap[
        np.clip(rr, 0, hm_h - 1)[:, :, None],
        np.clip(cc, 0, hm_w - 1)[:, None, :],
        np.arange(n)[:, None, None],
    ].astype(np.float64)
    conf = np.where(valid, 1.0 / (1.0 + np.exp(-vals)), 0.0)  # (n, k, k)
    total = conf.sum(axis=(1, 2))
    peak = conf.max(axis=(1, 2))
    w_col = (conf * cc[:, None, :]).sum(axis=(1, 2))
    w_row = (conf * rr[:, :, None]).sum(axis=(1, 2))
    ok = inside & (peak >= MIN_HEATMAP_CONFIDENCE) & (total > 0)
    safe = np.where(total > 0, total, 1.0)
    out = xy.copy()
    out[:, 0] = np.where(ok, w_col / hm_w / safe, xy[:, 0])
    out[:, 1] = np.where(ok, w_row / hm_h / safe, xy[:, 1])
    return out


def decode(
    landmarks: np.ndarray, flag: np.ndarray, heatmap: np.ndarray, world: np.ndarray, roi: Roi
) -> RawLandmarks:
    """Landmark model outputs -> :class:`RawLandmarks` in the image.

    landmarks ``(1, 195)``, flag ``(1, 1)``, heatmap ``(1, 64, 64, 39)``, world ``(1, 117)``.
    """
    raw = landmarks.reshape(NUM_LANDMARKS, 5).astype(np.float64)
    xy = refine_from_heatmap(raw[:, :2] / INPUT_SIZE, heatmap[0])
    cos_r, sin_r = math.cos(roi.rotation), math.sin(roi.rotation)
    u, v = xy[:, 0] - 0.5, xy[:, 1] - 0.5
    image = np.empty((NUM_LANDMARKS, 5))
    image[:, 0] = (cos_r * u - sin_r * v) * roi.size + roi.cx
    image[:, 1] = (sin_r * u + cos_r * v) * roi.size + roi.cy
    image[:, 2] = raw[:, 2] / INPUT_SIZE * roi.size
    image[:, 3:5] = 1.0 / (1.0 + np.exp(-raw[:, 3:5]))
    w = world.reshape(NUM_LANDMARKS, 3).astype(np.float64)
    world_rot = np.empty_like(w)
    world_rot[:, 0] = cos_r * w[:, 0] - sin_r * w[:, 1]
    world_rot[:, 1] = sin_r * w[:, 0] + cos_r * w[:, 1]
    world_rot[:, 2] = w[:, 2]
    return RawLandmarks(image=image, world=world_rot, flag=float(np.asarray(flag).reshape(-1)[0]))
