"""Case base store faults found by hunting: a writer racing another, a killed first train, a
read-only folder; real processes on real SQLite files."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import textwrap
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from cbr.similarity import get_measure
from features.poses import load_pose, save_pose
from posecbr.cli import main
from tests.badinput import (
    posecbr_on_read_only_mount,
    read_only_mounts_work,
    refused,
    small_case_base,
)
from tests.processes import posecbr_process

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small trained case base (three activities, three clips each), copied per test."""
    return small_case_base(tmp_path_factory.mktemp("small"))


def _copy(src: Path, dst: Path) -> Path:
    dst.write_bytes(src.read_bytes())
    return dst


#: ``posecbr ARGV`` that prints PAUSED once trim has read and edited the case base, and waits
#: (outside any transaction) until the file ``argv[1]`` exists before it writes
GATED_TRIM = """
import os, sys, time
import cbr.stored as stored
recalibrated = stored.recalibrated
def gated(*a, **kw):
    out = recalibrated(*a, **kw)
    print("PAUSED", flush=True)
    while not os.path.exists(sys.argv[1]):
        time.sleep(0.01)
    return out
stored.recalibrated = gated
from posecbr.cli import main
sys.exit(main(sys.argv[2:]))
"""


def test_trim_of_a_case_base_changed_since_it_was_read_writes_nothing(
    small: Path, tmp_path: Path
) -> None:
    """A clip retained while trim edits the case base: the trim, decided on the cases as they
    were (and its unknown judges calibrated on them), is refused with one line, not committed
    over the new case."""
    db = _copy(small, tmp_path / "cb.sqlite")
    gate = tmp_path / "go"
    trim = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(GATED_TRIM), str(gate),
         "casebase", "trim", "--db", str(db), "-k", "1", "--keep", "0.5"],
        cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert trim.stdout is not None
    assert trim.stdout.readline().strip() == "PAUSED"
    clip = small.parent / "train" / "右腕 raise" / "clip01.npz"
    # retained by another writer (in this process) while the trim waits
    assert main(["classify", str(clip), "--db", str(db), "--feedback", "右腕 raise",
                 "--novelty", "0", "--benefit", "0"]) == 0  # fmt: skip
    before = _sha(db)
    gate.touch()
    out, err = trim.communicate(timeout=120)
    assert trim.returncode == 1, (out, err)
    assert err.splitlines() == [
        f"posecbr casebase trim: error: {db}: case base 'default' was changed by another "
        "process since it was read (version 1, now 2); nothing was written (run the command "
        "again)"
    ]
    assert out == ""
    assert _sha(db) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cb.sqlite", "go"]


def test_a_killed_first_train_leaves_a_temporary_the_next_train_removes(
    small: Path, tmp_path: Path
) -> None:
    """A first ``train`` builds its case base file under a hidden temporary name: killed in
    its transaction it leaves only that temporary (and its journal), and the next train into
    the same file removes them, so killed runs never pile up copies of a case base."""
    folder = tmp_path / "out"
    folder.mkdir()
    db = folder / "cb.sqlite"
    argv = ["train", str(small.parent / "train"), "--db", str(db), "--mirror", "off",
            "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    killed = posecbr_process(*argv, pause_after="build")
    assert killed.stdout is not None and killed.stdout.readline().strip() == "PAUSED"
    killed.send_signal(signal.SIGKILL)
    killed.wait(timeout=30)
    left = sorted(p.name for p in folder.iterdir())
    assert len(left) == 2 and left[0].startswith(".cb.sqlite.") and left[1] == left[0] + "-journal"
    assert main(argv) == 0
    assert sorted(p.name for p in folder.iterdir()) == ["cb.sqlite"]


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)
def test_a_first_train_into_a_read_only_folder_names_the_file_asked_for(
    small: Path, tmp_path: Path
) -> None:
    """The case base file cannot be created: the one line names it, not the hidden temporary
    it would have been built under."""
    folder = tmp_path / "ro"
    folder.mkdir()
    db = folder / "cb.sqlite"
    argv = ["train", str(small.parent / "train"), "--db", str(db), "--mirror", "off",
            "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    done = posecbr_on_read_only_mount(folder, argv)
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"posecbr train: error: {db}: cannot write the case base file: the folder {folder} is "
        "read-only"
    ]  # refused before the training, naming the file asked for
    assert list(folder.iterdir()) == []


#: ``posecbr ARGV`` that prints PAUSED once it has read the case base's cached representations
#: (before it caches those it computed) and waits until the file ``argv[1]`` exists
GATED_CACHE = """
import os, sys, time
from casebase_store import store
load = store.CaseStore.load_representations
def gated(self, *a, **kw):
    out = load(self, *a, **kw)
    print("PAUSED", flush=True)
    while not os.path.exists(sys.argv[1]):
        time.sleep(0.01)
    return out
store.CaseStore.load_representations = gated
from posecbr.cli import main
sys.exit(main(sys.argv[2:]))
"""


def test_a_case_revised_while_another_process_caches_representations_keeps_its_own(
    small: Path, tmp_path: Path
) -> None:
    """DTW retrieval compares with the cached representations. A writer that read a revised
    case (its representation dropped) computes one from the problem it read; a revision
    committed meanwhile must not be hidden behind that old representation."""
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(small.parent / "train"), "--db", str(db), "--similarity", "dtw",
                 "--mirror", "off"]) == 0  # fmt: skip
    seq = load_pose(small.parent / "train" / "右腕 raise" / "clip01.npz")
    noise = np.random.default_rng(0).normal(scale=0.02, size=seq.positions.shape)
    clip = save_pose(replace(seq, positions=seq.positions + noise, source=""), tmp_path / "q.npz")
    revise = [
        "classify",
        str(clip),
        "--db",
        str(db),
        "--feedback",
        "右腕 raise",
        "--novelty",
        "1e9",
    ]  # fmt: skip  (never retained: the nearest case is revised)
    assert main(revise) == 0  # its representation is dropped
    gate = tmp_path / "go"
    reader = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(GATED_CACHE), str(gate),
         "casebase", "trim", "--db", str(db), "-k", "1"],
        cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert reader.stdout is not None and reader.stdout.readline().strip() == "PAUSED"
    assert main(revise) == 0  # the same case, revised again (by another writer than the reader)
    gate.touch()
    reader.communicate(timeout=120)
    store = open_store(db, readonly=True)
    info, cases = store.load_case_base("default")
    measure = get_measure(info.similarity)
    kind = measure.cache_kind(tuple(cases.features.shape[1:]))
    assert kind is not None
    cached = store.load_representations("default", kind)
    store.close()
    revised = [i for i, o in enumerate(cases.origins) if o == "revised"]
    assert len(revised) == 1
    for i, case_id in enumerate(cases.ids.tolist()):
        if case_id in cached:
            want = measure.represent(cases.features[i : i + 1])[0]
            np.testing.assert_array_equal(cached[case_id], want, err_msg=f"case {case_id}")


@pytest.mark.parametrize(
    ("damage", "said"),
    [
        ("DROP TABLE cases", "not a whole posecbr case base store: a table is missing"),
        (
            "UPDATE case_bases SET name = CAST(X'66ff6f' AS TEXT)",
            "a text column holds bytes that are not UTF-8",
        ),
    ],
)
def test_a_store_missing_a_table_or_holding_broken_text_is_named_so(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], damage: str, said: str
) -> None:
    """Another program dropped a table, or damaged pages left a name that is not UTF-8: one
    line saying what is wrong with the file (it was SQLite's raw "no such table: cases" or
    "Could not decode to UTF-8 column"), exit 1, the file unchanged."""
    import sqlite3

    db = tmp_path / "damaged.sqlite"
    _copy(small, db)
    con = sqlite3.connect(db)
    con.execute(damage)
    con.commit()
    con.close()
    for argv in (["casebase", "info"], ["casebase", "list"]):
        refused([*argv, "--db", str(db)], tmp_path, capsys, str(db), said)
