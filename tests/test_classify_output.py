"""What ``posecbr classify`` prints for people: four lines per clip, target values as words,
a closing summary (--quiet: alone), --verbose, the flag in --json, a pose file named as passed
with its video as provenance."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from features.poses import load_pose, save_pose
from posecbr.cli import main
from tests.bodies import squat_clip
from tests.once import made_once

KINDS = {"deep": (0.9, 1.0, "true"), "shallow": (0.45, 0.55, "false")}


def _write(root: Path, subjects: tuple[str, ...], per: int, seed: int) -> Path:
    """Squats as pose files and a labels CSV with a label and a ``correct`` column (deep
    squats are the correct repetitions)."""
    rng = np.random.default_rng(seed)
    rows = []
    root.mkdir(parents=True, exist_ok=True)
    for subject in subjects:
        for kind, (lo, hi, correct) in KINDS.items():
            for i in range(per):
                name = f"{subject}_{kind}_{i}.npz"
                clip = squat_clip(rng.uniform(lo, hi), int(rng.integers(40, 60)),
                                  rng.uniform(30, 50), rng.uniform(0, 20), name)  # fmt: skip
                save_pose(clip, root / name)
                rows.append({"path": name, "label": f"{kind} squat", "subject": subject,
                             "correct": correct})  # fmt: skip
    with (root / "labels.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["path", "label", "subject", "correct"])
        w.writeheader()
        w.writerows(rows)
    return root / "labels.csv"


def _data_and_stores(base: Path) -> tuple[tuple[Path, Path], dict[str, str]]:
    train, test = (
        _write(base / "train", ("s1", "s2", "s3"), 3, 1),
        _write(base / "test", ("s9",), 2, 2),
    )
    label, correct = str(base / "label.sqlite"), str(base / "correct.sqlite")
    assert main(["train", str(train), "--db", label]) == 0
    assert main(["train", str(train), "--db", correct, "--target", "correct"]) == 0
    return (train, test), {"label": label, "correct": correct}


@pytest.fixture(scope="module")
def data_and_stores(
    tmp_path_factory: pytest.TempPathFactory,
) -> tuple[tuple[Path, Path], dict[str, str]]:
    """The training and test folders and the two case bases trained on the first, made once
    in the session (not once in each worker): the tests only read them."""
    return made_once(tmp_path_factory, "classify-output", _data_and_stores)


@pytest.fixture(scope="module")
def data(data_and_stores: tuple[tuple[Path, Path], dict[str, str]]) -> tuple[Path, Path]:
    return data_and_stores[0]


@pytest.fixture(scope="module")
def stores(data_and_stores: tuple[tuple[Path, Path], dict[str, str]]) -> dict[str, str]:
    return data_and_stores[1]


def test_four_lines_per_clip_and_a_summary(
    data: tuple[Path, Path], stores: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    _, test = data
    assert main(["classify", str(test), "--db", stores["label"]]) == 0
    out = capsys.readouterr().out
    body, _, summary = out.partition("\n\n")
    heads = [i for i, line in enumerate(body.splitlines()) if not line.startswith("  ")]
    assert len(heads) == 4  # four clips, each a head line and at most three more
    ends = [*heads[1:], len(body.splitlines())]
    assert all(b - a <= 4 for a, b in zip(heads, ends, strict=True))
    assert summary.startswith("4 clips: 4 classified; 0 unlike the stored cases.")
    # a percentage, as compare's table gives it (it was a fraction, "0.750")
    accuracy = re.search(r"accuracy: (\d+\.\d) % \((\d+)/4 labelled clips\)", summary)
    assert accuracy is not None, summary
    right = out.count("  [right]")
    assert int(accuracy.group(2)) == right
    assert accuracy.group(1) == {0: "0.0", 1: "25.0", 2: "50.0", 3: "75.0", 4: "100.0"}[right]
    assert "recall per class: deep squat " in summary and "; shallow squat " in summary
    assert summary.count("\nwrong: ") == 4 - right


def test_quiet_prints_the_summary_alone_and_verbose_everything(
    data: tuple[Path, Path], stores: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    _, test = data
    assert main(["classify", str(test), "--db", stores["label"], "--quiet"]) == 0
    quiet = capsys.readouterr().out
    assert quiet.lstrip().startswith("4 clips: 4 classified") and "Why:" not in quiet
    assert main(["classify", str(test), "--db", stores["label"], "--verbose", "--top", "2"]) == 0
    verbose = capsys.readouterr().out
    assert "Vote: " in verbose and "Counterfactual (" in verbose
    clips = re.split(r"^(?=\S)", verbose.split("\n\n")[0], flags=re.M)
    clips = [c for c in clips if c.strip()]
    assert len(clips) == 4  # each clip's similar cases: the two nearest of its five
    assert all(len(re.findall(r"^ +case #\d+ ", c, re.M)) == 2 for c in clips)
    assert main(["classify", str(test), "--db", stores["label"], "--quiet", "--verbose"]) == 1
    assert "--quiet: excludes --verbose" in capsys.readouterr().err


def test_a_repetition_check_reads_its_target_as_words(
    data: tuple[Path, Path], stores: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    _, test = data
    assert main(["classify", str(test), "--db", stores["correct"]]) == 0
    out = capsys.readouterr().out
    heads = [line for line in out.splitlines() if line.endswith(("[right]", "]"))]
    assert heads and all(
        re.search(r": an? (in)?correct repetition, confidence [01]\.\d\d", h) for h in heads
    )
    assert ": true" not in out and ": false" not in out
    # what the shallow ones did differently leads their explanation
    shallow = out[out.index("s9_shallow_0.npz") :].splitlines()
    assert shallow[1].startswith("  Done differently from correct repetitions: ")
    assert "recall per class: an incorrect repetition" in out or "incorrect repetition" in out


def test_json_gives_the_flag_beside_the_distance_ratio(
    data: tuple[Path, Path], stores: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    _, test = data
    assert main(["classify", str(test), "--db", stores["label"], "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    for r in doc["results"]:
        assert isinstance(r["unlike_cases"], bool) and r["unlike_cases"] is False
        assert r["novelty"] > 0 and r["unlike_reason"] is None
        assert 0.0 <= r["confidence"] <= 1.0 and 0.0 <= r["vote_share"] <= 1.0
        assert len(r["text"].splitlines()) <= 4 and len(r["text"]) <= 400
    assert doc["summary"]["clips"] == 4 and doc["summary"]["unlike_cases"] == []


def test_a_clip_of_another_sensor_is_unlike_the_stored_cases(
    data: tuple[Path, Path], stores: dict[str, str], tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    _, test = data
    seq = load_pose(test.parent / "s9_deep_0.npz")
    other = tmp_path / "kinect.npz"
    save_pose(seq.with_metadata(source_skeleton="uiprmd_kinect"), other)
    assert main(["classify", str(other), "--db", stores["label"], "--json"]) == 0
    r = json.loads(capsys.readouterr().out)["results"][0]
    assert r["unlike_cases"] is True and r["unlike_reason"] == "sensor"
    assert main(["classify", str(other), "--db", stores["label"]]) == 0
    out = capsys.readouterr().out
    assert "unlike the stored cases (recorded with a skeleton none of them has)" in out
    assert "1 unlike the stored cases." in out


def test_a_pose_file_made_from_a_video_is_named_as_passed(
    stores: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    made = tmp_path / "from_video.npz"
    # what posecbr extract writes: the video it came from as the sequence's source
    save_pose(squat_clip(0.95, 50, 40.0, 10.0, source="videos/squat.mp4"), made)
    assert load_pose(made).source == str(made)
    assert main(["classify", str(made), "--db", stores["label"]]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{made} (from videos/squat.mp4): ")
    assert main(["classify", str(made), "--db", stores["label"], "--json"]) == 0
    r = json.loads(capsys.readouterr().out)["results"][0]
    assert r["clip"] == str(made) and r["made_from"] == "videos/squat.mp4"


def test_words_from_the_users_files_are_printed_escaped(
    stores: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    made = tmp_path / "clip.npz"
    save_pose(squat_clip(0.95, 50, 40.0, 10.0, source="x\x1b]0;pwned\x07.mp4"), made)
    assert main(["classify", str(made), "--db", stores["label"]]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out
    assert f"{made} (from x\\x1b]0;pwned\\x07.mp4): " in out
