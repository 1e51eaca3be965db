"""Hunt 49i: ``casebase upgrade`` of a read-only file of the current schema version lacking
an index or a column (made before them: hunt 49d's ``cases.poses``) answered "already schema
version 2, nothing to do" (exit 0), as if it had none to add.

A real SQLite file, the command in a child process on a read-only mount.
"""

from __future__ import annotations

import contextlib
import sqlite3
from pathlib import Path

import pytest

from tests.badinput import posecbr_on_read_only_mount, read_only_mounts_work


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)
def test_upgrade_of_a_read_only_current_store_lacking_an_index_and_a_column_says_so(
    tmp_path: Path,
) -> None:
    """A store of the current schema version made before the index on the cases' sources and
    their poses column, the file read-only (a private read-only mount, which not even root
    can write to): refused naming what the upgrade would add and why it cannot, exit 1,
    nothing written (before: "already schema version 2, nothing to do", exit 0)."""
    from casebase_store import open_store

    db = tmp_path / "cb.sqlite"
    open_store(db, create=True).close()
    with contextlib.closing(sqlite3.connect(db)) as con, con:
        con.execute("ALTER TABLE cases DROP COLUMN poses")
        con.execute("DROP INDEX ix_cases_case_base_id_source")
    before = db.read_bytes()
    done = posecbr_on_read_only_mount(db, ["casebase", "upgrade", "--db", str(db)], db)
    assert (done.returncode, done.stdout) == (1, ""), done.stderr
    assert done.stderr.splitlines() == [
        f"posecbr casebase upgrade: error: {db}: would add the index "
        "ix_cases_case_base_id_source and the column cases.poses of a newer schema, but "
        "cannot write the case base file: it is read-only"
    ]
    assert db.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["cb.sqlite"]
