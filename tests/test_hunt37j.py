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


# Frames in a row stamped far ahead (a video's frame times 0.37, 5.0, 5.04, 0.41 ...) were
# taken as a clock reset: both kept, the frame after them (0.41 s) lost as the place the
# clock went back and every later one timed on from 5.04 s. Now a run of up to a bridged
# gap's frames (6 at 25 fps) whose next frame comes back between the last one taken and the
# run is left out, the later frames kept at their own times, in extract and watch alike.

RUN = [0.0, 0.02, 0.1, 0.18, 0.26, 0.33, 0.37, 5.0, 5.04, 0.41, 0.45, 0.49]


def test_two_frames_stamped_far_ahead_are_left_out_and_the_next_kept() -> None:
    """By hand at 25 fps (strayed at 0.02 s): 5.0 and 5.04 s lie far after 0.37 s and 0.41 s
    comes back between: frames 7 and 8 left out, 0.41, 0.45, 0.49 s their own. Before: 5.0
    and 5.04 kept, 0.41 left out, 0.45 and 0.49 at 5.04 + 0.04 + 0.04 = 5.12 and 5.16 s."""
    from features.pose_estimation.video import FrameClock, clocked_times

    elapsed, strayed = clocked_times(RUN, 25.0)
    assert strayed
    want = [0.0, 0.02, 0.1, 0.18, 0.26, 0.33, 0.37, np.nan, np.nan, 0.41, 0.45, 0.49]
    np.testing.assert_allclose(elapsed, want, atol=1e-9)
    clock = FrameClock(25.0)
    for i, t in enumerate(RUN):  # as watch: the next times read only as many as wanted
        clock.take(i, t, RUN[i + 1 : i + 1 + clock.needs_next(i, t)])
    assert clock.ahead == [(7, 0.37, 5.0, 0.41), (8, 0.37, 5.04, 0.41)]
    assert clock.went_back == []


def _run_of(n: int) -> tuple[list[float], list[float]]:
    """At 25 fps, ``n`` frames from 5.0 s every 40 ms after 0.18 s, then 0.22 and 0.26 s:
    the times, and what they are when the run is left out."""
    run = [5.0 + 0.04 * k for k in range(n)]
    return [0.0, 0.02, 0.1, 0.18, *run, 0.22, 0.26], [
        0.0,
        0.02,
        0.1,
        0.18,
        *[np.nan] * n,
        0.22,
        0.26,
    ]


@pytest.mark.parametrize(
    ("times", "want", "strays"),
    [
        # on the grid, two stamped 5 s ahead: each timed by its place, the file on the grid
        # (before: strayed, 0.2 s left out, 0.24 s at 5.12 s)
        ([0.0, 0.04, 0.08, 5.0, 5.04, 0.2, 0.24], [0.0, 0.04, 0.08, 0.12, 0.16, 0.2, 0.24], False),
        # six in a row (a bridged gap's frames at 25 fps: 0.25 s): left out
        (*_run_of(6), True),
        # seven: more than the run looked through (a stretch of the recording itself): the
        # clock went back, as before: all seven kept, 0.22 s left out, 0.26 s one interval
        # on from 5.24 s plus its 0.04 s after 0.22 s (5.32 s)
        (
            _run_of(7)[0],
            [0.0, 0.02, 0.1, 0.18, 5.0, 5.04, 5.08, 5.12, 5.16, 5.2, 5.24, np.nan, 5.32],
            True,
        ),
        # a clock reset after a gap: the times come back before the last one taken (0.1 <
        # 0.18 s), the gap's frames kept and the later ones timed on, as before
        (
            [0.0, 0.02, 0.1, 0.18, 5.0, 5.04, 0.1, 0.14],
            [0.0, 0.02, 0.1, 0.18, 5.0, 5.04, np.nan, 5.12],
            True,
        ),
        # a gap that never comes back: all kept, as before
        ([0.0, 0.02, 0.1, 0.18, 5.0, 5.04, 5.08], [0.0, 0.02, 0.1, 0.18, 5.0, 5.04, 5.08], True),
    ],
)
def test_a_run_stamped_ahead_against_a_clock_reset_and_a_gap(
    times: list[float], want: list[float], strays: bool
) -> None:
    from features.pose_estimation.video import clocked_times

    elapsed, strayed = clocked_times(times, 25.0)
    assert strayed is strays
    np.testing.assert_allclose(elapsed, want, atol=1e-9)


def test_a_video_with_two_frames_stamped_far_ahead_loses_those_two_alone(
    people: list[np.ndarray],  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The 13 variable-rate lunge frames (lossless), the ninth and tenth stamped 0.9 and
    0.94 s between 0.38 and 0.4 s: frames 8 and 9 left out, the others at their own times:
    14 rows at 25 fps (0 to 0.52 s), the last frame 12's pose (0.52 s). Before: frame 10
    (0.4 s) left out, 11 and 12 at 1.02 and 1.1 s: 28 rows. ``watch`` (stream_poses, then
    Regrid) pushes the same rows and every frame is read once, in order."""
    from features.pose_estimation import PoseEstimator
    from tests.test_hunt37c import stamped_video, watched

    pts_ms = [0, 20, 100, 180, 220, 260, 300, 380, 900, 940, 400, 440, 520]
    path, decoded, got = stamped_video(tmp_path, "ahead2.mkv", pts_ms, people)
    assert got.sequence.n_frames == 14
    assert got.video_frames is not None
    shown = got.video_frames.tolist()
    assert shown[-1] == 12 and 8 not in shown and 9 not in shown
    raw = PoseEstimator(smoothing=False, tracking=False).process(decoded[12][0])
    assert raw.person
    np.testing.assert_allclose(got.image_landmarks[-1], raw.image, atol=1e-6)
    vfr = got.sequence.metadata["variable_frame_rate"]
    assert vfr["frames_left_out"]["frames"] == [8, 9]
    assert vfr["stamped_ahead"]["frames"] == [8, 9]
    assert "clock_went_back" not in vfr
    err = capsys.readouterr().err
    assert "frame 8 is stamped 0.900 s, far ahead of the frames either side (0.380 and" in err
    frames = watched(path, got)
    assert [f.index for f in frames] == list(range(13))
    np.testing.assert_allclose(
        [f.video_time_s for f in frames],
        [0, 0.02, 0.1, 0.18, 0.22, 0.26, 0.3, 0.38, np.nan, np.nan, 0.4, 0.44, 0.52],
        atol=1e-9,
    )
    for f in frames:  # each frame's own image, though two were read ahead of their turn
        np.testing.assert_array_equal(f.rgb, decoded[f.index][0])
    err = capsys.readouterr().err
    assert "frame 9 is stamped 0.940 s" in err and "clock" not in err
