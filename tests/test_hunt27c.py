"""What hunt 27c found in the PostgreSQL store, the Dask path, watch and report: a database
URL with a port that is not a number (a traceback), ... Each test says what happened before its fix.

The PostgreSQL tests run against the server in ``POSECBR_TEST_POSTGRES_URL`` (``.ci/postgres.sh``
starts one) and skip without it, as ``test_store_postgres.py`` does; each gets a fresh database.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from casebase_store import StoreError, open_store
from posecbr.cli import main
from tests.badinput import refused
from tests.test_cbr_cli import _write_classes
from tests.test_store_postgres import pg_server, pg_url  # noqa: F401  (fixtures)


def _cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def clips(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Synthetic arm movements: three activities, two clips each."""
    return _write_classes(tmp_path_factory.mktemp("clips") / "train", 2, 5)


FAST = ["--mirror", "off", "--feature-weights", "none", "--phases", "0", "-k", "1"]


# ----------------------------------------------------------------------------- database URLs


@pytest.mark.parametrize("command", [["casebase", "info"], ["train", "DATA"], ["watch", "0"]])
def test_a_database_url_whose_port_is_not_a_number_is_one_line(
    command: list[str], clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--db postgresql+psycopg://me:pw@host:notaport/db`` (a slip of the fingers): SQLAlchemy
    reads the port with int(), and its ValueError came out as a traceback of every command
    (``sqlite_file`` caught only ArgumentError)."""
    url = "postgresql+psycopg://me:s3cret@127.0.0.1:54x2/cases"
    argv = [str(clips) if a == "DATA" else a for a in command]
    line = refused([*argv, "--db", url], tmp_path, capsys, "port is not a number")
    assert "s3cret" not in line and "me:***@127.0.0.1:54x2/cases" in line


def test_a_host_name_that_does_not_resolve_is_cannot_connect(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A server name the DNS does not know was "database error: failed to resolve host ...",
    where a refused connection says "cannot connect to the database server"."""
    pytest.importorskip("psycopg")
    url = "postgresql+psycopg://me:s3cret@no-such-host.invalid:5432/cases"
    refused(["casebase", "info", "--db", url], tmp_path, capsys, "cannot connect to the database")


def test_open_store_names_an_unreadable_url_without_its_password() -> None:
    """The URL SQLAlchemy could not read is named as the store names one it could."""
    with pytest.raises(StoreError) as e:
        open_store("postgresql+psycopg://me:s3cret@db.example:port/cases")
    assert "s3cret" not in str(e.value) and "me:***@db.example:port/cases" in str(e.value)
