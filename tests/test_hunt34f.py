"""What hunt 34f found integrating ``posecbr watch`` into another program (a robot's
supervisor reading its JSON lines through a pipe): a SIGTERM killed the watch with nothing
said, no last segment, no video and its hidden temporary left behind; a reader closing the
pipe made it exit 1 blaming the ``--out`` video ("cannot write: Broken pipe") and keep no
video.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from features.errors import DataError
from features.fileio import atomic_path
from tests.test_watch import (
    _watch,
    case_base,  # noqa: F401 - the fixture: CMU 13_29's windows
)

SQUATS = ("videos", "squat", "tfjs_pose_squats_pexels4838220.mp4")  # 65 frames at 5 fps


def _frames(video: Path) -> int:
    """The frames a video decodes to, counted one by one."""
    import cv2

    cap = cv2.VideoCapture(str(video))
    n = 0
    while cap.read()[0]:
        n += 1
    cap.release()
    return n


def _watched(stderr: str) -> int:
    """N of the final report's "watched N frames"."""
    return int(stderr.split("watched ")[1].split(" frame")[0])


def test_sigterm_ends_a_watch_as_ctrl_c_does(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
) -> None:
    """A real process watching the squat video at its own rate (13 s), sent SIGTERM (what
    ``kill``, systemd, ``docker stop`` and ``Popen.terminate()`` send) once it has printed
    its first segment: it ends as at Ctrl-C, the segment in progress printed, the latency
    report, the --out video with every frame watched, exit 0. (It was killed: status -15,
    nothing printed, no video, and its 0600 temporary ``.out.mp4.pid...mp4`` left.)"""
    video = shared_data.joinpath(*SQUATS)
    out = tmp_path / "out.mp4"
    run = _watch([str(video), "--db", str(case_base), "--out", str(out)])
    assert run.stdout is not None
    first = run.stdout.readline()  # as test_watch's Ctrl-C: a window seen, about 10 s left
    run.send_signal(signal.SIGTERM)
    stdout, stderr = run.communicate(timeout=120)
    assert run.returncode == 0, stderr
    assert "latency frame to label" in stderr and "Traceback" not in stderr, stderr
    watched = _watched(stderr)
    assert 0 < watched < 65, stderr
    lines = [json.loads(line) for line in (first + stdout).splitlines()]
    assert lines and lines[0]["start_frame"] == 0 and lines[-1]["end_frame"] == watched
    assert [p.name for p in tmp_path.iterdir()] == ["out.mp4"]  # no temporary left
    assert _frames(out) == watched


def test_a_reader_that_closes_the_pipe_ends_the_watch_and_keeps_the_video(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
) -> None:
    """A program reading watch's lines through a pipe takes the first and closes it (as
    ``| head -1`` does): the watch ends there as at Ctrl-C, saying so in one note, the
    latency report and the --out video of the frames watched, exit 0. (The next line raised
    BrokenPipeError inside the video's atomic write, which blamed the video: "posecbr
    watch: error: out.mp4: cannot write: Broken pipe", exit 1, no video.)"""
    video = shared_data.joinpath(*SQUATS)
    out = tmp_path / "out.mp4"
    run = _watch([str(video), "--db", str(case_base), "--out", str(out), "--speed", "0"])
    assert run.stdout is not None and run.stderr is not None
    first = json.loads(run.stdout.readline())
    assert first["start_frame"] == 0
    run.stdout.close()
    stderr = run.stderr.read()
    assert run.wait(timeout=120) == 0, stderr
    assert "Traceback" not in stderr and "BrokenPipe" not in stderr, stderr
    assert f"note: {video}: standard output was closed by its reader" in stderr, stderr
    assert "latency frame to label" in stderr, stderr
    assert [p.name for p in tmp_path.iterdir()] == ["out.mp4"]
    assert _frames(out) == _watched(stderr) >= first["end_frame"]


def test_a_broken_pipe_inside_an_atomic_write_is_not_the_files_fault(tmp_path: Path) -> None:
    """Standard output's reader gone while a file is being written: the BrokenPipeError
    goes on as it is (the command ends quietly on it) instead of a DataError naming the
    file ("cannot write: Broken pipe"); the file is not written, no temporary is left."""
    dest = tmp_path / "out.json"
    with pytest.raises(BrokenPipeError), atomic_path(dest) as tmp:
        tmp.write_text("{}")
        raise BrokenPipeError(32, "Broken pipe")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(
        DataError, match=r"cannot write: the disk is full \(No space left on device\)"
    ):
        with atomic_path(dest) as tmp:
            raise OSError(28, "No space left on device")
    assert list(tmp_path.iterdir()) == []


def _readme_block(first: str) -> str:
    """The README's ```python block holding the line ``first``, as written."""
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    at = text.index(first)
    start = text.rindex("```python\n", 0, at) + len("```python\n")
    return text[start : text.index("```", at)]


def test_the_readme_python_example_segments_and_watches(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
) -> None:
    """The README showed no way to segment or watch from Python (only the commands): its
    example, run as written in a folder holding the files it names (the case base, CMU
    13_31 as a pose file, a video), prints segment's segments of 13_31 (3017 frames at
    120 fps) and watch's lines of the video (65 frames at 5 fps), each strict JSON, one
    after the other without a gap."""
    import shutil

    from features.poses import save_pose
    from features.readers.asfamc import read_asf_amc

    shutil.copy(case_base, tmp_path / "cmu.sqlite")
    # the video's own case base, as the example loads it (here the same one: what is checked
    # is the lines, not the activities)
    shutil.copy(case_base, tmp_path / "workout.sqlite")
    (tmp_path / "cmu").mkdir()
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_31.amc",
    )
    save_pose(seq, tmp_path / "cmu" / "13_31.npz")
    (tmp_path / "workout").mkdir()
    shutil.copy(shared_data.joinpath(*SQUATS), tmp_path / "workout" / "workout.mp4")
    code = _readme_block("from cbr.live import LiveSegmenter")
    run = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stderr

    def strict(word: str) -> None:
        raise ValueError(word)

    lines = [json.loads(line, parse_constant=strict) for line in run.stdout.splitlines()]
    restart = next(i for i, s in enumerate(lines) if i and s["start_frame"] == 0)
    for part, frames, fps in ((lines[:restart], 3017, 120.0), (lines[restart:], 65, 5.0)):
        assert [s["start_frame"] for s in part] == [0] + [s["end_frame"] for s in part[:-1]]
        assert part[-1]["end_frame"] == frames
        assert part[-1]["end_s"] == round(frames / fps, 3)
        assert all(s["label"] is None or isinstance(s["label"], str) for s in part)
    assert "repetition_frames" in lines[0] and "repetition_frames" not in lines[-1]
