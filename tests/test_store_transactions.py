"""The case base store: atomic user actions, concurrent writers, clear errors on bad files."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from casebase_store import CaseStore, NewCase, StoreError, open_store

ROOT = Path(__file__).resolve().parents[1]


def _run_py(code: str, *args: str) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
    return subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(code), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _new_base(path: Path, name: str, n: int) -> None:
    store = open_store(path, create=True)
    with store.transaction() as tx:
        cb = tx.create_case_base(name, {"level": "fluents"}, ["a", "b"], ["a", "b"], {"name": "x"})
        tx.add_cases(cb, [NewCase(f"l{i % 3}", np.full((4, 2), i, np.float32)) for i in range(n)])
    store.close()


def test_round_trip_keeps_labels_with_quotes_and_unicode(tmp_path: Path) -> None:
    labels = ['squat "deep"', "l'arc", "Kniebeuge – tief ✓", "腕立て伏せ", "a,b;c\nd"]
    store = open_store(tmp_path / "cb.sqlite", create=True)
    with store.transaction() as tx:
        cb = tx.create_case_base("ünï 'base'", {"level": "fluents"}, ["x"], ["x"], {"name": "dtw"})
        tx.add_cases(cb, [NewCase(lab, np.eye(3) * i) for i, lab in enumerate(labels)])
    again = open_store(tmp_path / "cb.sqlite")
    got = again.load_cases("ünï 'base'")
    assert list(got.labels) == labels
    np.testing.assert_array_equal(got.features[2], np.eye(3) * 2)
    assert again.get_case_base("ünï 'base'").label_counts == {lab: 1 for lab in labels}


KILLED_TRAIN = """
import sys, time, numpy as np
from casebase_store import NewCase, open_store
store = open_store(sys.argv[1], create=True)
def cases():
    for i in range(3000):
        if i == 2600:
            print("MID", flush=True)   # 5 flushes of 500 rows are already in the file
            time.sleep(60)
        yield NewCase("squat", np.full((64, 64), i, np.float64), source=f"clip{i}")
with store.transaction() as tx:
    cb = tx.create_case_base("new", {"level": "fluents"}, ["a"], ["a"], {"name": "dtw"})
    tx.add_cases(cb, cases())
    tx.log(cb, "build", reason="all")
print("DONE", flush=True)
"""


def test_train_killed_mid_transaction_leaves_store_as_before(tmp_path: Path) -> None:
    db = tmp_path / "cb.sqlite"
    _new_base(db, "old", 7)
    size_before = db.stat().st_size
    proc = _run_py(KILLED_TRAIN, str(db))
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert line.strip() == "MID", proc.stderr.read() if proc.stderr else ""
    # 80 MB of rows overflow SQLite's page cache: they reached the file (a hot journal beside it)
    assert db.stat().st_size > size_before + 50_000_000
    assert (tmp_path / "cb.sqlite-journal").exists()
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)
    store = open_store(db)
    assert [cb.name for cb in store.list_case_bases()] == ["old"]
    assert store.count_cases("old") == 7
    # the store is healthy: a complete run afterwards stores everything
    done = _run_py(KILLED_TRAIN.replace("i == 2600", "i == -1"), str(db))
    out, err = done.communicate(timeout=60)
    assert out.strip() == "DONE", err
    assert store.count_cases("new") == 3000
    assert [e.action for e in store.maintenance_log("new")] == ["build"]


CONCURRENT_RETAIN = """
import sys, time
import numpy as np
from casebase_store import open_store
from cbr.casebase import CaseBase
from cbr.problem import FeatureConfig
from cbr.retain import record_retention, retain
from cbr.similarity import get_measure
db, tag, go = sys.argv[1], sys.argv[2], sys.argv[3]
store = open_store(db)
a = store.load_cases("shared")
cb = CaseBase(FeatureConfig(), get_measure("euclidean"), a.features, a.labels, (), (), a.ids)
rng = np.random.default_rng(int(tag))
while not __import__("os").path.exists(go):
    time.sleep(0.01)
for i in range(200):
    p = rng.normal(size=(4, 2))
    d = retain(cb, p, f"p{tag}", k=3, novelty_threshold=0.0, benefit_threshold=0.0, scale=1.0)
    assert d.retained
    with store.transaction() as tx:
        record_retention(tx, tx.case_base("shared"), d, p, f"p{tag}", source=f"{tag}-{i}")
print("OK", flush=True)
"""


def retained_by_two_processes(url: str, tmp_path: Path) -> CaseStore:
    """The store at ``url`` with a case base "shared" of 4 cases, into which two processes
    started together (:data:`CONCURRENT_RETAIN`) have each retained 200 cases: checked that
    both said OK and that all 400 cases and labels are there."""
    store = open_store(url, create=True)
    with store.transaction() as tx:
        cb = tx.create_case_base(
            "shared", {"level": "fluents"}, ["a", "b"], ["a", "b"], {"name": "euclidean"}
        )
        tx.add_cases(cb, [NewCase(f"l{i % 2}", np.full((4, 2), i, np.float32)) for i in range(4)])
    go = tmp_path / "go"
    procs = [_run_py(CONCURRENT_RETAIN, url, tag, str(go)) for tag in ("1", "2")]
    time.sleep(1.5)  # both have imported and loaded the case base: start together
    go.touch()
    for p in procs:
        out, err = p.communicate(timeout=120)
        assert out.strip() == "OK", err
    assert store.count_cases("shared") == 4 + 400
    counts = store.get_case_base("shared").label_counts
    assert counts["p1"] == 200 and counts["p2"] == 200
    return store


def test_two_processes_retaining_200_each_end_with_400_more(tmp_path: Path) -> None:
    store = retained_by_two_processes(str(tmp_path / "cb.sqlite"), tmp_path)
    assert sum(e.action == "retain" for e in store.maintenance_log("shared")) == 400


def test_corrupt_and_foreign_files_get_one_clear_error(tmp_path: Path) -> None:
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(os.urandom(8192))
    with pytest.raises(StoreError, match="not a readable SQLite database") as e:
        open_store(junk)
    assert str(junk) in str(e.value)

    text = tmp_path / "notes.sqlite"
    text.write_text("these are my notes\n" * 300)
    with pytest.raises(StoreError, match="not a readable SQLite database"):
        open_store(text)

    other = tmp_path / "other.sqlite"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE customers (id INTEGER)")
    con.commit()
    con.close()
    with pytest.raises(StoreError, match="not a posecbr case base store.*customers"):
        open_store(other)

    with pytest.raises(StoreError, match="no such case base file"):
        open_store(tmp_path / "missing.sqlite", create=False)


def test_schema_version_mismatch_is_refused(tmp_path: Path) -> None:
    db = tmp_path / "cb.sqlite"
    _new_base(db, "x", 2)
    con = sqlite3.connect(db)
    con.execute("UPDATE posecbr_schema_version SET version = 99")
    con.commit()
    con.close()
    with pytest.raises(StoreError, match="schema version 99.*reads version 2"):
        open_store(db)


def test_locked_database_reports_locked_and_names_the_file(tmp_path: Path) -> None:
    # a fresh file another program holds an exclusive lock on (rollback-journal mode)
    db = tmp_path / "locked.sqlite"
    holder = sqlite3.connect(db, isolation_level=None)
    holder.execute("CREATE TABLE t (x)")
    holder.execute("BEGIN EXCLUSIVE")
    t0 = time.monotonic()
    with pytest.raises(StoreError, match="locked by another process") as e:
        open_store(db, timeout_s=0.3)
    assert time.monotonic() - t0 < 5
    assert str(db) in str(e.value)
    holder.execute("ROLLBACK")
    holder.close()

    # an existing store whose writer lock is held: reads work, the write waits then fails
    db2 = tmp_path / "busy.sqlite"
    _new_base(db2, "x", 3)
    writer = sqlite3.connect(db2, isolation_level=None)
    writer.execute("BEGIN IMMEDIATE")
    store = open_store(db2, timeout_s=0.3)
    assert store.count_cases("x") == 3
    with pytest.raises(StoreError, match="locked by another process"):
        store.add_cases("x", [NewCase("l0", np.zeros((4, 2)))])
    writer.execute("ROLLBACK")
    store.add_cases("x", [NewCase("l0", np.zeros((4, 2)))])
    assert store.count_cases("x") == 4


def test_failed_action_rolls_back_everything(tmp_path: Path) -> None:
    store = open_store(tmp_path / "cb.sqlite", create=True)
    with pytest.raises(StoreError, match="unknown case origin"):
        with store.transaction() as tx:
            cb = tx.create_case_base("x", {"level": "fluents"}, ["a"], ["a"], {"name": "dtw"})
            tx.add_cases(cb, [NewCase("a", np.zeros(2)), NewCase("b", np.zeros(2), origin="?")])
    assert store.list_case_bases() == []
    with store.transaction() as tx:
        tx.create_case_base("x", {"level": "fluents"}, ["a"], ["a"], {"name": "dtw"})
    with pytest.raises(StoreError, match="already exists"), store.transaction() as tx:
        tx.create_case_base("x", {"level": "qmp"}, ["a"], ["a"], {"name": "dtw"})
    assert store.get_case_base("x").feature_config == {"level": "fluents"}


def test_sqlalchemy_url_opens_the_same_store(tmp_path: Path) -> None:
    db = tmp_path / "cb.sqlite"
    _new_base(db, "x", 5)
    store = open_store(f"sqlite:///{db}")
    assert store.where == str(db) and store.count_cases("x") == 5
    with pytest.raises(StoreError, match="not a database URL|cannot use database URL"):
        open_store("nosuchdialect://user@host/db")
