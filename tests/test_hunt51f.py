"""A phone's photo made of tiles, and a picture served over HTTP (hunt 51f).

Every iPhone photo since 2017 is a HEIC whose primary picture is a grid: 512x512 HEVC tiles,
each coded apart, put together and cropped to the photo's size (ISO/IEC 23008-12). FFmpeg
gives each tile as a stream of its own and OpenCV reads the first, so such a photo was
refused ("made of N tiles ..., of which OpenCV decodes one alone"). Its tiles are now decoded
by FFmpeg in one stream and put together, then turned by the grid's irot and imir.

The HEIC files are made here from a real photo as a phone makes them: each tile coded by
x265 (through PyAV, a test dependency) into an MP4 of its own, whose hvcC box and sample
are the tile's configuration and bytes, put together by :func:`_heic_grid` as
tests/test_hunt50e.py puts AVIF tiles together. libheif (pillow-heif) decoded such a file to
the photo within 1 grey level on average (checked once by hand, not here: pillow-heif is no
dependency). The expected pictures are the photo itself (turned with numpy as the HEIF
standard says irot and imir turn it) and its landmarks those of the photo given as a PNG.
"""

from __future__ import annotations

import io
import struct
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from features.pose_estimation import PoseEstimator, iter_frames, served_file_rate, stream_poses
from tests.badinput import refused
from tests.once import made_once
from tests.test_hunt50e import PHOTO, _box, _children, _full
from tests.test_hunt50i import server  # noqa: F401 (the fixture, one server a module)

av = pytest.importorskip("av")


def _x265() -> bool:
    try:
        av.codec.Codec("libx265", "w")
    except (ValueError, av.FFmpegError):
        return False
    return True


pytestmark = pytest.mark.skipif(not _x265(), reason="PyAV without the x265 encoder")


def _hevc_tile(rgb: np.ndarray) -> tuple[bytes, bytes]:
    """A picture coded by x265 as a phone codes a tile: its hvcC box and its coded bytes
    (NAL units each after its length), from an MP4 of one frame PyAV writes."""
    buf = io.BytesIO()
    with av.open(buf, "w", format="mp4") as out:
        stream = out.add_stream("libx265", rate=1)
        stream.width, stream.height, stream.pix_fmt = rgb.shape[1], rgb.shape[0], "yuv420p"
        stream.options = {
            "x265-params": "log-level=error:keyint=1",
            "crf": "18",
            "preset": "ultrafast",
        }
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")
        for packet in [*stream.encode(frame), *stream.encode(None)]:
            out.mux(packet)
    data = buf.getvalue()
    at = data.index(b"hvcC") - 4
    return data[at : at + int.from_bytes(data[at : at + 4], "big")], _children(data)[b"mdat"]


def _heic_grid(
    rgb: np.ndarray, tile: int, turns: Sequence[bytes] = (), blank_last: bool = False
) -> bytes:
    """``rgb`` as a phone stores a photo: ``tile`` x ``tile`` HEVC pictures (hidden items) put
    together by a grid item (rows, columns, the picture's size), the primary item, with the
    properties ``turns`` (irot, imir boxes) in that order; ``blank_last``: the last tile's
    bytes zeros (no NAL unit in them)."""
    h, w = rgb.shape[:2]
    rows, cols = -(-h // tile), -(-w // tile)
    canvas = np.zeros((rows * tile, cols * tile, 3), np.uint8)
    canvas[:h, :w] = rgb
    coded = [
        _hevc_tile(canvas[r * tile : (r + 1) * tile, c * tile : (c + 1) * tile])
        for r in range(rows)
        for c in range(cols)
    ]
    if blank_last:
        coded[-1] = (coded[-1][0], bytes(len(coded[-1][1])))
    n, grid = len(coded), len(coded) + 1
    layout = struct.pack(">BBBBHH", 0, 0, rows - 1, cols - 1, w, h)
    infe = [_full(b"infe", struct.pack(">HH4s", i + 1, 0, b"hvc1") + b"\0", 2, 1) for i in range(n)]
    infe.append(_full(b"infe", struct.pack(">HH4s", grid, 0, b"grid") + b"\0", 2))
    props = [config for config, _ in coded]
    props += [
        _full(b"ispe", struct.pack(">II", tile, tile)),
        _full(b"ispe", struct.pack(">II", w, h)),
    ]
    props += list(turns)
    assoc = [struct.pack(">HBBB", i + 1, 2, 0x80 | (i + 1), n + 1) for i in range(n)]
    shown = [n + 2, *range(n + 3, n + 3 + len(turns))]
    assoc.append(struct.pack(">HB", grid, len(shown)) + bytes(shown))
    tiles = struct.pack(">HH", grid, n) + b"".join(struct.pack(">H", i + 1) for i in range(n))

    def meta(offsets: list[int]) -> bytes:
        # iloc version 1: each item's construction method, the tiles in the file (0), the
        # grid's layout in the idat box (1), as a phone stores it
        items = b"".join(
            struct.pack(">HHHHII", i + 1, 0, 0, 1, offsets[i], len(coded[i][1])) for i in range(n)
        )
        items += struct.pack(">HHHHII", grid, 1, 0, 1, 0, len(layout))
        return _full(
            b"meta",
            _full(b"hdlr", b"\0\0\0\0pict" + b"\0" * 13)
            + _full(b"pitm", struct.pack(">H", grid))
            + _full(b"iloc", struct.pack(">BBH", 0x44, 0, n + 1) + items, 1)
            + _full(b"iinf", struct.pack(">H", n + 1) + b"".join(infe))
            + _full(b"iref", _box(b"dimg", tiles))
            + _box(
                b"iprp",
                _box(b"ipco", b"".join(props))
                + _full(b"ipma", struct.pack(">I", n + 1) + b"".join(assoc)),
            )
            + _box(b"idat", layout),
        )

    ftyp = _box(b"ftyp", b"heic\0\0\0\0mif1heic")
    start = len(ftyp) + len(meta([0] * n)) + 8  # the mdat's body
    offsets = [int(x) for x in start + np.cumsum([0, *[len(d) for _, d in coded[:-1]]])]
    return ftyp + meta(offsets) + _box(b"mdat", b"".join(d for _, d in coded))


def _photo(shared_data: Path) -> np.ndarray:
    return np.asarray(Image.open(shared_data / PHOTO).convert("RGB"))


@pytest.fixture(scope="module")
def heics(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of the 640x480 photo as HEIC files of 512x512 tiles (2 x 1, cropped to it),
    as a phone stores it: ``upright.heic`` as seen; ``sideways.heic`` stored a quarter turn
    counter-clockwise (480 wide, 640 high: 1 x 2 tiles), an irot of 3 quarter turns
    counter-clockwise (a quarter clockwise) saying how it is seen."""

    def make(folder: Path) -> Path:
        rgb = _photo(shared_data)
        (folder / "upright.heic").write_bytes(_heic_grid(rgb, 512))
        sideways = _heic_grid(np.rot90(rgb, 1), 512, [_box(b"irot", b"\x03")])
        (folder / "sideways.heic").write_bytes(sideways)
        return folder

    return made_once(tmp_path_factory, "hunt51f-heics", make)


def _first_landmarks(source: str, estimator: PoseEstimator, served: bool) -> np.ndarray:
    """The first frame's image landmarks, the source opened as ``watch`` opens it."""
    fps = served_file_rate(source, 10.0) if served else None
    frames = stream_poses(source, estimator=estimator, fps=fps, timeout_s=10.0, max_frames=1)
    return np.asarray(next(iter(frames)).pose.image)


@pytest.fixture(scope="module")
def estimator() -> PoseEstimator:
    return PoseEstimator(smoothing=True)


def test_a_phones_heic_photo_of_tiles_stored_sideways_is_posed_as_the_upright_photo(
    shared_data: Path,
    heics: Path,
    estimator: PoseEstimator,
    tmp_path: Path,
) -> None:
    """The photo stored sideways in tiles (``heics``): read as the photo, within the lossy
    coding's few grey levels, and posed as the photo given as a PNG, its landmarks within
    the coding's few pixels. Before: refused, "a HEIC picture of 640x480 made of 2 tiles
    ..., of which OpenCV decodes one alone (512x512)"."""
    rgb = _photo(shared_data)
    Image.fromarray(rgb).save(tmp_path / "upright.png")
    heic = tmp_path / "IMG_0001.HEIC"
    heic.write_bytes((heics / "sideways.heic").read_bytes())

    (frame,) = list(iter_frames(heic))
    assert frame.shape == rgb.shape
    assert np.abs(frame.astype(int) - rgb).mean() < 2.0  # x265 at crf 18: some 1 here
    got = _first_landmarks(str(heic), estimator, served=False)
    expected = _first_landmarks(str(tmp_path / "upright.png"), estimator, served=False)
    body = [0, 11, 12, 23, 24, 25, 26]  # nose, shoulders, hips, knees: well in view
    assert np.abs(got[body, :2] - expected[body, :2]).max() < 8.0


@pytest.mark.parametrize(
    ("turns", "seen"),
    [
        # imir axis 0: upside down; 1: left to right (as libheif shows them)
        ([b"imir\x00"], lambda a: a[::-1]),
        ([b"imir\x01"], lambda a: a[:, ::-1]),
        # irot first, then imir, in the order the grid lists them
        ([b"irot\x01", b"imir\x00"], lambda a: np.rot90(a, 1)[::-1]),
    ],
)
def test_a_heic_grid_is_turned_and_mirrored_as_its_properties_say(
    turns: list[bytes], seen: Callable[[np.ndarray], np.ndarray], tmp_path: Path
) -> None:
    """A 96x64 picture of four coloured quarters in 64x64 tiles (2 x 1, the second cropped):
    the picture read is the one its irot and imir properties show, each quarter's colour
    where it lands (a 16-px square in its middle, within the coding's few levels)."""
    rgb = np.zeros((64, 96, 3), np.uint8)
    rgb[:32, :48], rgb[:32, 48:], rgb[32:, :48] = (250, 0, 0), (0, 250, 0), (0, 0, 250)
    path = tmp_path / "quarters.heic"
    path.write_bytes(_heic_grid(rgb, 64, [_box(t[:4], t[4:]) for t in turns]))
    expected = seen(rgb)
    (frame,) = list(iter_frames(path))
    assert frame.shape == expected.shape
    h, w = expected.shape[0] // 2, expected.shape[1] // 2
    for y in (h // 2, h + h // 2):
        for x in (w // 2, w + w // 2):
            patch = frame[y - 8 : y + 8, x - 8 : x + 8].astype(int)
            assert np.abs(patch - expected[y, x]).max() < 24, (y, x)


def test_a_heic_grid_with_a_tile_that_does_not_decode_is_refused(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 192x128 part of the photo in 64x64 tiles, the last of its 6 zeroed (no NAL unit in
    it): refused in one line naming the photo and how many tiles FFmpeg decodes, not posed
    on a picture with a black hole."""
    path = tmp_path / "IMG_0002.heic"
    path.write_bytes(_heic_grid(_photo(shared_data)[100:228, 220:412], 64, blank_last=True))
    refused(["extract", str(path), "--out", str(tmp_path / "out")], tmp_path, capsys,
            f"{path}: a HEIC picture of 192x128 made of 6 tiles (as a phone stores a photo),"
            " of which FFmpeg decodes 5: convert it to JPEG or PNG first")  # fmt: skip


def test_served_photos_are_posed_as_the_same_files_here(
    shared_data: Path,
    heics: Path,
    server: tuple[Path, str],  # noqa: F811 (the fixture)
    estimator: PoseEstimator,
) -> None:
    """``stream_poses`` of a URL gives the landmarks the same file on this machine gives: a
    JPEG stored sideways with EXIF orientation 6 (a phone's portrait photo), from Python's
    server, and the HEIC of tiles, from a server answering range requests. Before: the JPEG
    was posed as stored, sideways (the served file's EXIF was not read), the HEIC refused."""
    folder, address = server
    rgb = _photo(shared_data)
    exif = Image.Exif()
    exif[0x0112] = 6  # turned a quarter clockwise to be seen
    Image.fromarray(np.ascontiguousarray(np.rot90(rgb, 1))).save(
        folder / "sideways.jpg", exif=exif, quality=95
    )
    (folder / "ranged" / "IMG_0003.heic").write_bytes((heics / "upright.heic").read_bytes())
    for name in ("sideways.jpg", "ranged/IMG_0003.heic"):
        expected = _first_landmarks(str(folder / name), estimator, served=False)
        assert expected[0, 1] < expected[23:25, 1].mean() - 100  # upright: nose above hips
        got = _first_landmarks(f"{address}/{name}", estimator, served=True)
        np.testing.assert_allclose(got, expected, atol=1e-6, equal_nan=True, err_msg=name)
