"""A Python caller reads the argument's name, the command its option; no message says its
name twice (hunt 48e).

``CompareSettings``, ``cbr.classification``'s feedback checks, ``features.cluster`` and
``cbr.unknown.false_unknown_threshold`` refused a Python caller naming the commands' options
(``--folds``, ``--feedback``, ``--scheduler``, ``--unknown``), which that caller never typed;
the commands still say their options. Refusals naming an argument repeated it ("folds: folds
must be at least 2", "chunk_frames: chunk_frames must be ...", "k: k must be ..."). Plain
``train`` of a new case base stored two copies of one clip, which ``train --append`` refuses.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.classification import FeedbackSettings, check_feedback_label
from cbr.estimator import CaseBaseClassifier
from cbr.evaluation.settings import CompareSettings
from cbr.segmentation import segment
from cbr.training import store_fitted
from cbr.unknown import false_unknown_threshold, judge_of
from features.cluster import check_scheduler
from features.errors import PosecbrError
from features.poses import PoseSequence, save_pose
from posecbr.cli import main
from tests.badinput import ROOT, refused
from tests.test_cbr_clips import arm_dataset

DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


def python_refusal(call: Any) -> str:
    """What ``call()`` is refused with: a ValueError (a Python caller's bad argument) that is
    one of posecbr's errors (one line for the command)."""
    with pytest.raises(ValueError) as raised:
        call()
    assert isinstance(raised.value, PosecbrError)
    return str(raised.value)


@pytest.mark.parametrize(
    ("kwargs", "said"),
    [
        ({"folds": 1}, "folds: must be at least 2, got 1"),
        ({"k": 0}, "k: must be a positive integer, got 0"),
        ({"trim": 1.5}, "trim: must be in (0, 1], got 1.5"),
        ({"jobs": 0}, "jobs: must be at least 1, got 0"),
        ({"explain": -1}, "explain: must be 0 or more, got -1"),
        ({"seed": -1}, "seed: must be in 0 to 2**32 - 1, got -1"),
        ({"peer_length": 3}, "peer_length: must be at least 9 frames, got 3"),
        ({"cv": "x"}, "cv: must be one of loso, kfold, got 'x'"),
        ({"features": ()}, "features: no feature level given"),
        ({"peers": ("dtw-knn", "dtw-knn")}, "peers: peer 'dtw-knn' given twice"),
    ],
)
def test_compare_settings_name_their_fields(kwargs: dict[str, Any], said: str) -> None:
    """Before: "--folds: folds must be at least 2, got 1", "--cv: cv must be one of ...",
    "peer_length: peer_length must be ...": the command's option, or the name twice."""
    assert python_refusal(lambda: CompareSettings(**kwargs)) == said


def test_compare_settings_name_cbr_params_and_jobs() -> None:
    line = python_refusal(lambda: CompareSettings(cbr_params={"bogus": 1}))
    assert line.startswith("cbr_params: unknown case-base parameter(s) bogus (known: "), line
    line = python_refusal(lambda: CompareSettings(jobs=2, scheduler="local:2"))
    assert line.startswith("jobs: goes with worker processes of this machine"), line


@pytest.mark.parametrize(
    ("options", "said"),
    [
        (["--cv", "kfold", "--folds", "1"], "--folds: must be at least 2, got 1"),
        (["--explain", "-1"], "--explain: must be 0 or more, got -1"),
        (["--seed", "-1"], "--seed: must be in 0 to 2**32 - 1, got -1"),
        (["--peers", "dtw-knn,dtw-knn"], "--peers: peer 'dtw-knn' given twice"),
        (["--param", "bogus=1"], "--param: unknown case-base parameter(s) bogus"),
        (["--param", "states=x"], "--param: states: must be one of "),
        (["--scheduler", "local:0"], "--scheduler: local:N needs a whole number of workers"),
    ],
)
def test_compare_still_says_its_options(
    options: list[str], said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    refused(["compare", str(DEMO), *options], tmp_path, capsys, f"posecbr compare: error: {said}")


def test_the_feedback_checks_name_their_arguments() -> None:
    """Before: "--feedback: the feedback label is empty", "--novelty: the novelty threshold
    must be ...", "--benefit: ..."."""
    assert python_refusal(lambda: check_feedback_label(" ", ["reach"], False)) == (
        "label: the feedback label is empty"
    )
    line = python_refusal(lambda: check_feedback_label("rech", ["reach"], False))
    assert line.startswith("label: 'rech' is not an activity of this case base"), line
    assert python_refusal(lambda: FeedbackSettings(novelty_threshold=-1.0)) == (
        "novelty_threshold: must be a number >= 0, got -1.0"
    )
    assert python_refusal(lambda: FeedbackSettings(benefit_threshold=2.0)) == (
        "benefit_threshold: must be in [0, 1], got 2.0"
    )


def test_classify_still_says_feedback(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    clf, rec, labels = arm_k3
    db = tmp_path / "arms.db"
    store_fitted(db, "arms", clf, labels)
    pose = tmp_path / "clip.npz"
    save_pose(PoseSequence(rec.positions[:60], rec.joint_names, 30.0), pose)
    argv = ["classify", str(pose), "--db", str(db)]
    refused([*argv, "--feedback", "nope"], tmp_path, capsys,
            "--feedback: 'nope' is not an activity of this case base")  # fmt: skip
    refused([*argv, "--feedback", labels[0], "--benefit", "2"], tmp_path, capsys,
            "--benefit: must be in [0, 1], got 2.0")  # fmt: skip


def test_a_scheduler_is_named_as_the_argument_and_as_the_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``check_scheduler("local:0")`` said "--scheduler: ..." to a Python caller."""
    words = "local:N needs a whole number of workers >= 1, got 'local:0'"
    assert python_refusal(lambda: check_scheduler("local:0")) == f"scheduler: {words}"
    labels = DEMO / "labels.csv"
    for argv in (
        ["train", str(labels), "--db", str(tmp_path / "cb.sqlite")],
        ["extract", str(DEMO), "--out", str(tmp_path / "out")],
    ):
        refused([*argv, "--scheduler", "local:0"], tmp_path, capsys, f"--scheduler: {words}")


def test_a_false_unknown_rate_is_named_as_the_argument() -> None:
    """No command gives the rate (``--unknown`` names a judge): before, "--unknown: ..."."""
    known = np.array([1.0, 2.0, 3.0])
    assert python_refusal(lambda: false_unknown_threshold(known, 1.0)) == (
        "rate: the false-unknown rate must be in [0, 1), got 1.0"
    )


def test_no_refusal_says_its_argument_twice(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
) -> None:
    """Before: "chunk_frames: chunk_frames must be None ...", "k: k must be ...", "judge:
    judge must be ...", "y: y is None ...", the name the line starts with said again."""
    clf, rec, _ = arm_k3
    lines = [
        python_refusal(lambda: segment(clf, rec, judge=judge_of(clf, "held-out"), chunk_frames=-1)),
        python_refusal(lambda: CaseBaseClassifier(k=0).fit([rec], ["a"])),
        python_refusal(lambda: segment(clf, rec, judge="held-out")),  # type: ignore[arg-type]
    ]
    assert lines[0] == "chunk_frames: must be None or a whole number >= 0, got -1"
    assert lines[1] == "k: must be a positive integer, got 0"
    assert lines[2].startswith("judge: must be None or a judge of cbr.unknown"), lines[2]


# ------------------------------------------------------------- train: two copies of one clip

#: train's options of tests/badinput.py's small case base (nothing learned that needs many)
QUICK = ["--mirror", "off", "--feature-weights", "none", "--phases", "0"]


def _arm_folders(root: Path) -> list[Path]:
    """Two arm clips of each of three activities in ``root/<activity>/``, each its own
    random movement; the files, in the order of the class folders."""
    X, y = arm_dataset(2, seed=5)
    names = {str(a): f"act{i}" for i, a in enumerate(dict.fromkeys(str(v) for v in y))}
    for i, (seq, label) in enumerate(zip(X, y, strict=True)):
        save_pose(seq, root / names[str(label)] / f"clip{i:02d}.npz")
    return sorted(root.rglob("*.npz"))


@pytest.mark.parametrize("folder", ["act1", "act0"])
def test_train_refuses_two_copies_of_one_clip_naming_both(
    folder: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip of act0 copied byte for byte into act1's folder (one clip labelled two
    activities) or into act0's own (a case voting twice): plain ``train`` of a new case base
    refused neither, and stored 7 cases, as ``train --append`` refuses them. Now refused
    naming both files, nothing written."""
    data = tmp_path / "data"
    first = _arm_folders(data)[0]  # act0/clip00.npz
    copy = data / folder / "copy.npz"
    copy.write_bytes(first.read_bytes())
    why = (
        "one clip labelled both 'act0' and 'act1'"
        if folder == "act1"
        else "its case would vote twice"
    )
    # the clips in the order of their folders and names: act0/clip00.npz before the copy
    frames = f"frames 0-{load_frames(first) - 1}"
    refused(
        ["train", str(data), "--db", str(tmp_path / "cb.sqlite"), *QUICK],
        tmp_path,
        capsys,
        f"posecbr train: error: training set: {copy} {frames} has the same frames and"
        f" poses as {first} {frames} (a copy of its file?): {why}; nothing stored",
    )


def load_frames(path: Path) -> int:
    """How many frames the pose file ``path`` holds."""
    from features.poses import load_pose

    return load_pose(path).n_frames


def test_train_keeps_a_clip_that_differs_from_another_by_a_few_centimetres(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Not every likeness is refused: the copy with its left shoulder 2 cm higher in every
    frame is another clip, trained (7 cases)."""
    from dataclasses import replace

    from features.poses import load_pose

    data = tmp_path / "data"
    first = _arm_folders(data)[0]
    seq = load_pose(first)
    moved = seq.positions.copy()
    moved[:, 11, 1] += 0.02
    save_pose(replace(seq, positions=moved), data / "act1" / "moved.npz")
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(data), "--db", str(db), *QUICK]) == 0, capsys.readouterr().err
    assert "7 cases (7 trained)" in capsys.readouterr().out


def test_copies_are_told_by_their_poses_not_by_features_alike(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
) -> None:
    """Two takes whose features agree (a few states, or QMP vectors: arm_4 and arm_7 of
    tests/test_hunt43i.py under four states) are no copies; the same poses under another
    name at the same frames are, at other frames not (a recording repeating itself)."""
    from dataclasses import replace

    from cbr.described import DescribedClip, poses_digest
    from cbr.training import copies_within

    _, rec, _ = arm_k3
    a, b = (PoseSequence(rec.positions[k : k + 30], rec.joint_names, 30.0) for k in (0, 30))
    assert poses_digest(a) != poses_digest(b)

    def described(seq: PoseSequence, source: str, frames: tuple[int, int]) -> DescribedClip:
        values = np.zeros(4)  # described alike, whatever the poses
        return DescribedClip(values, None, None, np.ones(4, dtype=bool), 1.0, source, None,
                             frames, "blazepose33", poses=poses_digest(seq))  # fmt: skip

    one, other = described(a, "a.npz", (0, 30)), described(b, "b.npz", (0, 30))
    copy = described(a, "copy.npz", (0, 30))
    assert copies_within([one, other]) is None
    assert copies_within([one, other, copy]) == (0, 2)
    assert copies_within([one, replace(copy, frames=(30, 60))]) is None
    assert copies_within([one, replace(copy, poses="")]) is None  # made by hand: not known
