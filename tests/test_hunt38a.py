"""Moving a case base between stores (hunt 38a): ``posecbr casebase copy --db SRC --to DST``
writes the case base whole (configuration, fitted model, every case in use or trimmed, labels,
provenance, cached representations, history) to the other store in one transaction, the source
opened read-only; classify and segment answer on the copy exactly as on the source."""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import signal
import sqlite3
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import casebase_store
from casebase_store import encode_array, open_store
from features.interrupts import TERMINATED_STATUS
from posecbr.cli import main
from tests.badinput import refused, snapshot
from tests.postgres import empty_postgres
from tests.processes import posecbr_process

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
CLIPS = [str(DEMO / f) for f in ("m01_s03_e01.npz", "m05_s03_e02.npz", "m02_s03_e02_inc.npz")]
KIND = "test_kind:demo"  # a cached representation a measure could keep per case


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    """``posecbr ARGV`` in this process: exit 0; its standard output."""
    capsys.readouterr()
    code = main(list(argv))
    out, err = capsys.readouterr()
    assert code == 0, err
    return out


# on one xdist worker: the module's source made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt38a")


@pytest.fixture(scope="module")
def source(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small case base with everything a case base can hold: trained on the demo's s01 and
    s02 (three activities), then a clip retained, one case revised, cases trimmed (kept,
    inactive), and a cached representation on three cases."""
    db = tmp_path_factory.mktemp("source") / "src.sqlite"
    labels = "deep_squat,hurdle_step,sit_to_stand"
    argv = ["train", str(DEMO / "labels.csv"), "--db", str(db), "--subjects", "s01,s02"]
    assert main([*argv, "--labels", labels]) == 0
    assert main(["classify", CLIPS[0], "--db", str(db), "--feedback", "deep_squat",
                 "--novelty", "0", "--benefit", "0"]) == 0  # fmt: skip
    assert main(["classify", CLIPS[1], "--db", str(db), "--feedback", "sit_to_stand",
                 "--novelty", "1e9"]) == 0  # fmt: skip
    assert main(["casebase", "trim", "--db", str(db), "--keep", "0.8"]) == 0
    store = open_store(db)
    try:
        ids = store.load_cases("default").ids[:3]
        with store.transaction() as tx:
            tx.put_representations(KIND, {int(i): np.arange(4.0) * int(i) for i in ids})
    finally:
        store.close()
    return db


def _seen(url: str, name: str) -> dict[str, Any]:
    """What a user sees of case base ``name`` of the store ``url`` (SQLite file or URL), read
    with plain SQL: its columns (not its row id and identity), its cases in id order (every
    column but the ids; ``ids`` apart), each cached representation and log entry with the
    place of its case among them; dates as UTC."""
    from sqlalchemy import create_engine, text

    engine = create_engine(url if "://" in url else f"sqlite:///{url}")

    def utc(v: Any) -> Any:
        if isinstance(v, str):  # SQLite keeps dates as text, written in UTC
            v = datetime.fromisoformat(v)
        if isinstance(v, datetime):
            return v.replace(tzinfo=UTC) if v.tzinfo is None else v.astimezone(UTC)
        return v

    try:
        with engine.connect() as c:
            cb = dict(c.execute(text("SELECT * FROM case_bases WHERE name = :n"), {"n": name})
                      .mappings().one())  # fmt: skip
            cases = [dict(r) for r in c.execute(
                text("SELECT * FROM cases WHERE case_base_id = :i ORDER BY id"), {"i": cb["id"]}
            ).mappings()]  # fmt: skip
            place = {r["id"]: n for n, r in enumerate(cases)}
            reps = [(place[r[0]], r[1], bytes(r[2])) for r in c.execute(
                text("SELECT r.case_id, r.kind, r.data FROM case_representations r JOIN cases c"
                     " ON c.id = r.case_id WHERE c.case_base_id = :i ORDER BY r.case_id, r.kind"),
                {"i": cb["id"]},
            )]  # fmt: skip
            log = [dict(r) for r in c.execute(
                text("SELECT * FROM maintenance_log WHERE case_base_id = :i ORDER BY id"),
                {"i": cb["id"]},
            ).mappings()]  # fmt: skip
    finally:
        engine.dispose()
    ids = [r.pop("id") for r in cases]
    for r in cases:
        del r["case_base_id"]
        r["features"] = bytes(r["features"])
        r["active"] = bool(r["active"])
        r["created_at"], r["updated_at"] = utc(r["created_at"]), utc(r["updated_at"])
    for e in log:
        del e["id"], e["case_base_id"]
        e["case_id"] = None if e["case_id"] is None else place[e["case_id"]]
        e["at"] = utc(e["at"])
    uid = cb.pop("uid")
    del cb["id"], cb["name"]
    cb["created_at"] = utc(cb["created_at"])
    return {"case_base": cb, "cases": cases, "reps": reps, "log": log, "ids": ids, "uid": uid}


def _same_but_ids(a: dict[str, Any], b: dict[str, Any]) -> None:
    for key in ("case_base", "cases", "reps", "log"):
        assert a[key] == b[key], key
    assert a["uid"] != b["uid"]  # a copy is a case base of its own


def _answers(capsys: pytest.CaptureFixture[str], db: str) -> list[str]:
    """classify (words and JSON) and segment of the demo's s03 clips on the case base ``db``
    (the JSON's ``db``, the store's name, said ``DB``)."""
    shown = casebase_store.shown_db(db)
    return [
        _run(capsys, "classify", *CLIPS, "--db", db),
        _run(capsys, "classify", *CLIPS, "--db", db, "--json").replace(shown, "DB"),
        _run(capsys, "segment", CLIPS[0], "--db", db),
        _run(capsys, "segment", CLIPS[0], "--db", db, "--json").replace(shown, "DB"),
    ]


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_the_source_has_what_a_copy_must_carry(source: Path) -> None:
    seen = _seen(str(source), "default")
    assert {"trained", "retained", "revised"} <= {c["origin"] for c in seen["cases"]}
    assert not all(c["active"] for c in seen["cases"])  # trimmed cases, kept
    assert {e["action"] for e in seen["log"]} >= {"build", "retain", "revise", "trim"}
    assert any(e["case_id"] is not None for e in seen["log"])
    assert len(seen["reps"]) == 3 and seen["case_base"]["version"] > 1


def test_a_copy_to_a_new_file_is_exact_and_answers_alike(
    source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before, folder = _sha(source), snapshot(source.parent)
    dst = tmp_path / "copy.sqlite"
    out = _run(capsys, "casebase", "copy", "--db", str(source), "--to", str(dst))
    src, copy = _seen(str(source), "default"), _seen(str(dst), "default")
    _same_but_ids(src, copy)
    assert copy["ids"] == src["ids"]  # a store made for it: the ids `classify` prints
    n_all, n_in_use = len(src["cases"]), sum(c["active"] for c in src["cases"])
    assert out == (
        f"copied case base 'default' of {source} to {dst}: {n_in_use} cases in use, "
        f"{n_all - n_in_use} trimmed, {len(src['log'])} history entries; case ids kept\n"
    )
    # the source is read-only to it: not a byte or a side file changed
    assert _sha(source) == before and snapshot(source.parent) == folder
    assert sorted(p.name for p in tmp_path.iterdir()) == ["copy.sqlite"]  # no temporaries
    assert _answers(capsys, str(dst)) == _answers(capsys, str(source))
    info = json.loads(_run(capsys, "casebase", "info", "--db", str(dst), "--json"))
    assert info == json.loads(_run(capsys, "casebase", "info", "--db", str(source), "--json")) | {
        "db": str(dst)
    }


def test_a_copy_beside_other_cases_is_numbered_after_them_in_order(
    source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dst = tmp_path / "two.sqlite"
    _run(capsys, "casebase", "copy", "--db", str(source), "--to", str(dst), "--as", "first")
    doc = json.loads(_run(capsys, "casebase", "copy", "--db", str(source), "--to", str(dst),
                          "--as", "second", "--json"))  # fmt: skip
    src, first, second = (_seen(str(source), "default"), _seen(str(dst), "first"),
                          _seen(str(dst), "second"))  # fmt: skip
    _same_but_ids(src, second)
    n = len(src["ids"])
    top = max(first["ids"])
    assert second["ids"] == list(range(top + 1, top + 1 + n))  # after the store's own, in order
    assert doc["case_ids_kept"] is False and doc["as"] == "second"
    assert doc["cases"] + doc["trimmed_cases"] == n and doc["history"] == len(src["log"])
    # under another name in the very store it is in: a second case base of its own
    again = tmp_path / "again.sqlite"
    shutil.copyfile(source, again)
    _run(capsys, "casebase", "copy", "--db", str(again), "--to", f"sqlite:///{again}",
         "--as", "twin")  # fmt: skip
    _same_but_ids(_seen(str(again), "default"), _seen(str(again), "twin"))
    assert _seen(str(again), "default") == src  # the original untouched


def test_sqlite_to_postgresql_and_back_is_exact(
    source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = empty_postgres()
    _run(capsys, "casebase", "copy", "--db", str(source), "--to", url)
    src, pg = _seen(str(source), "default"), _seen(url, "default")
    _same_but_ids(src, pg)
    assert pg["ids"] == src["ids"]
    assert _answers(capsys, url) == _answers(capsys, str(source))
    # a second copy on the server, beside the first: numbered after it (the sequence moved)
    _run(capsys, "casebase", "copy", "--db", url, "--to", url, "--as", "other")
    other = _seen(url, "other")
    _same_but_ids(src, other)
    assert min(other["ids"]) > max(src["ids"])
    back = tmp_path / "back.sqlite"
    _run(capsys, "casebase", "copy", "--db", url, "--name", "other", "--to", str(back),
         "--as", "default")  # fmt: skip
    home = _seen(str(back), "default")
    _same_but_ids(src, home)
    assert home["ids"] == other["ids"]
    assert main(["train", str(DEMO / "labels.csv"), "--db", url, "--name", "more",
                 "--subjects", "s03", "--labels", "deep_squat,sit_to_stand"]) == 0  # fmt: skip
    store = open_store(url, readonly=True)
    try:  # a case trained after the copies takes an id after theirs
        assert min(store.load_cases("more").ids) > max(other["ids"])
    finally:
        store.close()


def _damaged_feature(db: Path) -> None:
    con = sqlite3.connect(db)
    con.execute("UPDATE cases SET features = ? WHERE id = (SELECT MAX(id) FROM cases)",
                (b"not an array",))  # fmt: skip
    con.commit()
    con.close()


def test_bad_copies_are_refused_in_one_line_writing_nothing(
    source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "src.sqlite"
    shutil.copyfile(source, src)
    dst = tmp_path / "dst.sqlite"
    _run(capsys, "casebase", "copy", "--db", str(src), "--to", str(dst))
    copy = ["casebase", "copy", "--db", str(src)]
    refused([*copy, "--to", str(dst)], tmp_path, capsys, str(dst),
            "a case base named 'default' is here already: nothing was copied", "--as")  # fmt: skip
    for same in (str(src), f"sqlite:///{src}", f"{tmp_path}/./src.sqlite"):
        refused([*copy, "--to", same], tmp_path, capsys, str(src),
                "that is the case base itself")  # fmt: skip
    (tmp_path / "link.sqlite").symlink_to(src)
    refused([*copy, "--to", str(tmp_path / "link.sqlite")], tmp_path, capsys,
            "that is the case base itself")  # fmt: skip
    new = str(tmp_path / "new.sqlite")
    refused(["casebase", "copy", "--db", str(tmp_path / "nope.sqlite"), "--to", new], tmp_path,
            capsys, "nope.sqlite", "no such case base file")  # fmt: skip
    (tmp_path / "labels.csv").write_text("path,label\na.npz,squat\n")
    refused(["casebase", "copy", "--db", str(tmp_path / "labels.csv"), "--to", new], tmp_path,
            capsys, "labels.csv", "not a readable SQLite database")  # fmt: skip
    refused([*copy, "--name", "squats", "--to", new], tmp_path, capsys,
            "no case base named 'squats'")  # fmt: skip
    refused([*copy, "--to", new, "--as", " "], tmp_path, capsys, "--as", "name is empty")
    refused([*copy, "--to", new, "--as", "x" * 201], tmp_path, capsys, "--as", "at most 200")
    refused([*copy, "--to", ""], tmp_path, capsys, "--to", "is empty")
    refused([*copy, "--to", str(tmp_path / "no" / "dst.sqlite")], tmp_path, capsys,
            "folder does not exist")  # fmt: skip
    refused([*copy, "--to", str(tmp_path / "labels.csv")], tmp_path, capsys, "labels.csv",
            "not a readable SQLite database")  # fmt: skip
    damaged = tmp_path / "damaged.sqlite"
    shutil.copyfile(source, damaged)
    _damaged_feature(damaged)
    refused(["casebase", "copy", "--db", str(damaged), "--to", new], tmp_path, capsys,
            "damaged.sqlite", "is damaged")  # fmt: skip


def test_a_locked_source_is_refused_writing_nothing(
    source: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    src = tmp_path / "src.sqlite"
    shutil.copyfile(source, src)
    monkeypatch.setattr(casebase_store, "open_store",
                        functools.partial(casebase_store.open_store, timeout_s=0.3))  # fmt: skip
    holder = sqlite3.connect(src, isolation_level=None)
    try:
        holder.execute("BEGIN EXCLUSIVE")
        refused(["casebase", "copy", "--db", str(src), "--to", str(tmp_path / "new.sqlite")],
                tmp_path, capsys, "src.sqlite", "locked by another process")  # fmt: skip
    finally:
        holder.execute("ROLLBACK")
        holder.close()


def _killed_copy(db: Path, to: str) -> None:
    """``casebase copy --db DB --to TO``, stopped by SIGTERM inside its one transaction once
    every case is written (paused after it wrote the history's first entry)."""
    proc = posecbr_process("casebase", "copy", "--db", str(db), "--to", to, pause_after="build")
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == TERMINATED_STATUS, err
    assert "terminated (SIGTERM)" in err


def test_a_copy_stopped_midway_leaves_no_case_base(
    source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = _sha(source)
    dst = tmp_path / "dst.sqlite"
    _killed_copy(source, str(dst))
    assert not dst.exists() and os.listdir(tmp_path) == []  # no file, no temporary
    # into a store that exists: it is as it was
    _run(capsys, "casebase", "copy", "--db", str(source), "--to", str(dst), "--as", "first")
    was = _seen(str(dst), "first")
    _killed_copy(source, str(dst))
    store = open_store(dst)  # a writer: rolls back what the killed one left, if anything
    try:
        assert [i.name for i in store.list_case_bases()] == ["first"]
    finally:
        store.close()
    assert _seen(str(dst), "first") == was
    assert _sha(source) == before
    url = empty_postgres()
    _killed_copy(source, url)
    store = open_store(url, readonly=True)
    try:
        assert store.list_case_bases() == []
    finally:
        store.close()


def test_the_store_layer_copies_bytes_not_values(tmp_path: Path) -> None:
    """A problem's stored bytes travel as they are (a float32 problem stays float32, a -0.0
    stays -0.0, a NaN the NaN it was), as do the log's figures and an entry naming no case."""
    a, b = tmp_path / "a.sqlite", tmp_path / "b.sqlite"
    store = open_store(a, create=True)
    problems = [np.array([[-0.0, 1.5]], dtype=np.float32), np.array([[np.nan, 2.0]], np.float32)]
    try:
        with store.transaction() as tx:
            cb = tx.create_case_base("x", {"level": "fluents"}, ["f0", "f1"], ["f 0", "f 1"],
                                     {"name": "euclidean"}, model={"k": 1})  # fmt: skip
            ids = tx.add_cases(cb, [casebase_store.NewCase("l", p) for p in problems])
            tx.log(cb, "retain", case_id=ids[1], novelty=0.1, benefit=0.25)
            tx.log(cb, "retain", reason="not retained")
        whole = store.read_whole("x")
    finally:
        store.close()
    out = open_store(b, create=True)
    try:
        with out.transaction() as tx:
            info, new_ids = tx.copy_case_base(whole, "y")
        assert new_ids == ids and info.version == whole.info.version
        log = out.maintenance_log("y")
    finally:
        out.close()
    assert [c["features"] for c in _seen(str(b), "y")["cases"]] == [
        encode_array(p) for p in problems
    ]
    assert log[0].novelty == 0.1 and log[0].benefit == 0.25 and log[0].case_id == ids[1]
    assert log[1].case_id is None and log[1].reason == "not retained"


def test_a_large_copy_in_a_file_gets_its_matrices(
    source: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A case base large enough to be memory-mapped gets its matrices beside the file it is
    copied to, named for the copy (as every command that changes a case base writes them)."""
    import cbr.stored as stored_module

    monkeypatch.setattr(stored_module, "MAPPED_MIN_CASES", 10)  # "large": the source's 30
    monkeypatch.setattr(casebase_store.case_matrix, "MAPPED_MIN_CASES", 10)
    dst = tmp_path / "dst.sqlite"
    _run(capsys, "casebase", "copy", "--db", str(source), "--to", str(dst))
    store = open_store(dst, readonly=True)
    try:
        info = store.get_case_base("default")
    finally:
        store.close()
    name = hashlib.sha256(b"default").hexdigest()[:12]
    assert sorted(p.name for p in (tmp_path / "dst.sqlite.matrices").iterdir()) == [
        f"default~{name}.{kind}.{info.uid}-{info.version}.npy"
        for kind in ("problems", "representations")
    ]
    assert not (source.parent / "src.sqlite.matrices").exists()  # the source: read alone


@pytest.mark.parametrize(
    ("problems", "said"),
    [
        ([np.zeros((1, 2)), np.zeros((1, 3))], "features of different shapes"),
        ([np.array([["a", "b"]])], "non-numeric features"),
        ([np.zeros((1, 3))], "its cases have 3 feature columns but the case base names 2"),
    ],
)
def test_a_damaged_case_base_is_not_copied(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], problems: list[np.ndarray], said: str
) -> None:
    """Damage a command reading the case base would meet is refused before anything is
    written, not carried to the other store."""
    db = tmp_path / "cb.sqlite"
    store = open_store(db, create=True)
    try:
        with store.transaction() as tx:
            cb = tx.create_case_base("x", {"level": "fluents"}, ["f0", "f1"], ["f 0", "f 1"],
                                     {"name": "euclidean"})  # fmt: skip
            tx.add_cases(cb, [casebase_store.NewCase("l", p) for p in problems])
    finally:
        store.close()
    refused(["casebase", "copy", "--db", str(db), "--to", str(tmp_path / "new.sqlite")],
            tmp_path, capsys, "cb.sqlite", "case base 'x' is damaged", said)  # fmt: skip


def test_a_small_copy_loads_no_classifier(source: Path, tmp_path: Path) -> None:
    """Copying reads and writes the store: a case base too small for matrices loads neither
    scikit-learn nor SciPy (before: cbr.stored was imported to ask, 3 of the copy's 4 s)."""
    from tests.test_startup import _run as probe

    argv = ["casebase", "copy", "--db", str(source), "--to", str(tmp_path / "c.sqlite"), "--json"]
    out, loaded = probe(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    assert json.loads(out)["case_ids_kept"] is True
    assert loaded == {"numpy", "sqlalchemy"}
