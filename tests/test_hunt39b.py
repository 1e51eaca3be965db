"""Hunt 39b: label files and labels CSVs refused at the first command that reads them, in
one line naming the file and line, before the pose model runs and with nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused, small_case_base

SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"  # 65 frames, 5 fps


# ---------------------------------------------------------------- extract: overlapping rows


@pytest.mark.parametrize(
    ("rows", "needles"),
    [
        (["{v},squat,s01,0,30", "{v},lunge,s01,20,50"],
         ["lines 2 and 3 give tfjs_pose_squats_pexels4838220.mp4 frames 0,30 ('squat')",
          "and frames 20,50 ('lunge'): frames 20-29 would be cases of two activities"]),
        (["{v},squat,s01,10,20", "{v},squat_all,s02,,"],
         ["lines 2 and 3 give tfjs_pose_squats_pexels4838220.mp4 frames 10,20 ('squat') and"
          " whole ('squat_all'): frames 10-19 would be cases of two activities"]),
    ],
    ids=["overlapping start,end", "a stretch and the whole video"],
)  # fmt: skip
def test_extract_refuses_rows_giving_frames_of_a_video_two_labels(
    tmp_path: Path,
    shared_data: Path,
    capsys: pytest.CaptureFixture[str],
    rows: list[str],
    needles: list[str],
) -> None:
    """``extract`` of a labels CSV wrote the pose files of both rows (frames 20-29 under
    squat/ and lunge/), which ``train``, ``compare`` and ``convert`` of that CSV refuse and a
    ``train`` of the folder written takes as cases of two activities: refused as they refuse
    it, naming both lines, before the pose model runs."""
    video = shared_data / SQUAT
    csv = tmp_path / "labels.csv"
    body = "\n".join(r.format(v=video) for r in rows)
    csv.write_text(f"path,label,subject,start,end\n{body}\n", encoding="utf-8")
    refused(["extract", str(csv), "--out", str(tmp_path / "poses")], tmp_path, capsys,
            f"{csv}: ", *needles)  # fmt: skip


def test_extract_takes_overlapping_rows_of_one_label(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Rows of one label may overlap (as train takes them): not refused by the check."""
    from posecbr.commands.extract import find_jobs

    video = shared_data / SQUAT
    csv = tmp_path / "labels.csv"
    csv.write_text(f"path,label,start,end\n{video},squat,0,30\n{video},squat,20,50\n")
    jobs = find_jobs(csv, tmp_path / "poses", None)
    assert [(j.label, j.start, j.end) for j in jobs] == [("squat", 0, 30), ("squat", 20, 50)]


# ------------------------------------------- a label count that does not fit a video, at once


class _ModelRan(BaseException):
    """Raised in place of the pose model: a test that sees it knows the model would run."""


@pytest.fixture
def no_model(monkeypatch: pytest.MonkeyPatch) -> None:
    """The pose model made to fail at once, as the estimator is made: a refusal that comes
    from the label count came before it."""
    import features.pose_estimation.video as video

    def made(*_args: object, **_kwargs: object) -> None:
        raise _ModelRan

    monkeypatch.setattr(video, "PoseEstimator", made)


def _labels(path: Path, n: int) -> Path:
    path.write_text(" ".join(["squat"] * (n // 2) + ["stand"] * (n - n // 2)) + "\n")
    return path


def test_frames_known_before_decoding_a_constant_rate_video(shared_data: Path) -> None:
    """The squat video: 65 frames at 5 fps, its container says and its packets bear out (as
    OpenCV counts them by decoding); 2 fewer decoded would still be whole (check_whole)."""
    import cv2

    from features.pose_estimation.video import frames_before_decoding

    cap = cv2.VideoCapture(str(shared_data / SQUAT))
    decoded = 0
    while cap.grab():
        decoded += 1
    cap.release()
    assert decoded == 65
    assert frames_before_decoding(shared_data / SQUAT) == (63, 65, 5.0)


def test_train_refuses_a_count_that_does_not_fit_a_video_before_the_model_runs(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str], no_model: None
) -> None:
    """13 labels, one a second, given without --label-block: read one per frame they do not
    fit the squat video's 65 frames (65 or 66 needed). The refusal came after the pose model
    had run over the whole video (minutes for a long one); now at once, in the same words."""
    labels = _labels(tmp_path / "labels.txt", 13)
    video = shared_data / SQUAT
    refused(["train", str(video), "--frame-labels", str(labels), "--db",
             str(tmp_path / "cb.sqlite")], tmp_path, capsys,
            f"{labels}: 13 labels (one per frame) do not fit the recording"
            " tfjs_pose_squats_pexels4838220.mp4: 65 frames at 5 fps need 65 or 66")  # fmt: skip
    # with --label-block 1 they fit (13 s): the video is read, the model run
    with pytest.raises(_ModelRan):
        main(["train", str(video), "--frame-labels", str(labels), "--label-block", "1",
              "--db", str(tmp_path / "cb.sqlite")])  # fmt: skip


@pytest.mark.parametrize("n", [63, 64, 65, 66])
def test_a_count_a_whole_decoding_could_fit_is_left_for_the_read(
    tmp_path: Path, shared_data: Path, n: int, no_model: None
) -> None:
    """65 frames stated: a decoding of 63 or 64 would still be whole, so 63 to 66 labels are
    not refused before the video is read (frame_labels judges them on the frames decoded)."""
    labels = _labels(tmp_path / "labels.txt", n)
    with pytest.raises(_ModelRan):
        main(["train", str(shared_data / SQUAT), "--frame-labels", str(labels),
              "--db", str(tmp_path / "cb.sqlite")])  # fmt: skip


def test_a_variable_rate_video_is_checked_once_read(tmp_path: Path, no_model: None) -> None:
    """Frames 20 to 80 ms apart in a 25-fps stream: resampled to a grid whose frame count
    is known once decoded, so no count is trusted from the container and the model runs."""
    pytest.importorskip("av", reason="PyAV writes the variable-frame-rate video")
    from features.pose_estimation.video import frames_before_decoding
    from tests.test_video_vfr import PTS_MS, _grey, _write

    path = _write(tmp_path / "vfr.mkv", PTS_MS, _grey(len(PTS_MS)))
    assert frames_before_decoding(path) is None
    labels = _labels(tmp_path / "labels.txt", 3)
    with pytest.raises(_ModelRan):
        main(["train", str(path), "--frame-labels", str(labels), "--db",
              str(tmp_path / "cb.sqlite")])  # fmt: skip


def test_segment_truth_refuses_a_count_that_does_not_fit_a_video_before_the_model_runs(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str], no_model: None
) -> None:
    db = small_case_base(tmp_path / "cb")
    capsys.readouterr()  # the training's report
    labels = _labels(tmp_path / "labels.txt", 13)
    video = shared_data / SQUAT
    refused(["segment", str(video), "--db", str(db), "--truth", str(labels)], tmp_path, capsys,
            f"{labels}: 13 labels (one per frame) do not fit the recording {video}: 65 frames"
            " at 5 fps need 65 or 66")  # fmt: skip


def test_train_csv_label_file_of_a_video_is_refused_before_the_model_runs(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str], no_model: None
) -> None:
    """A labels CSV's label_file row of a video: its count fitted to the video's container
    before any clip is read, as a pose file's was."""
    labels = _labels(tmp_path / "labels.txt", 13)
    csv = tmp_path / "recordings.csv"
    csv.write_text(f"path,label_file\n{shared_data / SQUAT},{labels}\n", encoding="utf-8")
    refused(["train", str(csv), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
            f"{labels}: 13 labels (one per frame) do not fit the recording"
            " tfjs_pose_squats_pexels4838220.mp4: 65 frames at 5 fps need 65 or 66")  # fmt: skip


# ---------------------------------------------------- label files: the line of the mistake

NAMES = "1 squat\n2 lunge\n"


def _train_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str,
                   names: str, *needles: str) -> None:  # fmt: skip
    """``train rec.npz --frame-labels labels.txt --label-names names.txt`` (12 frames)
    refused in one line naming the file, nothing written."""
    rec = good_pose_file(tmp_path / "rec.npz", frames=12)
    (tmp_path / "labels.txt").write_text(text, encoding="utf-8")
    (tmp_path / "names.txt").write_text(names, encoding="utf-8")
    refused(["train", str(rec), "--frame-labels", str(tmp_path / "labels.txt"),
             "--label-names", str(tmp_path / "names.txt"), "--db",
             str(tmp_path / "cb.sqlite")], tmp_path, capsys, *needles)  # fmt: skip


def test_a_code_the_names_file_lacks_is_refused_naming_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Code 7 first stands on line 4 (of 12 labels, 3 a line): the line was not named, and
    in a file of thousands the user could not find it."""
    _train_refused(tmp_path, capsys, "1 1 1\n1 1 1\n2 2 2 # lunge\n2 2 7\n", NAMES,
                   f"{tmp_path / 'labels.txt'}: line 4: label code(s) 7 not in the label"
                   " names (which name 1, 2)")  # fmt: skip


@pytest.mark.parametrize(
    ("text", "shown"),
    [("1.0\n" * 6 + "2.0\n" * 6, "1.0 for 1, 2.0 for 2"), ("01\n" * 6 + "02\n" * 6,
      "01 for 1, 02 for 2")],
    ids=["decimals", "leading zeros"],
)  # fmt: skip
def test_codes_written_as_other_numbers_are_said_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, shown: str
) -> None:
    """Codes 1.0 and 2.0 (pandas writes a column of whole numbers with a NaN so), or 01 and
    02, for the names file's 1 and 2: refused as before, now saying they are its numbers
    written otherwise (the user saw only "1.0, 2.0 not in the label names (which name 1,
    2)")."""
    _train_refused(tmp_path, capsys, text, NAMES,
                   f"{tmp_path / 'labels.txt'}: line 1: label code(s)",
                   f"the same numbers written otherwise ({shown}); write them as the names"
                   " file does")  # fmt: skip


@pytest.mark.parametrize("which", ["labels", "names"])
def test_a_byte_order_mark_inside_a_label_file_is_refused_naming_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], which: str
) -> None:
    """Two files saved with a byte order mark joined together (``cat a.txt b.txt``) leave
    one at the start of the second's first line: read as part of a label it made activity
    "\\ufeff2" beside "2" (without names, trained under a name that looks like 2), or a code
    the names file named "\\ufeff2"."""
    bom = "\ufeff"
    text = f"{bom}1 1 1 1 1 1\n{bom}2 2 2 2 2 2\n" if which == "labels" else "1 " * 6 + "2 " * 6
    names = NAMES if which == "labels" else f"{bom}1 squat\n{bom}2 lunge\n"
    what = "label file" if which == "labels" else "label names file"
    _train_refused(tmp_path, capsys, text, names,
                   f"{which}.txt: line 2: a byte order mark (U+FEFF, unseen) inside the {what}",
                   "files joined together?")  # fmt: skip


def test_segment_truth_names_the_line_of_a_code_not_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = small_case_base(tmp_path / "cb")
    capsys.readouterr()
    rec = good_pose_file(tmp_path / "rec.npz", frames=12)
    (tmp_path / "truth.txt").write_text("1 1 1 1 1 1\n1 1 1 1 1 9\n", encoding="utf-8")
    (tmp_path / "names.txt").write_text(NAMES, encoding="utf-8")
    refused(["segment", str(rec), "--db", str(db), "--truth", str(tmp_path / "truth.txt"),
             "--label-names", str(tmp_path / "names.txt")], tmp_path, capsys,
            "truth.txt: line 2: label code(s) 9 not in the label names")  # fmt: skip


def test_labels_written_in_other_ways_read_the_same(tmp_path: Path) -> None:
    """Blank lines, CRLF line ends, a byte order mark at the start and comments change
    nothing (as before)."""
    from features.label_tracks import read_label_names, read_label_track

    plain, odd = tmp_path / "plain.txt", tmp_path / "odd.txt"
    plain.write_text("1 1 2 2\n", encoding="utf-8")
    odd.write_bytes(b"\xef\xbb\xbf1\r\n\r\n1 # one\r\n  \r\n2,2\r\n\r\n")
    names = tmp_path / "names.txt"
    names.write_bytes(b"\xef\xbb\xbf1 squat\r\n\r\n2\tlunge\r\n")
    assert read_label_track(odd, read_label_names(names)) == ["squat"] * 2 + ["lunge"] * 2
    assert read_label_track(odd) == read_label_track(plain)


@pytest.mark.parametrize("header", ["path,label,subject", "path,label_file,label_block_s"])
def test_a_labels_csv_given_for_a_label_file_is_refused_as_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], header: str
) -> None:
    """The recordings' labels CSV given to --frame-labels: its 12 cells were read as 12
    labels, which fit the 12 frames ('path', 'label', ... trained as activities), and
    another count was refused blaming "another frame rate or label block"."""
    rec = good_pose_file(tmp_path / "rec.npz", frames=12)
    csv = tmp_path / "labels.csv"
    row = "rec.npz,squat,s01" if "subject" in header else "rec.npz,track.txt,0.1"
    csv.write_text("\n".join([header, row, row, row]) + "\n", encoding="utf-8")
    refused(["train", str(rec), "--frame-labels", str(csv), "--db", str(tmp_path / "cb.sqlite")],
            tmp_path, capsys, f"{csv}: line 1: {header!r} is a labels CSV's header, and this a"
            " labels CSV, not a label file")  # fmt: skip
