"""Fluents on real motion capture with known movements (UI-PRMD Kinect and Vicon, HDM05)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from features.fluents import evaluate, state_signals
from features.readers.asfamc import read_asf_amc
from features.readers.uiprmd import read_uiprmd_kinect, read_uiprmd_vicon

SEG = "ui-prmd/data/Segmented Movements"


def _kinect(shared: Path, movement: str, subjects: range, episodes: range) -> list[Path]:
    folder = shared / SEG / "Kinect" / "Positions"
    return [
        folder / f"{movement}_s{s:02d}_e{e:02d}_positions.txt.gz"
        for s in subjects
        for e in episodes
        if (folder / f"{movement}_s{s:02d}_e{e:02d}_positions.txt.gz").exists()
    ]


def test_uiprmd_deep_squat_knees_straight_then_bent(shared_data: Path) -> None:
    files = _kinect(shared_data, "m01", range(1, 9), range(1, 4))
    assert len(files) >= 20
    straight_at_start = bent_at_deepest = 0
    for path in files:
        seq = read_uiprmd_kinect(path)
        result = evaluate(seq)
        sig = state_signals(seq)
        deepest = int(np.nanargmin(sig.column("left_knee") + sig.column("right_knee")))
        straight_at_start += all(
            result.column(f"{s}_leg_bent.straight")[0] > 0.9 for s in ("left", "right")
        )
        bent_at_deepest += all(
            result.column(f"{s}_leg_bent.bent")[deepest] > 0.99 for s in ("left", "right")
        )
        # the deepest frame is in the middle of the repetition, not at its ends
        assert 0.15 < deepest / seq.n_frames < 0.85, path.name
    assert straight_at_start >= 0.9 * len(files)
    assert bent_at_deepest == len(files)


def _abduction(seq):  # type: ignore[no-untyped-def]
    """(moving side, fluent result, signals) for a shoulder abduction repetition."""
    result = evaluate(seq)
    sig = state_signals(seq)
    ranges = {s: np.nanmax(sig.column(f"{s}_armpit")) for s in ("left", "right")}
    return max(ranges, key=ranges.__getitem__), result, sig


def test_uiprmd_shoulder_abduction_one_arm_rises_outward(shared_data: Path) -> None:
    kinect = shared_data / SEG / "Kinect" / "Positions"
    vicon = shared_data / SEG / "Vicon" / "Positions"
    for subject in range(1, 9):
        name = f"m07_s{subject:02d}_e01_positions.txt.gz"
        side_k, result, sig = _abduction(read_uiprmd_kinect(kinect / name))
        side_v, result_v, sig_v = _abduction(read_uiprmd_vicon(vicon / name))
        # Left and right are not swapped: the Kinect skeleton (forward kinematics on joint
        # names) and the Vicon one (Plug-in-Gait marker names), converted independently, agree
        # on which arm the subject abducts (the right arm, except subject 7 who uses the left).
        assert side_k == side_v, name
        for side, res, sg in ((side_k, result, sig), (side_v, result_v, sig_v)):
            other = "left" if side == "right" else "right"
            arm = sg.column(f"{side}_armpit")
            top = int(np.nanargmax(arm))
            assert res.column(f"{side}_arm_raised.lowered")[0] > 0.5, name
            # at the top "raised" is the most likely state (Vicon's marker-derived shoulder
            # centre gives a lower arm than Kinect's: 125-160 degrees at the top)
            assert res.column(f"{side}_arm_raised.raised")[top] > 0.5, name
            # on the way up, as the arm passes shoulder height, "outward" is the likeliest
            level = int(np.nanargmin(np.abs(arm[:top] - np.pi / 2)))
            assert res.column(f"{side}_arm_outward.outward")[level] > 0.5, name
            assert np.nanmax(res.column(f"{other}_arm_raised.raised")) < 0.1, name
            assert np.nanmax(sg.column(f"{other}_armpit")) < np.radians(70), name
            assert np.nanmax(res.column(f"{side}_arm_raised.raising")[:top]) > 0.5, name


def test_uiprmd_kinect_people_face_the_sensor(shared_data: Path) -> None:
    # The Kinect looks along -z at people standing at z of about -2.4 m. With left and right
    # correct, the chest-facing normal points back toward the sensor (+z); a mirrored skeleton
    # would face away.
    from features.geometry import body_frame

    for path in _kinect(shared_data, "m07", range(1, 9), range(1, 2)):
        seq = read_uiprmd_kinect(path).to_canonical()
        forward = body_frame(seq.positions).forward
        assert np.nanmedian(forward[:, 2]) > 0.8, path.name


def _hdm05(shared: Path, action: str) -> list[tuple[Path, Path]]:
    out = []
    for amc in sorted((shared / "hdm05" / "train").glob(f"*/HDM_*_{action}_*")):
        actor = amc.name.split("_")[1]
        out.append((amc.parent / f"HDM_{actor}.asf", amc))
    return out


def test_hdm05_squat_knees_extend_bend_extend(shared_data: Path) -> None:
    clips = _hdm05(shared_data, "squat1Reps")
    assert len(clips) >= 10
    for asf, amc in clips[::3]:
        seq = read_asf_amc(asf, amc)
        result = evaluate(seq)
        sig = state_signals(seq)
        knees = sig.column("left_knee") + sig.column("right_knee")
        deepest = int(np.nanargmin(knees))
        assert 0.15 < deepest / seq.n_frames < 0.85, amc.name
        for side in ("left", "right"):
            knee = sig.column(f"{side}_knee")
            assert knee[0] - knee[deepest] > np.radians(70), amc.name
            assert result.column(f"{side}_leg_bent.bent")[deepest] > 0.99, amc.name
        bending = result.column("left_leg_bent.bending")
        straightening = result.column("left_leg_bent.straightening")
        assert np.nanmax(bending[:deepest]) > 0.9 and np.nanmax(straightening[deepest:]) > 0.9


def test_hdm05_left_front_kick_raises_the_left_leg(shared_data: Path) -> None:
    clips = _hdm05(shared_data, "kickLFront1Reps")
    assert len(clips) >= 5
    for asf, amc in clips[::2]:
        seq = read_asf_amc(asf, amc)
        result = evaluate(seq)
        sig = state_signals(seq)
        top = int(np.nanargmin(sig.column("left_hip")))
        assert result.column("left_leg_raised.raised")[top] > 0.99, amc.name
        assert result.column("left_leg_in_front.in_front")[top] > 0.99, amc.name
        assert np.nanmin(sig.column("left_hip")) < np.nanmin(sig.column("right_hip")) - 0.5
