"""Hunt 39n: pose files written into a folder whose labels.csv would not list them (``train
OUT`` reads labels.csv alone and walks nothing) are refused by ``extract`` and ``convert``
before any work, rather than silently left out of training."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused

SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"  # 65 frames, 5 fps
# the header extract writes into --out for a labels CSV with rows naming label files
LISTING = "path,label,subject,label_file,label_block_s,label_names\n"


def _out_with_listing(tmp_path: Path, *rows: str) -> Path:
    """An --out as an earlier ``extract`` of a labels CSV naming a label file left it: a
    recording's pose file, its label file beside it, and labels.csv naming both."""
    out = tmp_path / "out"
    good_pose_file(out / "rec.npz", frames=30)
    (out / "rec.txt").write_text("1\n", encoding="utf-8")
    (out / "labels.csv").write_text(
        LISTING + "rec.npz,,s01,rec.txt,1.0,\n" + "".join(rows), encoding="utf-8"
    )
    return out


@pytest.mark.parametrize("given", ["folder", "csv", "video", "pose file"])
def test_extract_into_a_folder_whose_labels_csv_would_not_list_its_pose_files_is_refused(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str], given: str
) -> None:
    """``extract videos/ --out OUT`` (or a labels CSV without label files, one video, or
    one video with ``--out OUT/new.npz``) after an extract had written OUT/labels.csv: the
    new pose files went into OUT/squat/ (or OUT), which ``train OUT`` never looks at (it
    reads labels.csv), so they were silently left out of training. Refused before the model
    runs, naming labels.csv, a few files and the count, nothing written."""
    out = _out_with_listing(tmp_path)
    videos = tmp_path / "videos" / "squat"
    videos.mkdir(parents=True)
    for k in range(1, 5):
        shutil.copy(shared_data / SQUAT, videos / f"v{k}.mp4")
    csv = tmp_path / "more.csv"
    csv.write_text("path,label\nvideos/squat/v1.mp4,squat\n", encoding="utf-8")
    source, needles = {
        "folder": (tmp_path / "videos",
                   ["4 pose files this extract would write there",
                    "(squat/v1.npz, squat/v2.npz, squat/v3.npz and 1 more)"]),
        "csv": (csv, ["1 pose file this extract would write there (squat/v1.npz)"]),
        "video": (videos / "v1.mp4", ["1 pose file this extract would write there (v1.npz)"]),
        "pose file": (videos / "v1.mp4", ["1 pose file this extract would write there (new.npz)"]),
    }[given]  # fmt: skip
    dest = out / "new.npz" if given == "pose file" else out  # --out names the pose file itself
    refused(["extract", str(source), "--out", str(dest)], tmp_path, capsys,
            f"{out / 'labels.csv'}: lists the pose files train of {out} reads",
            *needles, "train would leave them out",
            "add a row for each to it (path,label[,subject]) before extracting",
            "or choose another --out")  # fmt: skip


def test_extract_of_pose_files_the_labels_csv_lists_goes_ahead_and_trains_with_them(
    tmp_path: Path, shared_data: Path
) -> None:
    """The way in the refusal names: rows added to OUT/labels.csv first, the extract runs
    and ``train OUT`` takes its clip (a case labelled squat beside the recording's)."""
    from casebase_store import open_store
    from cbr.stored import load_classifier

    out = _out_with_listing(tmp_path, "squat/v1.npz,squat,s02,,,\n")
    (tmp_path / "videos" / "squat").mkdir(parents=True)
    shutil.copy(shared_data / SQUAT, tmp_path / "videos" / "squat" / "v1.mp4")
    listed = (out / "labels.csv").read_bytes()
    assert main(["extract", str(tmp_path / "videos"), "--out", str(out)]) == 0
    assert (out / "squat" / "v1.npz").is_file()
    assert (out / "labels.csv").read_bytes() == listed  # never rewritten
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(out), "--db", str(db), "--k", "1"]) == 0
    with open_store(db, readonly=True) as store:
        cb = load_classifier(store, "default").classifier.case_base_
    # the recording's one 1-s block is labelled "1"; the squat video whole is one case
    assert sorted({str(v) for v in cb.labels}) == ["1", "squat"]
    assert sorted({str(s) for s in cb.subjects}) == ["s01", "s02"]


def test_convert_into_a_folder_of_pose_files_without_labels_csv_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``convert`` into a folder where an earlier ``extract videos/ --out OUT`` had put class
    folders of pose files wrote OUT/labels.csv naming its own clips alone: ``train OUT``
    then read that and left the extracted clips out. Refused before any work."""
    out = tmp_path / "out"
    good_pose_file(out / "squat" / "a.npz", frames=12)
    good_pose_file(out / "squat" / "b.npz", frames=12)
    good_pose_file(tmp_path / "src" / "rec1.npz", frames=12)
    (tmp_path / "src" / "labels.csv").write_text("path,label\nrec1.npz,lunge\n", encoding="utf-8")
    refused(["convert", str(tmp_path / "src" / "labels.csv"), "--out", str(out)], tmp_path,
            capsys, f"{out}: holds 2 pose files and no labels.csv (squat/a.npz, squat/b.npz)",
            "train of the folder would leave those out",
            "list them in a labels.csv there first (path,label), which convert adds to",
            "or choose another --out")  # fmt: skip


def test_convert_into_a_folder_with_labels_csv_adds_to_it_as_before(tmp_path: Path) -> None:
    """A labels.csv there listing its pose files: converting adds its clips' rows, and
    ``train``'s reading of the folder has both (nothing refused)."""
    from features.datasets import read_labels_csv

    out = tmp_path / "out"
    good_pose_file(out / "squat" / "a.npz", frames=12)
    (out / "labels.csv").write_text("path,label\nsquat/a.npz,squat\n", encoding="utf-8")
    good_pose_file(tmp_path / "src" / "rec1.npz", frames=12)
    (tmp_path / "src" / "labels.csv").write_text("path,label\nrec1.npz,lunge\n", encoding="utf-8")
    assert main(["convert", str(tmp_path / "src" / "labels.csv"), "--out", str(out)]) == 0
    rows = read_labels_csv(out / "labels.csv")
    assert [(r["path"], r["label"]) for r in rows] == [
        ((out / "squat" / "a.npz").resolve(), "squat"),
        ((out / "rec1.npz").resolve(), "lunge"),
    ]
