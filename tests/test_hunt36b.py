"""Hunt 36b: ``classify`` says when its confidence is the vote share, not calibrated (a case
base with nothing to hold out); the summary's ``unlike_cases`` name the pieces of a file,
not the file."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from features.poses import PoseSequence, save_pose
from posecbr.cli import main
from tests.bodies import squat_clip

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
