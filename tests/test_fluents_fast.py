"""The compiled fluent kernel equals the numpy reference (backend="numba" vs "numpy").

The reference (whole-array numpy, paper eqs. 2-6 written out directly) is the definition the
other fluent tests check against hand-made geometry; here the fused single-pass kernel must
reproduce it on signals built to hit every branch: values inside and outside each band, NaNs
(isolated and in runs), clips shorter than the window or than one lag, integer and
fractional lags, tilt pairs, touching, and tables with other parameters.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.errors import ConfigError, DataError
from features.fluents import DEFAULT_TABLE, FluentTable, evaluate, state_signals
from features.poses import PoseSequence, load_pose
from features.readers.asfamc import read_asf_amc
from features.readers.uiprmd import read_uiprmd_kinect, read_uiprmd_vicon
from features.signals import ANGLE_SIGNALS, NEAR_SIGNALS, StateSignals
from tests.bodies import standing, to_sequence

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
# The kernel computes in float32 where the float64 reference's precision is not needed (the
# band decisions and the differences beside a threshold stay float64) and stores float32.
TOL = 1e-6


def _assert_same(seq: PoseSequence, table: FluentTable = DEFAULT_TABLE,
                 signals: StateSignals | None = None) -> np.ndarray:  # fmt: skip
    fast = evaluate(seq, table, signals, backend="numba")
    ref = evaluate(seq, table, signals, backend="numpy")
    assert fast.state_names == ref.state_names
    a, b = fast.confidence, ref.confidence
    assert a.shape == b.shape == (seq.n_frames, len(ref.state_names))
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
    assert a.dtype == np.float32
    both = ~np.isnan(b)
    if both.any():
        assert np.max(np.abs(a[both] - b[both])) < TOL
    # the same band decisions: exactly 0 and exactly 1 wherever the reference has them
    np.testing.assert_array_equal(a[b == 0.0], 0.0)
    np.testing.assert_array_equal(a[b == 1.0], 1.0)
    return b


def _walk_signals(frames: int, fps: float, seed: int, nan_fraction: float = 0.03) -> StateSignals:
    """Random-walk signals around each fluent's thresholds with steps the size of the motion
    band, so instantaneous and temporal confidences land inside and outside every band."""
    rng = np.random.default_rng(seed)
    n_a, n_d = len(ANGLE_SIGNALS), len(NEAR_SIGNALS)
    start = np.concatenate([rng.uniform(0.0, np.pi, n_a), rng.uniform(0.0, 1.2, n_d)])
    step = np.concatenate([np.full(n_a, np.pi / 72), np.full(n_d, 0.06)])
    # Some stretches still (steps well inside the no-motion band), some moving steadily.
    drift = rng.choice([0.0, 1.5, -1.5], size=(frames, 1)) * step
    values = start + np.cumsum(drift + rng.normal(0.0, 1.0, (frames, n_a + n_d)) * step, axis=0)
    values[:, :n_a] = np.clip(values[:, :n_a], 0.0, np.pi)
    values[:, n_a:] = np.abs(values[:, n_a:])
    values[rng.random(values.shape) < nan_fraction] = np.nan
    if frames > 20:
        values[10:14, 3] = np.nan  # a run of missing frames
        values[:, 5] = np.nan  # a signal never available
    head = np.full(frames, 0.3)
    dist_m = values[:, n_a:] * 0.3
    return StateSignals(ANGLE_SIGNALS + NEAR_SIGNALS, values, fps, head, dist_m)


def _with_missing_signals(sig: StateSignals) -> StateSignals:
    """The same signals with some missing in every frame (the kernel leaves those fluents
    out): one direction of the head tilt pair, an elbow, and near distances in head-lengths
    whose metres stay known (so "touching" stays defined, as without ears on Vicon)."""
    values = sig.values.copy()
    names = list(sig.names)
    for name in ("neck_frontal", "left_elbow"):
        values[:, names.index(name)] = np.nan
    n_a = len(ANGLE_SIGNALS)
    values[:, n_a : n_a + 10] = np.nan
    dist_m = sig.distances_m.copy()
    dist_m[:, 5] = np.nan  # and one pair missing in both units
    values[:, n_a + 5] = np.nan
    return StateSignals(sig.names, values, sig.fps, sig.head_length_m, dist_m)


def _dummy_seq(frames: int, fps: float) -> PoseSequence:
    body = standing()
    return to_sequence(*([body] * frames), fps=fps)


@pytest.mark.parametrize("fps", [30.0, 60.0, 120.0, 100.0, 29.97, 15.0, 25.0])
def test_fast_equals_reference_on_random_walks(fps: float) -> None:
    frames = 300
    sig = _walk_signals(frames, fps, seed=int(fps * 100))
    ref = _assert_same(_dummy_seq(frames, fps), signals=sig)
    # the walk really exercises the temporal branches: products strictly between 0 and 1
    # (logs computed), exactly 0, exactly 1, and NaN all occur
    motion = ref[:, np.array(evaluate(_dummy_seq(1, fps)).temporal)]
    assert np.any((motion > 0.01) & (motion < 0.99))
    assert np.any(motion == 0.0) and np.any(motion == 1.0) and np.any(np.isnan(motion))


@pytest.mark.parametrize("fps", [30.0, 100.0])
def test_fast_equals_reference_over_several_blocks(fps: float) -> None:
    # The kernel works in blocks of 512 frames: a clip of three blocks and a part, with
    # distances that cross the touching threshold, so every block's touching states vary.
    frames = 3 * 512 + 77
    sig = _walk_signals(frames, fps, seed=5)
    ref = _assert_same(_dummy_seq(frames, fps), signals=sig)
    names = evaluate(_dummy_seq(1, fps)).state_names
    touching = ref[:, [i for i, name in enumerate(names) if name.endswith(".touching")]]
    for f0 in range(0, frames, 512):
        block = touching[f0 : f0 + 512]
        assert np.any(block == 1.0) and np.any(block == 0.0)


@pytest.mark.parametrize("frames", [1, 2, 3, 5, 6, 7])
@pytest.mark.parametrize("fps", [30.0, 120.0, 100.0, 10.0])
def test_fast_equals_reference_on_short_clips(frames: int, fps: float) -> None:
    sig = _walk_signals(frames, fps, seed=frames, nan_fraction=0.0)
    ref = _assert_same(_dummy_seq(frames, fps), signals=sig)
    temporal = evaluate(_dummy_seq(1, fps)).temporal
    lag = fps / 30.0
    if frames - 1 < lag - 1e-9:  # no frame has a full reference interval of history
        assert np.all(np.isnan(ref[:, temporal]))


@pytest.mark.parametrize("fps", [30.0, 100.0])
def test_fast_equals_reference_with_signals_missing_throughout(fps: float) -> None:
    sig = _with_missing_signals(_walk_signals(120, fps, seed=11))
    ref = _assert_same(_dummy_seq(120, fps), signals=sig)
    names = evaluate(_dummy_seq(1, fps)).state_names
    # what the kernel skipped is NaN, what it kept is not (touching on metres, the partner)
    assert np.all(np.isnan(ref[:, names.index("left_arm_bent.bent")]))
    near = [f"near:{a}~{b}" for a, b in (n.split("~") for n in NEAR_SIGNALS[:10])]
    assert np.all(np.isnan(ref[:, names.index(f"{near[0]}.near")]))
    assert not np.all(np.isnan(ref[:, names.index(f"{near[0]}.touching")]))
    assert np.all(np.isnan(ref[:, names.index(f"{near[5]}.touching")]))
    assert not np.all(np.isnan(ref[:, names.index("head_tilted_forward.tilted_forward")]))
    assert np.all(np.isnan(ref[:, names.index("head_tilted_forward.upright")]))


def test_all_joints_missing_gives_nan_everywhere() -> None:
    seq = PoseSequence(np.full((8, 33, 3), np.nan), _dummy_seq(1, 30.0).joint_names, 30.0)
    for backend in ("numba", "numpy"):
        assert np.all(np.isnan(evaluate(seq, backend=backend).confidence))


def test_signals_of_the_wrong_shape_are_a_data_error() -> None:
    seq = _dummy_seq(5, 30.0)
    sig = state_signals(seq)
    bad = StateSignals(sig.names, sig.values, sig.fps, sig.head_length_m, sig.distances_m[:, :3])
    with pytest.raises(DataError, match="shapes"):
        evaluate(seq, signals=bad)


def test_fast_equals_reference_with_other_parameters() -> None:
    table = DEFAULT_TABLE.with_overrides(
        {
            "epsilon": 0.05,
            "window": 3,
            "reference_fps": 25.0,
            "touching_m": 0.2,
            "fluents": {"arm_bent": {"lower": {"tau": "pi/2", "delta": "pi/6"}},
                        "near": {"motion": {"tau": 0.1, "delta": 0.02}}},
        }
    )  # fmt: skip
    for fps in (25.0, 100.0, 30.0):
        _assert_same(_dummy_seq(200, fps), table, _walk_signals(200, fps, seed=7))
    _assert_same(_dummy_seq(50, 30.0), FluentTable(window=1), _walk_signals(50, 30.0, seed=8))
    _assert_same(_dummy_seq(50, 30.0), FluentTable(window=9), _walk_signals(50, 30.0, seed=9))


def test_fast_equals_reference_on_a_posed_body_with_missing_joints() -> None:
    frames = []
    for k in range(40):
        body = standing()
        a = np.radians(4.0 * k)  # the left forearm swings up, the head nods
        body["left_wrist"] = body["left_elbow"] + 0.25 * np.array([0.0, -np.cos(a), np.sin(a)])
        body["nose"] = body["nose"] + np.array([0.0, -0.002 * k, 0.001 * k])
        frames.append(body)
    seq = to_sequence(*frames, fps=30.0)
    pos = seq.positions.copy()
    pos[5:8, 15, :] = np.nan  # left wrist lost for a few frames
    pos[:, 0, :] = np.nan  # no nose at all
    _assert_same(PoseSequence(pos, seq.joint_names, 30.0))


def test_fast_equals_reference_on_the_demo_clips() -> None:
    files = sorted(DEMO.glob("m0[17]_s*_e01.npz"))
    assert files
    for path in files:
        _assert_same(load_pose(path))


def test_fast_equals_reference_on_real_clips(shared_data: Path) -> None:
    seg = shared_data / "ui-prmd" / "data" / "Segmented Movements"
    name = "m01_s02_e01_positions.txt.gz"
    clips = [
        read_uiprmd_kinect(seg / "Kinect" / "Positions" / name),  # 30 Hz: lag 1
        read_uiprmd_vicon(seg / "Vicon" / "Positions" / name),  # ~100 Hz: fractional lag
    ]
    hdm = shared_data / "hdm05" / "train"
    amc = sorted(hdm.glob("*/HDM_bd_squat1Reps_*_120.amc"))[0]
    clips.append(read_asf_amc(amc.parent / "HDM_bd.asf", amc))  # 120 Hz: lag 4
    for seq in clips:
        ref = _assert_same(seq)
        assert np.isfinite(ref).any()
        # and at another rate: the same motion played at 24 Hz (lag 0.8)
        _assert_same(PoseSequence(seq.positions, seq.joint_names, 24.0))


def test_unknown_backend_is_a_config_error() -> None:
    seq = _dummy_seq(3, 30.0)
    with pytest.raises(ConfigError, match="backend"):
        evaluate(seq, backend="fortran")  # type: ignore[arg-type]


def test_results_share_no_writable_state() -> None:
    seq = _dummy_seq(4, 30.0)
    first = evaluate(seq, signals=state_signals(seq))
    with pytest.raises(ValueError):
        first.temporal[0] = not first.temporal[0]  # layout arrays are shared, so read-only
    assert first.confidence.flags.writeable


def _assert_same_signals(seq: PoseSequence) -> None:
    fast = state_signals(seq, backend="numba")
    ref = state_signals(seq, backend="numpy")
    assert fast.names == ref.names
    for a, b in ((fast.values, ref.values), (fast.head_length_m, ref.head_length_m),
                 (fast.distances_m, ref.distances_m)):  # fmt: skip
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
    ok = ~np.isnan(ref.values)
    n_angles = len(ANGLE_SIGNALS)
    # Distances: the same sums of squares, to a couple of ulps.
    np.testing.assert_allclose(fast.distances_m, ref.distances_m, rtol=1e-15, atol=0)
    np.testing.assert_allclose(fast.values[:, n_angles:], ref.values[:, n_angles:], rtol=1e-15)
    # Angles: arccos magnifies a last-bit difference in cos by 1/sin θ (and to √(2·ulp) ≈
    # 1.5e-8 at θ = 0 or π exactly), so the bound follows the conditioning.
    a, b = fast.values[:, :n_angles], ref.values[:, :n_angles]
    sin = np.sin(np.where(ok[:, :n_angles], b, 1.0))
    bound = np.where(sin > 1e-3, 1e-12, 2e-8)
    assert np.all(np.abs(a - b)[ok[:, :n_angles]] <= bound[ok[:, :n_angles]])


def test_fast_signals_equal_reference_on_synthetic_bodies() -> None:
    rng = np.random.default_rng(3)
    base = to_sequence(*([standing()] * 60), fps=30.0)
    pos = base.positions + np.cumsum(rng.normal(0.0, 0.01, base.positions.shape), axis=0)
    pos[7, 11, :] = np.nan  # a lost shoulder: the body frame is unavailable in that frame
    pos[9, 13, :] = pos[9, 11, :]  # a zero-length upper arm
    pos[:, 30, :] = np.nan  # a joint the skeleton lacks
    _assert_same_signals(PoseSequence(pos, base.joint_names, 30.0))
    _assert_same_signals(to_sequence(standing(), fps=30.0))  # exactly straight limbs (θ = π)


def test_fast_signals_equal_reference_on_real_clips(shared_data: Path) -> None:
    seg = shared_data / "ui-prmd" / "data" / "Segmented Movements"
    name = "m07_s01_e01_positions.txt.gz"
    _assert_same_signals(read_uiprmd_kinect(seg / "Kinect" / "Positions" / name))
    _assert_same_signals(read_uiprmd_vicon(seg / "Vicon" / "Positions" / name))
    amc = sorted((shared_data / "hdm05" / "train").glob("*/HDM_bd_squat1Reps_*_120.amc"))[0]
    _assert_same_signals(read_asf_amc(amc.parent / "HDM_bd.asf", amc))


def test_unknown_signal_backend_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match="backend"):
        state_signals(_dummy_seq(2, 30.0), backend="gpu")  # type: ignore[arg-type]


def test_a_distance_fluent_needs_a_joint_pair_signal() -> None:
    from dataclasses import replace

    specs = list(DEFAULT_TABLE.specs)
    specs[0] = replace(specs[0], kind="distance")  # left elbow angle as a "distance"
    table = replace(DEFAULT_TABLE, specs=tuple(specs))
    for backend in ("numba", "numpy"):
        with pytest.raises(ConfigError, match="not a near joint pair"):
            evaluate(_dummy_seq(3, 30.0), table, backend=backend)


@pytest.mark.parametrize("layout", ["C", "F", "strided", "float32"])
def test_fast_equals_reference_in_every_signal_layout(layout: str) -> None:
    # Signals in any layout give the reference's confidences: frames-major (state_signals,
    # what the kernel reads), signal-major, a view with gaps between columns, or float32
    # values (copied into the kernel's layout); over two blocks of 512 frames.
    for fps in (30.0, 100.0):
        sig = _walk_signals(600, fps, seed=21)
        values, dist_m = sig.values, sig.distances_m
        if layout == "F":
            values, dist_m = np.asfortranarray(values), np.asfortranarray(dist_m)
        elif layout == "strided":
            wide = np.full((values.shape[0], 2 * values.shape[1]), -7.0)
            wide[:, ::2] = values
            values = wide[:, ::2]
            dist_m = np.repeat(dist_m, 3, axis=0)[::3]
        elif layout == "float32":
            values, dist_m = values.astype(np.float32), dist_m.astype(np.float32)
        assert values.flags.c_contiguous == (layout in ("C", "float32"))
        _assert_same(
            _dummy_seq(600, fps),
            signals=StateSignals(sig.names, values, fps, sig.head_length_m, dist_m),
        )
