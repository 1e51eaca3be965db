"""A user's mistake that the arguments alone show is refused before the work, not after it:
``CaseBaseClassifier.fit``'s and ``cbr.training.train``'s bad labels before any clip is
described, ``posecbr train``'s one activity and a pose file that is no archive before the first
clip's features, ``classify --feedback``'s unknown label before the clips are read. Each test
counts the calls of the work the refusal must come before (the real function, called through):
the refusal and its words are the ones the user met after the work."""

from __future__ import annotations

import csv
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import cbr.estimator
import cbr.training
import posecbr.commands.classify
from cbr.estimator import CaseBaseClassifier
from cbr.training import store_fitted, train
from features.errors import InputError
from features.poses import PoseSequence, save_pose
from posecbr.cli import main
from tests.test_cbr_clips import ACTIVITIES, arm_dataset


def _counted(monkeypatch: pytest.MonkeyPatch, module: Any, name: str) -> list[int]:
    """``module.name`` replaced by the same function that also counts its calls."""
    real: Callable[..., Any] = getattr(module, name)
    calls: list[int] = []

    def counting(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, counting)
    return calls


@pytest.fixture(scope="module")
def arms() -> tuple[list[PoseSequence], list[str]]:
    """One clip of each synthetic arm movement, twice (six clips), and their labels."""
    X, y = arm_dataset(2, seed=7)
    return X, [str(v) for v in y]


def _nobody(seq: PoseSequence) -> PoseSequence:
    return PoseSequence(np.full_like(seq.positions, np.nan), seq.joint_names, seq.fps)


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ("one short", r"^y: 6 clips but y has shape \(5,\)$"),
        ("a column", r"^y: 6 clips but y has shape \(6, 1\)$"),
        ("None", r"^y: y\[0\] is None: every clip needs a label$"),
        ("NaN", r"^y: y\[5\] is nan: every clip needs a label$"),
        ("empty", r"^y: y\[2\] is ' ': every clip needs a label$"),
        ("one activity", r"^y: the training set has only one activity \('a'\); a classifier"),
        ("nobody", r"^X: 1 training clip shows no person \(no frame with a torso\): X\[4\]$"),
    ],
)
def test_fit_refuses_bad_labels_and_a_clip_of_nobody_before_any_clip_is_described(
    arms: tuple[list[PoseSequence], list[str]],
    monkeypatch: pytest.MonkeyPatch,
    bad: str,
    message: str,
) -> None:
    """The labels (and a clip without anyone in it) were checked once every clip's features
    were computed: seconds to minutes of work for a refusal the arguments alone give."""
    X, y = arms
    labels: Any = {
        "one short": y[:-1],
        "a column": np.array(y, dtype=object)[:, None],
        "None": [None, *y[1:]],
        "NaN": [*y[:-1], float("nan")],
        "empty": [*y[:2], " ", *y[3:]],
        "one activity": ["a"] * len(y),
        "nobody": y,
    }[bad]
    clips = [*X[:4], _nobody(X[4]), X[5]] if bad == "nobody" else X
    described = _counted(monkeypatch, cbr.estimator, "describe_clips")
    with pytest.raises(InputError, match=message):
        CaseBaseClassifier(k=1).fit(clips, labels)
    assert described == []


def test_train_refuses_one_activity_before_any_clip_is_described(
    arms: tuple[list[PoseSequence], list[str]], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    X, _ = arms
    described = _counted(monkeypatch, cbr.training, "describe")
    db = tmp_path / "cb.sqlite"
    with pytest.raises(InputError, match=r"^labels: the training set has only one activity \('a'"):
        train(db, "arms", X, ["a"] * len(X), CaseBaseClassifier(k=1))
    assert described == [] and not db.exists()


@pytest.fixture
def arm_folder(arms: tuple[list[PoseSequence], list[str]], tmp_path: Path) -> Path:
    """The six arm clips as pose files listed by a labels CSV (path, label, subject)."""
    X, y = arms
    with open(tmp_path / "labels.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["path", "label", "subject"])
        for i, (x, label) in enumerate(zip(X, y, strict=True)):
            save_pose(x, tmp_path / f"c{i}.npz")
            w.writerow([f"c{i}.npz", label, f"s{i % 2}"])
    return tmp_path


def test_train_refuses_one_activity_of_a_labels_csv_before_the_features(
    arm_folder: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--labels`` of one activity (``--target`` left out): refused once every clip's
    features were computed."""
    described = _counted(monkeypatch, cbr.training, "describe_entries")
    db = arm_folder / "cb.sqlite"
    data = arm_folder / "labels.csv"
    assert main(["train", str(data), "--db", str(db), "--labels", ACTIVITIES[1]]) == 1
    err = capsys.readouterr().err
    assert err == (
        f"posecbr train: error: {data}: the training data hold only one activity"
        f" ({ACTIVITIES[1]!r}); a classifier needs at least two\n"
    )
    assert described == [] and not db.exists()


def test_train_refuses_a_pose_file_that_is_no_archive_before_the_first_clip(
    arm_folder: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A truncated pose file listed last was found once the five before it were described."""
    bad = arm_folder / "c5.npz"
    bad.write_bytes(bad.read_bytes()[:100])
    described = _counted(monkeypatch, cbr.training, "describe_entry")
    db = arm_folder / "cb.sqlite"
    assert main(["train", str(arm_folder / "labels.csv"), "--db", str(db)]) == 1
    assert capsys.readouterr().err == (
        f"posecbr train: error: {bad}: cannot read pose file: not an .npz archive (truncated, or"
        " another format?)\n"
    )
    assert described == [] and not db.exists()


def test_classify_refuses_an_unknown_feedback_label_before_the_clips_are_read(
    arms: tuple[list[PoseSequence], list[str]],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A typo in ``--feedback`` was refused once every clip was read (a video's poses
    estimated: minutes); the case base is left as it was."""
    X, y = arms
    db = tmp_path / "cb.sqlite"
    clf = CaseBaseClassifier(k=1, mirror=False, feature_weights="none").fit(X, y)  # fast
    store_fitted(db, "arms", clf, y)
    before = db.read_bytes()
    save_pose(X[0], tmp_path / "new.npz")
    read = _counted(monkeypatch, posecbr.commands.classify, "load_inputs")
    argv = ["classify", str(tmp_path / "new.npz"), "--db", str(db), "--feedback", "lunge"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.startswith("posecbr classify: error: --feedback: 'lunge' is not an activity of")
    assert read == [] and db.read_bytes() == before
