"""A large case base maps its matrices from beside the database instead of copying them per
process (issue 17, item 4); the answers are those of the case base read from SQL."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import numpy as np
import pytest

import cbr.stored as stored_module
from casebase_store import open_store
from cbr.stored import load_classifier
from features.datasets import load_dataset
from posecbr.cli import main
from tests.once import made_once

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
#: the matrices' file names carry a hash of the exact case base name (its first 12 digits)
DEFAULT = hashlib.sha256(b"default").hexdigest()[:12]


def _matrices(db: Path) -> list[str]:
    folder = db.with_name(db.name + ".matrices")
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def _is_mapped(a: np.ndarray) -> bool:
    while a is not None and not isinstance(a, np.memmap):
        a = a.base  # type: ignore[assignment]
    return isinstance(a, np.memmap)


@pytest.fixture
def trained(tmp_path_factory: pytest.TempPathFactory, tmp_path: Path) -> Path:
    """``train --subjects s01,s02`` with a case base of 50 cases counted large (the demo's
    120), made once in the session: each test gets its own copy of the database and of the
    matrices the command wrote beside it."""

    def make(folder: Path) -> Path:
        db = folder / "cb.sqlite"
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(stored_module, "MAPPED_MIN_CASES", 50)
            argv = ["train", str(DEMO / "labels.csv"), "--db", str(db), "--subjects", "s01,s02"]
            assert main(argv) == 0
        return db

    made = made_once(tmp_path_factory, "mapped-s01-s02", make)
    db = tmp_path / "cb.sqlite"
    shutil.copyfile(made, db)
    matrices = made.name + ".matrices"
    shutil.copytree(made.with_name(matrices), db.with_name(matrices))
    return db


def test_a_large_case_base_is_mapped_and_answers_as_read_from_sql(
    trained: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(stored_module, "MAPPED_MIN_CASES", 50)  # "large": the demo's 120
    db = trained
    store = open_store(db, readonly=True)
    uid, version = store.get_case_base("default").uid, store.get_case_base("default").version
    assert _matrices(db) == [
        f"default~{DEFAULT}.problems.{uid}-{version}.npy",
        f"default~{DEFAULT}.representations.{uid}-{version}.npy",
    ]
    mapped = load_classifier(store, "default").classifier
    assert _is_mapped(mapped.case_base_.problems) and _is_mapped(mapped.case_base_.reps)
    assert not mapped.case_base_.problems.flags.writeable
    monkeypatch.setattr(stored_module, "MAPPED_MIN_CASES", 10**9)
    monkeypatch.setattr(stored_module, "_mapped", lambda *a: None)  # the SQL read
    from_sql = load_classifier(store, "default").classifier
    store.close()
    assert not _is_mapped(from_sql.case_base_.problems)
    np.testing.assert_array_equal(mapped.case_base_.problems, from_sql.case_base_.problems)
    X = [c.seq for c in load_dataset(DEMO / "labels.csv", subjects={"s03"})]
    np.testing.assert_array_equal(mapped.predict_proba(X), from_sql.predict_proba(X))


def test_a_change_maps_the_new_version_and_a_stale_matrix_is_never_read(
    trained: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(stored_module, "MAPPED_MIN_CASES", 50)
    db = trained
    clip = str(DEMO / "m01_s03_e01.npz")
    argv = ["classify", clip, "--db", str(db), "--feedback", "deep_squat", "--novelty", "1e9"]
    assert main(argv) == 0  # one revision: version 2, mapped anew
    capsys.readouterr()
    store = open_store(db, readonly=True)
    info = store.get_case_base("default")
    assert info.version == 2
    assert _matrices(db) == [
        f"default~{DEFAULT}.problems.{info.uid}-2.npy",
        f"default~{DEFAULT}.representations.{info.uid}-2.npy",
    ]
    revised = load_classifier(store, "default").classifier
    sql = store.load_cases("default").features
    np.testing.assert_array_equal(revised.case_base_.problems, sql)
    store.close()
    # a writer that changes the cases without mapping them: readers go back to SQL
    store = open_store(db)
    with store.transaction() as tx:
        cb = tx.case_base("default")
        tx.deactivate_cases(cb, [int(store.load_cases("default").ids[0])])
    store.close()
    store = open_store(db, readonly=True)
    fresh = load_classifier(store, "default").classifier
    assert not _is_mapped(fresh.case_base_.problems)
    assert len(fresh.case_base_) == len(revised.case_base_) - 1
    store.close()
