"""The fast search paths return exactly the brute-force neighbours on hard data as well as easy.

Euclidean: the plain pass, the pruned search (and its fall-back to the plain pass when the
bound prunes nothing) and the batched matrix product must give what ``distances`` +
``smallest_k`` give (ties -> lower index), and the neighbours a peer finds (scikit-learn's
brute force in float64, FAISS IndexFlatL2). DTW: the cascade, its fall-back scan on threads
and the threaded brute force must agree with the single-threaded brute force to the bit, and
with dtaidistance's distances.
"""

from __future__ import annotations

import numpy as np
import pytest

from cbr.similarity import DTW, Euclidean
from cbr.similarity.base import smallest_k
from cbr.similarity.dtw import dtw_all, knn_dtw
from cbr.similarity.euclidean import FALLBACK
from features.errors import InputError


def _unstructured(rng: np.random.Generator, n: int, dims: int) -> tuple[np.ndarray, np.ndarray]:
    return rng.random((n, dims), dtype=np.float32), rng.random((8, dims))


def _clustered(rng: np.random.Generator, n: int, dims: int) -> tuple[np.ndarray, np.ndarray]:
    centres = rng.random((10, dims)) * 4.0
    cases = centres[rng.integers(0, 10, n)] + rng.normal(scale=0.1, size=(n, dims))
    queries = centres[rng.integers(0, 10, 8)] + rng.normal(scale=0.1, size=(8, dims))
    return cases.astype(np.float32), queries


@pytest.fixture(scope="module", params=["unstructured", "clustered"])
def euclidean_case(request: pytest.FixtureRequest) -> tuple[str, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    make = _unstructured if request.param == "unstructured" else _clustered
    cases, queries = make(rng, 6000, 200)
    cases[4001] = cases[17]  # a duplicate: the tie goes to the lower index
    queries = np.vstack([queries, cases[17].astype(np.float64)])
    return request.param, cases, queries


@pytest.mark.parametrize("blas_min", [0, 1 << 40])  # the plain pass by BLAS, or by the kernel
def test_euclidean_every_path_equals_brute_force(
    euclidean_case: tuple[str, np.ndarray, np.ndarray],
    blas_min: int,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr("cbr.similarity.euclidean._BLAS_MIN", blas_min)
    kind, cases, queries = euclidean_case
    m = Euclidean(prune_min_cases=1000)
    pruned = m.build_index(cases)
    plain = Euclidean(prune_min_cases=10**9).build_index(cases)
    assert pruned.basis is not None and plain.basis is None
    for q in queries:
        qr = m.represent_query(q)
        want_i, want_d = smallest_k(m.distances(qr, plain), 6)
        for index in (pruned, plain):
            got_i, got_d = m.nearest(qr, index, 6)
            np.testing.assert_array_equal(got_i, want_i)
            np.testing.assert_array_equal(got_d, want_d)
    assert list(smallest_k(m.distances(m.represent_query(queries[-1]), plain), 2)[0]) == [17, 4001]
    share = pruned.pruning[0]
    if kind == "clustered":  # the bound prunes: the search stayed pruned
        assert share < 0.2
    else:  # nothing pruned: it fell back to the plain pass and stopped trying
        assert share == 1.0


def test_euclidean_pruned_bound_in_float32_is_exact_when_the_bound_is_tight() -> None:
    # cases and queries in a 6-dimensional subspace (away from the origin): the PCA bound
    # equals the distance up to rounding, so a bound computed in float32 without its rounding
    # allowance prunes true neighbours (32 of these 40 queries wrong, tried); the pruned
    # search must equal the brute force
    rng = np.random.default_rng(11)
    span = np.linalg.qr(rng.normal(size=(120, 6)))[0]
    cases = (50.0 + rng.normal(size=(8000, 6)) @ span.T).astype(np.float32)
    queries = 50.0 + rng.normal(size=(40, 6)) @ span.T
    m = Euclidean(prune_min_cases=1000)
    pruned = m.build_index(cases)
    plain = Euclidean(prune_min_cases=10**9).build_index(cases)
    assert pruned.basis is not None
    for q in queries:
        qr = m.represent_query(q)
        want_i, want_d = smallest_k(m.distances(qr, plain), 5)
        got_i, got_d = m.nearest(qr, pruned, 5)
        np.testing.assert_array_equal(got_i, want_i)
        np.testing.assert_array_equal(got_d, want_d)
    assert pruned.pruning[0] < FALLBACK  # the bound was computed for every query and pruned


def test_euclidean_batch_equals_single_queries(
    euclidean_case: tuple[str, np.ndarray, np.ndarray],
) -> None:
    _, cases, queries = euclidean_case
    m = Euclidean(prune_min_cases=1000)
    for index in (m.build_index(cases), Euclidean(prune_min_cases=10**9).build_index(cases)):
        many_i, many_d = m.nearest_many(queries, index, 5)
        assert many_i.shape == many_d.shape == (len(queries), 5)
        for j, q in enumerate(queries):
            one_i, one_d = m.nearest(m.represent_query(q), index, 5)
            np.testing.assert_array_equal(many_i[j], one_i)
            np.testing.assert_array_equal(many_d[j], one_d)


@pytest.mark.parametrize("blas_min", [0, 1 << 40])  # the plain pass by BLAS, or by the kernel
def test_euclidean_distance_of_a_near_copy_far_from_the_origin_is_exact(
    blas_min: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Cases near 1000 in every dimension, queries a case itself and a case moved by 0.01 in
    ten dimensions: the distances are the float64 distances of the float32 values (0.0 for
    the case itself) by every path. Before, the identity |c|^2 - 2 c.q + |q|^2 with a float32
    dot product erred by some 2^-24 D |c|^2 = 2e3 in d^2 here: every near distance was noise,
    and a clip's distance to its own case 0.0 or 0.0022 by the CPU's vector width."""
    monkeypatch.setattr("cbr.similarity.euclidean._BLAS_MIN", blas_min)
    rng = np.random.default_rng(11)
    cases = (1000.0 + rng.random((3000, 200))).astype(np.float32)
    moved = cases[5].copy()
    moved[:10] += np.float32(0.01)
    queries = np.vstack([cases[7], moved]).astype(np.float64)
    want = [
        np.sqrt(((cases.astype(np.float64) - q) ** 2).sum(axis=1)) for q in queries
    ]  # float64 differences of the float32 values
    assert want[0][7] == 0.0 and 0.03 < want[1][5] < 0.033  # 0.01 sqrt(10), float32-rounded
    m = Euclidean(prune_min_cases=1000)
    indexes = [m.build_index(cases), Euclidean(prune_min_cases=10**9).build_index(cases)]
    for q, w in zip(queries, want, strict=True):
        qr = m.represent_query(q)
        np.testing.assert_allclose(m.distances(qr, indexes[1]), w, rtol=1e-12, atol=0)
        for index in indexes:
            got_i, got_d = m.nearest(qr, index, 3)
            np.testing.assert_array_equal(got_i, np.argsort(w, kind="stable")[:3])
            np.testing.assert_allclose(got_d, np.sort(w)[:3], rtol=1e-12, atol=0)
    many_i, many_d = m.nearest_many(queries, indexes[0], 1)
    assert list(many_i[:, 0]) == [7, 5] and many_d[0, 0] == 0.0
    np.testing.assert_allclose(many_d[1, 0], want[1][5], rtol=1e-12)


def test_euclidean_neighbours_equal_scikit_learn_brute_force(
    euclidean_case: tuple[str, np.ndarray, np.ndarray],
) -> None:
    from sklearn.neighbors import NearestNeighbors

    _, cases, queries = euclidean_case
    queries = queries[:-1]  # the duplicate has a tie that sklearn may order either way
    q32 = queries.astype(np.float32).astype(np.float64)  # the measure compares float32 values
    peer = NearestNeighbors(n_neighbors=5, algorithm="brute").fit(cases.astype(np.float64))
    want_d, want_i = peer.kneighbors(q32)
    m = Euclidean(prune_min_cases=1000)
    got_i, got_d = m.nearest_many(queries, m.build_index(cases), 5)
    np.testing.assert_array_equal(got_i, want_i)
    # both within float64 rounding of the float32 values' distances: scikit-learn's
    # |c|^2 - 2 c.q + |q|^2 in float64, the measure's squared differences summed in float64
    scale = np.linalg.norm(cases, axis=1).max() ** 2 + (q32**2).sum(axis=1)
    assert np.all(np.abs(got_d**2 - want_d**2) <= 1e-12 * scale[:, None])


def test_euclidean_neighbours_equal_faiss_flat_index(
    euclidean_case: tuple[str, np.ndarray, np.ndarray],
) -> None:
    faiss = pytest.importorskip("faiss", reason="FAISS (faiss-cpu, extra 'bench') not installed")
    _, cases, queries = euclidean_case
    queries = queries[:-1]
    peer = faiss.IndexFlatL2(cases.shape[1])
    peer.add(cases)
    want_d, want_i = peer.search(queries.astype(np.float32), 5)
    m = Euclidean(prune_min_cases=1000)
    index = m.build_index(cases)
    for j, q in enumerate(queries):
        got_i, got_d = m.nearest(m.represent_query(q), index, 5)
        np.testing.assert_array_equal(got_i, want_i[j])
        bound = 2 * 200 * 2.0**-24 * np.linalg.norm(cases, axis=1).max() * np.linalg.norm(q)
        assert np.all(np.abs(got_d**2 - want_d[j]) <= 2 * bound)  # both sides in float32


def _dtw_data(kind: str, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    shape = (n + 6, 32, 4)
    if kind == "noise":  # no bound is tight: the cascade falls back to the threaded scan
        x = rng.normal(size=shape)
    elif kind == "walks":
        x = np.cumsum(rng.normal(size=shape), axis=1)
    else:
        protos = np.cumsum(rng.normal(size=(5, 32, 4)), axis=1)
        x = protos[rng.integers(0, 5, n + 6)] + rng.normal(scale=0.5, size=shape)
    x[9] = x[2]  # a duplicate: the tie goes to the lower index
    return x[:n], np.vstack([x[n:], x[2:3]])


@pytest.mark.parametrize("kind", ["noise", "walks", "clustered"])
@pytest.mark.parametrize("jobs", [1, 2])
def test_dtw_every_path_equals_single_threaded_brute_force(kind: str, jobs: int) -> None:
    rng = np.random.default_rng(11)
    cases, queries = _dtw_data(kind, rng, 1500)
    m = DTW(radius=3, jobs=jobs)
    index = m.build_index(m.represent(cases))
    for q in queries:
        qr = m.represent_query(q)
        brute = np.sqrt(dtw_all(qr[0], index.cases, 3, jobs=1))
        np.testing.assert_array_equal(m.distances(qr, index), brute)  # threaded brute force
        want_i, want_d = smallest_k(brute, 7)
        got_i, got_d = m.nearest(qr, index, 7)
        np.testing.assert_array_equal(got_i, want_i)
        np.testing.assert_array_equal(got_d, want_d)
    assert list(m.nearest(m.represent_query(queries[-1]), index, 2)[0]) == [2, 9]


def test_dtw_falls_back_on_noise_and_prunes_on_walks() -> None:
    rng = np.random.default_rng(12)
    computed = {}
    for kind in ("noise", "walks"):
        cases, queries = _dtw_data(kind, rng, 1500)
        m = DTW(radius=3)
        index = m.build_index(m.represent(cases))
        qr = m.represent_query(queries[0])
        args = (qr[0], qr[1], qr[2], index.cases, index.upper, index.lower, 3, 5)
        segs = (index.seg_len, index.seg_up, index.seg_lo)
        computed[kind] = knn_dtw(*args, *segs, jobs=2)[2]
    assert computed["walks"] < 0.2 * 1500  # the bounds prune random walks
    assert computed["noise"] > 0.5 * 1500  # noise: nearly every case needs its DTW


def test_dtw_distances_equal_dtaidistance() -> None:
    dtw_ndim = pytest.importorskip(
        "dtaidistance.dtw_ndim", reason="dtaidistance (extra 'bench') not installed"
    )
    rng = np.random.default_rng(13)
    cases, queries = _dtw_data("noise", rng, 200)
    m = DTW(radius=3, jobs=2)
    index = m.build_index(m.represent(cases))
    for q in queries[:3]:
        series = np.concatenate([q[None], cases])
        # dtaidistance's window w allows |i - j| < w: the band radius + 1
        peer = dtw_ndim.distance_matrix_fast(
            series, window=4, block=((0, 1), (1, len(series))), compact=True, parallel=False
        )
        np.testing.assert_allclose(m.distances(m.represent_query(q), index), peer, rtol=1e-10)


def _quantized_answer(index: object, query: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The quantized-bound search itself (``nearest`` reaches it only once the PCA bound has
    stopped pruning), on the float32 query the measure compares."""
    from cbr.similarity.euclidean import _quantized_search

    q32, q_sq = Euclidean()._query(query)
    return _quantized_search(index, q32, q_sq, k)  # type: ignore[arg-type]


def _adversarial(kind: str, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(cases ``(6000, 64)`` float32, queries ``(12, 64)``) the quantized bound must survive."""
    n, dims = 6000, 64
    if kind == "duplicates":  # 40 distinct rows, each ~150 times: ties everywhere
        distinct = rng.random((40, dims))
        cases = distinct[rng.integers(0, 40, n)]
        queries = np.vstack([distinct[:6], rng.random((6, dims))])
    elif kind == "huge-offset":  # values near 1e6 differing by ~1: float32 rounding dominates
        cases = 1e6 + rng.random((n, dims))
        queries = 1e6 + rng.random((12, dims))
    elif kind == "tiny":  # values ~1e-30: float32 products underflow
        cases = 1e-30 * rng.random((n, dims))
        queries = 1e-30 * rng.random((12, dims))
    elif kind == "one-wide-dimension":  # one dimension 10^4 wide sets a coarse grid for all
        cases = rng.random((n, dims))
        cases[:, 5] *= 1e4
        queries = rng.random((12, dims))
        queries[:, 5] *= 1e4
    else:  # "outside": queries far outside every case's range: clipped codes
        cases = rng.random((n, dims))
        queries = np.vstack([rng.random((6, dims)) * 3.0 - 1.0, rng.random((6, dims)) + 5.0])
    return cases.astype(np.float32), queries


@pytest.mark.parametrize("kind", ["unstructured", "clustered"])
def test_euclidean_quantized_bound_prunes_and_equals_brute_force(kind: str) -> None:
    rng = np.random.default_rng(9)
    make = _unstructured if kind == "unstructured" else _clustered
    cases, queries = make(rng, 20000, 120)
    cases[15000] = cases[77]  # a duplicate: the tie goes to the lower index
    queries = np.vstack([queries, cases[77].astype(np.float64)])
    m = Euclidean(prune_min_cases=1000)
    index = m.build_index(cases)
    plain = Euclidean(prune_min_cases=10**9).build_index(cases)
    for q in queries:
        qr = m.represent_query(q)
        want_i, want_d = smallest_k(m.distances(qr, plain), 5)
        got_i, got_d = _quantized_answer(index, qr, 5)
        np.testing.assert_array_equal(got_i, want_i)
        np.testing.assert_array_equal(got_d, want_d)
    assert list(_quantized_answer(index, m.represent_query(queries[-1]), 2)[0]) == [77, 15000]
    # uniform data: the 5th neighbour lies far below the bulk, nearly every case is pruned
    # (the 4-bit codes let through ~2 % at 20,000 cases); clustered: the nine clusters the
    # query is not in (nine tenths of the cases) are pruned
    assert index.codes is not None
    assert index.codes.pruning[0] < (0.05 if kind == "unstructured" else 0.1)


def test_quantization_error_norm_is_never_below_the_exact_one() -> None:
    from cbr.similarity.grid_codes import _quantize

    rng = np.random.default_rng(2)
    x = (1e6 + rng.random((500, 50)) * 1e3).astype(np.float32)
    base = x.astype(np.float64).min(axis=0)
    step = float((x.astype(np.float64).max(axis=0) - base).max()) / 255.0
    codes, err = _quantize(x, base, step)
    # the grid points and their distances in extended precision, from the codes alone
    grid = base.astype(np.longdouble) + np.longdouble(step) * codes.astype(np.longdouble)
    exact = np.sqrt(((x.astype(np.longdouble) - grid) ** 2).sum(axis=1))
    assert np.all(err >= exact)
    assert np.all(err <= exact * (1 + 1e-9) + 1e-6)  # raised by rounding, not by much
    assert np.all(np.abs(x.astype(np.float64) - grid.astype(np.float64)) <= step / 2 * (1 + 1e-9))


def _pca_answer(index: object, query: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The PCA-codes search itself on the float32 query the measure compares, never handing
    over to another pass (every row may get its distance), so its bound decides alone."""
    import cbr.similarity.euclidean as euclidean

    q32, q_sq = Euclidean()._query(query)
    idx, dist, count = euclidean._codes_search(index, index.pca, q32, q_sq, k, len(index.rows))  # type: ignore[arg-type, attr-defined]
    assert count >= k
    return idx, dist


@pytest.mark.parametrize("bound", ["quantized", "quantized-8-bit", "pca"])
@pytest.mark.parametrize(
    "kind",
    ["duplicates", "huge-offset", "tiny", "one-wide-dimension", "outside"],
)
def test_euclidean_bound_equals_brute_force_on_adversarial_data(
    kind: str, bound: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the whole rows' codes (quantized pass: 4-bit on these unstructured rows, or the 8-bit
    # codes it uses above 257 dimensions) and the PCA codes, each deciding alone
    if bound == "quantized-8-bit":
        monkeypatch.setattr("cbr.similarity.euclidean.MAX_DIMS", 0)
    quantized = bound.startswith("quantized")
    cases, queries = _adversarial(kind, np.random.default_rng(5 if quantized else 6))
    m = Euclidean(prune_min_cases=1000)
    index = m.build_index(cases)
    plain = Euclidean(prune_min_cases=10**9).build_index(cases)
    assert (index.codes if quantized else index.pca) is not None
    answer = _quantized_answer if quantized else _pca_answer
    for q in queries:
        qr = m.represent_query(q)
        want_i, want_d = smallest_k(m.distances(qr, plain), 7)
        got_i, got_d = answer(index, qr, 7)
        np.testing.assert_array_equal(got_i, want_i)
        np.testing.assert_array_equal(got_d, want_d)
        if quantized:
            np.testing.assert_array_equal(m.nearest(qr, index, 7)[0], want_i)
    if quantized:
        assert index.codes.pruning[1] >= len(queries)  # the bound ran for every query


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_euclidean_refuses_rows_and_queries_that_are_not_finite(bad: float) -> None:
    # a missing value is not a neighbour at distance 0: the index and the query refuse it
    rng = np.random.default_rng(9)
    cases = rng.random((3000, 40)).astype(np.float32)
    m = Euclidean(prune_min_cases=1000)
    for exact in (False, True):
        broken = cases.copy()
        broken[[17, 2048], 3] = bad
        with pytest.raises(InputError, match=r"case rows 17, 2048 hold NaN or inf"):
            Euclidean(prune_min_cases=1000, exact=exact).build_index(broken)
    index = m.build_index(cases)
    query = cases[5].astype(np.float64)
    query[0] = bad
    with pytest.raises(InputError, match="the query holds NaN or inf"):
        m.nearest(query, index, 5)
    with pytest.raises(InputError, match="queries 1 hold NaN or inf"):
        m.nearest_many(np.vstack([cases[4], query]), index, 5)


def test_euclidean_pca_codes_bound_never_exceeds_the_distance() -> None:
    # random walks: leading components hundreds of times wider than the last ones, so the
    # grid gives the narrow dimensions finer steps (several weights); the squared bound of
    # every row against a query, from the kernel, against the distance in extended precision
    import cbr.similarity.bounded_search as bounded_search
    from cbr.similarity.grid_codes import BLOCK

    rng = np.random.default_rng(8)
    cases = np.cumsum(rng.normal(size=(3000, 90)), axis=1).astype(np.float32)
    query = np.cumsum(rng.normal(size=90)).astype(np.float32)
    index = Euclidean(prune_min_cases=1000).build_index(cases)
    pca = index.pca
    assert pca is not None and len(set(pca.weights.tolist())) > 1
    qp, r_q, q_norm = bounded_search._project_query(query, pca.mean, pca.basis)
    qc, qc_sq, e_q = bounded_search._grid_codes(qp, pca.base, pca.steps, pca.weights)
    dots = np.empty(BLOCK, dtype=np.int32)
    lb = np.empty(BLOCK, dtype=np.float32)
    bounds = []
    query32 = (qc_sq, e_q, r_q, pca.step * (1 - 1e-15))
    for b in range(pca.codes.shape[0]):
        bounded_search._block_dots(pca.codes, b, qc, dots)
        bounded_search._block_bounds(dots, pca.code_sq, pca.errs, pca.resid, b * BLOCK, query32, lb)
        bounds.append(lb.astype(np.float64))
    row = pca.order[: len(cases)]  # the case stored at each place of the codes
    bound = np.empty(len(cases))
    bound[row] = np.concatenate(bounds)[: len(cases)]
    exact = ((cases.astype(np.longdouble) - query.astype(np.longdouble)) ** 2).sum(axis=1)
    scale = (pca.top_norm + q_norm) ** 2
    assert np.all(bound <= exact.astype(np.float64) + 1e-6 * scale)  # the docstring's claim
    assert np.median(bound / exact.astype(np.float64)) > 0.5  # and a bound that prunes
    # each block's bound (its box of codes and its ball) is under every one of its cases'
    block_bound, visit = bounded_search._block_order(
        pca.kernel_args[2], query, qc, e_q, r_q, pca.step * (1 - 1e-15)
    )
    nearest_in_block = np.minimum.reduceat(
        exact[row].astype(np.float64), np.arange(0, len(row), BLOCK)
    )
    assert np.all(block_bound <= nearest_in_block + 1e-6 * scale)
    assert np.all(np.diff(block_bound[visit]) >= 0)  # blocks visited nearest first
    assert np.median(block_bound / nearest_in_block) > 0.3  # and bounds that prune


def test_euclidean_blocks_hold_similar_cases_only_where_that_makes_them_tight() -> None:
    # 40 tight clusters of 100 cases in shuffled order: the stored blocks (64 cases) each
    # hold one or two clusters and the search visits them nearest first; uniform cases: no
    # block could be tight, the cases keep their own order and the blocks have no boxes;
    # both answer exactly what the brute force does
    rng = np.random.default_rng(11)
    labels = rng.permutation(np.repeat(np.arange(40), 100))
    centres = rng.random((40, 60)) * 3.0
    clustered = (centres[labels] + rng.normal(scale=0.05, size=(4000, 60))).astype(np.float32)
    uniform = rng.random((4000, 60), dtype=np.float32)
    m = Euclidean(prune_min_cases=1000)
    for cases, tight in ((clustered, True), (uniform, False)):
        index = m.build_index(cases)
        stored = index.pca.order[: len(cases)]
        assert sorted(stored.tolist()) == list(range(len(cases)))  # every case once
        radii = index.pca.boxes[-1]
        if tight:
            per_block = [len(set(labels[stored[a : a + 64]])) for a in range(0, 4000, 64)]
            assert np.median(per_block) <= 2 and len(radii) == len(per_block)
        else:
            assert np.array_equal(stored, np.arange(len(cases))) and len(radii) == 0
        plain = Euclidean(prune_min_cases=10**9).build_index(cases)
        for q in np.vstack([cases[[3, 2500]] + 0.01, rng.random((3, 60)) * 3.0]):
            qr = m.represent_query(q)
            want_i, want_d = smallest_k(m.distances(qr, plain), 5)
            got_i, got_d = m.nearest(qr, index, 5)
            np.testing.assert_array_equal(got_i, want_i)
            np.testing.assert_array_equal(got_d, want_d)


def _decoded_nibbles(codes: object, n: int, m: int) -> np.ndarray:
    """Each case's 4-bit codes ``(n, m)`` read back from the documented layout: blocks of
    64 cases, dimension-major, case ``t``'s code in the low nibble of byte ``t`` and case
    ``32 + t``'s in the high one."""
    raw = np.asarray(codes).reshape(-1, m, 32)
    cells = np.concatenate([raw & 15, raw >> 4], axis=2)  # (blocks, m, 64)
    return cells.transpose(0, 2, 1).reshape(-1, m)[:n]


def test_nibble_codes_hold_each_value_in_its_cell_and_bound_every_distance() -> None:
    # uniform rows (some on every cell edge) plus a constant column and one 1e4 wide: every
    # value inside its decoded cell, e_x never below the exact |x - x_hat|, the table sums
    # of both kernels equal a plain numpy sum of the tables, and sqrt(S / s) - e_x never
    # above the true distance
    from cbr.similarity import nibbles

    rng = np.random.default_rng(12)
    n, m = 1000, 70
    cases = rng.random((n, m)).astype(np.float32)
    cases[:17] = (np.arange(17) / 16.0)[:, None]  # every value on a cell edge of [0, 1]
    cases[:, 3] = 0.25
    cases[:, 9] *= 1e4
    codes = nibbles.nibble_codes(cases)
    assert codes is not None and codes.codes.nbytes == 16 * m * 32  # 16 blocks, 4 bits a value
    cells = _decoded_nibbles(codes.codes, n, m).astype(np.int64)
    cols = np.arange(m)
    assert np.all(codes.edges[cols, cells] <= cases) and np.all(
        cases <= codes.edges[cols, cells + 1]
    )
    centre = codes.centres[cols, cells].astype(np.longdouble)
    exact_err = np.sqrt(((cases.astype(np.longdouble) - centre) ** 2).sum(axis=1))
    assert np.all(codes.errs >= exact_err) and np.all(codes.errs <= exact_err * (1 + 1e-6))
    kernels = [False, True] if nibbles.HAS_SHUFFLE else [False]
    for q in rng.random((5, m)).astype(np.float32) * np.where(cols == 9, 1e4, 1.0):
        luts, scale = nibbles.nibble_tables(q, codes.centres)
        table = luts.reshape(m, 32)[:, :16].astype(np.int64)
        want = table[cols, cells].sum(axis=1)
        for shuffle in kernels:
            got = _nibble_sums(codes, luts, shuffle)[:n]
            np.testing.assert_array_equal(got, want)
        true = np.sqrt(((cases.astype(np.longdouble) - q.astype(np.longdouble)) ** 2).sum(axis=1))
        bound = np.sqrt(want / scale) - codes.errs
        assert np.all(bound <= true)
        assert np.median(bound / true.astype(np.float64)) > 0.8  # and a bound that prunes


def _nibble_sums(codes: object, luts: np.ndarray, shuffle: bool) -> np.ndarray:
    """Every case's table sum from one of the two kernels, block by block."""
    from cbr.similarity import nibbles

    m = len(luts) // 32
    blocks = len(codes.codes) // (m * 32)  # type: ignore[attr-defined]
    sums = np.empty(64, dtype=np.uint16)
    out = []
    for b in range(blocks):
        kernel = nibbles.shuffle_mask if shuffle else nibbles.scalar_block_mask
        mask = kernel(codes.codes, b * m * 32, luts, m, 65535, sums)  # type: ignore[attr-defined]
        assert mask == -1  # every case under the largest limit: all 64 bits set
        out.append(sums.astype(np.int64))
    return np.concatenate(out)


@pytest.mark.parametrize("kind", ["uniform", "duplicates", "outside", "one-wide-dimension"])
def test_euclidean_nibble_pass_equals_brute_force(kind: str) -> None:
    # the 4-bit pass deciding alone (every case may get its distance), by either kernel
    # (AVX2's byte shuffle where the CPU has it, and the scalar one)
    import cbr.similarity.euclidean as euclidean
    from cbr.similarity.nibbles import HAS_SHUFFLE, nibble_codes

    if not HAS_SHUFFLE:  # (where the index keeps the 8-bit codes)
        pytest.skip("this CPU (or numba's target) has no AVX2 byte shuffle")
    rng = np.random.default_rng(13)
    m = Euclidean(prune_min_cases=1000)
    if kind == "uniform":  # unstructured rows: the index chooses the 4-bit codes itself
        cases = rng.random((4000, 200), dtype=np.float32)
        cases[3000] = cases[33]  # a duplicate: the tie goes to the lower index
        queries = np.vstack([rng.random((5, 200)), cases[33].astype(np.float64)])
        index = m.build_index(cases)
        assert isinstance(index.codes, euclidean._Nibbles)
    else:  # (the duplicates would make tight blocks and 8-bit codes): 4-bit codes by hand
        cases, queries = _adversarial(kind, rng)
        sq = euclidean._row_norms_sq(cases)
        max_norm = euclidean._finite_max_norm(sq)
        codes = euclidean._Nibbles(nibble_codes(cases))
        index = euclidean._EuclideanIndex(cases, sq, np.sqrt(sq), None, max_norm, codes)
    plain = Euclidean(prune_min_cases=10**9).build_index(cases)
    for q in queries:
        qr = m.represent_query(q)
        want_i, want_d = smallest_k(m.distances(qr, plain), 7)
        q32, q_sq = m._query(qr)
        for shuffle in (True, False):
            got_i, got_d, count = euclidean._nibbles_search(
                index, index.codes.codes, q32, q_sq, 7, len(cases), shuffle
            )
            np.testing.assert_array_equal(got_i, want_i)
            np.testing.assert_array_equal(got_d, want_d)
            assert count >= 7
            if kind == "uniform":
                assert count < 0.3 * len(cases)  # the bound prunes
    if kind == "uniform":
        q32, q_sq = m._query(m.represent_query(queries[-1]))
        got = euclidean._nibbles_search(index, index.codes.codes, q32, q_sq, 2, len(cases))
        assert list(got[0]) == [33, 3000]
