"""A physical-therapy clinic's engineer new to posecbr (hunt 34e): UI-PRMD correct and
incorrect repetitions, the exercise videos cut into repetitions, and what each command's
output tells a therapist."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from features.poses import PoseSequence, load_pose, save_pose
from posecbr.cli import main
from tests.badinput import good_pose_file, refused, small_case_base
from tests.bodies import rot_z, rotate, standing, to_sequence


def test_classify_notes_clips_labelled_with_an_activity_the_case_base_lacks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip whose label the case base holds no case of (a new exercise, or a video
    labelled by its folder's name, as `extract videos/` labels `edge/`) is counted wrong
    whatever the answer: before, the summary said "accuracy: 0.000" and "[wrong: edge]" with
    nothing to tell the user that no answer could have been right."""
    db = small_case_base(tmp_path)
    capsys.readouterr()
    train = tmp_path / "train"
    known = sorted(p.name for p in train.iterdir())
    clip = sorted((train / known[0]).glob("*.npz"))[0]
    seq = load_pose(clip)
    odd = save_pose(seq.with_metadata(label="edge"), tmp_path / "odd.npz")
    same = save_pose(seq.with_metadata(label=known[0]), tmp_path / "same.npz")
    assert main(["classify", str(odd), str(same), "--db", str(db), "-q"]) == 0
    out, err = capsys.readouterr()
    assert "accuracy: 50.0 % (1/2 labelled clips)" in out
    notes = [line for line in err.splitlines() if "has no case of" in line]
    assert notes == [
        "note: case base 'default' has no case of 'edge' (1 clip): that clip cannot be "
        f"answered right and counts as wrong (its activities: {', '.join(known)})"
    ], err
    # clips of the case base's own activities alone: no note
    assert main(["classify", str(same), "--db", str(db), "-q"]) == 0
    assert "has no case of" not in capsys.readouterr().err
    # --json keeps standard output for the document
    assert main(["classify", str(odd), "--db", str(db), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["summary"]["accuracy"] == 0.0
    assert "has no case of 'edge'" in err


def test_a_sideways_position_is_said_the_way_it_points() -> None:
    """UI-PRMD deep squat m01_s01_e02_inc against a case base of s02 and s03: its right knee
    lies 0.31 torso lengths to the right of the starting mid-hip (worked out by hand from the
    pose file: -0.313 along the level left line of the hips over the first tenth, over the
    median neck-to-mid-hip length), which the explanation said as "right knee to the left
    -0.31 torso lengths (its cases: -0.35–-0.24)"; and a sit-to-stand's knees coming
    together as "left knee to the right -0.15 torso lengths (correct ones: -0.33–-0.26)".
    Now each reads the way the values point, the lowest of a value turned round its highest;
    values on both sides of the mid-hip keep the words as computed."""
    from cbr.explain import Claim, _change_text, _claim_text

    def claim(words: str, here: float | None, low: float, high: float) -> Claim:
        return Claim("why", "c", "f", words, here, "torso lengths", low=low, high=high)

    assert (
        _claim_text(claim("right knee to the left", -0.3126, -0.35, -0.24), "its cases")
        == "right knee to the right 0.31 torso lengths (its cases: 0.24–0.35)"
    )
    assert (
        _claim_text(claim("left knee to the right", -0.15, -0.33, -0.26), "correct ones")
        == "left knee to the left 0.15 torso lengths (correct ones: 0.26–0.33)"
    )
    assert (
        _claim_text(claim("right knee to the left (lowest)", -0.51, -0.74, -0.40), "its cases")
        == "right knee to the right (highest) 0.51 torso lengths (its cases: 0.40–0.74)"
    )
    assert (
        _claim_text(claim("left wrist to the left (middle third)", -0.2, -0.3, -0.1), "its cases")
        == "left wrist to the right (middle third) 0.20 torso lengths (its cases: 0.10–0.30)"
    )
    # either side of the mid-hip, a height, a variation: as computed
    assert (
        _claim_text(claim("right knee to the left", -0.05, -0.1, 0.02), "its cases")
        == "right knee to the left -0.05 torso lengths (its cases: -0.10 to 0.02)"
    )
    assert (
        _claim_text(claim("left wrist height", -0.5, -0.6, -0.4), "its cases")
        == "left wrist height -0.50 torso lengths (its cases: -0.60 to -0.40)"
    )
    change = Claim("change", "c", "f", "right knee to the left", -0.43, "torso lengths", -0.15)
    assert _change_text(change) == "right knee to the right 0.43 → 0.15 torso lengths"
    from cbr.explain import _difference_text  # the verbose "Differs from it most in"

    difference = {"feature": "right foot index to the left", "here": -0.60, "there": -0.38,
                  "unit": "torso lengths"}  # fmt: skip
    assert (
        _difference_text(difference)
        == "right foot index to the right 0.60 torso lengths here, 0.38 there"
    )


def _arm_raises(top_deg: float, frames: int = 45) -> PoseSequence:
    """Both arms raised sideways to ``top_deg`` and lowered once (a sin-squared bump)."""
    arm = tuple(f"{side}_{j}" for side in ("left", "right") for j in _ARM)
    body = standing()
    out = []
    for a in top_deg * np.sin(np.pi * np.arange(frames) / (frames - 1)) ** 2:
        left = rotate(body, arm[:5], rot_z(-a), body["left_shoulder"])
        out.append(rotate(left, arm[5:], rot_z(a), body["right_shoulder"]))
    return to_sequence(*out, fps=30.0)


_ARM = ("elbow", "wrist", "pinky", "index", "thumb")


@pytest.mark.parametrize("crossed", [True, False])
def test_train_notes_a_case_base_no_better_than_a_guess(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], crossed: bool
) -> None:
    """Two people whose "correct" and "incorrect" repetitions are each other's (s1's correct
    raise is 40 degrees, s2's 90; crossed): every training clip held out by person is
    answered wrong, so the case base tells nothing; before, `train` printed its cases and
    nothing else (UI-PRMD's sit to stand of s01 and s03: 7 of 16 held-out clips right, and
    `classify` then answered "an incorrect repetition, confidence 0.00"). Labelled alike
    for both people (not crossed), no note."""
    rows = ["path,label,subject,correct"]
    for subject, (good, bad) in (
        ("s1", (40.0, 90.0)),
        ("s2", (90.0, 40.0) if crossed else (40.0, 90.0)),
    ):
        for i in range(4):
            for truth, top in (("true", good), ("false", bad)):
                name = f"{subject}_{truth}_{i}.npz"
                # s2's a degree higher: no clip a copy of s1's (train refuses copies)
                save_pose(_arm_raises(top + 2.0 * i + (subject == "s2")), tmp_path / name)
                rows.append(f"{name},raise,{subject},{truth}")
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(tmp_path / "labels.csv"), "--db", str(db), "--target", "correct"]
    assert main([*argv, "--json"]) == 0
    out, err = capsys.readouterr()
    learned = json.loads(out)["learned"]
    assert learned["confidence_calibrated_on"] == 16
    notes = [line for line in err.splitlines() if "no better than" in line]
    if not crossed:
        assert notes == []
        assert learned["held_out_accuracy"] == 1.0
        return
    assert notes == [
        "note: held out in turn, the training clips were answered right 0 % of the time "
        "(0 of 16), no better than always answering a correct repetition (50 %): this case "
        "base does not tell its classes apart (more people, or clips of one movement per "
        "case base, may)"
    ]
    assert learned["held_out_accuracy"] == 0.0


def _raises(top_deg: float, times: int) -> PoseSequence:
    """``times`` arm raises to ``top_deg``, 0.5 s of standing before, between and after."""
    rest = _arm_raises(0.0, 15)
    one = _arm_raises(top_deg)
    parts = [rest.positions] + [np.concatenate([one.positions, rest.positions])] * times
    return PoseSequence(np.concatenate(parts), one.joint_names, one.fps)


def raises_case_base(tmp_path: Path) -> Path:
    """A case base of repetitions, ``train --split repetitions`` of four clips of two arm
    raises each: "high" (90 degrees) and "low" (40), by two subjects (s2 5 degrees higher)."""
    rows = ["path,label,subject"]
    for subject in ("s1", "s2"):
        for label, top in (("high", 90.0), ("low", 40.0)):
            name = f"{subject}_{label}.npz"
            save_pose(_raises(top + (5.0 if subject == "s2" else 0.0), 2), tmp_path / name)
            rows.append(f"{name},{label},{subject}")
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(tmp_path / "labels.csv"), "--db", str(db), "--split", "repetitions"]
    assert main(argv) == 0
    return db


def test_classify_notes_clips_of_several_repetitions_against_a_case_base_of_one_each(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case base trained with --split repetitions holds one repetition per case; a video
    of three squats classified against it got one answer for the three with nothing said
    (the README's note covered case bases of windows only). Now a note names the clip and
    its count, and says how to classify each repetition."""
    db = raises_case_base(tmp_path)
    assert "cut 4 clips into 8 repetitions" in capsys.readouterr().err
    three = save_pose(_raises(85.0, 3), tmp_path / "three.npz")
    one = save_pose(_raises(85.0, 1), tmp_path / "one.npz")
    assert main(["classify", str(three), str(one), "--db", str(db), "-q"]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "per repetition" in line]
    assert notes == [
        "note: case base 'default' holds a case per repetition and 1 clip holds several "
        "(three.npz: 3): each gets one answer here; to classify each repetition, add --split "
        "repetitions (or give them as rows path,label,start,end of a labels CSV, a label may be "
        "left empty; posecbr reps CLIP --json: each one's start_frame and end_frame)"
    ]
    assert main(["classify", str(one), "--db", str(db), "-q"]) == 0
    assert "per repetition" not in capsys.readouterr().err


def test_a_mistyped_target_column_gets_a_guess(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`--target corect` (UI-PRMD's column is `correct`) listed the columns alone; now the
    column meant is guessed, in train, compare and classify."""
    data = tmp_path / "data"
    for subject in ("s1", "s2"):
        for truth in (True, False):
            for i in range(2):
                good_pose_file(data / f"{subject}_{truth}_{i}.npz", frames=40, label="squat",
                               subject=subject, correct=truth)  # fmt: skip
    line = refused(["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--target",
                    "corect"], tmp_path, capsys, "no value for --target 'corect'")  # fmt: skip
    assert line.endswith("(did you mean 'correct'?)"), line
    line = refused(["compare", str(data), "--target", "corect", "--no-dad", "--peers", "none"],
                   tmp_path, capsys, "no value for target 'corect'")  # fmt: skip
    assert line.endswith("(did you mean 'correct'?)"), line
    db = small_case_base(tmp_path / "cb")
    capsys.readouterr()
    clip = good_pose_file(tmp_path / "clip.npz", frames=40, label="squat")
    line = refused(["classify", str(clip), "--db", str(db), "--target", "lable"], tmp_path,
                   capsys, "case base 'default' predicts 'label'")  # fmt: skip
    assert line.endswith("(did you mean 'label'?)"), line
    # nothing close: the columns alone, as before
    line = refused(["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--target",
                    "grade"], tmp_path, capsys, "no value for --target 'grade'")  # fmt: skip
    assert "did you mean" not in line
