"""Hunt 47n: three data-integrity defects of case bases left from the last session.

1. A stored problem changed on disk to hold NaN or an infinity (an UPDATE of its bytes with
   sqlite3): ``classify`` refused every clip in turn in the similarity measure's words
   ("euclidean: case rows 3, 4 hold NaN or inf": row numbers, not case ids, no case base
   named), and ``segment`` said the same once. Training never stores such a value (every
   problem made of a clip has its gaps filled), so the case base is refused once where
   ``cbr`` loads it for solving, naming it and the damaged cases.
2. Two copies of one clip under two file names given to ONE ``train --append`` were both
   stored (given in two appends, the second is refused as a case already held): refused,
   naming both files, nothing added.
3. A PostgreSQL connection lost right after an append committed (as the cases are counted)
   said "the connection to the database server was lost" alone: the user ran the append
   again and was refused as "already held". The line now says the cases were added before
   it; so do a new case base's, a trim's and a copy's when the error comes after their
   commit.
"""

from __future__ import annotations

import contextlib
import io
import shutil
import sqlite3
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.once import made_once


@pytest.fixture(scope="module")
def small_cases(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/badinput.py's small case base (three activities of synthetic arm movements,
    three clips each, in ``train/<activity>/clipNN.npz`` beside it), made once in the whole
    run; tests copy it."""
    from tests.badinput import small_case_base

    return made_once(tmp_path_factory, "small-case-base", small_case_base)


def _ids(db: Path) -> list[int]:
    """The ids of the cases stored in ``db``, read with sqlite3."""
    with contextlib.closing(sqlite3.connect(db)) as con:
        return [int(i) for (i,) in con.execute("SELECT id FROM cases ORDER BY id")]


def _set_value(db: Path, case_id: int, index: int, value: float) -> None:
    """Value ``index`` of case ``case_id``'s stored problem set to ``value``, with sqlite3
    and numpy's own ``.npy`` writer (as someone editing the file would)."""
    with contextlib.closing(sqlite3.connect(db)) as con, con:
        ((blob,),) = con.execute("SELECT features FROM cases WHERE id = ?", (case_id,))
        problem = np.load(io.BytesIO(blob)).copy()
        problem.flat[index] = value
        out = io.BytesIO()
        np.save(out, problem)
        con.execute("UPDATE cases SET features = ? WHERE id = ?", (out.getvalue(), case_id))


def test_a_case_base_damaged_on_disk_is_refused_once_naming_the_damaged_cases(
    small_cases: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The second case's problem given a NaN and the last one's a minus infinity (UPDATE with
    sqlite3): ``classify`` of six clips and ``segment`` of one are refused in one line naming
    the case base and the two cases by their ids, nothing written (before: each clip
    "unclassifiable (euclidean: case rows 1, 8 hold NaN or inf ...)", then "no clip could be
    classified"; ``segment`` the measure's line). One damaged case is named alone."""
    from tests.badinput import refused

    db = Path(shutil.copy(small_cases, tmp_path / "cb.sqlite"))
    ids = _ids(db)
    assert len(ids) == 9
    _set_value(db, ids[1], 0, np.nan)
    _set_value(db, ids[-1], 100, -np.inf)
    train = small_cases.parent / "train"
    folders = sorted(str(p) for p in train.iterdir())
    said = (
        f"{db}: case base 'default' is damaged: the problems of cases {ids[1]}, {ids[-1]} hold "
        "NaN or an infinity, which training never stores (changed outside posecbr?): no clip "
        "can be compared with them; train the case base again, or use a copy made before"
    )
    line = refused(["classify", *folders[:2], "--db", str(db)], tmp_path, capsys)
    assert line == f"posecbr classify: error: {said}"
    clip = sorted(Path(folders[0]).glob("*.npz"))[0]
    line = refused(["segment", str(clip), "--db", str(db)], tmp_path, capsys)
    assert line == f"posecbr segment: error: {said}"
    _set_value(db, ids[-1], 100, 0.25)
    line = refused(["classify", folders[0], "--db", str(db)], tmp_path, capsys)
    assert f"the problem of case {ids[1]} holds NaN or an infinity" in line
    assert line.endswith(
        "no clip can be compared with it; train the case base again, or use a copy made before"
    )


def test_the_check_refuses_nan_and_infinities_not_large_finite_values() -> None:
    """``check_finite`` on hand-made problems: values whose row sum overflows (1e308 twice)
    are finite, no damage; a NaN, an infinity, or both infinities (their sum NaN) are named
    by case id, in vectors and in sequences ``(n, frames, columns)``."""
    from casebase_store import StoreError
    from cbr.stored import check_finite

    ids = np.array([10, 11, 12, 13, 14])
    fine = np.array([[1e308, 1e308, 0.0], [0.0, 1.0, 2.0], [-1e308, -1e308, 5.0]])
    check_finite("x", fine, ids[:3], "w")
    bad = np.array([[1e308, 1e308, 0.0], [np.nan, 0.0, 0.0], [0.0, 1.0, 2.0],
                    [np.inf, -np.inf, 0.0], [0.0, 0.0, -np.inf]])  # fmt: skip
    with pytest.raises(StoreError, match=r"the problems of cases 11, 13, 14 hold NaN"):
        check_finite("x", bad, ids, "w")
    sequences = np.zeros((2, 3, 2))
    check_finite("x", sequences, ids[:2], "w")
    sequences[1, 2, 0] = np.inf
    with pytest.raises(StoreError, match=r"'x' is damaged: the problem of case 11 holds"):
        check_finite("x", sequences, ids[:2], "w")


def test_two_copies_of_one_clip_in_one_append_are_refused_naming_both(
    small_cases: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A new 2-s squat (60 frames) written as ``add/Squat/a.npz`` and, the same poses, as
    ``add/Squat/b.npz``: one ``--append`` of both is refused naming both files, nothing
    added (before: both stored, 9 cases to 11, the clip voting twice); b moved to another
    activity's folder, the same; with b's left shoulder moved 5 cm in every frame, it is
    another clip: both added, 11 cases."""
    import dataclasses

    from features.poses import load_pose, save_pose
    from posecbr.cli import main
    from tests.badinput import refused
    from tests.moves import clip

    db = Path(shutil.copy(small_cases, tmp_path / "cb.sqlite"))
    data = tmp_path / "add"
    a, b = data / "Squat" / "a.npz", data / "Squat" / "b.npz"
    save_pose(clip("squat", 2.0, 30.0), a)
    shutil.copyfile(a, b)
    argv = ["train", str(data), "--db", str(db), "--append"]
    line = refused(argv, tmp_path, capsys)
    assert line == (
        f"posecbr train: error: {db}: {b} frames 0-59 has the same frames and poses as "
        f"{a} frames 0-59, given in this append too (a copy of its file?): its case would "
        "vote twice; nothing added"
    )
    other = data / "Lunge" / "b.npz"
    other.parent.mkdir()
    b.rename(other)
    line = refused(argv, tmp_path, capsys)
    # the class folders in their order: Lunge's clip first, Squat's the copy of it
    assert f"{db}: {a} frames 0-59 has the same frames and poses as {other} frames" in line
    seq = load_pose(other)
    moved = seq.positions.copy()
    moved[:, 11, 0] += 0.05
    save_pose(dataclasses.replace(seq, positions=moved), other)
    assert main(argv) == 0
    assert len(_ids(db)) == 11


def _connection_lost(store: Any, name: str, *args: Any, **kwargs: Any) -> bool:
    """In place of ``write_matrices``, the first thing a train or append does after its
    commit: the driver's error of a connection the server ended, as SQLAlchemy hands it to
    the store."""
    import psycopg
    from sqlalchemy.exc import OperationalError

    with store._errors():
        raise OperationalError(
            "SELECT count(cases.id) AS count_1 FROM cases",
            {},
            psycopg.OperationalError(
                "consuming input failed: server closed the connection unexpectedly"
            ),
        )


@pytest.mark.parametrize("append", [True, False], ids=["append", "build"])
def test_an_error_after_the_commit_says_the_cases_are_stored(
    small_cases: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    append: bool,
) -> None:
    """The connection lost after the commit (the driver's error where the command writes the
    matrices and counts the cases): the line says the cases were stored before it and what
    running again does; they are in the case base (before: the lost connection alone)."""
    import cbr.training
    from posecbr.cli import main

    db = Path(shutil.copy(small_cases, tmp_path / "cb.sqlite"))
    data = small_cases.parent / "train"
    monkeypatch.setattr(cbr.training, "write_matrices", _connection_lost)
    if append:
        from features.poses import save_pose
        from tests.moves import clip

        save_pose(clip("squat", 2.0, 30.0), tmp_path / "add" / "Squat" / "s.npz")
        argv = ["train", str(tmp_path / "add"), "--db", str(db), "--append"]
        done = (
            "the 1 case was added to 'default' before it: run again, the append is refused "
            "as held already (casebase info shows them)"
        )
    else:
        argv = ["train", str(data), "--db", str(db), "--name", "other", "--mirror", "off",
                "--feature-weights", "none", "--phases", "0"]  # fmt: skip
        done = "case base 'other' was stored before it (9 cases): casebase info shows it"
    capsys.readouterr()
    assert main(argv) == 1
    assert capsys.readouterr().err == (
        f"posecbr train: error: {db}: the connection to the database server was lost "
        f"(consuming input failed: server closed the connection unexpectedly); {done}\n"
    )
    with contextlib.closing(sqlite3.connect(db)) as con:
        counts = dict(
            con.execute(
                "SELECT b.name, COUNT(*) FROM cases c JOIN case_bases b"
                " ON c.case_base_id = b.id GROUP BY b.name"
            ).fetchall()
        )
    assert counts == ({"default": 10} if append else {"default": 9, "other": 9})


def test_an_error_after_a_trim_or_a_copy_committed_says_it_is_stored(
    small_cases: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The same error where ``casebase trim`` (keeping 0.6 of each activity's three cases:
    two, 9 -> 6) and ``casebase copy`` (of a copy large enough for matrices: the least
    lowered to 5 cases) write the matrices after their commit: the line says the trim (the
    copy) is stored, and it is (before: the lost connection alone)."""
    import casebase_store.case_matrix
    import cbr.stored
    from posecbr.cli import main

    lost = (
        "the connection to the database server was lost (consuming input failed: server "
        "closed the connection unexpectedly)"
    )
    db = Path(shutil.copy(small_cases, tmp_path / "cb.sqlite"))
    monkeypatch.setattr(cbr.stored, "write_matrices", _connection_lost)
    capsys.readouterr()
    assert main(["casebase", "trim", "--db", str(db), "--keep", "0.6"]) == 1
    assert capsys.readouterr().err == (
        f"posecbr casebase trim: error: {db}: {lost}; the trim was stored before it (9 -> 6 "
        "cases: casebase info shows it); run again, it would trim the case base again\n"
    )
    with contextlib.closing(sqlite3.connect(db)) as con:
        assert con.execute("SELECT SUM(active) FROM cases").fetchone() == (6,)
    monkeypatch.setattr(casebase_store.case_matrix, "MAPPED_MIN_CASES", 5)
    to = tmp_path / "to.sqlite"
    assert main(["casebase", "copy", "--db", str(db), "--to", str(to)]) == 1
    assert capsys.readouterr().err == (
        f"posecbr casebase copy: error: {to}: {lost}; the copy 'default' was stored before it"
        " (casebase info --db shows it)\n"
    )
    assert _ids(to) == _ids(db)


def test_an_error_after_the_last_feedback_committed_says_it_is_stored(
    small_cases: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The same error where ``classify --feedback`` writes the matrices after the last clip's
    feedback committed: the line says every clip's feedback is stored, as it says between
    two clips, and the history holds its entries (before: the lost connection alone)."""
    import cbr.classification
    from posecbr.cli import main

    db = Path(shutil.copy(small_cases, tmp_path / "cb.sqlite"))
    clip = sorted((small_cases.parent / "train").rglob("*.npz"))[0]
    monkeypatch.setattr(cbr.classification, "write_matrices", _connection_lost)
    capsys.readouterr()
    argv = ["classify", str(clip), "--db", str(db), "--feedback", clip.parent.name]
    assert main(argv) == 1
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"posecbr classify: error: {db}: the connection to the database server was lost "
        "(consuming input failed: server closed the connection unexpectedly); before it, the "
        "feedback of every clip (1) is stored in the case base"
    )
    with contextlib.closing(sqlite3.connect(db)) as con:
        actions = [a for (a,) in con.execute("SELECT action FROM maintenance_log ORDER BY id")]
    assert actions[0] == "build" and actions[1:] and set(actions[1:]) <= {"retain", "revise"}


def test_a_postgres_connection_ended_after_an_append_commits_says_the_cases_are_stored(
    small_cases: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    """A real disconnect: on a PostgreSQL copy of the case base, every other session on the
    server is ended (``pg_terminate_backend``) right after the append committed, before the
    cases are counted: the line says the connection was lost and that the case was added
    (before: the first part alone, and run again the append was refused as held already);
    the case is there, once."""
    from sqlalchemy import create_engine, text

    import cbr.training
    from features.poses import save_pose
    from features.text import shown
    from posecbr.cli import main
    from tests.moves import clip
    from tests.postgres import postgres_copy_of

    url = postgres_copy_of(small_cases)
    real = cbr.training.write_matrices

    def ended(store: Any, name: str, *args: Any, **kwargs: Any) -> bool:
        engine = create_engine(url)
        try:
            with engine.connect() as con:
                con.execute(text(
                    "SELECT pg_terminate_backend(pid) FROM pg_stat_activity"
                    " WHERE pid <> pg_backend_pid() AND datname = current_database()"
                ))  # fmt: skip
        finally:
            engine.dispose()
        return bool(real(store, name, *args, **kwargs))

    monkeypatch.setattr(cbr.training, "write_matrices", ended)
    save_pose(clip("squat", 2.0, 30.0), tmp_path / "add" / "Squat" / "s.npz")
    capsys.readouterr()
    assert main(["train", str(tmp_path / "add"), "--db", url, "--append"]) == 1
    err = capsys.readouterr().err
    assert err.startswith(
        f"posecbr train: error: {shown(url)}: the connection to the database server was lost ("
    )
    assert err.endswith(
        "; the 1 case was added to 'default' before it: run again, the append is refused as"
        " held already (casebase info shows them)\n"
    )
    engine = create_engine(url)
    try:
        with engine.connect() as con:
            sources = con.execute(text("SELECT source FROM cases ORDER BY id")).scalars().all()
    finally:
        engine.dispose()
    assert len(sources) == 10 and sources[-1] == str(tmp_path / "add" / "Squat" / "s.npz")
