"""Small people are found (hunt 48p).

A robot, or a physio's phone across a room, sees a person a fifth of the frame's height or
less. The person detector sees the whole frame shrunk to 224 pixels and, when it finds
nobody, tiles of half the frame: it finds a person whose height is some 0.25-0.3 of its
input or more, so a person under about a fifth of a 4:3 frame (a quarter of a 16:9 one) was
"nobody in view". It now looks in tiles of a quarter of the frame too. And a false find in
the whole frame, which the landmark model rejects, no longer stops the search: before, the
tiles were not looked at.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from features.pose_estimation import PoseEstimator, estimate_video, stream_poses
from features.pose_estimation import detector as det
from features.pose_estimation import landmarks as lmk
from features.pose_estimation.video import FINER_EVERY_S
from tests.empty_scene import still_scene
from tests.test_video_vfr import _write

PHOTO = Path("media") / "basketball1.png"
BODY = [0, 11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28]  # nose, arms, legs
# basketball1.png (640 x 480), looked at: the player on the left, the ball in his hands,
# stands whole in x 35-185, y 80-475 (the one on the right, cut by the frame's edge, is left
# out).
PLAYER = (slice(60, 480), slice(20, 200))


def _player(shared_data: Path) -> np.ndarray:
    bgr = cv2.imread(str(shared_data / PHOTO))
    assert bgr is not None
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)[PLAYER]


def _far(picture: np.ndarray, height: float, size: tuple[int, int]) -> tuple[np.ndarray, float]:
    """``picture`` shrunk to ``height`` of a plain grey ``size`` (width, height) frame, its
    top-left corner at a third of the frame across and a fifth down; returns the frame and
    the scale."""
    width, frame_h = size
    scale = height * frame_h / picture.shape[0]
    small = cv2.resize(
        picture,
        (round(picture.shape[1] * scale), round(picture.shape[0] * scale)),
        interpolation=cv2.INTER_AREA,
    )
    frame = np.full((frame_h, width, 3), 128, dtype=np.uint8)
    x, y = width // 3, frame_h // 5
    frame[y : y + small.shape[0], x : x + small.shape[1]] = small
    return frame, scale


def test_finer_tiles_are_a_quarter_of_the_frame_overlapping_by_half() -> None:
    """640 x 480: windows of 160 (a quarter of 640) every 80, 7 across (0-480) and 5 down
    (0-320); 320 x 240 would take tiles of 80, under the 112 (half the detector's input)
    that still show it detail: none."""
    assert det.tiles(640, 480, det.FINER_ZOOM) == [
        (x, y, 160, 160) for y in range(0, 321, 80) for x in range(0, 481, 80)
    ]
    assert det.tiles(320, 240, det.FINER_ZOOM) == []
    assert det.tiles(448, 336, det.FINER_ZOOM) == [  # 112, the smallest, every 56
        (x, y, 112, 112) for y in range(0, 225, 56) for x in range(0, 337, 56)
    ]


@pytest.mark.parametrize("size", [(640, 480), (1280, 720)], ids=["480p", "720p"])
def test_a_person_a_fifth_of_the_frame_is_found(shared_data: Path, size: tuple[int, int]) -> None:
    """The basketball player shrunk to a fifth of a 640 x 480 frame's height (96 pixels tall:
    67 in the detector's input from a tile of half the frame, 134 from one of a quarter) and
    of a 1280 x 720 one (144 pixels: 50 and 101): found, each landmark of the body within a
    quarter of the torso's length of where the full-size picture puts it, shrunk and moved
    the same way. Before, nobody was found (nor in the whole frame, 35 and 25 pixels)."""
    player = _player(shared_data)
    est = PoseEstimator(tracking=False, smoothing=False)
    whole = est.process(player)
    frame, scale = _far(player, 0.2, size)
    far = est.process(frame)
    assert whole.person and far.person
    expected = whole.image[BODY, :2] * scale + [size[0] // 3, size[1] // 5]
    torso = np.linalg.norm(
        (expected[1] + expected[2]) / 2 - (expected[7] + expected[8]) / 2
    )  # shoulder centre to hip centre
    error = np.linalg.norm(far.image[BODY, :2] - expected, axis=1) / torso
    assert error.max() < 0.25, error.round(2)


class _FalseFind(PoseEstimator):
    """A real estimator whose detector also 'finds' a person, surer than any other, in an
    empty grey corner of the whole frame, where the landmark model sees nobody."""

    def detect(self, rgb: np.ndarray) -> list[det.Detection]:
        found = super().detect(rgb)
        if rgb.shape[:2] != (720, 1280):  # a tile
            return found
        hip, head = np.array([1150.0, 600.0]), np.array([1150.0, 520.0])
        ghost = det.Detection(
            box=np.array([1100.0, 480.0, 1200.0, 700.0]),
            keypoints=np.array([hip, head, head, head]),
            score=0.99,
        )
        return [ghost, *found]


def test_a_false_find_in_the_whole_frame_does_not_stop_the_search(shared_data: Path) -> None:
    """The player at 0.3 of a 1280 x 720 frame (216 pixels tall) beside a 'person' the
    detector finds in the grey corner, where the landmark model finds none: the tiles are
    still searched and the player found. Before, the search stopped at the false find:
    nobody in view."""
    player = _player(shared_data)
    frame, scale = _far(player, 0.3, (1280, 720))
    est = _FalseFind(tracking=False, smoothing=False)
    ghost = est.detect(frame)[0]
    rejected = est.landmarks(frame, lmk.roi_from_points(ghost.keypoints[0], ghost.keypoints[1]))
    assert rejected.flag < est.min_tracking_confidence  # the landmark model sees nobody there
    pose = est.process(frame)
    assert pose.person
    hips = pose.image[[23, 24], :2].mean(axis=0)
    x, y = 1280 // 3, 720 // 5
    assert x < hips[0] < x + player.shape[1] * scale and y < hips[1] < y + 0.3 * 720


def test_nobody_is_found_in_an_empty_scene_searched_finely() -> None:
    """An empty 640 x 480 scene (no shape of a person), searched in the whole frame and in
    both tiles' sizes: nobody."""
    est = PoseEstimator(tracking=False, smoothing=False)
    assert not est.process(still_scene(640, 480)).person


class _CountedFiner(PoseEstimator):
    """A real estimator that counts its searches of the finer tiles."""

    def __init__(self) -> None:
        super().__init__()
        self.finer = 0
        self.tiles: list[int] = []  # the tiles searched, search by search

    def detect_closer(
        self, rgb: np.ndarray, zoom: int = det.ZOOM, part: slice = slice(None)
    ) -> list[det.Detection]:
        self.finer += zoom == det.FINER_ZOOM
        self.tiles.append(len(det.tiles(rgb.shape[1], rgb.shape[0], zoom)[part]))
        return super().detect_closer(rgb, zoom, part)


def test_extract_searches_the_finer_tiles_at_most_five_times_a_second(tmp_path: Path) -> None:
    """4 frames (0-0.3 s) of an empty scene at 10 fps (lossless), a strip 456 x 114 so that
    its tiles are few: of half its width, 228, 3 (every 114); of a quarter, 114, 7 (every 57).
    Those of half are searched on every frame, as before; the finer ones on frame 0 and again
    0.2 s later, on frame 2, not on all 4."""
    assert len(det.tiles(456, 114)) == 3 and len(det.tiles(456, 114, det.FINER_ZOOM)) == 7
    video = _write(
        tmp_path / "empty.mkv",
        [100 * k for k in range(4)],
        [still_scene(456, 114)] * 4,
        rate=10,
        codec="ffv1",
    )
    est = _CountedFiner()
    poses = estimate_video(video, estimator=est, progress_bar=False)
    assert poses.missing == tuple(range(4))
    assert FINER_EVERY_S == 0.2
    assert est.tiles == [3, 7, 3, 3, 7, 3]


def test_a_stream_spreads_the_finer_search_over_frames(tmp_path: Path) -> None:
    """10 frames (0-0.9 s) of an empty 640 x 480 scene at 10 fps, streamed (``watch``): at
    most one tile a frame beyond the whole frame, the tiles of half the frame apart. Frame 0
    searches the six of half the frame; frames 1-4 the first 4 of the 35 finer tiles, one each;
    frame 5 (0.5 s) the six of half again; frames 6-9 the next 4 finer ones. Before, 35 in one
    frame stalled ``watch`` on a loaded machine (no frame for 5 s), and six a frame over the
    sweep's frames put a label 0.2-0.3 s behind its frame at the 95th percentile on an idle
    machine (60-70 ms before the finer tiles)."""
    video = _write(
        tmp_path / "empty.mkv",
        [100 * k for k in range(10)],
        [still_scene(640, 480)] * 10,
        rate=10,
        codec="ffv1",
    )
    est = _CountedFiner()
    frames = list(stream_poses(video, estimator=est))
    assert len(frames) == 10 and not any(f.pose.person for f in frames)
    assert est.tiles == [6, 1, 1, 1, 1, 6, 1, 1, 1, 1]
    assert est.finer == 8
