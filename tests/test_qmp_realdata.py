"""QMPs on real motion capture (UI-PRMD Kinect, held-out episodes 4-5: the ADD thresholds
were set while looking at episodes 1-3 only)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.datasets import Clip, iter_dataset
from features.qmp import qmp_features

SHOULDER_MOVES = {"m07", "m08", "m09", "m10"}


# on one xdist worker: the module's uiprmd_clips made once, not once per worker
pytestmark = pytest.mark.xdist_group("qmp_realdata")


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


def test_a_criterion_no_window_could_test_is_unknown_not_unmet() -> None:
    """A deep squat with its legs missing: the knee and hip criteria could be tested in no
    window, so they are NaN (unknown) in ``values``, not 0.0 (unmet), and the problem names
    them unseen (explanations cite none of them); with nobody in view every criterion is."""
    import dataclasses

    from cbr.problem import FeatureConfig, extract_problem
    from features.poses import load_pose

    demo = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
    clip = load_pose(demo / "m01_s01_e01.npz")
    n = len(qmp_features(clip).binary_names)
    whole = qmp_features(clip).values[:n]
    pos = clip.positions.copy()
    legs = [i for i, j in enumerate(clip.joint_names) if j.endswith(("hip", "knee", "ankle"))]
    pos[:, legs] = np.nan
    blind = qmp_features(dataclasses.replace(clip, positions=pos))
    unknown = np.isnan(blind.values[:n])
    assert unknown.sum() > np.isnan(whole).sum()
    assert not blind.binary[unknown].any()
    knees = [w for w in blind.binary_names if "knee" in w]
    assert knees and all(np.isnan(blind.values[blind.binary_names.index(w)]) for w in knees)
    for part in ("binary", "values"):
        config = FeatureConfig(level="qmp", qmp_part=part)
        problem = extract_problem(dataclasses.replace(clip, positions=pos), config)
        assert set(knees) <= problem.unseen
        assert not np.isnan(problem.values).any()  # filled for the measure, as before
    nobody = qmp_features(dataclasses.replace(clip, positions=np.full_like(pos, np.nan)))
    assert nobody.status == "not enough data" and np.isnan(nobody.values[:n]).all()
