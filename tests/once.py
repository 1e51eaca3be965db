"""Test data made once in a whole ``pytest`` run, shared by the pytest-xdist workers."""

from __future__ import annotations

import fcntl
import os
import pickle
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import pytest

T = TypeVar("T")


def made_once(factory: pytest.TempPathFactory, name: str, make: Callable[[Path], T]) -> T:
    """``make(folder)`` run once in the whole test session, however many pytest-xdist workers
    ask for it: the first one makes it (the others wait on a lock file in the folder the
    workers share), the rest read the value it returned. A module-scoped fixture is made
    once in each worker that runs a test of its module (both, on two cores), and once in
    each module that makes the same thing. ``make`` writes only into ``folder``, and the
    tests only read what it made (or copy it): they share it across workers and modules.
    A ``make`` that fails is tried again by the next worker that asks."""
    root = factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # pytest-of-<user>/pytest-<n>/: the workers' own folders are in it
    folder = root / f"once-{name}"
    done = root / f"once-{name}.pickle"
    with open(root / f"once-{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if done.exists():
            value: T = pickle.loads(done.read_bytes())
            return value
        shutil.rmtree(folder, ignore_errors=True)  # a failed attempt's
        folder.mkdir()
        value = make(folder)
        done.write_bytes(pickle.dumps(value))
        return value
