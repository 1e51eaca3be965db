"""A label file that is a table whose first column counts up ("time,label" per line) is refused
saying so: its times were read as labels too, and the refusal blamed the frame rate or block.
Label files of labels alone, however wrapped, are read as before."""

from __future__ import annotations

from pathlib import Path

import pytest

from features.errors import DataError
from features.label_tracks import read_label_track
from features.poses import save_pose
from tests.badinput import refused, standing_clip


def _truelabels(shared_data: Path) -> list[str]:
    text = (shared_data / "cmu-mocap6" / "truelabels" / "13_29.txt").read_text()
    return text.split()


@pytest.mark.parametrize(
    ("header", "sep", "step"),
    [("time,label\n", ",", 0.1), ("", "\t", 0.1), ("frame label\n", " ", 12)],
)
def test_a_table_of_times_and_labels_is_refused_saying_so(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    header: str, sep: str, step: float,
) -> None:  # fmt: skip
    """CMU 13_29's 0.1-s labels written as a table, one block per line: its first column the
    block's start (seconds, or frames at 120 fps)."""
    labels = _truelabels(shared_data)
    table = tmp_path / "labels.csv"
    lines = [f"{round(i * step, 3)}{sep}{code}" for i, code in enumerate(labels)]
    table.write_text(header + "\n".join(lines) + "\n", encoding="utf-8")
    recording = save_pose(standing_clip(30), tmp_path / "rec.npz")
    argv = ["train", str(recording), "--frame-labels", str(table), "--label-block", "0.1",
            "--db", str(tmp_path / "cb.sqlite")]  # fmt: skip
    line = refused(argv, tmp_path, capsys, str(table), "is a table of 2 columns")
    assert "frame rate" not in line


def test_the_shipped_label_files_read_as_before(shared_data: Path) -> None:
    """One line of space-separated codes (cmu-mocap6/truelabels): every token a label."""
    assert read_label_track(shared_data / "cmu-mocap6" / "truelabels" / "13_29.txt") == (
        _truelabels(shared_data)
    )


@pytest.mark.parametrize(
    "text",
    [
        "1 1 1\n2 2 2\n3 3 3\n",  # wrapped one activity per line: as many lines as labels
        "1\n1\n2\n2\n3\n",  # one label per line
        "1,1,6,6\n6,5,5,5\n",  # wrapped at a fixed width
    ],
)
def test_labels_alone_however_wrapped_are_read(tmp_path: Path, text: str) -> None:
    path = tmp_path / "labels.txt"
    path.write_text(text, encoding="utf-8")
    assert read_label_track(path) == text.replace(",", " ").split()


def test_a_table_is_refused_by_the_library_call_too(tmp_path: Path) -> None:
    path = tmp_path / "labels.txt"
    path.write_text("".join(f"{i}\t{'squat' if i < 20 else 'lunge'}\n" for i in range(40)))
    with pytest.raises(DataError, match="table of 2 columns whose first counts up"):
        read_label_track(path)
