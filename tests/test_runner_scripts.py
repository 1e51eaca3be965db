"""A script that starts worker processes as it is imported: the spawned workers import it again
and die; the error says so (and names the script) instead of blaming memory alone."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _run(script: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=120, cwd=ROOT
    )


def test_unguarded_script_is_told_to_guard_its_main(tmp_path: Path) -> None:
    script = tmp_path / "unguarded.py"
    script.write_text(
        textwrap.dedent(
            """
            from cbr.evaluation.runner import ProcessRunner
            from features.errors import PosecbrError

            def double(context, task):
                return 2 * task

            try:
                print(sorted(ProcessRunner(None, None, jobs=2).map(double, [1, 2, 3])))
            except PosecbrError as e:
                print("ERROR", e)
            """
        )
    )
    out = _run(script).stdout.strip().splitlines()
    assert len(out) == 1 and out[0].startswith("ERROR"), out
    assert str(script) in out[0]
    assert 'if __name__ == "__main__":' in out[0]


def test_guarded_script_runs_its_tasks_in_workers(tmp_path: Path) -> None:
    script = tmp_path / "guarded.py"
    script.write_text(
        textwrap.dedent(
            """
            from cbr.evaluation.runner import ProcessRunner

            def double(context, task):
                return context * task

            if __name__ == "__main__":
                print(sorted(ProcessRunner(3, None, jobs=2).map(double, [1, 2, 3])))
            """
        )
    )
    done = _run(script)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[3, 6, 9]"
