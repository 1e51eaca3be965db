"""Hunt 38h: the slow paths of a long recording (a 10-minute, 120-fps mocap file segmented).

Three products and filters cost far more than their arithmetic, with the same answers:

- a recording's windows are solved 32 at a time, each block's queries multiplied with the
  case base in one product; on all of BLAS's threads a small product waited for a time slice
  at every hand-off (32 x 500 x 5600 took 476 ms on a busy 2-core machine, 27 ms on one
  thread): small products now run on one thread;
- the joints of a 20,000-frame piece rotated into the body's frame were one product of
  380,000 rows, which BLAS splits over its threads (630 ms busy, 42 ms on one): now in
  blocks of 1024 frames, each under the size BLAS splits;
- the running median of the counted angles ran SciPy's ``(width, 1)`` filter over the whole
  array (1 s for 72,000 samples x 8 angles) where its one-dimensional filter per column gives
  the same medians in a tenth of the time;
- the SVD that finds a recording's movement direction, ``(18,000, 8)`` at 30 samples a
  second, split over BLAS's threads (42 ms busy, 1.3 ms on one thread): now on one.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import cbr.similarity.euclidean as euclidean
import features.blas
from cbr.similarity import Euclidean
from features import body
from features import repetitions as reps


class _Pool:
    """A stand-in for threadpoolctl's BLAS controller: two threads, every change recorded."""

    def __init__(self) -> None:
        self.threads = 2
        self.set_to: list[int] = []

    def get_num_threads(self) -> int:
        return self.threads

    def set_num_threads(self, n: int) -> None:
        self.set_to.append(n)
        self.threads = n


def _brute(cases: np.ndarray, queries: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The k nearest by float64 distances of the float32 values, ties to the lower index."""
    c = cases.astype(np.float32).astype(np.float64)
    q = queries.astype(np.float32).astype(np.float64)
    d = np.sqrt(((q[:, None, :] - c[None, :, :]) ** 2).sum(axis=2))
    order = np.argsort(d, axis=1, kind="stable")[:, :k]
    return order, np.take_along_axis(d, order, axis=1)


@pytest.fixture
def pool(monkeypatch: pytest.MonkeyPatch) -> _Pool:
    fake = _Pool()
    monkeypatch.setattr(features.blas, "_POOLS", [fake])
    return fake


def _windows_like(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A case base of 80 windows of 5600 values (175 states x 32 frames, as CMU subject 13's
    two recordings make) and a block of 32 windows to solve."""
    rng = np.random.default_rng(seed)
    cases = rng.standard_normal((80, 5600))
    queries = cases[rng.integers(0, 80, 32)] + 0.3 * rng.standard_normal((32, 5600))
    return cases, queries


def test_a_small_block_of_queries_is_multiplied_on_one_blas_thread(pool: _Pool) -> None:
    cases, queries = _windows_like(0)
    m = Euclidean()
    got_i, got_d = m.nearest_many(queries, m.build_index(cases), 5)
    assert pool.set_to == [1, 2]  # one thread for the block's product, then given back
    assert pool.threads == 2
    want_i, want_d = _brute(cases, queries, 5)
    np.testing.assert_array_equal(got_i, want_i)
    np.testing.assert_allclose(got_d, want_d, rtol=1e-5)


def test_a_large_product_keeps_every_blas_thread_and_the_same_neighbours(
    pool: _Pool, monkeypatch: pytest.MonkeyPatch
) -> None:
    cases, queries = _windows_like(1)
    m = Euclidean()
    index = m.build_index(cases)
    small_i, small_d = m.nearest_many(queries, index, 5)
    pool.set_to.clear()
    monkeypatch.setattr(euclidean, "SMALL_PRODUCT", 0)  # every product counts as large
    large_i, large_d = m.nearest_many(queries, index, 5)
    assert pool.set_to == []
    np.testing.assert_array_equal(large_i, small_i)
    np.testing.assert_array_equal(large_d, small_d)


class _Recorder:
    """``numpy`` as :mod:`features.body` sees it, with each ``matmul``'s rows recorded."""

    def __init__(self) -> None:
        self.rows: list[int] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(np, name)

    def matmul(self, a: np.ndarray, b: np.ndarray, **kw: Any) -> np.ndarray:
        self.rows.append(len(a))
        return np.matmul(a, b, **kw)


def test_a_long_pieces_joints_are_rotated_in_blocks_under_blas_threading(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = np.random.default_rng(2)
    frames = 2500
    p = rng.standard_normal((frames, 33, 3))
    p[5, 3] = np.nan  # a missing joint stays missing
    angle = 0.7
    axes = np.array([
        [np.cos(angle), 0.0, -np.sin(angle)],
        [0.0, 1.0, 0.0],
        [np.sin(angle), 0.0, np.cos(angle)],
    ])  # fmt: skip
    origin, torso = np.array([0.1, 0.9, -0.2]), 0.5
    recorder = _Recorder()
    monkeypatch.setattr(body, "np", recorder)
    got = body.positions_in_frame(p, (origin, axes, torso))
    joints = len(body.POSITION_JOINTS)
    # 1024 + 1024 + 452 frames, each block at most 2^18 multiply-adds (OpenBLAS's size
    # from which it splits a product over its threads)
    assert recorder.rows == [1024 * joints, 1024 * joints, 452 * joints]
    assert all(r * 9 <= 1 << 18 for r in recorder.rows)
    # worked out joint by joint: (position - origin) along each axis, in torso lengths
    index = [body.JOINT_INDEX[j] for j in body.POSITION_JOINTS]
    want = np.empty((frames, joints, 3))
    for j, at in enumerate(index):
        d = p[:, at] - origin
        for a in range(3):
            want[:, j, a] = (
                d[:, 0] * axes[a, 0] + d[:, 1] * axes[a, 1] + d[:, 2] * axes[a, 2]
            ) / 0.5
    assert got.shape == (frames, 3 * joints)
    np.testing.assert_allclose(got, want.reshape(frames, -1), rtol=1e-12, atol=1e-12)
    assert np.isnan(got[5]).sum() == (3 if 3 in index else 0)


def test_the_running_median_filters_each_angle_alone_with_the_same_medians(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import scipy.ndimage

    calls: list[int] = []
    real = scipy.ndimage.median_filter

    def recorded(x: np.ndarray, **kw: Any) -> np.ndarray:
        calls.append(np.ndim(x))
        return np.asarray(real(x, **kw))

    monkeypatch.setattr(scipy.ndimage, "median_filter", recorded)
    rng = np.random.default_rng(3)
    x = np.round(rng.standard_normal((300, 4)) * 4) / 4  # ties among the values
    width, half = 7, 3
    got = reps._running_median(x, width)
    assert calls == [1, 1, 1, 1]  # one 1-D filter per angle
    # each sample's window cut to the samples the clip has
    want = np.array([np.median(x[max(0, i - half) : i + half + 1], axis=0) for i in range(300)])
    np.testing.assert_array_equal(got, want)


def test_the_running_median_of_an_array_with_nan_stays_scipys_two_dimensional_filter(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The callers give finite angles (gaps interpolated); NaN, where the two filters order
    it differently, keeps the filter of before."""
    import scipy.ndimage

    calls: list[int] = []
    real = scipy.ndimage.median_filter
    monkeypatch.setattr(
        scipy.ndimage,
        "median_filter",
        lambda x, **kw: calls.append(np.ndim(x)) or np.asarray(real(x, **kw)),
    )
    x = np.arange(40.0).reshape(20, 2)
    x[7, 1] = np.nan
    got = reps._running_median(x, 5)
    assert calls == [2]
    want = [np.median(x[max(0, i - 2) : i + 3, 0]) for i in range(20)]  # cut at the ends
    np.testing.assert_array_equal(got[:, 0], want)


def test_the_running_median_equals_scipys_whole_array_filter_on_moving_angles() -> None:
    """The counted angles of a moving clip are the same through the per-angle median as
    through SciPy's whole-array filter (the function of before, run here as reference)."""
    from scipy.ndimage import median_filter

    t = np.arange(3000) / 120.0
    rng = np.random.default_rng(4)
    x = np.stack([np.sin(2 * np.pi * t / p) for p in (1.1, 1.7, 2.3)], axis=1)
    x += 0.05 * rng.standard_normal(x.shape)
    width = 25
    before = median_filter(x, size=(width, 1), mode="nearest")
    for i in range(width // 2):
        before[i] = np.median(x[: i + width // 2 + 1], axis=0)
        before[len(x) - 1 - i] = np.median(x[len(x) - 1 - i - width // 2 :], axis=0)
    np.testing.assert_array_equal(reps._running_median(x, width), before)


def test_a_long_recordings_movement_direction_is_found_on_one_blas_thread(
    monkeypatch: pytest.MonkeyPatch,
) -> None:

    fake = _Pool()
    monkeypatch.setattr(features.blas, "_POOLS", [fake])
    rng = np.random.default_rng(5)
    t = np.arange(18000) / 30.0
    along = np.array([0.6, 0.0, -0.8, 0.0, 0.0, 0.0, 0.0, 0.0])  # the movement's direction
    x = np.sin(2 * np.pi * t / 1.5)[:, None] * along + 0.01 * rng.standard_normal((18000, 8))
    got = reps.movement_direction(x)
    assert fake.set_to == [1, 2] and fake.threads == 2
    assert abs(float(got @ along)) > 0.999  # the direction it moves along, either sign
    # a clip's few hundred samples too (hunt 52e: on a busy machine BLAS's threads cost a
    # small SVD hundreds of times its arithmetic)
    fake.set_to.clear()
    short = reps.movement_direction(x[:300])
    assert fake.set_to == [1, 2]
    assert abs(float(short @ along)) > 0.99


def test_the_pose_models_are_loaded_once_per_process_for_every_estimator(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``posecbr train`` of a folder of videos made a PoseEstimator per video, each loading
    and optimising both BlazePose models again; now they share one session per model."""
    pytest.importorskip("onnxruntime")
    from features.pose_estimation import PoseEstimator, model

    made: list[str] = []
    real = model.ort.InferenceSession

    def counted(path: str, **kw: Any) -> Any:
        made.append(path)
        return real(path, **kw)

    monkeypatch.setattr(model, "_SESSIONS", {}, raising=False)
    monkeypatch.setattr(model.ort, "InferenceSession", counted)
    first, second = PoseEstimator(threads=1), PoseEstimator(threads=1)
    assert sorted(made) == sorted([str(model.DETECTOR_PATH), str(model.LANDMARK_PATH)])
    assert first._detector is second._detector and first._landmarker is second._landmarker
    # another thread count is another session; the estimators' own state stays their own
    PoseEstimator(threads=2)
    assert len(made) == 4
    assert first._image_filter is not second._image_filter
