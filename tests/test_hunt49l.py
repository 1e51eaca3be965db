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
