"""Frame rate from the data, not the name: CMU recordings (``13_29.amc``) are 120 fps, an HDM05
name states its rate, ``convert --fps`` sets it, and the rate assumed is printed."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from features.poses import load_pose
from features.readers.asfamc import amc_frame_rate, read_asf_amc
from posecbr.cli import main


def _cmu(shared_data: Path) -> tuple[Path, Path]:
    return (
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )


def test_cmu_name_is_not_a_frame_rate(shared_data: Path) -> None:
    asf, amc = _cmu(shared_data)
    seq = read_asf_amc(asf, amc)
    # CMU captures at 120 Hz; "30" in 13_30 is the trial number
    assert seq.fps == 120.0
    assert "assumed" in seq.metadata["fps_source"]
    # the recording's per-0.1-s labels need 12 frames per label at 120 fps: 206 labels for
    # 2465 frames (a 29- or 30-fps reading would need about four times as many labels)
    labels = (shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt").read_text().split()
    assert len(labels) == 206 and seq.n_frames // 12 + 1 == 206


def test_hdm05_name_states_its_rate() -> None:
    assert amc_frame_rate(Path("HDM_bd_squat1Reps_001_120.amc"))[0] == 120.0
    assert amc_frame_rate(Path("HDM_bd_squat1Reps_001_60.amc"))[0] == 60.0
    assert amc_frame_rate(Path("13_29.amc"))[0] == 120.0
    assert amc_frame_rate(Path("walk_25.amc"))[0] == 120.0


def test_convert_prints_the_rate_and_takes_fps(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    asf, amc = _cmu(shared_data)
    out = tmp_path / "a"
    assert main(["convert", str(amc), "--asf", str(asf), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "frame rate 120 fps for 1 clip (assumed" in printed
    assert load_pose(out / "13_30.npz").fps == 120.0
    out2 = tmp_path / "b"
    assert main(["convert", str(amc), "--asf", str(asf), "--out", str(out2), "--fps", "60"]) == 0
    assert "frame rate 60 fps for 1 clip (--fps)" in capsys.readouterr().out
    seq = load_pose(out2 / "13_30.npz")
    assert seq.fps == 60.0 and seq.metadata["fps_source"] == "--fps"
    # labels.csv does not grow a column for the note
    assert "fps_source" not in (out2 / "labels.csv").read_text()


@pytest.mark.parametrize("bad", ["0", "-5", "nan", "1e9"])
def test_convert_refuses_a_bad_fps(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], bad: str
) -> None:
    asf, amc = _cmu(shared_data)
    before = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (asf, amc)}
    out = tmp_path / "out"
    assert main(["convert", str(amc), "--asf", str(asf), "--out", str(out), "--fps", bad]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--fps" in err and "Traceback" not in err
    assert not out.exists()
    assert before == {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (asf, amc)}


def test_converting_into_a_folder_adds_to_its_labels(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Three CMU recordings converted one at a time into one folder: its labels.csv lists all
    three (it listed only the last: `posecbr train DIR` then dropped two); converting one
    again replaces its row. A labels.csv there that is not one (no path column): one line,
    exit 1, the folder as it was."""
    import csv

    asf = shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf"
    out = tmp_path / "p"
    for trial in ("13_29", "13_30", "13_31", "13_29"):
        amc = shared_data / "cmu-mocap6" / "amc" / f"{trial}.amc"
        assert main(["convert", str(amc), "--asf", str(asf), "--out", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith("wrote 1 pose file and labels.csv to")
    assert printed[-2].endswith("(2 clips listed before kept)")
    with open(out / "labels.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["path"] for r in rows] == ["13_30.npz", "13_31.npz", "13_29.npz"]
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "labels.csv").write_text("file,label\nx.npz,a\n")
    amc = shared_data / "cmu-mocap6" / "amc" / "13_30.amc"
    assert main(["convert", str(amc), "--asf", str(asf), "--out", str(bad)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "labels.csv: the labels file already there has no 'path'" in err
    assert [p.name for p in bad.iterdir()] == ["labels.csv"]
    assert (bad / "labels.csv").read_text() == "file,label\nx.npz,a\n"
    # rows train could not read were kept and merged (an unclosed quote became a row of its
    # own; a row without its label, a clip that is not there): refused, naming the line
    for text, problem in (
        ('path,label\n"unterminated,foo\n', "line 2: malformed CSV"),
        ("path,label\n13_29.npz,\n", "line 2: empty label"),
    ):
        (bad / "labels.csv").write_text(text)
        (bad / "13_29.npz").write_bytes((out / "13_29.npz").read_bytes())
        assert main(["convert", str(amc), "--asf", str(asf), "--out", str(bad)]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and (
            f"labels.csv: the labels file already there cannot be added to: {problem}" in err
        ), err
        assert sorted(p.name for p in bad.iterdir()) == ["13_29.npz", "labels.csv"]
        assert (bad / "labels.csv").read_text() == text


def test_one_ui_prmd_file_is_labelled_by_its_movement_and_its_rate_said_assumed(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One Kinect positions file (m01: the deep squat), converted alone: labelled deep_squat as
    when its folder is converted (it was written with an empty label, which train and
    convert then refused), and its rate said to be assumed, not read (the files hold
    coordinates only)."""
    kinect = shared_data / "ui-prmd" / "data" / "Segmented Movements" / "Kinect"
    for part in ("Positions", "Angles"):
        (tmp_path / "up" / part).mkdir(parents=True)
        name = f"m01_s01_e01_{part.lower()}.txt.gz"
        (tmp_path / "up" / part / name).write_bytes((kinect / part / name).read_bytes())
    src = tmp_path / "up" / "Positions" / "m01_s01_e01_positions.txt.gz"
    out = tmp_path / "one"
    assert main(["convert", str(src), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "frame rate 30 fps for 1 clip (assumed" in printed and "from the file" not in printed
    rows = (out / "labels.csv").read_text().splitlines()
    assert rows[1].startswith("m01_s01_e01.npz,deep_squat,s01,")
    assert load_pose(out / "m01_s01_e01.npz").label == "deep_squat"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--subjects", "dg"], "--subjects: filters the clips of a dataset folder"),
        (["--episodes", "5"], "--episodes: filters the clips of a dataset folder"),
        (["--correct"], "--correct: filters the clips of a dataset folder"),
        (["--bvh-unit", "mm"], "--bvh-unit: goes with BVH files, not 13_30.amc"),
    ],
)
def test_one_amc_file_refuses_what_would_be_ignored(
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    message: str,
) -> None:
    """A dataset folder's filters and BVH's unit given with one AMC file: converted as it is
    before, the filters unused (a subject that matched nothing still wrote the file)."""
    asf, amc = _cmu(shared_data)
    before = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (asf, amc)}
    out = tmp_path / "out"
    assert main(["convert", str(amc), "--asf", str(asf), "--out", str(out), *argv]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert not out.exists()
    assert before == {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (asf, amc)}


def test_a_sensor_is_refused_for_data_that_is_not_a_ui_prmd_folder(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--sensor`` chooses which recordings of a UI-PRMD folder are read; for an AMC file or a
    folder of pose files it chose nothing and was taken without a word (``convert`` and
    ``train``). The UI-PRMD folder takes it."""
    asf, amc = _cmu(shared_data)
    before = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (asf, amc)}
    out = tmp_path / "out"
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(out), "--sensor", "vicon"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--sensor: chooses a UI-PRMD folder's sensor" in err
    assert not out.exists()
    assert before == {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (asf, amc)}
    assert main(["convert", str(amc), "--asf", str(asf), "--out", str(out)]) == 0
    capsys.readouterr()
    converted = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in out.iterdir()}
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(out), "--db", str(db), "--sensor", "vicon"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--sensor: chooses a UI-PRMD folder's sensor" in err
    assert not db.exists()
    assert converted == {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in out.iterdir()}
    ui = tmp_path / "ui"
    argv = ["convert", str(shared_data / "ui-prmd"), "--sensor", "vicon", "--subjects", "s01",
            "--movements", "m01", "--episodes", "1", "--correct", "--out", str(ui)]  # fmt: skip
    assert main(argv) == 0
    assert load_pose(ui / "m01_s01_e01.npz").metadata["sensor"] == "vicon"
