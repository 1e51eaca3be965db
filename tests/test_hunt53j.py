"""Session 53, task J: a new user's afternoon with session 52's features (hips out of view,
`reps`), fed bad input: a refusal is its one line."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_clip
from features.poses import PoseSequence, save_pose
from features.skeleton import JOINT_INDEX
from posecbr.cli import main

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
BELOW_THE_WAIST = [
    i for n, i in JOINT_INDEX.items() if n.split("_", 1)[-1] in {"hip", "knee", "ankle", "heel"}
] + [JOINT_INDEX[f"{s}_foot_index"] for s in ("left", "right")]


def _abduction(name: str) -> PoseSequence:
    """A UI-PRMD standing shoulder abduction of the demo data (``s01_e01`` ...), canonical."""
    return load_clip(DEMO / f"m07_{name}.npz").to_canonical()


def _hips_out(seq: PoseSequence, source: str) -> PoseSequence:
    """``seq`` with the hips and everything below them missing in every frame (below a phone's
    bottom edge), named ``source``."""
    p = seq.positions.copy()
    p[:, BELOW_THE_WAIST] = np.nan
    return dataclasses.replace(seq, positions=p, source=source)


def test_reps_of_a_one_frame_clip_with_the_hips_out_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One frame (1/30 s) of a shoulder abduction, the hips out of view: refused as shorter
    than one repetition can be (0.4 s), in its one line. Before, "counted from the arms
    alone" came first, of a clip then not counted."""
    seq = _hips_out(_abduction("s01_e01"), "one.npz")
    one = dataclasses.replace(seq, positions=seq.positions[:1])
    path = tmp_path / "one.npz"
    save_pose(one, path)
    assert main(["reps", str(path)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "one.npz" in err[0] and "lasts 0.03 s" in err[0] and "(0.4 s)" in err[0]
