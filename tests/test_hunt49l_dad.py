"""Session 49, helper L: ``compare``'s explanations of DAD's errors when DAD scored no class,
a ``--param`` the comparison sets itself, and ``report``'s pictures named but not there."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from cbr.evaluation.compare import run_compare
from cbr.evaluation.misclassified import explain_dad_errors
from cbr.evaluation.settings import CompareSettings
from features.datasets import Clip
from features.errors import ParameterError
from features.poses import JOINT_INDEX, PoseSequence
from posecbr.cli import main
from tests.moves import clip


def _without_knees(seq: PoseSequence) -> PoseSequence:
    pos = seq.positions.copy()
    pos[:, [JOINT_INDEX["left_knee"], JOINT_INDEX["right_knee"]]] = np.nan
    return PoseSequence(pos, seq.joint_names, seq.fps, source="squat without knees")


def test_dad_answering_its_first_class_for_want_of_any_score_is_not_said_to_choose_it() -> None:
    """A squat whose knees are missing throughout leaves the ADD's squat too little observable,
    and "abduction" is no ADD activity: no class gets a score and DADClassifier answers its
    first class (sorted: "abduction"). Before, the explanation read "DAD chose abduction.",
    an activity DAD cannot recognise (the notes say so)."""
    squat = _without_knees(clip("squat", seconds=2.0))
    raise_arm = clip("arm_abduction", seconds=2.0)
    clips = [Clip(squat, "squat", "a"), Clip(raise_arm, "abduction", "a")] * 2
    plain = {"mirror": "off", "feature_weights": "off", "phases": "off"}  # no inner choice
    settings = CompareSettings(
        similarities=("euclidean",),
        features=("fluents",),
        peers=(),
        k=1,
        cbr_params=plain,
        explain=0,
        bootstrap=100,
    )
    run = run_compare(clips, settings, fold_indices=np.array([0, 0, 1, 1]))
    dad = run.results.method("dad").scores
    assert dad is not None and dad.predictions[0] == "abduction"
    texts = [e.text for e in explain_dad_errors(run, 5) if e.true == "squat"]
    assert texts and texts[0].startswith("DAD scored no activity standing for a class compared"), (
        texts
    )
    assert texts[0].split("\n")[0].endswith(", so it answered the first class, abduction.")
    assert "too little observable" in texts[0]  # the true activity says why it scored nothing


def test_a_param_compare_sets_itself_names_the_option_that_sets_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--param k=3`` (or ``similarity=dtw``, ``features=qmp``, ``trim=0.5``), each a
    CaseBaseClassifier parameter, was "unknown case-base parameter(s) k (known: angles, ...)":
    the comparison sets those per configuration, from its own options."""
    for param, option, value in (
        ("k=3", "--k", "3"),
        ("similarity=dtw", "--similarities", "dtw"),
        ("features=qmp", "--features", "qmp"),
        ("trim=0.5", "--trim", "0.5"),
    ):
        key = param.split("=")[0]
        assert main(["compare", str(tmp_path / "absent"), "--param", param]) == 1
        assert capsys.readouterr().err == (
            f"posecbr compare: error: --param: {key} is set for every case-base configuration"
            f" by {option} (give {option} {value}), not by a parameter\n"
        )
    with pytest.raises(ParameterError) as caught:
        CompareSettings(cbr_params={"k": 3})
    assert caught.value.source == "cbr_params"
    assert str(caught.value).startswith(
        "cbr_params: k is set for every case-base configuration by `k`"
    )
    assert list(tmp_path.iterdir()) == []


def test_report_says_which_pictures_the_results_name_are_not_there(
    swapped_compare: tuple[Path, Path, dict[str, str]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A picture ``results.json`` names that its folder lacks (deleted, or the results file
    copied alone) was left out of the page without a word; the accuracy picture and the
    confusion matrices are drawn again from the results, the others cannot be."""
    folder = tmp_path / "results"
    shutil.copytree(swapped_compare[1], folder)
    doc = json.loads((folder / "results.json").read_text())
    lost = doc["pictures"]["prevalence"]
    (folder / lost).unlink()
    page = tmp_path / "report.html"
    assert main(["report", str(folder), "--out", str(page)]) == 0
    line = (
        f"{lost}: named in {folder / 'results.json'} but not in its folder (moved or deleted?):"
        " the report is without it"
    )
    assert capsys.readouterr().err == f"note: {line}\nreport written to {page}\n"
    html = page.read_text()
    assert f"<li class='note'>{line}</li>" in html
    assert html.count("<img ") == len(doc["pictures"]["confusion"]) + 1 + len(
        doc["pictures"]["timelines"]
    )  # the accuracy, confusion and timeline pictures, not the prevalence
