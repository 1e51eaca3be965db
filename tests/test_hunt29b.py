"""Hunt 29b: outputs inside a folder read as class folders, compare's outputs named as an
input, an empty case base through the Python API, and repetition counting, conversion and
case base actions (``reps``, ``convert``, ``casebase``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused

# ------------------------------------------------ outputs inside a folder of class folders


def _video(path: Path) -> Path:
    """Two grey frames (nobody in view): refusals come before any frame is read."""
    import cv2

    path.parent.mkdir(parents=True, exist_ok=True)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 10.0, (32, 32))
    for k in range(2):
        writer.write(np.full((32, 32, 3), 60 + k, np.uint8))
    writer.release()
    return path


@pytest.mark.parametrize(
    ("option", "where", "needles"),
    [
        ("--overlay", "videos/ovl", ["overlay folder is inside the input folder", "videos"]),
        ("--out", "videos/poses", ["output folder is inside the input folder", "videos"]),
        ("--out", "videos", ["output folder is the input folder"]),
        # the pose files' folder is what `train poses` reads: each overlay one more clip
        ("--overlay", "poses", ["overlay folder is the folder of the pose files"]),
        ("--overlay", "poses/ovl", ["overlay folder is inside the folder of the pose files"]),
    ],
    ids=["overlay inside", "out inside", "out is the input", "overlay is out", "overlay in out"],
)
def test_extract_refuses_an_output_folder_in_the_folder_it_walks(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    option: str,
    where: str,
    needles: list[str],
) -> None:
    # videos/a.avi, videos/b.avi: an overlay folder videos/ovl/ of a.mp4, b.mp4 would be read
    # by the next `extract videos` as a class "ovl"; pose files in videos/poses/ by `train
    # videos` as a class "poses" (and the videos beside them no longer read at all).
    videos = tmp_path / "videos"
    _video(videos / "a.avi")
    _video(videos / "b.avi")
    argv = ["extract", str(videos), "--out", str(tmp_path / "poses")]
    argv = [*argv[:2], option, str(tmp_path / where)] if option == "--out" else [
        *argv, option, str(tmp_path / where)]  # fmt: skip
    refused(argv, tmp_path, capsys, str(tmp_path / where), *needles)


def test_convert_refuses_an_output_folder_inside_its_class_folders(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    for label in ("squat", "lunge"):
        (data / label).mkdir(parents=True)
        good_pose_file(data / label / "a.npz")
    # data/conv/a.npz and labels.csv would make `train data` read a third class, "conv"
    refused(["convert", str(data), "--out", str(data / "conv")], tmp_path, capsys,
            "output folder is inside the input folder", str(data / "conv"))  # fmt: skip


# ------------------------------------------------ compare: no output over a file of the data

_QUICK = ["--similarities", "euclidean", "--features", "fluents", "--no-dad", "--peers", "none",
          "--k", "1", "--explain", "0"]  # fmt: skip


@pytest.mark.parametrize("option", ["--json", "--csv"])
@pytest.mark.parametrize("victim", ["left out", "label file"])
def test_compare_refuses_an_output_named_as_a_file_of_the_data_it_does_not_load(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], option: str, victim: str
) -> None:
    # A labels CSV of five clips and a recording labelled over time; `--labels squat,lunge`
    # loads four of the clips, but the others (and the label file) are the data's all
    # the same: the results were written over the clip left out.
    data = tmp_path / "data"
    data.mkdir()
    rows = ["path,label,subject,label_file,label_block_s"]
    for name, label, subject in [("a", "squat", "p1"), ("b", "lunge", "p1"),
                                 ("c", "squat", "p2"), ("e", "lunge", "p2"),
                                 ("d", "reach", "p2")]:  # fmt: skip
        good_pose_file(data / f"{name}.npz", frames=40)
        rows.append(f"{name}.npz,{label},{subject},,")
    good_pose_file(data / "rec.npz", frames=60)  # 2 s: four labels of 0.5 s
    (data / "rec.txt").write_text("1\n1\n2\n2\n")
    rows.append("rec.npz,,p3,rec.txt,0.5")
    (data / "labels.csv").write_text("\n".join(rows) + "\n")
    target = data / ("d.npz" if victim == "left out" else "rec.txt")
    argv = ["compare", str(data), "--labels", "squat,lunge", *_QUICK, option, str(target)]
    refused(argv, tmp_path, capsys, "would overwrite an input", str(target))


def test_compare_refuses_the_data_folder_as_its_out_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # `compare data --out data` wrote results.json, results.csv and the pictures among the
    # clips: every output of compare is refused when named as an input, the data folder too
    data = tmp_path / "data"
    for label, subject in (("squat", "p1"), ("squat", "p2"), ("lunge", "p1"), ("lunge", "p2")):
        (data / label).mkdir(parents=True, exist_ok=True)
        good_pose_file(data / label / f"{subject}.npz", frames=40, subject=subject)
    argv = ["compare", str(data), *_QUICK, "--out", str(data)]
    refused(argv, tmp_path, capsys, "--out is the data folder", str(data))


# ------------------------------------------------ an empty case base through the Python API


@pytest.fixture(scope="module")
def emptied() -> tuple[Any, list[Any]]:
    """A fitted classifier whose case base was then emptied (every case taken out, as a
    subset of none), and a clip to classify."""
    from cbr.estimator import CaseBaseClassifier
    from tests.moves import clip

    names = ("squat", "squat", "arm_abduction", "arm_abduction")
    X = [clip(n, seconds=3.0).with_metadata(subject=f"p{i % 2}") for i, n in enumerate(names)]
    clf = CaseBaseClassifier(mirror="off", feature_weights="none", phases=0, k=1)
    clf.fit(X, list(names))
    clf.case_base_ = clf.case_base_.subset(np.array([], dtype=int))
    return clf, X


def _calls(clf: Any, X: list[Any]) -> dict[str, Any]:
    from cbr.maintenance import EDITORS
    from cbr.retrieve import retrieve, retrieve_many
    from cbr.segmentation import segment
    from tests.moves import clip

    values = np.zeros(len(clf.case_base_.names))
    cb = clf.case_base_
    return {
        "predict": lambda: clf.predict(X[:1]),  # was numpy's "zero-size array to reduction"
        "solve": lambda: clf.solve(X[:1]),
        "explain": lambda: clf.explain(X[:1]),
        "answer": lambda: clf.answer(values),  # was the first class, without a word
        "retrieve": lambda: retrieve(cb, values, 1),  # was no neighbour at all
        "retrieve_many": lambda: retrieve_many(cb, [values], 1),
        "segment": lambda: segment(clf, clip("squat", seconds=8.0)),
        **{
            f"trim {n}": (lambda e=e, n=n: e(cb) if n != "novelty-benefit" else e(cb, 0.5))
            for n, e in EDITORS.items()
        },  # fmt: skip
    }


@pytest.mark.parametrize(
    "call",
    ["predict", "solve", "explain", "answer", "retrieve", "retrieve_many", "segment",
     "trim novelty-benefit", "trim cnn", "trim renn", "trim icf"],
)  # fmt: skip
def test_an_empty_case_base_is_named_as_empty(emptied: tuple[Any, list[Any]], call: str) -> None:
    from features.errors import DataError

    clf, X = emptied
    with pytest.raises(DataError, match="the case base holds no cases"):
        _calls(clf, X)[call]()


# ------------------------------------------------ mocap text written on Windows (BOM)

_BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 95 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 -45 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 -45 0
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.04
0 95 0 0 0 0 0 0 0 0 0 0
0 95 0 0 0 0 0 0 0 0 90 0
"""


def test_a_bvh_file_with_a_byte_order_mark_is_read(tmp_path: Path) -> None:
    # Notepad and other Windows editors start a UTF-8 file with EF BB BF: the reader took it
    # for part of the first word and refused the file ("does not start with HIERARCHY").
    from features.readers.bvh import read_bvh
    from features.skeleton import JOINT_INDEX

    path = tmp_path / "knee.bvh"
    path.write_bytes(b"\xef\xbb\xbf" + _BVH.replace("\n", "\r\n").encode())
    seq = read_bvh(path, unit="cm")
    assert seq.fps == pytest.approx(25.0)
    hip, knee = JOINT_INDEX["left_hip"], JOINT_INDEX["left_knee"]
    # the hips 95 cm up, the left hip 10 cm to the side, the knee 45 cm below it; in the
    # second frame the knee joint turns 90 degrees about x (the hip does not: the knee stays)
    np.testing.assert_allclose(seq.positions[:, hip], [[0.10, 0.95, 0.0]] * 2, atol=1e-12)
    np.testing.assert_allclose(seq.positions[:, knee], [[0.10, 0.50, 0.0]] * 2, atol=1e-12)


def test_an_amc_file_with_a_byte_order_mark_is_read(tmp_path: Path, shared_data: Path) -> None:
    # an HDM05 squat (one repetition) saved again by a Windows editor: refused before ("line
    # 1: data before the first frame number", the mark glued to the header's "#")
    from features.readers.asfamc import read_asf_amc

    folder = shared_data / "hdm05" / "train" / "10"
    amc, asf = folder / "HDM_bd_squat1Reps_001_120.amc", folder / "HDM_bd.asf"
    marked = tmp_path / amc.name
    marked.write_bytes(b"\xef\xbb\xbf" + amc.read_bytes())
    np.testing.assert_array_equal(
        read_asf_amc(asf, marked).positions, read_asf_amc(asf, amc).positions
    )


def test_convert_refuses_a_recording_of_the_same_name_from_another_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # monday/squat.bvh and tuesday/squat.bvh, two takes, converted one after the other into
    # one folder: the second replaced the first's pose file without a word (each pose file's
    # origin was its file name alone, "squat.bvh", the same for both)
    from features.poses import load_pose

    for day, knee in (("monday", "90"), ("tuesday", "45")):
        (tmp_path / day).mkdir()
        (tmp_path / day / "squat.bvh").write_text(_BVH.replace(" 90 0\n", f" {knee} 0\n"))
    out = tmp_path / "poses"
    assert main(["convert", str(tmp_path / "monday" / "squat.bvh"), "--out", str(out)]) == 0
    capsys.readouterr()
    refused(["convert", str(tmp_path / "tuesday" / "squat.bvh"), "--out", str(out)], tmp_path,
            capsys, "already there from another recording", "monday", "tuesday")  # fmt: skip
    assert load_pose(out / "squat.npz").metadata["origin"] == "monday/squat.bvh"
    # the same take again replaces its own pose file, as before
    assert main(["convert", str(tmp_path / "monday" / "squat.bvh"), "--out", str(out)]) == 0


def test_convert_names_fps_it_cannot_write_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # 0.005 fps passed convert's own check, (0, 10000], and was refused by the pose file
    # when the first clip was written: "fps must be between ..." naming neither the option
    # nor a file. The rates a pose file takes are [0.01, 10000] (README).
    bvh = tmp_path / "squat.bvh"
    bvh.write_text(_BVH)
    argv = ["convert", str(bvh), "--out", str(tmp_path / "poses"), "--fps", "0.005"]
    refused(argv, tmp_path, capsys, "--fps: must be a frame rate in [0.01, 10000], got 0.005")


# ------------------------------------------------ casebase: --json on every action


def test_casebase_upgrade_takes_json_as_every_action_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # info, list, export and trim took --json; upgrade stopped at argparse's usage message.
    # A case base written by posecbr 0.1 (schema version 1: tests/fixtures/store_v1.sql),
    # upgraded, then upgraded again (nothing to do).
    import json
    import sqlite3

    db = tmp_path / "old.sqlite"
    con = sqlite3.connect(db)
    con.executescript((Path(__file__).with_name("fixtures") / "store_v1.sql").read_text("utf-8"))
    con.close()
    for before, changed in ((1, True), (2, False)):
        assert main(["casebase", "upgrade", "--db", str(db), "--json"]) == 0
        assert json.loads(capsys.readouterr().out) == {
            "db": str(db), "schema_version_before": before, "schema_version": 2,
            "left_wal_mode": False, "rolled_back_interrupted_change": False,
            "changed": changed}  # fmt: skip


def test_convert_into_a_windows_labels_file_keeps_its_clips_not_its_blank_lines(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a labels.csv saved by a Windows editor: byte order mark, CRLF, blank lines at the end
    # (one of spaces, one of commas alone). The blank lines were counted as clips ("3 clips
    # listed before kept") and written back as rows.
    out = tmp_path / "poses"
    out.mkdir()
    good_pose_file(out / "old.npz")
    (out / "labels.csv").write_bytes(
        b"\xef\xbb\xbfpath,label,subject\r\nold.npz,squat,p1\r\n\r\n   \r\n,,\r\n"
    )
    bvh = tmp_path / "knee.bvh"
    bvh.write_text(_BVH)
    assert main(["convert", str(bvh), "--out", str(out), "--bvh-unit", "cm"]) == 0
    assert "(1 clip listed before kept)" in capsys.readouterr().out
    assert (out / "labels.csv").read_text().splitlines() == [
        "path,label,subject,bvh_unit", "old.npz,squat,p1,", "knee.npz,knee,,cm"]  # fmt: skip
