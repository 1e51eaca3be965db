"""Case base stores under several processes at once (hunt 50g): real SQLite files, real
processes where the point is a process."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from casebase_store import (
    CaseStore,
    NewCase,
    StoreError,
    StoreTransaction,
    open_store,
    write_store,
)
from cbr.classification import classify_with_feedback
from cbr.similarity import get_measure
from cbr.stored import load_classifier
from cbr.training import append, append_described, append_plan, describe
from features.poses import PoseSequence, load_pose
from posecbr.cli import main
from tests.badinput import read_only_mounts_work, small_case_base

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
#: the first bytes of a SQLite rollback journal that holds a transaction
JOURNAL_MAGIC = bytes.fromhex("d9d505f920a163d7")


def _without_first_frame(clip: Path) -> PoseSequence:
    """Another take of ``clip``: its poses from the second frame on (another case)."""
    seq = load_pose(str(clip))
    return seq.slice_frames(1, None)


def _one_case(tx: StoreTransaction) -> None:
    """A case base "cb" of one case of 4,000 features (32 kB)."""
    cb = tx.create_case_base("cb", {"level": "fluents"}, ["f"], ["f"], {"name": "euclidean"})
    tx.add_cases(cb, [NewCase("walk", np.zeros(4000))])


def test_a_case_relabelled_by_another_process_is_not_moved_toward_a_clip_of_its_old_label(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: a feedback run that read the case base before another run relabelled case c
    # moved c, now of the other activity, a quarter of the way toward its clip of c's old
    # activity ("moved: nearest case has the true label"), as it had decided on c's old label
    db = small_case_base(tmp_path)
    clip = sorted((tmp_path / "train").rglob("*.npz"))[0]
    old, new = clip.parent.name, "relabelled"
    take = _without_first_frame(clip)
    store = open_store(db)
    try:
        stale = load_classifier(store, "default")  # read before the other run's change
        nearest = stale.classifier.solve([take])[0].retrieval
        case = int(nearest.case_ids[0])
        assert nearest.labels[0] == old  # so its feedback as `old` would move that case
        # the other run: the case's own clip is `new` (it lies at 0 from it: relabelled)
        argv = ["classify", str(clip), "--feedback", new, "--new-label", "--quiet"]
        assert main([*argv, "--db", str(db)]) == 0
        capsys.readouterr()
        relabelled = store.load_cases("default", ids=[case])
        assert relabelled.labels.tolist() == [new]
        (done,) = classify_with_feedback(store, stale, [take], old)
        after = store.load_cases("default", ids=[case])
        # a relabel moves no problem, and nothing else moved the case toward `take`
        assert np.array_equal(after.features, relabelled.features)
        rev = done.revision
        if rev is not None and rev.action == "moved":  # decided again on the case base now
            moved = store.load_cases("default", ids=[rev.case_id])
            assert moved.labels.tolist() == [old]
        log = [e for e in store.maintenance_log("default") if e.case_id == case]
        assert [e.reason.split(":")[0] for e in log] == ["relabelled"]
    finally:
        store.close()


def test_an_activity_another_append_added_meanwhile_is_not_said_to_be_new(
    tmp_path: Path,
) -> None:
    # before: two `train --append` at once of clips of one new activity both said "note: 1
    # activity the case base did not hold, added as new: ...": the second was told so of
    # the case base as it read it, though the first had added that activity before its cases
    db = small_case_base(tmp_path)
    clips = sorted((tmp_path / "train").rglob("*.npz"))
    plan, uid, _, _ = append_plan(db, "default")  # the second append reads the case base
    late = [describe(_without_first_frame(clips[0]), plan)]
    first = append(db, "default", [_without_first_frame(clips[1])], ["hop"])
    assert first.new_labels == ["hop"]
    second = append_described(db, "default", late, ["hop"], plan, uid)
    assert second.new_labels == []
    with open_store(db, readonly=True) as store:
        assert store.get_case_base("default").label_counts["hop"] == 2


#: another process inside its write transaction after SQLite wrote changed pages into the
#: database file (a small page cache spills them), waiting there until the file sys.argv[2]
#: exists: a writer still writing, whose journal holds what would undo its change, as a
#: killed writer's does. It trims every case but the first.
LIVE_WRITER = """
import os, sqlite3, sys, time
con = sqlite3.connect(sys.argv[1], isolation_level=None)
con.execute("PRAGMA cache_size = 2")
con.execute("BEGIN IMMEDIATE")
con.execute("UPDATE cases SET active = 0 WHERE id > (SELECT min(id) FROM cases)")
print("WRITING", flush=True)
while not os.path.exists(sys.argv[2]):
    time.sleep(0.01)
con.execute("COMMIT")
"""

#: what reads the case base in a private read-only mount of the folder sys.argv[1] (not even
#: root can write there), once the file sys.argv[3] exists: its active cases, or the error
READER = """
import os, sys, time
from casebase_store import StoreError, open_store
print("READY", flush=True)
while not os.path.exists(sys.argv[3]):
    time.sleep(0.01)
try:
    with open_store(sys.argv[2], readonly=True) as store:
        print(store.count_cases("default"))
except StoreError as exc:
    print(exc)
"""


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)
def test_a_reader_in_a_read_only_folder_waits_for_a_writer_still_writing(tmp_path: Path) -> None:
    # before: a reader that could not write the folder (another user's, a read-only mount)
    # opened the file "immutable", with no locks: a writer allowed to write there, caught in
    # its transaction, was said to be killed ("its last change was interrupted (the process
    # writing it was killed) ...: copy both files to a folder that can be written"), and a
    # commit while it read was read half-made
    folder = tmp_path / "shared"
    folder.mkdir()
    db = small_case_base(folder)
    with open_store(db, readonly=True) as store:
        n = store.count_cases("default")
    go, commit = tmp_path / "go", tmp_path / "commit"
    writer = subprocess.Popen(
        [sys.executable, "-c", LIVE_WRITER, str(db), str(commit)],
        env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    mount = f"mount --bind {folder} {folder} && mount -o remount,ro,bind {folder} {folder}"
    reader = subprocess.Popen(
        ["unshare", "-rm", "sh", "-c", f'{mount} && exec "$0" "$@"', sys.executable, "-c",
         READER, str(folder), str(db), str(go)],
        env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert writer.stdout is not None and writer.stdout.readline().strip() == "WRITING"
        # changed pages in the file, what undoes them in its journal (SQLite's header)
        assert db.with_name("cb.sqlite-journal").read_bytes()[:8] == JOURNAL_MAGIC
        assert reader.stdout is not None and reader.stdout.readline().strip() == "READY"
        go.touch()  # the reader opens the file while the writer is in its transaction
        time.sleep(0.3)
        commit.touch()
        out, err = reader.communicate(timeout=60)
        assert writer.wait(timeout=60) == 0, writer.stderr.read() if writer.stderr else ""
    finally:
        for p in (writer, reader):
            if p.poll() is None:
                p.kill()
                p.wait()
    assert reader.returncode == 0, err
    assert out.strip() == "1"  # the writer's change, committed: one of the n cases left
    assert n > 1


#: in a private tmpfs of 256 kB mounted on the folder sys.argv[1]: a case base file, then an
#: append of 3.2 MB of cases; what the store says, whether the file is as it was, the folder
FULL_DISK = """
import sys
from pathlib import Path
import numpy as np
from casebase_store import (
    CaseStore,
    NewCase,
    StoreError,
    StoreTransaction,
    open_store,
    write_store,
)
db = Path(sys.argv[1]) / "cb.sqlite"
def one_case(tx):  # as _one_case
    cb = tx.create_case_base("cb", {"level": "fluents"}, ["f"], ["f"], {"name": "euclidean"})
    tx.add_cases(cb, [NewCase("walk", np.zeros(4000))])
write_store(db, one_case)
before = db.read_bytes()
try:
    with open_store(db) as store:
        store.add_cases("cb", [NewCase("walk", np.zeros(4000)) for _ in range(100)])
except StoreError as exc:
    print(exc)
print(db.read_bytes() == before)
print(sorted(p.name for p in db.parent.iterdir()))
"""


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private mount (unshare -rm, mount)",
)
def test_a_full_disk_is_said_so_and_the_file_is_left_as_it_was(tmp_path: Path) -> None:
    # before: "database error: database or disk is full", as any error SQLite gives, and the
    # file changed, its journal beside it (as past a file size limit, the test above)
    folder = tmp_path / "small"
    folder.mkdir()
    mount = f'mount -t tmpfs -o size=256k tmpfs {folder} || exit 99; exec "$0" "$@"'
    done = subprocess.run(
        ["unshare", "-rm", "sh", "-c", mount, sys.executable, "-c", FULL_DISK, str(folder)],
        env=ENV, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    if done.returncode == 99:
        pytest.skip("no tmpfs can be mounted here")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        f"{folder / 'cb.sqlite'}: cannot write the database file: the disk is full (no room for"
        " the file or the journal SQLite writes beside it): free some space and run again",
        "True",
        "['cb.sqlite']",
    ]


def test_a_write_past_a_file_size_limit_leaves_the_file_as_it_was_for_readers(
    tmp_path: Path, file_size_limit: Callable[[int], None]
) -> None:
    # before: a write that failed partway, once changed pages had spilled into the file, left
    # the file changed and its journal beside it: every command that only reads then said
    # "its last change was interrupted (the process writing it was killed) ... undo it with
    # `posecbr casebase upgrade --db FILE`", of a writer that had said its error and ended
    db = tmp_path / "cb.sqlite"
    write_store(db, _one_case)
    before = db.read_bytes()
    file_size_limit(200_000)  # the appended cases (3.2 MB) spill past the store's page cache
    with pytest.raises(StoreError, match="ulimit -f"), open_store(db) as store:
        store.add_cases("cb", [NewCase("walk", np.zeros(4000)) for _ in range(100)])
    assert db.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cb.sqlite"]
    with open_store(db, readonly=True) as store:
        assert store.count_cases("cb") == 1


def test_a_case_revised_between_reading_the_cases_and_their_representations_is_read_again(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # before: a command read the cases, then, in a read of its own, their cached DTW
    # envelopes: a case revised in between, its new envelopes cached by a third run (a
    # feedback run reloading), was retrieved with its old problem and its new envelopes (the
    # lower bound of another problem, which can prune the nearest case)
    small = small_case_base(tmp_path / "small")
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(small.parent / "train"), "--db", str(db), "--similarity", "dtw",
            "--mirror", "off"]  # fmt: skip
    assert main(argv) == 0
    load = CaseStore.load_representations
    began: list[bool] = []

    def meanwhile(self: CaseStore, name: str, kind: str, **kw: Any) -> dict[int, np.ndarray]:
        if not began:  # between this run's two reads: another run revises case c (as
            began.append(True)  # feedback does), a third caches c's new envelopes
            with open_store(db) as writer:
                info, cases = writer.load_case_base(name)
                moved = cases.features[0] + 0.25 * (cases.features[1] - cases.features[0])
                with writer.transaction() as tx:
                    tx.update_case(tx.case_base(name), int(cases.ids[0]), features=moved)
                reps = get_measure(info.similarity).represent(moved[None])
                with writer.transaction() as tx:
                    tx.put_representations(kind, {int(cases.ids[0]): reps[0]})
        return load(self, name, kind, **kw)

    monkeypatch.setattr(CaseStore, "load_representations", meanwhile)
    with open_store(db, readonly=True) as store:
        cb = load_classifier(store, "default").classifier.case_base_
    assert began and cb.reps is not None
    np.testing.assert_array_equal(cb.reps, cb.measure.represent(cb.problems))
    assert cb.origins[0] == "revised"  # read again, after the revision
