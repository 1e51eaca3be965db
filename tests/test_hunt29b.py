"""Hunt 29b: outputs inside a folder read as class folders, compare's outputs named as an
input, an empty case base through the Python API, and repetition counting, conversion and
case base actions (``reps``, ``convert``, ``casebase``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.badinput import good_pose_file, refused

# ------------------------------------------------ outputs inside a folder of class folders


def _video(path: Path) -> Path:
    """Two grey frames (nobody in view): refusals come before any frame is read."""
    import cv2

    path.parent.mkdir(parents=True, exist_ok=True)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 10.0, (32, 32))
    for k in range(2):
        writer.write(np.full((32, 32, 3), 60 + k, np.uint8))
    writer.release()
    return path


@pytest.mark.parametrize(
    ("option", "where", "needles"),
    [
        ("--overlay", "videos/ovl", ["overlay folder is inside the input folder", "videos"]),
        ("--out", "videos/poses", ["output folder is inside the input folder", "videos"]),
        ("--out", "videos", ["output folder is the input folder"]),
    ],
    ids=["overlay inside", "out inside", "out is the input"],
)
def test_extract_refuses_an_output_folder_in_the_folder_it_walks(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    option: str,
    where: str,
    needles: list[str],
) -> None:
    # videos/a.avi, videos/b.avi: an overlay folder videos/ovl/ of a.mp4, b.mp4 would be read
    # by the next `extract videos` as a class "ovl"; pose files in videos/poses/ by `train
    # videos` as a class "poses" (and the videos beside them no longer read at all).
    videos = tmp_path / "videos"
    _video(videos / "a.avi")
    _video(videos / "b.avi")
    argv = ["extract", str(videos), "--out", str(tmp_path / "poses")]
    argv = [*argv[:2], option, str(tmp_path / where)] if option == "--out" else [
        *argv, option, str(tmp_path / where)]  # fmt: skip
    refused(argv, tmp_path, capsys, str(tmp_path / where), *needles)


def test_convert_refuses_an_output_folder_inside_its_class_folders(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    for label in ("squat", "lunge"):
        (data / label).mkdir(parents=True)
        good_pose_file(data / label / "a.npz")
    # data/conv/a.npz and labels.csv would make `train data` read a third class, "conv"
    refused(["convert", str(data), "--out", str(data / "conv")], tmp_path, capsys,
            "output folder is inside the input folder", str(data / "conv"))  # fmt: skip
