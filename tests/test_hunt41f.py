"""Hunt 41f: the suite takes Ctrl-C as a terminal's foreground job does, however it was
started (a background job of a script starts with SIGINT ignored)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: a Python process that sends itself SIGINT: it dies of it (the status -2) unless SIGINT was
#: ignored when it started, when it sleeps the 30 s out and exits 0
SENDS_ITSELF_CTRL_C = "import os, signal, time; os.kill(os.getpid(), signal.SIGINT); time.sleep(30)"


def test_ctrl_c_interrupts_a_test_and_what_it_starts() -> None:
    """A SIGINT raises KeyboardInterrupt in the test's process (as the tests of a command
    sent Ctrl-C expect), and ends a process the test starts, as Ctrl-C ends it."""
    with pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(30)  # the handler runs here
    child = subprocess.run(
        [sys.executable, "-c", SENDS_ITSELF_CTRL_C], capture_output=True, timeout=120
    )
    assert child.returncode == -signal.SIGINT


def test_a_run_started_with_ctrl_c_ignored_still_takes_it() -> None:
    """pytest started as a script's background job (SIGINT ignored, as ``bash -c 'pytest
    ... &'`` starts it) runs the test above as in a terminal. Before, SIGINT stayed ignored
    in the tests and in what they started: ``tests/test_hunt34i.py``'s ``describe`` sent
    SIGINT exited 0, not 130 (a flake of a run started so)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
    test = f"{Path(__file__).relative_to(ROOT)}::test_ctrl_c_interrupts_a_test_and_what_it_starts"
    run = subprocess.run(  # -v undoes the configured -q: the summary line is printed
        [sys.executable, "-m", "pytest", "-v", "-n", "0", "-p", "no:cacheprovider", test],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "= 1 passed in " in run.stdout  # run, not skipped or deselected
