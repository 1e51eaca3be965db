"""QMPs on real motion capture (UI-PRMD Kinect, held-out episodes 4-5: the ADD thresholds
were set while looking at episodes 1-3 only)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.datasets import Clip, iter_dataset
from features.qmp import qmp_features

SHOULDER_MOVES = {"m07", "m08", "m09", "m10"}


@pytest.fixture(scope="module")
def uiprmd_clips(shared_data: Path) -> list[Clip]:
    return list(
        iter_dataset(shared_data / "ui-prmd", movements={"m01"} | SHOULDER_MOVES, episodes={4, 5})
    )


def test_knee_oscillation_in_deep_squats_not_in_shoulder_exercises(
    uiprmd_clips: list[Clip],
) -> None:
    squat: list[bool] = []
    shoulder: list[bool] = []
    for clip in uiprmd_clips:
        f = qmp_features(clip.seq)
        met = bool(f.binary[f.criteria.index("knee_oscillation")])
        (squat if clip.extras["movement"] == "m01" else shoulder).append(met)
    assert len(squat) >= 30 and len(shoulder) >= 100  # correct and incorrect repetitions
    assert np.mean(squat) >= 0.8
    assert np.mean(shoulder) <= 0.05


def test_feature_vectors_have_stable_readable_names(uiprmd_clips: list[Clip]) -> None:
    a = qmp_features(uiprmd_clips[0].seq)
    b = qmp_features(uiprmd_clips[-1].seq)
    assert a.names == b.names
    assert a.values.shape == (len(a.names),) and a.values.dtype == np.float64
    assert a.binary.dtype == bool and len(a.binary) == len(a.binary_names)
    assert a.names[: len(a.binary_names)] == a.binary_names
    assert "knees bending and straightening in rhythm" in a.binary_names
    for name in ("left_knee.amplitude_rad", "left_knee.period_s", "right_armpit.mean_rad"):
        assert name in a.names
    # The knees of a deep squat swing by tens of degrees; a squat repetition lasts seconds.
    squat = next(c for c in uiprmd_clips if c.extras["movement"] == "m01")
    f = qmp_features(squat.seq).as_dict()
    assert 0.25 < f["left_knee.amplitude_rad"] < 1.6
    assert 0.8 < f["left_knee.period_s"] < 2 * squat.seq.positions.shape[0] / squat.seq.fps
    # Heels and ears are not on the Kinect skeleton: distances are not observable (NaN).
    assert np.isnan(f["left_heel~right_heel.range_hl"])
