"""A read-only command writes nothing: not beside the case base (SQLite's side files), not in
it (the measure's cached representations), and every file in its folder keeps its bytes and
its modification time."""

from __future__ import annotations

import hashlib
import sqlite3
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import refused, snapshot

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"
CLIP = DEMO / "m01_s03_e01.npz"
V1_SQL = Path(__file__).with_name("fixtures") / "store_v1.sql"


# on one xdist worker: the module's trained made once, not once per worker
pytestmark = pytest.mark.xdist_group("readonly22")


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small DTW case base (its envelopes are cached per case in the file)."""
    db = tmp_path_factory.mktemp("cb") / "cb.sqlite"
    argv = ["train", str(LABELS), "--db", str(db), "--subjects", "s01", "--similarity", "dtw",
            "--labels", "deep_squat,standing_shoulder_abduction,sit_to_stand",
            "--mirror", "off"]  # fmt: skip
    assert main(argv) == 0
    return db


def _stat_snapshot(root: Path) -> dict[str, tuple[int, int, str]]:
    """Every file under ``root``: size, modification time (ns) and sha256."""
    out = {}
    for p in sorted(root.rglob("*")):
        if p.is_file():
            st = p.stat()
            out[p.name] = (st.st_size, st.st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest())
    return out


def _in_wal_mode(db: Path) -> None:
    con = sqlite3.connect(db)
    assert con.execute("PRAGMA journal_mode = WAL").fetchone() == ("wal",)
    con.close()


def _readers(db: Path, out: Path) -> list[list[str]]:
    return [
        ["classify", str(CLIP), "--db", str(db)],
        ["segment", str(CLIP), "--db", str(db), "--unknown", "held-out"],
        ["casebase", "info", "--db", str(db)],
        ["casebase", "list", "--db", str(db)],
        ["casebase", "export", "--db", str(db), "--out", str(out / "cases.npz")],
        ["casebase", "trim", "--db", str(db), "--dry-run"],
    ]


@pytest.mark.parametrize("which", range(6))
def test_a_reader_leaves_no_wal_side_files_beside_a_store_in_wal_mode(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], which: int
) -> None:
    """A store still in WAL mode, in a folder this process can write: SQLite's read-only
    opening created ``cb.sqlite-wal`` and ``cb.sqlite-shm`` beside it and left them there
    (a reader cannot remove them), and touched ``-shm`` on every later read. Opening it
    ``immutable`` instead would read without locks while a writer may convert and change the
    file; so the reader refuses it in one line, before SQLite opens it, naming the writer
    that converts it."""
    folder, out = tmp_path / "cb", tmp_path / "out"
    folder.mkdir()
    out.mkdir()
    db = folder / "cb.sqlite"
    db.write_bytes(trained.read_bytes())
    _in_wal_mode(db)
    argv = _readers(db, out)[which]
    refused(argv, folder, capsys, "WAL", "posecbr casebase upgrade --db FILE")
    assert sorted(p.name for p in folder.iterdir()) == ["cb.sqlite"]
    assert not list(out.iterdir())


def test_a_store_of_posecbr_0_1_is_refused_without_side_files_then_upgraded(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """posecbr 0.1 kept its stores in WAL mode: reading one was refused for its schema, but
    the refusal left ``-wal`` and ``-shm`` beside it. ``casebase upgrade`` (a writer) converts
    the schema and the journal; readers then create nothing."""
    folder = tmp_path / "cb"
    folder.mkdir()
    db = folder / "old.sqlite"
    con = sqlite3.connect(db)
    con.executescript(V1_SQL.read_text(encoding="utf-8"))
    con.close()
    _in_wal_mode(db)
    refused(["classify", str(CLIP), "--db", str(db)], folder, capsys, "casebase upgrade")
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    said = capsys.readouterr().out
    assert "converted from schema version 1 to 2" in said and "WAL" in said
    assert sorted(p.name for p in folder.iterdir()) == ["old.sqlite"]
    before = _stat_snapshot(folder)
    assert main(["classify", str(CLIP), "--db", str(db), "--json"]) == 0
    assert '"label": "deep_squat"' in capsys.readouterr().out
    assert _stat_snapshot(folder) == before


def test_upgrade_of_a_current_store_in_wal_mode_says_it_converted_the_journal(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The refusal sends the user to ``casebase upgrade``, which converted the journal but
    said "already schema version 2, nothing to do"."""
    db = tmp_path / "cb.sqlite"
    db.write_bytes(trained.read_bytes())
    _in_wal_mode(db)
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    said = capsys.readouterr().out
    assert "nothing to do" not in said and "WAL" in said and "rollback journal" in said
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cb.sqlite"]
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert "already schema version 2, nothing to do" in capsys.readouterr().out
    before = _stat_snapshot(tmp_path)
    assert main(["casebase", "info", "--db", str(db)]) == 0
    assert _stat_snapshot(tmp_path) == before


def test_readers_never_write_the_representation_cache(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case base missing cached DTW envelopes (a revised case's are dropped) is read by
    ``classify``, ``segment``, ``casebase export`` and ``trim --dry-run`` with the envelopes
    computed in memory: the file keeps its bytes and its modification time, and nothing
    appears beside it."""
    folder, out = tmp_path / "cb", tmp_path / "out"
    folder.mkdir()
    out.mkdir()
    db = folder / "cb.sqlite"
    db.write_bytes(trained.read_bytes())
    con = sqlite3.connect(db)
    n = con.execute("SELECT COUNT(*) FROM case_representations").fetchone()[0]
    con.execute("DELETE FROM case_representations WHERE case_id % 3 = 0")
    con.commit()
    missing = n - con.execute("SELECT COUNT(*) FROM case_representations").fetchone()[0]
    con.close()
    assert n > 0 and missing > 0
    before, files = _stat_snapshot(folder), snapshot(folder)
    for argv in _readers(db, out):
        assert main(argv) == 0, capsys.readouterr().err
        capsys.readouterr()
        assert _stat_snapshot(folder) == before, argv
    assert snapshot(folder) == files


def _without_some_representations(trained: Path, folder: Path) -> Path:
    """A copy of ``trained`` in ``folder`` missing a third of its cached envelopes, as a case
    base whose cases were revised is (their representations are dropped)."""
    folder.mkdir()
    db = folder / "cb.sqlite"
    db.write_bytes(trained.read_bytes())
    con = sqlite3.connect(db)
    con.execute("DELETE FROM case_representations WHERE case_id % 3 = 0")
    con.commit()
    con.close()
    return db


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--feedback", "deep_sqat"], "did you mean"),  # a typo
        (["--feedback", "new_thing"], "--new-label"),  # a new activity without --new-label
        (["--feedback", "deep_squat", "--target", "correct"], "--target"),
        (["--feedback", "deep_squat", "-k", "999"], "-k"),
    ],
)
def test_refused_feedback_writes_nothing_into_the_case_base(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str],
    needle: str,
) -> None:  # fmt: skip
    """``classify --feedback`` loaded the classifier through its writable store, which stored
    the missing representations in the file before the label, ``--target`` or ``-k`` were
    checked: a refused command changed the case base."""
    db = _without_some_representations(trained, tmp_path / "cb")
    argv = ["classify", str(CLIP), "--db", str(db), *extra]
    refused(argv, db.parent, capsys, needle)


def test_feedback_on_an_unclassifiable_clip_writes_nothing_into_the_case_base(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import numpy as np

    db = _without_some_representations(trained, tmp_path / "cb")
    clip = dict(np.load(CLIP))
    short = tmp_path / "short.npz"
    np.savez(short, **{**clip, "positions": clip["positions"][:3]})  # type: ignore[arg-type]
    before = _stat_snapshot(db.parent)
    assert main(["classify", str(short), "--db", str(db), "--feedback", "deep_squat"]) == 1
    assert "no clip could be classified" in capsys.readouterr().err
    assert _stat_snapshot(db.parent) == before


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--editor", "renn", "-k", "100000"], "-k: must be less than"),
        (["--keep", "0.01"], "nothing trimmed"),  # fewer cases left than the case base's k
    ],
)
def test_refused_trim_writes_nothing_into_the_case_base(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str],
    needle: str,
) -> None:  # fmt: skip
    """``casebase trim`` too loaded the classifier through its writable store, storing the
    missing representations before it refused."""
    db = _without_some_representations(trained, tmp_path / "cb")
    refused(["casebase", "trim", "--db", str(db), *extra], db.parent, capsys, needle)
