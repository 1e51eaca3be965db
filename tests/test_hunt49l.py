"""Session 49, the lead's fixes: ``casebase`` with an empty ``--db``."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from posecbr.cli import main


@pytest.mark.parametrize(
    "action",
    [
        ["export", "--out", "x.npz"],
        ["upgrade"],
        ["list"],
        ["info"],
        ["trim", "--dry-run"],
        ["copy", "--to", "y.sqlite"],
    ],  # fmt: skip
    ids=lambda a: a[0],
)
def test_casebase_with_an_empty_db_says_so_and_writes_nothing(
    action: list[str],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Before: ``export`` an internal error (exit 70, "PosixPath('.') has an empty name"),
    ``upgrade`` ".: is a folder, not a case base file" (the working folder)."""
    monkeypatch.chdir(tmp_path)
    assert main(["casebase", *action, "--db", ""]) == 1
    err = capsys.readouterr().err.strip()
    assert err == (
        f"posecbr casebase {action[0]}: error: --db: is empty: name a case base file (SQLite)"
        " or a SQLAlchemy URL"
    )
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("returning", [True, False], ids=["returning", "sqlite-before-3.35"])
def test_cases_are_stored_with_and_without_insert_returning(
    returning: bool, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Cases are inserted with RETURNING (their ids in order) where the database has it, and
    one by one where it has not (SQLite before 3.35, as on Ubuntu 20.04, which SQLAlchemy
    tells by ``sqlite3.sqlite_version_info``): the same cases, ids 1..n in the order given.
    Before, nothing could be stored there (SQLAlchemy refuses RETURNING)."""
    import sqlite3

    import numpy as np

    from casebase_store import NewCase, open_store

    if not returning:
        monkeypatch.setattr(sqlite3.dbapi2, "sqlite_version_info", (3, 31, 1))
    new = [NewCase(f"a{i % 2}", np.array([i, 2.0 * i]), f"c{i}.npz", 0, 9) for i in range(6)]
    with open_store(str(tmp_path / "cb.sqlite"), create=True) as store:
        assert store.engine.dialect.insert_returning is returning
        with store.transaction() as tx:
            info = tx.create_case_base("default", {"f": 1}, ["a", "b"], ["a", "b"],
                                       {"name": "euclidean"})  # fmt: skip
            assert tx.add_cases(info, new) == [1, 2, 3, 4, 5, 6]
        with store.transaction() as tx:
            found = [
                c for chunk in tx.cases_framed(tx.case_base("default"), [(0, 9)]) for c in chunk
            ]
    assert [(c.id, c.source, list(c.features)) for c in found] == [
        (i + 1, f"c{i}.npz", [i, 2.0 * i]) for i in range(6)
    ]


def test_ctrl_c_while_the_console_script_imports_the_command_line_is_the_stop() -> None:
    """The console script's entry (``posecbr.console:run``) with Ctrl-C arriving while
    ``posecbr.cli`` is imported (a KeyboardInterrupt raised inside the import, as Python's
    SIGINT handler raises it there): one line, exit 130. Before, ``posecbr.cli:main`` was the
    entry, and the import ran in the script itself: Python's traceback, ended by SIGINT."""
    import subprocess
    import sys

    script = (
        "import sys\n"
        "class Interrupted:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'posecbr.cli':\n"
        "            raise KeyboardInterrupt\n"
        "sys.meta_path.insert(0, Interrupted())\n"
        "from posecbr.console import run\n"
        "run()\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert (proc.returncode, proc.stderr, proc.stdout) == (130, "posecbr: interrupted\n", "")


def test_the_console_script_runs_the_command_line() -> None:
    """``pyproject.toml``'s one console command is ``posecbr.console:run``, which gives
    ``posecbr.cli.main``'s status as the process's."""
    import subprocess
    import sys
    import tomllib

    with open(Path(__file__).resolve().parents[1] / "pyproject.toml", "rb") as f:
        assert tomllib.load(f)["project"]["scripts"] == {"posecbr": "posecbr.console:run"}
    script = (
        "import sys\nsys.argv = ['posecbr', 'no-such-command']\n"
        "from posecbr.console import run\nrun()\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2 and "invalid choice: 'no-such-command'" in proc.stderr
