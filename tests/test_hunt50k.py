"""Hunt 50k: the README as a new user meets it (a clean clone, its first command, the shell
examples run verbatim). What it found wrong in the code."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import good_pose_file, refused


@pytest.mark.parametrize("subject_column", ["", ",subject"])
def test_demo_data_without_subjects_is_said_to_have_none(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], subject_column: str
) -> None:
    """`posecbr demo --data DIR` of a labels.csv naming no subject (no subject column, or an
    empty cell in it) says the folder has no subjects; it said "has subjects None"."""
    data = tmp_path / "data"
    good_pose_file(data / "m01_s01_e01.npz", label="deep_squat")
    cell = "," if subject_column else ""
    (data / "labels.csv").write_text(
        f"path,label{subject_column}\nm01_s01_e01.npz,deep_squat{cell}\n"
    )
    line = refused(
        ["demo", "--data", str(data), "--quick", "--out", str(tmp_path / "out")],
        tmp_path,
        capsys,
        f"{data}: the demo trains on subjects s01 and s02, classifies s03 and describes "
        "m01_s01_e01.npz; this folder's labels.csv has no subjects",
    )
    assert "None" not in line
