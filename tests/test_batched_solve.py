"""Batched retrieval in CaseBaseClassifier.solve and classify_clips, on real UI-PRMD clips.

``solve`` retrieves every clip's neighbours with one ``nearest_many`` call (one matrix product
per block of queries). It must give, bit for bit, what one ``solve`` per clip gives (the
retrieval it replaced), and the neighbours scikit-learn's brute force finds in float64 on the
same case-base rows (a peer's independent answer).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from sklearn.metrics.pairwise import nan_euclidean_distances
from sklearn.neighbors import NearestNeighbors

from cbr.classification import classify_clips
from cbr.estimator import CaseBaseClassifier
from features.datasets import load_dataset

# under pytest-xdist the module's tests run on one worker: each fitted case base is fitted once
pytestmark = pytest.mark.xdist_group("batched-solve")

K = 5


@pytest.fixture(scope="module")
def uiprmd(shared_data: Path) -> tuple[list, list, list]:
    root = shared_data / "ui-prmd"
    odd = (1, 3, 5, 7, 9)  # half the episodes: 200 cases to search, 100 clips to ask
    train = load_dataset(root, subjects=["s01", "s02"], episodes=odd)
    test = load_dataset(root, subjects=["s07"], episodes=odd)
    return [c.seq for c in train], [c.label for c in train], [c.seq for c in test]


# the plain index (one matrix product for all queries) and the PCA-pruned one
@pytest.fixture(scope="module", params=[{}, {"prune_min_cases": 100}])
def fitted(request: pytest.FixtureRequest, uiprmd: tuple) -> CaseBaseClassifier:
    X, y, _ = uiprmd
    return CaseBaseClassifier(k=K, similarity_params=request.param).fit(X, y)


def test_batched_solve_equals_one_clip_at_a_time(fitted: CaseBaseClassifier, uiprmd: tuple):
    queries = uiprmd[2][::2]  # every other clip: a solve per clip costs a full search each
    assert len(queries) >= 40
    together = fitted.solve(queries)
    for seq, got in zip(queries, together, strict=True):
        alone = fitted.solve([seq])[0]
        np.testing.assert_array_equal(got.retrieval.indices, alone.retrieval.indices)
        np.testing.assert_array_equal(got.retrieval.distances, alone.retrieval.distances)
        np.testing.assert_array_equal(got.retrieval.case_ids, alone.retrieval.case_ids)
        assert got.solution.label == alone.solution.label
        assert got.solution.confidence == alone.solution.confidence
        assert got.novelty == alone.novelty


@pytest.mark.parametrize("fitted", [{}], indirect=True)
def test_solve_without_the_flag_answers_the_same_and_judges_nothing(
    fitted: CaseBaseClassifier, uiprmd: tuple
) -> None:
    queries = uiprmd[2][:12]
    for got, full in zip(fitted.solve(queries, flag=False), fitted.solve(queries), strict=True):
        np.testing.assert_array_equal(got.retrieval.indices, full.retrieval.indices)
        assert got.solution.label == full.solution.label
        np.testing.assert_array_equal(got.solution.proba, full.solution.proba)
        assert got.solution.confidence == full.solution.confidence
        assert got.novelty == full.novelty
        assert (got.unlike_cases, got.unlike_reason, got.description) == (False, "", None)


def test_batched_solve_finds_scikit_learns_brute_force_neighbours(
    fitted: CaseBaseClassifier, uiprmd: tuple
) -> None:
    cb = fitted.case_base_
    rows = np.asarray(cb.index.rows, dtype=np.float64)  # the float32 rows the search reads
    solved = fitted.solve(uiprmd[2])
    q = np.stack([cb.measure.represent_query(s.problem.values) for s in solved])
    q32 = q.astype(np.float32).astype(np.float64)  # the query as the search multiplies it
    full = [s.problem.measured() is None for s in solved]
    assert 0 < sum(full) < len(full)  # both kinds: every column shown, and some never shown
    dist, want = NearestNeighbors(n_neighbors=K, algorithm="brute").fit(rows).kneighbors(q32)
    got = np.stack([s.retrieval.indices for s in solved])
    np.testing.assert_array_equal(got[full], want[full])
    np.testing.assert_allclose(
        np.stack([s.retrieval.distances for s in solved])[full], dist[full], rtol=1e-5
    )
    # a column a clip never showed is left out: scikit-learn's nan_euclidean_distances with
    # its fills missing, on the same float32 rows and query
    for i in np.flatnonzero(~np.asarray(full)):
        s = solved[i]
        query = np.where(s.problem.measured(), q32[i], np.nan)
        d = nan_euclidean_distances(query[None], rows)[0]
        order = np.argsort(d, kind="stable")[:K]
        np.testing.assert_array_equal(s.retrieval.indices, order)
        np.testing.assert_allclose(s.retrieval.distances, d[order], rtol=1e-5)


@pytest.mark.parametrize("fitted", [{}], indirect=True)  # explaining costs; one index will do
def test_classify_clips_batched_equals_per_clip_and_refuses_only_the_empty_clip(
    fitted: CaseBaseClassifier, uiprmd: tuple
) -> None:
    queries = uiprmd[2][:10]
    empty = queries[3]
    nothing = dataclasses.replace(
        empty, positions=np.full_like(empty.positions, np.nan), source="empty.csv"
    )
    clips = [*queries[:7], nothing, *queries[7:]]
    stored = SimpleNamespace(classifier=fitted)
    results = classify_clips(stored, clips, [None] * len(clips))  # type: ignore[arg-type]
    assert [r.source for r in results] == [c.source for c in clips]
    assert results[7].solved is None and "no person" in str(results[7].unclassifiable)
    for seq, r in zip(clips[:7] + clips[8:], results[:7] + results[8:], strict=True):
        alone = fitted.solve([seq])[0]
        assert r.solved is not None
        np.testing.assert_array_equal(r.solved.retrieval.indices, alone.retrieval.indices)
        assert r.label == alone.solution.label
