"""The demo subset in posecbr/demo_data/uiprmd loads (no ../shared needed) with the right labels."""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import numpy as np

from features.datasets import detect_kind, load_clip, load_dataset

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"

# The label table of the project's conventions (briefs/labels.md), written out independently.
SLUGS = {
    "m01": "deep_squat",
    "m02": "hurdle_step",
    "m03": "inline_lunge",
    "m04": "side_lunge",
    "m05": "sit_to_stand",
    "m06": "standing_active_straight_leg_raise",
    "m07": "standing_shoulder_abduction",
    "m08": "standing_shoulder_extension",
    "m09": "standing_shoulder_internal_external_rotation",
    "m10": "standing_shoulder_scaption",
}


def test_demo_is_small_and_documented() -> None:
    size = sum(p.stat().st_size for p in DEMO.iterdir())
    assert size < 15e6
    text = (DEMO / "SOURCE.md").read_text()
    assert "PDDL" in text and "Vakanski" in text and "posecbr convert" in text


def test_demo_loads_with_right_labels() -> None:
    assert detect_kind(DEMO) == "csv"
    clips = load_dataset(DEMO)
    assert len(clips) == 180
    assert Counter(c.subject for c in clips) == {"s01": 60, "s02": 60, "s03": 60}
    assert Counter(c.extras["correct"] for c in clips) == {True: 90, False: 90}
    for clip in clips:
        name = Path(clip.seq.source).name
        m = re.match(r"(m\d\d)_(s\d\d)_e(\d\d)(_inc)?\.npz$", name)
        assert m, name
        assert clip.label == SLUGS[m.group(1)]
        assert clip.subject == m.group(2)
        assert clip.extras["correct"] is (m.group(4) is None)
        assert clip.seq.positions.dtype == np.float64
        assert clip.seq.positions.shape[1:] == (33, 3) and clip.seq.fps == 30.0
    # the same labels come from each file's own metadata (the folder as pose files)
    one = load_clip(DEMO / "m04_s03_e02_inc.npz")
    assert one.metadata["label"] == "side_lunge" and one.metadata["correct"] is False


def test_demo_movements_look_right() -> None:
    squat = load_clip(DEMO / "m01_s01_e01.npz")
    hips = (squat.joint("left_hip") + squat.joint("right_hip")) / 2
    assert hips[0, 1] - hips[:, 1].min() > 0.3  # the waist drops in a deep squat
    raised = 0
    for e in (1, 2, 3):
        abd = load_clip(DEMO / f"m07_s02_e{e:02d}.npz")
        top = max(abd.joint("left_wrist")[:, 1].max(), abd.joint("right_wrist")[:, 1].max())
        raised += top > abd.joint("left_shoulder")[:, 1].mean()
    assert raised == 3  # shoulder abduction lifts a hand above the shoulders
    assert np.isnan(squat.joint("nose")).all()  # Kinect has no face landmarks
