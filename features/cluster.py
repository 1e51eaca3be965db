"""Corpus work on a Dask cluster (``dask.distributed``): the ``--scheduler`` of ``posecbr
extract``, ``train`` and ``compare``.

``--scheduler ADDRESS`` connects to a running scheduler (``tcp://host:8786``, started with
``dask scheduler`` and ``dask worker ADDRESS`` on each machine); ``--scheduler local:N``
starts a ``LocalCluster`` of N single-threaded worker processes on this machine for the
command's duration, with Dask's bookkeeping cut to what a batch job needs
(:data:`LEAN_CONFIG`). :func:`map_outcomes` runs one function per work unit (a clip, a fold) and
yields each unit's result or its error as the units finish, with a progress bar: a unit that
fails is reported by name and the others finish; a unit whose worker dies is run again on
another worker by the scheduler (up to ``distributed.scheduler.allowed-failures`` times, then
it is reported as failed). Functions and their arguments travel by pickle (cloudpickle), so
they must be importable on the workers and the inputs they name reachable there.

dask is an optional dependency (``pip install 'posecbr[cluster]'``): without it,
``--scheduler`` is refused with one line. Refusals name the Python argument, ``scheduler``
(a malformed one with ParameterError, a ValueError too); the commands say ``--scheduler``.
"""

from __future__ import annotations

import asyncio
import difflib
import gc
import importlib
import logging
import os
import re
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import CancelledError
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from typing import Any, Generic, TypeVar
from urllib.parse import urlsplit

from .errors import ConfigError, ParameterError, PosecbrError
from .interrupts import interrupts_held, interrupts_ignored_by_children
from .progress import progress

T = TypeVar("T")
R = TypeVar("R")

LOCAL_PREFIX = "local:"
#: seconds to wait for a scheduler named by address
CONNECT_TIMEOUT_S = 20
SCHEDULER_HELP = (
    "run the work on a Dask cluster: a scheduler ADDRESS (tcp://host:8786) or local:N "
    "(N worker processes on this machine); needs posecbr[cluster]"
)
#: Dask settings for the scheduler, nannies and workers of ``local:N``: what they do besides
#: the tasks, cut to what a batch job needs (the dashboard, which these feed, is off; the
#: CPU they save is booked in ``python -m benchmarks.scale``'s decode + pose accounting).
LEAN_CONFIG: dict[str, Any] = {
    # the statistical profiler samples the stack of every running task every 10 ms, on the
    # worker's event loop, which takes the GIL from the task each time: the largest cost
    "distributed.worker.profile.enabled": False,
    # every server checks every 20 ms whether its event loop was blocked (a warning only)
    "distributed.admin.tick.interval": "1s",
    # host CPU, memory and network samples for the dashboard's plots, every 0.5 s per server
    "distributed.admin.system-monitor.interval": "5s",
    # each nanny and worker reads the worker's memory every 0.1 s (to spill, pause or restart
    # it); extraction and training workers peak far below their limit (about 0.45 GiB of the
    # machine's memory / N, benchmarks/results/scale.json), so every 0.5 s is in time
    "distributed.worker.memory.monitor-interval": "500ms",
}


@dataclass(frozen=True)
class Outcome(Generic[R]):
    """One work unit's end: ``value`` when it succeeded, else ``error`` (one line)."""

    index: int
    name: str
    value: R | None = None
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None


def _dask() -> Any:
    try:
        import dask.distributed as dd
    except ImportError:
        raise ConfigError(
            "needs dask.distributed, which is not installed (pip install 'posecbr[cluster]')",
            "scheduler",
        ) from None
    return dd


def local_workers(spec: str) -> int | None:
    """N of ``local:N``; None for a scheduler address. A bad spec is refused."""
    if not spec.startswith(LOCAL_PREFIX):
        if not spec.strip():
            raise ParameterError("the scheduler address is empty", "scheduler")
        _refuse_mistyped_local(spec)
        _refuse_impossible_port(spec)
        return None
    text = spec[len(LOCAL_PREFIX) :]
    # isdigit() holds for "²", which int() refuses; isdecimal() for what int() reads
    if not text.isdecimal() or int(text) < 1:
        raise ParameterError(
            f"local:N needs a whole number of workers >= 1, got {spec!r}", "scheduler"
        )
    return int(text)


#: a scheduler address that is ``local:N`` mistyped: a word and a number of workers
_LOCAL_TYPO = re.compile(r"(?P<word>[A-Za-z]{3,8})[:=_ -]?(?P<n>[0-9]{1,3})")


def _refuse_mistyped_local(spec: str) -> None:
    """Refuse ``lokal:2``, ``Local:2``, ``local2``: ``local:N`` mistyped, which Dask reads as
    the scheduler at host "lokal", port 2, and waited :data:`CONNECT_TIMEOUT_S` seconds for.
    A word close to "local" with at most 3 digits (a number of workers; no scheduler listens
    on a port below 1000 unless told, Dask's own is 8786)."""
    m = _LOCAL_TYPO.fullmatch(spec.strip())
    if m and difflib.get_close_matches(m["word"].lower(), ["local"], n=1, cutoff=0.75):
        raise ParameterError(
            f"{spec!r} is neither local:N nor a scheduler address (did you mean "
            f"local:{int(m['n'])}?)",
            "scheduler",
        )


def _refuse_impossible_port(spec: str) -> None:
    """Refuse a scheduler address whose port no program can listen on (0, above 65535, not a
    number): Dask tried to connect to ``:0`` or ``:99999`` for :data:`CONNECT_TIMEOUT_S`
    seconds, after the command had listed its clips. An address that is no URL is left to
    Dask, which says what is wrong with it."""
    try:
        parts = urlsplit(spec if "://" in spec else f"tcp://{spec}")
    except ValueError:  # "[::1" and the like
        return
    if parts.scheme == "inproc":  # a process's own address, no port
        return
    try:
        port = parts.port
    except ValueError:  # not a number, or out of range
        port = 0
    if port is not None and not 1 <= port <= 65535:
        said = (
            f"the scheduler address {spec} has the port {parts.netloc.rpartition(':')[2]!r}: a "
            "port is a number from 1 to 65535 (Dask's scheduler listens on 8786)"
        )
        raise ParameterError(_without_password(said, spec), "scheduler")


def check_scheduler(spec: str | None) -> None:
    """Refuse a bad ``--scheduler`` (malformed, or dask not installed) before any work."""
    if spec is not None:
        local_workers(spec)
        _dask()


@contextmanager
def connect(spec: str, lean: bool = True) -> Iterator[Any]:
    """A ``dask.distributed.Client`` for ``spec`` (see the module), closed on exit (with the
    local cluster it started, if any). ``lean``: a local cluster's workers start with
    :data:`LEAN_CONFIG` (False: Dask's defaults, the benchmark's point of comparison)."""
    n = local_workers(spec)
    dd = _dask()
    if n is not None:
        import dask

        # the workers start ignoring Ctrl-C, so the terminal's Ctrl-C (sent to the whole
        # process group) reaches this process alone, which closes them; each used to print
        # Dask's shutdown tracebacks under "posecbr ...: interrupted"
        cluster: Any = None
        client: Any = None
        try:
            with interrupts_ignored_by_children(), dask.config.set(LEAN_CONFIG if lean else {}):
                # the workers get the config they start with
                cluster = dd.LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    # no dashboard, but the scheduler's HTTP routes (health, metrics) still
                    # serve on 8787 unless told: a free port, so a second cluster (another
                    # command, a notebook's) does not warn that 8787 is taken
                    scheduler_kwargs={"dashboard_address": ":0"},
                    # posecbr says each unit's failure itself, and runs again those a dead
                    # worker lost: Dask's ERROR lines about them ("Removing worker ... caused
                    # the cluster to lose scattered data", "Couldn't gather keys") were
                    # printed under a run that then succeeded
                    silence_logs=logging.CRITICAL,
                )
                client = dd.Client(cluster)
            yield client
        except KeyboardInterrupt:
            _hush(client)
            raise
        finally:
            _close(client, cluster)
        return
    refused: ConfigError | None = None
    try:
        _refuse_other_than_a_scheduler(spec)
        client = dd.Client(spec, timeout=CONNECT_TIMEOUT_S)
    except ConfigError as exc:
        refused = exc
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        # TypeError: a scheme this Dask cannot connect by as set up (tls:// without
        # certificates, ucx:// without UCX)
        said = _without_password(f"cannot reach the Dask scheduler at {spec} ({exc})", spec)
        refused = ConfigError(said, "scheduler")
    if refused is not None:
        # the client that failed to connect is left half-built in a reference cycle, its loop
        # runner started: collected at some later moment, its __del__ closes it and takes
        # Dask's loop-runner lock, which a new client holds while it starts (a garbage
        # collection there hung the process for good). Collected now, outside any lock.
        gc.collect()
        raise refused
    with _client_logs_off():
        try:
            yield client
        except Exception as exc:
            if isinstance(exc, PosecbrError) or not _lost(client, exc):
                raise
            said = (
                f"lost the Dask scheduler at {spec} mid-run (it stopped, or the network to it "
                "failed): run the command again once it is back"
            )
            raise ConfigError(_without_password(said, spec), "scheduler") from None
        finally:
            client.close()


#: seconds a program that took the connection has to answer Dask's greeting, after
#: :data:`CONNECT_TIMEOUT_S` to connect
ANSWER_TIMEOUT_S = 5


def _refuse_other_than_a_scheduler(spec: str) -> None:
    """Refuse ``spec`` unless a Dask scheduler answers there, within :data:`CONNECT_TIMEOUT_S`
    and :data:`ANSWER_TIMEOUT_S`. Dask's client waits for the greeting of what it connected
    to without a deadline: a port where another program listens and says nothing (Dask's
    dashboard, 8787, for its scheduler's 8786: an HTTP server waits for a request line) hung
    the command for good. A Dask worker's or nanny's address is named as such (Dask said
    "Worker.identity() got an unexpected keyword argument", under its warnings). Asked on a
    thread of its own, so that a caller's running event loop (a notebook's) is no matter;
    OSError, TimeoutError, ValueError and TypeError as the client raises them."""
    asked: list[Any] = []

    def ask() -> None:
        try:
            asked.append(asyncio.run(asyncio.wait_for(_identity(spec), deadline)))
        except BaseException as exc:  # to be raised on the caller's thread
            asked.append(exc)

    deadline = CONNECT_TIMEOUT_S + ANSWER_TIMEOUT_S
    thread = threading.Thread(target=ask, name="posecbr-scheduler-check", daemon=True)
    thread.start()
    thread.join()
    (got,) = asked
    if isinstance(got, TimeoutError):  # the deadline's: Dask's own are OSErrors
        said = (
            f"{spec} took the connection but did not answer as a Dask scheduler (another "
            "program's port? Dask's scheduler listens on 8786, its dashboard on 8787)"
        )
        raise ConfigError(_without_password(said, spec), "scheduler")
    if isinstance(got, BaseException):
        raise got
    kind = got.get("type") if isinstance(got, dict) else None
    if not isinstance(kind, str):
        said = f"{spec} answered, but not as a Dask scheduler"
        raise ConfigError(_without_password(said, spec), "scheduler")
    if kind in _NOT_SCHEDULERS:
        said = f"{spec} is {_NOT_SCHEDULERS[kind]}, not the scheduler's"
        if got.get("scheduler"):
            said += f" (its scheduler: {got['scheduler']})"
        raise ConfigError(_without_password(said, spec), "scheduler")


#: the Dask servers that are no scheduler, by their identity's type
_NOT_SCHEDULERS = {
    "Worker": "a Dask worker's address",
    "Nanny": "a Dask nanny's address (the process that starts a worker)",
}


async def _identity(spec: str) -> Any:
    """What the Dask server at ``spec`` says it is (its ``identity``): a scheduler asked for
    none of its workers; another server (a worker, a nanny), which takes no such argument,
    asked again without it."""
    comms = importlib.import_module("distributed.comm")  # untyped: its attributes are Any
    args = _dask().Security().get_connection_args("client")
    comm = await comms.connect(spec, timeout=CONNECT_TIMEOUT_S, **args)
    try:
        await comm.write({"op": "identity", "n_workers": 0, "reply": True})
        got = await comm.read()
        if not (isinstance(got, dict) and "type" in got):
            await comm.write({"op": "identity", "reply": True})
            got = await comm.read()
        return got
    finally:
        await comm.close()


def _without_password(text: str, spec: str) -> str:
    """``text`` (words about the scheduler address ``spec``) with the password of
    ``spec``'s ``user:password@`` replaced by ``***``: Dask repeats the address without its
    scheme (``invalid address 'me:PW@head:8786'``), and one given without a scheme (Dask's
    tcp://) is no URL, where no password is looked for."""
    try:
        password = urlsplit(spec if "://" in spec else f"tcp://{spec}").password
    except ValueError:  # a port that is not a number
        return text
    return text.replace(f":{password}@", ":***@") if password else text


def _lost(client: Any, exc: BaseException) -> bool:
    """Whether ``exc`` comes of the client's connection to its scheduler being lost: a
    connection closed under it, or any error once the client no longer runs."""
    return type(exc).__name__ == "CommClosedError" or client.status != "running"


@contextmanager
def _client_logs_off() -> Iterator[None]:
    """The Dask client's own log off while it runs the command's work and closes: a scheduler
    lost mid-run is said in one line (:func:`connect`), where the client also printed its
    tries to reconnect with their tracebacks (the scheduler's and the workers' logs are
    theirs, where they run)."""
    log = logging.getLogger("distributed.client")
    level = log.level
    log.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        log.setLevel(level)


def _no_logs() -> None:
    """Dask's logging off in this process: its cluster is being closed mid-run, so each
    server logs the work it is losing, each worker the scheduler it lost ("Stream is
    closed", "caused the cluster to lose scattered data"): the run ends on Ctrl-C."""
    logging.disable(logging.CRITICAL)


def _hush(client: Any) -> None:
    """Dask's logging off here (the scheduler and the nannies) and on every worker, before a
    cluster interrupted mid-run (Ctrl-C) is closed: its one line is the command's."""
    _no_logs()
    if client is not None:
        with suppress(Exception):  # best effort: a worker gone meanwhile says nothing either
            client.run(_no_logs)


def _close(client: Any, cluster: Any) -> None:
    """Close a local cluster's client and the cluster (its workers end), whichever were made;
    Ctrl-C held meanwhile, so that a second one does not leave the workers running."""
    with interrupts_held():
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()


def _quiet_worker() -> None:
    # one progress bar, the client's: per-unit bars from the workers would garble it
    os.environ["POSECBR_NO_PROGRESS"] = "1"


def _run(fn: Callable[..., R], item: Any, *args: Any) -> R:
    _quiet_worker()
    return fn(item, *args)


def _message(exc: BaseException) -> str:
    if isinstance(exc, PosecbrError):
        return str(exc)
    if type(exc).__name__ == "KilledWorker":
        return "its worker died every time it ran it (out of memory?)"
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


def map_outcomes(
    client: Any,
    fn: Callable[..., R],
    items: Sequence[T],
    names: Sequence[str],
    *args: Any,
    desc: str = "tasks",
    unit: str = "task",
) -> Iterator[Outcome[R]]:
    """``fn(item, *args)`` for every item on the cluster, as each finishes (not in order).

    ``names`` name the items in error messages; ``args`` are sent to the workers once
    (scattered) and shared by every call. Exceptions become the unit's ``error``.
    """
    dd = _dask()
    batch = _Batch(client, fn, items, args)
    done = dd.as_completed(batch.futures)
    try:
        yield from progress(batch.finished(done, names), desc, total=len(items), unit=unit)
    finally:
        client.cancel(batch.futures)


#: times an item is sent again after its shared arguments were lost with a worker
RESUBMITS = 3


#: how often a wait for the next unit looks whether the client has given up its scheduler
LOST_POLL_S = 0.05


def _as_finished(done: Any, client: Any) -> Iterator[Any]:
    """The futures of ``done`` (Dask's ``as_completed``, to which more may be added) as each
    finishes. Raises once the client has given up a scheduler it lost (closing or closed
    after its tries to reconnect): ``as_completed`` alone waited for good on futures that
    never finish then (a scheduler stopped mid-run hung the command)."""
    while not done.is_empty():
        if done.has_ready():
            yield from done.next_batch(block=False)
        elif client.status in ("closing", "closed"):
            raise ConnectionError("the client gave up its lost scheduler")
        else:
            time.sleep(LOST_POLL_S)


class _Batch:
    """The futures of one :func:`map_outcomes` call. Its shared arguments are scattered to
    the workers; scattered data lives only on the workers that hold it, so a worker that dies
    holding the only copy takes it along and Dask cancels the calls that needed it. Those are
    sent again with the arguments scattered anew (at most :data:`RESUBMITS` times each)."""

    def __init__(self, client: Any, fn: Callable[..., Any], items: Sequence[Any],
                 args: tuple[Any, ...]) -> None:  # fmt: skip
        self.client, self.fn, self.items, self.args = client, fn, items, args
        self.generation = 0
        self.shared = self._scatter()
        self.futures = client.map(_run, [fn] * len(items), list(items),
                                  *[[a] * len(items) for a in self.shared], pure=False)  # fmt: skip
        self.index = {f.key: (i, 0) for i, f in enumerate(self.futures)}
        self.sent = [0] * len(items)

    def _scatter(self) -> list[Any]:
        """The shared arguments on every worker. Refused when the cluster has no worker (the
        scheduler waits the client's timeout for one): none joined a scheduler of the user's,
        or the last one died mid-run, its nanny too (an internal error, Dask's TimeoutError
        "No valid workers found", where a worker that died alone is started again)."""
        try:
            # each argument scattered as one object (a list is scattered element by element)
            return [self.client.scatter([a], broadcast=True, hash=False)[0] for a in self.args]
        except TimeoutError:
            raise ConfigError(
                "the Dask cluster has no worker to run the work on (none joined its scheduler "
                "in time, or every one stopped mid-run): start workers and run the command "
                "again",
                "scheduler",
            ) from None

    def _again(self, i: int, generation: int) -> Any:
        """Item ``i`` sent again; the arguments scattered anew unless that was done since the
        call that was lost was sent."""
        if generation == self.generation:
            self.shared, self.generation = self._scatter(), self.generation + 1
        self.sent[i] += 1
        fut = self.client.submit(_run, self.fn, self.items[i], *self.shared, pure=False)
        self.index[fut.key] = (i, self.generation)
        self.futures.append(fut)
        return fut

    def finished(self, done: Any, names: Sequence[str]) -> Iterator[Outcome[Any]]:
        """Every item's outcome, as each finishes."""
        for fut in _as_finished(done, self.client):
            i, generation = self.index[fut.key]
            outcome: Outcome[Any]
            if fut.status == "error":
                outcome = Outcome(i, names[i], error=_message(fut.exception()))
            else:
                try:
                    outcome = Outcome(i, names[i], value=fut.result())
                except CancelledError:  # its shared input was lost (the status may lag)
                    if self.sent[i] < RESUBMITS:
                        done.add(self._again(i, generation))
                        continue
                    outcome = Outcome(i, names[i], error="its input was lost with its worker")
            fut.release()
            yield outcome


def gather(outcomes: Iterator[Outcome[R]], n: int) -> tuple[list[R | None], list[Outcome[R]]]:
    """The values of ``n`` outcomes in item order, and the failed outcomes (in item order)."""
    values: list[R | None] = [None] * n
    failed: list[Outcome[R]] = []
    for o in outcomes:
        if o.ok:
            values[o.index] = o.value
        else:
            failed.append(o)
    return values, sorted(failed, key=lambda o: o.index)
