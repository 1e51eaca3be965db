"""The dtw-knn peer of `posecbr compare`: tslearn's DTW 1-NN on eight limb angles, checked
against hand-known angles and an independent dynamic-programming DTW written here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cbr.evaluation.peers import LIMB_ANGLES, DTWKNNPeer, angle_series
from tests.test_cbr_weights import _arm_clip, _elbow_clip

# under pytest-xdist the module runs on one worker: tslearn compiles its DTW (numba, 15-30 s)
# once per process, not once per test (once per machine since it is cached on disk:
# cbr.evaluation.peers.cache_tslearn_kernels)
pytestmark = pytest.mark.xdist_group("tslearn-peer")


def _dtw(a: np.ndarray, b: np.ndarray) -> float:
    """Textbook DTW: sqrt of the least sum of squared frame distances over warping paths."""
    n, m = len(a), len(b)
    cost = np.full((n + 1, m + 1), np.inf)
    cost[0, 0] = 0.0
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            d = float(((a[i - 1] - b[j - 1]) ** 2).sum())
            cost[i, j] = d + min(cost[i - 1, j], cost[i, j - 1], cost[i - 1, j - 1])
    return float(np.sqrt(cost[n, m]))


def test_angle_series_reads_the_known_elbow_angle() -> None:
    s = angle_series(_elbow_clip(90.0, frames=6), 10)
    assert s.shape == (10, 8)
    np.testing.assert_allclose(s[:, LIMB_ANGLES.index("left_elbow")], np.pi / 2, atol=1e-9)
    np.testing.assert_allclose(s[:, LIMB_ANGLES.index("right_elbow")], np.pi, atol=1e-9)


def test_dtw_knn_peer_is_the_nearest_clip_under_textbook_dtw() -> None:
    rng = np.random.default_rng(3)
    kinds = [("left", "sideways"), ("right", "sideways"), ("both", "forward")]
    X = [_arm_clip(a, m, "s1", rng) for a, m in kinds for _ in range(3)]
    y = np.array([f"{a} {m}" for a, m in kinds for _ in range(3)])
    Xt = [_arm_clip(a, m, "s2", rng) for a, m in kinds for _ in range(2)]
    peer = DTWKNNPeer(length=16).fit(X, y)
    got = peer.predict(Xt)
    train = [angle_series(s, 16) for s in X]
    want = [y[int(np.argmin([_dtw(angle_series(q, 16), t) for t in train]))] for q in Xt]
    assert list(got) == want
    assert list(got) == [f"{a} {m}" for a, m in kinds for _ in range(2)]


def test_spawned_fold_workers_give_the_tslearn_peer_the_serial_predictions(
    tmp_path: Path,
) -> None:
    """Fold workers are spawned, never forked (GNU OpenMP under the peer's neighbour search
    aborted forked children, a hang): with two workers the run finishes and the tslearn peer
    and the case base predict what a serial run in this process predicts."""
    import json
    import os
    import subprocess
    import sys

    from cbr.evaluation.compare import run_compare
    from cbr.evaluation.settings import CompareSettings
    from features.datasets import load_dataset

    demo = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
    labels, subjects = "deep_squat,standing_shoulder_abduction", "s01,s02"
    out = tmp_path / "j2.json"
    # two subjects: two folds, one for each of the two workers (the demo's third subject
    # was a third fold and a half more DTW for the peer, the same check)
    cmd = [
        sys.executable, "-m", "posecbr", "compare", str(demo), "--labels", labels,
        "--subjects", subjects, "--similarities", "euclidean", "--features", "fluents", "--no-dad",
        "--peers", "dtw-knn", "--explain", "0", "--jobs", "2", "--json", str(out),
    ]  # fmt: skip
    env = {**os.environ, "POSECBR_NO_PROGRESS": "1"}
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=240, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    parallel = {m["name"]: m for m in json.loads(out.read_text())["methods"]}
    settings = CompareSettings(
        similarities=("euclidean",), features=("fluents",), dad=False, peers=("dtw-knn",),
        explain=0, jobs=1,
    )  # fmt: skip
    clips = load_dataset(demo, labels=set(labels.split(",")), subjects=set(subjects.split(",")))
    assert len(clips) == 24  # 2 movements x 2 subjects x 6 clips
    serial = run_compare(clips, settings, source=str(demo)).results
    assert [m.name for m in serial.methods] == ["cbr fluents/euclidean", "dtw-knn"]
    for m in serial.methods:
        assert m.scores is not None and parallel[m.name]["status"] == "ok"
        assert parallel[m.name]["predictions"] == m.scores.predictions


_CACHED_DTW = """
import numpy as np
from tslearn.metrics import _dtw, cdist_dtw
from cbr.evaluation.peers import cache_tslearn_kernels
cache_tslearn_kernels()
d = cdist_dtw(np.ones((1, 5, 3)), np.zeros((1, 5, 3)))[0, 0]
print(d)
for kernel in (_dtw._njit_accumulated_matrix, _dtw._njit_dtw):
    print(sum(kernel.stats.cache_hits.values()), sum(kernel.stats.cache_misses.values()))
"""


def _cached_dtw() -> tuple[float, list[tuple[int, int]]]:
    """The distance of :data:`_CACHED_DTW` in a new process, and numba's cache hits and misses
    of its two kernels there: the accumulated cost matrix, and the DTW around it (a closure
    over tslearn's mask and matrix kernels)."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    out = subprocess.run([sys.executable, "-c", _CACHED_DTW], capture_output=True, text=True,
                         timeout=300, env=env, check=True).stdout.split()  # fmt: skip
    counts = [int(n) for n in out[1:]]
    return float(out[0]), list(zip(counts[::2], counts[1::2], strict=True))


def test_tslearn_dtw_is_kept_for_the_next_process() -> None:
    """tslearn compiled its DTW in every process (each spawned fold worker of ``compare
    --jobs`` too: 15-20 s of CPU each here); with numba's cache enabled for its kernels, a
    process loads both the dynamic programme (the accumulated cost matrix) and the DTW
    around it from disk. The DTW closes over other kernels, whose random per-process ids
    made its cache key new in every process: it was compiled again each time. A process
    that finds the cache cold compiles and leaves both for the next one, which must compile
    neither (the loaded DTW holds the matrix's code: that kernel is then not even called).
    The distance is unchanged: five frames one apart in each of three coordinates,
    sqrt(5 * 3) along the diagonal."""
    distance, counts = _cached_dtw()
    if any(misses for _, misses in counts):  # a cold cache (``-n 0``, a new machine)
        distance, counts = _cached_dtw()
    assert distance == pytest.approx(np.sqrt(15.0))
    (_, matrix_misses), (dtw_hits, dtw_misses) = counts
    assert (matrix_misses, dtw_misses) == (0, 0) and dtw_hits >= 1, counts
