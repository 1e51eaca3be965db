"""A worker stopped by SIGTERM ends with no hidden temporary left, however its task ends.

``extract --workers 2`` stopped by Ctrl-C left one on CI (tests/test_hunt34i.py's Ctrl-C
test; not seen in 28 runs here under load). Two ways a worker could leave one, both made
here on purpose: its task's interrupt lost (raised inside a finaliser, a ``__del__`` running
just then, Python prints it and goes on; the task went on and the pool's second SIGTERM ended
the worker UNWIND_GRACE_S later wherever it was), and SIGTERM again while the worker's
handler was taking the first (taken as a SIGTERM to an idle worker: ended on the spot).
"""

from __future__ import annotations

from pathlib import Path

from tests.test_hunt34i import pool_script_lines

SCRIPT = """
import concurrent.futures as cf, multiprocessing, os, sys, time
import features.interrupts as interrupts
from features.fileio import atomic_path
from features.interrupts import run_task, stop_workers

class Finaliser:
    def __del__(self):
        time.sleep(60)  # SIGTERM comes here: its interrupt is printed, not raised

def task(path, lost):
    with atomic_path(path) as tmp:  # the hidden temporary of the output being written
        tmp.write_text("begun")
        if lost:
            Finaliser()  # dropped at once: its __del__ runs
        time.sleep(20)
        tmp.write_text("written after the signal")

def init():
    interrupts.UNWIND_GRACE_S = 1.0
    interrupts.worker_ends_on_sigterm()

if __name__ == "__main__":
    folder = sys.argv[1]
    paths = [os.path.join(folder, name) for name in ("quick", "lost")]
    with cf.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn"),
                                initializer=init) as pool:
        futures = [pool.submit(run_task, task, path, lost)
                   for path, lost in zip(paths, (False, True))]
        while len(os.listdir(folder)) < 2:
            time.sleep(0.02)
        time.sleep(0.2)  # the second task inside its finaliser
        workers = list(pool._processes.values())
        stop_workers(pool)
    print(sorted(p.exitcode for p in workers), sorted(os.listdir(folder)))
"""


def test_a_worker_whose_interrupt_is_lost_ends_and_removes_what_it_was_writing(
    tmp_path: Path,
) -> None:
    """Both workers end, status 143, and neither leaves a file: not the hidden temporary
    (left when the worker was ended in the middle of its task), nor the output (written when
    the task went on to its end)."""
    assert pool_script_lines(SCRIPT, tmp_path) == ["[143, 143] []"]


NESTED = """
import os, signal, sys, threading, time
import features.interrupts as interrupts
from features.fileio import atomic_path

folder = sys.argv[1]
interrupts.worker_ends_on_sigterm()
start = threading.Timer.start

def start_after_another_sigterm(self):
    os.kill(os.getpid(), signal.SIGTERM)  # the pool's SIGTERM, as the first is handled
    start(self)

threading.Timer.start = start_after_another_sigterm

def task(path):
    try:
        with atomic_path(path) as tmp:
            tmp.write_text("begun")
            os.kill(os.getpid(), signal.SIGTERM)  # stop_workers'
            time.sleep(20)
    finally:
        print("unwound", os.listdir(folder), flush=True)

interrupts.run_task(task, os.path.join(folder, "out"))
"""


def test_a_second_sigterm_while_the_first_is_handled_lets_the_task_unwind(
    tmp_path: Path,
) -> None:
    """SIGTERM again while the worker's handler is still taking the first (the handler run
    inside itself): the task unwinds, its temporary removed, then the worker ends, 143.
    (Taken as a SIGTERM to an idle worker, it ended the worker on the spot.)"""
    import subprocess
    import sys

    from tests.test_hunt34i import ENV

    script = tmp_path / "nested.py"
    script.write_text(NESTED)
    (tmp_path / "work").mkdir()
    run = subprocess.run([sys.executable, str(script), str(tmp_path / "work")], env=ENV,
                         capture_output=True, text=True, timeout=60)  # fmt: skip
    assert (run.returncode, run.stdout, run.stderr) == (143, "unwound []\n", "")
