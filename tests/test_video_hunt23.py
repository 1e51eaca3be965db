"""The video side given what users give it (hunt 23): ``watch`` of a camera index OpenCV
cannot even take, of a server that accepts and never answers, of a ``file://`` URL naming
the ``--out`` video; ``extract`` into folders it had to make; videos whose frame rate is
absurdly low. Each refusal: one line naming the source, exit 1, inputs unchanged, no output.

Tiny synthetic videos (OpenCV writes them) keep each case to a few seconds.
"""

from __future__ import annotations

import time
from pathlib import Path

import cv2
import numpy as np
import pytest

import features.pose_estimation  # noqa: F401  (silences FFmpeg before any video is opened)
from posecbr.cli import main
from tests.badinput import small_case_base, snapshot, too_wide_video


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _video(path: Path, frames: int = 12, fps: float = 10.0, size: int = 64) -> Path:
    """A small MJPG AVI of ``frames`` grey frames (no person)."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), fps, (size, size))
    for k in range(frames):
        writer.write(np.full((size, size, 3), 10 * k, np.uint8))
    writer.release()
    return path


SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"


def _squat(shared_data: Path, path: Path, frames: int = 12) -> Path:
    """The first ``frames`` of the real squat video (5 fps, a woman in view) at a quarter
    size, as an MJPG AVI."""
    cap = cv2.VideoCapture(str(shared_data / SQUAT))
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 5.0, (180, 320))
    for _ in range(frames):
        ok, bgr = cap.read()
        assert ok
        writer.write(cv2.resize(bgr, (180, 320)))
    writer.release()
    cap.release()
    return path


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("index", ["2147483648", "99999999999999999999"])
def test_watch_a_camera_index_too_large_for_opencv_is_one_line(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], index: str
) -> None:
    """A camera index past a C int: OpenCV's overload error (or Python's OverflowError) came
    out as a traceback from the reader thread; now it is refused as an index with no camera
    behind it is."""
    out = tmp_path / "w.mp4"
    assert main(["watch", index, "--db", str(case_base), "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        f"posecbr watch: error: {index}: cannot open camera: none at this index, or another"
        " program holds it"
    )
    assert captured.out == "" and list(tmp_path.iterdir()) == []


def test_watch_a_server_that_never_answers_gives_up_after_the_stall(
    case_base: Path, silent_server: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--stall 1`` on a URL whose server accepts and never answers: the same line as a
    stream that stalls, after about a second. (The URL was first opened to learn whether it
    is a served file with FFmpeg's own 30-s timeout, in the main thread, where neither
    --stall nor Ctrl-C could end the wait.)"""
    out = tmp_path / "w.mp4"
    started = time.monotonic()
    argv = ["watch", silent_server, "--db", str(case_base), "--stall", "1", "--out", str(out)]
    assert main(argv) == 1
    took = time.monotonic() - started
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        f"posecbr watch: error: {silent_server}: the stream stalled: no frame for 1 s"
    )
    assert took < 15, took
    assert captured.out == "" and list(tmp_path.iterdir()) == []


def test_watch_out_never_overwrites_the_file_a_file_url_names(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch file:///x/clip.avi --out /x/clip.avi`` (here an .mp4): the URL was taken for a
    stream, so the file it names was no input; the watch played it and replaced it with the
    annotated video, exit 0. Refused as ``watch /x/clip.mp4 --out /x/clip.mp4`` is."""
    video = _squat(shared_data, tmp_path / "clip.avi")
    given = tmp_path / "clip.mp4"
    video.rename(given)
    before = snapshot(tmp_path)
    url = f"file://{given}"
    argv = ["watch", url, "--db", str(case_base), "--speed", "0", "--out", str(given)]
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        f"posecbr watch: error: {given}: the output video would overwrite an input ({given})"
    )
    assert captured.out == "" and snapshot(tmp_path) == before


def _declaring_fps(path: Path, rate: int, scale: int) -> Path:
    """An MJPG AVI of 12 frames whose header declares ``rate / scale`` frames per second
    (OpenCV refuses to write a rate under 1: its stream header is edited)."""
    _video(path, fps=10.0)
    data = bytearray(path.read_bytes())
    strh = data.index(b"strh") + 8  # dwScale, dwRate at 20 bytes into the stream header
    data[strh + 20 : strh + 28] = scale.to_bytes(4, "little") + rate.to_bytes(4, "little")
    avih = data.index(b"avih") + 8
    data[avih : avih + 4] = bytes(4)  # microseconds per frame: unknown
    path.write_bytes(bytes(data))
    return path


def test_a_video_declaring_under_a_hundredth_of_a_frame_per_second_is_refused_at_once(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A header declaring 0.001 frames per second: ``extract`` ran the model on every frame
    and then could not save the pose file (its rate under the pose files' 0.01); ``watch``
    played it at one frame per 1000 s and reported "the stream stalled". Both refuse it as
    a video with no usable frame rate, before any work, naming the rate."""
    video = _declaring_fps(tmp_path / "slow.avi", 1, 1000)
    assert cv2.VideoCapture(str(video)).get(cv2.CAP_PROP_FPS) == pytest.approx(0.001)
    before = snapshot(tmp_path)
    message = (
        f"{video}: video declares no usable frame rate (0.001 frames per second; posecbr takes"
        " 0.01 to 1000)"
    )
    argv = ["extract", str(video), "--out", str(tmp_path / "poses")]
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == f"posecbr extract: error: {message}"
    argv = ["watch", str(video), "--db", str(case_base), "--stall", "2",
            "--out", str(tmp_path / "w.mp4")]  # fmt: skip
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == f"posecbr watch: error: {message}"
    assert captured.out == "" and snapshot(tmp_path) == before


def test_extract_that_fails_leaves_none_of_the_folders_it_made(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--out`` three folders deep, none of them there, for a text file named .mp4: the
    refusal removed the last folder it had made and left the two above it."""
    video = tmp_path / "notes.mp4"
    video.write_text("not a video\n")
    before = snapshot(tmp_path)
    out = tmp_path / "runs" / "today" / "poses"
    assert main(["extract", str(video), "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        f"posecbr extract: error: {video}: not a video OpenCV can decode (unknown format,"
        " truncated or corrupt)"
    )
    assert captured.out == "" and snapshot(tmp_path) == before


def test_extract_interrupted_leaves_none_of_the_folders_it_made(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Ctrl-C while the model runs (here raised by a stand-in for it): "interrupted", exit
    130, the video as it was and none of the output folders left behind."""
    import features.pose_estimation as pose_estimation

    def interrupted(*_args: object, **_kwargs: object) -> None:
        raise KeyboardInterrupt

    video = _video(tmp_path / "clip.avi")
    before = snapshot(tmp_path)
    monkeypatch.setattr(pose_estimation, "estimate_video", interrupted)
    out = tmp_path / "runs" / "today" / "poses"
    assert main(["extract", str(video), "--out", str(out)]) == 130
    captured = capsys.readouterr()
    assert _one_line(captured.err) == "posecbr extract: interrupted"
    assert captured.out == "" and snapshot(tmp_path) == before


def test_a_pipe_named_like_a_video_is_refused_not_waited_on(tmp_path: Path) -> None:
    """A named pipe ``clip.mp4`` (nobody writing to it) given to ``describe``: opening it to
    read its first bytes waited for a writer forever. Refused in one line, exit 1, as
    ``extract`` now refuses it (it said "cannot list folder (Not a directory)")."""
    import os
    import subprocess
    import sys

    pipe = tmp_path / "clip.mp4"
    os.mkfifo(pipe)
    for argv, line in [
        (["describe", str(pipe)], f"posecbr describe: error: {pipe}: is a pipe, socket or"
         " device, not a clip file"),
        (["extract", str(pipe), "--out", str(tmp_path / "poses")], f"posecbr extract: error:"
         f" {pipe}: is a pipe, socket or device, not a video, folder or labels CSV"),
    ]:  # fmt: skip
        done = subprocess.run(
            [sys.executable, "-m", "posecbr", *argv],
            capture_output=True,
            text=True,
            timeout=60,
            env={**os.environ, "POSECBR_NO_PROGRESS": "1"},
        )
        assert done.returncode == 1, done.stderr
        assert _one_line(done.stderr) == line and done.stdout == ""
    assert list(tmp_path.iterdir()) == [pipe] and pipe.is_fifo()  # (reading it would block)


def test_an_overlay_too_wide_for_mp4_is_refused_before_the_work(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A video 8192 pixels wide (one more than an MP4 frame can be): ``extract --overlay``
    ran the model, wrote the pose file, then failed "cannot encode an MP4 overlay here"
    (exit 1 with a pose file written; as if the machine lacked the codec); ``watch --out``
    failed the same way at the first frame. Both refuse it first, saying why."""
    video = too_wide_video(tmp_path / "wide.avi", frames=3)
    before = snapshot(tmp_path)
    overlay, out = tmp_path / "overlay.mp4", tmp_path / "poses"
    assert main(["extract", str(video), "--out", str(out), "--overlay", str(overlay)]) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        f"posecbr extract: error: {overlay}: cannot encode an MP4 overlay of 8192x16 frames:"
        " MP4 frames are at most 8191 pixels a side"
    )
    assert captured.out == "" and snapshot(tmp_path) == before
    argv = ["watch", str(video), "--db", str(case_base), "--speed", "0", "--out", str(overlay)]
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        f"posecbr watch: error: {overlay}: cannot encode an MP4 video of 8192x16 frames:"
        " MP4 frames are at most 8191 pixels a side"
    )
    assert captured.out == "" and snapshot(tmp_path) == before


def test_an_empty_input_is_refused_not_taken_for_the_current_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``posecbr extract "$VIDEO" --out poses`` with VIDEO unset: the empty argument became
    Path(""), the current folder, and every video and picture in it (and one folder down)
    was extracted, exit 0; ``watch ""`` said "is a folder, not a video file" naming nothing.
    Both refuse the empty path, before any work."""
    _video(tmp_path / "clip.avi")
    monkeypatch.chdir(tmp_path)
    before = snapshot(tmp_path)
    assert main(["extract", "", "--out", str(tmp_path / "poses")]) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        "posecbr extract: error: the input is an empty path: name a video, still image, folder"
        " or labels CSV"
    )
    assert captured.out == "" and snapshot(tmp_path) == before
    assert main(["watch", "", "--db", str(tmp_path / "none.sqlite")]) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        "posecbr watch: error: the source is empty: name a webcam index, stream URL or video file"
    )
    assert captured.out == "" and snapshot(tmp_path) == before
