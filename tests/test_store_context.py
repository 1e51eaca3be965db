"""``with open_store(...) as store:`` closes the store's connections at the end of the block,
also when the block raised: no file descriptor of this process is left on the database."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from casebase_store.store import open_store
from tests.badinput import small_case_base


def _open_on(path: Path) -> int:
    """How many of this process's file descriptors point at ``path`` (Linux: /proc)."""
    fds = Path("/proc/self/fd")
    target = str(path.resolve())
    count = 0
    for fd in fds.iterdir():
        try:
            count += os.readlink(fd) == target
        except OSError:
            continue
    return count


@pytest.fixture(scope="module")
def db(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs Linux's /proc")
@pytest.mark.parametrize("readonly", [True, False])
def test_the_block_closes_the_store(db: Path, readonly: bool) -> None:
    assert _open_on(db) == 0
    with open_store(db, readonly=readonly) as store:
        assert [i.name for i in store.list_case_bases()] == ["default"]
        assert _open_on(db) >= 1  # the pool keeps the connection it read with
    assert _open_on(db) == 0


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs Linux's /proc")
def test_the_block_closes_the_store_when_it_raised(db: Path) -> None:
    with pytest.raises(KeyError), open_store(db, readonly=True) as store:
        store.list_case_bases()
        raise KeyError("the caller's own error, passed on")
    assert _open_on(db) == 0
