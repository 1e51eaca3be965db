"""What hunt 27c found in the PostgreSQL store, the Dask path, watch and report: a database
URL with a port that is not a number (a traceback), passwords printed by ``train`` and
``casebase upgrade``, two writers of one case base on PostgreSQL both committing,
``--scheduler`` values that were tracebacks, huge numbers in a results file ``report``
fell over, ``--param`` values too large for any number, names that are not UTF-8
(tracebacks from the database driver), listings in the order of the server's collation, and
matplotlib's raw warnings of missing glyphs. Each test says what happened before its fix.

The PostgreSQL tests run against the server in ``POSECBR_TEST_POSTGRES_URL`` (``.ci/postgres.sh``
starts one) and skip without it, as ``test_store_postgres.py`` does; each gets a fresh database.
"""

from __future__ import annotations

import json
import threading
import time
import uuid
from collections.abc import Callable, Iterator
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


# on one xdist worker: the module's clips, results made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt27c")


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


def test_a_password_given_as_a_url_parameter_is_not_shown(
    pg_url: str,  # noqa: F811
    clips: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """libpq takes the password as a parameter too (``...@host/db?password=PASSWORD``):
    every message and ``train``'s summary showed it, SQLAlchemy hiding only the one before
    the host."""
    url = make_url(pg_url)
    password = url.password
    assert password
    given = url.set(password=None).update_query_dict({"password": password})
    text = given.render_as_string(hide_password=False)
    assert f"password={password}" in text
    code, out, err = _cli(capsys, "train", str(clips), "--db", text, *FAST)
    assert code == 0, err
    assert password not in out + err and "?password=***" in out
    wrong = given.set(database="no_such_database").render_as_string(hide_password=False)
    line = refused(["casebase", "info", "--db", wrong], tmp_path, capsys, "cannot connect")
    assert password not in line and "?password=***" in line


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


# ----------------------------------------------------------------------------- two writers


def _waiters(url: str) -> int:
    """Sessions of this database waiting for a lock (another writer's) now."""
    from sqlalchemy import create_engine, text

    engine = create_engine(url)
    try:
        with engine.connect() as conn:
            query = (
                "SELECT count(*) FROM pg_stat_activity WHERE datname = current_database() "
                "AND wait_event_type = 'Lock'"
            )
            return int(conn.execute(text(query)).scalar_one())
    finally:
        engine.dispose()


class _Holder(threading.Thread):
    """A writer of ``url`` that opens its transaction, runs ``first(tx)``, then holds the
    transaction open until another session waits for a lock (or ``done`` is set: the other
    writer ran through without waiting), runs ``then(tx)`` and commits."""

    def __init__(
        self, url: str, first: Callable[[Any], Any], then: Callable[[Any], Any] | None = None
    ) -> None:
        super().__init__(daemon=True)
        self.url, self.first, self.then = url, first, then
        self.ready, self.done = threading.Event(), threading.Event()
        self.error: BaseException | None = None

    def run(self) -> None:
        try:
            with open_store(self.url, create=True) as store, store.transaction() as tx:
                state = self.first(tx)
                self.ready.set()
                deadline = time.monotonic() + 60
                while not self.done.is_set() and time.monotonic() < deadline:
                    if _waiters(self.url):
                        break
                    time.sleep(0.05)
                if self.then is not None:
                    self.then((tx, state))
        except BaseException as exc:  # reported by the test
            self.error = exc
        finally:
            self.ready.set()


def _while_held(holder: _Holder, capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    """``posecbr argv`` run while ``holder`` holds its transaction; its exit status and
    stderr."""
    holder.start()
    assert holder.ready.wait(30)
    try:
        code, _, err = _cli(capsys, *argv)
    finally:
        holder.done.set()
        holder.join(60)
    assert holder.error is None, holder.error
    return code, err


def test_a_trim_while_another_writer_changes_the_cases_is_refused_on_postgresql(
    pg_url: str,  # noqa: F811
    clips: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Another process holds case base version 1 in its write transaction (it checked it
    and is about to trim a case) while ``casebase trim`` decides on version 1 too. SQLite's
    writers queue (BEGIN IMMEDIATE): the trim waits, finds version 2, and is refused. On
    PostgreSQL (READ COMMITTED, nothing locked by the check) both checks passed and both
    commits went through: two trims decided on one version, the case base left smaller than
    either meant (a trim to 50 % then the other's case, version 3)."""
    code, _, err = _cli(capsys, "train", str(clips), "--db", pg_url, *FAST)
    assert code == 0, err
    with open_store(pg_url, readonly=True) as store:
        info = store.get_case_base("default")
        ids = [int(i) for i in store.load_cases("default").ids]

    def drop_one(args: tuple[Any, Any]) -> None:
        tx, cb = args
        tx.deactivate_cases(cb, ids[:1])

    holder = _Holder(pg_url, lambda tx: tx.expect("default", info.uid, info.version), drop_one)
    code, err = _while_held(holder, capsys, "casebase", "trim", "--db", pg_url, "--keep", "0.5")
    assert code == 1 and err.count("\n") == 1, err
    assert "changed by another process since it was read (version 1, now 2)" in err
    with open_store(pg_url, readonly=True) as store:
        after = store.get_case_base("default")
    assert (after.version, after.n_cases) == (2, len(ids) - 1)  # the other writer's alone


@pytest.mark.parametrize("replace", [False, True])
def test_two_trains_of_one_new_name_on_postgresql_end_as_on_sqlite(
    replace: bool,
    pg_url: str,  # noqa: F811
    clips: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Another process creates case base "x" while ``train --name x`` does. The second to
    write was refused with PostgreSQL's own words, "database error: duplicate key value violates
    unique constraint "case_bases_name_key"", with or without ``--replace``; now as on SQLite:
    "a case base named 'x' already exists", and with ``--replace`` (hunt 37n) "was created by
    another process since this command started": the other's case base, which this command
    never read, is kept, not replaced unseen."""

    def create(tx: Any) -> Any:
        return tx.create_case_base("x", {"level": "other"}, ["a"], ["a"], {"name": "euclidean"})

    holder = _Holder(pg_url, create, lambda _: None)
    argv = ["train", str(clips), "--db", pg_url, "--name", "x", *FAST]
    code, err = _while_held(holder, capsys, *argv, *(["--replace"] if replace else []))
    with open_store(pg_url, readonly=True) as store:
        stored = store.get_case_base("x")
    assert code == 1 and err.count("\n") == 1, err
    assert "duplicate key" not in err
    if replace:
        assert "case base 'x' was created by another process since this command started" in err
    else:
        assert "a case base named 'x' already exists" in err
    assert stored.feature_config == {"level": "other"}


# ----------------------------------------------------------------------------- the Dask path


@pytest.mark.parametrize("command", ["train", "compare"])
def test_a_superscript_number_of_local_workers_is_one_line(
    command: str, clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--scheduler local:²`` (a superscript two, as a phone keyboard may give): str.isdigit()
    holds for it and int() refuses it, a ValueError traceback before any work."""
    argv = [command, str(clips), "--scheduler", "local:²"]
    if command == "train":
        argv += ["--db", str(tmp_path / "cb.sqlite")]
    refused(argv, tmp_path, capsys, "local:N needs a whole number of workers >= 1")


@pytest.mark.parametrize("scheme", ["tls", "ucx"])
def test_a_scheduler_address_dask_cannot_use_here_is_one_line(
    scheme: str, clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--scheduler tls://host:8786`` without TLS set up in Dask's configuration (or
    ``ucx://`` without UCX): Dask raised TypeError, a traceback, where an address it cannot
    reach is "cannot reach the Dask scheduler"."""
    pytest.importorskip("dask.distributed")
    argv = ["train", str(clips), "--db", str(tmp_path / "cb.sqlite")]
    refused([*argv, "--scheduler", f"{scheme}://127.0.0.1:1"], tmp_path, capsys,
            f"--scheduler: cannot reach the Dask scheduler at {scheme}://127.0.0.1:1")  # fmt: skip


# ----------------------------------------------------------------------------- report


@pytest.fixture(scope="module")
def results(clips: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A real ``compare --json`` results document (one configuration on the synthetic clips)."""
    out = tmp_path_factory.mktemp("compared") / "results.json"
    argv = ["compare", str(clips), "--similarities", "euclidean", "--features", "fluents",
            "--no-dad", "--peers", "none", "--k", "1", "--json", str(out)]  # fmt: skip
    assert main(argv) == 0
    doc: dict[str, Any] = json.loads(out.read_text())
    return doc


@pytest.mark.parametrize(
    ("number", "message"),
    [
        ("1" + "0" * 400, "key 'methods[0].case_base_size' is too large a number (401 digits)"),
        ("9" * 5000, "not a results file: it holds a number of more than 4300 digits"),
    ],
)
def test_report_of_a_results_file_with_a_huge_number_is_one_line(
    number: str,
    message: str,
    results: dict[str, Any],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A whole number past any float where the results hold a number (an edited or damaged
    file): OverflowError, a traceback; one of more than 4300 digits, which Python's JSON
    reader refuses with a ValueError that is not a JSONDecodeError: a traceback too."""
    doc = dict(results, methods=[dict(results["methods"][0], case_base_size=0)])
    text = json.dumps(doc).replace('"case_base_size": 0', f'"case_base_size": {number}')
    path = tmp_path / "results.json"
    path.write_text(text)
    line = refused(["report", str(path), "--out", str(tmp_path / "r.html")], tmp_path, capsys)
    assert line.endswith(f"{path}: {message}"), line


# ----------------------------------------------------------------------------- --param


@pytest.mark.parametrize(
    ("command", "param", "message"),
    [
        ("train", "band=1" + "0" * 400, "the value of band holds too large a number"),
        ("compare", "k=" + "9" * 5000, "the value of k is a number of more than 4300 digits"),
    ],
)
def test_a_param_too_large_for_any_number_is_one_line(
    command: str, param: str, message: str, clips: Path, tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """``--param band=1000...0`` (401 digits) reached DTW's check as an int no float holds:
    OverflowError, a traceback; a value of more than 4300 digits was a ValueError traceback
    from the JSON reader (which only JSONDecodeError and RecursionError were caught of)."""
    argv = [command, str(clips), "--param", param]
    if command == "train":
        argv += ["--db", str(tmp_path / "cb.sqlite"), "--similarity", "dtw"]
    refused(argv, tmp_path, capsys, f"--param: {message}")


# ----------------------------------------------------------------------------- names not UTF-8


def _not_utf8(clips: Path, root: Path, where: str) -> Path:
    """The synthetic clips under ``root``, two activities; one byte that is not UTF-8 (latin-1
    "ä") in the name of the first activity's folder (``where="folder"``) or of one clip of
    each activity (``"files"``)."""
    import os
    import shutil

    folders = sorted(p for p in clips.iterdir() if p.is_dir())[:2]
    for k, folder in enumerate(folders):
        name = os.fsencode(folder.name) + (b"\xe4" if where == "folder" and k == 0 else b"")
        target = os.path.join(os.fsencode(root), name)
        os.makedirs(target)
        for j, clip in enumerate(sorted(folder.glob("*.npz"))):
            odd = b"\xe4" if where == "files" and j == 0 else b""
            file = os.fsencode(clip.stem) + odd + b".npz"
            shutil.copy(clip, os.path.join(target, file))
    return root


@pytest.fixture(params=["sqlite", "postgresql"])
def db(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """A store on each backend: a SQLite file, a fresh PostgreSQL database."""
    if request.param == "sqlite":
        return str(tmp_path / "cb.sqlite")
    return str(request.getfixturevalue("pg_url"))


def test_an_activity_folder_named_in_another_encoding_is_one_line(
    db: str, clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A class folder whose name holds a byte that is not UTF-8 (Python reads it as a lone
    surrogate): the label reached the database driver, a UnicodeEncodeError traceback on
    SQLite and PostgreSQL alike, after every clip's features were computed."""
    data = _not_utf8(clips, tmp_path / "data", "folder")
    line = refused(["train", str(data), "--db", db, *FAST], tmp_path, capsys, "\\udce4")
    assert "is not UTF-8 text" in line
    if "://" in db:
        with open_store(db, readonly=True) as store:
            assert store.list_case_bases() == []


def test_clips_whose_file_names_are_in_another_encoding_are_cases(
    db: str, clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Clips named with a byte that is not UTF-8 were a UnicodeEncodeError traceback of
    ``train`` (the source of the case). They are cases now, their source stored with the byte
    written ``\\xe4``; appending the same file again is refused as already there."""
    data = _not_utf8(clips, tmp_path / "data", "files")
    code, _, err = _cli(capsys, "train", str(data), "--db", db, *FAST)
    assert code == 0, err
    with open_store(db, readonly=True) as store:
        sources = store.load_cases("default").sources
    assert sum(s.endswith("\\xe4.npz") for s in sources) == 2, sources
    odd = next(p for p in data.rglob("*") if p.name.endswith("\udce4.npz"))
    code, _, err = _cli(capsys, "train", str(odd), "--db", db, "--append")
    assert code == 1 and "is already case" in err, err


def test_feedback_with_a_label_in_another_encoding_is_one_line(
    clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``classify --feedback`` with a label given in latin-1 on a UTF-8 terminal: a
    UnicodeEncodeError traceback from the database driver."""
    db = str(tmp_path / "cb.sqlite")
    code, _, err = _cli(capsys, "train", str(clips), "--db", db, *FAST)
    assert code == 0, err
    clip = next(clips.rglob("*.npz"))
    argv = ["classify", db, str(clip), "--feedback", "squat\udce4", "--new-label"]
    argv[1:1] = ["--db"]
    refused(argv, tmp_path, capsys, "label 'squat\\udce4' is not UTF-8 text")


# ----------------------------------------------------------------------------- one order


@pytest.fixture
def pg_icu_url(pg_server: str) -> Iterator[str]:  # noqa: F811
    """A fresh database on the test server that sorts text by ICU's en-US collation (as a
    server set up with en_US.UTF-8 does), dropped afterwards; skips where ICU is missing."""
    from sqlalchemy import create_engine, text

    name = f"posecbr_icu_{uuid.uuid4().hex[:8]}"
    admin = create_engine(pg_server, isolation_level="AUTOCOMMIT")
    try:
        with admin.connect() as conn:
            try:
                icu = "LOCALE_PROVIDER icu ICU_LOCALE 'en-US' LOCALE 'C.UTF-8'"
                conn.execute(text(f'CREATE DATABASE "{name}" TEMPLATE template0 {icu}'))
            except Exception as exc:  # an older server, or one built without ICU
                pytest.skip(f"no ICU collation on the test server: {str(exc).splitlines()[0]}")
        yield make_url(pg_server).set(database=name).render_as_string(hide_password=False)
    finally:
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


def test_case_bases_and_labels_come_in_one_order_on_every_backend(
    pg_icu_url: str, tmp_path: Path
) -> None:
    """The case bases of a store and the activities of a case base were listed in the order
    the server sorts text: by code point on SQLite ("Squat", "Zebra", "_walk", "apple"), by
    the database's collation on PostgreSQL (en-US: "_walk", "apple", "Squat", "Zebra"), so
    ``casebase info`` (text and --json) and the "choose one with --name" refusal listed them
    differently from one backend to the other, and from ``train``'s own summary."""
    import numpy as np

    from casebase_store import NewCase

    labels = ["apple", "Squat", "_walk", "Zebra"]
    seen = []
    for db in (str(tmp_path / "cb.sqlite"), pg_icu_url):
        with open_store(db, create=True) as store:
            with store.transaction() as tx:
                for name in ("apple2", "Beta"):
                    cb = tx.create_case_base(name, {"level": "x"}, ["a"], ["a"], {"name": "e"})
                    tx.add_cases(cb, [NewCase(lab, np.zeros(1)) for lab in labels])
            infos = store.list_case_bases()
            seen.append(([i.name for i in infos], list(infos[0].label_counts)))
            with pytest.raises(StoreError) as e:
                store.choose(None)
            seen.append(str(e.value).split(": ", 1)[1])
    assert seen[0] == (["Beta", "apple2"], ["Squat", "Zebra", "_walk", "apple"])
    assert seen[2:] == seen[:2]


def test_report_of_a_folder_whose_results_json_is_a_folder_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``report DIR`` where ``DIR/results.json`` is a folder was refused as "is a pipe,
    socket or device, not a results file"."""
    (tmp_path / "run" / "results.json").mkdir(parents=True)
    argv = ["report", str(tmp_path / "run"), "--out", str(tmp_path / "r.html")]
    refused(argv, tmp_path, capsys, "results.json: is a folder, not a results file")


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        ("negative", "key 'methods[0].confusion[0][0]' is a count of clips, got -1"),
        ("short", "key 'methods[0].unassigned' must hold one per class (3), got 1"),
    ],
)
def test_report_refuses_a_confusion_matrix_no_run_could_give(
    edit: str,
    message: str,
    results: dict[str, Any],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A confusion matrix with a negative count (or ``unassigned`` not one per class) passed
    the reader, which checks every other count, and the page drew -1 clips in its matrix."""
    method = dict(results["methods"][0])
    if edit == "negative":
        method["confusion"] = [[-1, *row[1:]] if i == 0 else row
                               for i, row in enumerate(method["confusion"])]  # fmt: skip
    else:
        method["unassigned"] = [0]
    path = tmp_path / "results.json"
    path.write_text(json.dumps(dict(results, methods=[method, *results["methods"][1:]])))
    line = refused(["report", str(path), "--out", str(tmp_path / "r.html")], tmp_path, capsys)
    assert line.endswith(f"{path}: {message}"), line


def test_report_names_the_characters_its_font_lacks_in_one_line(
    results: dict[str, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An activity named in a script the pictures' font (DejaVu Sans) lacks ("右腕 raise"):
    matplotlib warned twice per character and picture, eight lines of raw Python warnings
    (``UserWarning: Glyph 21491 (\\N{CJK UNIFIED IDEOGRAPH-53F3}) missing from font(s)``,
    the source line under each) around "report written", saying nothing of the boxes drawn.
    One line names the characters now (none where the font has them)."""
    import warnings

    path = tmp_path / "results.json"
    path.write_text(json.dumps(results))
    assert any("右" in c for c in results["dataset"]["classes"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code, out, err = _cli(capsys, "report", str(path), "--out", str(tmp_path / "r.html"))
    assert code == 0 and out == "", err
    assert not [w for w in caught if "missing from font" in str(w.message)]
    lines = err.splitlines()
    assert lines.pop() == f"report written to {tmp_path / 'r.html'}"  # on stderr, as all are
    assert lines == [] or (
        len(lines) == 1 and lines[0].startswith("pictures: the font has no glyph for ")
    ), err
    assert "Warning" not in err


def test_a_client_that_could_not_connect_is_not_left_for_a_later_collection() -> None:
    """A Dask client that failed to connect (``tls://`` without certificates, ``ucx://``
    without UCX) was left half-built in a reference cycle, its loop runner started. Collected
    later, inside the next client's start (which holds Dask's loop-runner lock), its
    ``__del__`` waited for that lock: the suite hung there for good. With automatic
    collection off, no such client is left once the refusal is raised."""
    pytest.importorskip("dask.distributed")
    import gc

    from distributed import Client

    from features.cluster import connect
    from features.errors import ConfigError

    gc.collect()
    gc.disable()
    try:
        for scheme in ("tls", "ucx"):
            with pytest.raises(ConfigError), connect(f"{scheme}://127.0.0.1:1"):
                pass
        left = [str(o.status) for o in gc.get_objects() if isinstance(o, Client)]
    finally:
        gc.enable()
    assert [s for s in left if "closed" not in s] == []
