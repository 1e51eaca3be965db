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

import numpy as np
import pytest
from sqlalchemy.engine import make_url

from casebase_store import open_store
from posecbr.cli import main
from tests.badinput import posecbr_on_read_only_mount, read_only_mounts_work, small_case_base
from tests.test_bad_input_casebase import assert_upgraded_store_v1
from tests.test_hunt39e import _changes_in_wal, _wal
from tests.test_store_postgres import pg_server, pg_url  # noqa: F401  (fixtures)

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
    return posecbr_on_read_only_mount(target, ["casebase", "upgrade", "--db", str(db)], db)


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


def _v1_on_postgres(url: str, tmp_path: Path) -> None:
    """The posecbr 0.1 store of tests/fixtures/store_v1.sql on PostgreSQL: posecbr 0.1's
    tables there were today's without the case bases' uid, version and model (the same
    SERIAL ids), its rows copied from the SQLite file with their ids."""
    from sqlalchemy import MetaData, create_engine, text

    open_store(url, create=True).close()  # today's tables
    src = sqlite3.connect(_v1_store(tmp_path / "v1.sqlite", wal=False))
    src.row_factory = sqlite3.Row
    engine = create_engine(url)
    try:
        with engine.begin() as conn:
            conn.execute(text("ALTER TABLE case_bases DROP COLUMN uid, DROP COLUMN version, "
                              "DROP COLUMN model"))  # fmt: skip
            conn.execute(text("UPDATE posecbr_schema_version SET version = 1"))
            tables = MetaData()
            tables.reflect(conn)
            for name in ("case_bases", "cases", "maintenance_log"):
                rows = [dict(r) for r in src.execute(f"SELECT * FROM {name}")]  # noqa: S608
                conn.execute(tables.tables[name].insert(), rows)
            # posecbr 0.1 took each id from the table's sequence
            for name in ("case_bases", "cases", "maintenance_log"):
                conn.execute(text(f"SELECT setval(pg_get_serial_sequence('{name}', 'id'), "
                                  f"(SELECT MAX(id) FROM {name}))"))  # fmt: skip
    finally:
        engine.dispose()
        src.close()


def test_a_store_of_schema_1_on_postgresql_is_refused_then_upgraded_in_place(
    pg_url: str,  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    # before: the refusal told a database URL's user to run `posecbr casebase upgrade --db
    # FILE`; the upgrade itself (ids kept, sequences moved past them) was tested on SQLite only
    _v1_on_postgres(pg_url, tmp_path)
    clip = ROOT / "posecbr" / "demo_data" / "uiprmd" / "m01_s03_e01.npz"
    assert main(["classify", str(clip), "--db", pg_url]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "schema version 1" in err
    assert err.endswith("(convert it with `posecbr casebase upgrade --db URL`)"), err
    assert main(["casebase", "upgrade", "--db", pg_url]) == 0
    assert "converted from schema version 1 to 2" in capsys.readouterr().out
    assert_upgraded_store_v1(pg_url, capsys)  # every case keeps its id
    # a new case takes the id after the highest, never an old one
    assert main(["classify", str(clip), "--db", pg_url, "--feedback", "deep_squat",
                 "--novelty", "0", "--benefit", "0"]) == 0  # fmt: skip
    store = open_store(pg_url, readonly=True)
    assert store.load_cases("squats ✓").ids.tolist() == list(range(1, 10))
    store.close()


def _tmpfs_mounts_work() -> bool:
    """Whether this machine can mount a private tmpfs (``unshare -rm``): how a test gives a
    folder whose disk is full."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        try:
            script = f"mount -t tmpfs -o size=8k tmpfs {d}"
            done = subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True)
        except OSError:
            return False
        return done.returncode == 0


@pytest.mark.skipif(
    not _tmpfs_mounts_work(), reason="this machine cannot mount a private tmpfs (unshare -rm)"
)
def test_a_full_disk_for_the_matrices_is_a_note_after_the_stored_change_not_a_bus_error(
    tmp_path: Path,
) -> None:
    # before: the matrix was written through a memory map, and a page that found no room on
    # the disk killed the process with SIGBUS ("Bus error", exit 135) after the feedback had
    # committed, its temporary file left in the folder; run again, the feedback was stored twice
    db = small_case_base(tmp_path)
    store = open_store(db, readonly=True)
    n_cases = store.count_cases("default")
    problems = store.load_case_base("default")[1].features
    store.close()
    size = problems.size * 8
    assert size > 3 * 4096  # the matrix needs more pages than the disk below has
    matrices = db.with_name(db.name + ".matrices")
    matrices.mkdir()
    stored = sorted((tmp_path / "train").rglob("*.npz"))[0]
    label = stored.parent.name
    # a clip no case is made of (a stored clip's case is not retained again): the stored
    # one without its first frame
    with np.load(stored, allow_pickle=False) as z:
        arrays = {k: z[k][1:] if k in ("positions", "confidence") else z[k] for k in z.files}
    clip = tmp_path / "new.npz"
    np.savez(clip, **arrays)
    code = (
        "import sys, cbr.stored; cbr.stored.MAPPED_MIN_CASES = 1; "  # every case base mapped
        "from posecbr.cli import main; sys.exit(main(sys.argv[1:]))"
    )
    script = (  # the folder's files are listed before the tmpfs goes with the namespace
        f'mount -t tmpfs -o size=12k tmpfs {matrices} || exit 99; "$0" -c "$@"; rc=$?; '
        f'echo "left: $(ls -A {matrices})" >&2; exit $rc'
    )
    done = subprocess.run(
        ["unshare", "-rm", "sh", "-c", script, sys.executable, code, "classify", str(clip),
         "--feedback", label, "--novelty", "0", "--benefit", "0", "--db", str(db)],
        cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, (done.returncode, done.stderr)
    notes = [line for line in done.stderr.splitlines() if "No space left on device" in line]
    assert len(notes) == 1, done.stderr
    assert notes[0].startswith(f"note: {matrices}/") and notes[0].endswith(
        "cannot write: the disk is full (No space left on device): free some space and run "
        "again (the change is stored; commands read its cases "
        "from the database instead of a memory-mapped copy)"
    )
    store = open_store(db, readonly=True)
    assert store.count_cases("default") == n_cases + 1  # the feedback is stored, once
    store.close()
    assert done.stderr.splitlines()[-1] == "left: "  # no temporary file left behind


def test_two_upgrades_of_one_postgresql_store_at_once_convert_it_once(
    pg_url: str,  # noqa: F811
    tmp_path: Path,
) -> None:
    # before: both read schema version 1 at READ COMMITTED; the second, once the first had
    # committed, converted the converted store again (new identities for its case bases: a
    # feedback run reading it was refused as "replaced"), or the two deadlocked
    import threading

    from sqlalchemy import create_engine, text

    from casebase_store.upgrade import upgrade_store

    _v1_on_postgres(pg_url, tmp_path)
    found: list[object] = []

    def upgrade() -> None:
        try:
            found.append(upgrade_store(pg_url))
        except Exception as exc:  # noqa: BLE001  (what the test reports)
            found.append(exc)

    engine = create_engine(pg_url)
    try:
        with engine.connect() as hold:
            # both upgrades start while the version table is held: they wait at once
            hold.execute(text("BEGIN"))
            hold.execute(text("LOCK TABLE posecbr_schema_version IN ACCESS EXCLUSIVE MODE"))
            threads = [threading.Thread(target=upgrade) for _ in range(2)]
            for t in threads:
                t.start()
            database = make_url(pg_url).database
            for _ in range(600):  # until both wait (a lock, the table's or each other's)
                with engine.connect() as look:  # a view of now, not of hold's transaction
                    waiting = look.execute(
                        text("SELECT count(*) FROM pg_stat_activity WHERE datname = :d AND "
                             "wait_event_type = 'Lock'"), {"d": database},
                    ).scalar()  # fmt: skip
                if waiting == 2:
                    break
                threading.Event().wait(0.05)
            assert waiting == 2
            hold.execute(text("COMMIT"))
        for t in threads:
            t.join(120)
    finally:
        engine.dispose()
    assert sorted(map(str, found)) == ["1", "2"], found  # converted once, then nothing to do
    store = open_store(pg_url, readonly=True)
    assert store.load_cases("squats ✓").ids.tolist() == list(range(1, 9))
    store.close()


@needs_mounts
def test_a_wal_files_changes_without_its_shm_in_a_read_only_folder_are_refused_not_ignored(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the file was opened "immutable", which ignores NAME-wal: a case base whose last
    # committed change was still in the -wal (its writer killed before a checkpoint, the -shm
    # not copied along) was read as it was before that change, in silence
    import shutil

    folder = tmp_path / "ro"
    folder.mkdir()
    db = folder / "cb.sqlite"
    shutil.copy(small_case_base(tmp_path), db)
    # in WAL mode as 0.1 wrote it, a committed change left in the -wal (the writer exited
    # without closing: no checkpoint), the -shm gone
    _changes_in_wal(_wal(db), shm=False)
    before = {p.name: _sha(p) for p in folder.iterdir()}
    done = posecbr_on_read_only_mount(folder, ["casebase", "list", "--db", str(db)])
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert done.stderr.splitlines() == [
        f"posecbr casebase list: error: {db}: cb.sqlite-wal beside it holds changes not yet in "
        "the file, and without cb.sqlite-shm, in a folder that cannot be written, they cannot "
        "be read: copy the files to a folder that can be written and run `posecbr casebase "
        "upgrade --db FILE` there"
    ]
    assert {p.name: _sha(p) for p in folder.iterdir()} == before
    # what it says to do reads the change
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    capsys.readouterr()
    assert main(["casebase", "list", "--db", str(db)]) == 0
    assert capsys.readouterr().out.splitlines()[0].split("\t")[:2] == ["#1", "relabelled"]


@needs_mounts
@pytest.mark.parametrize("action", ["info", "upgrade"])
def test_a_killed_writers_journal_beside_a_read_only_file_is_not_sent_to_upgrade(
    tmp_path: Path, action: str
) -> None:
    # before: both said "... undo it with `posecbr casebase upgrade --db FILE`", and upgrade
    # itself said so again: the file read-only (its folder writable), nothing here can undo it
    import shutil

    from tests.test_hunt32d import _killed_mid_write

    db = tmp_path / "cb.sqlite"
    shutil.copy(small_case_base(tmp_path / "made"), db)
    _killed_mid_write(db)
    before = {p.name: _sha(p) for p in tmp_path.iterdir() if p.is_file()}
    done = posecbr_on_read_only_mount(db, ["casebase", action, "--db", str(db)], db)
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"posecbr casebase {action}: error: {db}: its last change was interrupted (the process "
        f"writing it was killed): {db}-journal holds what to undo; the file cannot be written,"
        " so it cannot be rolled back here: make it writable, or copy both files to where they"
        " can be written, and run `posecbr casebase upgrade --db FILE` there"
    ]
    assert {p.name: _sha(p) for p in tmp_path.iterdir() if p.is_file()} == before


def test_a_file_size_limit_reached_in_a_write_is_one_line_saying_so(tmp_path: Path) -> None:
    # before: "database error: disk I/O error", which named neither the write nor the limit
    import resource
    import shutil

    db = tmp_path / "cb.sqlite"
    shutil.copy(small_case_base(tmp_path / "made"), db)
    before = _sha(db)
    size = db.stat().st_size
    clip = sorted((tmp_path / "made" / "train").rglob("*.npz"))[0]

    def limit() -> None:  # the file may not grow (Python ignores SIGXFSZ: write(2) fails)
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))

    done = subprocess.run(
        [sys.executable, "-m", "posecbr", "classify", str(clip), "--feedback",
         clip.parent.name, "--novelty", "0", "--benefit", "0", "--db", str(db)],
        cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=300, preexec_fn=limit,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"posecbr classify: error: {db}: cannot write the database file: disk I/O error (a "
        "failing disk, or the file would grow past a size limit such as `ulimit -f`)"
    ]
    assert _sha(db) == before and sorted(p.name for p in tmp_path.iterdir()) == [
        "cb.sqlite",
        "made",
    ]
