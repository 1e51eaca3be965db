"""Hunt 46r: the README's "Case bases" and "Long recordings" passages checked against the code.

1. An activity every labelled stretch of which is shorter than one movement can be (0.4 s) is
left out before training and gets no case; README ("Training from long recordings") says
``train`` names such an activity beneath the skipped ones ("no case of the activity ...:
every piece of it was skipped, as said above"; ``--json``: ``no_case``). It did so for
clips skipped in training, not for stretches of a recording labelled over time left out
before it: the case base lacked the activity with only the "left out" note on stderr.

2. ``convert --out DIR`` adds to DIR's labels.csv, "refused in one line when a row of it could
not be read by ``train``" (README, Commands). Each row was read, but not the rows together: a
labels.csv listing one pose file twice, or under two labels, was added to (exit 0), and
``train DIR`` then refused the folder convert had just written.

3. A labels CSV's other columns are "kept with each clip as the file spells it ... ``--target``
finds it in any case" (README, Commands). A column ``Correct`` beside pose files whose
metadata holds ``correct`` (UI-PRMD's, converted) lost to the file's: the lookup in any case
found the file's key, spelt exactly, first, so the CSV's verdicts were ignored."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import refused

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def test_train_names_an_activity_whose_every_stretch_was_too_short(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A real 73-frame UI-PRMD clip at 30 fps labelled frame by frame: 30 frames 'reach'
    (1.00 s), 5 frames 'flick' (0.17 s, under 0.4 s) and 38 frames 'squat' (1.27 s)."""
    labels = tmp_path / "labels.txt"
    labels.write_text(" ".join(["reach"] * 30 + ["flick"] * 5 + ["squat"] * 38))
    clip = DEMO / "m01_s01_e01.npz"
    argv = ["train", str(clip), "--frame-labels", str(labels), "--db", str(tmp_path / "a.sqlite")]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "left out 1 labelled stretch shorter than 0.4 s (flick)" in captured.err
    out = captured.out.splitlines()
    assert "no case of the activity 'flick': every piece of it was skipped, as said above" in out
    assert "2 activities" in out[1] and "reach" in out[-2] and "squat" in out[-1], out
    argv[-1] = str(tmp_path / "b.sqlite")
    assert main([*argv, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["no_case"] == ["flick"] and doc["labels"] == {"reach": 1, "squat": 1}


@pytest.mark.parametrize(
    ("second", "needle"),
    [("a", "lines 2 and 3 both give m01.npz whole ('a')"),
     ("b", "lines 2 and 3 give m01.npz whole ('a') and whole ('b')")],
)  # fmt: skip
def test_convert_refuses_to_add_to_a_labels_csv_train_would_refuse(
    second: str, needle: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The out folder's labels.csv lists its one pose file twice: the same stretch and label
    (train: "listed twice: its cases would vote twice"), or two labels (train: "its frames
    would be cases of two activities"). Refused naming both lines, nothing written."""
    source = tmp_path / "source"
    source.mkdir()
    (source / "m05.npz").write_bytes((DEMO / "m05_s01_e01.npz").read_bytes())
    (source / "labels.csv").write_text("path,label\nm05.npz,sit_to_stand\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "m01.npz").write_bytes((DEMO / "m01_s01_e01.npz").read_bytes())
    (out / "labels.csv").write_text(f"path,label\nm01.npz,a\nm01.npz,{second}\n")
    refused(["convert", str(source), "--out", str(out)], tmp_path, capsys,
            f"{out / 'labels.csv'}: the labels file already there cannot be added to", needle,
            "nothing written")  # fmt: skip


def test_a_labels_csv_column_overrides_the_pose_files_own_in_any_case(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two real UI-PRMD deep squats, both correct repetitions by their files' metadata
    (``correct: true``); the CSV's ``Correct`` calls the first incorrect. Trained on that
    column, the case base holds one case of each verdict (the old code: both "correct", and
    train refused the data as holding one value)."""
    for name in ("m01_s01_e01.npz", "m01_s02_e01.npz"):
        (tmp_path / name).write_bytes((DEMO / name).read_bytes())
    csv_path = tmp_path / "labels.csv"
    csv_path.write_text(
        "path,label,Correct\nm01_s01_e01.npz,deep_squat,false\nm01_s02_e01.npz,deep_squat,true\n"
    )
    argv = ["train", str(csv_path), "--target", "correct", "--db", str(tmp_path / "cb.sqlite")]
    assert main([*argv, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["labels"] == {"correct": 1, "incorrect": 1}
