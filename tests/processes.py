"""Running `posecbr` in a process of its own, paused at a chosen point so a test can kill it
there (deterministic fault injection: no race against the clock)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def posecbr_process(
    *argv: str, pause_after: str | None = None, gate: Path | None = None
) -> subprocess.Popen[str]:
    """`posecbr ARGV` in its own process. With ``pause_after`` it prints PAUSED and sleeps right
    after the store logs that action inside its transaction (for a test to kill it there); with
    ``gate`` it prints PAUSED after the first clip's feedback committed and waits, outside any
    transaction, until the file ``gate`` exists."""
    code = textwrap.dedent(
        """
        import os, sys, time
        from casebase_store import store as st
        import cbr.classification as cl
        pause, gate = sys.argv[1], sys.argv[2]
        if pause:
            log = st.StoreTransaction.log
            def paused(self, info, action, **kw):
                log(self, info, action, **kw)
                if action == pause:
                    print("PAUSED", flush=True)
                    time.sleep(120)
            st.StoreTransaction.log = paused
        if gate:
            learn, calls = cl._learn, []
            def gated(*a, **kw):
                out = learn(*a, **kw)
                calls.append(1)
                if len(calls) == 1:
                    print("PAUSED", flush=True)
                    while not os.path.exists(gate):
                        time.sleep(0.01)
                return out
            cl._learn = gated
        from posecbr.cli import main
        sys.exit(main(sys.argv[3:]))
        """
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
    return subprocess.Popen(
        [sys.executable, "-c", code, pause_after or "", str(gate or ""), *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def terminal_job(argv: list[str], cwd: Path) -> subprocess.Popen[bytes]:
    """``python -m posecbr ARGV`` as a terminal runs a job: in a process group of its own
    (so a test can send Ctrl-C to the whole group with ``os.killpg``), SIGINT not ignored
    (a shell's background job ignores it), this checkout first on the path, no progress."""
    env = {**os.environ, "POSECBR_NO_PROGRESS": "1"}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return subprocess.Popen(
        [sys.executable, "-m", "posecbr", *argv],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
