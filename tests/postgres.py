"""The test PostgreSQL server (``POSECBR_TEST_POSTGRES_URL``; ``.ci/postgres.sh`` starts one)
emptied of posecbr's tables, for tests that run on SQLite and PostgreSQL alike."""

from __future__ import annotations

import os

import pytest

PG_URL = os.environ.get("POSECBR_TEST_POSTGRES_URL")


def empty_postgres() -> str:
    """The server's URL after dropping every posecbr table; skips the test without a server."""
    if not PG_URL:
        pytest.skip("no PostgreSQL server (set POSECBR_TEST_POSTGRES_URL; CI starts one)")
    from sqlalchemy import create_engine, text

    engine = create_engine(PG_URL)
    with engine.begin() as conn:
        for table in ("case_representations", "maintenance_log", "cases", "case_bases",
                      "posecbr_schema_version"):  # fmt: skip
            conn.execute(text(f"DROP TABLE IF EXISTS {table} CASCADE"))
    engine.dispose()
    return PG_URL
