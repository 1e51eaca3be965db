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
    """Three frames at 30 fps (0.1 s, DAD judges 0.5 s or more): one line on stderr and exit 1
    (it was a line on stdout and exit 0); with --json the document says why, exit 1. A
    --window shorter than DAD judges is refused before the clip is read."""
    path = tmp_path / "blink.npz"
    save_pose(to_sequence(standing(), standing(), standing()), path)
    before = path.read_bytes()
    assert main(["dad", str(path)]) == 1
    out, err = capsys.readouterr()
    assert out == "" and err == (
        f"posecbr dad: error: {path}: not enough data: clip lasts 0.10 s; DAD needs at least "
        "0.5 s\n"
    )
    assert main(["dad", str(path), "--json"]) == 1
    assert json.loads(capsys.readouterr().out)["status"] == "not enough data"
    assert main(["dad", str(tmp_path / "absent.npz"), "--window", "0.1"]) == 1
    assert capsys.readouterr().err == (
        "posecbr dad: error: --window: must be at least 0.5 s, the shortest stretch DAD judges, "
        "got 0.1\n"
    )
    assert path.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == [
        "blink.npz"
    ]


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


def test_a_best_match_tied_with_others_says_so() -> None:
    """Three activities at 100 % and one at 66 % (the reverse-lunge video with the default
    ADD): "best match: a" alone read as if DAD had told them apart."""
    import argparse

    from cbr.dad import DADConfig
    from cbr.dad.outcome import ActivityScore, DADResult
    from posecbr.commands.dad import _text_lines

    def act(name: str, score: float) -> ActivityScore:
        return ActivityScore(name, f"{name} words", (name,), score, 3, 3, ())

    acts = (act("a", 1.0), act("b", 1.0), act("c", 1.0), act("d", 2 / 3))
    result = DADResult("x.npz", "ok", "", 30.0, 10.0, ((0.0, 4.0),), ((),), acts)
    args = argparse.Namespace(posefile=Path("x.npz"), top=1)
    lines = list(_text_lines(args, result, DADConfig()))
    assert lines[1] == (
        "best match: a words (100 % of its QMPs in order; tied with b words, c words)"
    )
    alone = DADResult("x.npz", "ok", "", 30.0, 10.0, ((0.0, 4.0),), ((),), acts[2:])
    assert list(_text_lines(args, alone, DADConfig()))[1] == (
        "best match: c words (100 % of its QMPs in order)"
    )
