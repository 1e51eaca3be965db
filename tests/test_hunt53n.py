"""Session 53, task N: leftovers of compare's and train's refusals (hunts 53e, 53j). ``train
--json`` says why each clip skipped was (``skipped_reasons``)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_clip
from features.poses import save_pose
from posecbr.cli import main
from tests.test_hunt53j import BELOW_THE_WAIST, DEMO


def test_train_json_says_why_each_clip_was_skipped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two activities of two real clips each (the demo's UI-PRMD pose files), and three clips
    no case can be made of: one with the hips out of view, one with no joint in any frame,
    one of 6 frames (0.2 s)."""
    data = tmp_path / "data"
    for label, stems in (("abduction", ("m07_s01_e01", "m07_s01_e02")),
                         ("squat", ("m01_s01_e01", "m01_s01_e02"))):  # fmt: skip
        (data / label).mkdir(parents=True)
        for stem in stems:
            (data / label / f"{stem}.npz").symlink_to(DEMO / f"{stem}.npz")
    seq = load_clip(DEMO / "m07_s02_e01.npz").to_canonical()
    no_hips = seq.positions.copy()
    no_hips[:, BELOW_THE_WAIST] = np.nan
    save_pose(dataclasses.replace(seq, positions=no_hips), data / "abduction" / "nohips.npz")
    blank = np.full_like(seq.positions, np.nan)
    save_pose(dataclasses.replace(seq, positions=blank), data / "abduction" / "blank.npz")
    short = load_clip(DEMO / "m01_s02_e01.npz")
    save_pose(dataclasses.replace(short, positions=short.positions[:6]), data / "squat" / "s.npz")
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(data), "--db", str(db), "-k", "1", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    reasons = {r["clip"]: r["reason"] for r in summary["skipped_reasons"]}
    # the text's words ("skipped 1 clip that shows no torso (...): nohips.npz")
    no_torso = "shows no torso (no frame shows its left hip, right hip)"
    assert [Path(c).name for c in reasons] == ["blank.npz", "nohips.npz", "s.npz (lasts 0.20 s)"]
    assert list(reasons.values()) == [
        "shows no person", no_torso, "shorter than one movement can be (0.4 s)"]  # fmt: skip
    assert [r["clip"] for r in summary["skipped_reasons"]] == summary["skipped"]  # as before
    assert summary["cases"] == 4
