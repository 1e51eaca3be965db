"""Session 44's fresh-eyes hunt over issue 14's commands (segment, reps, watch, label files)."""

from __future__ import annotations

from pathlib import Path

import pytest

from features.errors import DataError
from features.pose_estimation.video import open_video
from tests.badinput import refused, small_case_base
from tests.test_hunt34c import _serving


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("hunt44h_cb"))


def _label_file(shared_data: Path, folder: Path) -> Path:
    """CMU 13_31's label file (its 252 codes: FFmpeg opens a text file of 400 bytes or more)
    copied into ``folder``."""
    path = folder / "13_31.txt"
    path.write_bytes((shared_data / "cmu-mocap6" / "truelabels" / "13_31.txt").read_bytes())
    return path


def test_watch_refuses_a_label_file_given_for_its_video(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """FFmpeg's tty demuxer plays a ``.txt`` file as a video of its characters drawn in
    frames: ``watch labels.txt`` ran the pose model on three frames of digits and said the
    stream "ended after 3 frames (0.12 s), before the shortest window"; a longer text file
    was watched to its end, "nobody in view", exit 0."""
    labels = _label_file(shared_data, tmp_path)
    refused(["watch", str(labels), "--db", str(case_base), "--speed", "0"], tmp_path, capsys,
            str(labels), "a text file, not a video")  # fmt: skip


def test_open_video_refuses_a_text_file(shared_data: Path, tmp_path: Path) -> None:
    with pytest.raises(DataError, match="a text file, not a video"):
        open_video(_label_file(shared_data, tmp_path))


def test_watch_refuses_a_label_file_served_over_http(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same file served over HTTP: the stream "ended after 3 frames"."""
    served = tmp_path / "served"
    served.mkdir()
    _label_file(shared_data, served)
    with _serving(served) as address:
        url = f"{address}/13_31.txt"
        refused(["watch", url, "--db", str(case_base), "--speed", "0"], tmp_path, capsys,
                url, "a text file, not a video")  # fmt: skip
