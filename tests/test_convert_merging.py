"""``posecbr convert`` into a folder that already holds a dataset: what is there is kept (other
recordings with the same name, the labels file's columns and header, other files), and the
options a source would ignore are refused."""

from __future__ import annotations

import csv
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
