"""UI-PRMD readers on real files: the checks that chose the Kinect rotation order, and the
Vicon marker order (heights and sides)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.readers.uiprmd import (
    KINECT_JOINTS,
    VICON_MARKERS,
    read_uiprmd_kinect,
    read_uiprmd_kinect_joints,
    read_uiprmd_vicon,
    read_uiprmd_vicon_markers,
)
from features.skeleton import JOINT_INDEX

KINECT = "ui-prmd/data/Segmented Movements/Kinect/Positions"
VICON = "ui-prmd/data/Segmented Movements/Vicon/Positions"


def _kinect(shared: Path, movement: int, subject: int, episode: int) -> Path:
    return shared / KINECT / f"m{movement:02d}_s{subject:02d}_e{episode:02d}_positions.txt.gz"


def _joints(seq):
    return {n: seq.positions[:, JOINT_INDEX[n]] for n in JOINT_INDEX}


def _left_axis(p):
    """The person's left from where the feet point: left = up x forward (right-handed)."""
    forward = p["left_foot_index"] + p["right_foot_index"] - p["left_ankle"] - p["right_ankle"]
    forward[:, 1] = 0
    return np.cross([0.0, 1.0, 0.0], forward)


CLIPS = [(m, s, 1) for m in (1, 2, 5, 7, 10) for s in (1, 4, 8)]


def test_kinect_metadata_and_shape(shared_data: Path) -> None:
    seq = read_uiprmd_kinect(_kinect(shared_data, 1, 1, 1))
    assert seq.positions.shape[1:] == (33, 3)
    assert seq.fps == 30.0
    assert seq.metadata["movement"] == "m01" and seq.metadata["subject"] == "s01"
    assert seq.metadata["episode"] == 1 and seq.metadata["correct"] is True
    assert seq.metadata["sensor"] == "kinect"
    for name in ("nose", "left_ear", "left_heel", "left_index", "left_thumb"):
        assert np.isnan(seq.positions[:, JOINT_INDEX[name]]).all()
    inc = shared_data / ("ui-prmd/data/Incorrect Segmented Movements/Kinect/Positions/"
                         "m01_s01_e01_positions_inc.txt.gz")  # fmt: skip
    assert read_uiprmd_kinect(inc).metadata["correct"] is False


@pytest.mark.parametrize(("movement", "subject", "episode"), CLIPS)
def test_kinect_body_is_plausible(shared_data: Path, movement: int, subject: int, episode: int):
    seq = read_uiprmd_kinect(_kinect(shared_data, movement, subject, episode))
    p = _joints(seq)
    # Bone lengths: forward kinematics keeps each stored offset's length (Kinect re-estimates
    # them per frame), and they stay within 10 % of their mean over the clip.
    path = _kinect(shared_data, movement, subject, episode)
    raw = np.loadtxt(path, delimiter=",").reshape(-1, len(KINECT_JOINTS), 3) / 100
    for a, b, child in [("left_hip", "left_knee", "LeftLowerLeg"),
                        ("left_knee", "left_ankle", "LeftFoot"),
                        ("right_shoulder", "right_elbow", "RightForeArm"),
                        ("right_elbow", "right_wrist", "RightHand")]:  # fmt: skip
        length = np.linalg.norm(p[a] - p[b], axis=1)
        stored = np.linalg.norm(raw[:, KINECT_JOINTS.index(child)], axis=1)
        np.testing.assert_allclose(length, stored, atol=1e-9)
        assert length.std() < 0.1 * length.mean()
        assert 0.15 < length.mean() < 0.6
    # standing at the start: shoulders 1.0-1.6 m above the ankles, knees between
    y = {n: v[0, 1] for n, v in p.items()}
    assert 1.0 < y["left_shoulder"] - y["left_ankle"] < 1.6
    assert y["left_hip"] > y["left_knee"] > y["left_ankle"]
    # left joints on the person's left, judged from where the feet point
    left = _left_axis(p)
    for side in ("shoulder", "hip"):
        lr = np.sum((p[f"left_{side}"] - p[f"right_{side}"]) * left, axis=1)
        assert np.mean(lr > 0) > 0.9, side


def test_kinect_deep_squat_knees_go_forward(shared_data: Path) -> None:
    # The check that rules out the other Euler orders: in a deep squat the bent knees move
    # in front of the hip-ankle line (forward = where the feet point), and the waist drops.
    fractions = []
    for s in (1, 2, 3, 5):
        p = _joints(read_uiprmd_kinect(_kinect(shared_data, 1, s, 2)))
        forward = np.cross(_left_axis(p), [0.0, 1.0, 0.0])  # forward = left x up
        hips = (p["left_hip"] + p["right_hip"]) / 2
        assert hips[0, 1] - hips[:, 1].min() > 0.3
        for side in ("left", "right"):
            hip, knee, ankle = p[f"{side}_hip"], p[f"{side}_knee"], p[f"{side}_ankle"]
            bent = np.linalg.norm(hip - ankle, axis=1) < 0.8 * (
                np.linalg.norm(hip - knee, axis=1) + np.linalg.norm(knee - ankle, axis=1)
            )
            ahead = np.sum((knee - (hip + ankle) / 2) * forward, axis=1) > 0
            fractions.append(ahead[bent].mean())
    assert np.mean(fractions) > 0.85


def test_kinect_feet_still_while_standing(shared_data: Path) -> None:
    # In shoulder abduction the legs do not move: ankle drift below 1.5 cm, near the floor.
    for s in (1, 2, 6):
        p = _joints(read_uiprmd_kinect(_kinect(shared_data, 7, s, 1)))
        for side in ("left", "right"):
            ankle = p[f"{side}_ankle"]
            assert np.linalg.norm(ankle - ankle.mean(0), axis=1).mean() < 0.015
        # the raised arm: a wrist rises above the shoulders
        wrist_top = max(p["left_wrist"][:, 1].max(), p["right_wrist"][:, 1].max())
        assert wrist_top > p["left_shoulder"][:, 1].mean()


def test_kinect_malformed(tmp_path: Path, shared_data: Path) -> None:
    src = _kinect(shared_data, 1, 1, 1)
    pos = tmp_path / "m01_s01_e01_positions.txt"
    ang = tmp_path / "m01_s01_e01_angles.txt"
    import gzip

    rows = gzip.decompress(src.read_bytes()).decode().splitlines()
    angles_src = src.parent.parent / "Angles" / "m01_s01_e01_angles.txt.gz"
    arows = gzip.decompress(angles_src.read_bytes()).decode().splitlines()
    pos.write_text("\n".join(rows) + "\n")
    ang.write_text("\n".join(arows[:-3]) + "\n")
    with pytest.raises(DataError, match="frames") as info:
        read_uiprmd_kinect(pos)
    assert info.value.source == str(pos)
    ang.write_text("\n".join(arows) + "\n")
    pos.write_text("\n".join(rows[:5] + [rows[5][:40]]) + "\n")
    with pytest.raises(DataError, match="line 6"):
        read_uiprmd_kinect(pos)
    ang.unlink()
    with pytest.raises(DataError, match="angles"):
        read_uiprmd_kinect(pos)
    assert len(read_uiprmd_kinect_joints(src)[0]) == len(KINECT_JOINTS)


@pytest.mark.parametrize(("movement", "subject"), [(1, 1), (7, 3), (2, 8)])
def test_vicon_marker_order(shared_data: Path, movement: int, subject: int) -> None:
    path = shared_data / VICON / f"m{movement:02d}_s{subject:02d}_e01_positions.txt.gz"
    m = read_uiprmd_vicon_markers(path)
    ix = {n: i for i, n in enumerate(VICON_MARKERS)}
    y = {n: m[0, i, 1] for n, i in ix.items()}
    # heights in the first (standing) frame, top to bottom, of the markers on one side
    chain = ["LFHD", "LSHO", "LASI", "LTHI", "LKNE", "LTIB", "LANK"]
    assert all(y[a] > y[b] for a, b in zip(chain, chain[1:], strict=False)), y
    assert max(y["LHEE"], y["LTOE"], y["RHEE"], y["RTOE"]) < 0.12
    # facing: front head and ASIS markers ahead of the back ones
    forward = m[:, ix["LFHD"]] + m[:, ix["RFHD"]] - m[:, ix["LBHD"]] - m[:, ix["RBHD"]]
    forward[:, 1] = 0
    left = np.cross([0.0, 1.0, 0.0], forward)
    for name in ("FHD", "SHO", "ELB", "ASI", "PSI", "KNE", "ANK", "TOE"):
        lr = np.sum((m[:, ix["L" + name]] - m[:, ix["R" + name]]) * left, axis=1)
        assert np.mean(lr > 0) > 0.95, name
    ahead = np.sum((m[:, ix["LASI"]] - m[:, ix["LPSI"]]) * forward, axis=1)
    assert np.mean(ahead > 0) > 0.95
    toe = np.sum((m[:, ix["LTOE"]] - m[:, ix["LHEE"]]) * forward, axis=1)
    assert np.mean(toe > 0) > 0.95


def test_vicon_joint_centres(shared_data: Path) -> None:
    seq = read_uiprmd_vicon(shared_data / VICON / "m01_s02_e01_positions.txt.gz")
    p = _joints(seq)
    assert seq.metadata["sensor"] == "vicon" and seq.fps == 100.0
    width = np.linalg.norm(p["left_hip"] - p["right_hip"], axis=1)
    # adult hip joint centres are 15-22 cm apart
    assert 0.12 < width.mean() < 0.25
    m = read_uiprmd_vicon_markers(shared_data / VICON / "m01_s02_e01_positions.txt.gz")
    asis_y = m[:, VICON_MARKERS.index("LASI"), 1]
    # the hip centre lies 5-12 cm below the ASIS
    assert 0.04 < np.mean(asis_y - p["left_hip"][:, 1]) < 0.12
    thigh = np.linalg.norm(p["left_hip"] - p["left_knee"], axis=1)
    assert 0.3 < thigh.mean() < 0.5 and thigh.std() < 0.02
    hips = (p["left_hip"] + p["right_hip"]) / 2
    assert hips[0, 1] - hips[:, 1].min() > 0.3  # deep squat
    assert np.isnan(p["nose"]).all() and np.isnan(p["left_thumb"]).all()


def test_vicon_gaps_become_nan(shared_data: Path) -> None:
    # In this file the left wrist-bar marker LWRB is written as (0, 0, 0) (occluded) in 74 of
    # 223 frames (found by scanning the files once).
    path = shared_data / VICON / "m10_s05_e03_positions.txt.gz"
    raw = np.loadtxt(path, delimiter=",").reshape(-1, len(VICON_MARKERS), 3)
    gap = (raw[:, VICON_MARKERS.index("LWRB")] == 0).all(axis=1)
    assert 0 < gap.sum() < len(gap)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        seq = read_uiprmd_vicon(path)
    wrist = seq.positions[:, JOINT_INDEX["left_wrist"]]
    assert np.isnan(wrist[gap]).all()
    assert np.isfinite(wrist[~gap]).all()
    assert np.isfinite(seq.positions[:, JOINT_INDEX["left_elbow"]]).all()


def test_vicon_pelvis_gap_fill(shared_data: Path) -> None:
    from features.readers.uiprmd import PELVIS_MARKERS, fill_rigid_gaps

    rasi = VICON_MARKERS.index("RASI")
    errors = {}
    for clip in ("m07_s01_e01", "m01_s01_e01"):  # standing; deep squat
        m = read_uiprmd_vicon_markers(shared_data / VICON / f"{clip}_positions.txt.gz")
        assert np.isfinite(m).all()
        hidden = m.copy()
        hidden[::3, rasi] = np.nan  # hide RASI in every third frame
        filled = fill_rigid_gaps(hidden, PELVIS_MARKERS)
        errors[clip] = np.linalg.norm(filled[::3, rasi] - m[::3, rasi], axis=1)
        np.testing.assert_array_equal(filled[1::3], m[1::3])
    # standing, the pelvis markers move as one rigid body: the fill is within 5 mm
    assert np.percentile(errors["m07_s01_e01"], 90) < 0.005
    # in a deep squat the skin over the ASIS slides at full hip flexion: within 1.5 cm
    # typically (the module docstring states the worst case, about 6 cm)
    assert np.median(errors["m01_s01_e01"]) < 0.015
    # two pelvis markers missing in a frame: left NaN, never guessed
    hidden[0, VICON_MARKERS.index("LASI")] = np.nan
    assert np.isnan(fill_rigid_gaps(hidden, PELVIS_MARKERS)[0, rasi]).all()
    # in the real file with RASI occluded in its first frames the hips are now available
    seq = read_uiprmd_vicon(shared_data / VICON / "m07_s03_e01_positions.txt.gz")
    assert np.isfinite(seq.positions[:, JOINT_INDEX["right_hip"]]).all()
