"""Hunt 38f: a coach's phone videos. An MP4/MOV file cut short (a download or copy that
stopped) was taken when it still opened: one whose index comes first (a messaging app's or
a web page's "fast start" MP4) cut inside its last frame or frames was read as whole, the
last frame decoded half grey or the missing ones (up to 1 % of the frames, at least two)
passed as the end of the recording; one whose index comes at its end was refused as "not a
video OpenCV can decode (unknown format, truncated or corrupt)". Both are now refused as
cut, naming the byte where the file ends and where the box it ends in runs to."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.pose_estimation.video import open_video
from tests.badinput import refused

av = pytest.importorskip("av")

FRAMES = 12


def _mjpg_mp4(path: Path, faststart: bool) -> Path:
    """A 12-frame 96 x 64 MJPG MP4 of noise (every frame some kilobytes), its index at its
    start (``faststart``) or at its end, as PyAV writes it."""
    rng = np.random.default_rng(38)
    options = {"movflags": "+faststart"} if faststart else {}
    with av.open(str(path), "w", options=options) as out:
        stream = out.add_stream("mjpeg", rate=25)
        stream.width, stream.height, stream.pix_fmt = 96, 64, "yuvj420p"
        for _ in range(FRAMES):
            rgb = rng.integers(0, 256, (64, 96, 3), dtype=np.uint8)
            for packet in stream.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    return path


def _box_at(data: bytes, name: bytes) -> tuple[int, int]:
    """Where the only top-level box ``name`` of an MP4 file starts and the size it states."""
    assert data.count(name) == 1, name
    at = data.index(name) - 4
    return at, int.from_bytes(data[at : at + 4], "big")


def test_a_fast_start_mp4_cut_inside_its_last_frame_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The index first, the frames after it to the file's end: cut 300 bytes short (inside
    the last frame's JPEG, some kilobytes of noise), ``extract`` wrote a pose file of all 12
    frames, the last decoded from what was left, exit 0, as ``reps`` counted it. Now both
    refuse it: the frames' box (mdat, the last) runs to the whole file's end."""
    folder = tmp_path / "in"
    folder.mkdir()
    whole = _mjpg_mp4(tmp_path / "whole.mp4", faststart=True).read_bytes()
    at, stated = _box_at(whole, b"mdat")
    assert at + stated == len(whole) and whole.index(b"moov") < at  # index first, frames last
    cut = folder / "clip.mp4"
    cut.write_bytes(whole[:-300])
    why = (
        f"{cut}: truncated MP4/MOV: the file ends at byte {len(whole) - 300:,}, inside a box"
        f" that runs to byte {len(whole):,}"
    )
    refused(["extract", str(cut), "--out", str(folder / "poses")], folder, capsys, why)
    refused(["reps", str(cut)], folder, capsys, why)


def test_an_mp4_cut_before_its_index_is_refused_as_cut(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The index at the end, as a phone writes it: cut in the middle of its frames, it was
    "not a video OpenCV can decode (unknown format, truncated or corrupt)". Now: cut, inside
    the frames' box, which runs to where the index began."""
    whole = _mjpg_mp4(tmp_path / "whole.mp4", faststart=False).read_bytes()
    at, stated = _box_at(whole, b"mdat")
    moov, _ = _box_at(whole, b"moov")
    assert at + stated == moov
    cut = tmp_path / "clip.mp4"
    cut.write_bytes(whole[: at + stated // 2])
    refused(
        ["reps", str(cut)],
        tmp_path,
        capsys,
        f"{cut}: truncated MP4/MOV: the file ends at byte {at + stated // 2:,}, inside a box"
        f" that runs to byte {moov:,}",
    )
    header = tmp_path / "header.mp4"  # cut 4 bytes into the index's header
    header.write_bytes(whole[: moov + 4])
    with pytest.raises(DataError, match=r"ends at byte [\d,]+, inside a box's header$"):
        open_video(header)


def test_whole_mp4_files_open_as_before(tmp_path: Path) -> None:
    """Whole files, index first or last, and one with a maker's trailer after its last box
    (bytes that are no box: not judged), open with their 12 frames."""
    from features.pose_estimation.containers import mp4_timeless_frames, mp4_walk

    for name, faststart in (("first.mp4", True), ("last.mp4", False)):
        path = _mjpg_mp4(tmp_path / name, faststart)
        size = path.stat().st_size
        with open(path, "rb") as fh:
            assert mp4_walk(fh, size) == size
            assert mp4_timeless_frames(fh, size) is None  # 12 frames of 512 ticks each
        cap, info = open_video(path)
        cap.release()
        assert info.frames == FRAMES
    trailer = tmp_path / "trailer.mp4"
    trailer.write_bytes((tmp_path / "last.mp4").read_bytes() + b"\x00\x10\x00\x00SEFT" * 3)
    with open(trailer, "rb") as fh:
        assert mp4_walk(fh, trailer.stat().st_size) is None
    cap, info = open_video(trailer)
    cap.release()
    assert info.frames == FRAMES


def test_an_mp4_whose_frames_have_no_duration_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A zero frame-rate header: the MP4's time-to-sample table gives every frame a duration
    of 0. FFmpeg makes up a rate for it (here 2.08 fps, each frame as long as the whole
    0.48-s clip, its last stamped at 0 s; 12.25 fps of a 25 fps H.264 clip, its frames all
    at 0 s), and ``reps`` and ``extract`` read it at that rate (``reps`` with a note that at
    2.08 fps repetitions may be miscounted). Now it is refused as a video without a usable
    frame rate; the same file with its durations is read as before."""
    whole = _mjpg_mp4(tmp_path / "whole.mp4", faststart=False).read_bytes()
    at, stated = _box_at(whole, b"stts")
    entries = int.from_bytes(whole[at + 12 : at + 16], "big")
    assert entries == 1 and int.from_bytes(whole[at + 16 : at + 20], "big") == FRAMES
    zero = bytearray(whole)
    zero[at + 20 : at + 24] = bytes(4)  # the one entry's duration: 0
    folder = tmp_path / "in"
    folder.mkdir()
    clip = folder / "clip.mp4"
    clip.write_bytes(bytes(zero))
    why = (
        f"{clip}: video declares no usable frame rate (its header gives its {FRAMES} frames"
        " no duration)"
    )
    refused(["reps", str(clip)], folder, capsys, why)
    refused(["extract", str(clip), "--out", str(folder / "poses")], folder, capsys, why)
    cap, info = open_video(tmp_path / "whole.mp4")
    cap.release()
    assert (info.frames, info.fps) == (FRAMES, 25.0)
