"""Hunt 48h1: a physiotherapist's phone videos.

An MP4/MOV file still being recorded (copied off the phone, or synced, while the camera runs;
or left so when the recording app was killed) holds its frames' box (mdat) and no index: the
recorder writes the index (moov) when it stops, and until then the frames' box states size
0, "to the file's end" (FFmpeg's and PyAV's muxer; a 64-bit size of 0 where the recorder
reserved one). FFmpeg cannot open it, and every command said "not a video OpenCV can decode
(unknown format, truncated or corrupt)". Now it says what it is.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.pose_estimation.video import open_video
from tests.badinput import refused
from tests.test_hunt38f import FRAMES, _box_at, _mjpg_mp4

av = pytest.importorskip("av")

UNFINISHED = (
    "unfinished MP4/MOV: its frames have no index (no moov box): still being recorded, or the"
    " recording stopped before it was closed"
)


def _recording(tmp_path: Path, header: str) -> tuple[bytes, bytes]:
    """The bytes of a 12-frame MP4 written as a recorder writes it (its index at its end)
    and of the same file as it stood before the index was written: the frames' box stating
    ``header`` "zero" (size 0: to the file's end), "large" (a 64-bit size of 0), or "sized"
    (its final size: the recorder stopped between the frames and the index)."""
    whole = _mjpg_mp4(tmp_path / "whole.mp4", faststart=False).read_bytes()
    at, stated = _box_at(whole, b"mdat")
    moov, _ = _box_at(whole, b"moov")
    assert at + stated == moov  # the index comes after the frames
    body = whole[at + 8 : moov]
    box = {
        "zero": b"\x00\x00\x00\x00mdat",
        "large": b"\x00\x00\x00\x01mdat" + bytes(8),
        "sized": whole[at : at + 8],
    }[header]
    return whole, whole[:at] + box + body


@pytest.mark.parametrize("header", ["zero", "large", "sized"])
def test_an_mp4_still_being_recorded_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], header: str
) -> None:
    folder = tmp_path / "phone"
    folder.mkdir()
    _whole, growing = _recording(tmp_path, header)
    clip = folder / "session.mp4"
    clip.write_bytes(growing)
    why = f"{clip}: {UNFINISHED}"
    refused(["extract", str(clip), "--out", str(folder / "poses")], folder, capsys, why)
    refused(["reps", str(clip)], folder, capsys, why)


def test_finished_and_fragmented_recordings_open_as_before(tmp_path: Path) -> None:
    """The whole file (index last) and a fragmented one (an empty index first, a fragment's
    index, moof, before each stretch of frames) hold an index and open with their frames."""
    whole, _growing = _recording(tmp_path, "zero")
    done = tmp_path / "done.mp4"
    done.write_bytes(whole)
    fragmented = tmp_path / "fragmented.mp4"
    with av.open(str(fragmented), "w", options={"movflags": "frag_keyframe+empty_moov"}) as out:
        stream = out.add_stream("mjpeg", rate=25)
        stream.width, stream.height, stream.pix_fmt = 96, 64, "yuvj420p"
        for k in range(FRAMES):
            grey = np.full((64, 96, 3), 20 * k, dtype=np.uint8)
            frame = av.VideoFrame.from_ndarray(grey, format="rgb24")
            for packet in stream.encode(frame):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    assert b"moof" in fragmented.read_bytes()
    for path in (done, fragmented):
        cap, info = open_video(path)
        read = 0
        while cap.read()[0]:
            read += 1
        cap.release()
        assert read == FRAMES, path

