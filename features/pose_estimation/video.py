"""Video in, poses out: :func:`estimate_poses`, :func:`estimate_video`, :func:`stream_poses`.

Frames are decoded with OpenCV (FFmpeg). A video that cannot be used raises
:class:`features.errors.DataError` naming the file and the problem: missing or unreadable path,
not a video, no frames, no frame rate, or fewer frames decoded than the container declares
(truncated or corrupt). Damage that the decoder conceals (a few broken macroblocks in a
stream that still decodes every frame) cannot be seen from here and is not reported.

Variable frame rate (phone videos often are): each decoded frame's presentation time is read
from OpenCV (``CAP_PROP_POS_MSEC`` after the read; with the FFmpeg backend the frame's own
timestamp). When some frame lies more than :data:`VFR_TOLERANCE` of a frame interval away from
``index / fps`` (``fps``: the rate the container declares; above :data:`SUSPECT_FPS` and more
than twice the frames' own, their average rate instead: :func:`own_rate`),
:func:`estimate_video` puts the poses from there on on a uniform grid at that rate by linear
interpolation between the two decoded frames around each grid time
(:func:`resample_to_grid`), as ``watch`` does while the frames come; a grid time between two
frames more than :func:`bridge_limit_s` apart (a gap: frames dropped, a jump in the clock)
stays missing, no motion made up for it. A constant-rate video is
left as it was decoded; so is one whose frames carry no times to trust (:class:`FrameClock`).
Once the frames have strayed, a frame whose time is missing, repeated or earlier than the
frame's before is left out of the grid and the others are resampled (:func:`clocked_times`),
as ``watch`` does: ``segment`` and ``watch`` of one video see the same poses. Where the
times go back and run on from there (a clock reset), the frames after the one that went
back are timed on from the last frame taken, with a note (:class:`FrameClock`), not left
out until the times pass it again; a frame stamped far ahead of the frames either side, or
a few in a row (no more than a bridged gap holds), is left out alone (timed by its place in
a constant-rate video).
"""

from __future__ import annotations

import collections
import itertools
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeGuard

# FFmpeg prints decoder complaints straight to stderr; a user should see one clear line from
# posecbr instead. Must be set before OpenCV first opens a video.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from features.errors import DataError, InputError  # noqa: E402
from features.fileio import as_path, heif_brand, path_exists  # noqa: E402
from features.poses import EXTRACTION_VERSION, MIN_FPS, PoseSequence  # noqa: E402
from features.progress import progress  # noqa: E402
from features.skeleton import BLAZEPOSE_33  # noqa: E402
from features.text import shown  # noqa: E402

from .containers import (  # noqa: E402
    HeifGrid,
    HeifPicture,
    VideoTrack,
    counted_by_duration,
    heif_grid,
    heif_in_range,
    heif_picture,
    heif_shown,
    is_mp4,
    mp4_empty_video,
    mp4_timeless_frames,
    mp4_video_tracks,
    picture_orientation,
    refuse_cut,
    sound_only,
)
from .model import model_version  # noqa: E402
from .served import (  # noqa: E402
    Unread,
    served_cut,
    served_file,
    served_refusal,
    served_whole,
    served_whole_by_duration,
)
from .smoothing import AUX_FILTER, IMAGE_FILTER, VISIBILITY_ALPHA, WORLD_FILTER  # noqa: E402
from .tracker import FramePose, PoseEstimator  # noqa: E402

IMAGE_LANDMARK_FIELDS = ("x_px", "y_px", "z_px", "visibility", "presence")
MAX_VIDEO_FPS = 1000.0
"""The highest frame rate a video may declare (more is a broken header, no camera's)."""
SUSPECT_FPS = 120.0
"""Above this stated frame rate, :func:`open_video` looks at the frames' times (from their
packets, milliseconds): a rate more than twice theirs is a container's clock, not a frame
rate (:func:`own_rate`). A phone's 240-fps slow motion has frames at 240 fps and keeps it."""
VFR_TOLERANCE = 0.25
"""How far (in frame intervals at the declared rate) a frame's presentation time may lie from
``index / fps`` and the video still count as constant-rate: timestamp rounding and a phone's
jitter of a millisecond or two stay well inside it; a dropped or doubled frame does not."""
MAX_BRIDGE_S = 0.25
"""The longest time (s) between two decoded frames that resampling bridges by linear
interpolation; at a low declared rate, :data:`BRIDGE_FRAMES` frame intervals if longer
(:func:`bridge_limit_s`). A phone's frames come 20 to 100 ms apart, and a dropped frame or two
leaves 70 to 100 ms at 30 fps: a body moves little and smoothly in that, so the grid times
between are inferred. A quarter of a second is already a good part of a repetition (a squat
takes one to three seconds), and over a longer stretch without frames (a stream that dropped
them, a jump in the timestamps) the motion cannot be inferred: the grid times inside it stay
missing (NaN), as a frame without a person is."""
BRIDGE_FRAMES = 3
"""At a low declared rate, three frame intervals are bridged however long (a 4 fps video's
frames are 0.25 s apart: one dropped frame is bridged)."""


JUMP_TORSOS = 1.0
"""The hip centre moving more than this many torso lengths (shoulder centre to hip centre in
the image, the larger of the two frames') from one frame to the next is no movement of one
body: the pose jumped to someone else (the person tracked walked out while another was in
view, or a cut in the video). At :data:`JUMP_TORSOS_PER_S` times the frame interval if
more (a 5-fps video's frames are 0.2 s apart)."""
JUMP_TORSOS_PER_S = 8.0
"""The fastest a body's hips move across the image in an exercise video, in torso lengths a
second (about 4 m/s: a jumping jack's hips move one to two, a jog's on the spot less)."""


def person_jumps(image_lm: np.ndarray, fps: float) -> list[int]:
    """The frames (ascending) at which the pose jumped to another person: the hip centre of
    image landmarks ``image_lm`` ``(frames, 33, >=2)`` (px, NaN where nobody is in view)
    farther from the frame before's than :data:`JUMP_TORSOS` torso lengths (or
    :data:`JUMP_TORSOS_PER_S` a second), both frames showing the person. A frame after
    frames with nobody in view is none: who comes back into view after a gap is not judged,
    nor a cut between two people in one spot. Body proportions from the world landmarks do
    not tell people apart (hunt 39g: bone-length ratios differ between people by less than
    within one person, the pose model fitting much the same body to everyone). Nor does
    clothing colour (hunt 39i: it varies within one person as lighting and pose change, and
    different people wear the same colour; docs/measurements.md, "Figures behind the code's
    rules: Telling people apart")."""
    xy = np.asarray(image_lm, dtype=float)[:, :, :2]
    if len(xy) < 2:
        return []
    hips = (xy[:, 23] + xy[:, 24]) / 2.0
    shoulders = (xy[:, 11] + xy[:, 12]) / 2.0
    torso = np.linalg.norm(shoulders - hips, axis=1)
    step = np.linalg.norm(np.diff(hips, axis=0), axis=1)
    limit = max(JUMP_TORSOS, JUMP_TORSOS_PER_S / fps) * np.fmax(torso[:-1], torso[1:])
    with np.errstate(invalid="ignore"):
        jumped = step > limit  # NaN (nobody in view on either side): no jump
    return (np.flatnonzero(jumped) + 1).tolist()


def jump_words(
    path: str | Path,
    jumps: Sequence[int],
    fps: float,
    after: str = "repetitions are counted apart on either side",
) -> str:
    """The line that tells a user the pose jumped to another person (the first place, and
    how many there were), and ``after`` it what comes of it."""
    frame = jumps[0]
    limit = max(JUMP_TORSOS, JUMP_TORSOS_PER_S / fps)
    line = (
        f"{path}: the pose jumps to another person at frame {frame} ({frame / fps:.2f} s:"
        f" the hips moved more than {limit:.2g} torso length between two frames); {after}"
    )
    return f"{line} ({len(jumps)} such jumps)" if len(jumps) > 1 else line


@dataclass(frozen=True)
class VideoInfo:
    """What the container declares: frame count (0 if unknown), fps, width, height (of the
    frames as seen: a still picture turned by its EXIF ``orientation``, :func:`upright`)."""

    path: Path
    frames: int
    fps: float
    width: int
    height: int
    orientation: int = 1


class StillCapture:
    """A picture decoded whole (a HEIF photo's tiles put together: :func:`_whole_picture`)
    read as the one frame of a capture, as OpenCV's capture of a picture gives its frame:
    ``bgr`` (as OpenCV decodes, turned to be seen), at the rate and codec (``fps``,
    ``fourcc``) OpenCV states for the file."""

    def __init__(self, bgr: np.ndarray, fps: float, fourcc: float) -> None:
        self.bgr, self.fps, self.fourcc = bgr, fps, fourcc
        self.grabbed, self.taken, self.released = False, 0, False

    def isOpened(self) -> bool:  # noqa: N802 (OpenCV's name)
        return not self.released

    def release(self) -> None:
        self.released = True

    def grab(self) -> bool:
        self.grabbed = not self.released and self.taken == 0
        self.taken += 1
        return self.grabbed

    def retrieve(self) -> tuple[bool, Any]:
        return (True, self.bgr.copy()) if self.grabbed else (False, None)

    def read(self) -> tuple[bool, Any]:
        return self.retrieve() if self.grab() else (False, None)

    def get(self, prop: int) -> float:
        return {
            cv2.CAP_PROP_FRAME_COUNT: 1.0,
            cv2.CAP_PROP_FPS: self.fps,
            cv2.CAP_PROP_FOURCC: self.fourcc,
            cv2.CAP_PROP_FRAME_WIDTH: float(self.bgr.shape[1]),
            cv2.CAP_PROP_FRAME_HEIGHT: float(self.bgr.shape[0]),
            cv2.CAP_PROP_POS_MSEC: 0.0,
        }.get(prop, 0.0)


Capture = cv2.VideoCapture | StillCapture
"""What a file's frames are read from: OpenCV's capture, or a picture decoded whole
(:class:`StillCapture`)."""


def upright(image: np.ndarray, orientation: int) -> np.ndarray:
    """A still picture decoded as stored, flipped and turned as its EXIF ``orientation``
    (1-8, :func:`.containers.picture_orientation`) says a viewer shows it: 6, a phone's
    portrait photo stored sideways, a quarter turn clockwise; a video's frames as its display
    matrix turns them, less its mirror, where it mirrors them (:data:`UNMIRRORED`). A video's
    frames otherwise (1: a turn alone OpenCV applies itself) are given back as they are."""
    if orientation == 1:
        return image
    turned = {
        2: image[:, ::-1],
        3: image[::-1, ::-1],
        4: image[::-1],
        5: image.swapaxes(0, 1),
        6: image[::-1].swapaxes(0, 1),
        7: image[::-1, ::-1].swapaxes(0, 1),
        8: image[:, ::-1].swapaxes(0, 1),
    }[orientation]
    return np.ascontiguousarray(turned)


@dataclass(frozen=True)
class VideoPoses:
    """Everything estimated for one video.

    sequence: canonical :class:`PoseSequence` (world landmarks, metres, y up, NaN where no
    person; confidence = visibility). image_landmarks: ``(frames, 33, 5)`` x px, y px, z px,
    visibility, presence (NaN where no person). missing: indices of frames with no person.
    video_frames: for a variable-frame-rate video (resampled), the decoded frame on screen at
    each row's time (the last one at or before it), for drawing; None when the rows are the
    decoded frames themselves.
    """

    sequence: PoseSequence
    image_landmarks: np.ndarray
    missing: tuple[int, ...]
    info: VideoInfo
    video_frames: np.ndarray | None = None

    @property
    def resampled(self) -> bool:
        """Whether the video's frame times were irregular and the poses put on a grid."""
        return self.video_frames is not None


def _capture(name: str, threads: int | None) -> cv2.VideoCapture:
    """``cv2.VideoCapture(name)``; with ``threads``, FFmpeg decodes on that many threads
    (its default is one per core, whatever else runs on them: a worker given one core should
    decode on one), falling back to OpenCV's other backends if FFmpeg cannot open it."""
    if threads is None:
        return cv2.VideoCapture(name)
    with _quiet_opencv():  # FFmpeg refusing a file is no news: the fallback reports
        cap = cv2.VideoCapture(name, cv2.CAP_FFMPEG, [cv2.CAP_PROP_N_THREADS, threads])
    if cap.isOpened():
        return cap
    cap.release()
    return cv2.VideoCapture(name)


def open_video(path: str | Path, decode_threads: int | None = None) -> tuple[Capture, VideoInfo]:
    """Open a video file, or raise :class:`DataError` with a one-line reason.
    ``decode_threads``: FFmpeg's decoding threads (None: FFmpeg's default, one per core)."""
    path = as_path(path, "path")
    if not path_exists(path):
        raise DataError("no such file", path)
    if path.is_dir():
        raise DataError("is a folder, not a video", path)
    if not path.is_file():  # reading a pipe waits for a writer that may never come
        raise DataError("is a pipe, socket or device, not a video file", path)
    try:
        with open(path, "rb") as fh:
            head = fh.read(512)  # an MPEG-TS file's first packets: 188 bytes each
            fh.seek(max(0, path.stat().st_size - 64))
            tail = fh.read()
    except OSError as exc:
        raise DataError(f"cannot read ({exc.strerror or exc})", path) from None
    if not head:
        raise DataError("empty file, not a video", path)
    refuse_cut(path, head, tail)
    try:
        cap = _capture(str(path), decode_threads)
    except cv2.error as exc:
        raise DataError(f"cannot open as a video ({exc.msg or exc})", path) from None
    if not cap.isOpened():
        cap.release()
        raise _not_a_video(path, head, None)
    refuse_text(cap, path)
    frames = int(max(0.0, cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0.0))
    fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    seen, width, height, orientation = _seen_size(cap, path, head)
    fps, frames = _frames_rate(path, fps, frames, counted_by_duration(head))
    if not math.isfinite(fps) or fps < MIN_FPS or fps > MAX_VIDEO_FPS:
        # below MIN_FPS no pose file can hold it: refused before the model runs on every frame
        seen.release()
        raise _not_a_video(path, head, fps)
    timeless = _timeless_frames(path) if is_mp4(head) else None
    if timeless is not None:
        seen.release()
        raise DataError(
            f"video declares no usable frame rate (its header gives its {timeless} frames"
            " no duration)",
            path,
        )
    return seen, VideoInfo(path, frames, fps, width, height, orientation)


def _seen_size(cap: cv2.VideoCapture, path: Path, head: bytes) -> tuple[Capture, int, int, int]:
    """The capture of ``path`` (whose first bytes are ``head``) to read its frames from, their
    width and height as seen, and how posecbr turns them (:func:`upright`): a still picture
    by its EXIF orientation (:func:`.containers.picture_orientation`), an MP4/MOV video by
    its display matrix, less its mirror, where it mirrors the frames (:data:`UNMIRRORED`),
    OpenCV's own turning set off; one turned a quarter is as wide as it is stored high. An
    MP4/MOV whose first video track is a lesser one is refused
    (:func:`_refuse_lesser_track`). A HEIF photo of which OpenCV decodes a part, one tile of
    a phone's photo, or that its properties turn otherwise than OpenCV does (an imir, a
    clap), is read whole (its tiles put together, turned, mirrored and cropped:
    :func:`_whole_part`, turned 1 then), or refused where it cannot be."""
    orientation = picture_orientation(path)
    if is_mp4(head) and heif_brand(head) is None:
        orientation = _tracks_turn(cap, path, _video_tracks(cap, path), orientation)
    width = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH) or 0)
    height = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0)
    if orientation >= 5:
        width, height = height, width
    if heif_brand(head) is not None:
        whole = _whole_part(cap, path, head, width, height)
        if isinstance(whole, StillCapture):
            return whole, whole.bgr.shape[1], whole.bgr.shape[0], 1
    return cap, width, height, orientation


def _tracks_turn(
    cap: cv2.VideoCapture, source: str | Path, tracks: list[VideoTrack], orientation: int
) -> int:
    """How posecbr turns the frames of ``cap``, an MP4/MOV video of ``tracks``
    (:func:`.containers.mp4_video_tracks`), opened from ``source``: as its first video
    track's display matrix turns them less its mirror, where it mirrors them
    (:data:`UNMIRRORED`, OpenCV's own turning set off), else ``orientation`` (OpenCV's own
    turning kept). Refused when that track is a lesser one (:func:`_refuse_lesser_track`)."""
    _refuse_lesser_track(cap, source, tracks)
    if tracks and tracks[0].turn in UNMIRRORED:
        cap.set(cv2.CAP_PROP_ORIENTATION_AUTO, 0)
        return UNMIRRORED[tracks[0].turn]
    return orientation


UNMIRRORED = {2: 1, 4: 3, 5: 6, 7: 8}
"""The turn (EXIF orientation, :func:`upright`) posecbr gives the frames of a video whose
display matrix mirrors them (:data:`.containers.MATRIX_TURNS`: some phones' front camera
shows its recording as a mirror does): the matrix's turn without the mirror, the frames as
the camera saw the person, upright, their left side on the image's right (a mirrored frame
would be posed with left and right swapped). OpenCV turns them wrongly: it takes the
matrix's angle alone (FFmpeg's ``av_display_rotation_get``), so a mirror (2) was a half
turn, the person upside down; its own turning is set off for them. A turn without a mirror
OpenCV does right and keeps."""


def _video_tracks(cap: cv2.VideoCapture, path: Path) -> list[VideoTrack]:
    """:func:`.containers.mp4_video_tracks` of an MP4/MOV file (``cap`` released if it
    cannot be read)."""
    try:
        with open(path, "rb") as fh:
            return mp4_video_tracks(fh, path.stat().st_size)
    except OSError as exc:
        cap.release()
        raise DataError(f"cannot read ({exc.strerror or exc})", path) from None


def _whole_part(cap: cv2.VideoCapture, path: Path, head: bytes, width: int, height: int) -> Capture:
    """``cap`` of a HEIF photo (HEIC, AVIF: :func:`.containers.heif_picture`) of which
    OpenCV decodes a ``width`` x ``height`` frame that is its primary picture as shown
    (:func:`_as_decoded`), or whose picture cannot be read (OpenCV's verdict stands); else
    the picture read whole (:func:`_whole_picture`, ``cap`` released): put together from its
    tiles where it is a grid (a phone's photo, 512x512 tiles put together: FFmpeg gives each
    coded picture in the file as a stream of its own and OpenCV reads the first, the
    top-left tile alone), turned, mirrored and cropped as its properties say; any other such
    photo is refused."""
    try:
        with open(path, "rb") as fh:
            size = path.stat().st_size
            picture = heif_picture(fh, size, head)
            if picture is None or (_as_decoded(picture, width, height) and not picture.ranges):
                return cap
            grid = heif_grid(fh, size, head)
    except OSError as exc:
        cap.release()
        raise DataError(f"cannot read ({exc.strerror or exc})", path) from None
    return _whole_picture(cap, path, picture, grid, (width, height))


def _as_decoded(picture: HeifPicture, width: int, height: int) -> bool:
    """Whether OpenCV's frame of ``width`` x ``height`` of a HEIF file is its primary
    ``picture`` as shown: it is as large and turned by an irot alone, which OpenCV applies
    (FFmpeg gives it as a display matrix), or not at all. An imir it reads as a turn (axis 0
    none, 1 a half turn) and a clap it does not apply."""
    turned = all(name == "irot" for name, _ in picture.turns)
    return turned and (picture.width, picture.height) == (width, height)


def _whole_picture(
    cap: cv2.VideoCapture,
    source: str | Path,
    picture: HeifPicture,
    grid: HeifGrid | None,
    decoded: tuple[int, int],
) -> StillCapture:
    """The HEIF photo ``picture`` (opened from ``source``), of which OpenCV decodes a frame of
    ``decoded`` (width, height) that is not it as shown, read whole as one frame
    (:class:`StillCapture`, at the rate OpenCV states for it; ``cap`` released): put
    together from the tiles of its ``grid`` (:func:`.containers.heif_grid`: each decoded by
    FFmpeg, in one stream), or, coded whole, the frame OpenCV decodes as stored (its own
    turning set off), then turned, mirrored and cropped as its properties say, in their
    order (:func:`.containers.heif_shown`). Refused when it is no grid of tiles FFmpeg
    decodes nor coded whole as OpenCV decodes it, as it was before: a part of it was
    posed."""
    fps, fourcc = cap.get(cv2.CAP_PROP_FPS), cap.get(cv2.CAP_PROP_FOURCC)
    stored = _stored_frame(cap, picture.coded) if grid is None and picture.tiles == 1 else None
    cap.release()
    whole = f"{_a(picture.brand)} picture of {picture.width}x{picture.height}"
    if grid is not None:
        bgr = heif_shown(
            heif_in_range(_grid_picture(grid, source, whole), picture.ranges), grid.turns
        )
    elif stored is not None:
        bgr = heif_shown(heif_in_range(stored, picture.ranges), picture.turns)
    elif picture.tiles > 1:
        raise DataError(
            f"{whole} made of {picture.tiles} tiles (as a phone stores a photo), of which"
            f" OpenCV decodes one alone ({decoded[0]}x{decoded[1]}): convert it to JPEG or PNG"
            " first",
            source,
        )
    else:
        raise DataError(
            f"{whole} of which OpenCV decodes another picture in the file"
            f" ({decoded[0]}x{decoded[1]}): convert it to JPEG or PNG first",
            source,
        )
    if bgr.shape[:2] != (picture.height, picture.width):
        raise DataError(
            f"{whole} whose tiles make a picture of {bgr.shape[1]}x{bgr.shape[0]}: convert it"
            " to JPEG or PNG first",
            source,
        )
    return StillCapture(np.ascontiguousarray(bgr), float(fps or 1.0), float(fourcc or 0.0))


def _stored_frame(cap: cv2.VideoCapture, coded: tuple[int, int]) -> np.ndarray | None:
    """The frame ``cap`` of a HEIF picture coded whole decodes, as stored (OpenCV's own
    turning set off), when it is of the picture's ``coded`` size (width, height); None
    otherwise (another picture in the file, or none decoded)."""
    cap.set(cv2.CAP_PROP_ORIENTATION_AUTO, 0)
    ok, bgr = cap.read()
    if not ok or bgr is None or bgr.shape[:2] != (coded[1], coded[0]):
        return None
    return np.asarray(bgr)


def _grid_picture(grid: HeifGrid, source: str | Path, whole: str) -> np.ndarray:
    """The tiles of ``grid`` (:func:`_decoded_tiles`) put together and cut to its width and
    height; refused when FFmpeg decodes fewer than all (``whole``: the picture, in words)."""
    tiles = _decoded_tiles(grid, source)
    rows, columns, high, wide = grid.rows, grid.columns, grid.tile_height, grid.tile_width
    if len(tiles) < rows * columns:
        raise DataError(
            f"{whole} made of {rows * columns} tiles (as a phone stores a photo), of which"
            f" FFmpeg decodes {len(tiles)}: convert it to JPEG or PNG first",
            source,
        )
    return (
        np.stack(tiles)
        .reshape(rows, columns, high, wide, 3)
        .swapaxes(1, 2)
        .reshape(rows * high, columns * wide, 3)[: grid.height, : grid.width]
    )


def _decoded_tiles(grid: HeifGrid, source: str | Path) -> list[np.ndarray]:
    """The tiles of ``grid`` (:func:`.containers.heif_grid`) FFmpeg decodes from its stream
    (written to a file of its own in the temporary folder, deleted after: OpenCV reads a
    file), in order, up to the first it does not decode or of another size than the grid's."""
    suffix = ".hevc" if grid.codec == "hevc" else ".ivf"
    tiles: list[np.ndarray] = []
    try:
        with tempfile.TemporaryDirectory(prefix="posecbr-tiles-") as folder:
            stream = Path(folder) / f"tiles{suffix}"
            stream.write_bytes(grid.stream)
            with _quiet_opencv():
                cap = cv2.VideoCapture(str(stream), cv2.CAP_FFMPEG)
            try:
                while cap.isOpened() and len(tiles) < grid.rows * grid.columns:
                    ok, bgr = cap.read()
                    if not ok or bgr is None or bgr.shape != (grid.tile_height, grid.tile_width, 3):
                        break
                    tiles.append(bgr)
            finally:
                cap.release()
    except OSError as exc:
        raise DataError(f"cannot decode its tiles ({exc.strerror or exc})", source) from None
    except cv2.error as exc:
        raise DataError(f"cannot decode its tiles ({exc.msg or exc})", source) from None
    return tiles


def _refuse_lesser_track(
    cap: cv2.VideoCapture, source: str | Path, tracks: list[VideoTrack]
) -> None:
    """Refuse an MP4/MOV file whose first video track (the one OpenCV decodes: it takes
    FFmpeg's first video stream and can be given no other) is smaller than another of its
    ``tracks`` (a picture-in-picture or preview track ahead of the recording). Before, the
    pose model ran on the first, a 160x120 preview of a 720x1280 recording, and the pose
    file was written, exit 0."""
    largest = max(tracks, key=lambda track: track.width * track.height, default=None)
    if largest is None or largest.width * largest.height <= tracks[0].width * tracks[0].height:
        return
    cap.release()
    first = tracks[0]
    raise DataError(
        f"holds {len(tracks)} video tracks, and OpenCV decodes the first alone"
        f" ({first.width}x{first.height}, {first.frames} frames), not the largest"
        f" ({largest.width}x{largest.height}, {largest.frames} frames): save that track in a"
        " file of its own and give that",
        source,
    )


def _a(brand: str) -> str:
    """A HEIF brand's name (:func:`features.fileio.heif_brand`) with its article: "an AVIF"."""
    return f"{'an' if brand.startswith('A') else 'a'} {brand}"


TEXT_CODECS = frozenset({"ansi"})
"""The codecs (OpenCV's ``CAP_PROP_FOURCC``, as FFmpeg names them) in which FFmpeg plays a
text file as a video: its ``tty`` demuxer takes a ``.txt`` (``.nfo``, ``.asc``, ...) file, or
one served under such a name, and draws its characters as frames, 25 a second."""


def refuse_text(cap: cv2.VideoCapture, source: str | Path) -> None:
    """Refuse an opened capture whose "video" is a text file drawn as frames
    (:data:`TEXT_CODECS`): a label file given to ``watch`` for its video played as 3 frames
    of digits and ended "before the shortest window"; a longer one was watched to its end,
    "nobody in view", exit 0."""
    tag = int(cap.get(cv2.CAP_PROP_FOURCC) or 0) & 0xFFFFFFFF
    if tag.to_bytes(4, "little").decode("latin-1").strip() in TEXT_CODECS:
        cap.release()
        raise DataError(
            "a text file, not a video (FFmpeg would draw its characters as frames)", source
        )


def _timeless_frames(path: Path) -> int | None:
    """:func:`.containers.mp4_timeless_frames` of an MP4/MOV file."""
    try:
        with open(path, "rb") as fh:
            return mp4_timeless_frames(fh, path.stat().st_size)
    except OSError as exc:
        raise DataError(f"cannot read ({exc.strerror or exc})", path) from None


def _empty_video(path: Path) -> bool:
    """:func:`.containers.mp4_empty_video` of an MP4/MOV file."""
    try:
        with open(path, "rb") as fh:
            return mp4_empty_video(fh, path.stat().st_size)
    except OSError as exc:
        raise DataError(f"cannot read ({exc.strerror or exc})", path) from None


def _not_a_video(path: Path, head: bytes, fps: float | None) -> DataError:
    """Why a file (its first bytes ``head``) is no video to take: OpenCV could not open it
    (``fps`` None) or it states no frame rate posecbr takes; a sound file says so
    (:func:`.containers.sound_only`: a song's cover picture is FFmpeg's "video" at
    90 kHz), and so does an MP4/MOV file whose video track holds no frame
    (:func:`.containers.mp4_empty_video`: its clock's ticks were taken for its frame
    rate)."""
    sound = sound_only(path, head)
    if sound is not None:
        return DataError(
            f"sound alone, no video ({sound}{'' if fps is None else ' with a picture'})", path
        )
    if is_mp4(head) and _empty_video(path):
        return DataError("video has no frames (its video track is empty)", path)
    brand = heif_brand(head)
    if fps is None and brand is not None:
        return DataError(
            f"{_a(brand)} picture OpenCV cannot decode: convert it to JPEG or PNG first",
            path,
        )
    if fps is None:
        return DataError(
            "not a video OpenCV can decode (unknown format, truncated or corrupt)", path
        )
    return DataError(
        f"video declares no usable frame rate ({fps:g} frames per second; posecbr takes"
        f" {MIN_FPS:g} to {MAX_VIDEO_FPS:g})",
        path,
    )


def _frames_rate(path: Path, fps: float, frames: int, by_duration: bool) -> tuple[float, int]:
    """The frame rate and count OpenCV states for a video (``fps``, ``frames``), or, when
    that rate is above :data:`SUSPECT_FPS` and a clock's ticks rather than a frame rate
    (:func:`own_rate`), the frames' own rate and their number (their packets: not the
    container's duration at that rate, which counts an audio track running on after the
    video; a WebM cut short is found by :func:`.containers.matroska_end`). A file whose
    count OpenCV takes from its duration (``by_duration``:
    :func:`.containers.counted_by_duration`) holds no more frames than its packets: the
    duration is its longest track's (sound running on 0.3 s after the last frame of a 4-s
    clip counted 9 frames more than there are)."""
    if not (by_duration and frames) and not (math.isfinite(fps) and fps > SUSPECT_FPS):
        return fps, frames
    got = _packet_times(path)
    if got is None:
        return fps, frames
    rate = taken_rate(*got)
    if rate != fps:
        return rate, int(got[0].size)
    return fps, min(frames, int(got[0].size)) if by_duration and frames else frames


def taken_rate(times: np.ndarray, fps: float) -> float:
    """The frame rate :func:`open_video` takes for a video stating ``fps`` whose frames come
    at ``times`` (s): ``fps``, or, above :data:`SUSPECT_FPS`, the frames' own rate when
    :func:`own_rate` finds ``fps`` a clock's ticks. One rule for the rate a video is
    resampled to and the rate :func:`variable_rate` judges it by."""
    if math.isfinite(fps) and fps > SUSPECT_FPS:
        return own_rate(times, fps) or fps
    return fps


def iter_frames(path: str | Path, decode_threads: int | None = None) -> Iterator[np.ndarray]:
    """RGB uint8 frames ``(h, w, 3)`` of a video file; raises :class:`DataError` at the end if
    fewer frames decoded than the container declares, or none at all. ``decode_threads``: see
    :func:`open_video`."""
    for rgb, _time_s in iter_timed_frames(path, decode_threads):
        yield rgb


def iter_timed_frames(
    path: str | Path, decode_threads: int | None = None
) -> Iterator[tuple[np.ndarray, float]]:
    """:func:`iter_frames` with each frame's presentation time in seconds, as the decoder
    gives it (``CAP_PROP_POS_MSEC``; NaN when it gives none). A file whose frame count the
    container only estimates (Matroska/WebM: duration x rate, too many for a variable rate) is
    whole when its frames' times reach the container's duration."""
    cap, info = open_video(path, decode_threads)
    count = 0
    times: list[float] = []
    try:
        while True:
            try:
                ok, bgr = cap.read()
                if not ok or bgr is None:
                    break
                rgb = cv2.cvtColor(upright(bgr, info.orientation), cv2.COLOR_BGR2RGB)
            except cv2.error as exc:
                raise DataError(
                    f"cannot decode frame {count} ({exc.msg or exc})", info.path
                ) from None
            count += 1
            t = frame_time_s(cap)
            times.append(t)
            yield rgb, t
    finally:
        cap.release()
    if count == 0:
        raise DataError("video has no frames (empty, truncated or corrupt)", info.path)
    check_whole(count, info.frames, info.path, span_s(times, info.fps), info.fps)


def frame_time_s(cap: Capture) -> float:
    """The presentation time (s) of the frame ``cap`` read last; NaN when the decoder gives
    none."""
    ms = float(cap.get(cv2.CAP_PROP_POS_MSEC))
    return ms / 1000.0 if math.isfinite(ms) else float("nan")


def usable_times(times: np.ndarray | list[float]) -> bool:
    """Whether decoded frame times can be trusted: finite and strictly increasing."""
    t = np.asarray(times, dtype=np.float64)
    return bool(t.size >= 2 and np.isfinite(t).all() and (np.diff(t) > 0).all())


def span_s(times: list[float], fps: float) -> float | None:
    """How long the decoded frames cover (s): first frame's time to the last one's end (one
    interval at ``fps``); None when the times cannot be trusted. A frame left without a time
    after the frames strayed (:func:`clocked_times`: a repeated time) does not stop the
    others counting."""
    if usable_times(times):
        return times[-1] - times[0] + 1.0 / fps
    elapsed, strayed = clocked_times(times, fps)
    return float(np.nanmax(elapsed)) + 1.0 / fps if strayed else None


def strays(elapsed_s: Any, index: Any, fps: float) -> Any:
    """Whether a frame ``elapsed_s`` after the first (scalars or arrays) lies more than
    :data:`VFR_TOLERANCE` of a frame from ``index / fps``; a NaN time strays not."""
    return np.abs(np.asarray(elapsed_s) * fps - index) > VFR_TOLERANCE


class FrameClock:
    """A file's frame times as they come, the rule :func:`estimate_video` and
    :func:`stream_poses` share: :meth:`take` gives each frame's time from the first frame's
    and whether every frame so far lies on the grid ``index / fps`` (:func:`strays`). A time
    missing (NaN) or not after the one before while the frames still lie on the grid means
    the decoder has none to give (a raw H.264 stream: OpenCV gives 0 for every frame): from
    then on every frame's time is NaN, so the file is taken as constant-rate (as
    :func:`usable_times` decides for the whole file), not as frames that all stray from the
    grid at time 0. Once the frames have strayed (a variable rate), such a frame alone has
    no time (NaN); when that frame lies more than :func:`bridge_limit_s` before the last one
    taken and the next frame's time is again not after the last one taken but after that
    frame's, the clock went back there (a recording's clock reset, more frames in a row
    stamped far ahead of the others than :attr:`run`): the times from there on are taken as
    running on from the last frame taken, the frame where it went back one interval
    (``1 / fps``) after it, so every later frame keeps a time (before, all of them were left
    out until the times passed the last one taken again). Frames out of order by less than
    that are left out until the times pass the last one taken (no more than a bridged
    stretch of them), the times unshifted. :attr:`went_back` lists each place the clock
    went back: (the frame where it did, the time of the frame taken before it, its own
    time; s, as decoded).

    A frame stamped far ahead (more than :func:`bridge_limit_s` after the last one taken),
    alone or with up to :attr:`run` in a row in all, each far ahead, when the frame after
    them comes back between the last one taken and it (:meth:`needs_next` says how many of
    the next frames' times are wanted), is out of place: once the frames have strayed it
    has no time (left out), the frames after the run keep their own; while they lie on the
    grid it is timed by its place, ``index / fps``, and they stay on the grid. Before, a
    single frame was taken, the next frame left out as the place the clock went back and
    the later frames timed on from the stamp ahead; so were two or more in a row (0.37,
    5.0, 5.04, 0.41 s: 5.0 and 5.04 kept, 0.41 lost, the later ones timed on from 5.04).
    Without looking that far ahead a run cannot be told from a gap or a clock reset: the
    times after it are what tells. :attr:`ahead` lists them: (the frame, the time of the
    frame taken before it, its own time, the time of the frame that came back; s, as
    decoded)."""

    def __init__(self, fps: float) -> None:
        self.fps = fps
        self.first = self.last = float("nan")
        self.trusted = True
        self.on_grid = True
        self.offset = 0.0  # added to the decoded times once the clock went back (s)
        self.last_raw = float("nan")  # the decoded time of the last frame taken
        self.behind: tuple[int, float] | None = None  # the frame just left out for its
        # time not after the last one's (strayed): its index and decoded time
        self.went_back: list[tuple[int, float, float]] = []
        self.ahead: list[tuple[int, float, float, float]] = []

    @property
    def run(self) -> int:
        """The most frames in a row taken as stamped far ahead (:meth:`needs_next`): those of
        a bridged gap (:func:`bridge_limit_s`, at least one: 6 at 25 fps, 7 at 30). Left out,
        such a run leaves a hole resampling still bridges; a longer run is a stretch of the
        recording itself whose clock then went back (a reset), as before."""
        return max(1, int(bridge_limit_s(self.fps) * self.fps + 1e-9))

    def needs_next(self, index: int, time_s: float) -> int:
        """How many of the next frames' times (decoded, s) :meth:`take` wants for frame
        ``index`` (:attr:`run`), 0 for none: whether its time lies so far after the last one
        taken (beyond a bridged gap) that the frames after it tell whether it (and any far
        ahead after it) was stamped ahead."""
        far = (
            index > 0
            and self.trusted
            and math.isfinite(time_s)
            and time_s + self.offset - self.last > bridge_limit_s(self.fps)
        )
        return self.run if far else 0

    def _comes_back(self, time_s: float, coming: Sequence[float]) -> float:
        """The first of the next frames' times (``coming``, decoded) between the last one
        taken and ``time_s``, after none but frames far ahead too (beyond a bridged gap
        after the last one taken); NaN where there is none among :attr:`run` of them."""
        for t in coming[: self.run]:
            if not math.isfinite(t):
                break
            if self.last < t + self.offset < time_s + self.offset:
                return t
            if t + self.offset - self.last <= bridge_limit_s(self.fps):
                break
        return float("nan")

    def take(
        self, index: int, time_s: float, coming: float | Sequence[float] = float("nan")
    ) -> float:
        """Frame ``index``'s time (s) from the first frame's; NaN when it has none to trust.
        ``coming``: the next frames' decoded times (as many as :meth:`needs_next` wants; one
        as a number; NaN or none: the last frame)."""
        if index == 0:
            self.first = self.last = self.last_raw = time_s
            self.trusted = math.isfinite(time_s)
            return 0.0 if self.trusted else float("nan")
        if not self.trusted:
            return float("nan")
        following = [coming] if isinstance(coming, (int, float)) else list(coming)
        back = self._comes_back(time_s, following) if self.needs_next(index, time_s) else math.nan
        if math.isfinite(back):  # stamped far ahead of the frames either side (alone or with
            # the few after it): out of place
            self.ahead.append((index, self.last_raw, time_s, back))
            if not self.on_grid:
                return float("nan")
            elapsed = index / self.fps  # on the grid: its place; the last one taken
            self.last = self.first + elapsed
            self.last_raw = self.last - self.offset
            self.behind = None
            return elapsed
        if not (math.isfinite(time_s) and time_s + self.offset > self.last):
            if self.on_grid or not math.isfinite(time_s):
                self.trusted = not self.on_grid
                return float("nan")
            behind = self.behind
            if (
                behind is None
                or behind[0] != index - 1
                or time_s <= behind[1]
                or self.last_raw - behind[1] <= bridge_limit_s(self.fps)
            ):  # a frame out of order, a few (no longer than a gap bridged), or the clock
                self.behind = (index, time_s)  # went back: the next frame tells
                return float("nan")
            # the frame before went back and this one runs on from it: the clock went back
            self.went_back.append((behind[0], self.last_raw, behind[1]))
            self.offset = self.last + 1.0 / self.fps - behind[1]
        self.behind = None
        self.last, self.last_raw = time_s + self.offset, time_s
        elapsed = self.last - self.first
        self.on_grid = self.on_grid and not strays(elapsed, index, self.fps)
        return elapsed

    def filter_time(self, index: int, elapsed_s: float) -> float:
        """The time the temporal filters get for a frame: ``index / fps`` while the frames lie
        on the grid (or have no usable time), its own time once they stray; NaN for a frame
        left out for its time once they have strayed (the estimator passes its pose through
        unsmoothed, the filters untouched: the frames after it are smoothed as they would be
        without it). Before, such a frame got ``index / fps``: where that lay after the
        frames' own times, the filters took it and passed the frames after it through
        unsmoothed until their times passed it."""
        if self.on_grid:
            return index / self.fps
        return elapsed_s


def clocked_times(times: np.ndarray | list[float], fps: float) -> tuple[np.ndarray, bool]:
    """A file's decoded frame times (s) as :class:`FrameClock` takes them one by one, as
    ``watch`` does: each frame's time from the first frame's (NaN: none to trust), and
    whether the frames strayed from the grid (a variable frame rate: the videos
    :func:`estimate_video` resamples). Once they have strayed, a frame whose time is missing,
    repeated or earlier than the last one's has none (NaN) and the others keep theirs; before
    that, such a time means the file has none to trust (all NaN after it, not strayed)."""
    clock = FrameClock(fps)
    decoded = [float(t) for t in times]
    elapsed = [clock.take(i, t, decoded[i + 1 : i + 1 + clock.run]) for i, t in enumerate(decoded)]
    return np.asarray(elapsed, np.float64), not clock.on_grid


def _packet_times(
    path: str | Path, window_s: float | None = None, timeout_s: float | None = None
) -> tuple[np.ndarray, float] | None:
    """The presentation times (s, in order) of a video's packets and the frame rate OpenCV
    states, read without decoding (FFmpeg's raw mode: a few milliseconds where decoding
    takes a second); None where FFmpeg cannot give the packets. ``window_s``: only the
    packets up to the first that lies that long after the earliest (a stream's start, not the
    whole of it); ``timeout_s``: how long opening it and each read may wait (a stream URL)."""
    params: list[int] = []
    if timeout_s is not None:
        ms = max(1, round(timeout_s * 1000))
        params = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, ms, cv2.CAP_PROP_READ_TIMEOUT_MSEC, ms]
    with _quiet_opencv():
        cap = cv2.VideoCapture(str(path), cv2.CAP_FFMPEG, params)
    try:
        if not (cap.isOpened() and cap.set(cv2.CAP_PROP_FORMAT, -1)):
            return None
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        times: list[float] = []
        earliest = math.inf
        while cap.grab():
            times.append(frame_time_s(cap))
            earliest = min(earliest, times[-1])  # NaN: stays as it was
            if window_s is not None and times[-1] - earliest >= window_s:
                break
    finally:
        cap.release()
    return (np.sort(np.asarray(times)), fps) if times else None


def own_rate(times: np.ndarray, fps: float) -> float | None:
    """The rate a video's frames come at (their average: intervals over the time they span)
    when the rate stated for it, ``fps``, is more than twice that:
    no frame rate but the container's time base (a browser's MediaRecorder WebM states
    none: FFmpeg guesses 1000 from its millisecond clock). None when ``fps`` will do."""
    if not usable_times(times):
        return None
    rate = (times.size - 1) / float(times[-1] - times[0])
    return rate if MIN_FPS <= rate and 2.0 * rate < fps else None


def container_frame_times(path: str | Path) -> tuple[np.ndarray, float]:
    """The presentation times (s, in order) the container gives a video's frames and its
    frame rate as :func:`open_video` takes it, read from its packets without decoding them
    (:func:`_packet_times`); decoded (:func:`iter_timed_frames`) where FFmpeg cannot give
    the packets. Raises DataError for a file that is no video."""
    got = _packet_times(path)
    if got is not None:
        times, fps = got
        fps = taken_rate(times, fps)  # as open_video takes it: a 60 fps header stays 60
        if math.isfinite(fps) and MIN_FPS <= fps <= MAX_VIDEO_FPS:
            return times, fps
    _cap, info = open_video(path)
    _cap.release()
    return np.asarray([t for _rgb, t in iter_timed_frames(path)]), info.fps


def variable_rate(path: str | Path) -> bool:
    """Whether a video's frame times (:func:`container_frame_times`) are usable and stray from
    the rate it declares: the videos :func:`estimate_video` resamples."""
    times, fps = container_frame_times(path)
    return clocked_times(times, fps)[1]


def older_vfr_extraction(meta: Mapping[str, Any], video: str | Path) -> bool:
    """Whether a pose file (its metadata ``meta``) was made from ``video``, a
    variable-frame-rate video, by extraction code that timed its frames otherwise than
    today's (:data:`EXTRACTION_VERSION` below 3): its poses differ from what extracting the
    video now gives. A file of version 3 or later is not; one of an older version
    or none (written before the version was) is when its metadata says it was resampled
    (version 2: when its frames lay further apart than is bridged now, :func:`bridge_limit_s`); one
    without the version that does not say so (the oldest code did not notice a variable
    rate) is when the video's frame times, read from its packets (milliseconds, no decoding),
    stray from its declared rate. A constant-rate video's pose file never is: its poses are
    what they were."""
    version = meta.get("extraction_version")
    if isinstance(version, int | float) and version >= 3:
        return False  # timed as today's (version 4 changed which joints are kept, not times)
    vfr = meta.get("variable_frame_rate")
    if isinstance(version, int | float) and version >= 2 and isinstance(vfr, Mapping):
        return _blended_a_gap(vfr)  # version 2 differs only where it blended across a gap
    if vfr is not None:
        return True
    return version is None and variable_rate(video)


def _blended_a_gap(vfr: Mapping[str, Any]) -> bool:
    """Whether a version-2 pose file's resampling record (``variable_frame_rate``) shows
    frames further apart than today's extraction bridges (:func:`bridge_limit_s`): version 2
    blended across them. True when the record cannot tell."""
    try:
        longest = float(vfr["frame_interval_s"]["max"])
        return longest > bridge_limit_s(float(vfr["resampled_to_fps"]))
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return True


def blend(left: Any, right: Any, w: Any) -> Any:
    """``(1 - w) left + w right``, a missing (NaN) value in either staying missing, except
    that a weight within rounding of 0 or 1 takes that side whole (a time on a frame is that
    frame, whatever its neighbour lacks)."""
    mixed = (1.0 - w) * left + w * right
    return np.where(w <= 1e-9, left, np.where(w >= 1.0 - 1e-9, right, mixed))


def bridge_limit_s(fps: float) -> float:
    """The longest time (s) between two decoded frames that resampling to ``fps`` bridges:
    :data:`MAX_BRIDGE_S`, or :data:`BRIDGE_FRAMES` frame intervals if longer."""
    return max(MAX_BRIDGE_S, BRIDGE_FRAMES / fps)


def bridged_weight(elapsed_s: Any, left_s: Any, right_s: Any, fps: float) -> Any:
    """How far grid time ``elapsed_s`` lies from the decoded frame at ``left_s`` to the one
    at ``right_s`` (0: on the left frame, 1: on the right one); NaN (the values there stay
    missing, :func:`blend`) strictly between two frames more than :func:`bridge_limit_s`
    apart: no frame there to infer the motion from."""
    span = np.asarray(right_s) - np.asarray(left_s)
    w = (np.asarray(elapsed_s) - left_s) / span
    inside = (w > 1e-9) & (w < 1.0 - 1e-9)
    return np.where(inside & (span > bridge_limit_s(fps)), np.nan, w)


def _grid_weights(times: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where :func:`resample_to_grid` reads each grid time: (the frame before, its
    :func:`bridged_weight` to the frame after, the frame at or before it)."""
    tau = np.asarray(times, dtype=np.float64) - times[0]
    stray = np.flatnonzero(strays(tau, np.arange(tau.size), fps))
    s = int(stray[0]) if stray.size else tau.size  # frames 0 .. s-1: on the grid
    k = np.arange(s, int((tau[-1] + 1e-9) * fps) + 2)
    grid = k[k / fps <= tau[-1] + 1e-9] / fps  # the grid times after them, to the last frame
    before = np.concatenate([np.arange(s), np.searchsorted(tau, grid, side="right") - 1])
    j = np.clip(before, 0, tau.size - 2)
    t = np.concatenate([tau[:s], grid])  # an on-grid frame: at its own time, weight 0
    return j, bridged_weight(t, tau[j], tau[j + 1], fps), before


def resample_to_grid(
    times: np.ndarray, values: np.ndarray, fps: float
) -> tuple[np.ndarray, np.ndarray]:
    """``values`` (frames first) sampled at ``times`` (s, strictly increasing), put on the
    uniform grid ``times[0] + k / fps``, as ``watch`` puts them as the frames come: the frames
    before the first that :func:`strays` lie on the grid and are taken as they are; every grid
    time from there to the last frame's is the linear interpolation between the decoded frames
    just before and just after it (a grid time on a frame takes that frame's value). A value
    missing (NaN) in either neighbour stays missing, and so does every value at a grid time
    between two frames more than :func:`bridge_limit_s` apart (a gap in the video: no motion
    is made up for it). Returns (the grid values, the index of the frame at or before each
    grid time)."""
    j, w, before = _grid_weights(times, fps)
    w = w.reshape((-1,) + (1,) * (values.ndim - 1))
    return blend(values[j], values[j + 1], w), before


def unbridged_gaps(times: np.ndarray, fps: float) -> tuple[list[tuple[float, float]], np.ndarray]:
    """The gaps :func:`resample_to_grid` leaves missing in frames at ``times`` (s, strictly
    increasing, the first at 0): the (start, end) times (s) of each two frames more than
    :func:`bridge_limit_s` apart, and the grid rows inside them ``(rows,)`` bool."""
    tau = np.asarray(times, dtype=np.float64)
    _j, w, _before = _grid_weights(tau, fps)
    far = np.flatnonzero(np.diff(tau) > bridge_limit_s(fps))
    return [(float(tau[i]), float(tau[i + 1])) for i in far], np.isnan(w)


def resample_timed(
    elapsed: np.ndarray, values: np.ndarray, fps: float
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`resample_to_grid` of a file's frames timed by :func:`clocked_times` (strayed):
    a frame without a time (NaN) is left out, as ``watch`` leaves it out, and the grid is
    made from the others. Returns (the grid values, the index among all the frames of the
    frame at or before each grid time)."""
    timed = np.flatnonzero(np.isfinite(elapsed))
    grid, before = resample_to_grid(elapsed[timed], values[timed], fps)
    return grid, timed[before]


def check_whole(
    count: int,
    declared: int,
    where: str | Path,
    span: float | None = None,
    fps: float | None = None,
) -> None:
    """DataError naming ``where`` when ``count`` frames decoded to the end fall short of the
    ``declared`` frame count the container states (0: none stated; with a small slack for
    containers that estimate it). With ``span`` (s, the decoded frames' times: :func:`span_s`)
    and the declared ``fps``, frames that cover the container's duration (``declared / fps``,
    the same slack) are whole however few: a variable rate has fewer frames than an estimate
    at the declared rate gives."""
    slack = whole_slack(declared)
    if declared > 0 and count + slack < declared:
        if span is not None and fps and span * fps + slack >= declared:
            return
        raise DataError(f"truncated or corrupt: decoded {count} of {declared} frames", where)


def whole_slack(declared: int) -> int:
    """How many frames fewer than the ``declared`` count a video may decode and still be
    whole (:func:`check_whole`): containers that estimate their count are off by a few."""
    return max(2, math.ceil(0.01 * declared))


def frames_before_decoding(path: str | Path) -> tuple[int, int, float] | None:
    """The fewest and most rows :func:`estimate_video` can give a video, and their rate,
    known from its container without decoding a frame (its packets: milliseconds where
    the pose model takes minutes): for a video whose packets give their times, as many as
    the count OpenCV states, and whose times keep to its rate (constant rate: the rows are
    the decoded frames, none resampled), the count less :func:`whole_slack` (fewer is
    refused as truncated) to the count. None when that cannot be trusted: a variable frame
    rate (the rows are a grid known once the frames are decoded), a count the container
    only estimates that its packets do not bear out, no packets to read, or no video."""
    try:
        cap, info = open_video(path)
    except DataError:
        return None  # refused, in its own words, when it is read
    cap.release()
    got = _packet_times(path)
    if got is None or info.frames <= 0 or got[0].size != info.frames:
        return None
    if clocked_times(got[0], info.fps)[1]:
        return None  # strayed: resampled to a grid when decoded
    return max(0, info.frames - whole_slack(info.frames)), info.frames, info.fps


def outside_frame(image_landmarks: np.ndarray, width: int, height: int) -> np.ndarray:
    """``(frames, 33)`` True where a landmark's (x, y) lies outside the ``width x height`` frame."""
    x, y = image_landmarks[..., 0], image_landmarks[..., 1]
    with np.errstate(invalid="ignore"):
        return (x < 0) | (y < 0) | (x >= width) | (y >= height)


MIN_PRESENCE = 0.5
"""The presence (the landmark model's probability that a landmark is in the picture) below
which a landmark the model places inside the frame is not in the picture either: MediaPipe's
own threshold (its drawing utilities leave out a landmark below 0.5). Such a landmark sits at
the frame's edge where the limb leaves it (a knee below the bottom edge put on the thigh), or
stands for a hand or foot the model does not find. Visibility is another thing (in the
picture but hidden: the far side's limbs in a side view, well placed) and is not cut."""


def not_in_picture(image_landmarks: np.ndarray, width: int, height: int) -> np.ndarray:
    """``(..., 33)`` True where a landmark is not in the picture: placed outside the
    ``width x height`` frame (:func:`outside_frame`), or inside it at a presence below
    :data:`MIN_PRESENCE`. :func:`estimate_video` stores these missing (NaN), as ``watch``
    reads them (:attr:`StreamFrame.seen_world`)."""
    with np.errstate(invalid="ignore"):
        unlikely = image_landmarks[..., 4] < MIN_PRESENCE
    return outside_frame(image_landmarks, width, height) | unlikely


PRESENCE_VERSION = 4
"""The :data:`EXTRACTION_VERSION` from which landmarks not in the picture at a presence below
:data:`MIN_PRESENCE` are stored missing (:func:`not_in_picture`)."""


def kept_not_in_picture(
    meta: Mapping[str, Any], positions: np.ndarray, image_landmarks: np.ndarray
) -> int:
    """How many joint positions a pose file (its metadata ``meta``, ``positions`` and stored
    image landmarks) keeps where the model judged the joint not in the picture (presence
    below :data:`MIN_PRESENCE`) though its joints outside the frame were set missing: a file
    of an extraction older than :data:`PRESENCE_VERSION` (today's stores them missing). 0
    for a file of that version or later, one extracted keeping them (``keep_outside``), one
    not made from a video, or image landmarks that do not match its frames."""
    version = meta.get("extraction_version")
    if isinstance(version, int | float) and version >= PRESENCE_VERSION:
        return 0
    if "pose_model" not in meta or meta.get("joints_outside_frame_set_missing") is False:
        return 0
    lm = np.asarray(image_landmarks)
    pos = np.asarray(positions)
    if lm.ndim != 3 or lm.shape[2] < 5 or lm.shape[:2] != pos.shape[:2]:
        return 0
    with np.errstate(invalid="ignore"):
        unlikely = lm[..., 4] < MIN_PRESENCE
    return int((unlikely & np.isfinite(pos).all(axis=2)).sum())


def _room(clock: FrameClock, index: int, max_frames: int | None) -> int:
    """How many frames after frame ``index`` may be read to time it (:attr:`FrameClock.run`,
    no further than ``max_frames``)."""
    return clock.run if max_frames is None else min(clock.run, max_frames - index - 1)


def _looking_ahead(
    frames: Iterable[tuple[np.ndarray, float]], clock: FrameClock, max_frames: int | None
) -> Iterator[tuple[int, np.ndarray, float, list[float]]]:
    """Each frame (its index, image and decoded time, at most ``max_frames``) with the next
    frames' times ``clock`` wants to time it (:meth:`FrameClock.needs_next`: a frame far
    ahead of the last one taken), those frames read ahead and given in their turn. Take each
    frame before the next is asked for."""
    pairs = iter(frames)
    ahead: collections.deque[tuple[np.ndarray, float]] = collections.deque()
    for i in itertools.count() if max_frames is None else range(max_frames):
        read = ahead.popleft() if ahead else next(pairs, None)
        if read is None:
            return
        rgb, t = read
        wanted = min(clock.needs_next(i, t), _room(clock, i, max_frames))
        while len(ahead) < wanted and (more := next(pairs, None)) is not None:
            ahead.append(more)
        yield i, rgb, t, [at for _rgb, at in list(ahead)[:wanted]]


FINER_EVERY_S = 0.2
"""How often :func:`estimate_video` (``extract``) searches the finer tiles (a quarter of the
frame, :data:`.detector.FINER_ZOOM`: 28-35 detector runs, some 0.5 s of CPU) while nobody is
in view, found in neither the whole frame nor the tiles of half: at most once in 0.2 s of
the video (a still picture's one frame is searched), so that a person far away is found
within half the shortest movement (0.4 s) of coming into view and then tracked, while a
stretch with nobody in view costs some 1.7 times what it did (a 640x480 30-fps video: 202-214
ms of CPU a frame, was 119-124), not 6 times."""


def estimate_video(
    video_path: str | Path,
    *,
    smoothing: bool = True,
    tracking: bool = True,
    progress_bar: bool = True,
    estimator: PoseEstimator | None = None,
    metadata: dict[str, object] | None = None,
    max_frames: int | None = None,
    keep_outside: bool = False,
    decode_threads: int | None = None,
    announce: bool = True,
) -> VideoPoses:
    """Run BlazePose over every frame of a video file.

    Returns world landmarks as a canonical pose sequence (fps from the video) plus the image
    landmarks; frames without a person are NaN and listed in ``missing`` (and in the
    sequence's metadata). ``max_frames``: stop after that many frames (the truncation check is
    then skipped). A joint the model places outside the frame (e.g. legs below the bottom
    edge) is not seen, nor one it places inside the frame but judges not in the picture
    (presence below :data:`MIN_PRESENCE`, :func:`not_in_picture`), so its position is set
    missing (NaN) in the sequence unless ``keep_outside``; the image landmarks keep the
    model's guess, its visibility and its presence.
    ``decode_threads``: FFmpeg's decoding threads (None: one per core; see :func:`open_video`).
    A video whose frame times are irregular (variable frame rate: see the module docstring)
    is resampled to a uniform grid at its declared rate; ``announce`` says so in one line on
    stderr, and the metadata's ``variable_frame_rate`` records it.
    Raises :class:`DataError` for a video that cannot be used.
    """
    path = as_path(video_path, "video_path")
    cap, info = open_video(path, decode_threads)  # fail early with a clear reason
    cap.release()
    est = estimator or PoseEstimator(tracking=tracking, smoothing=smoothing)
    est.reset()
    world: list[np.ndarray] = []
    image: list[np.ndarray] = []
    person: list[bool] = []
    times: list[float] = []
    frames = iter_timed_frames(path, decode_threads)
    total = info.frames or None
    if max_frames is not None:
        total = min(total or max_frames, max_frames)
    if progress_bar:
        frames = progress(frames, desc=path.name, total=total, unit="frame")
    clock = FrameClock(info.fps)  # the filters get index / fps until the frames stray
    for i, rgb, t, coming in _looking_ahead(frames, clock, max_frames):
        times.append(clock.take(i, t, coming))  # as watch takes it: NaN where it has none
        pose = est.process(rgb, clock.filter_time(i, times[-1]), finer_every_s=FINER_EVERY_S)
        world.append(pose.world)
        image.append(pose.image)
        person.append(pose.person)
    image_lm = np.stack(image)
    positions = np.stack(world)
    outside = np.zeros(image_lm.shape[:2], dtype=bool)
    unseen = outside
    if not keep_outside:
        outside = outside_frame(image_lm, info.width, info.height)
        unseen = not_in_picture(image_lm, info.width, info.height)
        positions[unseen] = np.nan
    elapsed = np.asarray(times)
    video_frames = None
    vfr: dict[str, object] | None = None
    if not clock.on_grid:  # strayed: on the grid as watch's Regrid puts them
        # a frame that came without a time of its own (missing, repeated or going back)
        # after the frames strayed is left out, as watch leaves it out
        timed = np.flatnonzero(np.isfinite(elapsed))
        both = np.concatenate([positions, image_lm], axis=2)
        nobody = np.where(np.asarray(person), 0.0, np.nan)
        both, video_frames = resample_timed(elapsed, both, info.fps)
        positions, image_lm = both[:, :, :3], both[:, :, 3:]
        person_on_grid = ~np.isnan(resample_timed(elapsed, nobody, info.fps)[0])
        missing = np.flatnonzero(~person_on_grid).tolist()
        vfr, gaps, holes = _resampling_record(
            elapsed, timed, info.fps, clock.went_back, clock.ahead
        )
        notes = [vfr_words(path, info.fps, gaps, holes)]
        notes += [went_back_words(path, clock.went_back)] if clock.went_back else []
        notes += [ahead_words(path, clock.ahead, True)] if clock.ahead else []
        for words in notes if announce else []:
            print(f"note: {shown(words)}", file=sys.stderr)
    else:
        missing = [i for i, p in enumerate(person) if not p]
        if clock.ahead and announce:  # on the grid: timed by their places
            print(f"note: {shown(ahead_words(path, clock.ahead, False))}", file=sys.stderr)
    jumps = _jump_record(path, image_lm, info.fps, announce)
    meta: dict[str, object] = {
        "source_video": str(path),
        "video_fps": info.fps,
        "video_size": [info.width, info.height],
        "pose_model": model_version(),
        "extraction_version": EXTRACTION_VERSION,
        "missing_frames": missing,
        "n_missing_frames": len(missing),
        "smoothing": _smoothing_meta() if est.smoothing else None,
        "tracking": est.tracking,
        "joints_outside_frame_set_missing": not keep_outside,
        "n_joint_samples_outside_frame": int(outside.sum()),
        "min_presence": MIN_PRESENCE,
        "n_joint_samples_not_present": int((unseen & ~outside).sum()),
        "coordinates": "world landmarks, metres, x right, y up, z toward the camera, "
        "origin at the hip centre",
    }
    if vfr is not None:
        meta["variable_frame_rate"] = vfr
    if jumps is not None:
        meta["person_jumps"] = jumps
    meta.update(metadata or {})
    seq = PoseSequence(
        positions=positions,
        joint_names=BLAZEPOSE_33,
        fps=info.fps,
        confidence=image_lm[:, :, 3],
        source=str(path),
        metadata=meta,
    )
    return VideoPoses(seq, image_lm, tuple(missing), info, video_frames)


def _jump_record(
    path: Path, image_lm: np.ndarray, fps: float, announce: bool
) -> dict[str, object] | None:
    """The metadata's ``person_jumps`` of a video's image landmarks (:func:`person_jumps`;
    None without a jump), said in one line on stderr when ``announce``."""
    jumps = person_jumps(image_lm, fps)
    if not jumps:
        return None
    if announce:
        print(f"note: {shown(jump_words(path, jumps, fps))}", file=sys.stderr)
    return {
        "frames": jumps,
        "why": f"the hip centre moved more than {JUMP_TORSOS:g} torso length (or"
        f" {JUMP_TORSOS_PER_S:g} a second) from the frame before: the pose jumped to another"
        " person; repetitions are counted apart on either side, as at a cut",
    }


def _resampling_record(
    elapsed: np.ndarray,
    timed: np.ndarray,
    fps: float,
    went_back: list[tuple[int, float, float]] | None = None,
    ahead: list[tuple[int, float, float, float]] | None = None,
) -> tuple[dict[str, object], np.ndarray, list[tuple[float, float]]]:
    """How :func:`estimate_video` resampled frames at ``elapsed`` (s; ``timed``: those with a
    time; ``went_back``: where the frame times went back, :attr:`FrameClock.went_back`), for
    the metadata's ``variable_frame_rate``; with the frame intervals and the gaps left missing
    (:func:`unbridged_gaps`), for the note."""
    gaps = np.diff(elapsed[timed])
    holes, unbridged = unbridged_gaps(elapsed[timed], fps)
    vfr = {
        "resampled_to_fps": fps,
        "decoded_frames": int(elapsed.size),
        "frame_interval_s": {
            "min": round(float(gaps.min()), 6),
            "max": round(float(gaps.max()), 6),
        },
        "method": "linear interpolation between the decoded frames around each grid time;"
        " missing in either stays missing; none between frames more than"
        f" {bridge_limit_s(fps):g} s apart (a gap: missing)",
    }
    if holes:
        rows = np.flatnonzero(unbridged)
        vfr["gaps_left_missing"] = {
            "longer_than_s": round(bridge_limit_s(fps), 6),
            "gaps": [_gap_record(a, b, rows, fps) for a, b in holes],
            "n_rows": int(rows.size),
            "why": "no decoded frame in between: the motion there cannot be inferred, so"
            " the grid times inside are missing (NaN), not interpolated",
        }
    if timed.size < elapsed.size:
        untimed = np.setdiff1d(np.arange(elapsed.size), timed)
        vfr["frames_left_out"] = {
            "frames": untimed.tolist(),
            "why": "no time of its own after the frames strayed (missing, repeated,"
            " earlier than the frame before or stamped far ahead of the frames either"
            " side): left out, as watch leaves it out",
        }
    if went_back:
        vfr["clock_went_back"] = {
            "frames": [frame for frame, _before, _at in went_back],
            "why": "a frame's time earlier than the frame's before, and the next frame's"
            " running on from it (a clock reset, or more frames in a row stamped far ahead"
            " than a bridged gap holds): that frame left out, the later ones timed on from"
            " the frame before it",
        }
    if ahead:
        vfr["stamped_ahead"] = {
            "frames": [frame for frame, _before, _at, _after in ahead],
            "why": "a frame's time far after the frame's before (more than a bridged gap), alone"
            " or a few in a row (no more than a bridged gap holds), and the next frame's"
            " between the two: those frames alone out of place, left out, the later ones keep"
            " their own times",
        }
    return vfr, gaps, holes


def _gap_record(start: float, end: float, rows: np.ndarray, fps: float) -> dict[str, object]:
    """A gap's entry in a pose file's ``gaps_left_missing``: its start and end (s, the frames
    either side, from the first frame), its length and the grid rows inside it left missing
    (first, and one past the last; None when the gap holds no grid time)."""
    inside = rows[(rows / fps > start) & (rows / fps < end)]
    return {
        "start_s": round(start, 6),
        "end_s": round(end, 6),
        "seconds": round(end - start, 6),
        "rows": [int(inside[0]), int(inside[-1]) + 1] if inside.size else None,
    }


def gap_words(holes: list[tuple[float, float]]) -> str:
    """``holes`` (start, end: s) said in a few words: "3.0 s without frames at 2.0-5.0 s left
    missing"; of several, the longest and how many."""
    if not holes:
        return ""
    start, end = max(holes, key=lambda h: h[1] - h[0])
    words = f"{end - start:.1f} s without frames at {start:.1f}-{end:.1f} s"
    if len(holes) > 1:
        words = f"{len(holes)} gaps without frames (the longest {words})"
    return f"{words} left missing"


def vfr_words(
    path: str | Path, fps: float, gaps: np.ndarray, holes: list[tuple[float, float]] | None = None
) -> str:
    """The one line that tells a user a video was resampled (``gaps``: its frame intervals;
    ``holes``: the gaps left missing, :func:`unbridged_gaps`)."""
    line = (
        f"{path}: variable frame rate (frames {gaps.min() * 1000:.0f} to"
        f" {gaps.max() * 1000:.0f} ms apart): poses resampled to {fps:g} fps"
    )
    return f"{line}; {gap_words(holes)}" if holes else line


def went_back_words(path: str | Path, went_back: list[tuple[int, float, float]]) -> str:
    """The line that tells a user a video's frame times went back (:attr:`FrameClock.went_back`:
    the first place, and how many there were)."""
    frame, before, at = went_back[0]
    line = (
        f"{path}: the frame times go back at frame {frame} ({at:.3f} s after {before:.3f} s):"
        f" frame {frame} left out, the frames after it timed on from the one before it"
    )
    return f"{line} ({len(went_back)} such places)" if len(went_back) > 1 else line


def ahead_words(
    path: str | Path, ahead: list[tuple[int, float, float, float]], strayed: bool
) -> str:
    """The line that tells a user a frame of a video was stamped far ahead of the frames
    either side (:attr:`FrameClock.ahead`: the first, and how many there were); ``strayed``:
    the frames had strayed from the grid (the frame is left out), else it is timed by its
    place in the file."""
    frame, before, at, after = ahead[0]
    what = f"frame {frame} left out" if strayed else f"frame {frame} timed by its place"
    line = (
        f"{path}: frame {frame} is stamped {at:.3f} s, far ahead of the frames either side"
        f" ({before:.3f} and {after:.3f} s): {what}, the frames after it keep their times"
    )
    return f"{line} ({len(ahead)} such frames)" if len(ahead) > 1 else line


def _smoothing_meta() -> dict[str, object]:
    return {
        "image": vars(IMAGE_FILTER),
        "world": vars(WORLD_FILTER),
        "roi": vars(AUX_FILTER),
        "visibility_lowpass_alpha": VISIBILITY_ALPHA,
    }


def estimate_poses(
    video_path: str | Path, *, smoothing: bool = True, progress: bool = True
) -> PoseSequence:
    """BlazePose world landmarks of a video as a canonical :class:`PoseSequence`.

    positions ``(frames, 33, 3)`` metres (x right, y up, z toward the camera, hip centre at
    the origin), confidence = visibility, NaN for frames with no person (listed in
    ``metadata["missing_frames"]``), fps from the video, ``source`` = the path.
    """
    return estimate_video(video_path, smoothing=smoothing, progress_bar=progress).sequence


@dataclass(frozen=True)
class StreamFrame:
    """One frame of a live stream: its index, time (s: the frame rate's for a file, the wall
    clock's for a live source), the pose, and when it was read from the source
    (``time.perf_counter()``, before the pose was estimated: latency is measured from it)."""

    index: int
    time_s: float
    pose: FramePose
    rgb: np.ndarray
    read_at: float = float("nan")
    video_time_s: float = float("nan")
    """A file's frame: its presentation time as the decoder gives it, from the first frame's
    (s; NaN for a live source, or when the decoder gives none it can be trusted with:
    :class:`FrameClock`). A variable frame rate shows in it, not in ``time_s``."""
    last: bool = False
    """A file's frame at :func:`stream_poses`'s ``max_frames`` that the file ends with (no
    frame after it: the whole file was read, not cut by the limit); False for every other
    frame (a live source's: not known)."""

    @property
    def seen_world(self) -> np.ndarray:
        """The world landmarks ``(33, 3)`` as :func:`estimate_video` stores them: a joint the
        model places outside the frame, or judges not in the picture, is not seen, so it is
        missing (NaN) (:func:`not_in_picture`)."""
        height, width = self.rgb.shape[:2]
        world = self.pose.world.copy()
        world[not_in_picture(self.pose.image, width, height)] = np.nan
        return world

    @property
    def visibility(self) -> np.ndarray:
        """Each landmark's visibility ``(33,)`` (the sequence's confidence offline)."""
        return np.asarray(self.pose.image[:, 3])


@contextmanager
def _quiet_opencv() -> Iterator[None]:
    """OpenCV's own warnings kept off stderr meanwhile (posecbr reports what matters)."""
    logging = getattr(getattr(cv2, "utils", None), "logging", None)
    if logging is None:
        yield
        return
    level = logging.getLogLevel()
    logging.setLogLevel(logging.LOG_LEVEL_ERROR)
    try:
        yield
    finally:
        logging.setLogLevel(level)


def _open_quietly(device: int | str, timeout_s: float | None = None) -> cv2.VideoCapture:
    """Open a camera or stream without OpenCV's own warnings on stderr (posecbr reports).
    ``timeout_s``: for a stream URL, how long opening it may wait for the server (FFmpeg's
    default is 30 s, whatever the caller's patience; reads keep theirs: a stream that stalls
    later is the caller's to notice, not an end of the stream)."""
    with _quiet_opencv():
        if isinstance(device, str) and timeout_s is not None:
            ms = max(1, round(timeout_s * 1000))
            cap = cv2.VideoCapture(device, cv2.CAP_ANY, [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, ms])
        else:
            cap = cv2.VideoCapture(device)
    if cap.isOpened():
        refuse_text(cap, str(device))
    return cap


def _frame_count(cap: cv2.VideoCapture) -> int:
    """The frame count an open capture's container states, 0 when it states none."""
    frames = float(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0.0)
    return int(frames) if math.isfinite(frames) and frames > 0 else 0


NONE_SERVED = (
    "read none of the {} frames the served file holds: truncated or corrupt, or its index"
    " comes at its end (as cameras often write MP4 and MOV files) and the server does not"
    " answer range requests (python -m http.server does not)"
)
"""Why a file served over the network gave no frame though its container states some."""


RATE_WINDOW_S = 10.0
"""How much of a file served over the network (s of its frames, from the first)
:func:`served_file_rate` reads ahead for the frames' own rate when the rate it states is a
clock's ticks (:func:`own_rate`: a browser's WebM): the whole file when it is shorter, as for
a file on this machine; not the whole stream before the first frame is watched."""


def served_file_rate(url: str, timeout_s: float | None = None) -> float | None:
    """The frame rate of a stream URL that is a video file served over the network, None for
    a live stream (a camera's) and for one that cannot be opened (:func:`stream_poses`
    reports that). A file is one whose frame count OpenCV knows, or, when it knows none (a
    raw ``.h264`` stream, a browser's WebM without a duration), one an HTTP(S) server gives
    whole (:func:`.served.served_whole`). The rate is the one OpenCV states, or, when that is a
    clock's ticks (above :data:`SUSPECT_FPS`, more than twice the frames' own), the frames'
    own average rate over their first :data:`RATE_WINDOW_S` seconds (read from the packets,
    not decoded), as :func:`open_video` takes it for a file here. ``timeout_s``: how long
    the server may take to answer; one that says nothing for that long raises DataError
    (the stream stalled)."""
    started = time.perf_counter()
    cap = _open_quietly(url, timeout_s)
    try:
        if not cap.isOpened():
            if timeout_s is not None and time.perf_counter() - started >= timeout_s:
                raise DataError(f"the stream stalled: no frame for {timeout_s:g} s", url)
            return None
        frames = _frame_count(cap)
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    finally:
        cap.release()
    if not (math.isfinite(fps) and 0 < fps <= MAX_VIDEO_FPS):
        return None
    if not frames and not served_whole(url, timeout_s):
        return None  # a live stream: it has no end to know
    if fps > SUSPECT_FPS:
        got = _packet_times(url, RATE_WINDOW_S, timeout_s)
        if got is not None:
            fps = taken_rate(got[0], fps)
    return fps


def _is_path(source: int | str | Path) -> TypeGuard[str | Path]:
    """Whether a stream source is a video file's path (not a camera index or a URL)."""
    return isinstance(source, Path) or (
        isinstance(source, str) and "://" not in source and not source.isdigit()
    )


def _open_source(
    source: int | str | Path, fps: float | None, timeout_s: float | None
) -> tuple[Capture, float | None, int, bool, int]:
    """:func:`stream_poses`'s source opened: the capture, the frame rate it is timed by (None:
    a live source, the wall clock), the frame count its container states (0: none; a file
    served over the network, ``fps`` given, must hold them all, as a file must), whether
    it is such a served file and how its frames are turned to be seen (:func:`upright`: a
    still picture's EXIF orientation, a video's display matrix that mirrors its frames, less
    the mirror, a served file's too, :func:`_served_turn`; else 1). A ``file:`` URL's file is
    opened as its path is (:func:`open_video`'s checks: a WebM cut short), the path being
    what follows ``file:``, as FFmpeg reads it, and is no served file (what it lacks is said
    as for its path)."""
    if _is_path(source):
        cap, info = open_video(source)
        return cap, info.fps, info.frames, False, info.orientation
    if isinstance(source, str) and source.startswith("file:") and fps is not None:
        cap, info = open_video(source[len("file:") :])
        return cap, info.fps, info.frames, False, info.orientation
    if not isinstance(source, int | np.integer | str | os.PathLike):  # None: "cannot open"
        raise InputError(
            f"must be a camera index, a stream URL or a file path, got {source!r}", "source"
        )
    if isinstance(source, bool) or (isinstance(source, int) and source < 0):
        # OpenCV's "any camera", -1, crashes the process (a segmentation fault) where none is
        raise InputError(
            f"a camera index is a whole number from 0 (the first camera), got {source!r}",
            "source",
        )
    device = source if isinstance(source, int) else str(source)
    camera = isinstance(device, int) or device.isdigit()
    not_opened = NO_CAMERA if camera else "cannot open stream"
    try:
        cap = _open_quietly(int(device) if camera else device, timeout_s)
    except (cv2.error, OverflowError):  # an index too large for OpenCV (a C int)
        raise DataError(not_opened, str(source)) from None
    if not cap.isOpened():
        # a file the server gives whole, cut before its index (an MP4's, at its end), or a
        # server that gives no video (an error status, no server, a web page): said so
        why = None
        if _served_url(device):
            why = served_cut(str(device), timeout_s) or served_refusal(str(device), timeout_s)
        raise DataError(why or not_opened, str(source))
    if fps is None:
        return cap, None, 0, False, 1
    declared = _frame_count(cap)
    stated = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    if declared and math.isfinite(stated) and stated > fps:
        # a clock's ticks, not a frame rate (served_file_rate): the count OpenCV gives is
        # the duration at that rate; at the frames' own rate it is this many
        declared = int(declared * fps / stated)
    cap, turn = _served_turn(cap, str(device), timeout_s)
    return cap, fps, declared, True, turn


def _served_turn(cap: cv2.VideoCapture, url: str, timeout_s: float | None) -> tuple[Capture, int]:
    """The capture to read the frames of ``cap``, a file an HTTP(S) server gives whole at
    ``url``, from and how they are turned to be seen (:func:`upright`), or refused, as
    :func:`open_video` reads, turns and refuses a file here, from the bytes it reads of the
    file (:func:`.served.served_file`: its start, and, where the server answers range
    requests, its index at its end): an MP4/MOV whose display matrix mirrors its frames is
    turned as the matrix says less its mirror, one whose first video track is a lesser one
    refused (:func:`_tracks_turn`); a HEIF photo of which OpenCV decodes a part is read
    whole from its tiles, or refused (:func:`_whole_picture`: where they cannot be read
    too); a still picture is turned by
    its EXIF orientation (:func:`.containers.picture_orientation`). ``cap`` and 1 (OpenCV's
    own turning) for any other file and where those bytes cannot be read (a server that
    does not answer range requests, an index too large: :class:`.served.Unread`), as
    before."""
    served = served_file(url, timeout_s)
    if served is None:
        return cap, 1
    head = served.start[:512]
    try:
        if is_mp4(head) and heif_brand(head) is None:
            return cap, _tracks_turn(cap, url, mp4_video_tracks(served, served.length), 1)
        if heif_brand(head) is None:
            return cap, picture_orientation(served, head)
        picture = heif_picture(served, served.length, head)
    except Unread:
        return cap, 1
    width = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH) or 0)
    height = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0)
    if picture is None or (_as_decoded(picture, width, height) and not picture.ranges):
        return cap, 1
    try:
        grid = heif_grid(served, served.length, head)
    except Unread:  # its tiles lie past what is read of a served file: refused, as before
        grid = None
    return _whole_picture(cap, url, picture, grid, (width, height)), 1


NO_CAMERA = "cannot open camera: none at this index, or another program holds it"
"""Why a camera index gave no camera (OpenCV says no more than that it opened none)."""


def _served_url(device: int | str) -> bool:
    """Whether a source that is not a path is an HTTP(S) URL (a server may give a file)."""
    return isinstance(device, str) and device.lower().startswith(("http://", "https://"))


def _grab(cap: Any, fps: float | None) -> tuple[bool, None, float]:
    """The next frame grabbed (demuxed and decoded), not read: whether there is one, no
    image yet, and its time (s, as decoded; NaN for a live source, timed by the wall
    clock)."""
    ok = bool(cap.grab())
    return ok, None, frame_time_s(cap) if ok and fps else math.nan


def _ends(cap: Any, queue: collections.deque[tuple[bool, Any, float]], fps: float) -> bool:
    """Whether a file's frame just read is its last: the next frame grabbed (into ``queue``
    when none was read ahead) is not there."""
    if not queue:
        queue.append(_grab(cap, fps))
    return not queue[0][0]


def _read_ahead(
    cap: Any, queue: collections.deque[tuple[bool, Any, float]], wanted: int
) -> list[float]:
    """The next ``wanted`` frames' decoded times (s), those not read yet read (grabbed and
    retrieved, in order) into ``queue`` (whether each is there, its image, its time), up to
    the end of the file."""
    while len(queue) < wanted and not (queue and not queue[-1][0]):
        ok = bool(cap.grab())
        t = frame_time_s(cap) if ok else math.nan
        bgr = None
        if ok:
            ok, bgr = cap.retrieve()
            ok = bool(ok) and bgr is not None
        queue.append((ok, bgr, t))
    times = []
    for ok, _bgr, t in list(queue)[:wanted]:
        if not ok:
            break
        times.append(t)
    return times


def _clocked(
    cap: Any,
    clock: FrameClock,
    frame: tuple[int, float, Any],
    room: int,
    queue: collections.deque[tuple[bool, Any, float]],
    source: Any,
) -> tuple[bool, Any, float]:
    """A frame (its index, decoded time and image: None when grabbed, not read yet) timed by
    ``clock`` as :func:`stream_poses` takes it, its notes said as they come. A frame far
    ahead of the last one (:meth:`FrameClock.needs_next`) is read first and the next ones
    (as many as the clock wants, at most ``room``) read into ``queue`` for their times, as
    :func:`estimate_video` reads them: (whether this frame is there, its image when read
    already, its time)."""
    index, time_s, bgr = frame
    ok, coming = True, []
    wanted = min(clock.needs_next(index, time_s), room)
    if wanted > 0:
        if bgr is None:  # read before the next frame is grabbed
            ok, bgr = cap.retrieve()
            ok = bool(ok) and bgr is not None
        if ok:
            coming = _read_ahead(cap, queue, wanted)
    went_back, ahead = len(clock.went_back), len(clock.ahead)
    video_t = clock.take(index, time_s, coming)
    if len(clock.went_back) > went_back:  # said as it comes, as a gap is
        words = went_back_words(str(source), clock.went_back[-1:])
        print(f"note: {shown(words)}", file=sys.stderr)
    if len(clock.ahead) > ahead:
        words = ahead_words(str(source), clock.ahead[-1:], not clock.on_grid)
        print(f"note: {shown(words)}", file=sys.stderr)
    return bool(ok), bgr, video_t


STREAM_CLOSER_EVERY_S = 0.5
"""How often :func:`stream_poses` searches a frame's tiles for a person too small for the
whole frame (:meth:`.tracker.PoseEstimator.detect_closer`: six detector runs, about six times
a frame's detection) while nobody is in view: on every such frame a camera's frames would fall
behind; once in half a second costs a fraction of one core and finds a person who comes into
view within a quarter of the 2-s window a segment is judged on. Timed by the frames' own
times, so a file watched gives the same poses however fast the machine."""


STREAM_FINER_EVERY_S = 2.0
"""How often :func:`stream_poses` begins a search of the finer tiles (a quarter of the frame,
:data:`.detector.FINER_ZOOM`: 28-35 detector runs, some 0.5 s of CPU) while nobody is in
view, found in neither the whole frame nor the tiles of half: once in a window's length
(2 s), so that the search costs a camera at 30 fps some 10 ms of CPU a frame on average."""

STREAM_TILES_PER_FRAME = 1
"""How many tiles :func:`stream_poses` searches in one frame at most, both sizes counted:
the tiles of half the frame, when due, take all six (as before the finer tiles); the finer
tiles' search is spread one a frame over the frames after (35 over a 640x480 frame: 1.2 s at
30 fps), so that a frame costs at most two detector runs more than the whole frame's: with
six a frame (a sweep of 5-6 frames, each some 45 ms on two idle cores) a 640x480 30-fps watch
fell behind over every sweep, its labels' 95th percentile 0.22-0.31 s after their frames
against 0.06-0.07 s before the finer tiles; one a frame, 0.08-0.13 s (measured on 10 s of an
empty room then the lunge video, idle machine); 35 in one frame stalled a watch on a loaded
machine for over 5 s."""


def stream_poses(
    source: int | str | Path,
    *,
    smoothing: bool = True,
    max_frames: int | None = None,
    estimator: PoseEstimator | None = None,
    fps: float | None = None,
    timeout_s: float | None = None,
    pace: Callable[[int, float], bool] | None = None,
    alive: Callable[[], None] | None = None,
) -> Iterator[StreamFrame]:
    """Poses frame by frame from a webcam index (from 0; InputError for a negative one or
    a bool), a stream URL or a video path.

    Files are timed by their frame rate; live sources by the wall clock, or by ``fps`` when
    given (a file served over the network: :func:`served_file_rate`). Stops at the end of
    the stream, after ``max_frames``, or when the consumer stops iterating. A file, or a
    file served over the network (``fps`` given), that ends before the frame count its
    container states raises DataError, as :func:`iter_frames` does; so does a served
    MP4/MOV, Matroska/WebM or FLV file cut short (:func:`.served.served_cut`), as a file here
    is (one that does not open: said so in place of "cannot open").
    ``timeout_s``: how long a stream URL may take to open (FFmpeg's default: 30 s).
    ``pace``: called with each
    frame's index and ``video_time_s`` once it is decoded and before it is read (its
    ``read_at``) and its pose estimated; it may wait (a file played at its own rate) and
    returns False to stop the stream there. ``alive``: called while a served file is read
    again at its end (:func:`.served.served_cut`): no frame comes meanwhile.

    The source is opened when this is called, not at the first frame asked for: a camera,
    URL or file that cannot be opened is refused here (DataError, InputError), before the
    caller's own preparations for the frames (``posecbr watch``'s warm-up: a mistyped URL
    was said seconds late).
    """
    # served: over a network; turn: a still picture's EXIF orientation
    opened = _open_source(source, fps, timeout_s)
    return _streamed(source, opened, smoothing, max_frames, estimator, timeout_s, pace, alive)


def _streamed(
    source: int | str | Path,
    opened: tuple[Capture, float | None, int, bool, int],
    smoothing: bool,
    max_frames: int | None,
    estimator: PoseEstimator | None,
    timeout_s: float | None,
    pace: Callable[[int, float], bool] | None,
    alive: Callable[[], None] | None,
) -> Iterator[StreamFrame]:
    """:func:`stream_poses`'s frames from its source ``opened`` (:func:`_open_source`)."""
    cap, fps, declared, served, turn = opened
    est = estimator or PoseEstimator(smoothing=smoothing)
    est.reset()
    start = time.perf_counter()
    index = 0
    times: list[float] = []  # a file's frame times (s), as the decoder gives them
    clock = FrameClock(fps or 1.0)
    # the next frames, read to time a frame far ahead of the last (whether each is there,
    # its image, its time)
    queue: collections.deque[tuple[bool, Any, float]] = collections.deque()
    try:
        while max_frames is None or index < max_frames:
            # grabbed (demuxed and decoded), then timed, paced and only then taken: a paced
            # frame is read when it is due, as a camera would deliver it
            ok, bgr, raw_t = queue.popleft() if queue else _grab(cap, fps)
            video_t = float("nan")
            if ok and fps:
                times.append(raw_t)
                room = _room(clock, index, max_frames)
                ok, bgr, video_t = _clocked(cap, clock, (index, raw_t, bgr), room, queue, source)
            if ok and pace is not None and not pace(index, video_t):
                break
            if bgr is None:
                ok, bgr = cap.retrieve() if ok else (False, None)
            read_at = time.perf_counter()
            if not ok or bgr is None:  # read to its end: all of it
                cut = served_cut(str(source), timeout_s, alive) if served else None
                if cut is not None:  # an MP4, WebM or FLV cut on the server: it ended there
                    raise DataError(cut, str(source))
                if served and index == 0 and declared:
                    raise DataError(NONE_SERVED.format(declared), str(source))
                span = span_s(times, fps) if fps else None
                try:
                    check_whole(index, declared, str(source), span, fps)
                except DataError:
                    # a file whole on the server: its count was its duration (its longest
                    # track's: sound running on), its frames are what came
                    if not (served and served_whole_by_duration(str(source), timeout_s)):
                        raise
                break
            t = index / fps if fps else read_at - start
            rgb = cv2.cvtColor(upright(bgr, turn), cv2.COLOR_BGR2RGB)
            # as estimate_video times the filters: index / fps until the frames stray
            at = clock.filter_time(index, video_t) if fps else t
            last = fps is not None and index + 1 == max_frames and _ends(cap, queue, fps)
            pose = est.process(
                rgb,
                at,
                closer_every_s=STREAM_CLOSER_EVERY_S,
                finer_every_s=STREAM_FINER_EVERY_S,
                tiles_per_frame=STREAM_TILES_PER_FRAME,
            )
            yield StreamFrame(index, t, pose, rgb, read_at, video_t, last)
            index += 1
    finally:
        cap.release()
