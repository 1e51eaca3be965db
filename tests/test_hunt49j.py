"""``posecbr watch`` of a source that gives no video, said for what it is (hunt 49j): a URL
whose server answers an error status, gives a web page or text, or is not there, and a
camera index with no camera behind it. Each was "cannot open camera or stream". And a stop
(SIGTERM, Ctrl-C) that comes as a compiled module is imported, said as the stop it is."""

from __future__ import annotations

import signal
import socket
from pathlib import Path

import pytest

from features.errors import DataError
from features.interrupts import raise_interrupt
from features.pose_estimation import stream_poses
from posecbr.cli import main
from tests.test_hunt34c import _serving


def _refused(source: str | int) -> str:
    with pytest.raises(DataError) as refused:
        next(iter(stream_poses(source, timeout_s=5.0)))
    return str(refused.value)


def test_a_404_a_web_page_no_server_and_no_camera_are_said_so(tmp_path: Path) -> None:
    """python -m http.server answers 404 for a file it has not, gives a .txt file as
    text/plain and a folder as its listing, text/html; no server listens at a port bound and
    let go ("connection refused", naming the address); a camera index past any camera here
    has no camera behind it. (The command's line for a 404: tests/test_watch.py.)"""
    (tmp_path / "notes.txt").write_text("not a video\n")
    with _serving(tmp_path) as address:
        gone = _refused(f"{address}/gone.mp4")
        text = _refused(f"{address}/notes.txt")
        listing = _refused(f"{address}/")
    assert gone == f"{address}/gone.mp4: the server answered HTTP 404 (Not Found)"
    assert text == f"{address}/notes.txt: the server gives text/plain, not a video"
    assert listing == f"{address}/: the server gives text/html, not a video"
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        free = f"127.0.0.1:{s.getsockname()[1]}"
    assert _refused(f"http://{free}/clip.mp4") == (
        f"http://{free}/clip.mp4: no server answers at {free} (connection refused)"
    )
    assert _refused(97) == "97: cannot open camera: none at this index, or another program holds it"


@pytest.mark.parametrize(
    ("signum", "said", "status"),
    [
        (signal.SIGTERM, "posecbr watch: terminated (SIGTERM)\n", 143),
        (signal.SIGINT, "posecbr watch: interrupted\n", 130),
    ],
    ids=["sigterm", "ctrl-c"],
)
def test_a_stop_while_a_compiled_module_is_imported_is_the_stop(
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    signum: int,
    said: str,
    status: int,
) -> None:
    """SIGTERM 0.6 s into a watch, as onnxruntime was imported: pybind11's module init
    turns the KeyboardInterrupt it raises into "ImportError: initialization failed" raised
    from it, and the watch said "internal error, a bug in posecbr" (exit 70). The stop is
    said as the stop it is: terminated, 143 (Ctrl-C: interrupted, 130), as at any other
    moment (the import stood in for by raising as pybind11 raises)."""
    import posecbr.commands.watch as watch

    def importing(_args: object) -> int:
        try:
            raise_interrupt(signum)
        except KeyboardInterrupt as exc:
            raise ImportError("initialization failed") from exc

    monkeypatch.setattr(watch, "run", importing)
    capsys.readouterr()
    assert main(["watch", "0", "--db", "cb.sqlite"]) == status
    got = capsys.readouterr()
    assert (got.out, got.err) == ("", said)


def test_a_negative_camera_index_is_told_where_cameras_are_numbered_from(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch -1`` (OpenCV's "any camera"): no file of that name, and no camera index
    either: cameras are numbered from 0. It said only "-1: no such video file"."""
    capsys.readouterr()
    assert main(["watch", "-1", "--db", str(tmp_path / "cb.sqlite")]) == 1
    got = capsys.readouterr()
    assert got.err == (
        "posecbr watch: error: -1: no such video file, and a camera index is a whole number"
        " from 0 (the first camera)\n"
    )
