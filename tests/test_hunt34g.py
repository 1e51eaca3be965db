"""Case base store faults found by hunt 34g (a case base maintained over months: old schemas,
read-only and full disks, several processes): real SQLite files, real processes where a
read-only mount is the point."""

from __future__ import annotations

import hashlib
import os
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import read_only_mounts_work

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
V1_SQL = Path(__file__).with_name("fixtures") / "store_v1.sql"

needs_mounts = pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _v1_store(db: Path, *, wal: bool) -> Path:
    """A real case base written by posecbr 0.1 (schema version 1), in WAL mode as 0.1 left
    its files, or with a rollback journal."""
    con = sqlite3.connect(db)
    con.executescript(V1_SQL.read_text(encoding="utf-8"))
    mode = "WAL" if wal else "DELETE"
    assert con.execute(f"PRAGMA journal_mode = {mode}").fetchone() == (mode.lower(),)
    con.close()
    return db


def _upgrade_read_only(db: Path, what: str) -> subprocess.CompletedProcess[str]:
    """``posecbr casebase upgrade --db db`` with ``what`` ("folder": db's folder, "file": db
    alone) on a private read-only mount, which not even root can write to."""
    target = db.parent if what == "folder" else db
    script = (
        f"mount --bind {target} {target} && mount -o remount,ro,bind {target} {target} && "
        f"[ -w {db} ] && exit 99; "  # the file must really be read-only (access(2): EROFS)
        f'exec "$0" -m posecbr "$@"'
    )
    return subprocess.run(
        ["unshare", "-rm", "sh", "-c", script, sys.executable, "casebase", "upgrade", "--db",
         str(db)],
        cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=300,
    )  # fmt: skip


@needs_mounts
@pytest.mark.parametrize("wal", [False, True], ids=["journal", "wal"])
def test_upgrade_of_an_old_store_in_a_read_only_folder_says_the_folder_is_read_only(
    tmp_path: Path, wal: bool
) -> None:
    # before: "cannot open or write the database (unable to open database file)" (WAL mode)
    # or "(attempt to write a readonly database)", not naming why, unlike every other writer
    folder = tmp_path / "ro"
    folder.mkdir()
    db = _v1_store(folder / "old.sqlite", wal=wal)
    before = _sha(db)
    done = _upgrade_read_only(db, "folder")
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"posecbr casebase upgrade: error: {db}: cannot write the case base file: the folder "
        f"{folder} is read-only (SQLite writes its journal beside it)"
    ]
    assert done.stdout == ""
    assert _sha(db) == before and sorted(p.name for p in folder.iterdir()) == ["old.sqlite"]


@needs_mounts
def test_upgrade_of_a_read_only_file_in_wal_mode_leaves_no_side_files(tmp_path: Path) -> None:
    # before: "database error: disk I/O error", and old.sqlite-wal and old.sqlite-shm were
    # left beside the file (its folder can be written; SQLite opened the file to write)
    db = _v1_store(tmp_path / "old.sqlite", wal=True)
    before = _sha(db)
    done = _upgrade_read_only(db, "file")
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"posecbr casebase upgrade: error: {db}: cannot write the case base file: it is read-only"
    ]
    assert _sha(db) == before and sorted(p.name for p in tmp_path.iterdir()) == ["old.sqlite"]


@needs_mounts
def test_upgrade_of_a_current_store_in_a_read_only_folder_still_has_nothing_to_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    db = _v1_store(folder / "cb.sqlite", wal=False)
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    capsys.readouterr()
    before = _sha(db)
    done = _upgrade_read_only(db, "folder")
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"{db}: already schema version 2, nothing to do\n"
    assert _sha(db) == before and sorted(p.name for p in folder.iterdir()) == ["cb.sqlite"]
