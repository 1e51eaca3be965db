"""Joint positions in the person's own frame (features.body.body_positions) and their columns.

The synthetic person of tests.bodies stands facing +z with the left side at +x: torso length
(neck to mid-hip) 0.50 m, mid-hip at (0, 1.00, 0). Expected values are worked out by hand from
those coordinates, in torso lengths.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.explain import quantity
from cbr.problem import POSITION_PREFIX, FeatureConfig, extract_problem, resolve_config
from features.body import body_positions, mirrored, position_names
from features.poses import PoseSequence
from tests.bodies import rot_x, rot_y, rot_z, rotate, standing, to_sequence

TORSO = 0.50


def _column(seq, name: str) -> np.ndarray:  # type: ignore[no-untyped-def]
    return body_positions(seq)[:, position_names().index(name)]


def _raise_left_arm(body: dict[str, np.ndarray], deg: float) -> dict[str, np.ndarray]:
    """The left arm swung sideways (abduction) by ``deg`` about the shoulder."""
    arm = ("left_elbow", "left_wrist", "left_pinky", "left_index", "left_thumb")
    # rotation about the forward axis at the shoulder: positive raises the left arm outwards
    a = np.radians(deg)
    r = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    return rotate(body, arm, r, body["left_shoulder"])


def test_standing_person_in_torso_lengths() -> None:
    seq = to_sequence(*[standing()] * 5)
    # left wrist (0.20, 0.95, 0): 0.40 to the left, 0.10 below the mid-hip, not forward
    assert _column(seq, "left_wrist.left") == pytest.approx(np.full(5, 0.20 / TORSO))
    assert _column(seq, "left_wrist.height") == pytest.approx(np.full(5, -0.05 / TORSO))
    assert _column(seq, "left_wrist.forward") == pytest.approx(np.zeros(5), abs=1e-12)
    # right toes (-0.15, 0.02, 0.15): to the right, near the floor, ahead of the hips
    assert _column(seq, "right_foot_index.left")[0] == pytest.approx(-0.15 / TORSO)
    assert _column(seq, "right_foot_index.height")[0] == pytest.approx(-0.98 / TORSO)
    assert _column(seq, "right_foot_index.forward")[0] == pytest.approx(0.15 / TORSO)


def test_raised_arm_height_follows_the_abduction_angle() -> None:
    frames = [_raise_left_arm(standing(), d) for d in (0.0, 0.0, 0.0, 45.0, 90.0, 135.0)]
    seq = to_sequence(*frames)
    # the wrist hangs 0.55 m below the shoulder (1.50 m): raised by d, it is at
    # 1.50 - 0.55 cos(d), i.e. (0.50 - 0.55 cos d) / 0.50 torso lengths above the mid-hip
    d = np.radians([0.0, 0.0, 0.0, 45.0, 90.0, 135.0])
    assert _column(seq, "left_wrist.height") == pytest.approx((0.50 - 0.55 * np.cos(d)) / TORSO)
    assert _column(seq, "left_wrist.left") == pytest.approx((0.20 + 0.55 * np.sin(d)) / TORSO)


def test_independent_of_where_the_person_stands_and_faces() -> None:
    frames = [_raise_left_arm(standing(), d) for d in (0.0, 0.0, 0.0, 30.0, 60.0, 90.0)]
    plain = body_positions(to_sequence(*frames))
    turn, shift = rot_y(70.0), np.array([2.0, 0.3, -1.5])
    moved = [{k: turn @ v + shift for k, v in f.items()} for f in frames]
    assert body_positions(to_sequence(*moved)) == pytest.approx(plain, abs=1e-9)
    # twice the size: the same values in torso lengths
    big = [{k: 2.0 * v for k, v in f.items()} for f in frames]
    assert body_positions(to_sequence(*big)) == pytest.approx(plain, abs=1e-9)


def test_frame_is_fixed_at_the_start_so_a_squat_drops_the_hips() -> None:
    down = standing()
    for k in down:  # the whole body 0.40 m lower (a squat, legs aside), and leaning forward
        down[k] = down[k] - np.array([0.0, 0.40, 0.0])
    down = rotate(down, tuple(down), rot_x(20.0), down["left_hip"] * [0, 1, 0])
    seq = to_sequence(*([standing()] * 9 + [down]))
    hips = _column(seq, "left_hip.height")
    assert hips[:9] == pytest.approx(np.zeros(9), abs=1e-12)
    assert hips[9] == pytest.approx(-0.40 / TORSO)
    # leaning forward moves the nose ahead of the start frame's hips: 0.63 m above the hip
    # line, tilted 20 degrees
    nose = _column(seq, "nose.forward")
    tilt = np.radians(20.0)
    assert nose[9] == pytest.approx((0.10 * np.cos(tilt) + 0.63 * np.sin(tilt)) / TORSO)


def test_mirror_image_swaps_the_sides() -> None:
    frames = [_raise_left_arm(standing(), d) for d in (0.0, 0.0, 0.0, 90.0)]
    seq = to_sequence(*frames)
    mirror = mirrored(seq)
    assert _column(mirror, "right_wrist.height") == pytest.approx(_column(seq, "left_wrist.height"))
    assert _column(mirror, "right_wrist.left") == pytest.approx(-_column(seq, "left_wrist.left"))
    assert _column(mirror, "right_wrist.forward") == pytest.approx(
        _column(seq, "left_wrist.forward"), abs=1e-12
    )


def test_missing_joints_are_nan_and_dropped_from_the_columns() -> None:
    frames = [standing() for _ in range(4)]
    for f in frames:
        f["nose"] = np.full(3, np.nan)
    seq = to_sequence(*frames)
    assert np.isnan(_column(seq, "nose.height")).all()
    config = resolve_config(FeatureConfig(angles=True, positions=True, summary=True), [seq])
    pos = [s for s in config.states if s.startswith(POSITION_PREFIX)]
    assert POSITION_PREFIX + "nose.height" not in pos
    assert POSITION_PREFIX + "left_wrist.height" in pos
    problem = extract_problem(seq, config)
    i = problem.names.index(POSITION_PREFIX + "left_wrist.height@max")
    assert problem.values[i] == pytest.approx(-0.05 / TORSO)
    assert problem.words[i] == "left wrist height (highest)"
    assert np.isfinite(problem.values).all()


def test_a_person_without_hips_gets_no_position_columns() -> None:
    frames = [standing() for _ in range(4)]
    for f in frames:
        f["left_hip"] = f["right_hip"] = np.full(3, np.nan)
    seq = to_sequence(*frames)
    assert np.isnan(body_positions(seq)).all()
    config = resolve_config(FeatureConfig(angles=True, positions=True, summary=True), [seq])
    assert not [s for s in config.states if s.startswith(POSITION_PREFIX)]


def _right_arm_sideways(peak: float, subject: str) -> PoseSequence:
    """The right arm swung out sideways to ``peak`` degrees and back over 32 frames."""
    arm = tuple(f"right_{j}" for j in ("elbow", "wrist", "pinky", "index", "thumb"))
    body = standing()
    frames = [
        rotate(body, arm, rot_z(a), body["right_shoulder"])
        for a in peak * np.sin(np.linspace(0.0, np.pi, 32))
    ]
    return to_sequence(*frames).with_metadata(subject=subject)


def _arm_joint_heights(joint: str, peak: float) -> np.ndarray:
    """``(32,)`` the height of right-arm ``joint`` above the mid-hip (y = 1.00) in torso lengths
    over :func:`_right_arm_sideways` (``peak``): its standing offset from the shoulder turned
    about the forward axis by each frame's angle, as the clip turns it."""
    body = standing()
    shoulder, offset = body["right_shoulder"], body[joint] - body["right_shoulder"]
    angles = peak * np.sin(np.linspace(0.0, np.pi, 32))
    return np.array([(shoulder + rot_z(a) @ offset)[1] - 1.00 for a in angles]) / TORSO


def _arm_height(feature: str, peak: float) -> float:
    """The value a column named ``feature`` ("right wrist height (highest)", "right index
    height", ...) takes in :func:`_right_arm_sideways` (``peak``): the highest, lowest or mean
    height of that joint."""
    name, _, stat = feature.partition(" (")
    joint = "right_" + name.split()[1]
    h = _arm_joint_heights(joint, peak)
    return float({"highest)": h.max(), "lowest)": h.min()}.get(stat, h.mean()))


def test_explanation_gives_what_was_done_differently_in_units() -> None:
    peaks = {"s1": (150.0, 90.0), "s2": (145.0, 85.0), "s3": (155.0, 95.0)}
    X, y = [], []
    for subject, (high, low) in peaks.items():
        for extra in (0.0, 4.0, 8.0):
            X += [_right_arm_sideways(high + extra, subject)]
            X += [_right_arm_sideways(low + extra, subject)]
            y += ["overhead", "shoulder height"]
    clf = CaseBaseClassifier(k=1, mirror="off", feature_weights="fisher", phases=0).fit(X, y)
    exp = clf.explain([_right_arm_sideways(88.0, "s9")])[0]
    assert exp.label == "shoulder height"
    assert exp.contrast is not None and exp.contrast.label == "overhead"
    # to be overhead, a joint of the right arm must be higher: said in torso lengths, here as
    # this clip has it and there as one of the overhead clips has it
    arm = ("elbow", "wrist", "pinky", "index", "thumb")
    heights = [
        d
        for d in exp.differences
        if d["unit"] == "torso lengths"
        and any(d["feature"].startswith(f"right {j} height") for j in arm)
    ]
    assert heights, exp.differences
    d = heights[0]
    assert d["here"] == pytest.approx(_arm_height(d["feature"], 88.0), abs=1e-9)
    overhead = [
        _arm_height(d["feature"], h + e) for h, _ in peaks.values() for e in (0.0, 4.0, 8.0)
    ]
    assert min(abs(d["there"] - v) for v in overhead) < 1e-9
    assert d["there"] > d["here"]
    # the change said with its unit once, after the value it becomes
    said = re.escape(f"{d['feature']} {d['here']:.2f} → ") + r"-?\d+\.\d\d torso lengths"
    assert re.search(said, exp.text), exp.text


@pytest.mark.parametrize(
    ("name", "value", "expected"),
    [
        ("angle:left_knee@min", 0.5, (90.0, "degrees")),
        ("angle:left_upper_arm_plane@phase2", 0.25, (45.0, "degrees")),
        ("pos:left_wrist.height@max", 1.2, (1.2, "torso lengths")),
        ("left_leg_bent.bent@mean", 0.3, (0.3, "share")),
        ("left_leg_bent.bent@phase1", 0.3, (0.3, "share")),
        ("left_leg_bent.bent@max", 0.9, (0.9, "confidence")),
        ("left_leg_bent.bent@std", 0.2, (0.2, "")),
        ("left_leg_bent.bent", 0.7, (0.7, "confidence")),
    ],
)
def test_feature_units(name: str, value: float, expected: tuple[float, str]) -> None:
    # angles are stored as radians / pi: 0.5 is a right angle
    got = quantity(name, value)
    assert got[0] == pytest.approx(expected[0]) and got[1] == expected[1]


def test_a_stretch_sets_its_own_frame_from_the_rows_it_shares() -> None:
    # a person who turns 90 degrees half-way: a stretch of the second half faces the new way,
    # so its positions are those of a clip recorded from the turn on, not of the whole clip
    from features.derived import stretch

    frames = [standing()] * 6 + [{k: rot_y(90.0) @ v for k, v in standing().items()}] * 6
    whole = to_sequence(*frames)
    body_positions(whole)  # the whole clip's rows computed first, then shared by the stretch
    late = body_positions(stretch(whole, 6, 12))
    alone = body_positions(to_sequence(*frames[6:]))
    assert late == pytest.approx(alone, abs=1e-12)
    # turned with the person: the left wrist is still 0.40 torso lengths to the left
    assert late[:, position_names().index("left_wrist.left")] == pytest.approx(np.full(6, 0.4))


@pytest.mark.parametrize("n", [1, 2, 5, 6])
def test_frame_means_and_median_are_numpys_nan_skipping_ones(n: int) -> None:
    from features.body import _nanmean_rows, _nanmedian

    rng = np.random.default_rng(n)
    a = rng.normal(size=(n, 3))
    a[0, 1] = np.nan  # a gap in one column; with one row that column has no number at all
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # numpy warns of the empty column
        want = np.nanmean(a, axis=0)
    np.testing.assert_array_equal(_nanmean_rows(a), want)
    x = rng.normal(size=n + 1)
    x[-1] = np.nan
    assert _nanmedian(x) == np.nanmedian(x)  # n numbers: odd and even counts
    assert np.isnan(_nanmedian(np.full(3, np.nan)))


def test_the_frames_cross_product_is_numpys() -> None:
    from features.body import _cross

    rng = np.random.default_rng(4)
    for a, b in rng.normal(size=(20, 2, 3)):
        np.testing.assert_array_equal(_cross(a, b), np.cross(a, b))
    # by hand: left x up = forward for a person facing +z (x left, y up)
    np.testing.assert_array_equal(_cross(np.array([1.0, 0, 0]), np.array([0, 1.0, 0])), [0, 0, 1])


def test_a_stretch_counts_the_torso_in_its_own_frames() -> None:
    # frames 0-3 standing, 4-7 without hips: the whole clip shows the torso in half its
    # frames; a stretch of frames 2-6 in 2 of 4, as a clip of those frames alone does
    from features.body import torso_rows, torso_share
    from features.derived import stretch

    no_hips = {k: (np.full(3, np.nan) if k.endswith("hip") else v) for k, v in standing().items()}
    frames = [standing()] * 4 + [no_hips] * 4
    whole = to_sequence(*frames)
    assert torso_share(whole) == 0.5
    np.testing.assert_array_equal(torso_rows(whole), [True] * 4 + [False] * 4)
    part = stretch(whole, 2, 6)  # shares the whole clip's rows
    assert torso_share(part) == 0.5 == torso_share(to_sequence(*frames[2:6]))


def test_resampling_points_are_kept_read_only() -> None:
    from cbr.problem import resample, resample_points

    # times 0, 0.5, 1 over frames at 0, 0.25, ..., 1: frames 0 and 2 exactly, the last as
    # all of frame 4 after frame 3 (the last pair)
    i, w = resample_points(5, 3)
    np.testing.assert_array_equal(i, [0, 2, 3])
    np.testing.assert_allclose(w[:, 0], [0.0, 0.0, 1.0])
    assert resample_points(5, 3)[0] is i  # kept, not computed again
    with pytest.raises(ValueError):
        i[0] = 1  # so no caller can change what the next one reads
    x = np.arange(10.0).reshape(5, 2)
    np.testing.assert_allclose(resample(x, 3), [[0, 1], [4, 5], [8, 9]])
