"""Hunt 34c: a guess for a swapped pair of letters in a three-letter value (`--similarity
dwt`), and ``watch`` of a browser's WebM or a raw H.264 stream served over HTTP, played as
the same file on this machine is."""

from __future__ import annotations

import functools
import http.server
import json
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from posecbr.cli import main
from tests.badinput import refused, small_case_base
from tests.test_cbr_cli import _write_classes

# on one xdist worker: the module's clips, case_base made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt34c")


@pytest.fixture(scope="module")
def clips(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Synthetic arm movements (tests.test_cbr_cli's: three activities, two clips each)."""
    return _write_classes(tmp_path_factory.mktemp("clips"), 2, 5)


SIMILARITIES = ["dtw", "euclidean", "signature"]


@pytest.mark.parametrize(
    ("typed", "known", "guess"),
    [
        # two neighbouring letters swapped: every letter kept, difflib's ratio 0.67
        ("dwt", SIMILARITIES, "dtw"),
        ("tdw", SIMILARITIES, "dtw"),
        ("ncn", ["novelty-benefit", "cnn", "renn", "icf"], "cnn"),
        ("lal", ["angles", "instantaneous", "all"], "all"),
        # longer words: one edit was guessed before and still is
        ("margni", ["spread-margin", "activity-margin", "margin", "margin-distance"], "margin"),
        ("anlges", ["angles", "instantaneous", "all"], "angles"),
        ("eucldean", SIMILARITIES, "euclidean"),
    ],
)
def test_a_typo_gets_its_guess(typed: str, known: list[str], guess: str) -> None:
    from features.text import did_you_mean

    assert did_you_mean(typed, known) == f" (did you mean {guess!r}?)"


@pytest.mark.parametrize(
    ("typed", "known"),
    [
        ("xyz", SIMILARITIES),
        ("abc", SIMILARITIES),
        ("wtd", SIMILARITIES),  # dtw backwards: two swaps, not one
        ("twd", SIMILARITIES),  # a letter moved two places
        ("dtx", SIMILARITIES),  # a wrong letter: two of three kept, as cnm for cnn
        ("cnm", ["cnn"]),
        ("mxi", ["max", "min"]),
    ],
)
def test_a_non_typo_gets_no_guess(typed: str, known: list[str]) -> None:
    from features.text import did_you_mean

    assert did_you_mean(typed, known) == ""


def test_one_swap_alike_for_two_names_is_no_guess() -> None:
    """``bac`` is one swap from both ``abc`` and ``bca``: no guess rather than the first;
    a name close by difflib comes before one a swap away."""
    from features.text import did_you_mean

    assert did_you_mean("bac", ["abc", "bca"]) == ""
    assert did_you_mean("bac", ["abc"]) == " (did you mean 'abc'?)"
    assert did_you_mean("ba", ["ab", "ba2"]) == " (did you mean 'ba2'?)"  # ratio 0.8


def test_train_guesses_a_swapped_similarity(
    clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`train --similarity dwt` listed the known measures alone; now "(did you mean 'dtw'?)".
    `--similarity xyz` still gets none."""
    argv = ["train", str(clips), "--db", str(tmp_path / "cb.db"), "--similarity", "dwt"]
    line = refused(argv, tmp_path, capsys, "--similarity", "'dwt'")
    assert line.endswith("(did you mean 'dtw'?)"), line
    argv[-1] = "xyz"
    assert "did you mean" not in refused(argv, tmp_path, capsys, "--similarity", "'xyz'")


def test_a_swapped_choice_gets_a_guess(capsys: pytest.CaptureFixture[str]) -> None:
    """argparse's choices share the guess: `train --editor ncn`."""
    with pytest.raises(SystemExit) as exit_:
        main(["train", "data", "--db", "cb.sqlite", "--editor", "ncn"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "invalid choice: 'ncn'" in err, err
    assert "(did you mean 'cnn'?); see posecbr train --help" in err, err


# --- watch of a file served over HTTP: a browser's WebM, a raw H.264 stream ---------------

# a browser's frame times: 28 to 39 ms apart (about 30 fps), on no regular pattern
BROWSER_GAPS_MS = [33, 34, 37, 39, 28, 29, 37, 39, 30, 31, 38, 33, 31, 37, 31, 32, 35, 34, 29,
                   28, 38, 37, 38, 34, 37, 31, 33, 37, 29, 31, 29, 33, 39, 29, 32, 32, 38, 30,
                   34]  # fmt: skip
N_BROWSER = 120
BROWSER_PTS_MS = [
    sum(BROWSER_GAPS_MS[i % len(BROWSER_GAPS_MS)] for i in range(k)) for k in range(N_BROWSER)
]


def _grey(n: int) -> list[Any]:
    import numpy as np

    return [np.full((48, 64, 3), (5 * k) % 250, np.uint8) for k in range(n)]


def _encode(
    path: Path, pts_ms: list[int], codec: str, rate: int | None, options: dict[str, str]
) -> Path:
    """Grey frames at these presentation times (1-ms time base) in the container the file
    name says; ``rate``: the one the stream states (None: none, as a browser writes)."""
    from tests.test_video_vfr import _write  # skips where PyAV, which writes them, is missing

    return _write(path, pts_ms, _grey(len(pts_ms)), rate, codec, options)


def _browser_webm(path: Path, live: bool) -> Path:
    """A WebM as a browser's MediaRecorder writes it: VP8 on a millisecond clock, no frame
    rate stated (OpenCV then says 1000 fps); ``live``: no duration either (as MediaRecorder
    writes it: OpenCV then knows no frame count)."""
    return _encode(path, BROWSER_PTS_MS, "libvpx", None, {"live": "1"} if live else {})


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 (the base's name)
        """No request lines on stderr."""


class _Unsized(_Quiet):
    """Sends a file as a live source sends its stream: no length stated, until it ends."""

    def do_GET(self) -> None:  # noqa: N802 (the base's name)
        data = Path(self.translate_path(self.path)).read_bytes()
        self.send_response(200)
        self.send_header("Content-Type", "application/octet-stream")
        self.end_headers()
        self.wfile.write(data)
        self.close_connection = True


class _QuietServer(http.server.ThreadingHTTPServer):
    def handle_error(self, request: Any, client_address: Any) -> None:
        """No traceback on stderr when the client hangs up (watch stops reading)."""


@contextmanager
def _serving(folder: Path, handler: type[_Quiet] = _Quiet) -> Iterator[str]:
    """The address of ``folder`` served over HTTP on this machine while the block runs."""
    server = _QuietServer(("127.0.0.1", 0), functools.partial(handler, directory=str(folder)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _watch(source: str, db: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    capsys.readouterr()
    code = main(["watch", source, "--db", str(db), "--speed", "0"])
    got = capsys.readouterr()
    return code, got.out, got.err


@pytest.mark.parametrize("live", [False, True], ids=["with-duration", "no-duration"])
def test_a_served_browser_webm_is_taken_at_its_frames_rate(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], live: bool
) -> None:
    """A browser's WebM (120 frames 28 to 39 ms apart, no frame rate stated: OpenCV says
    1000 fps) on this machine is taken at its frames' own rate, 119 intervals in 3.985 s
    (29.862 fps), and resampled to it: 120 frames (k / rate up to 3.985 s). Served over
    HTTP it was taken at 1000 fps (3986 pose frames, each movement spread over 33 times as
    many), or, without a duration (as MediaRecorder writes it), as a camera: timed by the
    wall clock, and its end "the stream ended ... (camera or connection lost?)", exit 1.
    Now it is watched as the file here is: the same rate, frames, times and end."""
    from features.pose_estimation import open_video, served_file_rate

    span_s = BROWSER_PTS_MS[-1] / 1000
    assert span_s == 3.985
    rate = (N_BROWSER - 1) / span_s
    video = _browser_webm(tmp_path / "recording.webm", live)
    cap, info = open_video(video)
    cap.release()
    assert info.fps == pytest.approx(rate, rel=1e-12)
    here = _watch(str(video), case_base, capsys)
    with _serving(tmp_path) as address:
        url = f"{address}/recording.webm"
        assert served_file_rate(url, 5.0) == pytest.approx(rate, rel=1e-12)
        served = _watch(url, case_base, capsys)
    # read to the end; grey frames, nobody in them: refused there (tests/test_hunt45u.py)
    assert here[0] == served[0] == 1, served
    assert served[2].endswith("with nobody in view in any of them: no activity to label\n"), served[
        2
    ]
    segments = [json.loads(line) for line in served[1].splitlines()]
    assert [(s["start_frame"], s["end_frame"], s["explanation"]) for s in segments] == [
        (0, N_BROWSER, "nobody in view")
    ]
    assert segments[-1]["end_s"] == pytest.approx(N_BROWSER / rate, abs=1e-3)
    assert served[1] == here[1]
    note = f"resampled to {rate:g} fps as they come"
    assert note in here[2] and note in served[2].replace(url, str(video)), served[2]


def test_a_served_webm_longer_than_the_window_takes_its_first_frames_rate(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The rate of a served file is read from its start, not the whole stream: with a 1-s
    window, the packets up to the first 1 s or more after the first, 31 of them (frame 30
    at 1.010 s): 30 intervals in 1.010 s."""
    from features.pose_estimation import served_file_rate, video

    k = next(i for i, t in enumerate(BROWSER_PTS_MS) if t >= 1000)
    assert (k, BROWSER_PTS_MS[k]) == (30, 1010)
    _browser_webm(tmp_path / "recording.webm", live=True)
    monkeypatch.setattr(video, "RATE_WINDOW_S", 1.0)
    with _serving(tmp_path) as address:
        assert served_file_rate(f"{address}/recording.webm", 5.0) == pytest.approx(30 / 1.010)


def test_a_served_raw_h264_stream_is_read_at_its_rate_to_its_end(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A raw H.264 stream (``.h264``: no container, no frame times, no frame count; FFmpeg
    takes it at 25 fps) on this machine is read at 25 fps and ends at its end: 100 frames,
    one segment with nobody in view, 0-4 s. Served over HTTP it was taken for a camera:
    timed by the wall clock, and its end "the stream ended after ... frames (camera or
    connection lost?)", exit 1. Now it is read as the file is. The same bytes sent as a
    camera sends its stream (no length) are still a live source."""
    from features.pose_estimation import served_file_rate, stream_poses

    n = 100
    _encode(tmp_path / "camera.h264", [40 * k for k in range(n)], "libx264", 25, {})
    here = _watch(str(tmp_path / "camera.h264"), case_base, capsys)
    with _serving(tmp_path) as address:
        url = f"{address}/camera.h264"
        assert served_file_rate(url, 5.0) == 25.0
        frames = list(stream_poses(url, fps=25.0, timeout_s=5.0))
        served = _watch(url, case_base, capsys)
    assert [f.time_s for f in frames] == [k / 25 for k in range(n)]
    assert [f.video_time_s == f.video_time_s for f in frames] == [True] + [False] * (n - 1)
    # read to the end; grey frames, nobody in them: refused there (tests/test_hunt45u.py)
    assert here[0] == served[0] == 1, served
    assert served[2].endswith("with nobody in view in any of them: no activity to label\n"), served[
        2
    ]
    segments = [json.loads(line) for line in served[1].splitlines()]
    assert [(s["start_frame"], s["end_frame"], s["end_s"], s["explanation"]) for s in segments] == [
        (0, n, 4.0, "nobody in view")
    ]
    assert served[1] == here[1]
    assert "camera or connection lost" not in served[2] and "variable" not in served[2]
    with _serving(tmp_path, _Unsized) as address:
        assert served_file_rate(f"{address}/camera.h264", 5.0) is None


def test_only_a_whole_binary_file_counts_as_served_whole(tmp_path: Path) -> None:
    """A server that states a file's length gives it whole; a playlist (text: its own length
    says nothing of the stream's) or a stream without a length is no file."""
    from features.pose_estimation.served import served_whole

    (tmp_path / "clip.bin").write_bytes(b"\x00\x00\x00\x01\x67" + bytes(100))
    (tmp_path / "live.m3u8").write_text("#EXTM3U\n#EXT-X-TARGETDURATION:2\n")
    (tmp_path / "marked.m3u8").write_bytes(b"\xef\xbb\xbf#EXTM3U\n#EXT-X-VERSION:3\n")
    with _serving(tmp_path) as address:
        assert served_whole(f"{address}/clip.bin", 5.0)
        assert not served_whole(f"{address}/live.m3u8", 5.0)
        assert not served_whole(f"{address}/marked.m3u8", 5.0)
        assert not served_whole(f"{address}/none.bin", 5.0)
    with _serving(tmp_path, _Unsized) as address:
        assert not served_whole(f"{address}/clip.bin", 5.0)
    assert not served_whole("rtsp://127.0.0.1:1/stream", 5.0)
