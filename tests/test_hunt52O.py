"""A user's mistake that the arguments alone show is refused before the work, not after it:
``CaseBaseClassifier.fit``'s and ``cbr.training.train``'s bad labels before any clip is
described, ``posecbr train``'s one activity and a pose file that is no archive before the first
clip's features, ``classify --feedback``'s unknown label before the clips are read. Each test
counts the calls of the work the refusal must come before (the real function, called through):
the refusal and its words are the ones the user met after the work."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import cbr.estimator
import cbr.training
from cbr.estimator import CaseBaseClassifier
from cbr.training import train
from features.errors import InputError
from features.poses import PoseSequence
from tests.test_cbr_clips import arm_dataset


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
