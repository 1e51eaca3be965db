"""Where the tasks of a comparison run: serially in this process, in worker processes
started with *spawn* that each receive the shared data once, or on a Dask cluster.

A runner is made with a ``context`` (the data every task reads) and a ``setup`` run once per
worker before its first task (warming caches and compilers); ``map(fn, tasks)`` then yields
``fn(context, task)`` for every task, in the order they finish, with a progress bar. ``fn`` and
``setup`` must be module-level functions and the context picklable: :class:`DaskRunner` runs
the same tasks on a Dask cluster (``--scheduler``; the context scattered to every worker once,
the tasks mapped).

Spawn, not fork: a forked child inherits the parent's threads' locks (GNU OpenMP under
scikit-learn's neighbour search aborts such children), and fork does not exist on Windows and
is unsafe on macOS.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any, Generic, TypeVar

from features.errors import PosecbrError
from features.interrupts import interrupts_held, stop_workers
from features.progress import progress

C = TypeVar("C")
T = TypeVar("T")
R = TypeVar("R")


class Runner(ABC, Generic[C]):
    """Runs ``fn(context, task)`` for every task; ``setup(context)`` once per worker first."""

    def __init__(self, context: C, setup: Callable[[C], None] | None = None) -> None:
        self.context = context
        self.setup = setup

    @abstractmethod
    def map(
        self, fn: Callable[[C, T], R], tasks: Sequence[T], desc: str = "tasks", unit: str = "task"
    ) -> Iterator[R]:
        """``fn(context, task)`` for every task, in the order they finish."""


class SerialRunner(Runner[C]):
    """Every task in this process, one after the other (``setup`` once, on the first map)."""

    _ready = False

    def map(
        self, fn: Callable[[C, T], R], tasks: Sequence[T], desc: str = "tasks", unit: str = "task"
    ) -> Iterator[R]:
        if not self._ready and self.setup is not None:
            self.setup(self.context)
        self._ready = True
        for task in progress(tasks, desc, total=len(tasks), unit=unit):
            yield fn(self.context, task)


# The context of this worker process, set once by its initializer (never used in the parent).
_WORKER_CONTEXT: list[Any] = []


def _start_worker(context: Any, setup: Callable[[Any], None] | None) -> None:
    os.environ["POSECBR_NO_PROGRESS"] = "1"  # only the parent draws a bar
    _WORKER_CONTEXT[:] = [context]
    if setup is not None:
        setup(context)


def _call(fn: Callable[[Any, T], R], task: T) -> R:
    return fn(_WORKER_CONTEXT[0], task)


class ProcessRunner(Runner[C]):
    """Tasks spread over ``jobs`` spawned worker processes (``concurrent.futures``); each
    worker unpickles the context once and runs ``setup`` before its first task."""

    def __init__(self, context: C, setup: Callable[[C], None] | None = None, jobs: int = 2) -> None:
        super().__init__(context, setup)
        self.jobs = int(jobs)

    def map(
        self, fn: Callable[[C, T], R], tasks: Sequence[T], desc: str = "tasks", unit: str = "task"
    ) -> Iterator[R]:
        pool = ProcessPoolExecutor(
            max_workers=self.jobs,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_start_worker,
            initargs=(self.context, self.setup),
        )
        futures: list[Future[R]] = []
        with pool:
            try:
                with interrupts_held():  # inherited by the workers submit starts
                    futures = [pool.submit(_call, fn, t) for t in tasks]
                for fut in progress(as_completed(futures), desc, total=len(futures), unit=unit):
                    yield fut.result()
            except BrokenProcessPool:
                raise PosecbrError(_died(), "jobs") from None
            except KeyboardInterrupt:  # Ctrl-C or SIGTERM, which reached this process alone
                stop_workers(pool)
                raise
            finally:
                for fut in futures:
                    fut.cancel()


def _died() -> str:
    """Why a worker process may have died: out of memory, or (run from a script) the script
    starts the workers as it is imported: each spawned worker imports the main script again,
    and one that starts workers there dies (``multiprocessing``'s "safe importing of main
    module")."""
    main = sys.modules.get("__main__")
    script = getattr(main, "__file__", None)
    from_script = script is not None and getattr(main, "__spec__", None) is None
    if from_script and Path(str(script)).suffix == ".py":
        return (
            f"a worker process died: out of memory (try fewer `jobs`), or {script} starts"
            ' workers when imported (put its code under `if __name__ == "__main__":`)'
        )
    return "a worker process died (out of memory?); try fewer `jobs`"


# The contexts this Dask worker process has run ``setup`` for (kept alive: identity, not id()).
_DASK_READY: list[Any] = []


def _dask_call(task: T, fn: Callable[[Any, T], R], context: Any, setup: Any) -> R:
    """One task on a Dask worker: the scattered ``context`` is one object per worker, so the
    caches ``setup`` warms serve every later task there."""
    if setup is not None and not any(c is context for c in _DASK_READY):
        setup(context)
        _DASK_READY.append(context)
    return fn(context, task)


class DaskRunner(Runner[C]):
    """Tasks on a Dask cluster (:mod:`features.cluster`: ``local:N`` or a scheduler address);
    the context is sent to every worker once, and each worker runs ``setup`` before its first
    task. A worker that dies has its tasks run again elsewhere; a task that fails stops the
    map with its error."""

    def __init__(self, context: C, setup: Callable[[C], None] | None, scheduler: str) -> None:
        super().__init__(context, setup)
        self.scheduler = scheduler

    def map(
        self, fn: Callable[[C, T], R], tasks: Sequence[T], desc: str = "tasks", unit: str = "task"
    ) -> Iterator[R]:
        from features.cluster import connect, map_outcomes

        names = [str(t) for t in tasks]
        with connect(self.scheduler) as client:
            outcomes = map_outcomes(client, _dask_call, tasks, names, fn, self.context,
                                    self.setup, desc=desc, unit=unit)  # fmt: skip
            for o in outcomes:
                if not o.ok:
                    raise PosecbrError(f"task {o.name} failed: {o.error}", "scheduler")
                yield o.value  # type: ignore[misc]


def make_runner(
    context: C,
    setup: Callable[[C], None] | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
) -> Runner[C]:
    """A Dask runner when ``scheduler`` is given, else a serial runner for ``jobs == 1`` and
    ``jobs`` spawned worker processes otherwise."""
    if scheduler is not None:
        return DaskRunner(context, setup, scheduler)
    if jobs <= 1:
        return SerialRunner(context, setup)
    return ProcessRunner(context, setup, jobs)
