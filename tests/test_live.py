"""The live decoder (cbr.live): segments are finished where the best path over the votes
goes, checked against every path tried by brute force."""

from __future__ import annotations

import itertools

import numpy as np

from cbr.live import _Forward


def _best_path(score: np.ndarray, cost: np.ndarray) -> list[int]:
    """The path of greatest total score less costs, found by trying every path."""
    n, k = score.shape
    best, value = None, -np.inf
    for path in itertools.product(range(k), repeat=n):
        v = sum(score[t, s] for t, s in enumerate(path))
        v -= sum(cost[a, b] for a, b in zip(path[:-1], path[1:], strict=True))
        if v > value:
            best, value = list(path), v
    assert best is not None
    return best


def test_settled_hops_follow_the_best_path_whatever_comes_after() -> None:
    """Random votes over three states, a change costing 1.5 (2.5 from state 0 to 2): the
    hops settled as the votes come, then the rest at the end, give the best path over all
    the votes, the one brute force finds; and a settled hop is never changed."""
    rng = np.random.default_rng(7)
    cost = np.full((3, 3), 1.5) - 1.5 * np.eye(3)
    cost[0, 2] = 2.5
    early = 0  # hops settled before the votes ended
    for _ in range(12):
        score = np.log(rng.dirichlet(np.ones(3) * 0.7, size=8))
        best = _best_path(score, cost)
        forward = _Forward(cost)
        settled: list[int] = []
        for t in range(len(score)):
            forward.step(score[t])
            settled += forward.settle()
            assert settled == best[: len(settled)]
        early += len(settled)
        settled += forward.settle(final=True)
        assert settled == best
    assert early > 0
