"""Hunt 37j: defects found by this session's hunts.

``train --labels Squat`` (and ``compare``) of data with no clip labelled so said "no clip
labelled 'Squat' in the data" and no more: with CMU's label files and no names, the labels
are codes (1, 3, ...) and nothing said so. Now the refusal names the data and the labels its
clips have (at most 10, then "and N more"), with a word that codes are named by a names
file; a label the data have that the other filters (``--subjects``) leave out is said so.

A frame left out for its time once a video's frames have strayed from the grid (a repeated,
missing or far-ahead stamp) still gave the smoothing filters ``index / fps``: where that lay
after the frames' own times, the filters took it as their latest time and passed the frames
after it through unsmoothed until the video's times caught up with it. Now such a frame
has no filter time (NaN): its pose passes unsmoothed and the filters are left as they were,
so the frames after it are smoothed as they would be without it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tests.badinput import good_pose_file, refused
from tests.test_video_vfr import people  # noqa: F401 (a fixture)

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
CODES_HINT = " (codes: --label-names or a label_names column names them)"


def test_frames_after_a_left_out_one_are_smoothed_as_without_it(
    people: list[np.ndarray],  # noqa: F811
) -> None:
    """At 25 fps, frames 20 ms apart (strayed at frame 1), frame 3 repeating 0.04 s: it is
    left out. Before, the filters got 3 / 25 = 0.12 s for it, after 0.06, 0.08, 0.1 and
    0.12 s, so frames 4 to 7 passed through unsmoothed (each the raw pose). Now every frame
    after it is smoothed exactly as in a run without frame 3 (the times 0 to 0.16 s)."""
    from features.pose_estimation import PoseEstimator
    from features.pose_estimation.video import FrameClock

    times = [0.0, 0.02, 0.04, 0.04, 0.06, 0.08, 0.10, 0.12, 0.14, 0.16]
    clock = FrameClock(25.0)
    with_it = PoseEstimator(smoothing=True, tracking=False)
    poses = []
    for i, t in enumerate(times):
        elapsed = clock.take(i, t)
        at = clock.filter_time(i, elapsed)
        assert (i == 3) is math.isnan(elapsed)
        poses.append(with_it.process(people[i], at))
    assert not clock.on_grid
    without = PoseEstimator(smoothing=True, tracking=False)
    kept = [i for i in range(len(times)) if i != 3]
    alone = {i: without.process(people[i], times[i]) for i in kept}
    raw = PoseEstimator(smoothing=False, tracking=False)
    assert all(poses[i].person for i in kept)
    for i in kept:
        np.testing.assert_array_equal(poses[i].image, alone[i].image)
        np.testing.assert_array_equal(poses[i].world, alone[i].world)
    # the smoothing did something after frame 3: frame 4 is not its raw pose
    assert not np.allclose(poses[4].image[:, :2], raw.process(people[4]).image[:, :2], atol=1e-6)
    # the left-out frame itself: its raw pose, the filters untouched
    np.testing.assert_allclose(poses[3].image, raw.process(people[3]).image, atol=1e-9)


def _recording(tmp_path: Path) -> tuple[Path, Path]:
    """A 90-frame recording (3 s at 30 fps) and its label file, one code per frame: 30
    frames each of 1, 3 and 5 (what a CMU truelabels file holds, per frame)."""
    rec = good_pose_file(tmp_path / "rec.npz", frames=90)
    codes = tmp_path / "codes.txt"
    codes.write_text(" ".join(["5"] * 30 + ["1"] * 30 + ["3"] * 30) + "\n")
    return rec, codes


def test_train_frame_labels_names_the_codes_a_missing_label_is_not(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The codes 5, 1, 3 are listed by value, 1, 3 and 5, with the word that they are codes.
    Before: "--labels: no clip labelled 'Squat' in the data", no labels named."""
    rec, codes = _recording(tmp_path)
    argv = ["train", str(rec), "--frame-labels", str(codes), "--labels", "Squat,1",
            "--db", str(tmp_path / "cb.sqlite")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line == (
        f"posecbr train: error: --labels: no clip labelled 'Squat' in {rec}: its labels are"
        f" 1, 3 and 5{CODES_HINT}"
    )
    names = tmp_path / "names.txt"
    names.write_text("1 Jog\n3 Squat\n5 Box\n")
    argv = ["train", str(rec), "--frame-labels", str(codes), "--label-names", str(names),
            "--labels", "squat", "--db", str(tmp_path / "cb.sqlite")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(f"no clip labelled 'squat' in {rec}: its labels are Box, Jog and Squat")


def test_train_a_labels_csv_of_recordings_names_their_codes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV whose row names the label file (no label_names column): the same codes.
    Before: "no clip labelled 'Squat' in the data"."""
    _recording(tmp_path)
    csv = tmp_path / "train.csv"
    csv.write_text("path,label_file\nrec.npz,codes.txt\n")
    argv = ["train", str(csv), "--labels", "Squat", "--db", str(tmp_path / "cb.sqlite")]
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(f"--labels: no clip labelled 'Squat' in {csv}: its labels are 1, 3 and 5"
                         f"{CODES_HINT}")  # fmt: skip


def test_train_of_class_folders_names_ten_labels_and_how_many_more(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """12 class folders (a01 to a12), one clip each, read by entries: ten named, "and 2
    more". Before: "no clips found (check --labels)", no label named."""
    data = tmp_path / "data"
    for k in range(1, 13):
        good_pose_file(data / f"a{k:02d}" / "clip.npz", frames=30)
    argv = ["train", str(data), "--labels", "a1", "--db", str(tmp_path / "cb.sqlite")]
    line = refused(argv, tmp_path, capsys)
    listed = ", ".join(f"a{k:02d}" for k in range(1, 11))
    assert line == (
        f"posecbr train: error: --labels: no clip labelled 'a1' in {data}: its labels are"
        f" {listed} and 2 more"
    )


def test_a_pose_folder_names_the_labels_of_its_files_metadata(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Pose files whose metadata holds their labels (walk, run): the files' labels, read
    without decoding the poses."""
    data = tmp_path / "poses"
    for k, label in enumerate(["walk", "run", "walk"]):
        good_pose_file(data / f"c{k}.npz", frames=30, label=label)
    argv = ["train", str(data), "--labels", "jog", "--db", str(tmp_path / "cb.sqlite")]
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(f"no clip labelled 'jog' in {data}: its labels are run and walk")


def test_compare_names_the_labels_the_data_have(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo's ten UI-PRMD movements, named (sorted) after a mistyped one."""
    argv = ["compare", str(DEMO), "--labels", "deep_squat,Squat", "--json",
            str(tmp_path / "r.json")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(
        f"--labels: no clip labelled 'Squat' in {DEMO}: its labels are deep_squat, hurdle_step,"
        " inline_lunge, side_lunge, sit_to_stand, standing_active_straight_leg_raise,"
        " standing_shoulder_abduction, standing_shoulder_extension,"
        " standing_shoulder_internal_external_rotation and standing_shoulder_scaption"
    )


def test_a_label_the_subjects_leave_out_is_said_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """walk is a label of the CSV's clips, but not of subject s01's: said as left out by
    the other filters, not as missing from the data (before: "no clip labelled 'walk' in
    the data", where two clips are)."""
    rows = ["path,label,subject"]
    for k, (label, subject) in enumerate([("run", "s01"), ("run", "s01"), ("walk", "s02"),
                                          ("walk", "s02")]):  # fmt: skip
        good_pose_file(tmp_path / f"c{k}.npz", frames=30)
        rows.append(f"c{k}.npz,{label},{subject}")
    csv = tmp_path / "labels.csv"
    csv.write_text("\n".join(rows) + "\n")
    argv = ["train", str(csv), "--labels", "run,walk", "--subjects", "s01", "--db",
            str(tmp_path / "cb.sqlite")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(f"--labels: no clip labelled 'walk' in {csv} passes the other filters")
