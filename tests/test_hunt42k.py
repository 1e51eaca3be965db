"""A worker stopped by SIGTERM finishes unwinding its task when SIGTERM comes again.

``stop_workers`` sends SIGTERM to every worker; as soon as one has ended, the pool (finding
a process gone: its "broken" state) sends SIGTERM again to every worker left. One still
unwinding its task then ended on the spot, before the task's clean-up had removed the hidden
temporary of the file it was writing: ``extract --workers 2`` stopped by Ctrl-C left one now
and then, under load (tests/test_hunt34i.py's Ctrl-C test, 1 run in 9).
"""

from __future__ import annotations

from pathlib import Path

from tests.test_hunt34i import pool_script_lines

SCRIPT = """
import concurrent.futures as cf, multiprocessing, os, sys, time
from features.interrupts import run_task, stop_workers, worker_ends_on_sigterm

def task(path, unwinding_s):
    open(path, "w").close()  # the hidden temporary of the output being written
    try:
        time.sleep(60)
    finally:
        time.sleep(unwinding_s)  # a clean-up that takes a while (a loaded machine)
        os.remove(path)

if __name__ == "__main__":
    folder = sys.argv[1]
    paths = [os.path.join(folder, name) for name in ("quick", "slow")]
    with cf.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn"),
                                initializer=worker_ends_on_sigterm) as pool:
        futures = [pool.submit(run_task, task, path, s) for path, s in zip(paths, (0, 3))]
        while not all(os.path.exists(p) for p in paths):
            time.sleep(0.02)
        workers = list(pool._processes.values())
        stop_workers(pool)
    print(sorted(p.exitcode for p in workers), sorted(os.listdir(folder)))
"""


def test_a_worker_sent_sigterm_twice_still_removes_what_it_was_writing(tmp_path: Path) -> None:
    """Both workers end with status 143 (128 + SIGTERM) and neither leaves its file: the slow
    one's clean-up (3 s) outlasts the quick one's end, after which the pool's own SIGTERM
    reaches it; before, that SIGTERM ended it with its file left."""
    assert pool_script_lines(SCRIPT, tmp_path) == ["[143, 143] []"]
