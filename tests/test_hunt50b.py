"""Hunt 50b: ``extract ONE_VIDEO --overlay DIR``; an AMC file's assumed rate in every command.

- One video's ``--overlay DIR`` (a folder there, or a name ending in "/") was refused as "overlay
  must be an .mp4 file name", where several clips' ``--overlay DIR`` and one video's ``--out
  DIR`` write ``DIR/<stem>``: it writes ``DIR/<stem>.mp4`` now, as they do, replacing there
  only an overlay extract drew of that video. A labels CSV of one row was taken for one
  video: ``--overlay ovl`` was refused so, and ``--overlay ovl.mp4`` made a folder of that name.
- ``train``, ``classify``, ``compare``, ``describe`` and ``dad`` of an AMC file (which carries
  no frame rate: read at 120 fps) said nothing of the rate they assumed, which ``segment`` and
  ``reps`` said once per file: each says it once per command now, one line naming how many
  recordings and one of them, with how to give the rate (``--fps``, or converting a dataset).
"""

from __future__ import annotations

import contextlib
import io
import shutil
from pathlib import Path

import cv2
import pytest

from posecbr.cli import main
from tests.badinput import refused
from tests.test_extract_replaces import _video
from tests.test_hunt40k import _head

# what the AMC reader says of the rate it reads a file at whose name states none
WHY = "assumed: AMC files carry no rate, CMU and HDM05 record at 120"


def test_one_videos_overlay_folder_holds_its_stem_mp4_as_several_clips_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = _video(tmp_path / "in" / "squat.avi", seed=1)
    poses, overlays = tmp_path / "poses", tmp_path / "overlays"
    overlays.mkdir()
    capsys.readouterr()
    assert main(["extract", str(video), "--out", str(poses), "--overlay", str(overlays)]) == 0
    assert capsys.readouterr().err == f"overlay written to {overlays / 'squat.mp4'}\n"
    cap = cv2.VideoCapture(str(overlays / "squat.mp4"))  # the video's 4 frames, read by OpenCV
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 4
    cap.release()
    # a folder to be made, written ending in "/": made, as several clips' is
    made = tmp_path / "made"
    assert main(["extract", str(video), "--out", str(poses), "--overlay", f"{made}/"]) == 0
    assert sorted(p.name for p in made.iterdir()) == ["squat.mp4"]
    capsys.readouterr()
    # a name with no suffix that is no folder: not an MP4 file, told how to name a folder
    refused(["extract", str(video), "--out", str(poses), "--overlay", str(tmp_path / "fresh")],
            tmp_path, capsys,
            f"{tmp_path}/fresh: the overlay must be an .mp4 file name; a folder to be made for"
            f" it is written ending in / ({tmp_path}/fresh/)")  # fmt: skip
    # a file of the user's at its place in the folder is not replaced, as for several clips
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "squat.mp4").write_bytes(b"my own video")
    for out in (poses, poses / "named.npz"):  # the pose file in a folder, or named
        refused(["extract", str(video), "--out", str(out), "--overlay", str(theirs)],
                tmp_path, capsys,
                f"{theirs}/squat.mp4: is already there, not an overlay posecbr extract made of"
                f" squat.avi: extracting into {theirs} would replace it")  # fmt: skip


def test_a_labels_csv_of_one_row_takes_an_overlay_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Its overlays go in a folder, as any labels CSV's: a video's name is refused before any
    work, where it was made a folder (``one.mp4/squat/squat.mp4``)."""
    video = _video(tmp_path / "squat.avi", seed=1)
    csv = tmp_path / "one.csv"
    csv.write_text(f"path,label\n{video},squat\n")
    refused(["extract", str(csv), "--out", str(tmp_path / "poses"),
             "--overlay", str(tmp_path / "one.mp4")], tmp_path, capsys,
            "one.mp4: for a folder or labels CSV, --overlay names the folder for the overlay"
            " videos, not one video file")  # fmt: skip


# on one xdist worker: the module's amc_data made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt50b")


@pytest.fixture(scope="module")
def amc_data(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, str]:
    """Two activities of two AMC takes each (CMU 13_29's and 13_30's first 0.5 and 1.1 s),
    named as no HDM05 take is (so no rate is stated), a skeleton beside them; the case base
    ``train`` made of them, and what it said on stderr."""
    data = tmp_path_factory.mktemp("hunt50b-amc") / "data"
    cmu = shared_data / "cmu-mocap6" / "amc"
    for activity, take in (("jacks", "13_29"), ("twist", "13_30")):
        for name, frames in (("take1", 60), ("take2", 130)):
            _head(cmu / f"{take}.amc", frames, data / activity / f"{name}.amc")
        shutil.copyfile(shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
                        data / activity / "skel.asf")  # fmt: skip
    db = str(data.parent / "cb.sqlite")
    said = io.StringIO()
    with contextlib.redirect_stderr(said), contextlib.redirect_stdout(io.StringIO()):
        assert main(["train", str(data), "--db", db, "-k", "1"]) == 0
    return data, db, said.getvalue()


def _rate_lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if "assumed" in line]


def test_every_command_reading_amc_files_says_their_assumed_rate_once(
    amc_data: tuple[Path, str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    data, db, trained = amc_data
    one = data / "jacks" / "take1.amc"
    single = (
        f"note: {one}: read at 120 fps ({WHY}); give its rate with --fps if it was recorded"
        " at another"
    )
    convert = f"posecbr convert {data} --fps N --out DIR (then use its pose files)"
    four = (
        f"note: 4 recordings read at a frame rate assumed, not stated in their files (e.g."
        f" {one}: 120 fps, {WHY}); give theirs with {convert} if they were recorded at another"
    )
    assert _rate_lines(trained) == [four]
    capsys.readouterr()
    for argv, said in (
        (["classify", str(data), "--db", db, "--quiet"], four),
        (["classify", str(one), "--db", db, "--quiet"], single),
        (["describe", str(one)], single),
        (["dad", str(one)], single),
        (["compare", str(data), "-k", "1", "--features", "fluents",
          "--similarities", "euclidean", "--no-dad", "--peers", "none"], four),
    ):  # fmt: skip
        assert main(argv) == 0
        assert _rate_lines(capsys.readouterr().err) == [said], argv
    # the rate given: nothing assumed, nothing said
    assert main(["describe", str(one), "--fps", "60"]) == 0
    assert _rate_lines(capsys.readouterr().err) == []


def test_segment_of_several_amc_files_says_their_assumed_rate_in_one_line(
    amc_data: tuple[Path, str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """One line for the two recordings, naming the first, where each had its own."""
    data, db, _ = amc_data
    takes = [str(data / "jacks" / "take2.amc"), str(data / "twist" / "take2.amc")]
    capsys.readouterr()
    assert main(["segment", *takes, "--db", db, "--unknown", "held-out"]) == 0
    assert _rate_lines(capsys.readouterr().err) == [
        f"note: 2 recordings read at a frame rate assumed, not stated in their files (e.g."
        f" {takes[0]}: 120 fps, {WHY}); give theirs with --fps if they were recorded at"
        " another"
    ]
