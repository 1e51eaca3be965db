"""Hunt 38g: bad label files and labels CSVs of long recordings, each refused in one clear
line naming the file, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

from features.errors import DataError
from features.label_tracks import read_label_track
from tests.badinput import good_pose_file, refused

# 12 frames at 30 fps in 0.1-s blocks: 4 blocks (3 frames each)
CODES = ["1", "1", "2", "2"]


@pytest.mark.parametrize(
    "text",
    ["1;1;2;2\n", "1;\n1;\n2;\n2;\n", "1 1\n2;2\n"],
    ids=["one line", "one per line", "a later line"],
)
def test_a_label_file_of_semicolons_is_refused_naming_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str
) -> None:
    """Labels separated by ';' (a spreadsheet's row in many locales) were read as one label
    per line: "1;1;2;2" one label (refused as a count that does not fit, blaming the frame
    rate), "1;" once per line a label of its own that trained an activity named "1;"."""
    rec = good_pose_file(tmp_path / "rec.npz", frames=12)
    labels = tmp_path / "labels.txt"
    labels.write_text(text, encoding="utf-8")
    line = 2 if text.startswith("1 1") else 1
    refused(["train", str(rec), "--frame-labels", str(labels), "--label-block", "0.1",
             "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
            f"labels.txt: line {line}: labels separated by ';'",
            "separates its labels by spaces, tabs, commas or line ends")  # fmt: skip


def test_labels_without_semicolons_still_read(tmp_path: Path) -> None:
    labels = tmp_path / "labels.txt"
    labels.write_text("1,1\t2 # a comment; not labels\n2\n", encoding="utf-8")
    assert read_label_track(labels) == CODES


def test_codes_not_named_are_shown_cut_short(tmp_path: Path) -> None:
    """A code not in the names file is shown with its first 40 characters, at most five of
    them: one long code (a whole line read as one label) made a line as long as the file."""
    labels = tmp_path / "labels.txt"
    codes = [f"{k:03d}" + "x" * 200 for k in range(7)]
    labels.write_text(" ".join(codes), encoding="utf-8")
    with pytest.raises(DataError) as err:
        read_label_track(labels, {"1": "squat"})
    shown = ", ".join(c[:40] + "..." for c in codes[:5]) + ", ..."
    assert str(err.value).endswith(
        f"label code(s) {shown} not in the label names (which name 1)"
    ), str(err.value)


def _rows_csv(folder: Path, *rows: str) -> Path:
    """A labels CSV path,label,start,end of ``rows`` over rec.npz (60 frames standing) and
    other.npz (60 frames)."""
    good_pose_file(folder / "rec.npz", frames=60)
    good_pose_file(folder / "other.npz", frames=60)
    csv = folder / "labels.csv"
    csv.write_text("path,label,start,end\n" + "".join(r + "\n" for r in rows), encoding="utf-8")
    return csv


@pytest.mark.parametrize(
    ("rows", "needle"),
    [
        (["rec.npz,squat,0,30", "rec.npz,lunge,20,50"],
         "lines 2 and 3 give rec.npz frames 0,30 ('squat') and frames 20,50 ('lunge'):"
         " frames 20-29 would be cases of two activities (end is exclusive"),
        # listed out of order, a row of the same label between: still found, lines as listed
        (["other.npz,squat,0,60", "rec.npz,lunge,40,60", "rec.npz,squat,0,20",
          "rec.npz,squat,10,45"],
         "lines 3 and 5 give rec.npz frames 40,60 ('lunge') and frames 10,45 ('squat'):"
         " frames 40-44 would be cases of two activities"),
        (["rec.npz,squat,,", "rec.npz,lunge,10,40"],
         "lines 2 and 3 give rec.npz whole ('squat') and frames 10,40 ('lunge'): frames 10-39"
         " would be cases of two activities"),
    ],
    ids=["two rows", "unsorted", "whole and a stretch"],
)  # fmt: skip
def test_train_refuses_rows_giving_frames_two_labels(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], rows: list[str], needle: str
) -> None:
    """Rows start,end of one file that overlap with different labels were trained: the frames
    they share became cases of both activities, nothing said (a row listed twice whole was
    refused, after every clip was described). Now refused before any clip is read, naming
    both lines and the frames they share (end exclusive, as the CSV's)."""
    csv = _rows_csv(tmp_path, *rows)
    for extra in ([], ["--split", "windows"], ["--split", "repetitions"]):
        refused(["train", str(csv), "--db", str(tmp_path / "cb.sqlite"), *extra], tmp_path,
                capsys, f"{csv}: {needle}")  # fmt: skip


def test_rows_that_meet_or_share_a_label_or_are_left_out_are_no_overlap(tmp_path: Path) -> None:
    from features.datasets import check_no_overlaps

    csv = _rows_csv(tmp_path, "rec.npz,squat,0,30", "rec.npz,lunge,30,60",
                    "rec.npz,squat,0,20", "other.npz,lunge,0,60", "other.npz,jog,0,10")  # fmt: skip
    with pytest.raises(DataError, match="lines 5 and 6 give other.npz"):
        check_no_overlaps(csv)
    check_no_overlaps(csv, ["squat", "lunge"])  # jog left out by --labels: nothing shared
    check_no_overlaps(tmp_path / "rec.npz")  # not a labels CSV
    # frame numbers in full, however large (they were formatted as 1.23457e+06)
    csv.write_text("path,label,start,end\nrec.npz,squat,1234000,1234568\n"
                   "rec.npz,lunge,1234567,1300000\n", encoding="utf-8")  # fmt: skip
    with pytest.raises(DataError, match="frames 1234567-1234567 would be cases"):
        check_no_overlaps(csv)


@pytest.mark.parametrize(
    ("rows", "needle"),
    [
        (["rec.npz,,track.txt,0.1,,,", "rec.npz,squat,,,,0,40"],
         "lines 2 and 3 both give frames of rec.npz (label file track.txt; frames 0,40"
         " ('squat')): line 2 labels all of it over time"),
        (["rec.npz,squat,,,,,", "other.npz,lunge,,,,,", "rec.npz,,track.txt,0.1,,,"],
         "lines 2 and 4 both give frames of rec.npz (whole ('squat'); label file track.txt):"
         " line 4 labels all of it over time"),
        (["rec.npz,,track.txt,0.1,,,", "rec.npz,,track.txt,0.1,,,"],
         "lines 2 and 3 both give frames of rec.npz (label file track.txt; label file"
         " track.txt)"),
    ],
    ids=["a stretch after", "the whole file before", "twice"],
)  # fmt: skip
def test_train_refuses_a_recording_labelled_over_time_listed_again(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], rows: list[str], needle: str
) -> None:
    """A row naming a label file labels every frame of its recording: another row of the
    same recording (a stretch with a label, the whole file) was trained as well, its frames
    cases twice, nothing said; the row listed twice was refused only after every clip was
    described, as "training set: rec.npz frames 0-29 is listed twice", no line named."""
    good_pose_file(tmp_path / "rec.npz", frames=60)
    good_pose_file(tmp_path / "other.npz", frames=60)
    (tmp_path / "track.txt").write_text("squat " * 10 + "lunge " * 10, encoding="utf-8")
    csv = tmp_path / "labels.csv"
    csv.write_text("path,label,label_file,label_block_s,label_names,start,end\n"
                   + "".join(r + "\n" for r in rows), encoding="utf-8")  # fmt: skip
    refused(["train", str(csv), "--db", str(tmp_path / "cb.sqlite"), "--split", "clips"],
            tmp_path, capsys, f"{csv}: {needle}",
            "would be cases twice; list the recording once")  # fmt: skip


def test_compare_refuses_rows_giving_frames_two_labels(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """As train: two subjects, each a recording of two labelled stretches that overlap by 10
    frames, were cross-validated, the shared frames a case of each activity."""
    rows = []
    for subject in ("s01", "s02"):
        good_pose_file(tmp_path / f"{subject}.npz", frames=60)
        rows += [f"{subject}.npz,squat,{subject},0,30", f"{subject}.npz,lunge,{subject},20,60"]
    csv = tmp_path / "labels.csv"
    csv.write_text("path,label,subject,start,end\n" + "\n".join(rows) + "\n", encoding="utf-8")
    refused(["compare", str(csv), "--similarities", "euclidean", "--features", "fluents",
             "--peers", "none", "--no-dad", "--k", "1"], tmp_path, capsys,
            f"{csv}: lines 2 and 3 give s01.npz frames 0,30 ('squat') and frames 20,60"
            " ('lunge'): frames 20-29 would be cases of two activities")  # fmt: skip


@pytest.mark.parametrize(
    ("rows", "needle"),
    [
        (["rec.npz,squat,0,30", "rec.npz,squat,0,30"],
         "lines 2 and 3 both give rec.npz frames 0,30 ('squat'): the one stretch would be"
         " written twice; list it once"),
        (["rec.npz,squat,,", "other.npz,squat,,", "rec.npz,squat,,"],
         "lines 2 and 4 both give rec.npz whole ('squat'): the one stretch would be written"
         " twice"),
        (["rec.npz,squat,0,30", "rec.npz,lunge,20,50"],
         "lines 2 and 3 give rec.npz frames 0,30 ('squat') and frames 20,50 ('lunge'):"
         " frames 20-29 would be cases of two activities"),
    ],
    ids=["a stretch twice", "a file twice", "overlapping labels"],
)  # fmt: skip
def test_convert_refuses_a_stretch_twice_or_frames_of_two_labels(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], rows: list[str], needle: str
) -> None:
    """convert wrote a stretch listed twice as two pose files (rec.npz, rec_2.npz), and rows
    giving frames two labels as they were: `train` of the folder then took each twice, or
    the shared frames as two activities, without a word (`train` of the CSV itself refuses
    them). Now refused before any clip is read, the output folder not made."""
    csv = _rows_csv(tmp_path, *rows)
    refused(["convert", str(csv), "--out", str(tmp_path / "out")], tmp_path, capsys,
            f"{csv}: {needle}")  # fmt: skip


def test_convert_keeps_stretches_of_one_label_that_overlap(tmp_path: Path) -> None:
    from posecbr.cli import main

    csv = _rows_csv(tmp_path, "rec.npz,squat,0,30", "rec.npz,squat,10,40", "rec.npz,lunge,40,60")
    assert main(["convert", str(csv), "--out", str(tmp_path / "out")]) == 0
    assert len(list((tmp_path / "out").glob("*.npz"))) == 3
