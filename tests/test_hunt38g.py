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
