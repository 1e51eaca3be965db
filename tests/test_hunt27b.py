"""Leftovers fixed in session 27 (27b): ``convert`` keeps a labels CSV's columns as spelt and
refuses one named as what it writes itself; the Python API refuses a clip too short to classify,
as the commands do; ..."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from cbr.estimator import CaseBaseClassifier
from features.datasets import load_dataset
from features.errors import InputError
from features.poses import load_pose
from posecbr.cli import main
from tests.badinput import good_pose_file, refused
from tests.test_cbr_clips import arm_dataset


def _labelled(folder: Path, header: str, *rows: str) -> Path:
    """Two pose files and a labels CSV naming them with ``header`` and ``rows``."""
    folder.mkdir(parents=True)
    for i in range(2):
        good_pose_file(folder / f"c{i}.npz")
    csv_path = folder / "labels.csv"
    csv_path.write_text("\n".join([header, *rows]) + "\n")
    return csv_path


def test_convert_keeps_the_spelling_of_the_labels_csv_columns(tmp_path: Path) -> None:
    """Before: ``Camera`` was written as ``camera`` in labels.csv and the pose files (the
    reader lower-cased every column name)."""
    src = _labelled(
        tmp_path / "src", "path,Label,subject,Camera,Notes", "c0.npz,squat,s1,Front,tired",
        "c1.npz,squat,s1,Side,fresh",
    )  # fmt: skip
    out = tmp_path / "out"
    assert main(["convert", str(src), "--out", str(out)]) == 0
    with (out / "labels.csv").open(newline="") as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
    assert reader.fieldnames == ["path", "label", "subject", "Camera", "Notes"]
    assert [(r["Camera"], r["Notes"]) for r in rows] == [("Front", "tired"), ("Side", "fresh")]
    meta = load_pose(out / "c0.npz").metadata
    assert (meta["Camera"], meta["Notes"]) == ("Front", "tired")
    assert "camera" not in meta


def test_a_column_is_still_found_in_any_case(tmp_path: Path) -> None:
    """The columns keep their spelling, and are still found in any case where they are asked
    for: ``--target correct`` of a ``Correct`` column, as when every name was lower-cased.
    Before: ``--target Correct``, the column as the file spells it, found no value."""
    from features.datasets import clip_target

    src = _labelled(tmp_path / "src", "path,label,Correct", "c0.npz,squat,yes", "c1.npz,squat,no")
    clips = load_dataset(src)
    assert [clip_target(c, "correct") for c in clips] == ["correct", "incorrect"]
    assert [clip_target(c, "Correct") for c in clips] == ["correct", "incorrect"]


@pytest.mark.parametrize(
    ("column", "needle"),
    [("source", "made from"), ("ORIGIN", "came from"), ("fps_source", "frame rate")],
)
def test_a_column_convert_writes_itself_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], column: str, needle: str
) -> None:
    """Before: a ``source`` column was dropped from labels.csv and stored in each pose file as
    what it was made from; an ``origin`` column was overwritten with where the clip came
    from; both without a word."""
    src = _labelled(
        tmp_path / "src", f"path,label,{column}", "c0.npz,squat,lab A", "c1.npz,squat,lab B"
    )
    argv = ["convert", str(src), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, "labels.csv", repr(column), needle, "rename the column")


@pytest.fixture(scope="module")
def fitted() -> tuple[CaseBaseClassifier, list[object]]:
    X, y = arm_dataset(3, 5)
    clf = CaseBaseClassifier(k=3, feature_weights="none", phases=0, mirror="off")
    return clf.fit(X, y), X


@pytest.mark.parametrize("call", ["solve", "predict", "predict_proba", "explain"])
def test_the_api_refuses_a_clip_too_short_to_classify(
    fitted: tuple[CaseBaseClassifier, list[object]], call: str
) -> None:
    """Before: ``solve`` (and ``predict``, ``explain``) answered a clip of one frame, here
    with confidence 0.91, where ``classify`` calls it unclassifiable (one posture, no
    movement)."""
    from cbr.classification import too_short

    clf, X = fitted
    one = X[0].slice_frames(0, 1)  # type: ignore[attr-defined]
    with pytest.raises(InputError) as caught:
        getattr(clf, call)([X[1], one])
    assert caught.value.message == too_short(one)  # the words classify prints
    assert "1 frame" in caught.value.message and "nothing to classify" in caught.value.message
    assert isinstance(caught.value, ValueError)  # what scikit-learn users catch
    assert len(clf.solve([X[1]])) == 1  # a clip long enough is answered
