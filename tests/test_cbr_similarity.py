"""Similarity measures against brute force and peer libraries (tslearn, iisignature)."""

from __future__ import annotations

import iisignature
import numpy as np
import pytest
from tslearn.metrics import dtw as tslearn_dtw
from tslearn.neighbors import KNeighborsTimeSeriesClassifier

from cbr.casebase import CaseBase
from cbr.evaluation.peers import cache_tslearn_kernels
from cbr.problem import FeatureConfig
from cbr.retrieve import retrieve
from cbr.reuse import reuse
from cbr.similarity import DTW, Euclidean, Signature, available_measures, get_measure
from cbr.similarity.dtw import dtw_all, knn_dtw
from features.errors import ConfigError

# tslearn's DTW compiled once per machine, not once per process (numba's disk cache)
cache_tslearn_kernels()


def _walks(rng: np.random.Generator, n: int, length: int, d: int) -> np.ndarray:
    return rng.normal(size=(n, length, d)).cumsum(axis=1)


def test_registry_names_and_errors() -> None:
    assert {"euclidean", "dtw", "signature"} <= set(available_measures())
    assert get_measure({"name": "dtw", "band": 0.2}) == DTW(band=0.2)
    with pytest.raises(ConfigError, match="unknown similarity 'cosine'"):
        get_measure("cosine")
    with pytest.raises(ConfigError, match="no parameter depht"):
        get_measure("signature", depht=3)


@pytest.mark.parametrize("radius", [0, 2, 5, 24])
def test_dtw_distances_equal_tslearn(radius: int) -> None:
    rng = np.random.default_rng(radius)
    cases = _walks(rng, 12, 24, 3)
    q = _walks(rng, 1, 24, 3)[0]
    m = DTW(radius=radius)
    got = m.distances(m.represent_query(q), m.build_index(m.represent(cases)))
    want = [
        tslearn_dtw(q, c, global_constraint="sakoe_chiba", sakoe_chiba_radius=radius) for c in cases
    ]
    np.testing.assert_allclose(got, want, rtol=1e-10)
    if radius == 0:  # no warping at all: plain Euclidean distance of the whole sequences
        np.testing.assert_allclose(got, np.sqrt(((cases - q) ** 2).sum(axis=(1, 2))))


@pytest.mark.parametrize("k", [1, 3, 10])
def test_pruned_dtw_returns_exactly_brute_force_neighbours(k: int) -> None:
    rng = np.random.default_rng(k)
    # clustered data (prototypes + noise) so that the lower bounds actually prune
    protos = _walks(rng, 6, 40, 4)
    cases = protos[rng.integers(0, 6, 600)] + rng.normal(scale=0.6, size=(600, 40, 4))
    cases[17] = cases[3]  # exact duplicates: ties must go to the lower index
    m = DTW(band=0.1)
    index = m.build_index(m.represent(cases))
    computed = []
    for t in range(25):
        q = protos[t % 6] + rng.normal(scale=0.6, size=(40, 4))
        if t == 0:
            q = cases[3].copy()
        qr = m.represent_query(q)
        brute = m.distances(qr, index)
        want = np.lexsort((np.arange(len(brute)), brute))[:k]
        idx, dist = m.nearest(qr, index, k)
        np.testing.assert_array_equal(idx, want)
        np.testing.assert_allclose(dist, brute[want], rtol=1e-12)
        _, _, n_dtw = knn_dtw(
            qr[0],
            qr[1],
            qr[2],
            index.cases,
            index.upper,
            index.lower,
            index.radius,
            k,
            index.seg_len,
            index.seg_up,
            index.seg_lo,
        )
        computed.append(n_dtw)
    # the cascade must skip most full DTW computations on clustered data
    assert np.mean(computed) < 0.5 * len(cases)


def test_dtw_all_matches_full_matrix_recurrence() -> None:
    # independent O(n^2) dynamic programme written from the textbook recurrence
    rng = np.random.default_rng(5)
    a, b = _walks(rng, 2, 9, 2)
    cost = ((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2)
    acc = np.full((10, 10), np.inf)
    acc[0, 0] = 0.0
    for i in range(1, 10):
        for j in range(1, 10):
            if abs(i - j) <= 2:
                acc[i, j] = cost[i - 1, j - 1] + min(
                    acc[i - 1, j], acc[i, j - 1], acc[i - 1, j - 1]
                )
    assert dtw_all(a, b[None], 2)[0] == pytest.approx(acc[9, 9], rel=1e-12)


def test_knn_dtw_predicts_like_tslearn_classifier() -> None:
    rng = np.random.default_rng(7)
    protos = _walks(rng, 4, 30, 3)
    y_proto = np.array(["a", "b", "c", "d"])
    pick = rng.integers(0, 4, 120)
    X = protos[pick] + rng.normal(scale=1.5, size=(120, 30, 3))
    y = y_proto[pick]
    Xtr, ytr, Xte = X[:80], y[:80], X[80:]
    for k in (1, 3, 5):
        peer = KNeighborsTimeSeriesClassifier(
            n_neighbors=k,
            metric="dtw",
            metric_params={"global_constraint": "sakoe_chiba", "sakoe_chiba_radius": 3},
        ).fit(Xtr, ytr)
        want = peer.predict(Xte)
        cb = CaseBase(FeatureConfig(), DTW(radius=3), Xtr, ytr, ("x", "y", "z"), ("x", "y", "z"))
        classes = np.unique(ytr)
        got = [reuse(retrieve(cb, q, k), classes, "uniform").label for q in Xte]
        np.testing.assert_array_equal(got, want)
        assert (want != y[80:]).sum() < len(want)  # the task is not trivial for both


def test_euclidean_on_binary_vectors_counts_mismatches() -> None:
    cases = np.array([[1, 0, 1, 1, 0], [0, 0, 0, 0, 0], [1, 1, 1, 1, 1]], dtype=float)
    q = np.array([1, 0, 0, 1, 0], dtype=float)
    m = Euclidean()
    d = m.distances(m.represent_query(q), m.build_index(m.represent(cases)))
    np.testing.assert_allclose(d**2, [1, 2, 3])  # mismatched features, counted by hand
    idx, _ = m.nearest(m.represent_query(q), m.build_index(m.represent(cases)), 2)
    assert list(idx) == [0, 1]


def test_signature_matches_iisignature_on_hand_augmented_path() -> None:
    rng = np.random.default_rng(3)
    x = rng.normal(size=(2, 7, 2))
    m = Signature(depth=3, time=True, lead_lag=False, basepoint=True)
    t = np.linspace(0, 1, 8)  # basepoint: the origin first, then the 7 samples
    want = np.stack(
        [iisignature.sig(np.column_stack([t, np.vstack([[0.0, 0.0], xi])]), 3) for xi in x]
    )
    np.testing.assert_allclose(m.represent(x), want, rtol=1e-12)
    plain = Signature(depth=2, time=False, basepoint=False).represent(x)
    np.testing.assert_allclose(plain, np.stack([iisignature.sig(xi, 2) for xi in x]), rtol=1e-12)


def test_basepoint_makes_held_levels_visible() -> None:
    # level 1 of a signature is the total increment: without a basepoint a state held at 0.9
    # all clip long looks like one never seen; with it, level 1 is the final value
    held = np.full((1, 10, 1), 0.9)
    assert Signature(depth=1, time=False, basepoint=False).represent(held)[0, 0] == 0.0
    assert Signature(depth=1, time=False, basepoint=True).represent(held)[0, 0] == 0.9


def test_lead_lag_signature_area_is_quadratic_variation() -> None:
    # For the lead-lag path of x, the level-2 terms satisfy S(lead,lag) - S(lag,lead) =
    # sum of squared increments (the quadratic variation), a classical identity.
    x = np.array([[1.0], [2.0], [4.0], [3.0]])
    sig = Signature(depth=2, time=False, lead_lag=True, basepoint=False).represent(x[None])[0]
    # channels (lead, lag): level 2 terms follow the 2 level-1 terms, order 11, 12, 21, 22
    s12, s21 = sig[2 + 1], sig[2 + 2]
    assert s12 - s21 == pytest.approx(1 + 4 + 1)
    # and the first level is the total increment of both channels
    np.testing.assert_allclose(sig[:2], [2.0, 2.0])


def test_lower_bounds_never_exceed_dtw() -> None:
    from cbr.similarity.dtw import _lb_keogh_rows, _lb_paa, envelope, segment_envelopes

    rng = np.random.default_rng(11)
    cases = _walks(rng, 200, 30, 3)
    q = _walks(rng, 1, 30, 3)[0]
    up, lo = envelope(cases, 3)
    seg_len, seg_up, seg_lo = segment_envelopes(up, lo, 4)
    assert list(seg_len) == [4] * 7 + [2]
    qm = np.stack(
        [
            q[a : a + n].mean(axis=0)
            for a, n in zip(np.cumsum([0, *seg_len[:-1]]), seg_len, strict=True)
        ]
    )
    exact = dtw_all(q, cases, 3)
    rows = np.empty(30)
    for c in range(200):
        keogh = _lb_keogh_rows(q, up[c], lo[c], rows)
        paa = _lb_paa(qm, seg_len, seg_up[c], seg_lo[c])
        assert paa <= keogh * (1 + 1e-12) + 1e-12
        assert keogh <= exact[c] * (1 + 1e-12) + 1e-12


def test_pruned_euclidean_returns_exactly_brute_force_neighbours() -> None:
    rng = np.random.default_rng(2)
    basis = rng.normal(size=(8, 300))
    cases = rng.normal(size=(3000, 8)) @ basis + rng.normal(scale=0.5, size=(3000, 300))
    m = Euclidean(prune_min_cases=1000, prune_dims=16)
    index = m.build_index(m.represent(cases))
    assert index.basis is not None  # the bound is in use
    for _ in range(20):
        q = rng.normal(size=8) @ basis + rng.normal(scale=0.5, size=300)
        true = np.sqrt(((cases - q) ** 2).sum(axis=1))  # float64, independent of the index
        want = np.argsort(true, kind="stable")[:7]
        idx, dist = m.nearest(m.represent_query(q), index, 7)
        np.testing.assert_array_equal(idx, want)
        np.testing.assert_allclose(dist, true[want], rtol=1e-4)
