"""Session 45's hunt: ``train --append`` of clips stored from another working folder, and
``classify --target`` mistyped for a column the clips have."""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import sqlite3
from pathlib import Path

import pytest

from casebase_store import open_store
from features.poses import load_pose, save_pose
from posecbr.cli import main
from tests.test_cbr_cli import _write_classes


def _cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _labels_csv(folder: Path, extra: dict[str, str] | None = None) -> Path:
    """``folder/labels.csv`` listing its pose files relative to ``folder`` (by the name of
    their class folder), with the ``extra`` columns' values on every row."""
    clips = sorted(folder.rglob("*.npz"))
    extra = extra or {}
    path = folder / "labels.csv"
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["path", "label", *extra])
        for p in clips:
            w.writerow([p.relative_to(folder).as_posix(), p.parent.name, *extra.values()])
    return path


def _count(db: Path) -> int:
    store = open_store(db, readonly=True)
    try:
        return store.count_cases("default")
    finally:
        store.close()


def test_append_from_another_folder_of_clips_already_stored_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``train labels.csv`` inside conv1/, then ``train conv1/labels.csv --append`` from its
    parent added every clip again (case 1 ``m01.npz`` and case 7
    ``conv1/m01.npz``: each clip voted twice): the source stored relative to the other
    working folder resolved to nothing. Now refused in one line naming both, nothing
    written; a clip of the same name and frames with other poses is still added."""
    conv1 = _write_classes(tmp_path / "conv1", 2, 11)
    _labels_csv(conv1)
    db = tmp_path / "cb.sqlite"
    monkeypatch.chdir(conv1)
    assert _cli(capsys, "train", "labels.csv", "--db", str(db))[0] == 0
    assert _count(db) == 6
    stored = db.read_bytes()
    monkeypatch.chdir(tmp_path)
    code, _, err = _cli(capsys, "train", "conv1/labels.csv", "--db", str(db), "--append")
    assert code == 1 and err.count("\n") == 1 and "Traceback" not in err, err
    # the first clip of the labels CSV (sorted paths), its frames end inclusive
    clip = sorted(conv1.rglob("*.npz"))[0]
    rel = clip.relative_to(conv1).as_posix()
    last = load_pose(clip).n_frames - 1
    assert f"conv1/{rel} frames 0-{last} is already case 1 of 'default', " in err, err
    assert f"stored as {rel} frames 0-{last} " in err and "nothing added" in err, err
    assert db.read_bytes() == stored
    # cases stored without their frames (as before they were kept): compared without them
    with contextlib.closing(sqlite3.connect(db)) as con, con:
        con.execute("UPDATE cases SET frame_start = NULL, frame_end = NULL")
    code, _, err = _cli(capsys, "train", "conv1/labels.csv", "--db", str(db), "--append")
    assert code == 1 and err.count("\n") == 1, err
    assert f"already case 1 of 'default', stored as {rel} (the same " in err, err
    assert _count(db) == 6

    # another recording of that name and length (one joint moved 5 cm in every frame):
    # another clip, added
    seq = load_pose(clip)
    moved = seq.positions.copy()
    moved[:, 0, 0] += 0.05
    other = tmp_path / "conv2" / clip.parent.name / clip.name
    save_pose(dataclasses.replace(seq, positions=moved), other)
    code, _, err = _cli(capsys, "train", str(other.relative_to(tmp_path)), "--db", str(db),
                        "--append")  # fmt: skip
    assert code == 0, err
    assert _count(db) == 7


def test_classify_mistyped_target_guesses_the_clips_column(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``classify data.csv --target corect`` against a case base of labels said "train a case
    base with --target corect" with no guess, though the labels CSV has a ``correct``
    column; ``correct`` is guessed now (the case base's own target was the only guess)."""
    folder = _write_classes(tmp_path / "data", 2, 5)
    csv_path = _labels_csv(folder, {"correct": "true"})
    db = tmp_path / "cb.sqlite"
    assert _cli(capsys, "train", str(csv_path), "--db", str(db))[0] == 0
    code, out, err = _cli(capsys, "classify", str(csv_path), "--db", str(db), "--target", "corect")
    assert code == 1 and err.count("\n") == 1 and out == "", err
    assert "case base 'default' predicts 'label'" in err
    assert err.rstrip().endswith("(did you mean 'correct'?)"), err
    # nothing close among the columns: no guess
    code, _, err = _cli(capsys, "classify", str(csv_path), "--db", str(db), "--target", "speed")
    assert code == 1 and "did you mean" not in err, err
