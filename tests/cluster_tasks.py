"""Work units for tests/test_cluster.py, importable by the Dask workers (which unpickle
functions by module and name)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any


def square_or_die_once(x: int, marker_dir: str) -> int:
    """``x * x``; for ``x == 3`` the worker process running it dies first, once (the marker
    file remembers it died), as a worker killed by the machine would."""
    marker = Path(marker_dir) / "died"
    if x == 3 and not marker.exists():
        marker.touch()
        os._exit(1)
    return x * x


def fail_on_even(x: int) -> int:
    """``x``, or a ValueError for even numbers (a unit that fails on its own input)."""
    if x % 2 == 0:
        raise ValueError(f"{x} is even")
    return x


def bookkeeping(dask_worker: Any) -> dict[str, float]:
    """The worker's periodic callbacks and their periods in ms (run on each worker)."""
    return {name: float(pc.callback_time) for name, pc in dask_worker.periodic_callbacks.items()}


def slow_square(x: int) -> int:
    """``x * x``, a tenth of a second later (a unit still running when something happens)."""
    import time

    time.sleep(0.1)
    return x * x


def slow_add(x: int, y: int) -> int:
    """``x + y``, a tenth of a second later: a unit with a shared argument (``y``), as every
    command's are (scattered to the workers once)."""
    import time

    time.sleep(0.1)
    return x + y


def die(*args: Any) -> None:
    """The worker process running it dies at once, as one the kernel kills (out of memory)."""
    os._exit(1)
