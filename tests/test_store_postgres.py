"""The case base store on PostgreSQL: the same code, the same results as on SQLite.

Runs against the server in ``POSECBR_TEST_POSTGRES_URL`` (e.g. the one ``.ci/postgres.sh``
starts); every test gets a fresh database. Tests that say nothing backend-specific run on
SQLite too (parametrised), so the two backends are held to one standard; the SQLite-only
checks (WAL, corrupt files) stay in ``test_store_transactions.py``, whose subprocess scripts
are reused here for the concurrent-retain and killed-train checks.
"""

from __future__ import annotations

import json
import os
import signal
import threading
import time
import uuid
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import create_engine, event, text
from sqlalchemy.engine import make_url

from casebase_store import SCHEMA_VERSION, NewCase, StoreError, open_store
from casebase_store.models import Base
from cbr.casebase import CaseBase
from cbr.problem import FeatureConfig
from cbr.retain import record_retention, retain
from cbr.revise import record_revision, revise
from cbr.similarity import get_measure
from posecbr.cli import main
from tests.processes import posecbr_process
from tests.test_cbr_cli import _cli, _write_classes
from tests.test_cbr_cli import dataset as dataset  # noqa: F401  (module-scoped fixture)
from tests.test_store_transactions import (
    KILLED_TRAIN,
    _new_base,
    _run_py,
    retained_by_two_processes,
)

PG_ENV = "POSECBR_TEST_POSTGRES_URL"


@pytest.fixture(scope="session")
def pg_server() -> str:
    """The admin URL of a reachable PostgreSQL server, or skip saying why not."""
    url = os.environ.get(PG_ENV)
    if not url:
        pytest.skip(f"{PG_ENV} is not set (source .ci/postgres.sh to start a server)")
    try:
        import psycopg  # noqa: F401
    except ImportError:
        pytest.skip("the PostgreSQL driver is not installed (pip install 'psycopg[binary]')")
    engine = create_engine(url, connect_args={"connect_timeout": 3})
    try:
        with engine.connect() as conn:
            conn.execute(text("SELECT 1"))
    except Exception as exc:  # any failure to reach it means: skip, and say why
        where = make_url(url).render_as_string(hide_password=True)
        pytest.skip(f"PostgreSQL at {where} is unreachable: {str(exc).splitlines()[0]}")
    finally:
        engine.dispose()
    return url


@pytest.fixture
def pg_url(pg_server: str) -> Iterator[str]:
    """A fresh, empty database on the test server (dropped afterwards)."""
    name = f"posecbr_{uuid.uuid4().hex[:12]}"
    admin = create_engine(pg_server, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    try:
        yield make_url(pg_server).set(database=name).render_as_string(hide_password=False)
    finally:
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


@pytest.fixture(params=["sqlite", "postgresql"])
def db(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """A store location on each backend: a SQLite file, a PostgreSQL URL."""
    if request.param == "sqlite":
        return str(tmp_path / "cb.sqlite")
    return str(request.getfixturevalue("pg_url"))


def _sql_url(db: str) -> str:
    return db if "://" in db else f"sqlite:///{db}"


def _sql(db: str, statement: str) -> list[tuple[object, ...]]:
    """Run one statement beside the store (as another program would) and commit."""
    engine = create_engine(_sql_url(db))
    try:
        with engine.begin() as conn:
            result = conn.execute(text(statement))
            return [tuple(r) for r in result] if result.returns_rows else []
    finally:
        engine.dispose()


# ----------------------------------------------------------------------------- round trip

LABELS = [
    'squat "deep"',
    "l'arc",
    "Kniebeuge – tief ✓",
    "腕立て伏せ",
    "a,b;c\nd",
    "back\\slash 100%_",
    "'); DROP TABLE cases; --",
    "🏋️ lift",
]


def _awkward_features(n: int) -> np.ndarray:
    """``(n, 6, 3)`` float64 with every value class a float can hold: NaN (two payloads),
    infinities, signed zeros, subnormals, the extremes and random bits."""
    rng = np.random.default_rng(7)
    x = rng.normal(size=(n, 6, 3)) * 10.0 ** rng.integers(-300, 300, size=(n, 6, 3))
    special = np.array(
        [np.nan, np.inf, -np.inf, 0.0, -0.0, 5e-324, -2.2e-308, np.finfo(np.float64).max]
    )
    x[:, 0, :] = special[(np.arange(n)[:, None] + np.arange(3)) % len(special)]
    x[1::2, 1, 0] = np.frombuffer(np.uint64(0x7FF8DEADBEEF0001).tobytes(), np.float64)[0]
    return x


def test_bulk_round_trip_is_bit_identical(db: str) -> None:
    n = 1203  # more than two of the store's 500-row flushes
    feats = _awkward_features(n)
    store = open_store(db, create=True)
    try:
        with store.transaction() as tx:
            cb = tx.create_case_base(
                "ünï 'base' \"q\"", {"level": "fluents", "ß": "✓"}, ["x"], ["x ✓"], {"name": "dtw"}
            )
            ids = tx.add_cases(
                cb,
                (
                    NewCase(
                        LABELS[i % len(LABELS)],
                        feats[i],
                        source=f"/clips/sübject {i}/take '{i}'.npz",
                        frame_start=None if i % 5 == 0 else i,
                        frame_end=None if i % 5 == 0 else 2 * i + 7,
                        subject=None if i % 3 == 0 else f"S{i % 4:02d} – ✓",
                        skeleton="blazepose_33" if i % 2 else "vicon_39",
                        origin=("trained", "retained", "revised")[i % 3],
                    )
                    for i in range(n)
                ),
            )
            tx.put_representations(
                "sig:test", {cid: feats[j, 1:3] * 2 for j, cid in enumerate(ids)}
            )
    finally:
        store.close()

    again = open_store(db, create=False)
    try:
        got = again.load_cases("ünï 'base' \"q\"")
        assert list(got.ids) == ids and ids == sorted(ids) and len(set(ids)) == n
        assert got.features.dtype == np.float64 and got.features.shape == (n, 6, 3)
        # bit for bit, NaN payloads and the sign of zero included
        np.testing.assert_array_equal(got.features.view(np.uint64), feats.view(np.uint64))
        assert list(got.labels) == [LABELS[i % len(LABELS)] for i in range(n)]
        assert got.sources[17] == "/clips/sübject 17/take '17'.npz"
        assert got.frame_ranges[:3] == ((None, None), (1, 9), (2, 11))
        assert got.subjects[:3] == (None, "S01 – ✓", "S02 – ✓")
        assert got.origins[:4] == ("trained", "retained", "revised", "trained")
        skel = _sql(db, f"SELECT skeleton FROM cases WHERE id IN ({ids[0]}, {ids[1]}) ORDER BY id")
        assert skel == [("vicon_39",), ("blazepose_33",)]
        reps = again.load_representations("ünï 'base' \"q\"", "sig:test")
        assert sorted(reps) == ids
        np.testing.assert_array_equal(
            reps[ids[5]].view(np.uint64), (feats[5, 1:3] * 2).view(np.uint64)
        )
        some = again.load_cases("ünï 'base' \"q\"", ids=[ids[3], ids[1000]])
        np.testing.assert_array_equal(
            some.features.view(np.uint64), feats[[3, 1000]].view(np.uint64)
        )

        info = again.get_case_base("ünï 'base' \"q\"")
        assert info.feature_config == {"level": "fluents", "ß": "✓"}
        assert info.feature_words == ("x ✓",)
        expected = {lab: len(range(k, n, len(LABELS))) for k, lab in enumerate(LABELS)}
        assert info.label_counts == expected and info.n_cases == n
        # the same aware UTC time from both backends (SQLite hands back naive values)
        assert info.created_at.tzinfo is not None
        assert abs(datetime.now(UTC) - info.created_at) < timedelta(minutes=5)
    finally:
        again.close()


def test_text_a_stricter_server_would_refuse_is_refused_alike(db: str) -> None:
    store = open_store(db, create=True)
    try:
        with pytest.raises(StoreError, match="case base name is 201 characters long"):
            with store.transaction() as tx:
                tx.create_case_base("n" * 201, {"level": "fluents"}, ["a"], ["a"], {"name": "x"})
        with store.transaction() as tx:
            cb = tx.create_case_base("ok", {"level": "fluents"}, ["a"], ["a"], {"name": "x"})
        with pytest.raises(StoreError, match="label 'sq\\\\x00uat' contains a NUL character"):
            store.add_cases("ok", [NewCase("fine", np.zeros(2)), NewCase("sq\x00uat", np.zeros(2))])
        assert store.count_cases("ok") == 0  # the whole action was rolled back
        assert cb.n_cases == 0
    finally:
        store.close()


# ----------------------------------------------------------------------------- schema


def test_schema_version_mismatch_is_refused(db: str) -> None:
    # the SQLite tests' helper: it hands its argument to open_store (a path or a URL)
    _new_base(db, "x", 2)  # type: ignore[arg-type]
    _sql(db, "UPDATE posecbr_schema_version SET version = 99")
    with pytest.raises(StoreError, match="schema version 99.*reads version 2"):
        open_store(db)


def test_foreign_and_empty_postgres_databases(pg_url: str) -> None:
    with pytest.raises(StoreError, match="no case base store here \\(empty database\\)") as e:
        open_store(pg_url, create=False)
    assert "***" in str(e.value) and str(make_url(pg_url).password) not in str(e.value)
    _sql(pg_url, "CREATE TABLE customers (id INTEGER)")
    with pytest.raises(StoreError, match="not a posecbr case base store.*customers"):
        open_store(pg_url)


def test_two_clients_creating_the_tables_at_once(pg_url: str) -> None:
    # client A stops inside its create-the-tables transaction (not yet committed); client B
    # opens the same empty database meanwhile. B must wait for A and then use A's tables, not
    # fail creating them a second time (PostgreSQL: duplicate key in pg_type).
    a_inside, a_go = threading.Event(), threading.Event()

    def pause_a(*_: object, **__: object) -> None:
        if threading.current_thread().name == "A":
            a_inside.set()
            a_go.wait(10)

    errors: dict[str, BaseException] = {}

    def client() -> None:
        try:
            open_store(pg_url, create=True).close()
        except BaseException as exc:  # reported by the main thread below
            errors[threading.current_thread().name] = exc

    event.listen(Base.metadata, "after_create", pause_a)
    try:
        a = threading.Thread(target=client, name="A")
        a.start()
        assert a_inside.wait(10)
        b = threading.Thread(target=client, name="B")
        b.start()
        time.sleep(0.5)  # B has looked at the empty database and is waiting
        assert b.is_alive()
        a_go.set()
        a.join(10)
        b.join(10)
    finally:
        event.remove(Base.metadata, "after_create", pause_a)
    assert errors == {}
    assert _sql(pg_url, "SELECT version FROM posecbr_schema_version") == [(SCHEMA_VERSION,)]


def test_unreachable_server_is_one_clear_error(
    pg_server: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # port 1 on loopback: nothing listens there, the connection is refused at once
    url = make_url(pg_server).set(port=1, password="s3cret").render_as_string(hide_password=False)
    with pytest.raises(StoreError, match="cannot connect to the database server") as e:
        open_store(url)
    assert "s3cret" not in str(e.value) and "127.0.0.1:1" in str(e.value)
    code, _, err = _cli(capsys, "casebase", "info", "--db", url)
    assert code == 1 and err.count("\n") == 1 and "cannot connect" in err and "s3cret" not in err


def test_write_blocked_by_a_lock_fails_as_locked(pg_url: str) -> None:
    _new_base(pg_url, "x", 3)  # type: ignore[arg-type]
    holder = create_engine(pg_url)
    try:
        with holder.connect() as conn:
            conn.execute(text("BEGIN"))
            conn.execute(text("LOCK TABLE cases IN EXCLUSIVE MODE"))  # reads pass, writes wait
            store = open_store(pg_url, timeout_s=0.3)
            assert store.count_cases("x") == 3
            t0 = time.monotonic()
            with pytest.raises(StoreError, match="locked by another process") as e:
                store.add_cases("x", [NewCase("l0", np.zeros((4, 2)))])
            assert time.monotonic() - t0 < 5 and "***" in str(e.value)
            conn.execute(text("ROLLBACK"))
        store.add_cases("x", [NewCase("l0", np.zeros((4, 2)))])
        assert store.count_cases("x") == 4
        store.close()
    finally:
        holder.dispose()


# ----------------------------------------------------------------------------- the cycle


def test_revise_retain_and_the_maintenance_log(db: str) -> None:
    store = open_store(db, create=True)
    try:
        with store.transaction() as tx:
            cb = tx.create_case_base(
                "m", {"level": "fluents"}, ["a", "b"], ["a", "b"], {"name": "euclidean"}
            )
            ids = tx.add_cases(
                cb, [NewCase("a", np.zeros((4, 2))), NewCase("b", np.full((4, 2), 10.0))]
            )
            tx.log(cb, "build", reason="2 cases ✓")
        a = store.load_cases("m")
        mem = CaseBase(
            FeatureConfig(), get_measure("euclidean"), a.features, a.labels, (), (), a.ids
        )

        # nearest case (a, at 0) has the true label: it moves 0.25 of the way to 2 -> 0.5
        rev = revise(mem, np.full((4, 2), 2.0), "a")
        assert rev.action == "moved" and rev.case_id == ids[0]
        with store.transaction() as tx:
            record_revision(tx, tx.case_base("m"), rev, np.full((4, 2), 2.0))
        # an 'a' observation at 9.5: 'b' at 10 is sqrt(8 x 0.25) = 1.41 away, the nearest 'a'
        # (0.5) sqrt(8 x 81) = 25.5: 1.41 < 0.5 x 25.5, so the 'b' case is relabelled 'a'
        rev2 = revise(mem, np.full((4, 2), 9.5), "a")
        assert rev2.action == "relabelled" and rev2.case_id == ids[1]
        with store.transaction() as tx:
            record_revision(tx, tx.case_base("m"), rev2, np.full((4, 2), 9.5))
        # a far observation with a new label and zero thresholds is retained
        far = np.full((4, 2), 50.0)
        dec = retain(mem, far, "c", k=1, novelty_threshold=0.0, benefit_threshold=0.0, scale=1.0)
        assert dec.retained
        with store.transaction() as tx:
            new_id = record_retention(tx, tx.case_base("m"), dec, far, "c", source="far ✓")

        got = store.load_cases("m")
        assert list(got.ids) == [ids[0], ids[1], new_id]
        np.testing.assert_array_equal(got.features[0], np.full((4, 2), 0.5))
        np.testing.assert_array_equal(got.features[1], np.full((4, 2), 10.0))
        np.testing.assert_array_equal(got.features[2], far)
        assert list(got.labels) == ["a", "a", "c"]
        assert got.origins == ("revised", "revised", "retained") and got.sources[2] == "far ✓"
        log = store.maintenance_log("m")
        assert [(e.action, e.case_id) for e in log] == [
            ("build", None),
            ("revise", ids[0]),
            ("revise", ids[1]),
            ("retain", new_id),
        ]
        assert log[1].reason.startswith("moved:") and log[2].reason.startswith("relabelled:")
        assert log[3].novelty == pytest.approx(dec.novelty) and log[3].benefit is not None
        assert all(e.at.tzinfo is not None for e in log) and [e.id for e in log] == sorted(
            e.id for e in log
        )
    finally:
        store.close()


def _strip(doc: object) -> object:
    """A CLI JSON document without what names the backend or the time of day."""
    if isinstance(doc, dict):
        return {k: _strip(v) for k, v in doc.items() if k not in ("db", "created", "at")}
    if isinstance(doc, list):
        return [_strip(v) for v in doc]
    return doc


def test_cli_gives_the_same_answers_on_postgres_as_on_sqlite(
    dataset: tuple[Path, Path],  # noqa: F811
    pg_url: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    train, test = dataset
    clip = sorted(test.rglob("*.npz"))[3]
    runs: dict[str, list[object]] = {}
    for db in (str(tmp_path / "cb.sqlite"), pg_url):
        docs: list[object] = []
        steps = [
            ["train", str(train), "--db", db, "--similarity", "dtw", "--param", "band=0.2"],
            ["casebase", "info", "--db", db, "--json"],
            ["classify", str(test), "--db", db, "--json", "-k", "3"],
            [
                "classify",
                str(clip),
                "--db",
                db,
                "--feedback",
                'left ✓ "arm"',
                "--new-label",
                "--json",
            ],
            ["casebase", "trim", "--db", db, "--keep", "0.6", "--json"],
            ["casebase", "list", "--db", db, "--json"],
        ]
        for argv in steps:
            code, out, err = _cli(capsys, *argv)
            assert code == 0, (db, argv, err)
            where = make_url(_sql_url(db)).render_as_string(hide_password=True)
            shown = out.replace(where, "DB").replace(db, "DB")  # the store as printed
            docs.append(json.loads(out) if "--json" in argv else shown)
        runs[db] = docs
        store = open_store(db, create=False)
        log = [e.action for e in store.maintenance_log("default")]
        assert log[0] == "build" and log.count("retain") == 1 and log[-1] == "trim"
        assert store.get_case_base("default").label_counts.get('left ✓ "arm"', 0) <= 1
        store.close()
    sqlite_docs, pg_docs = runs.values()
    assert pg_docs[2]["accuracy"] == 1.0  # type: ignore[index]  # known labels, 6 clips
    assert "15 cases" in str(pg_docs[0]) and "3 activities" in str(pg_docs[0])
    assert _strip(pg_docs) == _strip(sqlite_docs)


# ----------------------------------------------------------------------------- processes


def test_two_processes_retaining_200_each_lose_nothing(pg_url: str, tmp_path: Path) -> None:
    store = retained_by_two_processes(pg_url, tmp_path)
    log = store.maintenance_log("shared")
    assert sum(e.action == "retain" for e in log) == 400
    assert len({e.case_id for e in log}) == 400  # each logged retention names its own case
    store.close()


def _backend_of(admin: str, app: str) -> tuple[object, ...] | None:
    """(state, whether it holds a transaction id) of the client ``app``, or None if gone."""
    rows = _sql(
        admin,
        "SELECT state, backend_xid IS NOT NULL FROM pg_stat_activity "
        f"WHERE application_name = '{app}'",
    )
    return rows[0] if rows else None


def _wait_gone(admin: str, app: str) -> None:
    deadline = time.monotonic() + 15
    while _backend_of(admin, app) is not None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert _backend_of(admin, app) is None, "the server kept the dead client's session"


def test_killed_train_leaves_the_database_as_before(pg_url: str) -> None:
    _new_base(pg_url, "old", 7)  # type: ignore[arg-type]
    app = f"posecbr_kill_{uuid.uuid4().hex[:8]}"
    proc = _run_py(KILLED_TRAIN, f"{pg_url}?application_name={app}")
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert line.strip() == "MID", proc.stderr.read() if proc.stderr else ""
    # the client is inside its transaction and has written (5 flushes of 500 rows were sent)
    assert _backend_of(pg_url, app) == ("idle in transaction", True)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)
    _wait_gone(pg_url, app)
    store = open_store(pg_url)
    assert [cb.name for cb in store.list_case_bases()] == ["old"]
    assert store.count_cases("old", include_inactive=True) == 7
    assert _sql(pg_url, "SELECT count(*) FROM cases") == [(7,)]  # no orphan rows either
    # the store is healthy: a complete run afterwards stores everything
    done = _run_py(KILLED_TRAIN.replace("i == 2600", "i == -1"), pg_url)
    out, err = done.communicate(timeout=60)
    assert out.strip() == "DONE", err
    assert store.count_cases("new") == 3000
    assert [e.action for e in store.maintenance_log("new")] == ["build"]
    store.close()


def test_posecbr_train_killed_inside_its_transaction_leaves_nothing(
    pg_url: str, tmp_path: Path
) -> None:
    data = _write_classes(tmp_path / "data", 10, 21)  # 30 clips
    app = f"posecbr_train_{uuid.uuid4().hex[:8]}"
    proc = posecbr_process(
        "train", str(data), "--db", f"{pg_url}?application_name={app}", pause_after="build"
    )
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    # inside the one train transaction, every case already sent to the server
    assert _backend_of(pg_url, app) == ("idle in transaction", True)
    proc.kill()
    proc.wait(timeout=30)
    _wait_gone(pg_url, app)
    store = open_store(pg_url)
    assert store.list_case_bases() == []
    assert _sql(pg_url, "SELECT count(*) FROM cases") == [(0,)]
    assert _sql(pg_url, "SELECT count(*) FROM case_representations") == [(0,)]
    # the store works afterwards
    argv = ["train", str(data), "--db", pg_url, "--similarity", "euclidean", "--name", "again"]
    assert main(argv) == 0
    assert store.count_cases("again") == 30
    store.close()
