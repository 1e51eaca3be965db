"""Two defects of the Python API a robot engineer met (hunt 35h, fixed in 35l): opening a
mistyped case base path to read made an empty database there, and a loaded model of a
repetition check explained itself in its plain labels ("true", "false")."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest

from casebase_store import EmptyStore, StoreError, open_store, write_store
from cbr.estimator import CaseBaseClassifier
from cbr.stored import load_classifier
from cbr.training import train
from features.poses import PoseSequence, load_pose
from tests.badinput import refused

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


# ------------------------------------------------------------ reading a missing case base


@pytest.mark.parametrize("readonly", [False, True])
def test_opening_a_missing_file_to_read_is_an_error_and_makes_no_file(
    tmp_path: Path, readonly: bool
) -> None:
    """``open_store("robto.sqlite")`` (a typo) made an empty ~57 KB database there, and the
    load that followed found no case base in it. Now the open itself refuses, naming the
    path, and nothing is created."""
    db = tmp_path / "robto.sqlite"
    with pytest.raises(StoreError, match="no such case base file") as info:
        open_store(db, readonly=readonly)
    assert info.value.source == str(db)
    assert str(db) in str(info.value)
    assert not db.exists()
    assert list(tmp_path.iterdir()) == []


def test_an_empty_file_is_not_made_a_store_by_reading_it(tmp_path: Path) -> None:
    """An empty file (touched, or made by another program) stays empty when opened to read."""
    db = tmp_path / "cb.sqlite"
    db.touch()
    with pytest.raises(EmptyStore, match="no case base store here"):
        open_store(db)
    assert db.stat().st_size == 0


def test_create_true_makes_a_new_store_that_then_opens_without_it(tmp_path: Path) -> None:
    """Writing to a new file says so (``create=True``); the store made opens by default."""
    db = tmp_path / "new.sqlite"
    with open_store(db, create=True) as store:
        assert store.list_case_bases() == []
    assert db.is_file() and db.stat().st_size > 0
    with open_store(db) as store:
        assert store.list_case_bases() == []
    with open_store(db, readonly=True) as store:
        assert store.list_case_bases() == []


def test_write_store_still_creates_the_file(tmp_path: Path) -> None:
    db = tmp_path / "sub.sqlite"
    assert write_store(db, lambda tx: 7) == 7
    with open_store(db, readonly=True) as store:
        assert store.list_case_bases() == []


# on one xdist worker: the module's squats, stored_check made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt35l")


@pytest.fixture(scope="module")
def squats() -> tuple[list[PoseSequence], list[str]]:
    """The demo's 18 deep squats (9 correct, 9 incorrect) with their ``correct`` column as
    the labels file gives it: "true" / "false"."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["label"] == "deep_squat"]
    return [load_pose(DEMO / r["path"]).to_canonical() for r in rows], [r["correct"] for r in rows]


@pytest.fixture(scope="module")
def stored_check(
    squats: tuple[list[PoseSequence], list[str]], tmp_path_factory: pytest.TempPathFactory
) -> Path:
    """A repetition check trained from Python with ``target="correct"`` (what ``posecbr
    train --target correct`` stores); training makes the file."""
    X, y = squats
    db = tmp_path_factory.mktemp("check") / "check.sqlite"
    assert not db.exists()
    train(db, "squat", X, y, CaseBaseClassifier(k=3, mirror=False), target="correct")
    assert db.is_file()
    return db


@pytest.mark.parametrize("argv", [["casebase", "list"], ["casebase", "info"]])
def test_the_commands_still_refuse_a_missing_database_as_before(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "nosuch.sqlite"
    line = refused([*argv, "--db", str(missing)], tmp_path, capsys, "no such case base file")
    assert line.endswith(f"{missing}: no such case base file"), line
    assert not missing.exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["classify", str(DEMO / "m01_s01_e01.npz")],
        ["segment", str(DEMO / "m01_s01_e01.npz")],
        ["train", str(DEMO), "--append"],
    ],
)
def test_the_commands_reading_clips_still_refuse_a_missing_database_as_before(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "nosuch.sqlite"
    refused([*argv, "--db", str(missing)], tmp_path, capsys, f"{missing}: no such case base file")
    assert not missing.exists()


def test_training_from_python_still_creates_the_file(stored_check: Path) -> None:
    """``cbr.training.train`` writes: a path that does not exist yet becomes the store."""
    with open_store(stored_check, readonly=True) as store:
        assert [cb.name for cb in store.list_case_bases()] == ["squat"]
        assert store.count_cases("squat") == 18


# ------------------------------------------------------- a loaded model's stored target


def test_a_loaded_repetition_check_explains_in_its_stored_targets_words(
    squats: tuple[list[PoseSequence], list[str]], stored_check: Path
) -> None:
    """Loaded, a case base trained with ``target="correct"`` explained "true, confidence 0.97
    ... To be false, 2 changes" (its labels as stored) unless ``explain(X,
    target="correct")`` was given; now the stored
    target is the default: "a correct repetition" / "an incorrect repetition", as
    ``posecbr classify`` says."""
    X, _ = squats
    with open_store(stored_check, readonly=True) as store:
        stored = load_classifier(store, "squat")
    clf = stored.classifier
    assert stored.target == "correct"
    answers = [str(v) for v in clf.predict(X[:4])]
    assert set(answers) <= {"true", "false"}
    for i, (exp, answer) in enumerate(zip(clf.explain(X[:4]), answers, strict=True)):
        words = "a correct repetition" if answer == "true" else "an incorrect repetition"
        assert words in exp.text, exp.text
        assert not re.search(r"\b(true|false)\b", exp.text), exp.text
        assert exp.text == clf.explain([X[i]], target="correct")[0].text
    assert clf.target_ == "correct"
    # a target given still wins: the plain labels when asked for
    plain = clf.explain(X[:1], target="label")[0].text
    assert "repetition" not in plain
    assert re.search(r"\b(true|false)\b", plain), plain


def test_a_model_fitted_in_memory_has_no_target_and_its_words_are_unchanged(
    squats: tuple[list[PoseSequence], list[str]],
) -> None:
    """Fitted here, the classifier does not know what its labels are: ``target_`` is None and
    ``explain`` says what it said before (the labels as given)."""
    X, y = squats
    clf = CaseBaseClassifier(k=3, mirror=False).fit(X, y)
    assert clf.target_ is None
    assert clf.explain(X[:1])[0].text == clf.explain(X[:1], target="label")[0].text
    del clf.target_  # a model pickled before target_ was kept
    assert clf.explain(X[:1])[0].text == clf.explain(X[:1], target="label")[0].text
