"""Hunt 48h1: a physiotherapist's phone videos.

An MP4/MOV file still being recorded (copied off the phone, or synced, while the camera runs;
or left so when the recording app was killed) holds its frames' box (mdat) and no index: the
recorder writes the index (moov) when it stops, and until then the frames' box states size
0, "to the file's end" (FFmpeg's and PyAV's muxer; a 64-bit size of 0 where the recorder
reserved one). FFmpeg cannot open it, and every command said "not a video OpenCV can decode
(unknown format, truncated or corrupt)". Now it says what it is.

`extract` of one video did not say the frame rate it read from it (every second `segment`,
`reps` and `watch` give is measured by it): now its line does ("390 frames at 29.97 fps").

A portrait video stored sideways with a display matrix, as phones write it, was already read
upright (OpenCV turns it); no test held it: now one does, both ways a phone turns.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from features.pose_estimation.video import iter_frames, open_video
from posecbr.cli import main
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


def _phone_video(path: Path, frames: list[np.ndarray], rate: Fraction, turn: int = 0) -> Path:
    """RGB ``frames`` as H.264, lossless (qp 0, no chroma subsampling), at ``rate``; with
    ``turn`` a display matrix that turns them by that many degrees counter-clockwise to be
    seen, as a phone held upright stores its portrait frames sideways."""
    with av.open(str(path), "w") as out:
        stream = out.add_stream("libx264", rate=rate)
        stream.codec_context.options = {"qp": "0"}
        stream.height, stream.width = frames[0].shape[:2]
        stream.pix_fmt = "yuv444p"
        if turn:
            stream.set_display_rotation(turn)
        for rgb in frames:
            for packet in stream.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    return path


def test_extract_says_the_frame_rate_it_read_from_the_video(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A phone's "30 fps" is NTSC's 30000/1001 = 29.97003 frames a second: `extract` of one
    video said "done: x.npz (3 frames, 3 without a person)", the rate it read (and every
    second `segment` and `reps` give is measured by) said nowhere."""
    grey = [np.full((64, 96, 3), 60 * k, dtype=np.uint8) for k in range(3)]
    video = _phone_video(tmp_path / "IMG_0001.mp4", grey, Fraction(30000, 1001))
    pose = tmp_path / "IMG_0001.npz"
    assert main(["extract", str(video), "--out", str(pose)]) == 0
    assert capsys.readouterr().out == f"done: {pose} (3 frames at 29.97 fps, 3 without a person)\n"


@pytest.mark.parametrize("turn", [-90, 90])
@pytest.mark.parametrize("threads", [None, 1])
def test_a_portrait_phone_video_stored_sideways_is_read_upright(
    tmp_path: Path, turn: int, threads: int | None
) -> None:
    """A portrait frame (taller than wide, bright at its head end, a mark at its top left)
    stored turned a quarter, with the display matrix that turns it back, is read as the
    portrait frame: its pixels, and the width and height the pose model's coordinates are
    judged against (the skeleton upright, not lying on its side). ``threads``: FFmpeg's
    decoding threads as extract's workers set them (another way of opening the file)."""
    portrait = np.zeros((64, 48, 3), dtype=np.uint8)
    portrait[:16] = 200  # the head end
    portrait[:8, :8] = (255, 0, 0)  # the top left corner
    stored = np.ascontiguousarray(np.rot90(portrait, 1 if turn < 0 else -1))
    assert stored.shape == (48, 64, 3)
    video = _phone_video(tmp_path / f"portrait{turn}.mp4", [stored] * 2, Fraction(30), turn)
    cap, info = open_video(video, threads)
    cap.release()
    assert (info.width, info.height) == (48, 64)
    seen = list(iter_frames(video, threads))
    assert len(seen) == 2
    for rgb in seen:
        assert rgb.shape == portrait.shape
        assert np.abs(rgb.astype(int) - portrait).max() <= 2
