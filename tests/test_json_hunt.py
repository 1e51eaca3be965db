"""Machine outputs at numeric edges: every ``--json`` document strict JSON (no NaN or
Infinity), its frames and seconds consistent with the clip, and options at their bounds."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest

from features.poses import save_pose
from posecbr.cli import main
from tests.badinput import good_pose_file, refused, small_case_base
from tests.moves import clip


def strict(text: str) -> Any:
    """``text`` parsed as strict JSON: NaN, Infinity and -Infinity refused."""

    def refuse(token: str) -> object:
        raise ValueError(f"not strict JSON: {token}")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def test_segment_at_the_lowest_frame_rates_covers_the_recording(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """At 0.2 fps a 2 s window holds 0.4 frames: rounded to none, each window was an empty
    slice and the recording was refused as having no frames. Windows now hold two frames at
    least (as watch's do), and the 60 frames at 0.2 fps (300 s) are segmented whole."""
    rec = save_pose(clip("squat", 2.0), tmp_path / "squat.npz")  # 60 frames
    code = main(["segment", str(rec), "--db", str(case_base), "--fps", "0.2", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    doc = strict(out)
    assert isinstance(doc, dict)
    assert doc["fps"] == 0.2 and doc["frames"] == 60
    segments = doc["segments"]
    assert segments[0]["start_frame"] == 0 and segments[-1]["end_frame"] == 60
    assert segments[-1]["end_s"] == pytest.approx(300.0)
    for a, b in zip(segments[:-1], segments[1:], strict=True):
        assert a["end_frame"] == b["start_frame"]
    for s in segments:
        assert s["end_frame"] > s["start_frame"]
        assert s["start_s"] == pytest.approx(s["start_frame"] / 0.2)


def test_train_at_the_shortest_length_leaves_automatic_phases_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--length 2`` is in the documented range (2 to 4096), but ``--phases auto`` (3 or
    none) tried 3 phases of a 2-frame sequence and the run was refused for ``phases``, an
    option not given. Auto now chooses none when 3 phases cannot fit; asked for, they are
    still refused."""
    from tests.test_cbr_cli import _write_classes

    data = _write_classes(tmp_path / "train", 3, 5)
    db = tmp_path / "cb.sqlite"
    code = main(["train", str(data), "--db", str(db), "--length", "2", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    doc = strict(out)
    assert isinstance(doc, dict)
    assert doc["learned"]["phases"] == 0 and doc["cases"] == 9
    code = main(["train", str(data), "--db", str(db), "--replace", "--length", "2",
                 "--phases", "3"])  # fmt: skip
    _, err = capsys.readouterr()
    assert code == 1 and "phases" in err and "got 3" in err


def test_classify_json_says_null_for_the_plausibility_of_no_counterfactual(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case base of three takes of one standing clip and three of one 3 s squat (each
    take's left shoulder 1 mm from the last's: train refuses copies of one clip): a 7.5 s
    squat finds no change that makes it "still" (``changes`` empty). Its plausibility, the
    changed clip's distance over the usual one, has no changed clip to measure: it was
    printed as the bare token NaN, which strict JSON parsers refuse; now null."""
    for i in range(3):
        for move, name in (("still", f"still/s{i}.npz"), ("squat", f"squat/q{i}.npz")):
            seq = clip(move, 3.0)
            moved = seq.positions.copy()
            moved[:, 11, 0] += 0.001 * i
            take = dataclasses.replace(seq, positions=moved)
            save_pose(take.with_metadata(subject=f"p{i}", take=str(i)), tmp_path / name)
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(tmp_path), "--db", str(db)]) == 0
    query = save_pose(clip("squat", 7.5), tmp_path / "query.npz")
    capsys.readouterr()
    code = main(["classify", str(query), "--db", str(db), "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    doc = strict(out)
    assert isinstance(doc, dict)
    contrast = doc["results"][0]["contrast"]
    assert contrast["label"] == "still" and contrast["changes"] == []
    assert contrast["plausibility"] is None


@pytest.mark.parametrize("block", ["0", "-1", "nan", "inf"])
def test_train_refuses_a_label_block_that_is_no_length_of_time_naming_the_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], block: str
) -> None:
    """``--label-block`` NaN, infinite, zero or negative: one line naming the option (it
    named the label file, which holds nothing wrong), nothing written."""
    rec = good_pose_file(tmp_path / "rec.npz", frames=60)
    labels = tmp_path / "labels.txt"
    labels.write_text("1\n1\n", encoding="utf-8")
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(rec), "--db", str(db), "--frame-labels", str(labels),
            "--label-block", block]  # fmt: skip
    line = refused(argv, tmp_path, capsys, "--label-block", block)
    assert str(labels) not in line
