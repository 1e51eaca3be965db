"""``posecbr watch --out``: the video of what was watched outlives a kill (hunt 49b).

OpenCV's MP4 writer puts the index (the ``moov`` box) at the end, when the writer is
released: a watch killed with ``kill -9`` left an MP4 temporary no player opens, and the next
writer of the same output removed it. The watch now writes a copy of the drawn frames in a
container that needs no index at its end (:data:`posecbr.commands.watch.RESCUE_SUFFIX`), and
the next writer keeps a killed watch's copy under a visible name
(:func:`features.fileio.remove_stale_temporaries`). (A stream lost keeps its video:
tests/test_watch.py.)
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from features.fileio import remove_stale_temporaries, write_bytes_atomic
from tests.badinput import small_case_base
from tests.test_fileio import _dead_pid


def test_the_next_writer_keeps_a_killed_watch_s_copy_under_a_visible_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A dead watch's copy of its video (``.seen.mp4.pid...partial.nut``) is kept as
    ``seen.partial.nut`` by the next writer of ``seen.mp4``, byte for byte, and said in one
    note; one there already is kept as it was (the copy goes to ``seen.partial-2.nut``). The
    dead watch's MP4 temporary is removed as before, and a live watch's copy is left alone.
    (Every dead writer's temporary was removed, the copy with it.)"""
    host, dead = socket.gethostname(), _dead_pid()
    out = tmp_path / "seen.mp4"
    copy = tmp_path / f".seen.mp4.pid{dead}@{host}.k2x9.partial.nut"
    mp4 = tmp_path / f".seen.mp4.pid{dead}@{host}.a7q1.mp4"
    live = tmp_path / f".seen.mp4.pid{os.getppid()}@{host}.b3z0.partial.nut"
    earlier = tmp_path / "seen.partial.nut"
    for path, data in ((copy, b"frames"), (mp4, b"no moov"), (live, b"at work")):
        path.write_bytes(data)
    earlier.write_bytes(b"kept by the user")
    write_bytes_atomic(out, b"the next video")
    kept = tmp_path / "seen.partial-2.nut"
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted([live.name, out.name, earlier.name, kept.name])
    assert kept.read_bytes() == b"frames" and earlier.read_bytes() == b"kept by the user"
    assert out.read_bytes() == b"the next video" and live.read_bytes() == b"at work"
    assert capsys.readouterr().err == (
        f"note: {out}: a writer of it (process {dead}) was killed before it finished: what it"
        f" had written is kept as {kept}\n"
    )


#: a real watch of a real video whose stream holds still after N frames (no stall: --stall
#: 600), saying on stderr when the N-th frame has been drawn and written
_DRIVER = """
import sys, time
import features.pose_estimation as pose_estimation
from posecbr.cli import main
from posecbr.commands import watch

n = int(sys.argv[1])
real_stream, real_write = pose_estimation.stream_poses, watch.Watcher._write

def stream(*args, **kwargs):
    for i, frame in enumerate(real_stream(*args, **kwargs)):
        yield frame
        if i + 1 == n:
            time.sleep(600)

def write(self, bgr):
    real_write(self, bgr)
    if self.drawn == n:
        print("DRAWN", file=sys.stderr, flush=True)

pose_estimation.stream_poses, watch.Watcher._write = stream, write
sys.exit(main(["watch", *sys.argv[2:]]))
"""


def _frames(path: Path, scale: int = 8) -> list[np.ndarray]:
    """A video's frames decoded by OpenCV, each shrunk ``scale`` times (for comparing)."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        h, w = bgr.shape[:2]
        frames.append(cv2.resize(bgr, (w // scale, h // scale)).astype(float))
    cap.release()
    return frames


def test_a_watch_killed_leaves_its_video_playable_to_near_the_kill(
    shared_data: Path, tmp_path: Path
) -> None:
    """A real ``posecbr watch --out seen.mp4`` of the squat video, killed with SIGKILL once it
    has drawn and written 26 frames: ``seen.mp4`` is not there (never half-written under its
    name), and the copy it leaves decodes with OpenCV, every one of the 26 frames, frame i
    the video's frame i (the nearest of its frames, the drawing on top aside); the next
    writer of ``seen.mp4`` keeps it as ``seen.partial.nut`` and removes the watch's other
    temporaries (the MP4's, empty, and the pipe the copy came through). (The MP4 temporary a
    kill left had no index: no player opened it, and the next writer removed it; the copy
    held what FFmpeg had flushed, 256 KiB at a time: 22 of these 26 frames, the last cut,
    hunt 50d.)"""
    n = 26
    video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    out = tmp_path / "seen.mp4"
    db = small_case_base(tmp_path / "cb")  # any case base: the video is what is looked at
    argv = [str(video), "--db", str(db), "--out", str(out), "--speed", "0",
            "--stall", "600"]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    proc = subprocess.Popen(
        [sys.executable, "-c", _DRIVER, str(n), *argv],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert proc.stderr is not None
        said = [proc.stderr.readline()]
        while said[-1] not in ("DRAWN\n", ""):
            said.append(proc.stderr.readline())
        assert said[-1] == "DRAWN\n", said
    finally:
        proc.kill()
        proc.wait()
    assert not out.exists()
    left_by_kill = [p for p in tmp_path.iterdir() if p.name != "cb"]
    copies = [p for p in left_by_kill if p.name.endswith(".partial.nut")]
    assert len(copies) == 1 and copies[0].name.startswith(f".seen.mp4.pid{proc.pid}@")
    source = _frames(video)
    left = _frames(copies[0])
    assert len(left) == n
    for i, frame in enumerate(left):  # each the video's frame of its index
        differences = [np.abs(frame - s).mean() for s in source]
        assert int(np.argmin(differences)) == i, (i, differences)
    assert len(left_by_kill) == 3  # the copy, the MP4 temporary and the pipe
    assert remove_stale_temporaries(tmp_path, out.name) == 2  # the MP4 temporary, the pipe
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cb", "seen.partial.nut"]
    assert len(_frames(tmp_path / "seen.partial.nut")) == len(left)
