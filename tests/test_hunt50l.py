"""Hunt 50l: small library loose ends left by hunts 50f (the library API) and 50g (stores
under stress).

- ``casebase upgrade`` that failed partway (a file size limit reached as the conversion's
  pages spilled into the file) left the file changed and its journal beside it, read by
  every reader as a killed writer's: it now undoes the failed write as a store's
  transaction does.
"""

from __future__ import annotations

import resource
import sqlite3
from collections.abc import Callable
from pathlib import Path

import pytest

from posecbr.cli import main

V1_SQL = Path(__file__).with_name("fixtures") / "store_v1.sql"


def _v1_store_of_long_sources(db: Path) -> None:
    """A case base written by posecbr 0.1 (schema version 1, tests/fixtures/store_v1.sql) with
    500 cases more, each a copy of its first case with a source of 3,000 characters: the
    upgrade's index on the sources (new in schema 2) grows the file by some 1.5 MB, past the
    store's page cache (2 MB), so pages spill into the file before the upgrade ends."""
    con = sqlite3.connect(db)
    con.executescript(V1_SQL.read_text(encoding="utf-8"))
    assert con.execute("PRAGMA journal_mode = DELETE").fetchone() == ("delete",)
    cols = [c[1] for c in con.execute("PRAGMA table_info(cases)") if c[1] not in ("id", "source")]
    row = con.execute(f"SELECT {', '.join(cols)} FROM cases WHERE id = 1").fetchone()
    marks = ", ".join("?" * (len(cols) + 1))
    con.executemany(
        f"INSERT INTO cases ({', '.join(cols)}, source) VALUES ({marks})",
        [(*row, f"{i:03000d}") for i in range(500)],
    )
    con.commit()
    con.close()


def test_an_upgrade_past_a_file_size_limit_leaves_the_file_as_it_was(
    tmp_path: Path, file_size_limit: Callable[[int], None], capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the file changed, its journal left beside it; every reader then said "its last
    # change was interrupted (the process writing it was killed)", of an upgrade that had
    # said its error and ended
    db = tmp_path / "old.sqlite"
    _v1_store_of_long_sources(db)
    before = db.read_bytes()
    file_size_limit(len(before) * 5 // 4)  # the upgraded file is some 1.6 times as large
    assert main(["casebase", "upgrade", "--db", str(db)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "a size limit such as `ulimit -f`" in err[0]
    assert db.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.sqlite"]
    file_size_limit(resource.RLIM_INFINITY)
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert "converted from schema version 1 to 2" in capsys.readouterr().out
