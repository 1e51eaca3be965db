"""Python callers read the argument's name, the commands their option (hunt 47a).

``cbr.segmentation.check_k`` (behind ``segment``, ``solve_recording`` and ``LiveSegmenter``)
named the option ``-k`` and ``cbr.unknown.judge_of`` the option ``--unknown`` to a Python
caller, who gave neither.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.live import LiveSegmenter
from cbr.segmentation import segment, solve_recording
from cbr.training import store_fitted
from cbr.unknown import JUDGES, judge_of
from features.errors import ConfigError
from features.poses import PoseSequence, save_pose
from posecbr.cli import main
from tests.badinput import refused

K_WORDS = "must be from 1 to the case base's k (3, the nearest cases a window retrieves)"


def test_a_python_caller_reads_k_not_the_commands_option(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
) -> None:
    """``segment``, ``solve_recording`` and ``LiveSegmenter`` given k = 4 by a classifier of
    k = 3 name their argument ``k``. Before: "-k: must be from 1 to ...", the commands'
    option, which a Python caller never typed."""
    clf, rec, _ = arm_k3
    held_out = judge_of(clf, "held-out")
    calls = [
        lambda: segment(clf, rec, judge=held_out, k=4),
        lambda: solve_recording(clf, rec, k=4),
        lambda: LiveSegmenter(clf, 30.0, judge=held_out, k=4),
    ]
    for call in calls:
        with pytest.raises(ValueError) as raised:
            call()
        assert str(raised.value).startswith(f"k: {K_WORDS}, a whole number, got 4")
        assert isinstance(raised.value, ConfigError) and raised.value.source == "k"


def test_segment_refuses_a_k_before_it_calibrates_the_default_judge(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
) -> None:
    """``segment(clf, rec, k=4)`` with no judge, on a classifier of k = 3 whose case base the
    default judge cannot be calibrated on (one clip per activity): the k is refused, as with a
    judge given. Before: the case base was, "no activity has cases apart from each other",
    after calibrating on it, and the bad k went unsaid."""
    clf, rec, _ = arm_k3
    with pytest.raises(ValueError, match=f"^k: {re.escape(K_WORDS)}"):
        segment(clf, rec, k=4)


def test_a_python_caller_reads_the_judges_argument_not_the_commands_option(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
) -> None:
    """``judge_of(clf, "nope")``: refused naming its argument ``name``, a ValueError (a bad
    argument's, as every other of the Python calls) and a ConfigError. Before: a ConfigError
    alone, "--unknown: unknown judge 'nope'"."""
    clf, _, _ = arm_k3
    with pytest.raises(ValueError) as raised:
        judge_of(clf, "nope")
    assert str(raised.value) == f"name: unknown judge 'nope': one of {', '.join(JUDGES)}"
    assert isinstance(raised.value, ConfigError)


def test_the_commands_still_say_their_options(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``segment`` and ``watch`` with -k 4 on a case base of k = 3 say "-k: must be from 1
    ...", in one line, before any recording or stream is read; an unknown --unknown is
    refused by the option's own choices, naming it."""
    clf, rec, labels = arm_k3
    db = tmp_path / "arms.db"
    store_fitted(db, "arms", clf, labels)
    pose = tmp_path / "rec.npz"
    save_pose(rec, pose)
    for argv in (["segment", str(pose)], ["watch", "0"]):
        refused([*argv, "--db", str(db), "-k", "4"], tmp_path, capsys, f"-k: {K_WORDS}")
        with pytest.raises(SystemExit) as exited:
            main([*argv, "--db", str(db), "--unknown", "nope"])
        assert exited.value.code == 2
        err = capsys.readouterr().err
        assert "argument --unknown: invalid choice: 'nope'" in err, err
