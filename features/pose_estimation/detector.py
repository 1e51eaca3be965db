"""BlazePose person detector: input letterbox, SSD anchors, box decoding, weighted NMS.

Mirrors MediaPipe 0.10.21's ``pose_detection_cpu`` graph: the whole frame is letterboxed
(zero border) into 224 x 224 RGB scaled to [-1, 1]; the model gives 2254 anchor-relative
boxes with 4 keypoints each (0: hip centre, 1: a point whose distance from the hip centre
sets the body's size and whose direction sets its rotation, 2: shoulder centre, 3: upper-body
size point) and a score logit; scores are clipped to [-100, 100] and passed through a sigmoid,
kept from 0.5, and overlapping boxes (IoU > 0.3) merged by a score-weighted average.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

INPUT_SIZE = 224
NUM_ANCHORS = 2254
NUM_KEYPOINTS = 4
MIN_SUPPRESSION_IOU = 0.3
SCORE_CLIP = 100.0


@dataclass(frozen=True)
class Detection:
    """One detected person, in image pixels.

    box: ``(4,)`` xmin, ymin, xmax, ymax; keypoints: ``(4, 2)`` x, y; score in [0, 1].
    """

    box: np.ndarray
    keypoints: np.ndarray
    score: float


@lru_cache(maxsize=1)
def anchors() -> np.ndarray:
    """SSD anchor centres ``(2254, 2)`` (x, y) in [0, 1], in the model's output order.

    MediaPipe's SsdAnchorsCalculator with 5 layers, strides 8, 16, 32, 32, 32, aspect ratio 1
    plus one interpolated anchor per scale, ``fixed_anchor_size`` (all widths/heights 1):
    consecutive layers with the same stride share one grid, 2 anchors per cell per layer.
    """
    strides = [8, 16, 32, 32, 32]
    out = []
    layer = 0
    while layer < len(strides):
        last = layer
        while last < len(strides) and strides[last] == strides[layer]:
            last += 1
        per_cell = 2 * (last - layer)
        size = int(np.ceil(INPUT_SIZE / strides[layer]))
        ys, xs = np.meshgrid(np.arange(size), np.arange(size), indexing="ij")
        centres = np.stack([(xs + 0.5) / size, (ys + 0.5) / size], axis=-1).reshape(-1, 2)
        out.append(np.repeat(centres, per_cell, axis=0))
        layer = last
    result = np.concatenate(out).astype(np.float64)
    assert result.shape == (NUM_ANCHORS, 2)
    return result


def letterbox(rgb: np.ndarray) -> tuple[np.ndarray, float, float, float]:
    """Detector input ``(1, 224, 224, 3)`` float32 in [-1, 1] from an RGB uint8 frame.

    Returns the tensor and the square's side and offsets (in pixels): an image point (x, y) is
    at ((x + off_x) / side, (y + off_y) / side) in the model's normalised coordinates.
    The centred square is sampled with MediaPipe's own bilinear sampling (zero border), see
    :func:`features.pose_estimation.landmarks.warp_rect`.
    """
    from .landmarks import warp_rect

    h, w = rgb.shape[:2]
    side = float(max(w, h))
    off_x, off_y = (side - w) / 2.0, (side - h) / 2.0
    box = cv2.boxPoints(((w / 2.0, h / 2.0), (side, side), 0.0))
    crop, _ = warp_rect(rgb, box, INPUT_SIZE, cv2.BORDER_CONSTANT)
    tensor = crop.astype(np.float32) * np.float32(2.0 / 255.0) - np.float32(1.0)
    return tensor[None], side, off_x, off_y


ZOOM = 2
"""How much closer the first :func:`tiles` look than the whole frame: the detector sees the
frame shrunk to 224 pixels on its longer side, where a small person's face is a few pixels (a
person a quarter of a 1920x1080 frame's height is not found); a tile half the frame's longer
side shows them twice as large."""

FINER_ZOOM = 4
"""How much closer the finer tiles look, searched when the first find nobody: the detector
finds a person whose height is at least some 0.25-0.3 of its 224-pixel input (measured: 44
pictures of people shrunk into a 224-pixel square, found 12-13 at 32 pixels tall, 26-33 at 48,
37-39 at 56, 42-43 at 80), so tiles of half the longer side reach people down to some 0.2 of
a 4:3 frame's height, tiles of a quarter down to some 0.1."""

MIN_TILE = INPUT_SIZE // 2
"""The smallest tile searched (pixels): the detector's input shows it enlarged, and beyond
twice it would show no detail the frame holds, only larger blur."""


def tiles(width: int, height: int, zoom: int = ZOOM) -> list[tuple[int, int, int, int]]:
    """Windows ``(x, y, w, h)`` of a ``width`` x ``height`` frame, each ``zoom`` times
    smaller than its longer side (at most the frame's own width or height), overlapping by
    half so that a person on one's edge lies whole in the next: at :data:`ZOOM`, 6 over a
    16:9 or 4:3 frame, at :data:`FINER_ZOOM` 28 over 16:9 and 35 over 4:3. None over a frame
    no larger than the detector's input (:data:`INPUT_SIZE` on its longer side): the
    detector sees every pixel of it already; none either where a tile would be smaller than
    :data:`MIN_TILE`."""
    if max(width, height) <= INPUT_SIZE:
        return []
    side = int(np.ceil(max(width, height) / zoom))
    if side < MIN_TILE:
        return []
    w, h = min(width, side), min(height, side)
    step = side / 2.0
    xs = np.linspace(0, width - w, int(np.ceil((width - w) / step)) + 1).round().astype(int)
    ys = np.linspace(0, height - h, int(np.ceil((height - h) / step)) + 1).round().astype(int)
    return [(int(x), int(y), w, h) for y in ys for x in xs]


def window_around(width: int, height: int, at: np.ndarray, zoom: int) -> tuple[int, int, int]:
    """The square window ``(x, y, side)`` of a ``width`` x ``height`` frame the size of its
    tiles at ``zoom`` (:func:`tiles`; at most the frame's shorter side), centred on ``at``
    (x, y) and moved in to lie within the frame."""
    side = min(int(np.ceil(max(width, height) / zoom)), width, height)
    x = int(np.clip(round(float(at[0]) - side / 2), 0, width - side))
    y = int(np.clip(round(float(at[1]) - side / 2), 0, height - side))
    return x, y, side


def same_person(found: Detection, others: list[Detection]) -> list[Detection]:
    """Those of ``others`` that are ``found`` seen again: their boxes overlap its box by more
    than :data:`MIN_SUPPRESSION_IOU`, as :func:`distinct` and the detector's own merging tell
    one person seen twice."""
    if not others:
        return []
    overlap = _iou(found.box, np.array([d.box for d in others])) > MIN_SUPPRESSION_IOU
    return [d for d, same in zip(others, overlap, strict=True) if same]


def shifted(found: list[Detection], x: int, y: int) -> list[Detection]:
    """Detections in a window at ``(x, y)`` of a frame, in the frame's pixels."""
    at = np.array([x, y], dtype=float)
    return [Detection(d.box + np.tile(at, 2), d.keypoints + at, d.score) for d in found]


def distinct(found: list[Detection]) -> list[Detection]:
    """Best first, each person once: a detection whose box overlaps a surer one's by more
    than :data:`MIN_SUPPRESSION_IOU` (the same person seen in two overlapping tiles) left
    out."""
    kept: list[Detection] = []
    for d in sorted(found, key=lambda d: -d.score):
        boxes = np.array([k.box for k in kept]).reshape(-1, 4)
        if not (_iou(d.box, boxes) > MIN_SUPPRESSION_IOU).any():
            kept.append(d)
    return kept


def _iou(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """IoU of ``box`` (4,) with ``boxes`` (n, 4), all xmin, ymin, xmax, ymax."""
    ix = np.clip(np.minimum(box[2], boxes[:, 2]) - np.maximum(box[0], boxes[:, 0]), 0, None)
    iy = np.clip(np.minimum(box[3], boxes[:, 3]) - np.maximum(box[1], boxes[:, 1]), 0, None)
    inter = ix * iy
    area = (box[2] - box[0]) * (box[3] - box[1])
    areas = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    union = area + areas - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)


def decode(
    regressors: np.ndarray, score_logits: np.ndarray, min_score: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Anchor-decoded candidates above ``min_score``, best first.

    regressors: ``(2254, 12)``; score_logits: ``(2254,)``. Returns boxes ``(n, 4)`` and
    keypoints ``(n, 4, 2)`` in normalised letterbox coordinates, scores ``(n,)``.
    """
    logits = np.clip(score_logits.astype(np.float64), -SCORE_CLIP, SCORE_CLIP)
    scores = 1.0 / (1.0 + np.exp(-logits))
    idx = np.flatnonzero(scores >= min_score)
    if idx.size == 0:
        return np.zeros((0, 4)), np.zeros((0, NUM_KEYPOINTS, 2)), np.zeros(0)
    idx = idx[np.argsort(-scores[idx], kind="stable")]
    raw = regressors[idx].astype(np.float64) / INPUT_SIZE
    anc = anchors()[idx]
    cx = raw[:, 0] + anc[:, 0]
    cy = raw[:, 1] + anc[:, 1]
    half_w, half_h = raw[:, 2] / 2.0, raw[:, 3] / 2.0
    boxes = np.stack([cx - half_w, cy - half_h, cx + half_w, cy + half_h], axis=1)
    keypoints = raw[:, 4:].reshape(-1, NUM_KEYPOINTS, 2) + anc[:, None, :]
    return boxes, keypoints, scores[idx]


def weighted_nms(
    boxes: np.ndarray, keypoints: np.ndarray, scores: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """MediaPipe's WEIGHTED non-maximum suppression on candidates sorted best first.

    The best remaining candidate absorbs every remaining one with IoU > 0.3 (itself included);
    its box and keypoints become their score-weighted mean, its score stays its own.
    """
    out: list[tuple[np.ndarray, np.ndarray, float]] = []
    remaining = np.arange(len(scores))
    while remaining.size:
        best = remaining[0]
        overlap = _iou(boxes[best], boxes[remaining]) > MIN_SUPPRESSION_IOU
        group = remaining[overlap]
        if group.size:
            weights = scores[group][:, None]
            box = (boxes[group] * weights).sum(0) / weights.sum()
            kps = (keypoints[group] * weights[:, :, None]).sum(0) / weights.sum()
        else:  # numerically possible only for a degenerate (zero-area) box
            box, kps = boxes[best], keypoints[best]
        out.append((box, kps, float(scores[best])))
        if group.size == 0:
            break
        remaining = remaining[~overlap]
    return out


def postprocess(
    regressors: np.ndarray,
    score_logits: np.ndarray,
    side: float,
    off_x: float,
    off_y: float,
    min_score: float = 0.5,
) -> list[Detection]:
    """Model outputs -> detections in image pixels, best first."""
    boxes, kps, scores = decode(
        regressors.reshape(NUM_ANCHORS, 12), score_logits.reshape(-1), min_score
    )
    offset = np.array([off_x, off_y])
    result = []
    for box, keypoints, score in weighted_nms(boxes, kps, scores):
        box_px = box * side - np.concatenate([offset, offset])
        result.append(Detection(box=box_px, keypoints=keypoints * side - offset, score=score))
    return result
