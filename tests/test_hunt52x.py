"""``posecbr compare`` refuses what its arguments and the dataset's listing show before any
clip is decoded: labels of one class, a ``--target`` column the clips lack, a ``-k`` above
the training clips of the smallest fold (each refused once every clip was read before, in the
same words); and the reader of results.json refuses an accuracy per subject the clips
contradict. The compare tests count the calls of the real decoding function (called
through), as tests/test_hunt52o.py does."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import pytest

import features.datasets
from cbr.evaluation.results import (
    ClipInfo,
    CompareResults,
    CVSummary,
    DatasetSummary,
    MethodResult,
    Rate,
    Scores,
)
from features.errors import DataError
from features.poses import save_pose
from posecbr.cli import main
from tests.test_cbr_clips import ACTIVITIES, arm_dataset
from tests.test_hunt52o import _counted


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


def _doc() -> dict[str, Any]:
    """A results file of four clips, two per subject (a, b), one method under leave-one-
    subject-out that got a's second clip wrong: a 1 of 2 right (0.5), b 2 of 2 (1.0)."""
    clips = [ClipInfo(f"c{i}.npz", lab, subj, lab) for i, (lab, subj) in
             enumerate([("x", "a"), ("y", "a"), ("x", "b"), ("y", "b")])]  # fmt: skip
    scores = Scores(
        accuracy=0.75, accuracy_ci=(0.3, 0.95), macro_f1=0.73, macro_f1_ci=(0.3, 1.0),
        per_class={"x": Rate(2, 1.0, (0.3, 1.0)), "y": Rate(2, 0.5, (0.1, 0.9))},
        per_group={}, confusion=[[2, 0], [1, 1]], unassigned=[0, 0], fit_s=0.1,
        predict_s=0.1, predict_ms_per_clip=25.0, case_base_size=2.0, training_size=2.0,
        predictions=["x", "x", "x", "y"], correct=[True, False, True, True], fold_notes=[],
        per_subject={"a": Rate(2, 0.5, (0.1, 0.9)), "b": Rate(2, 1.0, (0.3, 1.0))},
    )  # fmt: skip
    results = CompareResults(
        created_utc="2026-12-07T23:00:00+00:00",
        machine={"python": "3.12", "platform": "linux", "cpu_count": 2},
        dataset=DatasetSummary("d", 4, ["a", "b"], ["x", "y"], {"x": 2, "y": 2}, ["x", "y"]),
        settings={"target": "label", "within": None},
        cv=CVSummary("loso", 2, [0, 0, 1, 1], "subjects"),
        notes=[],
        clips=clips,
        methods=[MethodResult("cbr m", "cbr", True, {}, "ok", "", scores)],
        best="cbr m",
        best_interpretable="cbr m",
    )
    return results.to_dict()


def _edit_per_subject(doc: dict[str, Any], how: str) -> str:
    """The accuracy per subject made to contradict the clips; the key named."""
    table = doc["methods"][0]["per_subject"]
    if how == "n":  # one clip moved to the other subject: the n still add up
        table["a"]["n"], table["b"]["n"] = 1, 3
        return "key 'methods[0].per_subject.a.n' must be the subject's 2 clips, got 1"
    if how == "sum":
        table["b"]["n"] = 3
        return "key 'methods[0].per_subject' counts 5 clips in all, not the results' 4"
    if how == "stranger":
        table["c"] = table.pop("b")
        return "key 'methods[0].per_subject.c' names no subject of the results' clips"
    table["a"]["accuracy"] = 1.0  # as b's: a's second clip was wrong
    return (
        "key 'methods[0].per_subject.a.accuracy' must be the share of the subject's clips"
        " correct (0.5), got 1"
    )


@pytest.mark.parametrize("how", ["n", "sum", "stranger", "accuracy"])
def test_results_refuse_an_accuracy_per_subject_the_clips_contradict(how: str) -> None:
    doc = _doc()
    CompareResults.from_dict(json.loads(json.dumps(doc)), "r.json")  # as written: read
    key = _edit_per_subject(doc, how)
    with pytest.raises(DataError) as e:
        CompareResults.from_dict(json.loads(json.dumps(doc)), "r.json")
    assert str(e.value) == f"r.json: {key}"
