"""Hunt 46r: the README's "Case bases" and "Long recordings" passages checked against the code.

An activity every labelled stretch of which is shorter than one movement can be (0.4 s) is
left out before training and gets no case; README ("Training from long recordings") says
``train`` names such an activity beneath the skipped ones ("no case of the activity ...:
every piece of it was skipped, as said above"; ``--json``: ``no_case``). It did so for
clips skipped in training, not for stretches of a recording labelled over time left out
before it: the case base lacked the activity with only the "left out" note on stderr."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from posecbr.cli import main

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
