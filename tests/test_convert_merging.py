"""``posecbr convert`` into a folder that already holds a dataset: what is there is kept (other
recordings with the same name, the labels file's columns and header, other files), and the
options a source would ignore are refused."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import refused

ONE_CLIP = ["--subjects", "s01", "--movements", "m01", "--episodes", "1", "--correct"]


def _convert(source: Path, out: Path, *extra: str) -> None:
    assert main(["convert", str(source), "--out", str(out), *ONE_CLIP, *extra]) == 0


def _rows(labels: Path) -> list[dict[str, str]]:
    with labels.open(newline="", encoding="utf-8-sig") as fh:
        return list(csv.DictReader(fh))


def test_another_recording_with_the_same_name_is_refused_and_kept(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    uiprmd = shared_data / "ui-prmd"
    out = tmp_path / "kv"
    _convert(uiprmd, out)
    capsys.readouterr()
    argv = ["convert", str(uiprmd), "--sensor", "vicon", "--out", str(out), *ONE_CLIP[:-1]]
    refused(argv, tmp_path, capsys, "m01_s01_e01.npz", "Kinect", "Vicon", "another recording")
    _convert(uiprmd, out)  # the same clip again replaces its row
    assert [r["path"] for r in _rows(out / "labels.csv")] == ["m01_s01_e01.npz"]


def test_columns_of_rows_listed_before_are_kept(shared_data: Path, tmp_path: Path) -> None:
    out = tmp_path / "kb"
    out.mkdir()
    shutil.copy(Path(__file__).parents[1] / "posecbr/demo_data/uiprmd/m02_s01_e01.npz", out)
    (out / "labels.csv").write_text(
        "path,label,subject,source,origin,notes\n"
        "m02_s01_e01.npz,hurdle_step,s01,lab,camera 2,tired\n"
    )
    _convert(shared_data / "ui-prmd", out)
    rows = _rows(out / "labels.csv")
    assert [r["path"] for r in rows] == ["m02_s01_e01.npz", "m01_s01_e01.npz"]
    old = rows[0]
    assert (old["source"], old["origin"], old["notes"]) == ("lab", "camera 2", "tired")
    assert rows[1]["origin"] == ""  # the new clip's origin is in its pose file, not a column


def test_a_listed_file_whose_name_differs_only_in_case_is_not_replaced(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "kc"
    out.mkdir()
    shutil.copy(
        Path(__file__).parents[1] / "posecbr/demo_data/uiprmd/m02_s01_e01.npz",
        out / "M01_S01_E01.npz",
    )
    (out / "labels.csv").write_text("path,label,subject\nM01_S01_E01.npz,hurdle_step,s01\n")
    argv = ["convert", str(shared_data / "ui-prmd"), "--out", str(out), *ONE_CLIP]
    refused(argv, tmp_path, capsys, "m01_s01_e01.npz", "M01_S01_E01.npz", "only in case")


@pytest.mark.parametrize("header", ["\ufeffpath,label,subject", "Path,Label,Subject"])
def test_a_labels_file_train_reads_is_added_to(
    shared_data: Path, tmp_path: Path, header: str
) -> None:
    out = tmp_path / "kh"
    out.mkdir()
    shutil.copy(Path(__file__).parents[1] / "posecbr/demo_data/uiprmd/m02_s01_e01.npz", out)
    (out / "labels.csv").write_text(f"{header}\nm02_s01_e01.npz,hurdle_step,s01\n")
    _convert(shared_data / "ui-prmd", out)
    text = (out / "labels.csv").read_text(encoding="utf-8-sig")
    assert text.splitlines()[0].startswith(header.lstrip("\ufeff"))  # spelt as it was
    rows = _rows(out / "labels.csv")
    assert [r[header.lstrip("\ufeff")[:4]] for r in rows] == ["m02_s01_e01.npz", "m01_s01_e01.npz"]


@pytest.mark.parametrize(
    ("dataset", "flags", "needle"),
    [
        ("hdm05/train", ["--correct"], "--correct: goes with UI-PRMD"),
        ("hdm05/train", ["--incorrect"], "--incorrect: goes with UI-PRMD"),
        ("hdm05/train", ["--asf", "HDM_bd.asf"], "--asf: goes with one .amc file"),
        ("hdm05/train", ["--bvh-unit", "cm"], "--bvh-unit: goes with one .bvh file"),
        ("ui-prmd", ["--asf", "HDM_bd.asf"], "--asf: goes with one .amc file"),
        ("ui-prmd", ["--bvh-unit", "cm"], "--bvh-unit: goes with one .bvh file"),
    ],
)
def test_options_the_source_would_ignore_are_refused(
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    dataset: str,
    flags: list[str],
    needle: str,
) -> None:
    argv = ["convert", str(shared_data / dataset), "--out", str(tmp_path / "o"), "--limit", "1"]
    refused([*argv, *flags], tmp_path, capsys, needle)
