"""BlazePose on onnxruntime: geometry pieces by hand, images and video against real data.

The image reference (tests/fixtures/mediapipe_pose_reference.json) was made by MediaPipe
0.10.21's own ``solutions.pose`` (tools/make_mediapipe_reference.py, static image mode, full
model) in a separate environment; nothing here compares the code with its own output.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from features.errors import DataError
from features.pose_estimation import (
    PoseEstimator,
    estimate_poses,
    estimate_video,
    iter_frames,
    stream_poses,
)
from features.pose_estimation import detector as det
from features.pose_estimation import landmarks as lmk
from features.pose_estimation.smoothing import OneEuroFilter, OneEuroParams
from features.skeleton import JOINT_INDEX
from tests.empty_scene import empty_scene

FIXTURES = Path(__file__).parent / "fixtures"
REFERENCE = json.loads((FIXTURES / "mediapipe_pose_reference.json").read_text())


@pytest.fixture(scope="module")
def still_estimator() -> PoseEstimator:
    """Detector on every frame, no smoothing: MediaPipe's static image mode."""
    return PoseEstimator(tracking=False, smoothing=False)


def _rgb(path: Path) -> np.ndarray:
    return cv2.cvtColor(cv2.imread(str(path)), cv2.COLOR_BGR2RGB)


# --- pieces worked out by hand ---------------------------------------------------------------


def test_anchor_grid_matches_ssd_layout() -> None:
    a = det.anchors()
    assert a.shape == (2254, 2)
    # Stride 8: 28 x 28 cells, 2 anchors per cell; first cell centre (0.5/28, 0.5/28).
    np.testing.assert_allclose(a[0], [0.5 / 28, 0.5 / 28])
    np.testing.assert_allclose(a[1], a[0])
    # Second cell of the first row.
    np.testing.assert_allclose(a[2], [1.5 / 28, 0.5 / 28])
    # Stride 16 starts after 28*28*2 = 1568 anchors.
    np.testing.assert_allclose(a[1568], [0.5 / 14, 0.5 / 14])
    # Strides 32 (three layers share a 7 x 7 grid, 6 anchors per cell) end at cell (6, 6).
    np.testing.assert_allclose(a[-1], [6.5 / 7, 6.5 / 7])
    np.testing.assert_allclose(a[1568 + 392], [0.5 / 7, 0.5 / 7])


def test_roi_of_upright_person() -> None:
    # Scale point straight above the hip centre: no rotation; side = 2 * 100 * 1.25.
    roi = lmk.roi_from_points(np.array([100.0, 300.0]), np.array([100.0, 200.0]))
    assert (roi.cx, roi.cy) == (100.0, 300.0)
    assert roi.size == pytest.approx(250.0)
    assert roi.rotation == pytest.approx(0.0, abs=1e-12)
    # Lying with the head to the image's right: the crop's up direction (0, -1) must map to
    # the image's +x; a crop offset (u, v) maps to (cos r u - sin r v, sin r u + cos r v),
    # so up -> (sin r, -cos r) = (1, 0) gives r = +90 degrees.
    roi = lmk.roi_from_points(np.array([100.0, 300.0]), np.array([160.0, 300.0]))
    assert roi.rotation == pytest.approx(math.pi / 2)
    assert roi.size == pytest.approx(150.0)
    # And the crop shows it upright: a bright patch right of the centre ends up at the top.
    img = np.zeros((600, 400, 3), np.uint8)
    img[290:311, 150:171] = 255  # 60 px right of (100, 300)
    tensor, _ = lmk.crop(img, roi)
    rows, cols = np.nonzero(tensor[0, :, :, 0] > 0.5)
    # 60 px of a 150-px crop = 102.4 crop px above the centre (128, 128).
    assert abs(rows.mean() - (128 - 102.4)) < 2 and abs(cols.mean() - 128) < 2


def test_crop_maps_roi_corners_and_replicates_border() -> None:
    img = np.zeros((100, 200, 3), np.uint8)
    img[:, 100:] = 200  # right half bright
    roi = lmk.Roi(cx=100.0, cy=50.0, size=80.0, rotation=0.0)
    tensor, matrix = lmk.crop(img, roi)
    # The ROI's top-left corner (60, 10) lands on (0, 0), its bottom-right (140, 90) on (256, 256).
    np.testing.assert_allclose(matrix @ [60, 10, 1], [0, 0, 1], atol=1e-4)
    np.testing.assert_allclose(matrix @ [140, 90, 1], [256, 256, 1], atol=1e-4)
    assert tensor.shape == (1, 256, 256, 3)
    assert tensor[0, 128, 10, 0] == 0.0 and tensor[0, 128, 245, 0] == pytest.approx(200 / 255)
    # A ROI reaching past the image's right edge repeats the edge pixels (not black).
    tensor, _ = lmk.crop(img, lmk.Roi(cx=190.0, cy=50.0, size=80.0, rotation=0.0))
    assert tensor[0, 128, 250, 0] == pytest.approx(200 / 255)


def test_weighted_nms_averages_overlapping_boxes() -> None:
    boxes = np.array([[0.0, 0.0, 1.0, 1.0], [0.1, 0.0, 1.1, 1.0], [5.0, 5.0, 6.0, 6.0]])
    kps = np.zeros((3, 4, 2))
    kps[1] += 1.0
    scores = np.array([0.9, 0.6, 0.55])
    out = det.weighted_nms(boxes, kps, scores)
    assert len(out) == 2
    box, kp, score = out[0]
    # Score-weighted mean of the first two: xmin = 0.6 * 0.1 / 1.5 = 0.04.
    np.testing.assert_allclose(box, [0.04, 0.0, 1.04, 1.0])
    np.testing.assert_allclose(kp, np.full((4, 2), 0.4))
    assert score == 0.9
    np.testing.assert_allclose(out[1][0], boxes[2])


def test_one_euro_with_zero_beta_is_the_textbook_exponential_filter() -> None:
    f = OneEuroFilter(OneEuroParams(min_cutoff=1.0, beta=0.0), frequency=30.0)
    alpha = 1.0 / (1.0 + 30.0 / (2 * math.pi * 1.0))  # = 0.1731...
    out = [f.apply(i / 30.0, np.array([v]))[0] for i, v in enumerate([0.0, 1.0, 1.0])]
    assert out[0] == 0.0
    assert out[1] == pytest.approx(alpha)
    assert out[2] == pytest.approx(alpha + (1 - alpha) * alpha)


# --- real images against MediaPipe 0.10.21 ---------------------------------------------------


@pytest.mark.parametrize("name", ["basketball1.png", "basketball2.png", "messi5.jpg"])
def test_image_landmarks_match_mediapipe(
    shared_data: Path, still_estimator: PoseEstimator, name: str
) -> None:
    ref = REFERENCE["images"][name]
    img = shared_data / "media" / name
    pose = still_estimator.process(_rgb(img))
    still_estimator.reset()
    assert pose.person
    expected = np.array(ref["image_landmarks_px"])
    diff = np.linalg.norm(pose.image[:, :2] - expected[:, :2], axis=1)
    # The issue asks for a mean difference <= 2 px; the pipeline reproduces MediaPipe's
    # sampling and refinement, so it is held to far less (measured ~0.01 px).
    assert diff.mean() <= 0.25, f"mean landmark difference {diff.mean():.3f} px"
    assert diff.max() <= 1.0, f"max landmark difference {diff.max():.3f} px"
    assert np.abs(pose.image[:, 2] - expected[:, 2]).mean() < 1.0  # depth, px
    assert np.abs(pose.image[:, 3] - expected[:, 3]).max() < 0.01  # visibility
    # World landmarks: MediaPipe's frame (x right, y down, z away) -> canonical (x, -y, -z).
    world_mp = np.array(ref["world_landmarks_m"])
    np.testing.assert_allclose(pose.world, world_mp * [1, -1, -1], atol=0.01)


def test_basketball1_person_on_the_left_faces_camera(
    shared_data: Path, still_estimator: PoseEstimator
) -> None:
    pose = still_estimator.process(_rgb(shared_data / "media" / "basketball1.png"))
    still_estimator.reset()
    # The fully visible player stands in the left part of the 640-px frame.
    assert np.all(pose.image[:, 0] < 320)
    w = pose.world
    ls, rs = w[JOINT_INDEX["left_shoulder"]], w[JOINT_INDEX["right_shoulder"]]
    lh, rh = w[JOINT_INDEX["left_hip"]], w[JOINT_INDEX["right_hip"]]
    nose = w[JOINT_INDEX["nose"]]
    # He faces the camera: his left shoulder is on the image's right.
    assert (
        pose.image[JOINT_INDEX["left_shoulder"], 0] > pose.image[JOINT_INDEX["right_shoulder"], 0]
    )
    up = (ls + rs) / 2 - (lh + rh) / 2
    assert up[1] > 0.8 * np.linalg.norm(up)  # y is up
    forward = np.cross(ls - rs, up)
    # Right-handed frame: (left - right) x up points out of the chest, i.e. toward the camera
    # (+z) for a person facing it, and the nose lies on that side of the shoulders.
    assert forward[2] > 0
    assert np.dot(forward, nose - (ls + rs) / 2) > 0


# --- real video ------------------------------------------------------------------------------


def test_a_scene_with_nobody_in_it_has_no_person(tmp_path: Path) -> None:
    """A still scene with nobody in it (lossless): every frame missing, NaN, none taken for
    a person, though each is searched again in tiles."""
    vp = estimate_video(empty_scene(tmp_path / "empty.mkv", 8), progress_bar=False)
    assert vp.sequence.n_frames == 8
    assert vp.missing == tuple(range(8))
    assert np.isnan(vp.sequence.positions).all()
    assert vp.sequence.metadata["n_missing_frames"] == 8


def test_the_pedestrians_of_vtest_are_found_in_tiles(shared_data: Path) -> None:
    """vtest.avi's first frame (768 x 576), looked at: a man in dark clothes walking left
    across the road, head at about (660, 250) and feet at about (665, 315), another standing
    on the left, head at about (268, 230), a third far up the road (no larger than a tile
    shows well). The detector finds nobody in the whole frame shrunk to 224 pixels; in tiles
    of half the frame it finds the two nearer men, and the pose lands on the walker."""
    cap = cv2.VideoCapture(str(shared_data / "media" / "vtest.avi"))
    ok, bgr = cap.read()
    cap.release()
    assert ok
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    est = PoseEstimator()
    assert est.detect(rgb) == []
    heads = np.array([[660.0, 250.0], [268.0, 230.0]])
    found = est.detect_closer(rgb)
    boxes = np.array([d.box for d in found])
    assert len(found) == 2
    inside = (heads[:, None] >= boxes[None, :, :2]) & (heads[:, None] <= boxes[None, :, 2:])
    assert inside.all(axis=2).any(axis=1).all()  # each head in a box
    pose = est.process(rgb)
    assert pose.person
    hips = pose.image[[JOINT_INDEX["left_hip"], JOINT_INDEX["right_hip"]], :2].mean(axis=0)
    ankles = pose.image[[JOINT_INDEX["left_ankle"], JOINT_INDEX["right_ankle"]], :2]
    assert abs(hips[0] - 662) < 20 and 250 < hips[1] < 310
    np.testing.assert_allclose(ankles[:, 1], 315, atol=15)


def _knee_angles(positions: np.ndarray) -> np.ndarray:
    def angle(a: str, b: str, c: str) -> np.ndarray:
        u = positions[:, JOINT_INDEX[a]] - positions[:, JOINT_INDEX[b]]
        v = positions[:, JOINT_INDEX[c]] - positions[:, JOINT_INDEX[b]]
        cos = np.sum(u * v, 1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        return np.degrees(np.arccos(np.clip(cos, -1, 1)))

    left = angle("left_hip", "left_knee", "left_ankle")
    right = angle("right_hip", "right_knee", "right_ankle")
    return (left + right) / 2


def test_squat_knee_angle_dips_once_per_repetition(shared_data: Path) -> None:
    # Counted by eye from all 65 frames (5 fps): she squats three times; the bottoms are
    # around frames 8-13, 31-38 and 56-62; she is standing again by frames 18 and 42; the
    # clip ends half-way up from the third squat.
    seq = estimate_poses(
        shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4", progress=False
    )
    assert seq.fps == 5.0 and seq.n_frames == 65
    knee = _knee_angles(seq.positions)
    assert not np.isnan(knee).any()
    bent = knee < 120.0
    starts = np.flatnonzero(bent[1:] & ~bent[:-1]) + 1
    ends = np.flatnonzero(~bent[1:] & bent[:-1]) + 1
    assert len(starts) == 3
    bottoms = [int(np.argmin(np.where(np.arange(65) // 22 == k, knee, np.inf))) for k in range(3)]
    assert 6 <= bottoms[0] <= 14 and 29 <= bottoms[1] <= 39 and 54 <= bottoms[2] <= 63
    assert knee[18:26].min() > 150 and knee[42:52].min() > 150  # standing between squats
    assert len(ends) == 2  # recovered from the first two within the clip
    assert knee[:4].min() > 150  # standing at the start


def test_two_people_track_stays_on_one_person(shared_data: Path) -> None:
    for clip, frames in [
        ("jumping_jack_two_people_pexels8402086.mp4", 125),
        ("chair_squat_two_people_pexels4838146.mp4", 120),
    ]:
        vp = estimate_video(
            shared_data / "videos" / "edge" / clip, progress_bar=False, max_frames=frames
        )
        im = vp.image_landmarks
        hip = (im[:, JOINT_INDEX["left_hip"], :2] + im[:, JOINT_INDEX["right_hip"], :2]) / 2
        assert len(vp.missing) <= 2, clip
        steps = np.linalg.norm(np.diff(hip, axis=0), axis=1)
        # People stand ~1/3 of the frame apart; a switch would jump the hip centre that far.
        assert np.nanmax(steps) < 0.1 * vp.info.width, clip
        assert np.nanmax(hip[:, 0]) - np.nanmin(hip[:, 0]) < 0.2 * vp.info.width, clip


def test_legs_out_of_frame_are_missing_or_low_visibility(shared_data: Path) -> None:
    vp = estimate_video(
        shared_data / "videos" / "edge" / "jumping_jack_legs_cropped_pexels5034331.mp4",
        progress_bar=False,
        max_frames=45,
    )
    lower = [
        JOINT_INDEX[n]
        for n in (
            "left_ankle",
            "right_ankle",
            "left_heel",
            "right_heel",
            "left_foot_index",
            "right_foot_index",
        )
    ]
    assert not vp.missing
    # Feet and ankles are below the bottom edge in every frame: low visibility in the image
    # landmarks, missing in the pose sequence.
    assert vp.image_landmarks[:, lower, 3].max() < 0.5
    assert np.isnan(vp.sequence.positions[:, lower]).all()
    # The upper body is seen and kept.
    shoulders = [JOINT_INDEX["left_shoulder"], JOINT_INDEX["right_shoulder"]]
    assert not np.isnan(vp.sequence.positions[:, shoulders]).any()
    assert vp.sequence.confidence is not None
    assert vp.sequence.confidence[:, shoulders].min() > 0.9


def test_crop_following_a_walker_in_vtest_gives_a_walking_pose(shared_data: Path) -> None:
    # By eye: in the first frames a man in dark clothes walks left across the road at about
    # (660, 285), some 8-9 px per frame (10 fps). A 200 x 200 window moved with him.
    est = PoseEstimator(tracking=True, smoothing=True)
    hips, gait, upright, knees = [], [], [], []
    for i, rgb in enumerate(iter_frames(shared_data / "media" / "vtest.avi")):
        if i == 20:
            break
        x0 = 560 - round(8.5 * i)
        pose = est.process(np.ascontiguousarray(rgb[190:390, x0 : x0 + 200]), i / 10.0)
        assert pose.person, f"frame {i}: walker not found"
        im = pose.image
        y = {n: im[JOINT_INDEX[n], 1] for n in ("nose", "left_shoulder", "left_hip", "left_ankle")}
        upright.append(y["nose"] < y["left_shoulder"] < y["left_hip"] < y["left_ankle"])
        hips.append(x0 + (im[JOINT_INDEX["left_hip"], 0] + im[JOINT_INDEX["right_hip"], 0]) / 2)
        gait.append(im[JOINT_INDEX["left_ankle"], 0] - im[JOINT_INDEX["right_ankle"], 0])
        knees.append(_knee_angles(pose.world[None])[0])
    assert all(upright)
    assert hips[0] - hips[-1] > 100  # he walks left by ~170 px in 2 s
    # Steps: which ankle is ahead flips again and again.
    assert np.count_nonzero(np.diff(np.sign(gait)) != 0) >= 3
    assert min(knees) > 110  # walking, not crouching


def test_stream_poses_from_a_file_and_a_missing_camera(shared_data: Path) -> None:
    clip = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    got = list(stream_poses(clip, max_frames=4))
    assert [f.index for f in got] == [0, 1, 2, 3]
    assert [f.time_s for f in got] == [0.0, 0.2, 0.4, 0.6]  # 5 fps file: timed by its rate
    assert all(f.pose.person for f in got)
    assert got[0].rgb.shape == (1280, 720, 3)
    with pytest.raises(DataError, match="cannot open camera: none at this index"):
        next(iter(stream_poses(99)))


def test_a_streamed_frame_sees_what_extract_stores() -> None:
    """A 64 x 48 frame whose landmarks are all inside but the left ankle (x = 64: one pixel
    past the last column) and the right ankle (y = -1), and the left wrist inside it at a
    presence of 0.3 (the model judges it not in the picture): those three are missing in the
    world landmarks the stream gives, as :func:`estimate_video` stores them; the rest as the
    model gave them, at whatever visibility; the visibility is the image landmarks' fourth
    field."""
    from features.pose_estimation import StreamFrame
    from features.pose_estimation.tracker import FramePose

    image = np.zeros((33, 5))
    image[:, :2] = [10.0, 20.0]
    image[:, 3] = np.linspace(0.0, 1.0, 33)
    image[:, 4] = 0.5  # presence: in the picture (0.5 and above)
    image[JOINT_INDEX["left_ankle"], 0] = 64.0
    image[JOINT_INDEX["right_ankle"], 1] = -1.0
    image[JOINT_INDEX["left_wrist"], 4] = 0.3
    world = np.arange(99.0).reshape(33, 3)
    frame = StreamFrame(0, 0.0, FramePose(image, world, True, True, 1.0, None),
                        np.zeros((48, 64, 3), dtype=np.uint8))  # fmt: skip
    seen = frame.seen_world
    gone = [JOINT_INDEX["left_ankle"], JOINT_INDEX["right_ankle"], JOINT_INDEX["left_wrist"]]
    assert np.isnan(seen[gone]).all()
    kept = np.setdiff1d(np.arange(33), gone)
    np.testing.assert_array_equal(seen[kept], world[kept])
    np.testing.assert_array_equal(frame.visibility, np.linspace(0.0, 1.0, 33))
    assert np.isfinite(frame.pose.world).all()  # the model's output itself is kept
