"""Leftovers fixed in session 27 (27b): ``convert`` keeps a labels CSV's columns as spelt and
refuses one named as what it writes itself; the Python API refuses a clip too short to classify,
as the commands do; a case base of correct / incorrect repetitions is worded as classes, not
activities. Each test says what happened before its fix."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from cbr.estimator import CaseBaseClassifier
from features.datasets import load_dataset
from features.errors import InputError
from features.poses import load_pose
from posecbr.cli import main
from tests.badinput import good_pose_file, refused, small_case_base
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


# on one xdist worker: the module's fitted, correct_db made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt27b")


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


DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


@pytest.fixture(scope="module")
def correct_db(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, str]:
    """A case base of correct / incorrect deep squats (``--target correct``), and what train
    printed (stdout, stderr)."""
    import contextlib
    import io

    db = tmp_path_factory.mktemp("correct") / "cb.sqlite"
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["train", str(DEMO / "labels.csv"), "--labels", "deep_squat",
                     "--target", "correct", "--db", str(db), "--mirror", "off",
                     "--feature-weights", "none", "--phases", "0"])  # fmt: skip
    assert code == 0, err.getvalue()
    return db, out.getvalue(), err.getvalue()


def test_a_case_base_of_correct_repetitions_is_not_called_activities(
    correct_db: tuple[Path, str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``train --target correct`` said "18 cases (18 trained) from 2 activities", and
    ``casebase info`` "18 cases, 2 activities" and "fewer than three activities": correct and
    incorrect repetitions are no activities."""
    db, out, err = correct_db
    assert "from 2 classes" in out
    assert "activit" not in out + err
    assert main(["casebase", "info", "--db", str(db)]) == 0
    info = capsys.readouterr().out
    assert "18 cases, 2 classes" in info and "fewer than three classes" in info
    assert "activit" not in info


def test_feedback_of_no_class_of_a_correct_case_base_is_refused_in_its_words(
    correct_db: tuple[Path, str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: "'corect' is not an activity of this case base ... To add a new activity"."""
    db = correct_db[0]
    argv = ["classify", str(DEMO / "m01_s01_e02_inc.npz"), "--db", str(db), "--feedback",
            "corect"]  # fmt: skip
    line = refused(argv, db.parent, capsys, "not a class of this case base", "'correct'")
    assert "activit" not in line


def test_a_case_base_of_activities_still_says_activities(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = small_case_base(tmp_path)
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db)]) == 0
    assert "9 cases, 3 activities" in capsys.readouterr().out
    argv = ["classify", str(next((tmp_path / "train").rglob("*.npz"))), "--db", str(db),
            "--feedback", "nothing"]  # fmt: skip
    refused(argv, tmp_path, capsys, "not an activity of this case base", "new activity")
