"""Hunt 49d: ``train --append`` tells a stored case's copy by its clip's poses, not its features.

Within one command copies were told by their poses (``copies_within``: a SHA-256 of the
poses); against the cases already stored, by their frames and features within 1e-9, since the
store did not keep the digest. So

(b) two different takes of the same length whose features agree were refused as copies: real
    UI-PRMD takes, two subjects' shoulder scaptions of 69 frames (one done incorrectly), have
    the same binary QMP vector, and the second was refused from a QMP case base holding the
    first ("the same frames and features under another file name: a copy of its file?");
(a) a copy of a stored clip was added (voting twice) when the stored features were computed
    otherwise in the last digits (another posecbr computing the features otherwise; no case
    of it was found within one version from the command line: the stored case is made so by
    hand here, and said so).

Each case now stores its clip's poses digest (``cases.poses``); a store made before has no such
column: it is read and written as it is, its cases compared by their features as before, and
``casebase upgrade`` adds the column (its cases NULL there, compared by features still).
"""

from __future__ import annotations

import contextlib
import io
import shutil
import sqlite3
from pathlib import Path

import numpy as np
import pytest

#: two takes of a standing shoulder scaption, 69 frames each (s01 incorrect, s02 correct),
#: whose binary QMP vectors are the same, and a shoulder abduction
_KINECT = {
    "train/scaption/a.npz": "Incorrect Segmented Movements/Kinect/Positions/m10_s01_e08",
    "train/abduction/b.npz": "Segmented Movements/Kinect/Positions/m07_s01_e01",
    "other/scaption/c.npz": "Segmented Movements/Kinect/Positions/m10_s02_e04",
}


# on one xdist worker: the module's takes, fluent_cb made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt49d")


@pytest.fixture(scope="module")
def takes(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three real UI-PRMD Kinect takes as pose files: ``train/scaption/a.npz``,
    ``train/abduction/b.npz`` and the other scaption take ``other/scaption/c.npz``."""
    return write_takes(shared_data, tmp_path_factory.mktemp("takes"), _KINECT)


def write_takes(shared_data: Path, root: Path, takes: dict[str, str]) -> Path:
    """UI-PRMD Kinect takes (``takes``: the pose file under ``root`` -> the take's name in
    the data set) written as pose files; ``root``."""
    from features.poses import save_pose
    from features.readers.uiprmd import read_uiprmd_kinect

    for rel, name in takes.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        inc = "_inc" * name.startswith("Incorrect")
        path = shared_data / "ui-prmd" / "data" / f"{name}_positions{inc}.txt.gz"
        save_pose(read_uiprmd_kinect(path), root / rel)
    return root


def _run(argv: list[str]) -> tuple[int, str]:
    from posecbr.cli import main

    said = io.StringIO()
    with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
        code = main(argv)
    return code, said.getvalue()


def _train(takes: Path, db: Path, *options: str) -> None:
    argv = ["train", str(takes / "train"), "--db", str(db), "--mirror", "off", "-k", "1"]
    code, said = _run([*argv, "--feature-weights", "none", *options])
    assert code == 0, said


@pytest.fixture(scope="module")
def fluent_cb(takes: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A case base (fluent summaries) of ``a.npz`` and ``b.npz``, trained by the command
    once; tests copy it."""
    db = tmp_path_factory.mktemp("fluent") / "cb.sqlite"
    _train(takes, db, "--phases", "0")
    return db


def _cases(db: Path) -> list[tuple]:
    with contextlib.closing(sqlite3.connect(db)) as con:
        return con.execute("SELECT * FROM cases ORDER BY id").fetchall()


def _features(db: Path, source: Path) -> np.ndarray:
    with contextlib.closing(sqlite3.connect(db)) as con:
        ((blob,),) = con.execute("SELECT features FROM cases WHERE source = ?", (str(source),))
    return np.load(io.BytesIO(blob))


def _copy(takes: Path, tmp_path: Path, of: str = "train/scaption/a.npz") -> Path:
    """Take ``of`` copied byte for byte as ``copy/scaption/renamed.npz``: the folder to
    append."""
    copy = tmp_path / "copy" / "scaption" / "renamed.npz"
    copy.parent.mkdir(parents=True)
    shutil.copyfile(takes / of, copy)
    return copy.parent.parent


def assert_refused_by_poses(
    takes: Path, db: Path, tmp_path: Path, of: str = "train/scaption/a.npz", case: int = 2
) -> None:
    """Appending a byte copy of take ``of`` (:func:`_copy`) is refused as case ``case`` of
    ``db`` by its frames and poses, in one line, the store unchanged."""
    before = db.read_bytes()
    code, said = _run(["train", str(_copy(takes, tmp_path, of)), "--db", str(db), "--append"])
    assert code == 1
    assert said == (
        f"posecbr train: error: {db}: {tmp_path}/copy/scaption/renamed.npz frames 0-68 is "
        f"already case {case} of 'default', stored as {takes / of} frames 0-68 (the same"
        " frames and poses under another file name: a copy of its file?): nothing added\n"
    )
    assert db.read_bytes() == before


def test_another_take_described_alike_is_added_and_a_copy_refused_by_its_poses(
    takes: Path, tmp_path: Path
) -> None:
    """(b) A QMP case base of ``a.npz`` (s01's scaption) and ``b.npz``: s02's scaption take,
    of the same 69 frames and the same binary QMP vector but other poses, is added (before:
    refused as a copy of ``a.npz``, "the same frames and features under another file name");
    a byte copy of ``a.npz`` under another name is then refused naming its case, told by its
    poses, nothing added."""
    db = tmp_path / "cb.sqlite"
    _train(takes, db, "--features", "qmp")
    code, said = _run(["train", str(takes / "other"), "--db", str(db), "--append"])
    assert code == 0, said
    a, c = takes / "train" / "scaption" / "a.npz", takes / "other" / "scaption" / "c.npz"
    np.testing.assert_array_equal(_features(db, a), _features(db, c))  # described alike
    assert len(_cases(db)) == 3
    assert_refused_by_poses(takes, db, tmp_path)


def test_a_copy_is_refused_by_its_poses_when_the_stored_features_differ_in_the_last_digits(
    takes: Path, fluent_cb: Path, tmp_path: Path
) -> None:
    """(a) The stored case of ``a.npz`` with its features scaled by 1 + 1e-7 (made so by
    hand: as another posecbr computing them otherwise in the last digits would have stored
    them; beyond the 1e-9 the features are compared within): a byte copy of ``a.npz`` under
    another name is refused naming the case, nothing added (before: added, 2 cases to 3, the
    clip voting twice)."""
    db = Path(shutil.copy(fluent_cb, tmp_path / "cb.sqlite"))
    a = takes / "train" / "scaption" / "a.npz"
    stored = _features(db, a)
    moved = stored * (1 + 1e-7)
    assert not np.allclose(moved, stored, rtol=1e-9, atol=1e-9)
    blob = io.BytesIO()
    np.save(blob, moved)
    with contextlib.closing(sqlite3.connect(db)) as con, con:
        con.execute("UPDATE cases SET features = ? WHERE source = ?", (blob.getvalue(), str(a)))
    assert_refused_by_poses(takes, db, tmp_path)
    assert len(_cases(db)) == 2


def test_a_store_made_before_the_digests_is_read_as_it_is_and_compared_by_features(
    takes: Path, fluent_cb: Path, tmp_path: Path
) -> None:
    """The case base in a store of the schema before (no ``cases.poses`` column): classified
    with no upgrade, nothing written; a byte copy of ``a.npz`` is refused by its frames and
    features, as before. ``casebase upgrade`` adds the column, saying so (before: "nothing to
    do"), its cases without a digest; ``c.npz`` appended then stores its own (the SHA-256 of
    its poses), the old cases none."""
    from cbr.described import poses_digest
    from features.poses import load_pose

    db = Path(shutil.copy(fluent_cb, tmp_path / "cb.sqlite"))
    with contextlib.closing(sqlite3.connect(db)) as con, con:
        columns = [row[1] for row in con.execute("PRAGMA table_info(cases)")]
        if "poses" in columns:  # the schema of the store before
            con.execute("ALTER TABLE cases DROP COLUMN poses")
    width = len(_cases(db)[0])
    before = db.read_bytes()
    c = takes / "other" / "scaption" / "c.npz"
    code, said = _run(["classify", str(c), "--db", str(db)])
    assert code == 0, said
    assert "scaption" in said.splitlines()[0]
    assert db.read_bytes() == before
    a = takes / "train" / "scaption" / "a.npz"
    code, said = _run(["train", str(_copy(takes, tmp_path)), "--db", str(db), "--append"])
    assert (code, db.read_bytes() == before) == (1, True)
    assert said.endswith(
        f"already case 2 of 'default', stored as {a} frames 0-68 (the same frames and features "
        "under another file name: a copy of its file?): nothing added\n"
    )
    assert _run(["casebase", "upgrade", "--db", str(db)]) == (
        0,
        f"{db}: added the column cases.poses of a newer schema (no case changed)\n",
    )
    code, said = _run(["train", str(takes / "other"), "--db", str(db), "--append"])
    assert code == 0, said
    rows = _cases(db)
    assert [len(r) for r in rows] == [width + 1] * 3
    assert [r[-1] for r in rows] == [None, None, poses_digest(load_pose(c))]


@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_the_store_keeps_each_cases_poses_digest_and_a_store_made_before_none(
    backend: str, tmp_path: Path
) -> None:
    """``add_cases`` keeps a case's poses digest, ``cases_framed`` gives it back (None for a
    case stored without); a store whose cases table has no such column (made before) takes
    the same cases without it, and they are read back (None); ``casebase copy`` to it leaves
    the digests out, from it to a new store copies none, from a new store copies them. A
    digest that is not 64 hexadecimal digits is refused."""
    from sqlalchemy import text

    from casebase_store import NewCase, StoreError, open_store
    from tests.postgres import empty_postgres

    digest = "0123456789abcdef" * 4
    new = [NewCase("l", np.array([1.0, 2.0]), "x.npz", 0, 9, poses=digest),
           NewCase("l", np.array([3.0, 4.0]), "y.npz", 0, 9)]  # fmt: skip

    def store_cases(db: str, made_before: bool) -> list[tuple[str, str | None]]:
        with open_store(db, create=True) as store, store.transaction() as tx:
            if made_before:  # the schema before (SQLite: the column dropped)
                tx.session.execute(text("ALTER TABLE cases DROP COLUMN poses"))
        with open_store(db) as store:
            with store.transaction() as tx:
                info = tx.create_case_base("default", {"f": 1}, ["a", "b"], ["a", "b"],
                                           {"name": "euclidean"})  # fmt: skip
                tx.add_cases(info, new)
                with pytest.raises(StoreError, match="64 hexadecimal digits, got 'abc'"):
                    tx.add_cases(info, [NewCase("l", np.zeros(2), "z.npz", poses="abc")])
            with store.transaction() as tx:
                found = list(tx.cases_framed(tx.case_base("default"), [(0, 9)]))
        return [(c.source, c.poses) for chunk in found for c in chunk]

    url = empty_postgres() if backend == "postgresql" else str(tmp_path / "new.sqlite")
    assert store_cases(url, made_before=False) == [("x.npz", digest), ("y.npz", None)]
    old = str(tmp_path / "old.sqlite")
    assert store_cases(old, made_before=True) == [("x.npz", None), ("y.npz", None)]
    for db, to, poses in ((url, old, None), (old, tmp_path / "a.sqlite", [None, None]),
                          (url, tmp_path / "b.sqlite", [digest, None])):  # fmt: skip
        argv = ["casebase", "copy", "--db", str(db), "--name", "default", "--to", str(to)]
        code, said = _run([*argv, "--as", "c"])
        assert code == 0, said
        with contextlib.closing(sqlite3.connect(to)) as con:
            cur = con.execute("SELECT * FROM cases WHERE case_base_id = (SELECT id FROM"
                              " case_bases WHERE name = 'c') ORDER BY id")  # fmt: skip
            rows = [dict(zip([d[0] for d in cur.description], r, strict=True)) for r in cur]
        assert [r["source"] for r in rows] == ["x.npz", "y.npz"]
        assert [r.get("poses") for r in rows] == (poses or [None, None])
        assert ("poses" in rows[0]) is (poses is not None)
