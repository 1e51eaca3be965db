"""Hunt 39l: ``extract`` of a labels CSV row naming a ``label_file`` (a recording labelled over
time) writes what ``train`` reads as the CSV; a byte order mark inside a labels CSV (two CSVs
joined) refused naming its line."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import good_pose_file, refused

BOM = "\ufeff"


# ---------------------------------------------------------------- a byte order mark inside


@pytest.mark.parametrize("command", ["train", "convert", "extract"])
def test_a_byte_order_mark_inside_a_labels_csv_is_refused_naming_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    """Two labels CSVs, each saved with a byte order mark (as Excel saves "CSV UTF-8"),
    joined with ``cat``: the second's mark began the path of line 4, and every command said
    "no such file \\ufeffrec2.npz", a name that looks right. Refused as a label file with
    one inside is, naming the line, nothing written."""
    for name in ("rec1.npz", "rec2.npz"):
        good_pose_file(tmp_path / name, frames=12)
    first = f"{BOM}path,label\nrec1.npz,squat\n"
    second = f"{BOM}rec2.npz,lunge\n"  # the second file's rows, no header
    csv = tmp_path / "labels.csv"
    csv.write_text(first + "\n" + second, encoding="utf-8")
    argv = {
        "train": ["train", str(csv), "--db", str(tmp_path / "cb.sqlite")],
        "convert": ["convert", str(csv), "--out", str(tmp_path / "converted")],
        "extract": ["extract", str(csv), "--out", str(tmp_path / "poses")],
    }[command]
    line = refused(argv, tmp_path, capsys,
                   f"{csv}: line 4: a byte order mark (U+FEFF, unseen) inside the labels CSV",
                   "files joined together?", "part of a path or label")  # fmt: skip
    assert "no such file" not in line


def test_a_byte_order_mark_at_the_start_of_a_labels_csv_changes_nothing(tmp_path: Path) -> None:
    from features.datasets import read_labels_csv

    good_pose_file(tmp_path / "rec1.npz", frames=12)
    plain, marked = tmp_path / "plain.csv", tmp_path / "marked.csv"
    plain.write_text("path,label\nrec1.npz,squat\n", encoding="utf-8")
    marked.write_bytes(b"\xef\xbb\xbfpath,label\r\nrec1.npz,squat\r\n")
    assert read_labels_csv(marked) == read_labels_csv(plain)
