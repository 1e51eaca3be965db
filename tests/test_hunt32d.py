"""Case base store faults found by hunt 32d (several commands on one case base): real SQLite
files, real processes where the point is a process."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from casebase_store import NewCase, open_store, write_store
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


#: a writer killed (SIGKILL) inside its transaction after SQLite wrote changed pages into the
#: database file (a small page cache spills them): what undoes them is the journal beside it.
#: It trims every case (named by id: the ids up to a million, 2,000 statements, took 3 s of
#: CPU) and adds a hundred.
KILLED_WRITER = """
import os, sys
import numpy as np
from sqlalchemy import text
from casebase_store import NewCase, open_store
store = open_store(sys.argv[1], create=False)
every = store.load_cases("default").ids.tolist()
with store.transaction() as tx:
    tx.session.execute(text("PRAGMA cache_size = 2"))
    info = tx.case_base("default")
    assert tx.deactivate_cases(info, every) == len(every) > 0
    tx.add_cases(info, [NewCase("zzz", np.zeros(2000)) for _ in range(100)])
    tx.session.flush()
    os.kill(os.getpid(), 9)
"""


def _killed_mid_write(db: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-c", KILLED_WRITER, str(db)], env=ENV, capture_output=True, timeout=120
    )
    assert done.returncode == -9, done.stderr
    journal = db.with_name(db.name + "-journal")
    # a journal that holds a transaction: SQLite's header (it zeroes or deletes it at commit)
    assert journal.read_bytes()[:8] == bytes.fromhex("d9d505f920a163d7")


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("small"))


def _listed(db: Path, capsys: pytest.CaptureFixture[str]) -> object:
    capsys.readouterr()
    assert main(["casebase", "list", "--all", "--json", "--db", str(db)]) == 0
    return json.loads(capsys.readouterr().out)["cases"]


def test_after_a_writer_was_killed_a_reader_says_so_and_upgrade_rolls_it_back(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: every command, reading or writing, said "cannot open or write the database
    # (attempt to write a readonly database)" (each opens the file read-only first, and a
    # read-only connection cannot undo the killed transaction), `casebase upgrade` undid it
    # saying "already schema version 2, nothing to do"
    db = tmp_path / "cb.sqlite"
    shutil.copy(small, db)
    before = _listed(db, capsys)
    assert len(before) == 9  # three activities, three clips each
    _killed_mid_write(db)
    for argv in (["casebase", "info"], ["casebase", "list"], ["casebase", "trim", "--dry-run"]):
        refused(
            [*argv, "--db", str(db)], tmp_path, capsys,
            f"{db}: its last change was interrupted", f"{db}-journal holds what to undo",
            "posecbr casebase upgrade --db FILE",
        )  # fmt: skip
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert "rolled back the change a killed process left half-made" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cb.sqlite"]
    assert _listed(db, capsys) == before
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0  # nothing more to undo
    assert capsys.readouterr().out.strip().endswith("nothing to do")


@pytest.mark.parametrize("command", ["trim", "feedback", "append"])
def test_a_writer_after_a_killed_one_undoes_its_change_first(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    clip = sorted((small.parent / "train").rglob("*.npz"))[0]
    # a clip not in the case base: one of its clips, the nose 5 cm further right
    seq = load_pose(clip)
    moved = seq.positions.copy()
    moved[:, 0, 0] += 0.05
    save_pose(
        dataclasses.replace(seq, positions=moved), tmp_path / "more" / clip.parent.name / "new.npz"
    )
    argv = {
        "trim": ["casebase", "trim", "-k", "1", "--keep", "0.5"],
        "feedback": ["classify", str(clip), "--feedback", clip.parent.name, "--quiet"],
        "append": ["train", str(tmp_path / "more"), "--append"],
    }[command]
    pristine, killed = tmp_path / "pristine.sqlite", tmp_path / "killed.sqlite"
    shutil.copy(small, pristine)
    shutil.copy(small, killed)
    _killed_mid_write(killed)
    assert main([*argv, "--db", str(pristine)]) == 0
    assert main([*argv, "--db", str(killed)]) == 0, capsys.readouterr().err
    assert not killed.with_name("killed.sqlite-journal").exists()
    # the same change, made to the case base as it was before the killed write
    mine, theirs = _listed(killed, capsys), _listed(pristine, capsys)
    assert [{**c, "source": ""} for c in mine] == [{**c, "source": ""} for c in theirs]  # type: ignore[union-attr]
    assert len(mine) == {"trim": 9, "feedback": 9, "append": 10}[command]  # type: ignore[arg-type]


def test_through_a_symbolic_link_the_journal_beside_the_file_it_names_is_found(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # SQLite keeps the journal beside the file the link leads to: looked for beside the link,
    # a writer did not find it and failed as a reader does
    (tmp_path / "real").mkdir()
    (tmp_path / "via").mkdir()
    db = tmp_path / "real" / "cb.sqlite"
    shutil.copy(small, db)
    before = _listed(db, capsys)
    link = tmp_path / "via" / "cb.sqlite"
    link.symlink_to(db)
    _killed_mid_write(db)
    refused(
        ["casebase", "info", "--db", str(link)], tmp_path, capsys,
        f"{link}: its last change was interrupted", f"{db}-journal holds what to undo",
    )  # fmt: skip
    assert main(["casebase", "trim", "--dry-run", "--db", str(link)]) == 1
    # a clip no case is made of (a stored clip's own case would be relabelled, none added):
    # the first stored one without its first frame
    with np.load(sorted((small.parent / "train").rglob("*.npz"))[0]) as z:
        arrays = {k: z[k][1:] if k in ("positions", "confidence") else z[k] for k in z.files}
    clip = tmp_path / "new.npz"
    np.savez(clip, **arrays)
    assert main(["classify", str(clip), "--feedback", "x", "--new-label", "--quiet", "--db",
                 str(link)]) == 0  # fmt: skip
    assert not db.with_name("cb.sqlite-journal").exists()
    after = _listed(db, capsys)
    assert after[:-1] == before and after[-1]["label"] == "x"  # type: ignore[index]


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)
def test_a_killed_writers_journal_in_a_read_only_folder_is_refused_not_ignored(
    small: Path, tmp_path: Path
) -> None:
    # before: a read-only folder's file is opened "immutable", which ignores the journal:
    # the half-written file was read ("not a readable SQLite database (corrupt or not a
    # database)" here; a smaller change would have been read as if committed)
    folder = tmp_path / "ro"
    folder.mkdir()
    db = folder / "cb.sqlite"
    shutil.copy(small, db)
    _killed_mid_write(db)
    done = posecbr_on_read_only_mount(folder, ["casebase", "info", "--db", str(db)])
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"posecbr casebase info: error: {db}: its last change was interrupted (the process "
        f"writing it was killed): {db}-journal holds what to undo; its folder cannot be "
        "written, so it cannot be rolled back here: copy both files to a folder that can be "
        "written and run `posecbr casebase upgrade --db FILE` there"
    ]


def test_ctrl_c_during_feedback_says_whose_feedback_is_stored(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "posecbr classify: interrupted" alone, with the first clips' feedback stored:
    # run again on the same clips, they were learnt from twice
    db = tmp_path / "cb.sqlite"
    shutil.copy(small, db)
    clips = sorted((small.parent / "train").rglob("*.npz"))[:3]
    gate = tmp_path / "never"  # never made: the process waits after the first clip's commit
    proc = posecbr_process(
        "classify", *map(str, clips), "--feedback", clips[0].parent.name, "--quiet",
        "--db", str(db), gate=gate,
    )  # fmt: skip
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.splitlines() == [
        "posecbr classify: interrupted: the feedback of 1 of the 3 clips is stored in the case "
        f"base (the last: {clips[0].name}); the others' is not"
    ]
    with open_store(db, readonly=True) as store:
        learnt = [e for e in store.maintenance_log("default") if e.action != "build"]
    assert len([e for e in learnt if e.action == "retain"]) == 1  # one clip's decision


@pytest.mark.parametrize("url", ["sqlite://", "sqlite:///:memory:"])
def test_an_in_memory_sqlite_url_is_refused_before_any_work(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], url: str
) -> None:
    # before: train read and fitted every clip, stored the case base in a database that
    # vanished as the command ended, then failed "no case base store here (empty database)"
    data = tmp_path / "data"
    shutil.copytree(small.parent / "train", data)
    for argv in (["train", str(data)], ["casebase", "info"], ["casebase", "upgrade"]):
        refused(
            [*argv, "--db", url], tmp_path, capsys,
            f"{url}: an in-memory SQLite database keeps nothing once the command ends: name "
            "a case base file",
        )  # fmt: skip


def test_a_case_base_name_no_store_can_hold_is_refused_before_training(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # before: every clip was read and the classifier fitted (minutes on a real dataset), then
    # the write refused "DB: case base name is 201 characters long (at most 200)"
    import cbr.training
    from features.errors import DataError

    def no_work(*args: object, **kwargs: object) -> None:
        raise DataError("clips were read")

    monkeypatch.setattr(cbr.training, "describe_entries", no_work)
    data = tmp_path / "data"
    shutil.copytree(small.parent / "train", data)
    refused(
        ["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--name", "n" * 201],
        tmp_path, capsys, "--name: case base name is 201 characters long (at most 200)",
    )  # fmt: skip
    assert main(["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--name", "é" * 200,
                 "--mirror", "off", "--feature-weights", "none", "--phases", "0"]) == 1  # fmt: skip
    assert "clips were read" in capsys.readouterr().err  # 200 characters pass the check


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)
@pytest.mark.parametrize("command", ["trim", "feedback", "append"])
def test_a_writer_in_a_read_only_folder_is_refused_before_its_work(
    small: Path, tmp_path: Path, command: str
) -> None:
    # before: trim edited the case base and classify classified the clip (train --append read
    # and described its clips) before the write failed "cannot open or write the database
    # (attempt to write a readonly database)"; train of a new file was already refused so
    folder = tmp_path / "ro"
    folder.mkdir()
    db = folder / "cb.sqlite"
    shutil.copy(small, db)
    clip = sorted((small.parent / "train").rglob("*.npz"))[0]
    argv = {
        "trim": ["casebase", "trim", "-k", "1"],
        "feedback": ["classify", str(clip), "--feedback", clip.parent.name],
        "append": ["train", str(clip.parent), "--append"],
    }[command]
    done = posecbr_on_read_only_mount(folder, [*argv, "--db", str(db)])
    assert done.returncode == 1, done.stderr
    name = {"trim": "casebase trim", "feedback": "classify", "append": "train"}[command]
    assert done.stderr.splitlines() == [
        f"posecbr {name}: error: {db}: cannot write the case base file: the folder {folder} is "
        "read-only (SQLite writes its journal beside it)"
    ]
    assert done.stdout == ""
    assert _sha(db) == _sha(small)


def _refused_quickly(argv: list[str], folder: Path) -> str:
    """``posecbr argv`` in a process: one line, exit 1, within a minute (a pipe made SQLite
    wait for a writer forever); ``folder`` holds the same names after."""
    names = sorted(p.name for p in folder.iterdir())
    done = subprocess.run(
        [sys.executable, "-m", "posecbr", *argv],
        cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and done.stdout == "", done.stderr
    assert sorted(p.name for p in folder.iterdir()) == names
    return lines[0]


@pytest.mark.parametrize("argv", [["casebase", "info"], ["casebase", "upgrade"]])
def test_a_pipe_as_the_case_base_file_is_refused_not_waited_on(
    tmp_path: Path, argv: list[str]
) -> None:
    # before: every reader (info, list, classify, segment...) and upgrade hung, SQLite (or the
    # WAL check) waiting in open() for a process to write into the pipe; train refused it
    pipe = tmp_path / "cb.sqlite"
    os.mkfifo(pipe)
    line = _refused_quickly([*argv, "--db", str(pipe)], tmp_path)
    assert line.endswith(f"{pipe}: is not a case base file: a device, pipe or socket"), line


def test_a_pipe_where_sqlite_keeps_the_journal_is_refused_not_waited_on(
    small: Path, tmp_path: Path
) -> None:
    db = tmp_path / "cb.sqlite"
    shutil.copy(small, db)
    os.mkfifo(tmp_path / "cb.sqlite-journal")
    line = _refused_quickly(["casebase", "info", "--db", str(db)], tmp_path)
    assert line == (
        f"posecbr casebase info: error: {db}: cb.sqlite-journal beside it, where SQLite keeps its "
        "journal, is not a file (a folder, device, pipe or socket): remove or rename it"
    )


def test_a_trim_whose_memory_mapped_copy_cannot_be_written_still_succeeds_once(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # before: the trim committed, then writing the large case base's matrices failed and the
    # command exited 1 ("cannot write: File exists"); run again, it trimmed a second time
    import cbr.stored

    monkeypatch.setattr(cbr.stored, "MAPPED_MIN_CASES", 1)  # matrices for every case base
    db = tmp_path / "cb.sqlite"
    shutil.copy(small, db)
    (tmp_path / "cb.sqlite.matrices").write_text("in the way\n")  # a file, not their folder
    capsys.readouterr()
    assert main(["casebase", "trim", "-k", "1", "--keep", "0.5", "--json", "--db", str(db)]) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert doc["changed"] and doc["size_before"] == 9 and doc["size_after"] < 9
    note = captured.err.strip().splitlines()
    assert len(note) == 1 and note[0].startswith("note: "), captured.err
    assert note[0].endswith(
        "(the change is stored; commands read its cases from the database instead of a "
        "memory-mapped copy)"
    )
    with open_store(db, readonly=True) as store:
        assert store.count_cases("default") == doc["size_after"]


def test_a_case_base_left_with_one_activity_classifies_without_runtime_warnings(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # feedback can relabel the last case of an activity (classify --feedback deep_squat on
    # hurdle_step clips left a case base of deep_squat alone); classify then printed two
    # "RuntimeWarning: invalid value encountered in divide" lines from the Why line's
    # comparison with the other activities, of which there were none
    import warnings

    db = tmp_path / "cb.sqlite"
    shutil.copy(small, db)
    with open_store(db) as store:
        ids = store.load_cases("default").ids
        with store.transaction() as tx:
            info = tx.case_base("default")
            for case_id in ids:
                tx.update_case(info, int(case_id), label="walk")
    clip = sorted((small.parent / "train").rglob("*.npz"))[0]
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        assert main(["classify", str(clip), "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{clip} (from synthetic): walk, confidence")
    assert "Why: nearest to the walk cases overall; no one feature sets it apart." in out


def test_a_case_base_file_in_a_folder_that_does_not_exist_is_named_with_it(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "posecbr train: error: DIR/missing: folder does not exist", the file not named
    data = tmp_path / "data"
    shutil.copytree(small.parent / "train", data)
    db = tmp_path / "missing" / "cb.sqlite"
    line = refused(["train", str(data), "--db", str(db)], tmp_path, capsys)
    assert line == f"posecbr train: error: {db}: folder does not exist ({db.parent})"


@pytest.mark.parametrize(
    "argv", [["casebase", "info"], ["casebase", "upgrade"], ["casebase", "trim"]]
)
def test_a_case_base_file_name_too_long_for_the_file_system_is_refused_by_every_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str]
) -> None:
    # before: OSError "[Errno 36] File name too long" with a traceback (asking whether the
    # file exists); train alone refused it in one line
    db = tmp_path / ("c" * 300 + ".sqlite")
    refused(
        [*argv, "--db", str(db)], tmp_path, capsys,
        f"{db}: the file name is too long: 307 bytes, at most 247",
    )  # fmt: skip
