"""convert writes a piece of a recording where the whole recording was converted (or a piece
cut at other frames) only by refusing: both come from one source, so the piece was taken for
the same clip converted again and replaced it in silence (the 4,592-frame recording by its
first 468-frame stretch)."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused


def _labels(folder: Path, *rows: str, name: str = "labels.csv") -> Path:
    csv = folder / name
    csv.write_text("path,label,start,end\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return csv


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_piece_is_not_written_over_the_whole_recording(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "src"
    src.mkdir()
    good_pose_file(src / "rec.npz", frames=60)
    out = tmp_path / "out"
    whole_csv = _labels(src, "rec.npz,squat,,", name="whole.csv")
    assert main(["convert", str(whole_csv), "--out", str(out)]) == 0
    whole = out / "rec.npz"
    before = _sha(whole)
    capsys.readouterr()
    csv = _labels(src, "rec.npz,squat,0,30", "rec.npz,lunge,30,60")
    refused(["convert", str(csv), "--out", str(out)], tmp_path, capsys,
            f"{whole}: already there from", "frames 0-59 of it", "writes frames 0-29 of it",
            "choose another --out")  # fmt: skip
    assert _sha(whole) == before


def test_the_same_pieces_converted_again_replace_themselves(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Converting again what was converted (the same stretches) stays allowed; cutting them
    at other frames is refused, naming both."""
    src = tmp_path / "src"
    src.mkdir()
    good_pose_file(src / "rec.npz", frames=60)
    out = tmp_path / "out"
    csv = _labels(src, "rec.npz,squat,0,30", "rec.npz,lunge,30,60")
    assert main(["convert", str(csv), "--out", str(out)]) == 0
    assert main(["convert", str(csv), "--out", str(out)]) == 0
    assert len(list(out.glob("*.npz"))) == 2
    capsys.readouterr()
    moved = _labels(src, "rec.npz,squat,0,20", "rec.npz,lunge,20,60")
    refused(["convert", str(moved), "--out", str(out)], tmp_path, capsys,
            "already there from", "frames 0-29 of it", "writes frames 0-19 of it")  # fmt: skip
