"""Session 44's fresh-eyes hunt over issue 14's commands (segment, reps, watch, label files)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.label_tracks import read_label_track
from features.pose_estimation.video import open_video
from features.poses import save_pose
from posecbr.cli import main
from tests.badinput import refused, small_case_base, standing_clip
from tests.test_hunt34c import _serving
from tests.test_video_vfr import _write


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


# the truth tools/make_workout.py writes beside its workout (its four parts, seconds)
WORKOUT_TRUTH = (
    "label,start_s,end_s\njumping_jack,0.00,5.00\nsquat,5.00,12.80\n"
    "incline_pushup,12.80,17.80\nglute_bridge,17.80,21.48\n"
)


@pytest.mark.parametrize("header", [True, False])
def test_segment_truth_refuses_a_table_of_stretches_saying_so(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], header: bool
) -> None:
    """Read as labels, the 15 words and times of the table (12 without its header) were
    refused as "15 labels (one per frame) do not fit ... (another frame rate or label
    block?)", though the frame rate and the block were right and the file is no list of
    labels."""
    truth = tmp_path / "workout_truth.csv"
    text = WORKOUT_TRUTH if header else WORKOUT_TRUTH.split("\n", 1)[1]
    truth.write_text(text, encoding="utf-8")
    rec = save_pose(standing_clip(60), tmp_path / "rec.npz")
    line = refused(["segment", str(rec), "--db", str(case_base), "--truth", str(truth)],
                   tmp_path, capsys, str(truth), "a table of 3 columns")  # fmt: skip
    assert "frame rate" not in line


@pytest.mark.parametrize(
    "text",
    [
        "squat squat\nlunge lunge\nsquat squat\n",  # words wrapped, no number beside them
        "1 squat\n1 squat\n2 lunge\n",  # a number that does not count up
    ],
)
def test_labels_alone_are_no_table_of_stretches(tmp_path: Path, text: str) -> None:
    path = tmp_path / "labels.txt"
    path.write_text(text, encoding="utf-8")
    assert read_label_track(path) == text.split()


def test_watch_of_a_video_at_2_fps_says_what_segment_says_of_it(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """At 2 fps a movement repeating within 1 s (two frames) is not followed: ``segment``
    and ``reps`` say so of a video at that rate; ``watch`` played it and counted its
    repetitions without a word. An empty scene, 8 frames (lossless): refused at its end as
    having nobody in view (tests/test_hunt45u.py), after the note."""
    scene = np.zeros((120, 160, 3), np.uint8)
    scene[:, :, 1] = np.arange(160, dtype=np.uint8)  # a plain green ramp: nobody in view
    video = _write(tmp_path / "slow.mp4", [i * 500 for i in range(8)], [scene] * 8, rate=2)
    assert main(["watch", str(video), "--db", str(case_base), "--speed", "0"]) == 1
    err = capsys.readouterr().err
    assert err.endswith(
        f"{video}: the stream ended after 8 frames (4.00 s)"
        " with nobody in view in any of them: no activity to label\n"
    )
    assert (
        f"note: {video}: at 2 fps a movement that repeats within 1 s (two frames) is not"
        " followed: its repetitions may be miscounted (the shortest, 0.4 s, needs 5 fps)"
    ) in err


def test_extract_refuses_a_label_file_given_for_a_video(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract 13_31.txt --out poses`` wrote poses/13_31.npz, 3 frames "without a person",
    exit 0: the same text drawn as frames."""
    labels = _label_file(shared_data, tmp_path)
    refused(["extract", str(labels), "--out", str(tmp_path / "poses")], tmp_path, capsys,
            str(labels), "a text file, not a video")  # fmt: skip


def test_watch_plays_a_file_url_without_slashes_as_the_file(
    case_base: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """FFmpeg opens ``file:clip.mp4`` as the path after ``file:``; ``watch file:clip.mp4``
    said "no such video file" of a file there is. It is played as ``clip.mp4`` is (the same
    note; its grey frames refused at the end as having nobody in view, as ``slow.mp4``
    is); ``file:`` of a file there is not is refused naming the path."""
    scene = np.zeros((120, 160, 3), np.uint8)
    scene[:, :, 1] = np.arange(160, dtype=np.uint8)
    _write(tmp_path / "slow.mp4", [i * 500 for i in range(8)], [scene] * 8, rate=2)
    monkeypatch.chdir(tmp_path)
    assert main(["watch", "file:slow.mp4", "--db", str(case_base), "--speed", "0"]) == 1
    err = capsys.readouterr().err
    assert "note: slow.mp4: at 2 fps a movement that repeats within 1 s" in err
    assert err.endswith(
        "slow.mp4: the stream ended after 8 frames (4.00 s)"
        " with nobody in view in any of them: no activity to label\n"
    )
    refused(["watch", "file:gone.mp4", "--db", str(case_base), "--speed", "0"], tmp_path, capsys,
            "gone.mp4", "no such video file")  # fmt: skip
