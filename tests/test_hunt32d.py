"""Case base store faults found by hunt 32d (several commands on one case base): real SQLite
files, real processes where the point is a process."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

from casebase_store import NewCase, open_store, write_store
from posecbr.cli import main
from tests.badinput import small_case_base

#: file names whose characters mean something in a URL: a query, a fragment, an escape
URL_LIKE_NAMES = ("a?b.sqlite", "a#b.sqlite", "a%20b.sqlite", "a?mode=rw.sqlite")


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _one_case_base(tx: object, name: str = "cb") -> None:
    cb = tx.create_case_base(name, {"level": "fluents"}, ["f"], ["f"], {"name": "euclidean"})  # type: ignore[attr-defined]
    tx.add_cases(cb, [NewCase("walk", np.array([1.0]))])  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", URL_LIKE_NAMES)
def test_a_file_name_with_url_characters_is_the_file_written_and_read(
    tmp_path: Path, name: str
) -> None:
    # before: the path went into a "sqlite:///PATH" URL as text, so "a?b.sqlite" was the file
    # "a" with a query "b.sqlite", and "a%20b.sqlite" the file "a b.sqlite": a first write
    # built its case base in a hidden ".a", then failed "cannot create the case base file
    # (No such file or directory)"; a read opened (and created) "a"
    other = tmp_path / "a"  # another case base, the file the name's text stops at
    write_store(other, lambda tx: _one_case_base(tx, "other"))
    before = _sha(other)
    db = tmp_path / name
    write_store(db, _one_case_base)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["a", name])
    with open_store(db, readonly=True) as store:
        assert [cb.name for cb in store.list_case_bases()] == ["cb"]
    with open_store(db) as store:  # written again: the same file
        store.add_cases("cb", [NewCase("run", np.array([2.0]))])
    with open_store(db, readonly=True) as store:
        assert store.get_case_base("cb").label_counts == {"run": 1, "walk": 1}
    assert _sha(other) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["a", name])


def test_train_and_info_on_a_file_name_with_a_question_mark(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = small_case_base(tmp_path / "first")
    named = tmp_path / "cb?v2.sqlite"
    named.write_bytes(db.read_bytes())
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(named), "--json"]) == 0
    assert '"cases": 9' in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cb?v2.sqlite", "first"]
