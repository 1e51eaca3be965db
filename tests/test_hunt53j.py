"""Session 53, task J: a new user's afternoon with session 52's features (hips out of view,
`reps`, `compare`), fed bad input: a refusal is its one line, and a clip that shows the
shoulders and arms, the hips out of view, is not said to show no person."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from cbr.described import DescribedClip
from cbr.evaluation.data import prepare
from cbr.evaluation.settings import CompareSettings
from features.clips import Clip
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


def test_compare_names_clips_with_the_hips_out_of_view_as_showing_no_torso() -> None:
    """Of eight clips, two with the hips out of view (shoulders and arms seen) and one with no
    joint at all are left out, each kind said as classify and segment say it; the two were
    "left out 2 clips that show no person"."""
    usable = [_abduction(f"s01_e0{e}") for e in (1, 2, 3)]
    no_hips = [_hips_out(_abduction(f"s02_e0{e}"), f"nohips{e}.npz") for e in (1, 2)]
    blank = dataclasses.replace(
        usable[0], positions=np.full_like(usable[0].positions, np.nan), source="blank.npz"
    )
    clips = [Clip(s, "abduction", "s01") for s in usable]
    clips += [Clip(s, "other", "s01") for s in (*no_hips, blank)]
    clips += [Clip(_abduction(f"s03_e0{e}"), "other", "s03") for e in (1, 2)]
    notes = prepare(clips, CompareSettings()).notes
    assert notes == [
        "left out 2 clips that show no torso (no frame shows its left hip, right hip):"
        " nohips1.npz, nohips2.npz",
        "left out 1 clip that shows no person: blank.npz",
    ]


def test_train_names_a_clip_with_the_hips_out_of_view_as_showing_no_torso() -> None:
    """`train`'s line of the clips it skips: those with the hips out of view (shoulders and
    arms seen) show no torso, naming the hips, as classify and segment say it; one with no
    joint at all shows no person, as before. All three were "skipped 3 clips that show no
    person"."""
    from cbr.described import describe_clip
    from cbr.problem import FeatureConfig, candidate_config
    from posecbr.commands.train import _skipped

    def describe(seq: PoseSequence) -> DescribedClip:
        return describe_clip(seq, candidate_config(FeatureConfig()), True, True)

    seq = _abduction("s02_e01")
    blank = dataclasses.replace(seq, positions=np.full_like(seq.positions, np.nan))
    described = [
        describe(_hips_out(seq, "nohips1.npz")),
        describe(dataclasses.replace(blank, source="blank.npz")),
        describe(_hips_out(_abduction("s02_e02"), "nohips2.npz")),
    ]
    assert [c.torso_share for c in described] == [0.0, 0.0, 0.0]
    words = "shows no torso (no frame shows its left hip, right hip)"
    assert [c.no_torso for c in described] == [words, "", words]
    names = [c.source for c in described]
    assert _skipped(names, [], "clips", (), [c.no_torso for c in described]) == (
        "skipped 2 clips that show no torso (no frame shows its left hip, right hip):"
        " nohips1.npz, nohips2.npz\nskipped 1 clip that shows no person: blank.npz"
    )
