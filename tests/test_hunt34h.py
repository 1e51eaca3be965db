"""Hunt 34h: video input. A Matroska/WebM file cut short on this machine (a browser's WebM,
whose frame count came from the frames that were there, was taken as whole); a served
file's probe asks as FFmpeg asks (credentials in the URL, a self-signed HTTPS server)."""

from __future__ import annotations

import base64
import functools
import json
import shutil
import ssl
import subprocess
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from posecbr.cli import main
from tests.badinput import refused, small_case_base
from tests.media import mux_frames_and_silence, silence_file
from tests.test_hunt34c import (
    BROWSER_PTS_MS,
    _browser_webm,
    _encode,
    _Quiet,
    _QuietServer,
    _serving,
)

NOBODY = "with nobody in view in any of them: no activity to label\n"
"""How ``watch`` ends a video file read to its end with nobody in view (hunt 45u)."""


# on one xdist worker: the module's case_base, self_signed made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt34h")


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _opencv_vp8(path: Path) -> Path:
    """A WebM from OpenCV's own VP8 writer: 60 grey frames at 25 fps."""
    import cv2

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"VP80"), 25, (64, 48))
    assert writer.isOpened()
    for k in range(60):
        writer.write(np.full((48, 64, 3), 3 * k, np.uint8))
    writer.release()
    return path


WEBMS: dict[str, Callable[[Path], Path]] = {
    # a browser's: no frame rate stated (OpenCV says 1000 fps), with a duration or without
    "browser": lambda p: _browser_webm(p, live=False),
    "browser-no-duration": lambda p: _browser_webm(p, live=True),
    "vp8-30fps": lambda p: _encode(p, [33 * k for k in range(120)], "libvpx", 30, {}),
    "opencv-vp8": _opencv_vp8,
}


def _whole_and_cut(kind: str, folder: Path) -> tuple[Path, Path]:
    whole = WEBMS[kind](folder / "whole.webm")
    data = whole.read_bytes()
    cut = folder / "cut.webm"
    cut.write_bytes(data[: len(data) // 2])
    return whole, cut


@pytest.mark.parametrize("kind", list(WEBMS))
def test_a_webm_cut_in_half_is_truncated(kind: str, tmp_path: Path) -> None:
    """Each WebM whole opens and decodes every frame; cut at half its bytes it is refused
    when opened, "truncated", naming the file. A browser's (its frame count taken from the
    frames that were there) gave the 54 frames before the cut as the whole video."""
    from features.errors import DataError
    from features.pose_estimation import iter_frames, open_video

    whole, cut = _whole_and_cut(kind, tmp_path)
    frames = {"opencv-vp8": 60}.get(kind, 120)
    assert sum(1 for _ in iter_frames(whole)) == frames
    with pytest.raises(DataError) as info:
        open_video(cut)
    line = str(info.value)
    assert line.startswith(f"{cut}: truncated Matroska/WebM: the file ends at byte")
    assert f"byte {cut.stat().st_size:,}," in line and "\n" not in line


def test_a_webm_cut_anywhere_inside_an_element_is_truncated(tmp_path: Path) -> None:
    """A browser's WebM without a duration (its segment and no size stated: written as it
    went) cut one byte short, or inside its header, is truncated; cut where a cluster starts
    it holds whole clusters and is taken as a recording stopped there."""
    from features.errors import DataError
    from features.pose_estimation import iter_frames, open_video

    whole = _browser_webm(tmp_path / "whole.webm", live=True)
    data = whole.read_bytes()
    for n in (len(data) - 1, 30, 5):
        cut = tmp_path / f"cut{n}.webm"
        cut.write_bytes(data[:n])
        with pytest.raises(DataError, match="truncated Matroska/WebM"):
            open_video(cut)
    clusters = [i for i in range(len(data)) if data.startswith(b"\x1f\x43\xb6\x75", i)]
    stopped = tmp_path / "stopped.webm"
    stopped.write_bytes(data[: clusters[-1]])
    shown = sum(1 for _ in iter_frames(stopped))
    assert 0 < shown < len(BROWSER_PTS_MS)


@pytest.mark.parametrize("kind", ["browser", "browser-no-duration", "vp8-30fps"])
@pytest.mark.parametrize("command", ["extract", "segment", "watch"])
def test_commands_refuse_a_cut_webm_in_one_line(
    kind: str, command: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract``, ``segment`` and ``watch`` of a cut WebM: one line naming the file and
    "truncated", exit 1, nothing written. ``extract`` had written poses of the frames before
    the cut of a browser's WebM, ``watch`` and ``segment`` labelled them, exit 0."""
    _whole, cut = _whole_and_cut(kind, tmp_path)
    argv = {
        "extract": ["extract", str(cut), "--out", str(tmp_path / "poses")],
        "segment": ["segment", str(cut), "--db", str(case_base)],
        "watch": ["watch", str(cut), "--db", str(case_base), "--speed", "0"],
    }[command]
    refused(argv, tmp_path, capsys, f"{cut}: truncated Matroska/WebM")


# --- a served file's probe asks as FFmpeg asks: credentials in the URL, HTTPS -------------

USER, PASSWORD = "coach", "p@ss:w rd"  # '@', ':' and ' ' percent-escaped in the URL
IN_URL = "coach:p%40ss%3Aw%20rd"


class _Guarded(_Quiet):
    """Gives its files only to a client that sends USER and PASSWORD (HTTP Basic): any
    other request gets 401 and a challenge, as a camera's or a NAS's server does."""

    def do_GET(self) -> None:  # noqa: N802 (the base's name)
        token = base64.b64encode(f"{USER}:{PASSWORD}".encode()).decode()
        if self.headers.get("Authorization") != f"Basic {token}":
            self.send_response(401)
            self.send_header("WWW-Authenticate", 'Basic realm="videos"')
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        super().do_GET()


class _Ranged(_Quiet):
    """Answers range requests (``Range: bytes=N-``), as most web servers do (Python's own
    does not): FFmpeg then reads an MPEG-TS file's end for its duration."""

    def do_GET(self) -> None:  # noqa: N802 (the base's name)
        wanted = self.headers.get("Range", "")
        if not wanted.startswith("bytes="):
            super().do_GET()
            return
        data = Path(self.translate_path(self.path)).read_bytes()
        first, _, last = wanted.removeprefix("bytes=").partition("-")
        start, end = int(first or 0), int(last) if last else len(data) - 1
        self.send_response(206)
        self.send_header("Content-Range", f"bytes {start}-{end}/{len(data)}")
        self.send_header("Content-Length", str(end + 1 - start))
        self.end_headers()
        self.wfile.write(data[start : end + 1])


def _raw_h264(folder: Path, n: int = 50) -> Path:
    """A raw H.264 stream (no container: FFmpeg knows no frame count, takes it at 25 fps)."""
    return _encode(folder / "camera.h264", [40 * k for k in range(n)], "libx264", 25, {})


def test_a_served_file_behind_basic_auth_is_a_file(tmp_path: Path) -> None:
    """FFmpeg reads ``http://user:pass@host/camera.h264`` (it answers the server's Basic
    challenge with the URL's credentials, percent-escapes decoded); the probe that tells a
    file from a live stream, by urllib, took ``user:pass@host`` for the host, failed and
    called the file live (``served_file_rate`` None: watched as a camera). Now the file is
    taken at its 25 fps, as without a password; with a wrong password it is no file."""
    from features.pose_estimation import served_file_rate
    from features.pose_estimation.served import served_whole

    _raw_h264(tmp_path)
    with _serving(tmp_path, _Guarded) as address:
        host = address.removeprefix("http://")
        url = f"http://{IN_URL}@{host}/camera.h264"
        assert served_whole(url, 5.0)
        assert served_file_rate(url, 5.0) == 25.0
        assert not served_whole(f"http://coach:wrong@{host}/camera.h264", 5.0)
        assert not served_whole(f"{address}/camera.h264", 5.0)  # no credentials: 401


def test_watch_of_a_served_file_behind_basic_auth_reads_it_to_its_end(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch`` of that URL: watched as the file here is, 50 frames at 25 fps, one segment
    0-2 s, exit 1 at the end, nobody being in view (it was taken for a camera: wall-clock
    times, "camera or connection lost", exit 1)."""
    _raw_h264(tmp_path)
    with _serving(tmp_path, _Guarded) as address:
        url = f"http://{IN_URL}@{address.removeprefix('http://')}/camera.h264"
        capsys.readouterr()
        code = main(["watch", url, "--db", str(case_base), "--speed", "0"])
    got = capsys.readouterr()
    # read to its end; grey frames, nobody in them: refused there (tests/test_hunt45u.py)
    assert code == 1 and got.err.endswith(NOBODY), got.err
    segments = [json.loads(line) for line in got.out.splitlines()]
    assert [(s["start_frame"], s["end_frame"], s["end_s"]) for s in segments] == [(0, 50, 2.0)]
    assert "camera or connection lost" not in got.err


@pytest.fixture(scope="module")
def self_signed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A certificate for 127.0.0.1 that no authority signed, and its key (openssl)."""
    if shutil.which("openssl") is None:
        pytest.skip("openssl makes the certificate")
    folder = tmp_path_factory.mktemp("tls")
    cert, key = folder / "cert.pem", folder / "key.pem"
    subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2",
         "-subj", "/CN=127.0.0.1", "-keyout", str(key), "-out", str(cert)],
        check=True, capture_output=True,
    )  # fmt: skip
    return cert, key


@contextmanager
def _serving_tls(folder: Path, cert: Path, key: Path) -> Iterator[str]:
    """``folder`` served over HTTPS with the self-signed certificate while the block runs."""
    server = _QuietServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(folder)))
    context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    context.load_cert_chain(cert, key)
    server.socket = context.wrap_socket(server.socket, server_side=True)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield f"https://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


def test_a_self_signed_https_server_is_probed_as_ffmpeg_reads_it(
    tmp_path: Path, self_signed: tuple[Path, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """FFmpeg (as OpenCV ships it) checks an HTTPS server's certificate: from a server whose
    certificate no authority signed, no video opens, and the probe calls it no file either.
    With FFmpeg's check turned off (``OPENCV_FFMPEG_CAPTURE_OPTIONS=tls_verify;0``) FFmpeg
    reads the video; the probe, by urllib, still checked the certificate, failed and called
    the file live. Now it is taken at its 25 fps, as FFmpeg reads it."""
    import cv2

    from features.pose_estimation import served_file_rate
    from features.pose_estimation.served import served_whole

    _raw_h264(tmp_path)
    with _serving_tls(tmp_path, *self_signed) as address:
        url = f"{address}/camera.h264"
        monkeypatch.delenv("OPENCV_FFMPEG_CAPTURE_OPTIONS", raising=False)
        cap = cv2.VideoCapture(url, cv2.CAP_FFMPEG)
        assert not cap.isOpened()
        assert not served_whole(url, 5.0) and served_file_rate(url, 5.0) is None
        monkeypatch.setenv("OPENCV_FFMPEG_CAPTURE_OPTIONS", "rw_timeout;5000000|tls_verify;0")
        cap = cv2.VideoCapture(url, cv2.CAP_FFMPEG)
        assert cap.isOpened() and cap.read()[0]
        cap.release()
        assert served_file_rate(url, 5.0) == 25.0


# --- a Matroska/WebM whose audio runs on after its last frame -----------------------------


def _with_longer_audio(path: Path, frames: int, audio_s: float) -> Path:
    """``frames`` grey frames at 30 fps (VP8 in WebM, MJPEG in Matroska, MPEG-2 in MPEG-TS
    and a camcorder's M2TS) and a silent mono track (Opus, 48 kHz, 20-ms packets) of
    ``audio_s`` seconds, interleaved by time."""
    av = pytest.importorskip("av", reason="PyAV writes the videos")
    codec = {".webm": "libvpx", ".mkv": "mjpeg"}.get(path.suffix, "mpeg2video")
    options = {"mpegts_m2ts_mode": "1"} if path.suffix == ".m2ts" else {}
    out = av.open(
        str(path), "w", format="mpegts" if codec == "mpeg2video" else None, options=options
    )
    video = out.add_stream(codec, rate=30)
    video.width, video.height = 64, 48
    video.pix_fmt = "yuvj420p" if codec == "mjpeg" else "yuv420p"
    audio = out.add_stream("libopus", rate=48000)
    mux_frames_and_silence(out, video, audio, frames, audio_s, "flt", 960)
    return path


@pytest.mark.parametrize("name", ["clip.webm", "clip.mkv", "clip.ts", "clip.m2ts"])
def test_audio_running_on_after_the_last_frame_is_no_truncation(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 4-s clip, 120 frames at 30 fps, whose sound runs on to 4.3 s (WebM, MKV, MPEG-TS,
    M2TS: none states its frame count): OpenCV counts the container's duration at 30 fps,
    round(4.3 x 30) = 129 frames, and the clip was refused as "truncated or corrupt:
    decoded 120 of 129 frames" (``extract``, ``segment``, ``watch``). Its frames are its
    120 packets: all decode, ``extract`` writes 120 poses."""
    clip = _with_longer_audio(tmp_path / name, 120, 4.3)
    assert_read_by_its_120_frames(clip, 129, tmp_path, capsys)  # 129: the duration's count


def assert_read_by_its_120_frames(
    clip: Path, stated: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``clip`` (120 frames at 30 fps) of which OpenCV states ``stated`` frames: opened as 120
    at 30 fps, all 120 decode, and ``extract`` writes 120 poses."""
    import cv2

    from features.pose_estimation import iter_frames, open_video
    from features.poses import load_pose

    said = cv2.VideoCapture(str(clip))
    assert said.get(cv2.CAP_PROP_FRAME_COUNT) == stated
    said.release()
    cap, info = open_video(clip)
    cap.release()
    assert (info.frames, info.fps) == (120, 30.0)
    assert sum(1 for _ in iter_frames(clip)) == 120
    out = tmp_path / "poses"
    assert main(["extract", str(clip), "--out", str(out)]) == 0, capsys.readouterr().err
    (written,) = out.glob("*.npz")
    assert load_pose(written).n_frames == 120


# --- a sound file given for a video --------------------------------------------------------

SOUNDS = {
    # file name: (codec, sample format, samples a packet, what the line calls it)
    "talk.m4a": ("aac", "fltp", 1024, "an MP4 file of sound alone"),
    "talk.mp4": ("aac", "fltp", 1024, "an MP4 file of sound alone"),
    "talk.wav": ("pcm_s16le", "s16", 1024, "a WAVE file"),
    "talk.mp3": ("libmp3lame", "s16p", 1152, "an MP3 file"),
    "talk.webm": ("libopus", "flt", 960, "a Matroska/WebM file of sound alone"),
    "talk.ogg": ("libopus", "flt", 960, "an Ogg sound file"),
}


def _sound(path: Path) -> Path:
    """One second of silence (48 kHz, mono) in the format the file name says."""
    pytest.importorskip("av", reason="PyAV writes the sound files")
    codec, fmt, n, _kind = SOUNDS[path.name]
    return silence_file(path, codec, fmt, n, 48000)


@pytest.mark.parametrize("name", list(SOUNDS))
def test_a_sound_file_is_refused_as_sound_not_as_damage(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A sound file (an M4A, a sound-only MP4 or WebM as downloaders save a video's sound,
    a WAVE, MP3 or Ogg) given to ``extract``: refused, one line, exit 1, nothing written,
    saying what it is. It said "not a video OpenCV can decode (unknown format, truncated or
    corrupt)", sending the user after damage that is not there."""
    sound = _sound(tmp_path / name)
    argv = ["extract", str(sound), "--out", str(tmp_path / "poses")]
    line = refused(argv, tmp_path, capsys, f"{sound}: sound alone, no video")
    assert line.endswith(f"({SOUNDS[name][3]})") and "truncated" not in line, line


@pytest.mark.parametrize("name", ["clip.webm", "clip.ts"])
def test_watch_of_a_served_clip_whose_sound_runs_on_reads_it_whole(
    name: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """That clip (120 frames, sound to 4.3 s) served over HTTP: ``watch`` refused it as
    "truncated or corrupt: decoded 120 of 129 frames", exit 1. A WebM whose segment ends
    within the length the server states, or an MPEG-TS file (its duration read from the
    packets there are; the server answers range requests, so FFmpeg reads its end):
    watched whole, 120 frames, 0-4 s, as the file here (exit 1 at its end: nobody in view).
    The WebM cut at half its bytes is still refused, as the file here is ("truncated
    Matroska/WebM")."""
    _with_longer_audio(tmp_path / name, 120, 4.3)
    data = (tmp_path / "clip.webm").read_bytes() if name == "clip.webm" else b""
    (tmp_path / "cut.webm").write_bytes(data[: len(data) // 2])
    with _serving(tmp_path, _Ranged) as address:
        capsys.readouterr()
        code = main(["watch", f"{address}/{name}", "--db", str(case_base), "--speed", "0"])
        got = capsys.readouterr()
        # read whole; grey frames, nobody in them: refused at the end (tests/test_hunt45u.py)
        assert code == 1 and got.err.endswith(NOBODY), got.err
        segments = [json.loads(line) for line in got.out.splitlines()]
        assert [(s["start_frame"], s["end_frame"], s["end_s"]) for s in segments] == [(0, 120, 4.0)]
        if name != "clip.webm":
            return
        url = f"{address}/cut.webm"
        argv = ["watch", url, "--db", str(case_base), "--speed", "0"]
        size = len(data) // 2  # refused as the file here is (it said "decoded 54 of 129")
        needle = f"{url}: truncated Matroska/WebM: the served file ends at byte {size:,}, inside"
        refused(argv, tmp_path, capsys, needle)


def test_a_song_with_a_cover_picture_is_refused_as_sound(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An MP3 with its cover picture (FFmpeg shows the picture as a one-picture video
    stream on a 90-kHz clock): ``extract`` said "video declares no usable frame rate (90000
    frames per second; ...)". Now: sound alone, no video (an MP3 file with a picture)."""
    av = pytest.importorskip("av", reason="PyAV writes the song")
    song = tmp_path / "song.mp3"
    out = av.open(str(song), "w")
    sound = out.add_stream("libmp3lame", rate=48000)
    cover = out.add_stream("mjpeg", rate=1)
    cover.width, cover.height, cover.pix_fmt = 64, 48, "yuvj420p"
    cover.disposition = av.stream.Disposition.attached_pic
    picture = av.VideoFrame.from_ndarray(np.full((48, 64, 3), 128, np.uint8), format="rgb24")
    pictures = [*cover.encode(picture), *cover.encode()]
    for k in range(40):
        frame = av.AudioFrame.from_ndarray(np.zeros((1, 1152), np.int16), "s16p", "mono")
        frame.sample_rate, frame.pts = 48000, k * 1152
        for packet in sound.encode(frame):
            out.mux(packet)
    for packet in [*sound.encode(), *pictures]:
        out.mux(packet)
    out.close()
    argv = ["extract", str(song), "--out", str(tmp_path / "poses")]
    refused(argv, tmp_path, capsys, f"{song}: sound alone, no video (an MP3 file with a picture)")


def test_watch_of_a_file_url_is_the_file(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch file:///.../recording.webm`` (a browser's WebM without a duration: OpenCV
    knows no frame count) was taken for a camera: timed by the wall clock, and its end
    "the stream ended after 120 frames (camera or connection lost?)", exit 1. A file URL's
    file has an end: watched as its path is, the same segments (exit 1 at the end: nobody in
    view)."""
    from features.pose_estimation import served_file_rate

    video = _browser_webm(tmp_path / "recording.webm", live=True)
    url = f"file://{video}"
    assert served_file_rate(url, 5.0) == pytest.approx((120 - 1) / 3.985, rel=1e-12)
    results = []
    for source in (str(video), url):
        capsys.readouterr()
        code = main(["watch", source, "--db", str(case_base), "--speed", "0"])
        got = capsys.readouterr()
        results.append((code, got.out))
        # read to its end; grey frames, nobody in them: refused there (tests/test_hunt45u.py)
        assert code == 1 and got.err.endswith(NOBODY), got.err
        assert "camera or connection lost" not in got.err
    assert results[0] == results[1]
    assert [json.loads(line)["end_frame"] for line in results[1][1].splitlines()] == [120]


def test_watch_of_a_file_url_of_a_cut_webm_is_refused_as_its_path_is(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The browser's WebM cut at half its bytes, watched as ``file://...``: refused as the
    path is, "truncated Matroska/WebM", one line, exit 1 (it was watched to the cut, or,
    before, taken for a camera)."""
    _whole, cut = _whole_and_cut("browser-no-duration", tmp_path)
    argv = ["watch", f"file://{cut}", "--db", str(case_base), "--speed", "0"]
    refused(argv, tmp_path, capsys, f"{cut}: truncated Matroska/WebM")
