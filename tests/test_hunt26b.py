"""``convert``, ``extract``, ``describe``, ``compare`` and ``demo`` used as a newcomer would
(hunt 26b): mocap skeletons with odd but parseable units, output names in capitals, and the
other mistakes and edge cases a first user makes. Each test says what happened before its
fix.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

import features.pose_estimation  # noqa: F401  (silences FFmpeg before any video is opened)
from features.poses import load_pose
from posecbr.cli import main
from tests.badinput import good_pose_file, refused
from tests.test_compare_bad_input import DEMO
from tests.test_readers_asfamc import ASF, _write


@pytest.mark.parametrize("scale", ["0", "-0.5", "0.0e0"])
def test_an_asf_length_unit_that_is_not_positive_is_refused(
    scale: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``:units length 0`` made the metres per unit a division by zero: a ZeroDivisionError
    traceback; ``length -0.5`` was taken, every position negated (the person upside down
    and mirrored, left side on the right)."""
    assert "  length 0.5\n" in ASF  # the hand-made skeleton's unit, replaced
    data = tmp_path / "data"
    data.mkdir()
    skel, amc = _write(data, asf=ASF.replace("  length 0.5\n", f"  length {scale}\n"))
    out = tmp_path / "out"
    refused(
        ["convert", str(amc), "--asf", str(skel), "--out", str(out)],
        tmp_path, capsys, str(skel), "length", "positive",
    )  # fmt: skip


def _one_frame_video(path: Path) -> Path:
    """An MJPG AVI of one grey 16 x 16 frame (nobody in view)."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 10.0, (16, 16))
    writer.write(np.full((16, 16, 3), 90, np.uint8))
    writer.release()
    return path


def test_extract_out_a_pose_file_name_in_capitals_is_written_by_that_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract clip.avi --out clip.NPZ`` printed "done: clip.NPZ" but wrote
    ``clip.NPZ.npz``: the file named was never made, so every run extracted again ("done",
    never "up to date")."""
    video = _one_frame_video(tmp_path / "clip.avi")
    out = tmp_path / "clip.NPZ"
    assert main(["extract", str(video), "--out", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.NPZ", "clip.avi"]
    assert load_pose(out).n_frames == 1
    capsys.readouterr()
    assert main(["extract", str(video), "--out", str(out)]) == 0
    assert "up to date" in capsys.readouterr().out


def _demo_data(folder: Path) -> Path:
    """Data the demo accepts: one clip of a person standing per demo subject."""
    rows = ["path,label,subject"]
    for subject in ("s01", "s02", "s03"):
        good_pose_file(folder / f"m01_{subject}_e01.npz", label="deep_squat")
        rows.append(f"m01_{subject}_e01.npz,deep_squat,{subject}")
    (folder / "labels.csv").write_text("\n".join(rows) + "\n")
    return folder


@pytest.mark.parametrize("theirs", ["casebase.sqlite", "compare", "report.html"])
def test_demo_never_replaces_a_users_own_files_in_its_output_folder(
    theirs: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``demo --out .`` in a folder holding the user's own ``casebase.sqlite`` (or the
    ``compare`` folder of their own comparison, or a ``report.html``) deleted or replaced it
    with the demo's, without a word."""
    data = _demo_data(tmp_path / "data")
    out = tmp_path / "work"
    mine = out / theirs
    if theirs == "compare":
        mine.mkdir(parents=True)
        (mine / "results.json").write_text('{"mine": 1}')
    else:
        out.mkdir()
        mine.write_bytes(b"the user's own")
    refused(["demo", "--data", str(data), "--quick", "--out", str(out)], tmp_path, capsys,
            f"{out}: holds {theirs}, not written by the demo")  # fmt: skip


def test_demo_replaces_its_own_earlier_outputs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The demo's own folder is still the demo's to rerun into: what an earlier demo wrote
    there is cleared (the steps themselves are skipped here; test_wheel runs them)."""
    from posecbr.commands import demo

    monkeypatch.setattr(demo, "_run_step", lambda step: 0)
    monkeypatch.setattr(demo, "_write_report", lambda *a: None)
    data = _demo_data(tmp_path / "data")
    out = tmp_path / "demo-output"
    argv = ["demo", "--data", str(data), "--quick", "--out", str(out)]
    assert main(argv) == 0
    (out / "casebase.sqlite").write_bytes(b"an earlier demo's")
    (out / "compare" / "results.json").write_text("{}")
    assert main(argv) == 0
    assert not (out / "casebase.sqlite").exists()
    assert list((out / "compare").iterdir()) == []


@pytest.mark.parametrize(
    ("param", "needle"),
    [
        ("states=x", "states: must be one of"),
        ("length=1", "length: must be a whole number of frames from 2"),
        ("mirror=maybe", "mirror: must be"),
        ("phases=-1", "phases: must be 'auto' or a whole number >= 0"),
    ],
)
def test_compare_refuses_a_bad_case_base_parameter_value_before_the_run(
    param: str, needle: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Only the names of ``--param`` were checked: ``--param states=x`` loaded the data and
    cross-validated every fold, each case-base configuration "failed: states: ..." in the
    table, and the command exited 0, having written its results."""
    data = tmp_path / "data"
    data.mkdir()
    rows = ["path,label,subject"]
    for movement, label in (("m01", "deep_squat"), ("m07", "shoulder_abduction")):
        for subject in ("s01", "s02", "s03"):
            name = f"{movement}_{subject}_e01.npz"
            shutil.copy(DEMO / name, data / name)
            rows.append(f"{name},{label},{subject}")
    (data / "labels.csv").write_text("\n".join(rows) + "\n")
    out = tmp_path / "res"
    refused(
        ["compare", str(data), "--similarities", "euclidean,dtw", "--no-dad", "--peers",
         "none", "--k", "1", "--param", param, "--out", str(out)],
        tmp_path, capsys, "--param: ", needle, "(cbr fluents/euclidean)",
    )  # fmt: skip


@pytest.mark.parametrize(("width", "height"), [(1, 1), (1, 16), (16, 1)])
def test_extract_overlay_of_frames_one_pixel_wide_is_refused_before_the_model_runs(
    width: int, height: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The MP4 encoder takes no frame 1 pixel wide or high: the pose file was written, then
    the overlay failed ("cannot encode an MP4 overlay here") and the command exited 1 with
    the pose file left behind."""
    picture = tmp_path / "thin.png"
    cv2.imwrite(str(picture), np.full((height, width, 3), 90, np.uint8))
    line = refused(
        ["extract", str(picture), "--out", str(tmp_path / "thin.npz"),
         "--overlay", str(tmp_path / "thin.mp4")],
        tmp_path, capsys, str(tmp_path / "thin.mp4"), f"{width}x{height} frames",
    )  # fmt: skip
    assert line.endswith("MP4 frames are at least 2 pixels a side")


def test_extract_of_pose_files_is_one_line_pointing_to_the_other_commands(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract`` of a folder whose labels.csv lists pose files (the demo's, a converted
    dataset) tried each as a video: one "not a video OpenCV can decode" line per clip (181
    lines for the demo's 180 clips), exit 1; and a pose file given alone said only what it
    is not."""
    data = _demo_data(tmp_path / "data")
    first = data / "m01_s01_e01.npz"
    refused(["extract", str(data), "--out", str(tmp_path / "poses")], tmp_path, capsys,
            f"{first}: is a pose file already (listed in {data / 'labels.csv'})",
            "extract makes pose files from videos and pictures")  # fmt: skip
    refused(["extract", str(first), "--out", str(tmp_path / "poses")], tmp_path, capsys,
            f"{first}: is a pose file already: extract makes")  # fmt: skip
