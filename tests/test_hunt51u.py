"""A HEIF picture's transformative properties, and a full disk under an overlay (hunt 51u).

HEIF (ISO/IEC 23008-12) turns a picture as seen by the transformative properties its ipma
box lists for it, applied in that order, as libheif applies them: ``irot`` (quarter turns
counter-clockwise), ``imir`` (axis 0: upside down; 1: left to right) and ``clap`` (a clean
aperture: the window of the given width and height centred at the picture's centre plus the
given offsets, its left edge rounded down, its top to the nearest). OpenCV (FFmpeg's mov
demuxer) applied a picture coded whole's irot and read its imir as a turn (axis 0 not at
all, axis 1 as a half turn) and its clap not at all; a grid's clap was ignored. The
expected pictures here are made with numpy from the picture before it was coded.

OpenCV's video writer only warns when a write fails, so an overlay written to a full disk
was refused as "N frames encoded but 0 read back"; it now says the disk is full, as the
case base store says it.
"""

from __future__ import annotations

import os
import struct
import subprocess
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image, features

from features.errors import DataError
from features.pose_estimation import iter_frames
from features.pose_estimation.overlay import write_overlay
from tests.badinput import ROOT, read_only_mounts_work
from tests.test_hunt50e import _box, _full


def _quarters() -> np.ndarray:
    """A 96x64 picture of four grey quarters (40, 100, 160, 220 from the top left, by rows):
    grey, so that coding its colour at half resolution (4:2:0) moves no edge; a picture read
    a pixel off is 60 or more levels off along an edge."""
    grey = np.zeros((64, 96, 3), np.uint8)
    grey[:32, :48], grey[:32, 48:], grey[32:, :48], grey[32:, 48:] = 40, 100, 160, 220
    return grey


def _read(path: Path) -> np.ndarray:
    (frame,) = list(iter_frames(path))
    return frame


#: what Pillow writes an AVIF's EXIF orientation as (an irot, an imir, or both), and the
#: picture a viewer shows for it (the EXIF standard's: 2 mirrored left to right, 4 upside
#: down, 5 mirrored about the main diagonal, 7 about the other)
EXIF_SHOWN: dict[int, Callable[[np.ndarray], np.ndarray]] = {
    2: lambda a: a[:, ::-1],
    4: lambda a: a[::-1],
    5: lambda a: a.swapaxes(0, 1),
    7: lambda a: a[::-1, ::-1].swapaxes(0, 1),
}


@pytest.mark.skipif(not features.check("avif"), reason="Pillow without AVIF")
@pytest.mark.parametrize("orientation", sorted(EXIF_SHOWN))
def test_an_avif_coded_whole_that_its_properties_mirror_is_read_as_shown(
    orientation: int, tmp_path: Path
) -> None:
    """Pillow (libavif) writes a picture given EXIF orientation 2, 4, 5 or 7 as an AVIF coded
    whole whose imir (and irot) properties say how it is shown. Before, OpenCV's turn was
    taken: 2 and 4 a half turn or none, each quarter of the picture 120 levels off."""
    path = tmp_path / f"mirrored{orientation}.avif"
    exif = Image.Exif()
    exif[0x0112] = orientation
    Image.fromarray(_quarters()).save(path, exif=exif, quality=90)
    assert b"imir" in path.read_bytes()
    expected = EXIF_SHOWN[orientation](_quarters())
    frame = _read(path)
    assert frame.shape == expected.shape
    assert np.abs(frame.astype(int) - expected).max() <= 8


def _heic(rgb: np.ndarray, turns: Sequence[bytes]) -> bytes:
    """``rgb`` coded whole by x265 as a HEIC of one picture (the primary item), with its
    ispe, then the properties ``turns`` (irot, imir, clap boxes) in that order."""
    from tests.test_hunt51f import _hevc_tile

    config, data = _hevc_tile(rgb)
    h, w = rgb.shape[:2]
    props = [config, _full(b"ispe", struct.pack(">II", w, h)), *turns]
    assoc = struct.pack(">HB", 1, len(props)) + bytes([0x81, *range(2, len(props) + 1)])

    def meta(offset: int) -> bytes:
        return _full(
            b"meta",
            _full(b"hdlr", b"\0\0\0\0pict" + b"\0" * 13)
            + _full(b"pitm", struct.pack(">H", 1))
            + _full(
                b"iloc", struct.pack(">BBHHHHHII", 0x44, 0, 1, 1, 0, 0, 1, offset, len(data)), 1
            )
            + _full(b"iinf", struct.pack(">H", 1) + _full(b"infe", b"\0\1\0\0hvc1\0", 2))
            + _box(
                b"iprp",
                _box(b"ipco", b"".join(props)) + _full(b"ipma", struct.pack(">I", 1) + assoc),
            ),
        )

    ftyp = _box(b"ftyp", b"heic\0\0\0\0mif1heic")
    start = len(ftyp) + len(meta(0)) + 8  # the mdat's body
    return ftyp + meta(start) + _box(b"mdat", data)


def _clap(width: int, height: int, across: tuple[int, int], down: tuple[int, int]) -> bytes:
    """A clean aperture ``width`` x ``height`` whose centre lies ``across`` and ``down``
    (fractions: numerator, denominator) from the picture's."""
    return _box(b"clap", struct.pack(">IIIIiIiI", width, 1, height, 1, *across, *down))


#: the transformative properties (in their order) and the picture shown, worked out by hand:
#: a clean aperture's first column is its centre's, the picture's (width - 1) / 2 plus its
#: offset, less (its width - 1) / 2, rounded down; its first row the same, rounded to the
#: nearest (as libheif does; libheif decoded these files to within 1 level of these)
TURNED: dict[str, tuple[list[bytes], Callable[[np.ndarray], np.ndarray]]] = {
    "upside down": ([_box(b"imir", b"\0")], lambda a: a[::-1]),
    "left to right": ([_box(b"imir", b"\1")], lambda a: a[:, ::-1]),
    "mirrored, then a quarter turn": (
        [_box(b"imir", b"\0"), _box(b"irot", b"\1")],
        lambda a: np.rot90(a[::-1], 1),
    ),
    # 41 x 25 about (47.5 + 3.5, 31.5 - 3): columns from 51 - 20 = 31, rows from 28.5 - 12 =
    # 16.5, to the nearest 17; then mirrored left to right, turned 3 quarters
    "cropped, mirrored, turned": (
        [_clap(41, 25, (7, 2), (-3, 1)), _box(b"imir", b"\1"), _box(b"irot", b"\3")],
        lambda a: np.rot90(a[17:42, 31:72, :][:, ::-1], 3),
    ),
    # turned first: 64 wide, 96 high; 33 x 31 about (31.5 + 4.5, 47.5 - 5.5): columns from
    # 36 - 16 = 20, rows from 42 - 15 = 27
    "turned, then cropped": (
        [_box(b"irot", b"\1"), _clap(33, 31, (9, 2), (-11, 2))],
        lambda a: np.rot90(a, 1)[27:58, 20:53],
    ),
}


@pytest.mark.parametrize(
    ("name", "coded"),
    [(name, "whole") for name in TURNED]
    + [(name, "in tiles") for name in TURNED if "crop" in name],
)
def test_a_heic_is_turned_mirrored_and_cropped_in_its_properties_order(
    name: str, coded: str, tmp_path: Path
) -> None:
    """The grey quarters coded whole, or in 64x64 tiles put together by a grid (2 x 1, the
    second cropped; its irot and imir alone: tests/test_hunt51f.py), with the properties of
    :data:`TURNED`: the picture read is the one they show. Before: coded whole, OpenCV's
    turn (an imir read as a half turn or none, a clap not applied); in tiles, a clap
    ignored."""
    av = pytest.importorskip("av")
    try:
        av.codec.Codec("libx265", "w")
    except (ValueError, av.FFmpegError):
        pytest.skip("PyAV without the x265 encoder")
    from tests.test_hunt51f import _heic_grid

    turns, shown = TURNED[name]
    path = tmp_path / "turned.heic"
    path.write_bytes(
        _heic(_quarters(), turns) if coded == "whole" else _heic_grid(_quarters(), 64, turns)
    )
    expected = shown(_quarters())
    frame = _read(path)
    assert frame.shape == expected.shape
    assert np.abs(frame.astype(int) - expected).max() <= 8


def _noise_video(path: Path) -> Path:
    """Three frames of 320x240 noise at 5 fps (MP4, mp4v): some 30 kB each once coded."""
    rng = np.random.default_rng(51)
    out = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), 5.0, (320, 240))
    for _ in range(3):
        out.write(rng.integers(0, 256, (240, 320, 3), np.uint8))
    out.release()
    return path


def _overlay(video: Path, folder: Path) -> None:
    write_overlay(video, np.full((3, 33, 5), np.nan), folder / "over.mp4", 5.0)


#: in a private tmpfs of 16 kB mounted on the folder sys.argv[2]: the overlay of the video
#: sys.argv[1], then its frames recorded as ``watch --out`` records them (a NUT file beside
#: the MP4, copied into it); what each says, the folder's files after
FULL_DISK = """
import sys
from pathlib import Path
import cv2
import numpy as np
from features.errors import DataError
from features.pose_estimation.overlay import write_overlay
from features.pose_estimation.recording import Recording
folder = Path(sys.argv[2])
try:  # as _overlay
    write_overlay(sys.argv[1], np.full((3, 33, 5), np.nan), folder / "over.mp4", 5.0)
except DataError as exc:
    print(exc)
print(sorted(p.name for p in folder.iterdir()))
recording = Recording(folder / "w.nut", 5.0, (320, 240), "w.mp4")
cap = cv2.VideoCapture(sys.argv[1])
while (got := cap.read())[0]:
    recording.write(got[1])
try:
    recording.to_mp4(folder / "w.mp4")
except DataError as exc:
    print(exc)
"""


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private mount (unshare -rm, mount)",
)
def test_an_overlay_written_to_a_full_disk_says_the_disk_is_full(tmp_path: Path) -> None:
    """Before: "cannot write: 3 frames encoded but 0 read back", OpenCV's writer's failed
    writes seen only in the file it left; ``watch --out``'s recording: "cannot write: the
    video could not be copied to MP4"."""
    video = _noise_video(tmp_path / "noise.mp4")
    folder = tmp_path / "small"
    folder.mkdir()
    mount = f'mount -t tmpfs -o size=16k tmpfs {folder} || exit 99; exec "$0" "$@"'
    done = subprocess.run(
        ["unshare", "-rm", "sh", "-c", mount, sys.executable, "-c", FULL_DISK, str(video),
         str(folder)],
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True,
        timeout=120,
    )  # fmt: skip
    if done.returncode == 99:
        pytest.skip("no tmpfs can be mounted here")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        f"{folder / 'over.mp4'}: cannot write: the disk is full (3 frames encoded but 0 read"
        " back): free some space and run again",
        "[]",
        "w.mp4: cannot write: the disk is full (the video could not be copied to MP4): free"
        " some space and run again",
    ]


def test_an_overlay_past_a_file_size_limit_says_so(
    tmp_path: Path, file_size_limit: Callable[[int], None]
) -> None:
    """Before: "cannot write: 3 frames encoded but 0 read back"."""
    video = _noise_video(tmp_path / "noise.mp4")
    file_size_limit(16 << 10)
    with pytest.raises(DataError) as caught:
        _overlay(video, tmp_path)
    assert str(caught.value) == (
        f"{tmp_path / 'over.mp4'}: cannot write: the file would grow past a size limit such as"
        " `ulimit -f` (3 frames encoded but 0 read back)"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["noise.mp4"]
