"""Hunt 42h: long recordings used as a new user would.

An activity every piece of which ``train`` skips (it shows no person, or is too short) gets
no case: ``train`` named only the skipped pieces, and the activity was missing from the case
base without a word."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from features.poses import PoseSequence, save_pose
from features.readers.asfamc import read_asf_amc
from posecbr.cli import main

NAMES = "1 JumpJack\n2 Jog\n3 Squat\n4 KneeRaise\n6 Twist\n"


# on one xdist worker: the module's away made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt42h")


@pytest.fixture(scope="module")
def away(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """CMU 13_30 with its first labelled stretch, JumpJack (18 blocks of 0.1 s: frames
    0-215, read off the label file), blanked as if the person were out of view; its label
    file and the codes' names."""
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    codes = labels.read_text().split()
    first = next(i for i, c in enumerate(codes) if c != codes[0])
    assert (codes[0], first) == ("1", 18)  # JumpJack for 1.8 s, then Twist
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    positions = seq.positions.copy()
    positions[: 12 * first] = np.nan  # 120 fps: 12 frames a block
    folder = tmp_path_factory.mktemp("away")
    rec = save_pose(PoseSequence(positions, seq.joint_names, seq.fps), folder / "away.npz")
    names = folder / "names.txt"
    names.write_text(NAMES, encoding="utf-8")
    return rec, labels, names


def _stored_labels(db: Path) -> set[str]:
    from casebase_store import open_store

    store = open_store(db, create=False, readonly=True)
    try:
        return {str(v) for v in store.load_cases("default").labels}
    finally:
        store.close()


def test_train_names_an_activity_left_without_a_case(
    away: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec, labels, names = away
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(rec), "--frame-labels", str(labels), "--label-block", "0.1",
            "--label-names", str(names), "--db", str(db)]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out.splitlines()
    assert (
        "no case of the activity 'JumpJack': every piece of it was skipped, as said above" in out
    ), out
    # the line says what the case base holds: the four other labelled activities
    assert _stored_labels(db) == {"Twist", "KneeRaise", "Squat", "Jog"}


def test_train_json_lists_the_activities_left_without_a_case(
    away: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec, labels, names = away
    argv = ["train", str(rec), "--frame-labels", str(labels), "--label-block", "0.1",
            "--label-names", str(names), "--db", str(tmp_path / "cb.sqlite"), "--json"]  # fmt: skip
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["no_case"] == ["JumpJack"]
    assert "JumpJack" not in doc["labels"]


def test_append_names_an_activity_left_without_a_case(
    away: tuple[Path, Path, Path],
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The same recording, its left wrist 1 cm further right (not a copy of the stored stretches:
    tests/test_hunt46f.py), appended to a case base of it unblanked (13_30 whole): JumpJack
    adds nothing, and --append says so as train does."""
    import dataclasses

    from features.poses import load_pose

    blanked, labels, names = away
    seq = load_pose(blanked)
    moved = seq.positions.copy()
    moved[:, 15, 0] += 0.01  # the left wrist (the mocap has no nose)
    rec = save_pose(dataclasses.replace(seq, positions=moved), tmp_path / "away.npz")
    whole = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    first = save_pose(whole, tmp_path / "13_30.npz")
    db = tmp_path / "cb.sqlite"
    common = ["--frame-labels", str(labels), "--label-block", "0.1", "--label-names",
              str(names), "--db", str(db)]  # fmt: skip
    assert main(["train", str(first), *common]) == 0
    capsys.readouterr()
    assert main(["train", str(rec), *common, "--append"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert (
        "no case of the activity 'JumpJack': every piece of it was skipped, as said above" in out
    ), out


def test_an_activity_with_a_case_left_is_not_named(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """13_30 unblanked: every activity has cases; no such line."""
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    names = tmp_path / "names.txt"
    names.write_text(NAMES, encoding="utf-8")
    whole = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    rec = save_pose(whole, tmp_path / "13_30.npz")
    argv = ["train", str(rec), "--frame-labels", str(labels), "--label-block", "0.1",
            "--label-names", str(names), "--db", str(tmp_path / "cb.sqlite"), "--json"]  # fmt: skip
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    assert "no_case" not in doc
    assert set(doc["labels"]) == {"JumpJack", "Twist", "KneeRaise", "Squat", "Jog"}
