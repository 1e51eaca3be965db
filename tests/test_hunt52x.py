"""``posecbr compare`` refuses what its arguments and the dataset's listing show before any
clip is decoded: labels of one class, a ``--target`` column the clips lack, a ``-k`` above
the training clips of the smallest fold (each refused once every clip was read before, in the
same words). The tests count the calls of the real decoding function (called
through), as tests/test_hunt52o.py does."""

from __future__ import annotations

import csv
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import features.datasets
from features.poses import save_pose
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
def arm_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Six synthetic arm clips (each of the three movements twice) as pose files listed by a
    labels CSV: path, label, subject (s0 for the 1st, 3rd, 5th; s1 for the others), side."""
    folder = tmp_path_factory.mktemp("arms")
    X, y = arm_dataset(2, seed=7)
    with open(folder / "labels.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["path", "label", "subject", "side"])
        for i, (x, label) in enumerate(zip(X, y, strict=True)):
            save_pose(x, folder / f"c{i}.npz")
            w.writerow([f"c{i}.npz", label, f"s{i % 2}", "left"])
    return folder


@pytest.mark.parametrize(
    ("args", "problem"),
    [
        # the two clips of one movement: one class
        (
            ["--labels", ACTIVITIES[1]],
            f"need at least two classes of 'label' with two or more clips each; found"
            f" {{{ACTIVITIES[1]!r}: 2}}",
        ),
        # made_from: the source each clip had when saved, read back as a pose file's
        (
            ["--target", "nosuch"],
            "6 of 6 clips have no value for target 'nosuch' (e.g. c0.npz); columns available:"
            " label, made_from, side, subject",
        ),
        # leave one subject out: either fold trains on the other subject's 3 clips
        (["-k", "4"], None),
    ],
)
def test_compare_refuses_before_any_clip_is_decoded(
    arm_folder: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    problem: str | None,
) -> None:
    data = arm_folder / "labels.csv"
    decoded = _counted(monkeypatch, features.datasets, "load_clip")
    monkeypatch.setenv("POSECBR_NO_PROGRESS", "1")
    assert main(["compare", str(data), *args]) == 1
    said = (
        f"{data}: {problem}"
        if problem
        else "--k: must be at most 3, the training clips of the smallest fold, got 4 (5 unless"
        " given): give --k 3 or less"
    )
    assert capsys.readouterr().err == f"posecbr compare: error: {said}\n"
    assert decoded == []


def test_compare_refuses_loso_of_one_subject_before_any_clip_is_decoded(
    arm_folder: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    data = arm_folder / "labels.csv"
    decoded = _counted(monkeypatch, features.datasets, "load_clip")
    monkeypatch.setenv("POSECBR_NO_PROGRESS", "1")
    assert main(["compare", str(data), "--subjects", "s1", "--cv", "loso"]) == 1
    err = capsys.readouterr().err
    assert err.startswith(
        f"posecbr compare: error: --cv: leave-one-subject-out is impossible in {data}: only one"
        " subject (s1);"
    )
    assert decoded == []
