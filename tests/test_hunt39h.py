"""Hunt 39h: a new user's afternoon, following README from the top.

``extract`` of a folder (or labels CSV) prints no line per clip, only the counts: what a single
video's line says beyond its frames (the pose jumping to another person, a variable frame rate
resampled, a gap left missing) was said nowhere, though README says ``extract`` tells it. Each
such clip now gets a note on stderr, in the clip line's words.

``extract clip.mp4 --out out.mp4`` made a folder named out.mp4: such an ``--out`` is refused.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from posecbr.cli import main
from tests.test_person_jump import LEAVES, _leave_video


def test_extract_of_a_folder_says_where_a_clips_pose_jumps(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    videos, out = tmp_path / "videos", tmp_path / "poses"
    (videos / "lunge").mkdir(parents=True)
    _leave_video(shared_data, videos / "lunge" / "leaves.avi")
    assert main(["extract", str(videos), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    # the lunging woman leaves at frame 125 (5.00 s at 25 fps), the other is taken at once
    assert printed.err.splitlines() == [
        f"note: {out / 'lunge' / 'leaves.npz'}: the pose jumps to another person at frame "
        f"{LEAVES} (5.00 s)"
    ]
    assert printed.out.strip() == f"1 extracted, 0 up to date, 0 failed -> {out}"


def test_the_notes_of_a_run_of_several_clips_are_their_lines_remarks(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A pose file up to date whose overlay alone was drawn says the same as one extracted;
    a clip with nothing more to say, or one that failed, gets no note."""
    from posecbr.commands.extract import _summary

    results = [
        ("done", Path("p/a.npz"), "50 frames, 0 without a person"),
        (
            "drawn",
            Path("p/b.npz"),
            "up to date, 75 frames, 2 without a person; variable frame rate: resampled to "
            "25 fps; 3.0 s without frames at 2.0-5.0 s left missing; its overlay drawn",
        ),
        ("skipped", Path("p/c.npz"), "up to date"),
    ]
    assert _summary(results, Path("p")) == 0
    printed = capsys.readouterr()
    assert printed.err.splitlines() == [
        "note: p/b.npz: variable frame rate: resampled to 25 fps; 3.0 s without frames at "
        "2.0-5.0 s left missing"
    ]
    assert (
        printed.out.strip()
        == "1 extracted, 2 up to date (1 overlay drawn from them), 0 failed -> p"
    )


def _grey_video(path: Path, frames: int = 5) -> Path:
    """A few grey frames (MJPG: no codec's run-to-run noise): a video nobody is in."""
    import cv2
    import numpy as np

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 25, (64, 48))
    for _ in range(frames):
        writer.write(np.full((48, 64, 3), 128, np.uint8))
    writer.release()
    return path


@pytest.mark.parametrize("out", ["out.mp4", "clip.avi", "still.png"])
def test_extract_refuses_an_out_that_names_a_video_or_picture(
    out: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract clip.avi --out out.mp4`` made a folder named out.mp4 holding clip.npz, and
    ``--out clip.avi``, the input itself, was refused as "output is not a folder": a video
    was meant, which is --overlay's. Refused in one line naming --out, nothing made."""
    from tests.badinput import refused

    _grey_video(tmp_path / "clip.avi")
    line = refused(
        ["extract", str(tmp_path / "clip.avi"), "--out", str(tmp_path / out)],
        tmp_path,
        capsys,
        f"{tmp_path / out}: --out names the folder for the pose files or, for one video, its "
        ".npz pose file, not a video or picture (--overlay writes a video",
    )
    assert "output is not a folder" not in line
    # a folder or labels CSV alike
    (tmp_path / "videos" / "grey").mkdir(parents=True)
    _grey_video(tmp_path / "videos" / "grey" / "a.avi")
    refused(
        ["extract", str(tmp_path / "videos"), "--out", str(tmp_path / out)],
        tmp_path,
        capsys,
        "--out names the folder for the pose files",
    )


def test_extract_into_an_existing_folder_named_like_a_video_is_taken(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A folder that exists is a folder, whatever its name says."""
    _grey_video(tmp_path / "clip.avi")
    (tmp_path / "poses.mp4").mkdir()
    assert main(["extract", str(tmp_path / "clip.avi"), "--out", str(tmp_path / "poses.mp4")]) == 0
    assert (tmp_path / "poses.mp4" / "clip.npz").is_file()
    assert capsys.readouterr().out.startswith(f"done: {tmp_path / 'poses.mp4' / 'clip.npz'}")
