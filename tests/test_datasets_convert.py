"""``posecbr convert``: real UI-PRMD and HDM05 subsets, hand-made BVH, and bad input."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_dataset
from features.poses import load_pose
from features.readers.uiprmd import read_uiprmd_kinect
from posecbr.cli import main
from posecbr.commands.convert import parse_ranges
from tests.badinput import leg_bvh

BVH = leg_bvh("0.02", *["0 90 0 0 0 0 0 0 0 0 0 0"] * 3)


def test_parse_ranges() -> None:
    assert parse_ranges("1-3,5, 7-7") == {1, 2, 3, 5, 7}
    assert parse_ranges(None) is None


def test_convert_uiprmd_subset(shared_data: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    argv = ["convert", str(shared_data / "ui-prmd"), "--out", str(out), "--subjects", "s04",
            "--movements", "m02,m09", "--episodes", "2-3", "--incorrect", "--float32"]  # fmt: skip
    assert main(argv) == 0
    files = sorted(p.name for p in out.glob("*.npz"))
    assert files == [f"{m}_s04_e0{e}_inc.npz" for m in ("m02", "m09") for e in (2, 3)]
    with (out / "labels.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [r["label"] for r in rows] == ["hurdle_step"] * 2 + [
        "standing_shoulder_internal_external_rotation"
    ] * 2
    assert all(r["correct"] == "false" and r["subject"] == "s04" for r in rows)
    # float32 storage keeps positions within float32 rounding of the reader's output
    src = (shared_data / "ui-prmd/data/Incorrect Segmented Movements/Kinect/Positions"
           / "m02_s04_e02_positions_inc.txt.gz")  # fmt: skip
    np.testing.assert_allclose(
        load_pose(out / "m02_s04_e02_inc.npz").positions,
        read_uiprmd_kinect(src).positions,
        atol=1e-6,
    )
    assert len(load_dataset(out)) == 4


def test_convert_hdm05_amc(shared_data: Path, tmp_path: Path) -> None:
    amc = next((shared_data / "hdm05" / "train").glob("*/HDM_dg_squat1Reps_*.amc"))
    assert main(["convert", str(amc), "--out", str(tmp_path)]) == 0
    seq = load_pose(tmp_path / f"{amc.stem}.npz")
    assert seq.metadata["label"] == "squat1Reps" and seq.metadata["subject"] == "dg"
    assert seq.fps == 120.0


def test_convert_bvh(tmp_path: Path) -> None:
    f = tmp_path / "walk.bvh"
    f.write_text(BVH)
    assert main(["convert", str(f), "--out", str(tmp_path / "o"), "--bvh-unit", "cm"]) == 0
    seq = load_pose(tmp_path / "o" / "walk.npz")
    assert seq.n_frames == 3 and seq.metadata["label"] == "walk"
    np.testing.assert_allclose(seq.joint("left_knee")[0], [0.1, 0.5, 0.0], atol=1e-12)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--episodes", "3-1"], "--episodes: the range '3-1' runs backwards: write 1-3"),
        (["--correct", "--incorrect"], "not both"),
    ],
)
def test_convert_bad_input_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    (tmp_path / "x.npz").write_bytes(b"")
    assert main(["convert", str(tmp_path), "--out", str(tmp_path / "o"), *extra]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("posecbr convert: error:") and message in err
    assert "\n" not in err


def test_convert_truncated_bvh_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    f = tmp_path / "cut.bvh"
    f.write_text(BVH[:-20])
    assert main(["convert", str(f), "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"posecbr convert: error: {f}:") and "truncated" in err
    assert not list((tmp_path / "o").glob("*.npz"))


def test_convert_with_a_bad_clip_leaves_the_earlier_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip that fails halfway through the folder: the output folder of the earlier run is
    left byte for byte (its labels.csv and clips), with no staging folder or temporary."""
    src, out = tmp_path / "src", tmp_path / "out"
    src.mkdir()
    (src / "a.bvh").write_text(BVH)
    (src / "labels.csv").write_text("path,label\na.bvh,walk\n")
    assert main(["convert", str(src), "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert sorted(before) == ["a.npz", "labels.csv"]
    (src / "b.bvh").write_text(BVH)
    (src / "c.bvh").write_text(BVH[:-20])  # truncated: read after a.bvh and b.bvh
    (src / "labels.csv").write_text("path,label\na.bvh,walk\nb.bvh,walk\nc.bvh,walk\n")
    capsys.readouterr()
    assert main(["convert", str(src), "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"posecbr convert: error: {src / 'c.bvh'}:") and "truncated" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
