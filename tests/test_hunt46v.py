"""Pictures and videos as other people's phones and cameras write them (hunt 46v).

A person far from the camera, a quarter of a 1920x1080 frame's height (the bundled squat
clip's picture at 0.28 of its size in a larger frame): the person detector, which sees the
whole frame shrunk to 224 pixels, found her in none of the 65 frames ("nobody in view",
`reps` and `segment` refused); it now looks again in tiles of half the frame.

A phone stores a portrait photo as its sensor took it, sideways, and says in the EXIF
orientation tag how a viewer turns it upright. FFmpeg, and so OpenCV's capture, decodes the
picture as stored: posecbr found the person lying on their side ("torso tilted backward 1.00,
tilted right 1.00"; the head 5 cm above the hips where it is 63 cm upright). Photos here are
``../shared/data/media/basketball1.png`` (one person fully in view) saved as a phone saves it.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image, ImageOps

from features.pose_estimation import PoseEstimator, stream_poses
from features.pose_estimation.detector import ZOOM, Detection, tiles
from features.pose_estimation.video import upright
from features.poses import load_pose, load_pose_arrays, pose_file_metadata
from posecbr.cli import main
from tests.badinput import refused

PHOTO = Path("media") / "basketball1.png"
NOSE, LEFT_HIP, RIGHT_HIP = 0, 23, 24


def _photo(shared_data: Path, path: Path, orientation: int) -> Path:
    """The photo stored as a camera stores it for EXIF ``orientation`` (1: upright, no tag;
    6: turned a quarter counter-clockwise, shown a quarter clockwise; 8: the other way), as a
    JPEG (best quality, no chroma subsampling, so that the turned copies hold the same
    pixels)."""
    rgb = np.asarray(Image.open(shared_data / PHOTO).convert("RGB"))
    stored = {1: rgb, 6: np.rot90(rgb, 1), 8: np.rot90(rgb, -1)}[orientation]
    picture = Image.fromarray(np.ascontiguousarray(stored))
    exif = picture.getexif()
    if orientation != 1:
        exif[0x0112] = orientation
    picture.save(path, quality=100, subsampling=0, exif=exif)
    return path


def test_upright_turns_a_picture_as_pillow_shows_it() -> None:
    """Every EXIF orientation, against Pillow's own ``ImageOps.exif_transpose``."""
    stored = np.arange(4 * 6 * 3, dtype=np.uint8).reshape(4, 6, 3)
    for orientation in range(1, 9):
        picture = Image.fromarray(stored)
        picture.getexif()[0x0112] = orientation
        expected = np.asarray(ImageOps.exif_transpose(picture))
        np.testing.assert_array_equal(upright(stored, orientation), expected, str(orientation))


# on one xdist worker: the module's extracted made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt46v")


@pytest.fixture(scope="module")
def extracted(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``extract`` of the photo upright and stored sideways both ways: their pose files."""
    root = tmp_path_factory.mktemp("exif")
    (root / "photos").mkdir()
    for orientation in (1, 6, 8):
        _photo(shared_data, root / "photos" / f"photo{orientation}.jpg", orientation)
    assert main(["extract", str(root / "photos"), "--out", str(root / "poses")]) == 0
    return root


@pytest.mark.parametrize("orientation", [6, 8])
def test_a_sideways_stored_photo_is_read_upright(extracted: Path, orientation: int) -> None:
    """The photo stored sideways with its orientation tag gives the pose of the upright photo:
    the person standing (the nose some 0.5 m above the hips, y up), the same landmarks, the
    size as seen. Before, the picture was read as stored: the person lay on their side."""
    upright_seq = load_pose(extracted / "poses" / "photo1.npz")
    turned = extracted / "poses" / f"photo{orientation}.npz"
    seq = load_pose(turned)
    hips_y = (seq.positions[0, LEFT_HIP, 1] + seq.positions[0, RIGHT_HIP, 1]) / 2
    assert seq.positions[0, NOSE, 1] - hips_y > 0.4
    np.testing.assert_allclose(seq.positions, upright_seq.positions, atol=0.03)
    image = load_pose_arrays(turned)["image_landmarks"][0, :, :2]
    first = load_pose_arrays(extracted / "poses" / "photo1.npz")["image_landmarks"][0, :, :2]
    np.testing.assert_allclose(image, first, atol=3.0)  # pixels of the 640x480 picture
    assert pose_file_metadata(turned)["video_size"] == [640, 480]


def test_watch_reads_a_sideways_stored_photo_upright(extracted: Path) -> None:
    """``watch``'s reader (stream_poses) turns the photo as ``extract`` does."""
    frames = list(stream_poses(extracted / "photos" / "photo6.jpg"))
    assert len(frames) == 1 and frames[0].rgb.shape == (480, 640, 3)
    seq = load_pose(extracted / "poses" / "photo1.npz")
    hips = (seq.positions[0, LEFT_HIP] + seq.positions[0, RIGHT_HIP]) / 2
    pose = frames[0].pose
    assert pose.person
    got_hips = (pose.world[LEFT_HIP] + pose.world[RIGHT_HIP]) / 2
    np.testing.assert_allclose(
        pose.world[NOSE] - got_hips, seq.positions[0, NOSE] - hips, atol=0.03
    )


def _mp4(path: Path, frames: int = 4, options: dict[str, str] | None = None) -> Path:
    """``frames`` grey 64x64 frames at 25 fps, H.264 in MP4 (``options``: the muxer's)."""
    import av

    out = av.open(str(path), "w", options=options or {})
    stream = out.add_stream("libx264", rate=25)
    stream.width, stream.height, stream.pix_fmt = 64, 64, "yuv420p"
    for _ in range(frames):
        grey = av.VideoFrame.from_ndarray(np.full((64, 64, 3), 128, np.uint8), format="rgb24")
        for packet in stream.encode(grey):
            out.mux(packet)
    for packet in stream.encode():
        out.mux(packet)
    out.close()
    return path


def _emptied(path: Path) -> Path:
    """The MP4 with its video track's frames taken out of its index, as a camera leaves a
    recording stopped before its first frame: the entry counts of the time-to-sample,
    sample-to-chunk and chunk-offset tables and the sample count of the sample-size table
    set to 0 (each after its box's name and 4 bytes of version and flags)."""
    data = bytearray(path.read_bytes())
    for name, field in ((b"stts", 0), (b"stsc", 0), (b"stco", 0), (b"stsz", 4), (b"stss", 0)):
        at = data.find(name)
        if at > 0:
            data[at + 8 + field : at + 12 + field] = bytes(4)
    path.write_bytes(bytes(data))
    return path


def test_a_video_track_without_frames_is_said_to_be_empty(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An MP4 whose video track holds no frame: one line saying so, exit 1, nothing written.
    Before: "video declares no usable frame rate (16000 frames per second ...)", FFmpeg's
    clock for the track taken for a frame rate."""
    video = _emptied(_mp4(tmp_path / "stopped.mp4"))
    needle = "stopped.mp4: video has no frames (its video track is empty)"
    refused(["extract", str(video), "--out", str(tmp_path / "poses")], tmp_path, capsys, needle)
    refused(["reps", str(video)], tmp_path, capsys, needle)


def test_only_an_empty_track_is_judged_empty(tmp_path: Path) -> None:
    """A whole MP4 and a fragmented one (its frames in fragments, its index's tables empty,
    as a browser or some phones write it) are not judged empty."""
    from features.pose_estimation.containers import mp4_empty_video

    whole = _mp4(tmp_path / "whole.mp4")
    fragmented = _mp4(tmp_path / "frag.mp4", options={"movflags": "frag_keyframe+empty_moov"})
    emptied = _emptied(_mp4(tmp_path / "emptied.mp4"))
    judged = {}
    for path in (whole, fragmented, emptied):
        with open(path, "rb") as fh:
            judged[path.name] = mp4_empty_video(fh, path.stat().st_size)
    assert judged == {"whole.mp4": False, "frag.mp4": False, "emptied.mp4": True}


SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"


def test_tiles_are_half_the_frame_overlapping_by_half() -> None:
    """A 1920x1080 frame: windows of 960 (half its width) every 480 across, and from top
    and bottom (1080 - 960 = 120 down); a portrait 720x1280: 640 high every 320, 720 - 640
    = 80 across."""
    assert tiles(1920, 1080) == [(x, y, 960, 960) for y in (0, 120) for x in (0, 480, 960)]
    assert tiles(720, 1280) == [(x, y, 640, 640) for y in (0, 320, 640) for x in (0, 80)]


def test_no_tiles_over_a_frame_the_detector_sees_whole() -> None:
    """The detector's input is 224 pixels a side: a 64 x 48 frame, or one 224 wide, is seen
    at (at least) its own pixels, so no tile is looked at; one pixel wider, 225 x 100, is
    shrunk, and is looked at in tiles of 113 (half of 225, rounded up), 113 high at most
    (its height is 100), every 56.5 across: x 0, 56, 112."""
    assert tiles(64, 48) == tiles(224, 168) == tiles(100, 224) == []
    assert tiles(225, 100) == [(0, 0, 113, 100), (56, 0, 113, 100), (112, 0, 113, 100)]


def test_a_person_small_in_a_large_frame_is_found(shared_data: Path) -> None:
    """The squat clip's first frame (720x1280) shrunk to 0.28 (a woman some 220 pixels tall)
    at (1100, 600) of a 1920x1080 frame: she is found, her landmarks where the full-size
    frame's land once shrunk and moved so (within 3 % of the small picture's height).
    Before, nobody was found."""
    cap = cv2.VideoCapture(str(shared_data / SQUAT))
    ok, bgr = cap.read()
    cap.release()
    assert ok
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    scale, at = 0.28, np.array([1100.0, 600.0])
    small = cv2.resize(rgb, (round(720 * scale), round(1280 * scale)), interpolation=cv2.INTER_AREA)
    frame = np.full((1080, 1920, 3), (90, 110, 90), dtype=np.uint8)
    frame[600 : 600 + small.shape[0], 1100 : 1100 + small.shape[1]] = small
    est = PoseEstimator()
    whole = est.process(rgb)
    est.reset()
    far = est.process(frame)
    assert whole.person and far.person
    body = [0, 11, 12, 23, 24, 25, 26, 27, 28]  # nose, shoulders, hips, knees, ankles
    expected = whole.image[body, :2] * (small.shape[1] / 720) + at
    np.testing.assert_allclose(far.image[body, :2], expected, atol=0.03 * small.shape[0])


class _CountedTiles(PoseEstimator):
    """A real estimator that counts its tile searches."""

    def __init__(self) -> None:
        super().__init__()
        self.searches = 0

    def detect_closer(
        self, rgb: np.ndarray, zoom: int = ZOOM, part: slice = slice(None)
    ) -> list[Detection]:
        self.searches += 1
        return super().detect_closer(rgb, zoom, part)


def test_a_stream_searches_the_tiles_at_most_twice_a_second_while_nobody_is_in_view(
    tmp_path: Path,
) -> None:
    """12 frames of an empty 320x240 scene at 10 fps (0.0-1.1 s): a stream (``watch``) looks
    in the tiles at 0.0, 0.5 and 1.0 s only, by the frames' own times (six detector runs on
    every empty frame, 95 ms of CPU, would leave a 30-fps camera behind); a frame processed
    on its own, as ``extract`` does, is searched every time (4 frames: 4 searches)."""
    from tests.empty_scene import empty_scene

    video = empty_scene(tmp_path / "empty.mkv", 12, fps=10)
    est = _CountedTiles()
    frames = list(stream_poses(video, estimator=est))
    assert len(frames) == 12 and not any(f.pose.person for f in frames)
    assert est.searches == 3
    alone = _CountedTiles()
    still = frames[0].rgb
    for k in range(4):
        assert not alone.process(still, k / 10).person
    assert alone.searches == 4
