"""Hunt 51h: readers and label files as a new user's files are.

- A label read from the user's files and a case base's activity that are the same text in
  other Unicode characters ("Plié" typed, its é one character, and from a macOS file name, e
  and a combining accent) are the same label: ``segment --truth`` counted every such block
  as a label the case base lacks, ``classify`` every such clip wrong, without a word, and
  ``classify --feedback`` refused the label (with ``--new-label``: a second activity).
- A labels CSV saved by a spreadsheet with empty columns after the last one used
  (``path,label,,``) is read; it was refused as "repeated column names in the header", and
  ``convert`` refused to add to such a labels.csv. A label file with an empty label between
  commas (a spreadsheet row with a cell left empty) is refused: every label after it fell a
  frame or block early.
- A labels CSV in UTF-16 or another code page, or gzip-compressed, is said to be so, as a
  label file is, and so is a thresholds or ADD file; a pose file that is empty or
  gzip-compressed too; an ASF, AMC, BVH or UI-PRMD file gzip-compressed under its own name
  is read, as one named ``.gz`` is.
- Symbolic links that lead round in a loop, as an input or an output, are refused in one line
  saying so: several commands said "a bug in posecbr" (Python's RuntimeError "Symlink loop")
  and the rest "no such file".
"""

from __future__ import annotations

import gzip
import os
import unicodedata
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from features.datasets import read_labels_csv
from features.errors import DataError
from features.readers.bvh import read_bvh
from tests.badinput import good_pose_file, leg_bvh, refused

PLIE_TYPED = "Pli\u00e9"  # é as one character (NFC), as typed
PLIE_FILE_NAME = "Plie\u0301"  # e and a combining acute accent (NFD), as macOS names files


def test_segment_truth_counts_an_activity_spelt_in_other_unicode_characters_as_it() -> None:
    from cbr.evaluation.segments import score_segmentation

    assert PLIE_TYPED != PLIE_FILE_NAME == unicodedata.normalize("NFD", PLIE_TYPED)
    # 6 blocks: the case base called the first three Plié and the rest squat; the truth
    # (another spelling of Plié) says Plié for four, then squat: 5 of 6 right, none unseen.
    result = SimpleNamespace(
        blocks=[PLIE_FILE_NAME] * 3 + ["squat"] * 3,
        fps=10.0,
        segments=[SimpleNamespace(start_frame=0), SimpleNamespace(start_frame=3)],
    )
    truth = np.array([PLIE_TYPED] * 4 + ["squat"] * 2, dtype=object)
    s = score_segmentation(result, truth, [PLIE_FILE_NAME, "squat"], 0.1)
    assert (s.blocks, s.seen_blocks, s.seen_right) == (6, 6, 5)
    assert (s.unseen_labels, s.unseen_blocks) == ((), 0)
    # the change of label at block 4 (0.4 s) lies 0.1 s from the boundary at 0.3 s
    assert s.boundary_errors_s == pytest.approx((0.1,))


def test_classify_judges_a_clip_labelled_in_other_unicode_characters_by_its_activity() -> None:
    from cbr.classification import classify_clips, summarise
    from cbr.estimator import CaseBaseClassifier
    from tests.test_cbr_clips import ACTIVITIES, arm_dataset

    X, y = arm_dataset(2, seed=5)
    stored_as = np.array([PLIE_FILE_NAME if v == ACTIVITIES[0] else v for v in y], dtype=object)
    clf = CaseBaseClassifier(k=1).fit(X, stored_as)
    # the training clips themselves, k = 1: each its own nearest case, every one right
    truths = [PLIE_TYPED if v == PLIE_FILE_NAME else str(v) for v in stored_as]
    results = classify_clips(SimpleNamespace(classifier=clf), X, truths)  # type: ignore[arg-type]
    assert [r.label for r in results] == list(stored_as)
    summary = summarise(results)
    assert (summary["right"], summary["labelled"], summary["wrong"]) == (6, 6, [])
    assert summary["recall"][PLIE_FILE_NAME] == {"right": 2, "clips": 2, "recall": 1.0}


@pytest.mark.parametrize("new_label", [False, True])
def test_feedback_typed_in_other_unicode_characters_is_the_case_bases_activity(
    new_label: bool,
) -> None:
    from cbr.classification import check_feedback_label

    # refused as no activity of the case base, or, with new_label, a second activity
    # printed the same
    got = check_feedback_label(PLIE_TYPED, [PLIE_FILE_NAME, "squat"], new_label)
    assert got == PLIE_FILE_NAME


def test_spelt_as_keeps_values_it_cannot_tell_and_two_spellings_known() -> None:
    from features.text import spelt_as

    assert spelt_as([PLIE_TYPED, "squat", "Squat"], [PLIE_FILE_NAME, "squat"]) == [
        PLIE_FILE_NAME,
        "squat",
        "Squat",  # case is no Unicode spelling: another label
    ]
    # the case base holds both spellings (two activities train noted): neither is guessed
    assert spelt_as(["Plie\u0301"], [PLIE_TYPED, "Plie\u0301"]) == ["Plie\u0301"]
    assert spelt_as(["Pl\u0069\u0065\u0301"], [PLIE_TYPED, PLIE_FILE_NAME]) == [PLIE_FILE_NAME]


def _csv(folder: Path, name: str, text: str | bytes) -> Path:
    for clip in ("a.npz", "b.npz"):
        (folder / clip).touch()
    path = folder / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8", newline="")
    return path


def test_a_labels_csv_with_a_spreadsheets_empty_columns_is_read(tmp_path: Path) -> None:
    path = _csv(
        tmp_path, "x.csv", "path,label,subject,,\r\na.npz,squat,s1,,\r\nb.npz,lunge,s2,,\r\n"
    )
    rows = read_labels_csv(path)
    assert [(r["path"].name, r["label"], r["subject"], r["extras"]) for r in rows] == [
        ("a.npz", "squat", "s1", {}),
        ("b.npz", "lunge", "s2", {}),
    ]
    one = _csv(tmp_path, "y.csv", "path,label,\na.npz,squat,\n")  # one: kept as a column ""
    assert [r["extras"] for r in read_labels_csv(one)] == [{}]


def test_a_labels_csv_saved_with_its_row_index_is_read(tmp_path: Path) -> None:
    """pandas' to_csv() (and R's write.csv) saves its row index as a first column without a
    name: read as before the spreadsheet's empty columns were refused (not refused as 'column 1
    holds 0')."""
    path = _csv(tmp_path, "x.csv", ",path,label,subject\n0,a.npz,squat,s1\n1,b.npz,lunge,s2\n")
    rows = read_labels_csv(path)
    assert [(r["path"].name, r["label"], r["subject"], r["extras"]) for r in rows] == [
        ("a.npz", "squat", "s1", {}),
        ("b.npz", "lunge", "s2", {}),
    ]


@pytest.mark.parametrize(
    ("rows", "said"),
    [
        ("a.npz,squat,,\nb.npz,lunge,,left\n", "line 3: column 4 holds 'left', and the header"),
        ("a.npz,squat,s1\n", "line 2: column 3 holds 's1', and the header"),  # a row short
    ],
    ids=["as wide as the header", "narrower"],
)
def test_a_value_in_a_column_the_header_does_not_name_is_refused(
    tmp_path: Path, rows: str, said: str
) -> None:
    path = _csv(tmp_path, "x.csv", "path,label,,\n" + rows)
    with pytest.raises(DataError, match=said):
        read_labels_csv(path)


def test_convert_into_a_folder_whose_labels_csv_has_a_spreadsheets_empty_columns(
    tmp_path: Path,
) -> None:
    from posecbr.cli import main

    out = tmp_path / "out"
    out.mkdir()
    good_pose_file(out / "a.npz")
    (out / "labels.csv").write_bytes(b"path,label,,\r\na.npz,squat,,\r\n")
    take = tmp_path / "kick.bvh"
    take.write_text(leg_bvh("0.02", "0 90 0 0 0 0 0 0 0 0 0 0", "0 90 0 0 0 0 30 0 0 45 0 0"))
    assert main(["convert", str(take), "--out", str(out), "--bvh-unit", "cm"]) == 0
    header, *rows = (out / "labels.csv").read_text().splitlines()
    assert header.startswith("path,label,subject") and "" not in header.split(",")
    assert [row.split(",")[:2] for row in rows] == [["a.npz", "squat"], ["kick.npz", "kick"]]


@pytest.mark.parametrize(
    ("content", "said"),
    [
        ("path,label\na.npz,squat\n".encode("utf-16"), "UTF-16 text (its byte order mark)"),
        # ü at byte 26: "path,label\n" (11 bytes), "a.npz," (6) and "Kniebeuge" (9) before it
        ("path,label\na.npz,Kniebeuge\u00fc\n".encode("cp1252"), "byte 26, line 2): save it"),
        (gzip.compress(b"path,label\na.npz,squat\n"), "is a gzip-compressed file (gunzip it"),
    ],
    ids=["UTF-16", "a Windows code page", "gzip"],
)
def test_a_labels_csv_in_another_encoding_is_said_so(
    tmp_path: Path, content: bytes, said: str
) -> None:
    with pytest.raises(DataError) as refusal:
        read_labels_csv(_csv(tmp_path, "x.csv", content))
    assert str(refusal.value).startswith(f"{tmp_path / 'x.csv'}: ")
    assert said in str(refusal.value)


@pytest.mark.parametrize(
    ("content", "said"),
    [
        ('{"window": 5}'.encode("utf-16"), "not UTF-8 text: it is UTF-16 (its byte order mark);"),
        # ü at byte 20: '{"note": "Kniebeuge ' before it
        (
            '{"note": "Kniebeuge \u00fc"}'.encode("cp1252"),
            "(invalid start byte at byte 20, line 1)",
        ),
        (gzip.compress(b'{"window": 5}'), "not UTF-8 text: it is a gzip-compressed file (gunzip"),
    ],
    ids=["UTF-16", "a Windows code page", "gzip"],
)
def test_a_thresholds_file_in_another_encoding_is_said_so(
    tmp_path: Path, content: bytes, said: str
) -> None:
    from features.config import read_config
    from features.errors import ConfigError

    path = tmp_path / "t.json"
    path.write_bytes(content)
    with pytest.raises(ConfigError) as refusal:
        read_config(path, "thresholds file")
    assert str(refusal.value).startswith(f"{path}: the thresholds file is not UTF-8 text")
    assert said in str(refusal.value) and "a binary file?" not in str(refusal.value)


@pytest.mark.parametrize(
    ("content", "said"),
    [(b"", "the file is empty (0 bytes)"), (None, "it is gzip-compressed (gunzip it first)")],
    ids=["empty", "gzip"],
)
def test_an_empty_or_gzip_compressed_pose_file_is_said_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: bytes | None, said: str
) -> None:
    clip = tmp_path / "clip.npz"
    if content is None:
        content = gzip.compress(good_pose_file(tmp_path / "good.npz").read_bytes())
    clip.write_bytes(content)
    refused(["describe", str(clip)], tmp_path, capsys, f"clip.npz: cannot read pose file: {said}")


def test_a_bvh_file_gzip_compressed_under_its_own_name_is_read(tmp_path: Path) -> None:
    text = leg_bvh("0.02", "0 90 0 0 0 0 0 0 0 0 0 0", "0 90 0 0 0 0 30 0 0 45 0 0")
    plain = tmp_path / "take.bvh"
    plain.write_text(text)
    packed = tmp_path / "packed.bvh"
    packed.write_bytes(gzip.compress(text.encode()))
    want, got = read_bvh(plain, unit="cm"), read_bvh(packed, unit="cm")
    np.testing.assert_array_equal(got.positions, want.positions)
    assert got.fps == want.fps == 50.0


def test_a_label_file_with_an_empty_label_between_commas_is_refused(tmp_path: Path) -> None:
    from features.label_tracks import frame_labels, read_label_track

    # 10 frames, one label each; the spreadsheet row has 11 cells, frame 3's left empty:
    # read without it, 10 labels fit the 10 frames (11 would too) and frames 3-9 were
    # labelled sit, one frame early
    path = tmp_path / "labels.txt"
    path.write_text("walk,walk,walk,,sit,sit,sit,sit,sit,sit,sit\n")
    with pytest.raises(DataError, match=r"line 1: an empty label between commas after label 3 "):
        frame_labels(read_label_track(path), 10, 30.0, None, path)
    # commas with spaces, and empty cells ending a line (a shorter last row), are no gap
    path.write_text("walk, walk, walk, sit, sit\nsit, sit, sit, sit, sit,,\n")
    assert read_label_track(path) == ["walk"] * 3 + ["sit"] * 7


def _loop(path: Path) -> Path:
    os.symlink(path.name, path)  # a link to itself
    return path


@pytest.mark.parametrize(
    "argv",
    [
        ["reps", "{good}", "--plot", "{loop}.png"],  # an output: "a bug in posecbr"
        ["train", "{loop}.npz", "--db", "{dir}/cb.sqlite"],  # an input read: the same
        ["segment", "{loop}.npz", "--db", "{dir}/cb.sqlite"],  # "no such file"
    ],
    ids=["reps --plot", "train", "segment"],
)
def test_symbolic_links_in_a_loop_are_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str]
) -> None:
    good = good_pose_file(tmp_path / "good.npz")
    args = [a.format(good=good, loop=tmp_path / "loop", dir=tmp_path) for a in argv]
    looped = next(a for a in args if Path(a).stem == "loop")
    _loop(Path(looped))
    refused(args, tmp_path, capsys, f"{looped}: ", "symbolic links that lead round in a loop")


def test_pythons_symlink_loop_error_is_the_systems_refusal() -> None:
    from posecbr.cli import symlink_loop

    try:
        Path("/nonexistent-51h/a").resolve(strict=False)
    except RuntimeError:  # pragma: no cover - not raised for a missing path
        pytest.fail("a missing path is no loop")
    loop = symlink_loop(RuntimeError("Symlink loop from '/data/x.npz'"))
    assert loop is not None
    assert (loop.filename, loop.strerror) == (
        "/data/x.npz",
        "symbolic links that lead round in a loop",
    )
    assert symlink_loop(RuntimeError("something else")) is None
    assert symlink_loop(ValueError("Symlink loop from '/data/x.npz'")) is None
