"""BLAS on one thread where its threads cost more than they give.

OpenBLAS (as numpy ships it) splits a product or factorisation over all its threads once it
is a few hundred thousand multiply-adds. On a busy machine each hand-off waits for a time
slice: on the 2-core machine at load 7-17, the SVD of a 10-minute recording's angle
velocities ``(72,000, 8)`` took 42 ms on two threads and 1.3 ms on one, with the same bits.
Long, narrow arrays (a recording's frames by a few angles) gain nothing from the threads.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

_POOLS: list[Any] | None = None  # threadpoolctl's BLAS handles, found on first use


def blas_pools() -> list[Any]:
    """threadpoolctl's handles of the loaded BLAS libraries (found once; none without it)."""
    global _POOLS
    if _POOLS is None:
        try:  # installed with scikit-learn
            from threadpoolctl import ThreadpoolController

            _POOLS = [c for c in ThreadpoolController().lib_controllers if c.user_api == "blas"]
        except ImportError:  # pragma: no cover
            _POOLS = []
    return list(_POOLS)


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """BLAS on one thread inside, as many as before after. The library's own thread setters
    (a microsecond each), not ``threadpool_limits`` (~0.1 ms a call, measured)."""
    pools = blas_pools()
    before = [p.get_num_threads() for p in pools]
    for p, t in zip(pools, before, strict=True):
        if t != 1:
            p.set_num_threads(1)
    try:
        yield
    finally:
        for p, t in zip(pools, before, strict=True):
            if t != 1:
                p.set_num_threads(t)
