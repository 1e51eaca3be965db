"""Session 45's fresh-eyes hunt over compare, report, convert, casebase, train --append and demo."""

from __future__ import annotations

from pathlib import Path

import pytest

from posecbr.cli import main
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


def test_compare_where_no_method_could_be_scored_exits_1_writing_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Every method failed (here the one case-base configuration: --trim 0.05 keeps one case
    of each of three activities in each fold, fewer than the 5 it votes with) and compare
    exited 0, writing results that measured nothing; train --trim refuses such a case base."""
    out, json_file = tmp_path / "out", tmp_path / "r.json"
    code = main([*THREE, "--trim", "0.05", "--out", str(out), "--json", str(json_file)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    failed = [line for line in err if line.startswith("note: cbr fluents/euclidean failed: ")]
    assert len(failed) == 1 and "trimming kept 3 of 12 cases, fewer than the 5" in failed[0], err
    assert err[-1] == (
        f"posecbr compare: error: {THREE[1]}: no method could be scored: every one failed or"
        " was skipped (the notes say why); no results written"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == []
