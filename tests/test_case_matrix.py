"""The memory-mapped case matrix: written whole or not at all, read without a copy, used in
place by the measures' indexes, keyed by version so a stale matrix is never read."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from casebase_store.case_matrix import (
    cached_case_matrix,
    content_version,
    matrix_path,
    open_case_matrix,
    write_case_matrix,
)
from cbr.similarity import DTW, Euclidean
from cbr.similarity.dtw import envelope
from features.errors import DataError


def _chunks(x: np.ndarray, size: int) -> Iterator[np.ndarray]:
    for a in range(0, len(x), size):
        yield x[a : a + size]


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_written_in_chunks_and_read_back_memory_mapped(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(size=(1003, 12)).astype(np.float32)
    path = write_case_matrix(tmp_path / "m.npy", _chunks(x, 100), x.shape)
    m = open_case_matrix(path, x.shape)
    assert isinstance(m, np.memmap) and not m.flags.writeable
    np.testing.assert_array_equal(m, x)
    assert [p.name for p in tmp_path.iterdir()] == ["m.npy"]  # no temporary file left


def test_euclidean_index_uses_the_mapped_rows_in_place(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(6000, 40)).astype(np.float32)
    mapped = open_case_matrix(write_case_matrix(tmp_path / "m.npy", _chunks(x, 999), x.shape))
    m = Euclidean(prune_min_cases=1000)
    index = m.build_index(mapped)
    assert np.shares_memory(index.rows, mapped)  # no copy of the case matrix
    q = rng.normal(size=40)
    true = np.sqrt(((x.astype(np.float64) - q.astype(np.float32)) ** 2).sum(axis=1))
    idx, dist = m.nearest(m.represent_query(q), index, 5)
    np.testing.assert_array_equal(idx, np.argsort(true, kind="stable")[:5])
    np.testing.assert_allclose(dist, true[idx], rtol=1e-5)


def test_dtw_index_uses_mapped_sequences_and_envelopes_in_place(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    seqs = np.cumsum(rng.normal(size=(300, 20, 3)), axis=1).astype(np.float32)
    m = DTW(radius=2)
    up, lo = envelope(seqs, 2)
    mapped = [
        open_case_matrix(write_case_matrix(tmp_path / f"{name}.npy", _chunks(a, 64), a.shape))
        for name, a in (("cases", seqs), ("upper", up), ("lower", lo))
    ]
    index = m.index_from(*mapped)
    for got, src in zip((index.cases, index.upper, index.lower), mapped, strict=True):
        assert np.shares_memory(got, src)
    memory = m.build_index(m.represent(seqs))
    q = m.represent_query(seqs[7] + rng.normal(scale=0.1, size=(20, 3)))
    for a, b in zip(m.nearest(q, index, 4), m.nearest(q, memory, 4), strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    ("chunks", "message"),
    [
        ([np.zeros((5, 3)), np.zeros((5, 4))], "do not fit a matrix of (10, 3)"),
        ([np.zeros((5, 3))], "got 5 rows, expected 10"),
        ([np.zeros((5, 3)), np.zeros((6, 3))], "do not fit a matrix of (10, 3) after 5 rows"),
        ([np.zeros((5, 3)), np.full((5, 3), np.nan)], "rows 5..9 are not finite"),
    ],
)
def test_bad_rows_leave_the_old_matrix_untouched(
    tmp_path: Path, chunks: list[np.ndarray], message: str
) -> None:
    path = write_case_matrix(tmp_path / "m.npy", [np.ones((10, 3))], (10, 3))
    before = _files(tmp_path)
    with pytest.raises(DataError) as err:
        write_case_matrix(path, chunks, (10, 3))
    assert message in str(err.value) and str(path) in str(err.value)
    assert _files(tmp_path) == before  # old matrix as it was, no temporary file left


def test_unreadable_or_mismatched_matrix_is_one_clear_error(tmp_path: Path) -> None:
    junk = tmp_path / "junk.npy"
    junk.write_bytes(b"not a numpy file at all")
    with pytest.raises(DataError, match="not a case matrix"):
        open_case_matrix(junk)
    good = write_case_matrix(tmp_path / "m.npy", [np.ones((4, 2))], (4, 2))
    with pytest.raises(DataError, match=r"has shape \(4, 2\), expected \(5, 2\)"):
        open_case_matrix(good, (5, 2))
    with pytest.raises(DataError, match="no case matrix file"):
        open_case_matrix(tmp_path / "absent.npy")
    assert junk.read_bytes() == b"not a numpy file at all"


def test_cache_is_keyed_by_version_and_replaces_only_its_own_old_versions(tmp_path: Path) -> None:
    db = tmp_path / "cb.sqlite"
    calls: list[int] = []

    def rows(value: float) -> list[np.ndarray]:
        calls.append(1)
        return [np.full((3, 2), value)]

    v1 = content_version(np.array([1, 2, 3]), "rev 1")
    v2 = content_version(np.array([1, 2, 3]), "rev 2")
    assert v1 != v2 and v1 == content_version(np.array([1, 2, 3]), "rev 1")
    other = cached_case_matrix(db, "other", "rows", v1, (3, 2), lambda: rows(9.0))
    a = cached_case_matrix(db, "squats", "rows", v1, (3, 2), lambda: rows(1.0))
    again = cached_case_matrix(db, "squats", "rows", v1, (3, 2), lambda: rows(5.0))
    assert len(calls) == 2  # the second open of v1 read the file, did not rebuild it
    np.testing.assert_array_equal(again, a)
    b = cached_case_matrix(db, "squats", "rows", v2, (3, 2), lambda: rows(2.0))
    assert float(b[0, 0]) == 2.0
    assert not matrix_path(db, "squats", "rows", v1).exists()  # the stale version is gone
    assert matrix_path(db, "other", "rows", v1).exists()  # another case base's is kept
    assert float(other[0, 0]) == 9.0
    assert matrix_path(db, "squats", "rows", v2).parent == tmp_path / "cb.sqlite.matrices"
