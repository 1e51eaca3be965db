"""``posecbr dad``: text for people, JSON for machines, one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from features.datasets import load_clip
from features.poses import save_pose
from posecbr.cli import main
from tests.bodies import standing, to_sequence


@pytest.fixture(scope="module")
def squat_file(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = (
        shared_data / "ui-prmd" / "data" / "Incorrect Segmented Movements" / "Kinect"
        / "Positions" / "m01_s02_e04_positions_inc.txt.gz"
    )  # fmt: skip
    out = tmp_path_factory.mktemp("dad") / "squat.npz"
    save_pose(load_clip(src), out)
    return out


def test_text_output_ranks_and_lists_met_and_unmet(
    squat_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["dad", str(squat_file), "--top", "0"]) == 0
    out = capsys.readouterr().out
    assert "ranking:" in out and "best match:" in out
    assert "deep squat (arms raised high)" in out
    assert "knees bending and straightening in rhythm" in out
    assert "+ " in out and ("- " in out or "? " in out)


def test_json_output_is_the_api_structure(
    squat_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["dad", str(squat_file), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["status"] == "ok"
    acts = data["activities"]
    assert {"activity", "score", "labels", "qmps"} <= set(acts[0])
    scores = [a["score"] for a in acts if a["score"] is not None]
    assert scores == sorted(scores, reverse=True)
    statuses = {q["status"] for a in acts for q in a["qmps"]}
    assert statuses <= {"met", "not met", "out of order", "not observable"}


def test_too_short_clip_says_not_enough_data(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "blink.npz"
    save_pose(to_sequence(standing(), standing(), standing()), path)
    assert main(["dad", str(path)]) == 0
    assert "not enough data" in capsys.readouterr().out


def test_bad_add_and_missing_file_are_one_line_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    add = tmp_path / "broken.toml"
    add.write_text('[activity.x]\nwords = "x"\n')
    pose = tmp_path / "still.npz"
    save_pose(to_sequence(*[standing()] * 40), pose)
    assert main(["dad", str(pose), "--add", str(add)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("posecbr dad: error:") and "broken.toml" in err and "\n" not in err
    assert main(["dad", str(tmp_path / "nothing.npz")]) == 1
    assert "nothing.npz" in capsys.readouterr().err
