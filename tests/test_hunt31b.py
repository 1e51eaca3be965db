"""Bug hunt 31b: the mocap path with another person's recordings (CMU-style ASF/AMC files
and label files as real ones vary), converted, trained on and segmented."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.readers.asfamc import read_asf_amc
from features.skeleton import JOINT_INDEX
from tests.badinput import refused
from tests.test_readers_asfamc import AMC, ASF, _write


def _renumbered(numbers: list[int]) -> str:
    """The test AMC file (three frames, their numbers on lines 4, 9 and 14) with its frames
    numbered ``numbers``."""
    lines = AMC.split("\n")
    for line_no, n in zip((4, 9, 14), numbers, strict=True):
        lines[line_no - 1] = str(n)
    return "\n".join(lines)


def test_amc_frames_numbered_from_zero_read_as_from_one(tmp_path: Path) -> None:
    """Frame numbers count the frames; where they start does not matter."""
    one = read_asf_amc(*_write(tmp_path, amc=_renumbered([1, 2, 3])))
    zero = read_asf_amc(*_write(tmp_path, amc=_renumbered([0, 1, 2])))
    np.testing.assert_array_equal(one.positions, zero.positions)
    assert zero.n_frames == 3


@pytest.mark.parametrize(
    ("numbers", "message"),
    [
        ([1, 2, 5], "line 14: frame 5 follows frame 2 "),  # two frames missing
        ([1, 3, 2], "line 9: frame 3 follows frame 1 "),  # out of order
        ([1, 2, 2], "line 14: frame 2 follows frame 2 "),  # one frame twice
    ],
)
def test_amc_frames_missing_or_out_of_order_are_refused(
    tmp_path: Path, numbers: list[int], message: str
) -> None:
    """Frames 1, 2, 5 were read as three frames one after another: the time between frame 2
    and 5 vanished, and every label after it (one per 12 frames, say) landed 3 frames late
    from there on. The frame number names where the file jumps."""
    asf, amc = _write(tmp_path, amc=_renumbered(numbers))
    with pytest.raises(DataError, match=message):
        read_asf_amc(asf, amc)


def test_convert_refuses_an_amc_file_with_a_gap_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    asf, amc = _write(tmp_path, asf=ASF, amc=_renumbered([1, 2, 4]))
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, str(amc), "line 14: frame 4 follows frame 2")


def _labelled_recording(tmp_path: Path, recording: Path, labels: str) -> Path:
    """A labels CSV naming ``recording`` labelled over time, one label per 0.1 s."""
    (tmp_path / "track.txt").write_text(labels)
    csv = tmp_path / "list.csv"
    csv.write_text(f"path,label_file,label_block_s\n{recording},track.txt,0.1\n")
    return csv


def test_convert_fps_cuts_a_recording_by_its_label_file_at_that_rate(tmp_path: Path) -> None:
    """``convert LIST.csv --fps R``: the label file (one label per 0.1 s) is laid over the
    frames at R fps, the rate the pose files are written with. It was laid over them at the
    file's own rate, and the pieces then relabelled R fps: each stretch cut at the wrong
    frames, and a label file that fitted the recording at R fps refused. 24 frames (30 fps
    in the file) at 60 fps are 0.4 s: labels a a b b cover frames 0-11 and 12-23."""
    from features.poses import load_pose
    from posecbr.cli import main
    from tests.badinput import good_pose_file

    rec = good_pose_file(tmp_path / "rec.npz", frames=24)
    csv = _labelled_recording(tmp_path, rec, "a a b b\n")
    out = tmp_path / "out"
    assert main(["convert", str(csv), "--out", str(out), "--fps", "60"]) == 0
    first, second = load_pose(out / "rec.npz"), load_pose(out / "rec_2.npz")
    assert (first.metadata["label"], first.n_frames, first.fps) == ("a", 12, 60.0)
    assert (second.metadata["label"], second.n_frames, second.fps) == ("b", 12, 60.0)
    assert second.metadata["frame_offset"] == 12


def test_convert_fps_refuses_a_label_file_that_does_not_fit_at_that_rate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An AMC recording of 3 frames is 0.025 s at 120 fps (one 0.1-s label) but 0.3 s at
    10 fps (three): one label at --fps 10 is refused, naming the label file; it was cut at
    120 fps and written as 10 fps without a word."""
    asf, amc = _write(tmp_path)
    csv = _labelled_recording(tmp_path, amc, "a\n")
    argv = ["convert", str(csv), "--out", str(tmp_path / "out"), "--fps", "10"]
    refused(argv, tmp_path, capsys, "track.txt", "1 label (one per 0.1 s) does not fit the"
            " recording t_60.AMC: 3 frames at 10 fps need 3")  # fmt: skip


def test_asf_units_written_on_one_line(tmp_path: Path) -> None:
    """``:units mass 1.0 length 0.5 angle deg`` on one line (the statements usually have a
    line each): the words after ``:units`` were dropped, so the length unit stayed 1 and the
    person came out half as tall (0.45 in CMU's files: 0.68 m instead of 1.51 m). The test
    chain's first bone is 10 units along +x: 10 x 0.0254 / 0.5 = 0.508 m."""
    units = ":units\n  mass 1.0\n  length 0.5\n  angle deg\n"
    assert units in ASF
    asf = ASF.replace(units, ":units mass 1.0 length 0.5 angle deg\n")
    seq = read_asf_amc(*_write(tmp_path, asf=asf))
    np.testing.assert_allclose(seq.positions[0, JOINT_INDEX["left_hip"]], [0.508, 0, 0])
    # radians said there hold for the axes too: lfemur's axis 0 0 pi/2 is 90 degrees
    rad = asf.replace("angle deg", "angle rad").replace(
        "axis 0 0 90 XYZ", "axis 0 0 1.5707963267948966 XYZ"
    )
    seq = read_asf_amc(*_write(tmp_path, asf=rad))
    np.testing.assert_allclose(seq.positions[2, JOINT_INDEX["left_knee"]], [0.508, 0, -0.508],
                               atol=1e-9)  # fmt: skip
    with pytest.raises(DataError, match="line 4: :units 'mass 1.0 length' is not name value"):
        read_asf_amc(*_write(tmp_path, asf=ASF.replace(units, ":units mass 1.0 length\n")))


def test_asf_documentation_is_free_text(tmp_path: Path) -> None:
    """A line of ``:documentation`` that is one of the ASF's keywords alone ("Length", a
    heading of the notes) was refused as "'length' without a value": the notes are text."""
    asf = ASF.replace(":documentation\n", ":documentation\n  Length\n  measured, axis\n  name\n")
    with_notes = read_asf_amc(*_write(tmp_path, asf=asf))
    np.testing.assert_array_equal(with_notes.positions, read_asf_amc(*_write(tmp_path)).positions)
    # in a bone block the keyword alone is still refused
    bad = ASF.replace("     length 10\n     axis 0 0 90", "     length\n     axis 0 0 90")
    with pytest.raises(DataError, match="line 29: 'length' without a value"):
        read_asf_amc(*_write(tmp_path, asf=bad))


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("ltibia -90\n", ""), "line 13: frame 1 is incomplete: no ltibia"),
        (
            ("ltibia -90\n", "ltibia -90\nlfemur 0\n"),
            "line 14: bone 'lfemur' is listed twice in frame 1",
        ),
        (("lfemur 90\n", "lfemur nan\n"), "bone 'lfemur': not a finite number in frame 2"),
    ],
)
def test_amc_messages_name_frames_by_the_files_numbers(
    tmp_path: Path, change: tuple[str, str], message: str
) -> None:
    """A file numbered from 0: a frame is named by the number the file gives it (they were
    counted from 1, so "frame 2" was the file's frame 1, the one after the frame named)."""
    amc = _renumbered([0, 1, 2]).replace(*change)
    with pytest.raises(DataError, match=message):
        read_asf_amc(*_write(tmp_path, amc=amc))


def test_a_labels_csv_names_where_it_looked_for_a_relative_path(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A labels CSV in another folder naming its files from the working folder (as the
    commands' own arguments are): "no such file cmu/names.txt" of a file that is there, seen
    from where the user stands. The line says where it was looked for."""
    from tests.badinput import good_pose_file

    monkeypatch.chdir(tmp_path)
    (tmp_path / "cmu").mkdir()
    good_pose_file(tmp_path / "cmu" / "rec.npz", frames=24)
    (tmp_path / "cmu" / "track.txt").write_text("a a b b a a b b\n")
    (tmp_path / "cmu" / "names.txt").write_text("a Squat\nb Jog\n")
    (tmp_path / "lists").mkdir()
    csv = tmp_path / "lists" / "train.csv"
    csv.write_text("path,label_file,label_block_s,label_names\n"
                   "../cmu/rec.npz,../cmu/track.txt,0.1,cmu/names.txt\n")  # fmt: skip
    refused(["train", "lists/train.csv", "--db", "cb.sqlite"], tmp_path, capsys,
            "lists/train.csv: line 2: no such file cmu/names.txt (looked for"
            " lists/cmu/names.txt: paths are from the CSV's folder)")  # fmt: skip
    csv.write_text("path,label\ncmu/rec.npz,squat\n")
    refused(["train", "lists/train.csv", "--db", "cb.sqlite"], tmp_path, capsys,
            "line 2: no such file cmu/rec.npz (looked for lists/cmu/rec.npz: ")  # fmt: skip


def test_a_label_file_too_long_for_a_one_frame_recording_counts_in_words() -> None:
    """A label file of 24 for a recording of one frame read "... do not fit the recording
    one.amc: 1 frames at 120 fps": a count of one is singular, as the verb of one label is."""
    from features.label_tracks import frame_labels

    with pytest.raises(DataError, match=r"3 labels \(one per frame\) do not fit the recording"
                       r" one.amc: 1 frame at 120 fps need 1 or 2 "):  # fmt: skip
        frame_labels(["a", "a", "b"], 1, 120.0, None, "t.txt", "one.amc")
    with pytest.raises(DataError, match=r"^t.txt: 1 label \(one per 0.1 s\) does not fit the"
                       r" recording: 24 frames at 120 fps need 2 "):  # fmt: skip
        frame_labels(["a"], 24, 120.0, 0.1, "t.txt")


def test_an_amc_line_of_a_superscript_digit_is_no_frame_number(tmp_path: Path) -> None:
    """Byte 0xB2 read as latin-1 is "²", a digit to ``str.isdigit``: as a line of its own it
    was taken for a frame number, which int() cannot read (a traceback once frame numbers
    were checked). It is a line that is no bone of the skeleton."""
    amc = AMC.replace("2\nroot 1 2 3", "\xb2\nroot 1 2 3")
    with pytest.raises(DataError, match="line 9: bone '\xb2' is not in the skeleton"):
        read_asf_amc(*_write(tmp_path, amc=amc))


def test_asf_negative_bone_length_is_refused(tmp_path: Path) -> None:
    """ "length -10" (a sign slipped in by hand) drew the bone the other way from its joint,
    the knee behind the hip, without a word. A length is a distance."""
    bad = ASF.replace("     length 10\n     axis 0 0 90", "     length -10\n     axis 0 0 90")
    with pytest.raises(DataError, match="line 29: a bone's length must be >= 0, got -10"):
        read_asf_amc(*_write(tmp_path, asf=bad))
    zero = ASF.replace("     length 10\n     axis 0 0 90", "     length 0\n     axis 0 0 90")
    seq = read_asf_amc(*_write(tmp_path, asf=zero))  # a bone of no length: its end is its start
    hip, knee = JOINT_INDEX["left_hip"], JOINT_INDEX["left_knee"]
    np.testing.assert_allclose(seq.positions[:, knee], seq.positions[:, hip], atol=1e-12)


@pytest.mark.parametrize(("sep", "said"), [(";", "';'"), ("\t", "tabs")])
def test_a_labels_csv_separated_by_semicolons_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], sep: str, said: str
) -> None:
    """A "CSV" saved by a spreadsheet set to a locale whose decimal mark is the comma has its
    columns separated by semicolons: it was told "missing path, label" of a header whose
    first word is path."""
    from tests.badinput import good_pose_file

    good_pose_file(tmp_path / "rec.npz", frames=24)
    (tmp_path / "track.txt").write_text("a a b b a a b b\n")
    csv = tmp_path / "list.csv"
    csv.write_text(sep.join(["path", "label_file", "label_block_s"]) + "\n"
                   + sep.join(["rec.npz", "track.txt", "0.1"]) + "\n")  # fmt: skip
    refused(["train", str(csv), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
            f"list.csv: line 1: the columns are separated by {said}, not commas")  # fmt: skip


def test_label_codes_not_named_say_what_the_names_file_names(tmp_path: Path) -> None:
    """A names file written "1: JumpJack" names the code "1:": the label file's codes 1 and
    2 were "not in the label names", of a file the user sees naming 1 and 2. The codes it
    does name are shown."""
    from features.label_tracks import read_label_names, read_label_track

    (tmp_path / "names.txt").write_text("1: JumpJack\n2: Jog\n")
    (tmp_path / "track.txt").write_text("1 1 2 2\n")
    names = read_label_names(tmp_path / "names.txt")
    with pytest.raises(DataError, match=r"track.txt: line 1: label code\(s\) 1, 2 not in the label"
                       r" names \(which name 1:, 2:\)$"):  # fmt: skip
        read_label_track(tmp_path / "track.txt", names)
