"""Hunt 36b: ``classify`` says when its confidence is the vote share, not calibrated (a case
base with nothing to hold out); the summary's ``unlike_cases`` name the pieces of a file,
not the file; the one repetition of a slow lunge runs down and up again, not the half
second of a pose model's left-right flicker."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from features.datasets import Clip
from features.poses import PoseSequence, save_pose
from features.repetitions import count_repetitions, split_repetitions
from posecbr.cli import main
from tests.bodies import rot_x, rotate, squat_clip, standing, to_sequence

UNCALIBRATED = "(the vote share, not calibrated)"


def _squats(depth: float, n: int, seed: int, source: str) -> PoseSequence:
    """``n`` squats of about ``depth`` one after the other (45-55 frames each, 30 fps)."""
    rng = np.random.default_rng(seed)
    clips = [squat_clip(depth + rng.uniform(-0.05, 0.05), int(rng.integers(45, 55)))
             for _ in range(n)]  # fmt: skip
    positions = np.concatenate([c.positions for c in clips])
    return PoseSequence(positions, clips[0].joint_names, 30.0, source=source)


def _json(args: list[str], capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    capsys.readouterr()
    assert main([*args, "--json"]) == 0
    return dict(json.loads(capsys.readouterr().out))


def _share(result: dict[str, Any]) -> float:
    """The answer's share of the vote worked out from the neighbours listed: each retrieved
    case votes 1/distance (the README's vote; no case here lies at distance 0)."""
    votes = {n["label"]: 0.0 for n in result["neighbours"]}
    for n in result["neighbours"]:
        votes[n["label"]] += 1.0 / n["distance"]
    return votes[result["label"]] / sum(votes.values())


# on one xdist worker: the module's one_recording_each, three_people made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt36b")


@pytest.fixture(scope="module")
def one_recording_each(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A case base of two activities, each one recording of three squats (deep, shallow), no
    subjects: held out by recording, each clip is of an activity the rest lacks, so nothing
    calibrates the confidence (``train``'s note). And a new recording of deep squats."""
    root = tmp_path_factory.mktemp("one_each")
    for label, depth, seed in (("deep_squat", 0.95, 1), ("shallow_squat", 0.5, 2)):
        (root / "train" / label).mkdir(parents=True)
        save_pose(_squats(depth, 3, seed, label), root / "train" / label / f"{label}.npz")
    clip = root / "deep_new.npz"
    save_pose(_squats(0.93, 1, 3, "deep_new"), clip)
    db = root / "cb.sqlite"
    assert main(["train", str(root / "train"), "--db", str(db)]) == 0
    return db, clip


@pytest.fixture(scope="module")
def three_people(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same two activities, one clip each of three people (a labels CSV with subjects):
    held out by person, the confidence is calibrated."""
    root = tmp_path_factory.mktemp("three")
    rows = []
    for s, subject in enumerate(("s1", "s2", "s3")):
        for label, depth in (("deep_squat", 0.95), ("shallow_squat", 0.5)):
            name = f"{subject}_{label}.npz"
            save_pose(_squats(depth, 1, 10 + 2 * s + (label == "deep_squat"), name), root / name)
            rows.append({"path": name, "label": label, "subject": subject})
    with (root / "labels.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["path", "label", "subject"])
        w.writeheader()
        w.writerows(rows)
    db = root / "cb.sqlite"
    assert main(["train", str(root / "labels.csv"), "--db", str(db)]) == 0
    return db


def test_an_uncalibrated_confidence_says_it_is_the_vote_share(
    one_recording_each: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One recording per activity: ``classify`` printed "deep_squat, confidence 0.50" (the
    raw share; 1.00 when every neighbour agrees) as if it were the calibrated probability;
    now the line says it is the vote share, and ``--json`` carries
    ``confidence_calibrated: false`` for the clip and the summary. The confidence itself
    is the vote share worked out from the neighbours."""
    db, clip = one_recording_each
    doc = _json(["classify", str(clip), "--db", str(db)], capsys)
    (r,) = doc["results"]
    assert r["label"] == "deep_squat"
    assert r["confidence_calibrated"] is False
    assert r["confidence"] == pytest.approx(_share(r), abs=1e-9)
    assert r["confidence"] == pytest.approx(r["vote_share"], abs=1e-12)
    assert (
        r["text"]
        .splitlines()[0]
        .startswith(f"deep_squat, confidence {r['confidence']:.2f} {UNCALIBRATED}")
    )
    assert doc["summary"]["confidence_calibrated"] is False
    capsys.readouterr()
    assert main(["classify", str(clip), "--db", str(db), "--verbose"]) == 0
    out = capsys.readouterr().out
    assert f": deep_squat, confidence {r['confidence']:.2f} {UNCALIBRATED}" in out
    assert "the confidence is the vote share, not calibrated" in out  # as before
    # labelled: the summary's mean confidence says so too
    labelled = tmp_path / "labels.csv"
    labelled.write_text(f"path,label\n{clip},deep_squat\n")
    capsys.readouterr()
    assert main(["classify", str(labelled), "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert re.search(r"\nmean confidence: \d\.\d{3} \(vote shares, not calibrated\)\n", out), out


def test_a_calibrated_confidence_reads_as_before(
    three_people: Path, one_recording_each: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """Three people: the confidence is calibrated (not the raw share), ``true`` in the JSON,
    and the line reads as before."""
    _, clip = one_recording_each
    doc = _json(["classify", str(clip), "--db", str(three_people)], capsys)
    (r,) = doc["results"]
    assert r["confidence_calibrated"] is True and doc["summary"]["confidence_calibrated"] is True
    assert r["confidence"] != pytest.approx(r["vote_share"], abs=1e-6)
    assert "not calibrated" not in r["text"]
    assert re.match(r"\w+, confidence \d\.\d\d(;|\n|$)", r["text"]), r["text"]


def test_unlike_cases_name_the_pieces_of_a_file(
    one_recording_each: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two pieces of one file, rows ``path,label,start,end`` of a labels CSV, both flagged
    (recorded with a skeleton none of the cases has): the summary listed the file twice,
    ``["kinect.npz", "kinect.npz"]``; now each piece as its own entry names it (``clip``,
    ``start_frame``, ``end_frame``); the wrong and unclassifiable lists alike."""
    db, _ = one_recording_each
    seq = _squats(0.95, 2, 5, "kinect")
    f = tmp_path / "kinect.npz"
    save_pose(seq.with_metadata(source_skeleton="uiprmd_kinect"), f)
    half = seq.n_frames // 2
    csv_path = tmp_path / "pieces.csv"
    csv_path.write_text(
        "path,label,start,end\n"
        f"{f},deep_squat,0,{half}\n{f},shallow_squat,{half},{seq.n_frames}\n{f},deep_squat,0,1\n"
    )
    doc = _json(["classify", str(csv_path), "--db", str(db)], capsys)
    assert [r["unlike_reason"] for r in doc["results"][:2]] == ["sensor", "sensor"]
    pieces = [(0, half), (half, seq.n_frames)]
    want = [{"clip": str(f), "frames": [a, b], "start_frame": a, "end_frame": b}
            for a, b in pieces]  # fmt: skip
    s = doc["summary"]
    assert s["unlike_cases"] == want
    # the one-frame piece is unclassifiable, named as a piece too
    assert s["unclassifiable"] == [
        {"clip": str(f), "frames": [0, 1], "start_frame": 0, "end_frame": 1}
    ]
    for w in s["wrong"]:  # as before: the piece's frames beside the labels
        assert (w["start_frame"], w["end_frame"]) in pieces and w["clip"] == str(f)
    # a whole file: its name alone
    whole = _json(["classify", str(f), "--db", str(db)], capsys)["summary"]
    assert whole["unlike_cases"] == [{"clip": str(f)}]


FPS = 30.0
LEG = ("knee", "ankle", "heel", "foot_index")


def _lunge(depth: float) -> dict[str, np.ndarray]:
    """A split-stance lunge ``depth`` of the way down (0: standing): the left thigh 80
    degrees forward and the left shin back under it (front knee at 100 degrees), the right
    thigh 20 degrees back and the right knee bent 80 degrees."""
    b = standing()
    out = rotate(b, tuple(f"left_{j}" for j in LEG), rot_x(80 * depth), b["left_hip"])
    out = rotate(out, tuple(f"left_{j}" for j in LEG[1:]), rot_x(-80 * depth), out["left_knee"])
    out = rotate(out, tuple(f"right_{j}" for j in LEG), rot_x(-20 * depth), b["right_hip"])
    return rotate(out, tuple(f"right_{j}" for j in LEG[1:]), rot_x(-80 * depth), out["right_knee"])


def _swapped(body: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The legs as a pose model swaps them in a side view: each leg joint takes the other
    leg's height and depth (the sides' widths kept)."""
    out = dict(body)
    for j in LEG:
        left, right = body[f"left_{j}"], body[f"right_{j}"]
        out[f"left_{j}"] = np.array([left[0], right[1], right[2]])
        out[f"right_{j}"] = np.array([right[0], left[1], left[2]])
    return out


def _ease(a: float, b: float, s: float) -> np.ndarray:
    return a + (b - a) * 0.5 * (1 - np.cos(np.linspace(0.0, np.pi, int(round(s * FPS)))))


def _slow_lunge(flicker: int) -> PoseSequence:
    """The bundled reverse-lunge video's course, built by hand (30 fps): half way down at the
    start, down by 1.0 s, held down to 3.5 s, up by 5.5 s, standing to 7.0 s, then 40 % of
    the way down again as the clip ends (8.5 s). From 0.9 to 1.7 s the legs are swapped in
    runs of ``flicker`` frames every other run (0: never), as the pose model swapped them
    in the video."""
    depth = np.concatenate([_ease(0.5, 1.0, 1.0), np.ones(int(2.5 * FPS)), _ease(1.0, 0.0, 2.0),
                            np.zeros(int(1.5 * FPS)), _ease(0.0, 0.4, 1.5)])  # fmt: skip
    frames = [_lunge(d) for d in depth]
    a, b = int(0.9 * FPS), int(1.7 * FPS)
    for f in range(a, b) if flicker else ():
        if (f - a) // flicker % 2 == 0:
            frames[f] = _swapped(frames[f])
    return to_sequence(*frames, fps=FPS)


@pytest.mark.parametrize("flicker", [0, 2, 3, 4])
def test_the_one_slow_lunge_runs_down_and_up_again(flicker: int) -> None:
    """One slow lunge (down by 1.0 s, held to 3.5 s, up by 5.5 s): one repetition from the
    clip's start to near the end of the way up, 4.8-5.5 s (where the line comes within a
    tenth of the way of standing), its far point in the hold, and the case that ``train
    --split repetitions`` stores is that stretch. With the legs swapped back and forth at
    0.9-1.7 s, a period of under a second was read from the flicker and cut the repetition
    to it: 2.53-2.57 s (runs of 4 frames), 1.63-3.47 s (2), 1.77-3.27 s (3)."""
    seq = _slow_lunge(flicker)
    (rep,) = count_repetitions(seq).repetitions
    assert rep.start_frame <= 1.0 * FPS, rep
    assert 4.8 * FPS <= rep.end_frame <= 5.5 * FPS, rep
    assert 1.0 * FPS <= rep.peak_frame <= 3.5 * FPS, rep
    split = split_repetitions([Clip(seq, "lunge", None)])
    (case,) = split.clips
    assert split.kept_whole == 0 and case.seq.n_frames == rep.end_frame - rep.start_frame


def test_the_bundled_slow_lunge_video_is_one_repetition_down_and_up(
    lunge_poses: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The bundled reverse lunge (counted by hand, tests/fixtures/repetition_counts.json:
    one slow lunge, lowest 1.5-3.6 s): ``reps`` gave 1 repetition of 0.80-1.32 s, the
    half second in which the pose model swapped her legs, and ``train --split
    repetitions`` stored that as the lunge's case. Now it holds her lowest stretch and the
    way up (by eye: rising at 5.0 s, upright from about 6 s, lowering again after 8 s).
    ``reps`` of the video's poses as extract finds them (the session's): what ``reps`` of
    the video gives (the same --json but for the path, checked), without the pose model."""
    poses = save_pose(lunge_poses, tmp_path / "fit_reverse_lunge_pexels8233047.npz")
    doc = _json(["reps", str(poses)], capsys)
    (rep,) = doc["repetitions"]
    assert rep["start_s"] <= 1.5 and 5.0 <= rep["end_s"] <= 8.0, rep


def test_holding_out_two_ways_in_one_scan_gives_each_way_alone() -> None:
    """The calibration's two passes for one recording per activity (by recording; by piece,
    overlapping pieces with it) from one scan of the cases per query: each the same as
    :func:`held_out` of that way alone. Six cases on a line (the windows of
    test_calibration_soft): x = 0, 0.1, 0.2 (overlapping windows), 1.0, 1.1 of A, 5.0 of B."""
    from cbr.calibration import HoldOut, held_out, held_out_ways
    from cbr.casebase import CaseBase
    from cbr.problem import FeatureConfig
    from cbr.similarity import Euclidean

    xs = [0.0, 0.1, 0.2, 1.0, 1.1, 5.0]
    spans = [(0, 240), (60, 300), (120, 360), (600, 840), (900, 1140), (1200, 1440)]
    p = np.array([[x, 0.0] for x in xs])
    labels = np.array(["A"] * 5 + ["B"], dtype=object)
    cb = CaseBase(FeatureConfig(), Euclidean(exact=True), p, labels, ("x", "y"), ("x", "y"),
                  frames=tuple(spans))  # fmt: skip
    frames = np.array(spans)
    recording = HoldOut(np.array(["a"] * 6, dtype=object)[:4],
                        np.array(["a"] * 5 + ["b"], dtype=object))  # fmt: skip
    piece = HoldOut(np.arange(4).astype(object), np.arange(6).astype(object), (frames[:4], frames))
    both = held_out_ways(cb, p[:4], labels[:4], [recording, piece], k=2)
    for way, got in zip((recording, piece), both, strict=True):
        alone = held_out(cb, p[:4], labels[:4], way.groups, way.case_groups, k=2,
                         frames=way.frames)  # fmt: skip
        for field in ("nearest", "share", "right", "answer", "distances", "codes", "truth"):
            np.testing.assert_array_equal(getattr(got, field), getattr(alone, field))
    # worked out by hand: by recording, every A is held out and B (5.0) is nearest; by
    # piece, 0, 0.1 and 0.2 overlap each other and keep 1.0 nearest; 1.0 keeps 1.1
    np.testing.assert_allclose(both[0].nearest, [5.0, 4.9, 4.8, 4.0])
    np.testing.assert_allclose(both[1].nearest, [1.0, 0.9, 0.8, 0.1])
    assert both[0].truth.tolist() == [-1] * 4 and both[1].right.tolist() == [True] * 4
