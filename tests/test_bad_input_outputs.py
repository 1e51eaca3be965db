"""Outputs that would overwrite an input or cannot be written are refused before the run
(nothing written, no stray temporary file); user data printed to a terminal is escaped
(issue 15)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from features.text import shown
from posecbr.cli import main
from tests.badinput import good_pose_file, refused, small_case_base, snapshot


def test_describe_plot_is_checked_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = good_pose_file(tmp_path / "clip.npz")
    thresholds = tmp_path / "t.toml"
    thresholds.write_text("window = 5\n")
    # a folder given holds the picture, <clip>.png, as segment --plot's: here that is a folder
    (tmp_path / "pics" / "clip.png").mkdir(parents=True)
    (tmp_path / "pics" / "bad.png").mkdir()
    describe = ["describe", str(clip), "--thresholds", str(thresholds), "--plot"]
    refused([*describe, str(tmp_path / "pics")], tmp_path, capsys,
            "the picture is a folder, not a file")  # fmt: skip
    refused([*describe, str(clip)], tmp_path, capsys, "the picture would overwrite an input")
    refused([*describe, str(thresholds)], tmp_path, capsys,
            "the picture would overwrite an input")  # fmt: skip
    refused([*describe, str(tmp_path / "no" / "t.png")], tmp_path, capsys,
            "the folder of the picture does not exist")  # fmt: skip
    # checked before the clip is read: a bad clip with a bad picture names the picture
    (tmp_path / "bad.npz").write_text("not a pose file")
    refused(["describe", str(tmp_path / "bad.npz"), "--plot", str(tmp_path / "pics")],
            tmp_path, capsys, "the picture is a folder")  # fmt: skip


@pytest.mark.parametrize(
    ("flags", "needle"),
    [
        (["--min-run", "0"], "--min-run: must be at least 1 frame, got 0"),
        (["--min-confidence", "0"], "--min-confidence: must be in (0, 1], got 0.0"),
        (["--min-confidence", "nan"], "--min-confidence: must be in (0, 1], got nan"),
        (["--min-confidence", "1.5"], "--min-confidence: must be in (0, 1], got 1.5"),
    ],
)
def test_bad_describe_arguments_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], needle: str
) -> None:
    clip = good_pose_file(tmp_path / "clip.npz")
    refused(["describe", str(clip), *flags], tmp_path, capsys, needle)


def test_describe_plot_is_written_whole_in_the_format_of_its_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = good_pose_file(tmp_path / "clip.npz")
    for name, magic in (("t.png", b"\x89PNG"), ("t.svg", b"<?xml"), ("t.pdf", b"%PDF")):
        assert main(["describe", str(clip), "--plot", str(tmp_path / name)]) == 0
        assert (tmp_path / name).read_bytes()[: len(magic)] == magic
    capsys.readouterr()
    assert not list(tmp_path.glob(".*"))  # no temporary file left behind


# on one xdist worker: the module's case_base made once, not once per worker
pytestmark = pytest.mark.xdist_group("bad_input_outputs")


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def test_casebase_export_never_overwrites_the_case_base(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 15, data loss 6: ``casebase export --db X.npz --out X.npz``."""
    db = tmp_path / "X.npz"
    shutil.copy(case_base, db)
    capsys.readouterr()
    refused(["casebase", "export", "--db", str(db), "--out", str(db)], tmp_path, capsys,
            "the export file would overwrite an input")  # fmt: skip
    # --out X (the .npz is added) is the same file
    refused(["casebase", "export", "--db", str(db), "--out", str(tmp_path / "X")], tmp_path,
            capsys, "would overwrite an input")  # fmt: skip
    (tmp_path / "dir.npz").mkdir()
    refused(["casebase", "export", "--db", str(db), "--out", str(tmp_path / "dir.npz")],
            tmp_path, capsys, "the export file is a folder, not a file")  # fmt: skip
    refused(["casebase", "export", "--db", str(db), "--out", str(tmp_path / "no" / "e.npz")],
            tmp_path, capsys, "the folder of the export file does not exist")  # fmt: skip
    # and the good path still writes the export beside it
    assert main(["casebase", "export", "--db", str(db), "--out", str(tmp_path / "e.npz")]) == 0
    n_clips = len(list((case_base.parent / "train").rglob("*.npz")))
    assert f"wrote {n_clips} cases" in capsys.readouterr().out


def test_extract_outputs_that_would_overwrite_a_video_are_refused_before_the_model_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # The videos are never opened: the refusal comes first (their bytes need not be video).
    videos = tmp_path / "videos"
    videos.mkdir()
    (videos / "squat.mp4").write_bytes(b"not decoded")
    (videos / "lunge.mp4").write_bytes(b"not decoded")
    video = videos / "squat.mp4"
    refused(["extract", str(video), "--out", str(tmp_path / "poses"), "--overlay", str(video)],
            tmp_path, capsys, "the overlay would overwrite an input")  # fmt: skip
    refused(["extract", str(videos), "--out", str(tmp_path / "poses"), "--overlay", str(videos)],
            tmp_path, capsys, "the overlay would overwrite an input")  # fmt: skip
    refused(["extract", str(video), "--out", str(tmp_path / "poses"), "--workers", "0"],
            tmp_path, capsys, "--workers (--jobs): must be at least 1, got 0")  # fmt: skip
    refused(["extract", str(tmp_path / "none.mp4"), "--out", str(tmp_path / "poses")],
            tmp_path, capsys, "no such file or folder")  # fmt: skip


# ---- user data on the terminal ---------------------------------------------------------

ESCAPES = "\x1b]0;pwned\x07\x1b[2J\u202e"


def test_shown_escapes_controls_and_keeps_text() -> None:
    assert shown("deep squat é 日本 😀") == "deep squat é 日本 😀"
    assert shown("a\x1b]0;t\x07b") == "a\\x1b]0;t\\x07b"
    assert shown("x\u202ey\u2066z") == "x\\u202ey\\u2066z"
    assert shown("one\ntwo\tthree\r") == "one\\x0atwo\\x09three\\x0d"
    assert shown("\x9b31m") == "\\x9b31m"  # the 8-bit CSI


def test_describe_prints_a_hostile_label_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = good_pose_file(tmp_path / "clip.npz", label=f"squat{ESCAPES}")
    assert main(["describe", str(clip)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\u202e" not in out
    assert "label squat\\x1b]0;pwned\\x07\\x1b[2J\\u202e" in out
    assert main(["describe", str(clip), "--json", "--min-run", "1"]) == 0
    raw = capsys.readouterr().out
    assert "\x1b" not in raw  # JSON escapes it itself


def test_error_lines_print_hostile_file_names_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / f"clip{ESCAPES}.npz"
    bad.write_text("not a pose file")
    before = snapshot(tmp_path)
    assert main(["describe", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "\x1b" not in err and "\u202e" not in err
    assert "clip\\x1b]0;pwned\\x07" in err and len(err.strip().splitlines()) == 1
    assert snapshot(tmp_path) == before


def test_dad_prints_hostile_add_words_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from features.qmp.add import default_add_path

    text = default_add_path().read_text(encoding="utf-8")
    add = tmp_path / "add.toml"
    toml_escapes = "\\u001b]0;pwned\\u0007\\u001b[2J\\u202e"  # TOML's own escapes
    add.write_text(text.replace('words = "squat"', f'words = "squat{toml_escapes}"', 1))
    clip = good_pose_file(tmp_path / "clip.npz", frames=150)
    assert main(["dad", str(clip), "--add", str(add), "--top", "0"]) == 0
    out = capsys.readouterr().out
    assert "squat\\x1b]0;pwned" in out and "\x1b" not in out


def test_convert_prints_a_hostile_folder_name_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    good_pose_file(data / "a.npz", label="x")
    out = tmp_path / f"out{ESCAPES}"
    assert main(["convert", str(data), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "\x1b" not in printed and "out\\x1b]0;pwned" in printed
    assert json.loads(json.dumps(sorted(p.name for p in out.iterdir()))) == ["a.npz", "labels.csv"]


def test_demo_output_folder_that_cannot_be(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    rows = ["path,label,subject"]
    for subject in ("s01", "s02", "s03"):
        good_pose_file(data / f"m01_{subject}_e01.npz", label="deep_squat")
        rows.append(f"m01_{subject}_e01.npz,deep_squat,{subject}")
    (data / "labels.csv").write_text("\n".join(rows[:3]) + "\n")  # no s03 yet
    (tmp_path / "afile").write_text("x")
    demo = ["demo", "--data", str(data), "--quick", "--out"]
    # data the steps cannot run on: refused before anything is written (it stopped at step 3,
    # classify, leaving the case base and the comparison's folder behind)
    refused([*demo, str(tmp_path / "out")], tmp_path, capsys,
            f"{data}: the demo trains on subjects s01 and s02, classifies s03 and describes "
            "m01_s01_e01.npz; this folder's labels.csv has subjects s01, s02")  # fmt: skip
    (data / "labels.csv").write_text("\n".join(rows) + "\n")
    refused([*demo, str(tmp_path / "afile")], tmp_path, capsys, "exists and is not a folder")
    # the demo clears its earlier outputs in --out: never in the data it reads
    refused([*demo, str(data)], tmp_path, capsys, "is the demo data folder or inside it")
    refused([*demo, str(data / "out")], tmp_path, capsys, "is the demo data folder or inside it")


def test_extract_reads_the_key_of_a_damaged_output_as_out_of_date(tmp_path: Path) -> None:
    """An existing output that is not a pose file (a renamed .npy, a bomb) is re-extracted,
    not read: its stored key is None."""
    import numpy as np

    from posecbr.commands.extract import stored_key

    np.save(tmp_path / "p.npy", np.zeros((3, 33, 3)))
    (tmp_path / "p.npy").rename(tmp_path / "p.npz")
    assert stored_key(tmp_path / "p.npz") is None
    (tmp_path / "t.npz").write_text("text")
    assert stored_key(tmp_path / "t.npz") is None


def test_convert_removes_the_staging_folder_a_killed_convert_left(tmp_path: Path) -> None:
    import socket
    import subprocess
    import sys

    data = tmp_path / "data"
    good_pose_file(data / "a.npz", label="x")
    out = tmp_path / "out"
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    stale = out / f".posecbr-stage.pid{gone.pid}@{socket.gethostname()}.q1w2"
    stale.mkdir(parents=True)
    (stale / ".a.npz.pid1@x.tmp").write_bytes(b"half a pose file")
    assert main(["convert", str(data), "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["a.npz", "labels.csv"]


def test_describe_plot_never_overwrites_the_files_read_beside_the_clip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A UI-PRMD positions file's angles file and an AMC file's skeleton are read with it:
    ``--plot`` onto either replaced it with a picture, and the clip could not be read."""
    positions = tmp_path / "m01_s01_e01_positions.txt"
    angles = tmp_path / "m01_s01_e01_angles.txt"
    amc, asf = tmp_path / "HDM_bd_01.amc", tmp_path / "HDM_bd.asf"
    for p in (positions, angles, amc, asf):
        p.write_text("not read: refused before\n")
    refused(["describe", str(positions), "--plot", str(angles)], tmp_path, capsys,
            "the picture would overwrite an input", str(angles))  # fmt: skip
    refused(["describe", str(amc), "--plot", str(asf)], tmp_path, capsys,
            "the picture would overwrite an input", str(asf))  # fmt: skip


def test_describe_plot_onto_a_pipe_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import os
    import stat

    clip = good_pose_file(tmp_path / "in" / "clip.npz")
    pipe = tmp_path / "out" / "pipe.png"
    pipe.parent.mkdir()
    os.mkfifo(pipe)
    refused(["describe", str(clip), "--plot", str(pipe)], tmp_path / "in", capsys,
            "the picture is not a regular file", str(pipe))  # fmt: skip
    assert stat.S_ISFIFO(pipe.lstat().st_mode) and sorted(pipe.parent.iterdir()) == [pipe]


def test_reps_refuses_asf_it_would_ignore_and_a_plot_over_the_skeleton(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = good_pose_file(tmp_path / "clip.npz")
    amc, asf = tmp_path / "13_29.amc", tmp_path / "sk.asf"
    for p in (amc, asf):
        p.write_text("not read: refused before\n")
    refused(["reps", str(clip), "--asf", str(tmp_path / "none.asf")], tmp_path, capsys,
            "--asf: goes with an AMC recording, not clip.npz")  # fmt: skip
    refused(["reps", str(amc), "--asf", str(asf), "--plot", str(asf)], tmp_path, capsys,
            "the picture would overwrite an input", str(asf))  # fmt: skip
    refused(["reps", str(clip), "--fps", "0.001"], tmp_path, capsys,
            "--fps: must be a frame rate in [0.01, 10000], got 0.001")  # fmt: skip


def test_watch_out_never_overwrites_the_case_base(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case base named like a video: ``--out`` onto it replaced the case base."""
    video, db = tmp_path / "v.mp4", tmp_path / "cb.mp4"
    video.write_bytes(b"not read: refused before")
    db.write_bytes(b"not opened: refused before")
    refused(["watch", str(video), "--db", str(db), "--out", str(db)], tmp_path, capsys,
            "the output video would overwrite an input", str(db))  # fmt: skip
