"""Two refusals the video hunt (23) left giving the wrong reason or coming late: ``watch`` of
a named pipe said "no such video file"; ``segment --overlay`` of a video too large for an
MP4 ran the pose model over the whole video before finding it could not write the overlay.
Each: one line naming the file and the real problem, exit 1, nothing written or changed.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import features.pose_estimation  # noqa: F401  (silences FFmpeg before any video is opened)
from posecbr.cli import main
from tests.badinput import small_case_base, snapshot, too_wide_video


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def test_watch_of_a_named_pipe_says_it_is_a_pipe(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pipe = tmp_path / "live.mp4"
    os.mkfifo(pipe)
    assert main(["watch", str(pipe), "--db", str(case_base)]) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        f"posecbr watch: error: {pipe}: is a pipe, socket or device, not a video file"
    )
    assert captured.out == "" and list(tmp_path.iterdir()) == [pipe] and pipe.is_fifo()
    gone = tmp_path / "gone.mp4"  # a file that is not there is still said to be missing
    assert main(["watch", str(gone), "--db", str(case_base)]) == 1
    assert _one_line(capsys.readouterr().err) == (
        f"posecbr watch: error: {gone}: no such video file"
    )


def test_segment_overlay_too_wide_for_mp4_is_refused_before_the_model_runs(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """8192 pixels wide, one more than an MP4 frame can be; 40 frames, no person in view
    (the model would have said "nobody in view" after reading them all)."""
    video = too_wide_video(tmp_path / "wide.avi", frames=40)
    overlay = tmp_path / "overlay.mp4"
    before = snapshot(tmp_path)
    argv = ["segment", str(video), "--db", str(case_base), "--overlay", str(overlay)]
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert _one_line(captured.err) == (
        f"posecbr segment: error: {overlay}: cannot encode an MP4 overlay of 8192x16 frames:"
        " MP4 frames are at most 8191 pixels a side"
    )
    assert captured.out == "" and snapshot(tmp_path) == before
