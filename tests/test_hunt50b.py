"""Hunt 50b: ``extract ONE_VIDEO --overlay DIR``.

- One video's ``--overlay DIR`` (a folder there, or a name ending in "/") was refused as "overlay
  must be an .mp4 file name", where several clips' ``--overlay DIR`` and one video's ``--out
  DIR`` write ``DIR/<stem>``: it writes ``DIR/<stem>.mp4`` now, as they do, replacing there
  only an overlay extract drew of that video. A labels CSV of one row was taken for one
  video: ``--overlay ovl`` was refused so, and ``--overlay ovl.mp4`` made a folder of that name.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest

from posecbr.cli import main
from tests.badinput import refused
from tests.test_extract_replaces import _video


def test_one_videos_overlay_folder_holds_its_stem_mp4_as_several_clips_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = _video(tmp_path / "in" / "squat.avi", seed=1)
    poses, overlays = tmp_path / "poses", tmp_path / "overlays"
    overlays.mkdir()
    capsys.readouterr()
    assert main(["extract", str(video), "--out", str(poses), "--overlay", str(overlays)]) == 0
    assert capsys.readouterr().err == f"overlay written to {overlays / 'squat.mp4'}\n"
    cap = cv2.VideoCapture(str(overlays / "squat.mp4"))  # the video's 4 frames, read by OpenCV
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 4
    cap.release()
    # a folder to be made, written ending in "/": made, as several clips' is
    made = tmp_path / "made"
    assert main(["extract", str(video), "--out", str(poses), "--overlay", f"{made}/"]) == 0
    assert sorted(p.name for p in made.iterdir()) == ["squat.mp4"]
    capsys.readouterr()
    # a name with no suffix that is no folder: not an MP4 file, told how to name a folder
    refused(["extract", str(video), "--out", str(poses), "--overlay", str(tmp_path / "fresh")],
            tmp_path, capsys,
            f"{tmp_path}/fresh: the overlay must be an .mp4 file name; a folder to be made for"
            f" it is written ending in / ({tmp_path}/fresh/)")  # fmt: skip
    # a file of the user's at its place in the folder is not replaced, as for several clips
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "squat.mp4").write_bytes(b"my own video")
    for out in (poses, poses / "named.npz"):  # the pose file in a folder, or named
        refused(["extract", str(video), "--out", str(out), "--overlay", str(theirs)],
                tmp_path, capsys,
                f"{theirs}/squat.mp4: is already there, not an overlay posecbr extract made of"
                f" squat.avi: extracting into {theirs} would replace it")  # fmt: skip


def test_a_labels_csv_of_one_row_takes_an_overlay_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Its overlays go in a folder, as any labels CSV's: a video's name is refused before any
    work, where it was made a folder (``one.mp4/squat/squat.mp4``)."""
    video = _video(tmp_path / "squat.avi", seed=1)
    csv = tmp_path / "one.csv"
    csv.write_text(f"path,label\n{video},squat\n")
    refused(["extract", str(csv), "--out", str(tmp_path / "poses"),
             "--overlay", str(tmp_path / "one.mp4")], tmp_path, capsys,
            "one.mp4: for a folder or labels CSV, --overlay names the folder for the overlay"
            " videos, not one video file")  # fmt: skip
