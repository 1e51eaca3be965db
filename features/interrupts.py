"""Ctrl-C held back while worker processes are started (:func:`interrupts_held`), for the
commands that start them: ``compare --jobs`` and ``--scheduler local:N``, and while files that
belong together are written (``compare``'s results files); and SIGTERM taken as Ctrl-C
(:func:`sigterm_as_interrupt`), for every command."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, NoReturn

from .errors import PosecbrError
from .fileio import remove_unfinished_temporaries

#: the exit status of a command stopped by Ctrl-C (128 + SIGINT, as a shell reports it)
INTERRUPTED_STATUS = 130
#: the exit status of a command stopped by SIGTERM (128 + SIGTERM)
TERMINATED_STATUS = 143

# SIGTERM came in this run (the KeyboardInterrupt it raised is said as a termination)
_TERMINATED: list[int] = []


def terminated() -> bool:
    """Whether the KeyboardInterrupt being handled was raised by SIGTERM (under
    :func:`sigterm_as_interrupt`, or by :func:`raise_interrupt`), not by Ctrl-C."""
    return bool(_TERMINATED)


def raise_interrupt(signum: int, _frame: Any = None, said: str = "") -> NoReturn:
    """What Ctrl-C does, for the signal ``signum``: KeyboardInterrupt raised (so every
    ``finally``, context manager and ``except KeyboardInterrupt`` on the way cleans up: a
    hidden temporary removed, a transaction rolled back, worker processes stopped); SIGTERM
    is remembered (:func:`terminated`). ``said``: what the command says after
    "interrupted" (what was done before)."""
    if signum == signal.SIGTERM:
        _TERMINATED.append(signum)
    raise KeyboardInterrupt(said) if said else KeyboardInterrupt


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM (``kill PID``, systemd, ``docker stop``, a program's ``Popen.terminate()``)
    raises KeyboardInterrupt meanwhile, as Ctrl-C does, instead of killing the process on
    the spot (which left an output's hidden temporary behind and a ``compare --jobs`` run's
    worker processes running). Set in the main thread only (the only one a handler can be
    set from); elsewhere SIGTERM does what it did."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _TERMINATED.clear()
    previous = signal.signal(signal.SIGTERM, raise_interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)


@contextmanager
def sigterm_held(then: Any = None) -> Iterator[Any]:
    """A SIGTERM that comes meanwhile is delivered at the end of the block (to the handler
    there was, or ``then`` when given: the handler SIGTERM is left with), not in the middle
    of starting a worker process, which it left running after this process had ended, nor
    between setting or putting back the handlers of SIGINT and SIGTERM. Yields the handler
    SIGTERM had before (``SIG_DFL`` for one not set from Python). Main thread only
    (elsewhere: nothing held, nothing set)."""
    if threading.current_thread() is not threading.main_thread():
        yield None
        return
    came: list[int] = []
    previous = signal.signal(signal.SIGTERM, lambda n, _: came.append(n))
    if previous is None:  # a handler not set from Python, which cannot be set back
        previous = signal.SIG_DFL
    try:
        yield previous
    finally:
        signal.signal(signal.SIGTERM, previous if then is None else then)
        if came:
            signal.raise_signal(signal.SIGTERM)


@contextmanager
def stored_before(done: str, again: str = "", stored: bool = True) -> Iterator[None]:
    """Work after a change committed (a large case base's matrices, a summary's counts):
    Ctrl-C or SIGTERM there says the change is stored (``done``), not "interrupted" alone,
    which reads as a change not made (run again, a trim trimmed twice); so does one of
    posecbr's errors there (the store lost or locked as the matrices are written, a
    PostgreSQL connection lost as the cases are counted), ``again`` after it when given (what
    running the command again would do). ``stored`` False: nothing was committed, nothing
    added."""
    try:
        yield
    except KeyboardInterrupt:
        if not stored:
            raise
        raise KeyboardInterrupt(done) from None
    except PosecbrError as exc:
        if stored:
            exc.add(f"{done}: {again}" if again else done)
        raise


def stop_workers(pool: Any) -> None:
    """Stop a ``concurrent.futures.ProcessPoolExecutor``'s worker processes now (Ctrl-C or
    SIGTERM reached this process alone): each is sent SIGTERM (a worker started with
    :func:`worker_ends_on_sigterm` unwinds its task first), and the pool, finding them gone,
    fails their tasks; then it is shut down, every worker waited for. (Left to the pool's own
    shutdown, every task queued was run first, the workers writing on after the command was
    told to stop.)"""
    for proc in list((pool._processes or {}).values()):
        proc.terminate()
    # the pool finds them gone and fails their tasks: its thread done with them, no future is
    # left to cancel under it (it failed on one cancelled meanwhile)
    pool.shutdown(wait=True)


# whether this worker process is running a task (:func:`run_task`)
_IN_TASK: list[bool] = [False]


# how long a worker's task may take to unwind after SIGTERM
UNWIND_GRACE_S = 10.0


def _worker_sigterm(signum: int, _frame: Any) -> None:
    if _TERMINATED:
        # unwinding the task the first SIGTERM stopped: the pool sends SIGTERM again to every
        # worker left once one has ended (its "broken" state), which ended this one on the
        # spot, before its task's clean-up had removed the output's hidden temporary; the
        # clean-up now finishes (the task's end ends the worker: run_task)
        return
    if not _IN_TASK[0]:
        _end_worker()
    # first, so that a SIGTERM coming in what follows (the handler run again inside this one)
    # finds the task being stopped, not this worker idle
    _TERMINATED.append(signum)
    # the task has UNWIND_GRACE_S to unwind: its interrupt can be lost (raised inside a
    # finaliser, where Python only prints it) and the task go on
    _end_later()
    raise KeyboardInterrupt


def _end_worker() -> NoReturn:
    """End this worker now, as stopped by SIGTERM, its outputs' hidden temporaries removed
    (a task cut short by the end has not removed them)."""
    remove_unfinished_temporaries()
    os._exit(TERMINATED_STATUS)


# whether the timer of _end_later is running
_ENDING: list[bool] = [False]


def _end_later() -> None:
    """End this worker (:func:`_end_worker`) UNWIND_GRACE_S from the first call (a daemon
    timer; later calls add none)."""
    if _ENDING[0]:
        return
    _ENDING[0] = True
    timer = threading.Timer(UNWIND_GRACE_S, _end_worker)
    timer.daemon = True
    timer.start()


def _quiet_when_stopped(unraisable: Any) -> None:
    """Once this worker is being stopped, an object whose clean-up fails as the task is
    unwound (a ``ZipFile`` whose member was being written: "Exception ignored in ...
    ValueError: Can't close the ZIP file ...") says nothing: the command says one line."""
    if not _TERMINATED:
        sys.__unraisablehook__(unraisable)


def worker_ends_on_sigterm() -> None:
    """For a worker process's initializer: SIGTERM (:func:`stop_workers`) unwinds the task
    under way (:func:`run_task`: an output it was writing leaves no hidden temporary), then
    ends the process; idle, it ends it at once. (Killed on the spot, it left the temporary.)
    SIGTERM again while it unwinds lets the unwinding finish; a task not unwound after
    UNWIND_GRACE_S (its interrupt lost) ends there, the temporaries it was writing removed.
    Ctrl-C is left to the command (the terminal sends it to every process of the group),
    which stops its workers so."""
    signal.signal(signal.SIGTERM, _worker_sigterm)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    sys.unraisablehook = _quiet_when_stopped


def run_task(fn: Any, *args: Any) -> Any:
    """``fn(*args)`` in a worker started with :func:`worker_ends_on_sigterm`: a SIGTERM
    meanwhile unwinds it (every ``finally`` and context manager run), and the worker ends
    there, however the task ended (its interrupt replaced by another error on the way, or
    turned into a failed clip): not on to the next task queued. One whose SIGTERM came as
    the task before ended (raised in this ``finally``, which it cut short: the pool took the
    interrupt for that task's result) ends before beginning this one."""
    if _TERMINATED:
        _end_worker()
    _IN_TASK[0] = True
    try:
        return fn(*args)
    finally:
        _IN_TASK[0] = False
        if _TERMINATED:
            _end_worker()


@contextmanager
def interrupts_held() -> Iterator[None]:
    """Ctrl-C held back while worker processes are started, then raised: SIGINT is blocked
    in this thread, and the workers inherit the block (as does a thread started meanwhile,
    and the processes it starts: a Dask local cluster's event loop and its workers), so the
    terminal's Ctrl-C (sent to every process of the group) reaches this process alone, which
    stops them; and one that comes meanwhile is raised only once every worker started is
    known (raised in the middle of starting one, it left that worker running after this
    process had ended). Each worker printed a KeyboardInterrupt traceback, of a task or of its
    imports."""
    if not hasattr(signal, "pthread_sigmask"):  # Windows: Ctrl-C is not a POSIX signal
        yield
        return
    came: list[int] = []
    main = threading.current_thread() is threading.main_thread()  # where handlers are set
    # SIGTERM held outermost: raised once the mask and SIGINT's handler are back (raised as
    # its handler was put back, before them, it left Ctrl-C blocked in a caller that goes on)
    with sigterm_held():
        handler = signal.signal(signal.SIGINT, lambda n, _: came.append(n)) if main else None
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            yield
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)
            if main:  # None: a handler not set from Python, which cannot be set back
                signal.signal(signal.SIGINT, signal.SIG_DFL if handler is None else handler)
    if came:
        raise KeyboardInterrupt


@contextmanager
def interrupts_ignored_by_children() -> Iterator[None]:
    """Processes started meanwhile ignore Ctrl-C for good; this one raises KeyboardInterrupt
    after the block when one came meanwhile.

    A process started by *spawn* (fork and exec, as ``multiprocessing`` and Dask's nannies
    start their workers) does not keep the blocked signal mask :func:`interrupts_held` sets,
    but keeps an ignored signal (``SIG_IGN`` survives exec, and Python leaves an ignored
    SIGINT ignored): SIGINT is ignored meanwhile. This process would then miss a Ctrl-C that
    came meanwhile (blocking it in this thread does not keep it: another thread, a native
    library's, takes it and ignores it), so a sentinel process of the same process group,
    started first and not ignoring it, tells: the terminal's Ctrl-C, sent to every process
    of the group, ends it. (A SIGINT sent to this process alone meanwhile is missed.)"""
    main = threading.current_thread() is threading.main_thread()  # where handlers are set
    if not (hasattr(signal, "pthread_sigmask") and main):  # Windows: no POSIX signals
        yield
        return
    # SIGTERM held outermost: raised once SIGINT's handler is back and the sentinel ended
    with sigterm_held():
        sentinel = _sentinel()
        try:
            handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
            try:
                yield
            finally:
                signal.signal(signal.SIGINT, signal.SIG_DFL if handler is None else handler)
            came = sentinel is not None and sentinel.poll() is not None
        finally:
            if sentinel is not None:
                if sentinel.poll() is None:
                    sentinel.kill()
                sentinel.wait()
    if came:
        raise KeyboardInterrupt


def _sentinel() -> subprocess.Popen[bytes] | None:
    """A process of this process group that ends on Ctrl-C (it waits a day otherwise); None
    where none can be started (no Python executable known: an embedded interpreter)."""
    if not sys.executable:
        return None
    try:
        return subprocess.Popen(
            [sys.executable, "-I", "-S", "-c", "import time; time.sleep(86400)"],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError:
        return None
