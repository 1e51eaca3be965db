"""Session 45's fresh-eyes hunt over compare, report, convert, casebase, train --append and demo."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused
from tests.test_hunt40j import THREE


@pytest.mark.parametrize(
    ("name", "content"),
    [("results.json", '{"my": "own results"}\n'), ("results.csv", "run,score\na,1\n")],
)
def test_compare_out_keeps_a_results_file_it_did_not_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, content: str
) -> None:
    """``compare --out DIR`` replaced a ``results.json`` or ``results.csv`` of another tool
    (or the user's own) in DIR without a word; a rerun replaces its own results only."""
    out = tmp_path / "out"
    out.mkdir()
    (out / name).write_text(content)
    refused([*THREE, "--out", str(out)], tmp_path, capsys,
            str(out), f"holds {name}, not written by posecbr compare")  # fmt: skip
    assert (out / name).read_text() == content


def test_demo_data_given_as_its_labels_csv_is_told_to_give_the_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``demo --data data/labels.csv`` said "demo data not found (expected labels.csv)" of
    the very labels.csv it had been given."""
    labels = tmp_path / "data" / "labels.csv"
    labels.parent.mkdir()
    labels.write_text("path,label,subject\n")
    refused(["demo", "--data", str(labels), "--out", str(tmp_path / "o")], tmp_path, capsys,
            f"{labels}: is a file: --data takes the folder holding the demo's labels.csv: give"
            f" its folder, {labels.parent}")  # fmt: skip
