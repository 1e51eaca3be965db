"""Degenerate but legal data (hunt 25b): what ``reps`` and the calibrated confidence made of
clips and training sets that are legal but lopsided. Each test says what happened before its
fix.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from features.poses import PoseSequence, save_pose
from posecbr.cli import main
from tests.bodies import squat_clip
from tests.test_cbr_clips import ACTIVITIES, arm_clip

# one squat of tests.bodies: 45 frames at 30 fps, standing at its first and last frame and
# deepest at frame 22 (its depth is 0.5 (1 - cos(2 pi i / 44)), largest at i = 22)
SQUAT_FRAMES, DEEPEST = 45, 22


def _squats_and_rests(tmp_path: Path, *parts: int | str) -> tuple[Path, list[int]]:
    """A pose file of ``parts`` in turn: an int is that many squats, ``"rest N"`` N frames
    of standing still (the squat's first frame held); and the frame of every squat's deepest
    point."""
    squat = squat_clip(1.0)
    pieces, deepest, at = [], [], 0
    for part in parts:
        if isinstance(part, int):
            pieces += [squat.positions] * part
            deepest += [at + i * SQUAT_FRAMES + DEEPEST for i in range(part)]
            at += part * SQUAT_FRAMES
        else:
            n = int(part.split()[1])
            pieces.append(np.repeat(squat.positions[:1], n, axis=0))
            at += n
    seq = replace(squat, positions=np.concatenate(pieces), source="")
    return save_pose(seq, tmp_path / "squats.npz"), deepest


@pytest.mark.parametrize(
    "parts",
    [
        (1, "rest 900"),  # one squat, then 30 s standing: was 0 repetitions
        ("rest 900", 1),  # 30 s standing, then one squat: was 0
        ("rest 600", 2, "rest 600"),  # was 3: far points in both rests, none at a squat
        (3, "rest 1000", 3),  # was 7: one more in the middle of the rest
        (1, "rest 1000", 1),  # was 3: at frame 0, mid-rest and the last frame
    ],
)
def test_reps_counts_the_squats_of_a_clip_that_mostly_stands_still(
    parts: tuple[int | str, ...], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip that stands still for most of its frames: the movement's line was read upside
    down (its 10th and 90th percentiles both lay in the rest, so neither end looked like the
    movement) and far points were found in the rest, or a long rest between repetitions,
    measured about the running mean, stood out as a far point of its own."""
    path, deepest = _squats_and_rests(tmp_path, *parts)
    assert main(["reps", str(path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["count"] == len(deepest)
    peaks = [r["peak_frame"] for r in doc["repetitions"]]
    assert np.abs(np.array(peaks) - np.array(deepest)).max() <= 2, (peaks, deepest)
    for r, peak in zip(doc["repetitions"], deepest, strict=True):
        assert r["start_frame"] < peak < r["end_frame"]


def _one_activity_per_person(n_per_person: int, seed: int) -> tuple[list[PoseSequence], list[str]]:
    """Three people, each of whom did one of the three arm movements only, ``n_per_person``
    times: activity ``i`` by subject ``p{i}``."""
    rng = np.random.default_rng(seed)
    X, y = [], []
    for i, activity in enumerate(ACTIVITIES):
        for _ in range(n_per_person):
            X.append(arm_clip(activity, rng).with_metadata(subject=f"p{i}"))
            y.append(activity)
    return X, y


@pytest.mark.parametrize("weighting", ["fisher", "none"])
def test_confidence_when_every_person_did_one_activity_only(weighting: str) -> None:
    """Each person did one activity. Held out by subject, no clip can be answered right
    (its activity leaves the case base with its person), so the calibration learned that
    answers are never right: every confidence was 1/14 = 0.07, for clips the classifier
    answers right at distance 0. Such clips now say nothing of how often an answer is right;
    with no subject's activity shared, the clips are held out by recording (each clip its own
    file), where all 12 are answered right (three well-apart movements): Platt's smoothed
    accuracy (12 + 1) / (12 + 2)."""
    X, y = _one_activity_per_person(4, seed=5)
    clf = CaseBaseClassifier(mirror="off", feature_weights=weighting, phases=0).fit(X, y)
    solved = clf.solve(X)
    assert [s.solution.label for s in solved] == y
    confidence = np.array([s.solution.confidence for s in solved])
    assert confidence == pytest.approx(13 / 14)
    assert clf.confidence_.basis != "leave-one-subject-out"
    assert clf.confidence_.n == 12 and clf.confidence_.accuracy == 1.0


def test_a_person_alone_in_an_activity_does_not_count_against_the_others() -> None:
    """Two people did all three activities and a third only one of them, plus a fourth
    activity (squats) no one else did: that person's squats could not be right held out, and
    counted as wrong answers, pulling every confidence down (held-out accuracy 20 of 22). The
    calibration now holds the 2 x 3 x 3 + 2 clips of activities another person did too, all
    answered right (three well-apart arm movements)."""
    rng = np.random.default_rng(9)
    X, y = [], []
    for person in ("p0", "p1"):
        for activity in ACTIVITIES:
            for _ in range(3):
                X.append(arm_clip(activity, rng).with_metadata(subject=person))
                y.append(activity)
    for depth in (0.8, 1.0):  # p2: squats, which no one else did, and two left arm raises
        X.append(replace(squat_clip(depth), source="").with_metadata(subject="p2"))
        y.append("squat")
        X.append(arm_clip(ACTIVITIES[0], rng).with_metadata(subject="p2"))
        y.append(ACTIVITIES[0])
    clf = CaseBaseClassifier(mirror="off", feature_weights="none", phases=0).fit(X, y)
    assert clf.confidence_.basis == "leave-one-subject-out"
    assert clf.confidence_.n == 20 and clf.confidence_.accuracy == 1.0


def test_train_notes_labels_that_differ_only_in_case_or_spacing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV naming one activity two ways ("deep_squat" for one subject, "Deep Squat"
    for another) trained two activities without a word; now a note names them (exit 0, the
    case base as asked: three activities)."""
    demo = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
    rows = ["path,label,subject"]
    for subject in ("s01", "s02"):
        for movement, label in (("m01", "deep_squat"), ("m07", "shoulder_abduction")):
            if subject == "s02" and movement == "m01":
                label = "Deep Squat"
            for clip in sorted(demo.glob(f"{movement}_{subject}_e0[1-3].npz")):
                rows.append(f"{clip},{label},{subject}")
    labels = tmp_path / "labels.csv"
    labels.write_text("\n".join(rows) + "\n")
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(labels), "--db", str(db), "--mirror", "off",
            "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    assert main(argv) == 0
    err = capsys.readouterr().err
    notes = [line for line in err.splitlines() if "differ only in case or spacing" in line]
    assert notes == [
        "note: 'Deep Squat' and 'deep_squat' differ only in case or spacing: they are 2 "
        "activities (one spelt two ways in the labels?)"
    ]
