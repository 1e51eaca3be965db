"""The units every command prints (hunt 34b): an accuracy, share or rate is a percentage for
people ("75.0 %", as `compare`'s table and the explanations give it), a fraction 0-1 in
``--json``; a confidence stays a number 0-1 labelled "confidence". Before, `classify` said
"accuracy: 0.750", `casebase info` "their accuracy 0.907" beside "94.5%", `casebase trim`
"accuracy 1.000 -> 0.875", DAD "78%" without the space every other percentage has."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest


def test_percent_is_one_way_of_writing_a_share() -> None:
    from features.text import percent

    assert percent(3 / 4) == "75.0 %"
    assert percent(1.0) == "100.0 %"
    assert percent(0.02, 0) == "2 %"
    assert percent(1 - 0.055) == "94.5 %"
    assert percent(None) == "n/a" and percent(math.nan) == "n/a"


def test_classify_summary_gives_the_accuracy_as_a_percentage(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """3 of 4 labelled clips right: 75.0 %, as compare's table would say (it said 0.750)."""
    from posecbr.commands.classify import _print_summary

    summary: dict[str, Any] = {
        "target": "label",
        "clips": 4,
        "classified": 4,
        "labelled": 4,
        "right": 3,
        "accuracy": 0.75,
        "expected_accuracy": 0.8125,
        "recall": {"a": {"right": 2, "clips": 2}, "b": {"right": 1, "clips": 2}},
        "wrong": [{"clip": "d.npz", "label": "a", "true_label": "b"}],
        "unlike_cases": [],
        "unclassifiable": [],
        "answers": {"a": 3, "b": 1},
    }
    _print_summary(summary, "label", [])
    out = capsys.readouterr().out
    assert "accuracy: 75.0 % (3/4 labelled clips)" in out
    assert "mean confidence: 0.812" in out  # a confidence: 0-1, labelled so
    assert "0.750" not in out


def test_casebase_info_gives_every_share_as_a_percentage(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The calibration's accuracy 0.9 (36 of 40 held-out training clips) read "their
    accuracy 0.900" two lines below "99.5% of ... lie within": now 90.0 % and 99.5 %."""
    from posecbr.commands.casebase import _print_model

    model = {
        "unlike_cases": {
            "unlike_ratio": 1.72,
            "quantile": 0.995,
            "basis": "leave-one-subject-out",
            "features": {"unlike_ratio": 1.0},
            "combined": {"threshold": 0.055, "budget": 0.02},
        },
        "confidence": {
            "neighbours": 10,
            "temperature": 0.08,
            "n": 40,
            "basis": "nested leave-one-subject-out",
            "accuracy": 36 / 40,
        },
    }
    _print_model(model, 3)
    out = capsys.readouterr().out
    assert "(99.5 % of leave-one-subject-out training clips lie within)" in out
    assert "less usual than 94.5 % of held-out clips'" in out
    assert "2 % of held-out clips flagged" in out
    assert "training clips (their accuracy 90.0 %)" in out


def test_trim_gives_the_accuracies_as_percentages() -> None:
    """18 of 20 cases right before, 7 of 8 after: "accuracy 90.0 % -> 87.5 %"."""
    from cbr.maintenance import MaintenanceReport

    report = MaintenanceReport("ICF", 20, 8, 18 / 20, 7 / 8, np.arange(8), None)  # type: ignore[arg-type]
    assert report.summary().startswith("ICF: 20 -> 8 cases, accuracy 90.0 % -> 87.5 %")


def test_dad_ranking_writes_its_percentages_as_every_command_does() -> None:
    """2 of 3 weight in order is 67 %, with the space the other commands' percentages have
    (it printed " 67%"); an activity too little observed to score keeps its dash."""
    from cbr.dad import DADConfig
    from cbr.dad.outcome import ActivityScore, DADResult
    from posecbr.commands.dad import _text_lines

    acts = (
        ActivityScore("a", "a words", ("a",), 1.0, 3, 3, ()),
        ActivityScore("d", "d words", ("d",), 2 / 3, 3, 3, ()),
        ActivityScore("e", "e words", ("e",), math.nan, 1, 3, ()),
    )
    result = DADResult("x.npz", "ok", "", 30.0, 10.0, ((0.0, 4.0),), ((),), acts)
    args = argparse.Namespace(posefile=Path("x.npz"), top=1)
    lines = list(_text_lines(args, result, DADConfig()))
    assert lines[1] == "best match: a words (100 % of its QMPs in order)"
    assert "   1. 100 %  a words  [a]" in lines
    assert "   2.  67 %  d words  [d]" in lines
    assert "   3.    -   e words  [e]" in lines
    assert acts[1].in_words().startswith("d words (67 % of its QMPs in order)")


def test_dad_and_describe_name_the_clip_clip_as_classify_and_reps_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`classify` and `reps` name the clip they read `clip`; `dad` and `describe` said only
    `source`. Both now say `clip` too, keeping `source`; every document strict JSON."""
    from features.poses import save_pose
    from posecbr.cli import main
    from tests.moves import clip
    from tests.test_json_hunt import strict

    path = save_pose(clip("squat", 2.0), tmp_path / "squat.npz")
    docs = {}
    for command in ("dad", "describe", "reps"):
        assert main([command, str(path), "--json"]) == 0
        docs[command] = strict(capsys.readouterr().out)
    for command, doc in docs.items():
        assert doc["clip"] == str(path), command
    assert docs["dad"]["source"] == docs["describe"]["source"] == str(path)


def test_describe_says_its_figures_are_confidences(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`describe` printed "torso upright 0.97" with no word of what 0.97 is, where classify
    says "confidence 0.59": its header now says so, once."""
    from features.poses import save_pose
    from posecbr.cli import main
    from tests.moves import clip

    path = save_pose(clip("squat", 2.0), tmp_path / "squat.npz")
    assert main(["describe", str(path)]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert head == f"{path}: 60 frames at 30 fps (2.0 s); each state with its confidence, 0-1"


def test_reps_and_segment_escape_the_file_name_as_describe_and_dad_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A pose file named with an ANSI escape: `describe` and `dad` print it as ``\\x1b``,
    `reps` and `segment` printed the escape itself, which recolours the terminal."""
    from features.poses import save_pose
    from posecbr.cli import main
    from tests.badinput import small_case_base
    from tests.moves import clip

    db = small_case_base(tmp_path)
    path = save_pose(clip("squat", 4.0), tmp_path / "a\x1b[31mred.npz")
    capsys.readouterr()  # what train printed
    for command in (["reps", str(path)], ["segment", str(path), "--db", str(db)]):
        assert main(command) == 0
        out = capsys.readouterr().out
        assert "\x1b" not in out, command
        assert out.startswith(f"{tmp_path}/a\\x1b[31mred.npz: "), command


def test_compare_results_name_the_clip_and_its_truth_as_classify_does() -> None:
    """`compare`'s results named a clip `id` in `clips` and `clip` in `explanations`, and
    the value a clip is checked against `true` where classify says `true_label`: both names
    now, the old ones kept (posecbr report reads either)."""
    from cbr.evaluation.results import ClipInfo, ExplainedClip

    clip = ClipInfo("a.npz", "squat", "s01", "squat").to_dict()
    assert clip["clip"] == clip["id"] == "a.npz"
    wrong = ExplainedClip("a.npz", "s01", "squat", "squat", "lunge", "dad", "why").to_dict()
    assert wrong["true_label"] == wrong["true"] == "squat"
    assert wrong["clip"] == "a.npz" and wrong["predicted"] == "lunge"
