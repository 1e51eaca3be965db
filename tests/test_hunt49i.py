"""Hunt 49i: follow-ups of the poses digest (``cases.poses``, hunt 49d) and ``casebase upgrade``.

(1) A case retained by ``classify --feedback`` stored no poses digest, so ``train --append``
    compared it by its features alone: another take described alike (two subjects' UI-PRMD
    scaptions of 69 frames, the same binary QMP vector) was refused as a copy of the retained
    clip. And a clip whose case is stored already (trained, or retained before) was retained
    again when the thresholds let it, or always as a new activity's first case, the same poses
    stored twice, voting twice (or for two labels at distance 0).
(2) ``casebase upgrade`` of a read-only file of the current schema version lacking an index or
    a column answered "already schema version 2, nothing to do" (exit 0), as if it had none
    to add.

Real UI-PRMD takes, real SQLite files, the command in process (a read-only mount in a child).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import shutil
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from tests.badinput import posecbr_on_read_only_mount, read_only_mounts_work
from tests.test_hunt49d import _run, assert_refused_by_poses, write_takes

#: two takes of a standing shoulder scaption, 69 frames each (s01 incorrect, s02 correct),
#: whose binary QMP vectors are the same; a shoulder abduction and a deep squat to train on
_KINECT = {
    "feedback/scaption/a.npz": "Incorrect Segmented Movements/Kinect/Positions/m10_s01_e08",
    "other/scaption/c.npz": "Segmented Movements/Kinect/Positions/m10_s02_e04",
    "train/abduction/b.npz": "Segmented Movements/Kinect/Positions/m07_s01_e01",
    "train/squat/e.npz": "Segmented Movements/Kinect/Positions/m01_s01_e01",
}


# on one xdist worker: the module's takes, qmp_cb made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt49i")


@pytest.fixture(scope="module")
def takes(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The real UI-PRMD Kinect takes of :data:`_KINECT` as pose files."""
    return write_takes(shared_data, tmp_path_factory.mktemp("takes"), _KINECT)


@pytest.fixture(scope="module")
def qmp_cb(takes: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A QMP case base of ``b.npz`` (abduction) and ``e.npz`` (squat), trained by the command
    once; tests copy it."""
    db = tmp_path_factory.mktemp("qmp") / "cb.sqlite"
    argv = ["train", str(takes / "train"), "--db", str(db), "--features", "qmp"]
    code, said = _run([*argv, "--mirror", "off", "-k", "1", "--feature-weights", "none"])
    assert code == 0, said
    return db


def _cases(db: Path) -> list[tuple[int, str, str, str, str | None]]:
    with contextlib.closing(sqlite3.connect(db)) as con:
        return con.execute(
            "SELECT id, label, source, origin, poses FROM cases ORDER BY id"
        ).fetchall()


def _digest(file: Path) -> str:
    """The SHA-256 of a pose file's poses as ``cbr.described.poses_digest`` documents it,
    worked out here from the file's arrays: its joint names and frame rate as JSON, then its
    positions and confidences as float64 bytes."""
    with np.load(file, allow_pickle=False) as z:
        head = json.dumps([[str(j) for j in z["joint_names"]], float(z["fps"])])
        out = hashlib.sha256(head.encode())
        out.update(np.ascontiguousarray(z["positions"], dtype=np.float64).tobytes())
        if "confidence" in z.files:
            out.update(np.ascontiguousarray(z["confidence"], dtype=np.float64).tobytes())
    return out.hexdigest()


def test_a_retained_case_keeps_its_poses_digest_and_train_append_tells_its_copy_by_it(
    takes: Path, qmp_cb: Path, tmp_path: Path
) -> None:
    """``a.npz`` retained by feedback as the first scaption keeps the SHA-256 of its poses;
    then s02's scaption take ``c.npz`` (the same 69 frames and binary QMP vector, other
    poses) is added by ``train --append`` (before: refused as a copy of the retained case,
    "the same frames and features under another file name"), and a byte copy of ``a.npz``
    under another name is refused, told by its poses."""
    db = Path(shutil.copy(qmp_cb, tmp_path / "cb.sqlite"))
    a = takes / "feedback" / "scaption" / "a.npz"
    code, said = _run(["classify", str(a), "--db", str(db), "--feedback", "scaption",
                       "--new-label"])  # fmt: skip
    assert code == 0, said
    assert "feedback: retained: first case of 'scaption'" in said
    assert _cases(db)[-1] == (3, "scaption", str(a), "retained", _digest(a))
    code, said = _run(["train", str(takes / "other"), "--db", str(db), "--append"])
    assert code == 0, said
    c = takes / "other" / "scaption" / "c.npz"
    assert [r[2] for r in _cases(db)][2:] == [str(a), str(c)]
    assert_refused_by_poses(takes, db, tmp_path, "feedback/scaption/a.npz", case=3)


def test_feedback_on_a_clip_whose_case_is_stored_retains_no_second_case(
    takes: Path, qmp_cb: Path, tmp_path: Path
) -> None:
    """``e.npz``, stored as the squat case, given as a new activity's first clip: its case is
    relabelled (the clip lies at 0 from it), no second case of the same poses is retained
    (before: case 3 'lunge' beside case 2 'squat', both ``e.npz``, tied at 0). ``b.npz``,
    stored as the abduction case, with every clip let through (novelty and benefit
    thresholds 0): not retained again (before: retained, case 3 a second ``b.npz``)."""
    db = Path(shutil.copy(qmp_cb, tmp_path / "cb.sqlite"))
    b, e = takes / "train" / "abduction" / "b.npz", takes / "train" / "squat" / "e.npz"
    code, said = _run(["classify", str(e), "--db", str(db), "--feedback", "lunge",
                       "--new-label"])  # fmt: skip
    assert code == 0, said
    assert "feedback: not retained: the same frames and poses as case #2, stored already" in said
    assert "revised case #2 (relabelled)" in said
    assert [r[:4] for r in _cases(db)] == [
        (1, "abduction", str(b), "trained"),
        (2, "lunge", str(e), "revised"),
    ]
    code, said = _run(["classify", str(b), "--db", str(db), "--feedback", "abduction",
                       "--novelty", "0", "--benefit", "0"])  # fmt: skip
    assert code == 0, said
    assert "feedback: not retained: the same frames and poses as case #1, stored already" in said
    assert [r[0] for r in _cases(db)] == [1, 2]


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)
def test_upgrade_of_a_read_only_current_store_lacking_an_index_and_a_column_says_so(
    tmp_path: Path,
) -> None:
    """A store of the current schema version made before the index on the cases' sources and
    their poses column, the file read-only (a private read-only mount, which not even root
    can write to): refused naming what the upgrade would add and why it cannot, exit 1,
    nothing written (before: "already schema version 2, nothing to do", exit 0)."""
    from casebase_store import open_store

    db = tmp_path / "cb.sqlite"
    open_store(db, create=True).close()
    with contextlib.closing(sqlite3.connect(db)) as con, con:
        con.execute("ALTER TABLE cases DROP COLUMN poses")
        con.execute("DROP INDEX ix_cases_case_base_id_source")
    before = db.read_bytes()
    done = posecbr_on_read_only_mount(db, ["casebase", "upgrade", "--db", str(db)], db)
    assert (done.returncode, done.stdout) == (1, ""), done.stderr
    assert done.stderr.splitlines() == [
        f"posecbr casebase upgrade: error: {db}: would add the index "
        "ix_cases_case_base_id_source and the column cases.poses of a newer schema, but "
        "cannot write the case base file: it is read-only"
    ]
    assert db.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["cb.sqlite"]
