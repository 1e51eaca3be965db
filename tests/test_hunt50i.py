"""``watch`` of a file an HTTP server gives (hunt 50i): turned and refused as the same file
on this machine is (tests/test_hunt50e.py), where its bytes can be read: a display matrix
that mirrors the frames, a preview video track ahead of the recording, a HEIF photo of
tiles, a still picture given to ``watch``.

The served file's start is read (one request), and its index at its end by a range request
where the server answers them (:class:`_Server`: under ``ranged/``, as tests/test_hunt34h.py's
``_Ranged``; Python's own server does not, as elsewhere). The videos are OpenCV's (MPEG-4
Part 2, its index at the end, after the frames); a ``free`` box put between the two moves
the index past the start the first request reads, the frames' offsets unchanged.
"""

from __future__ import annotations

import functools
import http.server
import os
import struct
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from features.errors import DataError
from features.pose_estimation import (
    PoseEstimator,
    iter_frames,
    served_file_rate,
    stream_poses,
)
from features.pose_estimation.served import SERVED_START, Unread, served_cut, served_file
from tests.badinput import refused, small_case_base
from tests.test_hunt34c import _QuietServer
from tests.test_hunt34h import _Ranged
from tests.test_hunt50e import PHOTO, _avif_grid, _mirrored, _two_tracks


class _Server(_Ranged):
    """The module's server, one for all its files: under ``ranged/`` it answers range
    requests; under ``live/`` it sends the file as a live stream does (no length stated);
    elsewhere as Python's server does (no range requests)."""

    def do_GET(self) -> None:  # noqa: N802 (the base's name)
        if self.path.startswith("/ranged/"):
            super().do_GET()
        elif self.path.startswith("/live/"):
            self.send_response(200)
            self.end_headers()
            self.wfile.write(Path(self.translate_path(self.path)).read_bytes())
            self.close_connection = True
        else:
            http.server.SimpleHTTPRequestHandler.do_GET(self)


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Path, str]]:
    """A folder (with ``ranged/`` and ``live/`` in it) and its address (:class:`_Server`)."""
    folder = tmp_path_factory.mktemp("served")
    (folder / "ranged").mkdir()
    (folder / "live").mkdir()
    server = _QuietServer(("127.0.0.1", 0), functools.partial(_Server, directory=str(folder)))
    # polled often: its shutdown then waits no half a second (serve_forever's default)
    threading.Thread(target=server.serve_forever, args=(0.02,), daemon=True).start()
    try:
        yield folder, f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


def _index_past_start(path: Path) -> Path:
    """``path`` (an MP4 whose index, moov, follows its frames) with a ``free`` box of
    :data:`SERVED_START` bytes put before its index: the index then lies past the start a
    served file's first request reads."""
    data = path.read_bytes()
    at = data.index(b"moov") - 4
    assert data.index(b"mdat") < at  # the frames' offsets are before it: unchanged
    path.write_bytes(data[:at] + struct.pack(">I4s", 8 + SERVED_START, b"free")
                     + bytes(SERVED_START) + data[at:])  # fmt: skip
    return path


def _clip(path: Path, bgr: np.ndarray) -> Path:
    """Two frames of ``bgr`` (640x480) at 5 fps, written by OpenCV: the index at the end."""
    import cv2

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 5.0, (640, 480))
    for _ in range(2):
        writer.write(bgr)
    writer.release()
    return path


def _first_landmarks(source: str, estimator: PoseEstimator, served: bool) -> np.ndarray:
    """The first frame's image landmarks, the source opened as ``watch`` opens it."""
    fps = served_file_rate(source, 10.0) if served else None
    frames = stream_poses(source, estimator=estimator, fps=fps, timeout_s=10.0, max_frames=1)
    return np.asarray(next(iter(frames)).pose.image)


def test_a_served_mirrored_video_is_posed_as_the_file_here_is(
    shared_data: Path, tmp_path: Path, server: tuple[Path, str]
) -> None:
    """A display matrix mirroring the frames left to right: the file here is posed as the
    camera took it, upright (tests/test_hunt50e.py). Served, OpenCV turned it a half turn,
    the person upside down (nose some 500 px below the hips). Now served as the file here
    is, the same landmarks as the file without the matrix, exactly: from Python's server
    (no range requests) the small file whole within the start read, and from one answering
    range requests the file whose index lies past that start."""
    import cv2

    plain = _clip(tmp_path / "plain.mp4", cv2.imread(str(shared_data / PHOTO)))
    folder, address = server
    _mirrored(plain, folder / "mirror.mp4", (-1, 0, 0, 1))
    _index_past_start(_mirrored(plain, folder / "ranged" / "far.mp4", (-1, 0, 0, 1)))
    estimator = PoseEstimator(smoothing=True)
    expected = _first_landmarks(str(plain), estimator, served=False)
    assert expected[0, 1] < expected[23:25, 1].mean() - 100  # upright: nose above the hips
    whole = _first_landmarks(f"{address}/mirror.mp4", estimator, served=True)
    far = _first_landmarks(f"{address}/ranged/far.mp4", estimator, served=True)
    np.testing.assert_allclose(whole, expected, atol=1e-6, equal_nan=True)
    np.testing.assert_allclose(far, expected, atol=1e-6, equal_nan=True)


def test_a_served_mp4_whose_first_track_is_a_preview_is_refused(server: tuple[Path, str]) -> None:
    """A 64x48 preview track ahead of the 320x240 recording, its index past the start:
    refused as the file here is, naming both. Before: the preview was posed (64x48
    frames)."""
    folder, address = server
    _index_past_start(_two_tracks(folder / "ranged" / "preview.mp4", [(64, 48), (320, 240)]))
    url = f"{address}/ranged/preview.mp4"
    with pytest.raises(DataError) as refusal:
        stream_poses(url, fps=served_file_rate(url, 10.0), timeout_s=10.0)
    assert str(refusal.value) == (
        f"{url}: holds 2 video tracks, and OpenCV decodes the first alone (64x48, 3 frames),"
        " not the largest (320x240, 3 frames): save that track in a file of its own and give"
        " that"
    )


def test_a_served_photo_of_tiles_is_read_whole_as_the_file_here(
    shared_data: Path, server: tuple[Path, str]
) -> None:
    """A 128x96 AVIF of 2 x 2 tiles: from a server answering range requests OpenCV read one
    64x64 tile at 1 fps; refused as the file here was (until hunt 51f), now read whole as
    the file here is, the same picture exactly. From Python's server (OpenCV does not open
    it) the check for a cut file called it "unfinished MP4/MOV: ... no index": it read 8
    bytes of its start, too few for the brand that says it is a photo."""
    rgb = np.asarray(Image.open(shared_data / PHOTO).convert("RGB"))[100:196, 220:348]
    folder, address = server
    (folder / "ranged" / "IMG_0002.avif").write_bytes(_avif_grid(np.ascontiguousarray(rgb), 64))
    (folder / "IMG_0002.avif").write_bytes((folder / "ranged" / "IMG_0002.avif").read_bytes())
    url = f"{address}/ranged/IMG_0002.avif"
    frames = stream_poses(url, fps=served_file_rate(url, 10.0), timeout_s=10.0, max_frames=1)
    (here,) = list(iter_frames(folder / "IMG_0002.avif"))
    assert here.shape == (96, 128, 3)
    np.testing.assert_array_equal(next(iter(frames)).rgb, here)
    assert served_cut(f"{address}/IMG_0002.avif", 10.0) is None


@pytest.mark.parametrize(
    ("name", "words"), [("IMG_0003.avif", "an AVIF picture"), ("photo", "a PNG or JPEG picture")]
)
def test_watch_refuses_a_served_photo_as_the_photo_here(
    name: str,
    words: str,
    tmp_path: Path,
    server: tuple[Path, str],
    capsys: pytest.CaptureFixture[str],
) -> None:
    """As ``watch`` of a photo here is refused (tests/test_hunt50e.py). Before: the AVIF was
    an "unfinished MP4/MOV", the JPEG (named without a suffix, as a camera's snapshot URL
    may be) read as a one-frame video."""
    folder, address = server
    Image.fromarray(np.full((48, 64, 3), 120, np.uint8)).save(
        folder / name, format="AVIF" if name.endswith(".avif") else "JPEG"
    )
    url = f"{address}/{name}"
    refused(["watch", url, "--db", str(small_case_base(tmp_path))], tmp_path, capsys,
            f"{url}: {words}, not a video: watch plays videos")  # fmt: skip


def test_a_served_file_is_read_past_its_start_by_range_requests_within_bounds(
    server: tuple[Path, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """:func:`served_file`: its start from any server; a part past it by a range request
    where the server answers them (the same bytes as the file's), none from Python's server
    (:class:`Unread`), nor more than the limit; a live stream (no length) is no file."""
    from features.pose_estimation import served

    folder, address = server
    data = os.urandom(3 * SERVED_START)
    for under in ("", "ranged/", "live/"):
        (folder / under / "bytes.mp4").write_bytes(data)
    ranged = served_file(f"{address}/ranged/bytes.mp4", 10.0)
    assert ranged is not None and (ranged.length, ranged.start) == (len(data), data[:SERVED_START])
    ranged.seek(len(data) - 100)
    assert ranged.read(200) == data[-100:]  # to the end, no further
    ranged.seek(SERVED_START - 4)
    assert ranged.read(8) == data[SERVED_START - 4 : SERVED_START + 4]
    whole = served_file(f"{address}/bytes.mp4", 10.0)
    assert whole is not None and (whole.length, whole.start) == (len(data), data[:SERVED_START])
    whole.seek(SERVED_START)
    with pytest.raises(Unread):
        whole.read(4)
    assert served_file(f"{address}/live/bytes.mp4", 10.0) is None
    monkeypatch.setattr(served, "SERVED_INDEX_LIMIT", SERVED_START)
    far = served_file(f"{address}/ranged/bytes.mp4", 10.0)
    assert far is not None
    far.seek(SERVED_START)
    assert far.read(4) == data[SERVED_START : SERVED_START + 4]
    far.seek(2 * SERVED_START + 8)
    with pytest.raises(Unread):
        far.read(4)
