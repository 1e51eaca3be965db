"""Hunt 39l: ``extract`` of a labels CSV row naming a ``label_file`` (a recording labelled over
time) writes what ``train`` reads as the CSV; a byte order mark inside a labels CSV (two CSVs
joined) refused naming its line."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused

BOM = "\ufeff"


# ---------------------------------------------------------------- a byte order mark inside


@pytest.mark.parametrize("command", ["train", "convert", "extract"])
def test_a_byte_order_mark_inside_a_labels_csv_is_refused_naming_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    """Two labels CSVs, each saved with a byte order mark (as Excel saves "CSV UTF-8"),
    joined with ``cat``: the second's mark began the path of line 4, and every command said
    "no such file \\ufeffrec2.npz", a name that looks right. Refused as a label file with
    one inside is, naming the line, nothing written."""
    for name in ("rec1.npz", "rec2.npz"):
        good_pose_file(tmp_path / name, frames=12)
    first = f"{BOM}path,label\nrec1.npz,squat\n"
    second = f"{BOM}rec2.npz,lunge\n"  # the second file's rows, no header
    csv = tmp_path / "labels.csv"
    csv.write_text(first + "\n" + second, encoding="utf-8")
    argv = {
        "train": ["train", str(csv), "--db", str(tmp_path / "cb.sqlite")],
        "convert": ["convert", str(csv), "--out", str(tmp_path / "converted")],
        "extract": ["extract", str(csv), "--out", str(tmp_path / "poses")],
    }[command]
    line = refused(argv, tmp_path, capsys,
                   f"{csv}: line 4: a byte order mark (U+FEFF, unseen) inside the labels CSV",
                   "files joined together?", "part of a path or label")  # fmt: skip
    assert "no such file" not in line


def test_a_byte_order_mark_at_the_start_of_a_labels_csv_changes_nothing(tmp_path: Path) -> None:
    from features.datasets import read_labels_csv

    good_pose_file(tmp_path / "rec1.npz", frames=12)
    plain, marked = tmp_path / "plain.csv", tmp_path / "marked.csv"
    plain.write_text("path,label\nrec1.npz,squat\n", encoding="utf-8")
    marked.write_bytes(b"\xef\xbb\xbfpath,label\r\nrec1.npz,squat\r\n")
    assert read_labels_csv(marked) == read_labels_csv(plain)


# ------------------------------------------------ extract: a recording labelled over time

SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"  # 65 frames, 5 fps


def _cases(db: Path) -> tuple[list[tuple[str, tuple[int, int], str]], np.ndarray]:
    """Each case's label, frame span and subject, and the problems."""
    from casebase_store import open_store
    from cbr.stored import load_classifier

    with open_store(db, readonly=True) as store:
        cb = load_classifier(store, "default").classifier.case_base_
    spans = [(int(a), int(b)) for a, b in cb.frames]
    cases = list(zip([str(v) for v in cb.labels], spans, [str(s) for s in cb.subjects],
                     strict=True))  # fmt: skip
    return cases, np.asarray(cb.problems)


def _windows(label: str, start: int, stop: int, subject: str) -> list[tuple[Any, ...]]:
    """Worked out by hand: at 5 fps a 2-s window is 10 frames, one every 0.5 s (2.5 frames,
    Python rounding halves to even: 0, 2, 5, 8, 10, ...) that fits the stretch."""
    starts = [start + round(2.5 * k) for k in range(100)]
    return [(label, (a, a + 10), subject) for a in starts if a + 10 <= stop]


def _recording_csv(tmp_path: Path, shared_data: Path) -> Path:
    """The squat video labelled by hand over 1-s blocks (codes named in a names file: 6 s
    squat, 7 s rest), beside a copy of it with one stretch labelled by its row (frames 1-20,
    whose windows start where none of the squat's does: a window of the same frames would be
    a copy of one labelled squat, which train refuses)."""
    shutil.copy(shared_data / SQUAT, tmp_path / "squat.mp4")
    shutil.copy(shared_data / SQUAT, tmp_path / "squat2.mp4")
    (tmp_path / "truth").mkdir()
    (tmp_path / "truth" / "squat.txt").write_text("1 1 1 1 1 1 2 2 2 2 2 2 2\n", encoding="utf-8")
    (tmp_path / "truth" / "names.txt").write_text("1 squat\n2 rest\n", encoding="utf-8")
    csv = tmp_path / "rec.csv"
    csv.write_text(
        "path,label,label_file,label_block_s,label_names,subject,start,end,camera\n"
        "squat.mp4,,truth/squat.txt,1,truth/names.txt,s01,,,front\n"
        "squat2.mp4,deep,,,,s02,1,21,side\n",
        encoding="utf-8",
    )
    return csv


def test_extract_of_a_recording_labelled_over_time_trains_as_its_labels_csv(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV row naming a label_file was extracted to OUT/_/squat.npz with an empty
    label and its label track dropped: ``train OUT`` took "_" as an activity of one case.
    Now the recording is kept whole, its label file and names file copied beside it, and
    OUT/labels.csv names them (with every other row's pose file), so ``train OUT`` makes
    the cases ``train CSV`` makes: the same labels, frame spans, subjects and problems."""
    csv = _recording_csv(tmp_path, shared_data)
    out = tmp_path / "out"
    assert main(["extract", str(csv), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    for db, data in (("from_csv.sqlite", csv), ("from_out.sqlite", out)):
        assert main(["train", str(data), "--db", str(tmp_path / db)]) == 0
    by_csv, problems_csv = _cases(tmp_path / "from_csv.sqlite")
    by_out, problems_out = _cases(tmp_path / "from_out.sqlite")
    # 1-s blocks at 5 fps: squat frames 0-29, rest 30-64; the deep row frames 1-20
    expected = [*_windows("squat", 0, 30, "s01"), *_windows("rest", 30, 65, "s01"),
                *_windows("deep", 1, 21, "s02")]  # fmt: skip
    assert len(expected) == 9 + 11 + 5
    assert by_csv == expected
    assert by_out == by_csv
    assert np.allclose(problems_out, problems_csv, atol=1e-6, equal_nan=True)

    assert f"wrote {out / 'labels.csv'}" in err
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == [
        "deep", "deep/squat2_1-21.npz", "labels.csv", "names.txt", "squat.npz", "squat.txt",
    ]  # fmt: skip
    assert (out / "squat.txt").read_bytes() == (tmp_path / "truth" / "squat.txt").read_bytes()
    assert (out / "names.txt").read_bytes() == (tmp_path / "truth" / "names.txt").read_bytes()
    assert (out / "labels.csv").read_text(encoding="utf-8").splitlines() == [
        "path,label,subject,label_file,label_block_s,label_names,camera",
        "squat.npz,,s01,squat.txt,1.0,names.txt,front",
        "deep/squat2_1-21.npz,deep,s02,,,,side",
    ]

    # again: up to date, the model not run, labels.csv and the label files as they were
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    capsys.readouterr()
    assert main(["extract", str(csv), "--out", str(out)]) == 0
    assert "0 extracted, 2 up to date, 0 failed" in capsys.readouterr().out
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_extract_refuses_an_out_folder_whose_pose_files_labels_csv_would_hide(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """OUT/labels.csv is what ``train OUT`` reads: a pose file already there that it would
    not list (an earlier extract's class folder) would silently drop out of training."""
    csv = _recording_csv(tmp_path, shared_data)
    good_pose_file(tmp_path / "out" / "lunge" / "old.npz", frames=12)
    refused(["extract", str(csv), "--out", str(tmp_path / "out")], tmp_path, capsys,
            f"{tmp_path / 'out'}: holds pose files this labels CSV does not list"
            " (lunge/old.npz)", "choose another --out")  # fmt: skip


def test_extract_refuses_to_write_labels_csv_over_the_csv_it_reads(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    csv = _recording_csv(tmp_path, shared_data)
    listed = tmp_path / "labels.csv"
    listed.write_bytes(csv.read_bytes())
    refused(["extract", str(tmp_path), "--out", str(tmp_path)], tmp_path, capsys,
            f"{listed}: is the labels CSV being read")  # fmt: skip


def test_extract_refuses_a_label_file_that_does_not_fit_the_video_before_the_model_runs(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The label file was never read by extract (the track dropped): one that cannot fit
    its video (13 labels, one per frame, for 65 frames) is refused as train refuses it."""
    csv = _recording_csv(tmp_path, shared_data)
    csv.write_text(csv.read_text().replace("truth/squat.txt,1,", "truth/squat.txt,,"))
    refused(["extract", str(csv), "--out", str(tmp_path / "out")], tmp_path, capsys,
            "squat.txt: 13 labels (one per frame) do not fit the recording squat.mp4")  # fmt: skip


def test_label_files_of_one_name_are_copied_under_names_of_their_own(tmp_path: Path) -> None:
    """Two recordings' label files both named labels.csv (one folder per take) go beside
    the pose files as labels_2.csv and labels_3.csv: neither replaces the labels.csv that
    names them, nor the other; one inside --out already stays where it is."""
    from features.label_tracks import LabelTrack
    from posecbr.commands.extract import Job, _label_file_copies

    out = tmp_path / "out"
    (out / "truth").mkdir(parents=True)
    inside = out / "truth" / "c.txt"
    jobs = [
        Job(video=tmp_path / f"{k}.mp4", out=out / f"{k}.npz",
            track=LabelTrack(tmp_path / k / "labels.csv", 0.1, tmp_path / "names.txt"))
        for k in ("a", "b")
    ] + [Job(video=tmp_path / "c.mp4", out=out / "c.npz", track=LabelTrack(inside))]  # fmt: skip
    copies = _label_file_copies(out, jobs)
    assert {
        str(k.relative_to(tmp_path)): str(v.relative_to(tmp_path)) for k, v in copies.items()
    } == {
        "a/labels.csv": "out/labels_2.csv",
        "names.txt": "out/names.txt",
        "b/labels.csv": "out/labels_3.csv",
        "out/truth/c.txt": "out/truth/c.txt",
    }
