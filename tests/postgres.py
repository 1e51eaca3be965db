"""The test PostgreSQL server (``POSECBR_TEST_POSTGRES_URL``; ``.ci/postgres.sh`` starts one)
emptied of posecbr's tables, for tests that run on SQLite and PostgreSQL alike."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

PG_URL = os.environ.get("POSECBR_TEST_POSTGRES_URL")
TABLES = ("case_representations", "maintenance_log", "cases", "case_bases",
          "posecbr_schema_version")  # fmt: skip


def _worker_database(url: str, worker: str) -> str:
    """The URL of this pytest-xdist worker's own database on the server, created if missing:
    the suite runs in several processes at once, and two of them emptying one database would
    drop each other's tables mid-test."""
    from sqlalchemy import create_engine, make_url, text

    name = f"{make_url(url).database}_{worker}"
    admin = create_engine(url, isolation_level="AUTOCOMMIT")
    try:
        with admin.connect() as conn:
            found = conn.execute(text("SELECT 1 FROM pg_database WHERE datname = :n"), {"n": name})
            if found.first() is None:
                conn.execute(text(f'CREATE DATABASE "{name}"'))
    finally:
        admin.dispose()
    return make_url(url).set(database=name).render_as_string(hide_password=False)


def empty_postgres() -> str:
    """The server's URL (under pytest-xdist: the worker's own database on it) after dropping
    every posecbr table; skips the test without a server."""
    if not PG_URL:
        pytest.skip("no PostgreSQL server (set POSECBR_TEST_POSTGRES_URL; CI starts one)")
    from sqlalchemy import create_engine, text

    worker = os.environ.get("PYTEST_XDIST_WORKER")
    url = _worker_database(PG_URL, worker) if worker else PG_URL
    engine = create_engine(url)
    with engine.begin() as conn:
        for table in TABLES:
            conn.execute(text(f"DROP TABLE IF EXISTS {table} CASCADE"))
    engine.dispose()
    return url


def postgres_copy_of(db: Path) -> str:
    """:func:`empty_postgres` holding a copy of the case base in the SQLite file ``db``
    (``casebase copy``: its configuration, model, cases and history, in one transaction), for
    tests that train the same case base on both backends: the clips are read and described
    once, for the SQLite file, not again for the server."""
    from posecbr.cli import main

    url = empty_postgres()
    assert main(["casebase", "copy", "--db", str(db), "--to", url]) == 0
    return url
