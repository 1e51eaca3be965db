"""``extract --out DIR`` replaces only its own pose file of the same video (a rerun: after
Ctrl-C, with other options, the video edited); a pose file of another video of the same
name, or a file of the user's, at ``DIR/<stem>.npz`` (or at an overlay's place in
``--overlay DIR``) is refused in one line before any work, as ``convert --out DIR`` and
``--plot DIR`` refuse what they did not write. Before, each was overwritten in silence."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused
from tests.test_hunt35f import _tiny_video


def _video(path: Path, seed: int) -> Path:
    """Four 32x32 MJPG frames of noise (no person), in a folder made if need be: each seed
    gives other bytes."""
    path.parent.mkdir(parents=True, exist_ok=True)
    return _tiny_video(path, seed)


def _digest_in(pose: Path) -> str:
    """The video SHA-256 a pose file records (read with numpy, not posecbr)."""
    with np.load(pose, allow_pickle=False) as data:
        return str(json.loads(str(data["metadata"]))["video_sha256"])


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_pose_file_of_another_video_of_the_same_name_is_not_replaced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    first = _video(tmp_path / "a" / "squat.avi", seed=1)
    other = _video(tmp_path / "b" / "squat.avi", seed=2)
    poses = tmp_path / "poses"
    assert main(["extract", str(first), "--out", str(poses)]) == 0
    assert _digest_in(poses / "squat.npz") == _sha(first)
    capsys.readouterr()
    for argv in (["extract", str(other)], ["extract", str(tmp_path / "b")]):  # a video, a folder
        refused([*argv, "--out", str(poses)], tmp_path, capsys,
                "squat.npz: is already there, not a pose file posecbr extract made of"
                " squat.avi", "choose another --out")  # fmt: skip
    assert _digest_in(poses / "squat.npz") == _sha(first)


def test_a_rerun_of_the_same_video_still_replaces_its_own_pose_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = _video(tmp_path / "a" / "squat.avi", seed=1)
    poses = tmp_path / "poses"
    assert main(["extract", str(video), "--out", str(poses)]) == 0
    # other options: extracted again over its own pose file
    assert main(["extract", str(video), "--out", str(poses), "--detect-every-frame"]) == 0
    assert capsys.readouterr().out.splitlines()[-1].startswith("done: ")
    # the video edited in place (other bytes, the file the pose file names): extracted again
    _video(video, seed=3)
    assert main(["extract", str(video), "--out", str(poses)]) == 0
    assert capsys.readouterr().out.splitlines()[-1].startswith("done: ")
    assert _digest_in(poses / "squat.npz") == _sha(video)
    # the same video copied elsewhere (the same bytes): its pose file holds the same poses
    copy = tmp_path / "c" / "squat.avi"
    copy.parent.mkdir()
    copy.write_bytes(video.read_bytes())
    assert main(["extract", str(copy), "--out", str(poses), "--force"]) == 0
    assert capsys.readouterr().out.splitlines()[-1].startswith("done: ")


@pytest.mark.parametrize("kind", ["pose file", "text"])
def test_a_file_of_the_users_at_the_pose_files_name_is_not_replaced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str
) -> None:
    video = _video(tmp_path / "videos" / "squat.avi", seed=1)
    poses = tmp_path / "poses"
    poses.mkdir()
    if kind == "pose file":  # converted or hand-made: no video's digest
        good_pose_file(poses / "squat.npz", frames=30, label="squat")
    else:
        (poses / "squat.npz").write_text("my notes")
    for argv in (["extract", str(video)], ["extract", str(tmp_path / "videos")]):
        refused([*argv, "--out", str(poses)], tmp_path, capsys,
                "squat.npz: is already there, not a pose file posecbr extract made of"
                " squat.avi")  # fmt: skip
    # a pose file named by the user is theirs to replace
    assert main(["extract", str(video), "--out", str(poses / "squat.npz")]) == 0
    assert _digest_in(poses / "squat.npz") == _sha(video)


def test_a_file_at_an_overlays_place_in_the_overlay_folder_is_not_replaced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    videos = tmp_path / "videos"
    _video(videos / "squat.avi", seed=1)
    _video(videos / "lunge.avi", seed=2)
    overlays = tmp_path / "overlays"
    overlays.mkdir()
    (overlays / "squat.mp4").write_bytes(b"my own video")
    poses = tmp_path / "poses"
    argv = ["extract", str(videos), "--out", str(poses), "--overlay", str(overlays)]
    refused(argv, tmp_path, capsys,
            "squat.mp4: is already there, not an overlay posecbr extract made of squat.avi",
            "choose another --overlay")  # fmt: skip
    (overlays / "squat.mp4").unlink()
    assert main(argv) == 0
    assert (overlays / "squat.mp4").stat().st_size > 0
    assert main([*argv, "--force"]) == 0  # its own overlays, beside its own pose files
    assert "2 extracted" in capsys.readouterr().out


def test_a_label_file_copy_replaces_only_its_own_earlier_copy(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV row naming a label_file copies it into --out; a file of the user's of
    that name there was overwritten. An earlier extract's copy (labels.csv there names it)
    is brought up to date when the label file was edited."""
    data = tmp_path / "data"
    _video(data / "rec.avi", seed=1)  # 4 frames at 10 frames/s: 4 labels of 0.1 s
    (data / "track.txt").write_text("1\n1\n2\n2\n")
    (data / "labels.csv").write_text("path,label_file,label_block_s\nrec.avi,track.txt,0.1\n")
    poses = tmp_path / "poses"
    poses.mkdir()
    (poses / "track.txt").write_text("my notes\n")
    argv = ["extract", str(data / "labels.csv"), "--out", str(poses)]
    refused(argv, tmp_path, capsys,
            "track.txt: is already there, not a label file the labels.csv there names:"
            " copying track.txt there would replace it")  # fmt: skip
    assert (poses / "track.txt").read_text() == "my notes\n"
    (poses / "track.txt").unlink()
    assert main(argv) == 0
    (data / "track.txt").write_text("1\n2\n2\n2\n")  # edited: copied again over its own copy
    assert main(argv) == 0
    assert (poses / "track.txt").read_text() == "1\n2\n2\n2\n"
