"""Compile numba's kernels once, before the suite's worker processes start (``conftest.py``):
run as ``python -m tests._kernels fluents`` or ``... search``, each on a tiny input, so that
numba writes its cache and every later process (xdist workers, Dask workers, the commands
the tests start) loads the kernels instead of compiling them again (about 50 s of CPU each,
cold: the fluents 18 s, the searches 33 s, on a slow evening of 2026-12-04)."""

from __future__ import annotations

import sys

import numpy as np


def fluents() -> None:
    from features.fluents import evaluate
    from tests.bodies import squat_clip

    evaluate(squat_clip(0.8, 30, 10.0, 10.0))
    tslearn_dtw()


def tslearn_dtw() -> None:
    """tslearn's DTW, the peer several test modules compare with, as they call it (float64
    series, with and without a Sakoe-Chiba band): kept in numba's cache
    (:func:`cbr.evaluation.peers.cache_tslearn_kernels`, which those modules call too)."""
    from tslearn.metrics import cdist_dtw, dtw

    from cbr.evaluation.peers import cache_tslearn_kernels

    cache_tslearn_kernels()
    x = np.random.default_rng(0).random((3, 12, 2))
    dtw(x[0], x[1])
    dtw(x[0], x[1], global_constraint="sakoe_chiba", sakoe_chiba_radius=2)
    cdist_dtw(x)
    cdist_dtw(x, x[:2], global_constraint="sakoe_chiba", sakoe_chiba_radius=2)


def search() -> None:
    from cbr.similarity import DTW, Euclidean

    rng = np.random.default_rng(0)
    m = Euclidean(prune_min_cases=1000)
    index = m.build_index(rng.random((3000, 40)).astype(np.float32))
    queries = np.stack([m.represent_query(rng.random(40)) for _ in range(4)])
    m.nearest(queries[0], index, 5)
    m.nearest_many(queries, index, 5)
    small = m.build_index(rng.random((30, 40)).astype(np.float32))  # a small case base's
    m.nearest(queries[0], small, 5)  # plain pass
    m.distances(queries[0], small)
    d = DTW(radius=3)
    x = rng.random((50, 32, 6))
    d.nearest(d.represent_query(x[0]), d.build_index(d.represent(x)), 3)


if __name__ == "__main__":
    {"fluents": fluents, "search": search}[sys.argv[1]]()
