"""What a phone gives, as a new user hands it to posecbr (hunt 50e): photos in HEIF files
(HEIC, an iPhone's and many Android phones', and AVIF) and WebP; an MP4 whose first video
track is a small preview of the recording in its second; a live photo's picture and video
side by side in a folder; a video whose display matrix mirrors it (a front camera's).

A HEIF file of still pictures is an ISO base media file, as MP4 is: an ftyp box, a meta box
indexing its pictures, their bytes in an mdat box, and no moov box. posecbr took it for an
MP4 whose recording stopped before its index was written ("unfinished MP4/MOV: its frames
have no index (no moov box)"), in ``extract`` and in ``watch``, and ``extract`` of a folder
passed ``.heic``/``.avif`` photos by. FFmpeg reads such a picture, turned by its irot
property; but it gives each coded picture in the file as a stream, and a phone stores a photo
as 512x512 tiles put together (a grid): OpenCV reads the first stream, one tile. Such a
photo is refused in one line naming it, not posed on its top-left tile.

The files are made here: Pillow codes AVIF (a photo turned by irot, as a phone's stores it
sideways; each tile of a grid), and :func:`_avif_grid` puts tiles together as a phone does
(ISO/IEC 23008-12: grid item, dimg references, ispe and av1C properties). Pillow (libavif)
decodes the grid whole, the reference the test checks the file against. The videos are
written by OpenCV or PyAV (MPEG-4 Part 2), their display matrices set in the track header by
hand.
"""

from __future__ import annotations

import io
import struct
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, features

from features.pose_estimation import iter_frames
from features.poses import load_pose_arrays
from posecbr.cli import main
from tests.badinput import refused

pytestmark = pytest.mark.skipif(not features.check("avif"), reason="Pillow without AVIF")

PHOTO = Path("media") / "basketball1.png"


def _box(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I4s", 8 + len(body), kind) + body


def _full(kind: bytes, body: bytes, version: int = 0, flags: int = 0) -> bytes:
    return _box(kind, struct.pack(">I", version << 24 | flags) + body)


def _children(data: bytes) -> dict[bytes, bytes]:
    """The bodies of the boxes in ``data``, by name (the first of each)."""
    found: dict[bytes, bytes] = {}
    at = 0
    while at + 8 <= len(data):
        size, kind = struct.unpack(">I4s", data[at : at + 8])
        found.setdefault(kind, data[at + 8 : at + size])
        at += size
    return found


def _avif_tile(rgb: np.ndarray) -> tuple[bytes, bytes]:
    """A picture coded by Pillow as AVIF: its av1C box and its coded bytes (its one item's
    extent, as its iloc box states it)."""
    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="AVIF", quality=90)
    data = buf.getvalue()
    meta = _children(_children(data)[b"meta"][4:])
    config = _children(_children(meta[b"iprp"])[b"ipco"])[b"av1C"]
    iloc = meta[b"iloc"]
    offset_n, length_n, base_n = iloc[4] >> 4, iloc[4] & 15, iloc[5] >> 4
    at = 8 + 2 + 2 + base_n + 2  # item count, item ID, data reference, base offset, extents
    offset = int.from_bytes(iloc[at : at + offset_n], "big")
    length = int.from_bytes(iloc[at + offset_n : at + offset_n + length_n], "big")
    return _box(b"av1C", config), data[offset : offset + length]


def _avif_grid(rgb: np.ndarray, tile: int) -> bytes:
    """``rgb`` as a phone stores a photo: ``tile`` x ``tile`` pictures coded apart (hidden
    items), a grid item putting them together (rows, columns, the picture's size) the primary
    item (pitm)."""
    h, w = rgb.shape[:2]
    rows, cols = -(-h // tile), -(-w // tile)
    canvas = np.zeros((rows * tile, cols * tile, 3), np.uint8)
    canvas[:h, :w] = rgb
    coded = [
        _avif_tile(canvas[r * tile : (r + 1) * tile, c * tile : (c + 1) * tile])
        for r in range(rows)
        for c in range(cols)
    ]
    n, grid = len(coded), len(coded) + 1
    layout = struct.pack(">BBBBHH", 0, 0, rows - 1, cols - 1, w, h)
    infe = [_full(b"infe", struct.pack(">HH4s", i + 1, 0, b"av01") + b"\0", 2, 1) for i in range(n)]
    infe.append(_full(b"infe", struct.pack(">HH4s", grid, 0, b"grid") + b"\0", 2))
    props = [config for config, _ in coded]
    props += [
        _full(b"ispe", struct.pack(">II", tile, tile)),
        _full(b"ispe", struct.pack(">II", w, h)),
    ]
    assoc = [struct.pack(">HBBB", i + 1, 2, 0x80 | (i + 1), n + 1) for i in range(n)]
    assoc.append(struct.pack(">HBB", grid, 1, n + 2))
    tiles = struct.pack(">HH", grid, n) + b"".join(struct.pack(">H", i + 1) for i in range(n))
    lengths = [len(data) for _, data in coded] + [len(layout)]

    def meta(offsets: list[int]) -> bytes:
        items = b"".join(
            struct.pack(">HHHII", i + 1, 0, 1, offsets[i], lengths[i]) for i in range(n + 1)
        )
        return _full(
            b"meta",
            _full(b"hdlr", b"\0\0\0\0pict" + b"\0" * 13)
            + _full(b"pitm", struct.pack(">H", grid))
            + _full(b"iloc", struct.pack(">BBH", 0x44, 0, n + 1) + items)
            + _full(b"iinf", struct.pack(">H", n + 1) + b"".join(infe))
            + _full(b"iref", _box(b"dimg", tiles))
            + _box(
                b"iprp",
                _box(b"ipco", b"".join(props))
                + _full(b"ipma", struct.pack(">I", n + 1) + b"".join(assoc)),
            ),
        )

    ftyp = _box(b"ftyp", b"avif\0\0\0\0avifmif1miaf")
    start = len(ftyp) + len(meta([0] * (n + 1))) + 8  # the mdat's body
    offsets = list(start + np.cumsum([0, *lengths[:-1]]))
    return ftyp + meta(offsets) + _box(b"mdat", b"".join(d for _, d in coded) + layout)


def _sideways_avif(rgb: np.ndarray, path: Path) -> Path:
    """``rgb`` stored a quarter turn counter-clockwise with an irot property saying a viewer
    turns it a quarter clockwise (Pillow writes EXIF orientation 6 as one), as a phone
    stores a portrait photo."""
    exif = Image.Exif()
    exif[0x0112] = 6
    sideways = Image.fromarray(np.ascontiguousarray(np.rot90(rgb, 1)))
    sideways.save(path, exif=exif, quality=95)
    return path


def test_heif_picture_reads_the_primary_pictures_size_as_shown(tmp_path: Path) -> None:
    """The irot photo: 30 wide, 20 high as shown (stored 20 x 30), coded whole; the grid:
    its size and tiles as :func:`_avif_grid` wrote them; an MP4-like ftyp: none."""
    from features.pose_estimation.containers import heif_picture

    rgb = np.zeros((20, 30, 3), np.uint8)
    photo = _sideways_avif(rgb, tmp_path / "a.avif")
    grid = tmp_path / "g.avif"
    grid.write_bytes(_avif_grid(np.zeros((40, 100, 3), np.uint8), 32))
    found = []
    for path in (photo, grid):
        with open(path, "rb") as fh:
            found.append(heif_picture(fh, path.stat().st_size, fh.read(64)))
    assert [(p.brand, p.width, p.height, p.tiles) for p in found if p] == [
        ("AVIF", 30, 20, 1), ("AVIF", 100, 40, 8)  # 4 columns of 32 by 2 rows
    ]  # fmt: skip
    mp4 = _box(b"ftyp", b"isom\0\0\2\0isomiso2avc1mp41") + _box(b"mdat", b"")
    assert heif_picture(io.BytesIO(mp4), len(mp4), mp4) is None


def test_a_phones_avif_photo_stored_sideways_is_posed_as_the_upright_picture(
    shared_data: Path, tmp_path: Path
) -> None:
    """A photo stored sideways with an irot property (Pillow writes EXIF orientation 6 as
    one), in a folder: extracted, its landmarks those of the upright picture given as a PNG,
    within the lossy coding's few pixels. Before: passed by in the folder ("no videos or
    images found"); named, "unfinished MP4/MOV"."""
    photos = tmp_path / "photos"
    photos.mkdir()
    rgb = np.asarray(Image.open(shared_data / PHOTO).convert("RGB"))
    Image.fromarray(rgb).save(photos / "upright.png")
    _sideways_avif(rgb, photos / "IMG_0001.AVIF")

    assert main(["extract", str(photos), "--out", str(tmp_path / "out")]) == 0
    got = load_pose_arrays(tmp_path / "out" / "IMG_0001.npz")["image_landmarks"]
    expected = load_pose_arrays(tmp_path / "out" / "upright.npz")["image_landmarks"]
    assert got.shape == expected.shape == (1, 33, 5)
    body = [0, 11, 12, 23, 24, 25, 26]  # nose, shoulders, hips, knees: well in view
    assert np.abs(got[0, body, :2] - expected[0, body, :2]).max() < 8.0


def test_a_photo_of_tiles_is_read_whole_not_one_tile(shared_data: Path, tmp_path: Path) -> None:
    """A 128x96 picture in 64x64 tiles (2 x 2, as a phone's 4032x3024 photo is 8 x 6 of
    512): read as Pillow (libavif) reads it whole, within the coding's grey levels; OpenCV
    reads one tile. Before hunt 51f: refused in one line ("made of 4 tiles ..., of which
    OpenCV decodes one alone (64x64)"); before hunt 50e: "unfinished MP4/MOV: its frames
    have no index"."""
    rgb = np.asarray(Image.open(shared_data / PHOTO).convert("RGB"))[100:196, 220:348]
    photo = tmp_path / "IMG_0002.avif"
    photo.write_bytes(_avif_grid(np.ascontiguousarray(rgb), 64))
    whole = np.asarray(Image.open(photo).convert("RGB"))
    assert whole.shape == (96, 128, 3) and np.abs(whole.astype(int) - rgb).mean() < 4
    (frame,) = list(iter_frames(photo))
    assert frame.shape == whole.shape
    assert np.abs(frame.astype(int) - whole).mean() < 2


@pytest.mark.parametrize(
    ("name", "words"), [("IMG_0003.avif", "an AVIF picture"), ("photo.webp", "a WebP picture")]
)
def test_watch_names_a_phones_photo_as_the_picture_it_is(
    name: str, words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: the AVIF was "unfinished MP4/MOV: its frames have no index", the WebP "a PNG
    or JPEG picture"."""
    photo = tmp_path / name
    Image.fromarray(np.full((48, 64, 3), 120, np.uint8)).save(photo)
    db = tmp_path / "cb.sqlite"
    db.write_bytes(b"not opened: refused before")
    refused(["watch", str(photo), "--db", str(db)], tmp_path, capsys,
            f"{photo}: {words}, not a video")  # fmt: skip


def test_a_phones_photo_given_for_a_clip_or_a_case_base_is_named_as_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: the WebP and AVIF given for a clip were an "unknown clip format", the AVIF
    given as --db "a video file" (its ftyp box, as an MP4's)."""
    webp, avif = tmp_path / "photo.webp", tmp_path / "photo.avif"
    for photo in (webp, avif):
        Image.fromarray(np.full((48, 64, 3), 120, np.uint8)).save(photo)
    refused(["describe", str(webp)], tmp_path, capsys, f"{webp}: a WebP picture, not a clip")
    refused(["describe", str(avif)], tmp_path, capsys, f"{avif}: an AVIF picture, not a clip")
    refused(["segment", str(webp), "--db", str(avif)], tmp_path, capsys,
            f"{avif}: not a readable SQLite database (an AVIF picture: --db takes")  # fmt: skip


def _two_tracks(path: Path, sizes: list[tuple[int, int]]) -> Path:
    """An MP4 of two video tracks of 3 frames each (MPEG-4 Part 2, 5 fps), of ``sizes``
    (width, height) in the order the file lists them."""
    av = pytest.importorskip("av")
    out = av.open(str(path), "w")
    streams = []
    for width, height in sizes:
        stream = out.add_stream("mpeg4", rate=5)
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
        streams.append(stream)
    for k in range(3):
        for stream in streams:
            picture = np.full((stream.height, stream.width, 3), 40 * k, np.uint8)
            frame = av.VideoFrame.from_ndarray(picture, format="rgb24")
            frame.pts = k
            for packet in stream.encode(frame):
                out.mux(packet)
    for stream in streams:
        for packet in stream.encode():
            out.mux(packet)
    out.close()
    return path


def test_an_mp4_whose_first_video_track_is_a_preview_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """OpenCV decodes the first video track and can be given no other: of a 64x48 preview
    ahead of a 320x240 recording it read the preview (the pose model ran on it, the pose file
    written, exit 0). Now refused in one line naming both. The larger track first is read."""
    from features.pose_estimation import open_video

    first = open_video(_two_tracks(tmp_path / "big_first.mp4", [(320, 240), (64, 48)]))
    first[0].release()
    assert (first[1].width, first[1].height, first[1].frames) == (320, 240, 3)
    preview = _two_tracks(tmp_path / "preview_first.mp4", [(64, 48), (320, 240)])
    refused(
        ["extract", str(preview), "--out", str(tmp_path / "p.npz")],
        tmp_path,
        capsys,
        f"{preview}: holds 2 video tracks, and OpenCV decodes the first alone (64x48, 3 frames),"
        " not the largest (320x240, 3 frames)",
    )


def test_a_live_photos_still_beside_its_video_is_left_out_of_a_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An iPhone's photos copied off it: each live photo a picture and a video of its name
    (IMG_0001.JPG and IMG_0001.MOV; .HEIC with the phone's default format). Before: the
    folder was refused, "both would be written to out/IMG_0001.npz" (for .HEIC since it is
    read). The video is extracted (its 2 frames), the picture left out with a note; a
    picture alone is extracted."""
    import cv2

    photos = tmp_path / "DCIM"
    photos.mkdir()
    grey = np.full((48, 64, 3), 120, np.uint8)
    writer = cv2.VideoWriter(
        str(photos / "IMG_0001.MOV"), cv2.VideoWriter_fourcc(*"mp4v"), 5.0, (64, 48)
    )
    for _ in range(2):
        writer.write(grey)
    writer.release()
    for name in ("IMG_0001.JPG", "IMG_0002.JPG"):
        Image.fromarray(grey).save(photos / name)
    assert main(["extract", str(photos), "--out", str(tmp_path / "out")]) == 0
    said = capsys.readouterr().err
    assert "note: 1 still picture beside a video of the same name left out (IMG_0001.JPG)" in said
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["IMG_0001.npz", "IMG_0002.npz"]
    assert load_pose_arrays(tmp_path / "out" / "IMG_0001.npz")["image_landmarks"].shape[0] == 2


def _mirrored(plain: Path, path: Path, matrix: tuple[int, int, int, int]) -> Path:
    """A copy of the MP4 ``plain`` whose video track's display matrix is ``matrix`` (a, b, c,
    d: a stored pixel x, y is shown at a x + c y, b x + d y, shifted into the frame): the
    same frames, shown mirrored as some phones' front cameras show theirs."""
    data = bytearray(plain.read_bytes())
    tkhd = data.index(b"tkhd", data.index(b"moov")) - 4
    at = tkhd + (60 if data[tkhd + 8] == 1 else 48)  # past the header's times
    width, height = (int.from_bytes(data[at + k : at + k + 4], "big") >> 16 for k in (36, 40))
    a, b, c, d = matrix
    shift = (width if a < 0 else 0, height if d < 0 else 0)
    numbers = [a << 16, b << 16, 0, c << 16, d << 16, 0, shift[0] << 16, shift[1] << 16, 1 << 30]
    data[at : at + 36] = struct.pack(">9i", *numbers)
    path.write_bytes(bytes(data))
    return path


def test_a_video_shown_mirrored_is_posed_as_the_camera_saw_it_not_upside_down(
    shared_data: Path, tmp_path: Path
) -> None:
    """A display matrix that mirrors the frames (left to right; top to bottom, which is that
    and a half turn, stored turned): OpenCV took the matrix's angle alone and turned the
    frames a half turn, the person upside down (the nose some 400 px below the hips). Now
    the frames are posed as the camera took them, the mirror left out (left and right kept
    the person's own): the same landmarks as the file without the matrix, exactly."""
    import cv2

    bgr = cv2.imread(str(shared_data / PHOTO))
    videos = tmp_path / "videos"
    videos.mkdir()
    for name, picture in (
        ("plain.mp4", bgr),
        ("turned.mp4", np.ascontiguousarray(bgr[::-1, ::-1])),
    ):
        writer = cv2.VideoWriter(
            str(tmp_path / name), cv2.VideoWriter_fourcc(*"mp4v"), 5.0, (640, 480)
        )
        for _ in range(2):
            writer.write(picture)
        writer.release()
    (videos / "plain.mp4").write_bytes((tmp_path / "plain.mp4").read_bytes())
    _mirrored(tmp_path / "plain.mp4", videos / "mirror.mp4", (-1, 0, 0, 1))
    _mirrored(tmp_path / "turned.mp4", videos / "flipped.mp4", (1, 0, 0, -1))
    assert main(["extract", str(videos), "--out", str(tmp_path / "out")]) == 0
    poses = {p.stem: load_pose_arrays(p)["image_landmarks"] for p in (tmp_path / "out").iterdir()}
    nose, hips = poses["plain"][0, 0, 1], poses["plain"][0, 23:25, 1].mean()
    assert nose < hips - 100  # upright
    np.testing.assert_allclose(poses["mirror"], poses["plain"], atol=1e-6, equal_nan=True)
    body = [0, 11, 12, 23, 24]  # re-coded turned: the same picture within a few pixels
    assert np.abs(poses["flipped"][:, body, :2] - poses["plain"][:, body, :2]).max() < 6.0
