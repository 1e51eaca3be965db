"""What hunt 27c found in the PostgreSQL store, the Dask path, watch and report: a database
URL with a port that is not a number (a traceback), passwords printed by ``train`` and
``casebase upgrade``, ... Each test says what happened before its fix.

The PostgreSQL tests run against the server in ``POSECBR_TEST_POSTGRES_URL`` (``.ci/postgres.sh``
starts one) and skip without it, as ``test_store_postgres.py`` does; each gets a fresh database.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy.engine import make_url

from casebase_store import StoreError, open_store
from features.errors import DataError
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


def test_train_and_upgrade_name_a_database_without_its_password(
    pg_url: str,  # noqa: F811
    clips: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``train --db postgresql://me:PASSWORD@...`` printed the URL as given, password and all,
    in its summary line and as "db" in its --json; ``casebase upgrade`` in its one line
    (every other command names the database as the store does: ``me:***@``)."""
    password = make_url(pg_url).password
    assert password
    code, out, err = _cli(capsys, "train", str(clips), "--db", pg_url, *FAST)
    assert code == 0, err
    assert password not in out + err and ":***@" in out
    code, out, err = _cli(capsys, "train", str(clips), "--db", pg_url, "--replace", "--json", *FAST)
    assert code == 0, err
    assert password not in out + err
    assert json.loads(out)["db"] == make_url(pg_url).render_as_string(hide_password=True)
    code, out, err = _cli(capsys, "casebase", "upgrade", "--db", pg_url)
    assert code == 0, err
    assert password not in out + err and "already schema version" in out


def test_a_case_base_that_cannot_judge_unknown_is_named_without_the_password(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``segment``/``watch`` refusing a case base that cannot judge unknown named ``--db`` as
    given: a database URL with its password."""
    import cbr.unknown
    from posecbr.commands.segment import judge_named

    def cannot(_clf: Any, _name: str) -> Any:
        raise DataError("a case base of one activity cannot say what is unlike it", "case base")

    monkeypatch.setattr(cbr.unknown, "judge_of", cannot)
    with pytest.raises(DataError) as e:
        judge_named(None, "activities", "postgresql+psycopg://me:s3cret@db.example/cases")
    assert e.value.source == "postgresql+psycopg://me:***@db.example/cases"
    assert "s3cret" not in str(e.value)


def test_open_store_names_an_unreadable_url_without_its_password() -> None:
    """The URL SQLAlchemy could not read is named as the store names one it could."""
    with pytest.raises(StoreError) as e:
        open_store("postgresql+psycopg://me:s3cret@db.example:port/cases")
    assert "s3cret" not in str(e.value) and "me:***@db.example:port/cases" in str(e.value)
