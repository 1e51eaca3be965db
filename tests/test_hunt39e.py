"""Store and compare faults found by hunt 39e: a refused writer that changed the file it
refused (posecbr 0.1's WAL mode left before the schema was checked); a comparison
interrupted while drawing its pictures, whose results file named none of those drawn."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import sqlite3
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from posecbr.cli import main
from tests.badinput import refused, snapshot

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"
CLIP = DEMO / "m01_s03_e01.npz"
V1_SQL = Path(__file__).with_name("fixtures") / "store_v1.sql"


def _md5(path: Path) -> str:
    return hashlib.md5(path.read_bytes()).hexdigest()


def _wal(db: Path) -> Path:
    """``db`` put in WAL mode, as posecbr 0.1 left its stores (no -wal or -shm after)."""
    con = sqlite3.connect(db)
    assert con.execute("PRAGMA journal_mode = WAL").fetchone() == ("wal",)
    con.close()
    assert sorted(p.name for p in db.parent.iterdir() if p.name.startswith(db.name)) == [db.name]
    return db


def _header_modes(db: Path) -> bytes:
    """Bytes 18 and 19 of a SQLite file: 2, 2 in WAL mode, 1, 1 with a rollback journal."""
    return db.read_bytes()[18:20]


# on one xdist worker: the module's trained, three made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt39e")


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    db = tmp_path_factory.mktemp("cb") / "cb.sqlite"
    argv = ["train", str(LABELS), "--db", str(db), "--subjects", "s01",
            "--labels", "deep_squat,sit_to_stand", "--mirror", "off"]  # fmt: skip
    assert main(argv) == 0
    return db


def _v1_wal(folder: Path) -> Path:
    db = folder / "old.sqlite"
    con = sqlite3.connect(db)
    con.executescript(V1_SQL.read_text(encoding="utf-8"))
    con.close()
    return _wal(db)


def _writers_of(db: Path, source: Path) -> list[list[str]]:
    return [
        ["casebase", "copy", "--db", str(source), "--to", str(db)],
        ["casebase", "copy", "--db", str(source), "--to", str(db), "--as", "other"],
        [
            "train",
            str(LABELS),
            "--db",
            str(db),
            "--subjects",
            "s01",
            "--labels",
            "deep_squat,sit_to_stand",
            "--mirror",
            "off",
            "--name",
            "other",
        ],  # fmt: skip
        [
            "train",
            str(LABELS),
            "--db",
            str(db),
            "--subjects",
            "s02",
            "--labels",
            "deep_squat,sit_to_stand",
            "--append",
        ],  # fmt: skip
    ]


@pytest.mark.parametrize("which", range(4))
def test_a_writer_refusing_a_posecbr_0_1_store_in_wal_mode_leaves_it_byte_identical(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], which: int
) -> None:
    # before: `casebase copy --to OLD.sqlite` set the file's journal mode on connecting, then
    # refused its schema version: OLD.sqlite was no longer in WAL mode, its bytes changed
    folder = tmp_path / "old"
    folder.mkdir()
    db = _v1_wal(folder)
    before = _md5(db)
    refused(_writers_of(db, trained)[which], folder, capsys, "casebase upgrade --db FILE")
    assert _md5(db) == before and _header_modes(db) == b"\x02\x02"
    assert sorted(p.name for p in folder.iterdir()) == ["old.sqlite"]


def _newer_wal(folder: Path) -> Path:
    """A posecbr 0.1 store in WAL mode in ``folder`` (made), its schema version set to 99 (a
    store of a newer posecbr)."""
    folder.mkdir()
    db = _v1_wal(folder)
    con = sqlite3.connect(db)
    con.execute("UPDATE posecbr_schema_version SET version = 99")
    con.commit()
    con.close()
    return db


def test_upgrade_refusing_a_newer_store_in_wal_mode_leaves_it_byte_identical(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the journal mode was converted, then the schema version 99 refused
    folder = tmp_path / "new"
    db = _newer_wal(folder)
    assert _header_modes(db) == b"\x02\x02"
    before = _md5(db)
    refused(["casebase", "upgrade", "--db", str(db)], folder, capsys, "schema version 99")
    assert _md5(db) == before and sorted(p.name for p in folder.iterdir()) == ["old.sqlite"]


def _current_wal(trained: Path, folder: Path) -> Path:
    """A copy of the current store ``trained`` in ``folder`` (made), put in WAL mode."""
    folder.mkdir()
    db = folder / "cb.sqlite"
    db.write_bytes(trained.read_bytes())
    return _wal(db)


def _copied_as_other(argv: list[str], db: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``argv``, a ``casebase copy --to db`` refused for the name taken, run again ``--as
    other``: made and said, ``db`` converted to a rollback journal, nothing left beside it."""
    assert main([*argv, "--as", "other"]) == 0
    assert "as 'other'" in capsys.readouterr().out
    assert _header_modes(db) == b"\x01\x01"
    assert sorted(p.name for p in db.parent.iterdir()) == [db.name]


def test_a_copy_refused_for_a_name_taken_leaves_a_current_store_in_wal_mode_as_it_was(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the copy converted the file to a rollback journal, then found 'default' there
    folder = tmp_path / "to"
    db = _current_wal(trained, folder)
    before = _md5(db)
    argv = ["casebase", "copy", "--db", str(trained), "--to", str(db)]
    refused(argv, folder, capsys, "a case base named 'default' is here already")
    assert _md5(db) == before and _header_modes(db) == b"\x02\x02"
    # a copy that is made converts it (readers then need no side files), and says nothing
    _copied_as_other(argv, db, capsys)
    before = snapshot(folder)
    assert main(["classify", str(CLIP), "--db", str(db), "--name", "other"]) == 0
    assert snapshot(folder) == before


def _changes_in_wal(db: Path, *, shm: bool) -> dict[str, str]:
    """``db`` (in WAL mode) with a committed change (case 1 relabelled) still in its -wal file,
    as a posecbr 0.1 writer killed before a checkpoint left it, with or without the -shm file
    (SQLite's index of the -wal, rebuilt from it). Returns the md5 of the file and its -wal."""
    change = (
        "import os, sqlite3, sys; c = sqlite3.connect(sys.argv[1]); "
        "c.execute('PRAGMA wal_autocheckpoint = 0'); "
        "c.execute(\"UPDATE cases SET label = 'relabelled' WHERE id = 1\"); c.commit(); "
        "os._exit(0)"
    )
    subprocess.run([sys.executable, "-c", change, str(db)], check=True, timeout=60)
    wal = db.with_name(db.name + "-wal")
    assert wal.stat().st_size > 32 and _header_modes(db) == b"\x02\x02"
    if not shm:
        db.with_name(db.name + "-shm").unlink()
    return {"file": _md5(db), "wal": _md5(wal)}


def _refused_keeping_the_wal(
    argv: list[str], db: Path, md5: dict[str, str], capsys: pytest.CaptureFixture[str], needle: str
) -> None:
    """``posecbr argv`` refused in one line holding ``needle``, the file and its -wal file
    byte-identical (the change still in the -wal, not copied into the file), a -shm file there
    kept (its bytes are SQLite's to rewrite). Where there was none, a writer that opened the
    file leaves the one SQLite made: only the close that copies the -wal into the file (what
    a refusal must not do) deletes it."""
    shm = db.with_name(db.name + "-shm")
    had_shm = shm.exists()
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert captured.out == "" and len(captured.err.splitlines()) == 1, captured.err
    assert needle in captured.err
    wal = db.with_name(db.name + "-wal")
    assert {"file": _md5(db), "wal": _md5(wal)} == md5
    left = {p.name for p in db.parent.iterdir()}
    if had_shm:
        assert left == {db.name, wal.name, shm.name}
    else:
        assert left - {shm.name} == {db.name, wal.name}


def _label_of_case_1(db: Path) -> str:
    con = sqlite3.connect(db)
    try:
        return str(con.execute("SELECT label FROM cases WHERE id = 1").fetchone()[0])
    finally:
        con.close()


@pytest.mark.parametrize("shm", [True, False], ids=["shm", "no-shm"])
@pytest.mark.parametrize("which", range(4))
def test_a_writer_refusing_a_0_1_store_with_changes_in_its_wal_leaves_file_and_wal_as_they_were(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], which: int, shm: bool
) -> None:
    # before: `casebase copy --to OLD.sqlite` refused its schema version, and its connection's
    # close (the last one) copied the -wal's change into OLD.sqlite and deleted the -wal and
    # -shm: the file's bytes changed
    folder = tmp_path / "old"
    folder.mkdir()
    db = _v1_wal(folder)
    md5 = _changes_in_wal(db, shm=shm)
    _refused_keeping_the_wal(_writers_of(db, trained)[which], db, md5, capsys, "upgrade")
    # nothing lost: the upgrade it names reads the change, and converts the file
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    capsys.readouterr()
    assert _label_of_case_1(db) == "relabelled" and _header_modes(db) == b"\x01\x01"
    assert sorted(p.name for p in folder.iterdir()) == ["old.sqlite"]


def test_a_copy_refused_for_a_name_taken_keeps_a_current_stores_changes_in_its_wal(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the refused copy's close checkpointed cb.sqlite (its bytes changed, -wal and
    # -shm deleted)
    db = _current_wal(trained, tmp_path / "to")
    md5 = _changes_in_wal(db, shm=True)
    argv = ["casebase", "copy", "--db", str(trained), "--to", str(db)]
    _refused_keeping_the_wal(argv, db, md5, capsys, "a case base named 'default' is here")
    # a copy that is made commits, then converts the file with the change in it
    _copied_as_other(argv, db, capsys)
    assert _label_of_case_1(db) == "relabelled"


def test_upgrade_refusing_a_newer_store_keeps_the_changes_in_its_wal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the refusal was right, but its close copied the -wal's change into the file
    folder = tmp_path / "new"
    db = _newer_wal(folder)
    md5 = _changes_in_wal(db, shm=True)
    argv = ["casebase", "upgrade", "--db", str(db)]
    _refused_keeping_the_wal(argv, db, md5, capsys, "schema version 99")


@pytest.mark.parametrize("which", range(3))
def test_a_reader_of_a_current_store_in_wal_mode_writes_nothing(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], which: int
) -> None:
    folder = tmp_path / "cb"
    db = _current_wal(trained, folder)
    before = _md5(db)
    argv = [
        ["classify", str(CLIP), "--db", str(db)],
        ["segment", str(CLIP), "--db", str(db), "--unknown", "held-out"],
        ["casebase", "list", "--db", str(db)],
    ][which]
    refused(argv, folder, capsys, "WAL mode", "posecbr casebase upgrade --db FILE")
    assert _md5(db) == before and snapshot(folder) == {"cb.sqlite": snapshot(folder)["cb.sqlite"]}


#: ``python -m posecbr`` whose second picture written (accuracy, then a confusion matrix) is
#: followed by a marker file and a long wait: an interrupt then comes once it is on disk,
#: before the command has named it
COMPARE = ["compare", str(DEMO), "--subjects", "s01", "--labels",
           "deep_squat,sit_to_stand,standing_shoulder_abduction", "--folds", "3",
           "--similarities", "euclidean", "--features", "fluents", "--no-dad", "--peers",
           "none", "--explain", "0"]  # fmt: skip


def _pngs(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.suffix == ".png")


@pytest.fixture
def earlier_run(compared_three: Path) -> Path:
    """The --out folder of one ``COMPARE`` (three activities: six pictures, three of them
    timelines), made once in the session (tests/conftest.py); each test copies it as the
    earlier run its own comparison writes over."""
    from tests.test_hunt40j import THREE

    assert THREE == COMPARE  # the comparison made once is this module's
    return compared_three


def _earlier_run_in(earlier_run: Path, out: Path) -> None:
    shutil.copytree(earlier_run, out)


def test_compare_interrupted_while_drawing_names_exactly_the_pictures_on_disk(
    earlier_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: results.json, written before the pictures, named none; the two drawn lay beside
    # it unnamed, and the earlier run's timelines and prevalence, no longer named by any
    # results file, were never removed
    import cbr.evaluation.pictures as pictures

    out = tmp_path / "o"
    _earlier_run_in(earlier_run, out)
    assert _pngs(out) == ["accuracy.png", "confusion_cbr_fluents_euclidean.png",
                          "prevalence.png", "timeline_00.png", "timeline_01.png",
                          "timeline_02.png"]  # fmt: skip
    real_save, drawn = pictures._save, []

    def save(fig: Any, path: Any) -> Any:
        """The picture saved; once the second is on disk, SIGINT to this process (as Ctrl-C
        sends it), which compare gets before it goes on."""
        saved = real_save(fig, path)
        drawn.append(path)
        if len(drawn) == 2:
            os.kill(os.getpid(), signal.SIGINT)
        return saved

    capsys.readouterr()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(pictures, "_save", save)
        mp.chdir(tmp_path)
        try:
            code = main([*COMPARE, "--out", str(out)])
        except KeyboardInterrupt:
            pytest.fail("the interrupt escaped compare")
    stderr = capsys.readouterr().err
    assert len(drawn) == 2, drawn  # the interrupt came with the second picture
    assert code == 130, stderr
    assert stderr.splitlines()[-1] == (
        f"posecbr compare: interrupted: results in {out}, with the 1 picture drawn before it;"
        " the rest were not drawn"
    )
    assert "Traceback" not in stderr
    # the confusion matrix, written but not yet named when the interrupt came, is removed (a
    # picture of the earlier run under the name would be stale); so are the earlier run's
    # pictures not drawn again, which no results file names any more
    assert sorted(p.name for p in out.iterdir()) == ["accuracy.png", "results.csv", "results.json"]
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    assert doc["pictures"] == {"accuracy": "accuracy.png"}
    assert "interrupted while drawing the pictures: 1 drawn" in " ".join(doc["notes"])
    # the report shows the one picture named, and draws none of the others
    assert main(["report", str(out), "--out", str(tmp_path / "r.html")]) == 0
    html = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert html.count('<img src="data:image/png;base64,') == 1
    assert (out / "accuracy.png").read_bytes().startswith(b"\x89PNG")


TWO = [*COMPARE]
TWO[TWO.index("--labels") + 1] = "deep_squat,sit_to_stand"


def _interrupted_in_first_write(where: str, out: Path, capsys: pytest.CaptureFixture[str]) -> str:
    """``compare`` of two activities into ``out``, run in this process from ``out``'s folder,
    sending itself SIGINT (as Ctrl-C does) at a known point of the first write of its
    results: ``where`` "rename" as results.json is put in place (written under its
    temporary name), "csv" between results.json and results.csv, "last" as results.json
    naming the pictures drawn is put in place. Exit 130, no traceback; returns the last line
    it said."""
    import cbr.evaluation.tables as tables

    real_replace, real_csv = os.replace, tables.write_csv
    sent: list[str] = []
    renamed: list[str] = []

    def interrupt(here: str) -> None:
        if where == here and not sent:  # once: the first write's
            sent.append(here)
            os.kill(os.getpid(), signal.SIGINT)

    def replace(src: Any, dst: Any) -> None:
        if str(dst).endswith("results.json"):
            renamed.append(str(dst))
            interrupt("rename" if len(renamed) == 1 else "last")
        real_replace(src, dst)

    def write_csv(rows: Any, path: Any) -> Any:
        interrupt("csv")
        return real_csv(rows, path)

    capsys.readouterr()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(os, "replace", replace)
        mp.setattr(tables, "write_csv", write_csv)
        mp.chdir(out.parent)
        try:
            code = main([*TWO, "--out", str(out)])
        except KeyboardInterrupt:
            pytest.fail("the interrupt escaped compare")
    err = capsys.readouterr().err
    assert sent == [where], sent
    assert code == 130, err
    assert "Traceback" not in err
    return err.splitlines()[-1]


@pytest.mark.parametrize("earlier", [False, True], ids=["new-folder", "earlier-run"])
@pytest.mark.parametrize("where", ["rename", "csv"])
def test_compare_interrupted_in_its_first_write_leaves_whole_results_and_a_rerun_clean(
    earlier_run: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    where: str,
    earlier: bool,
) -> None:
    # before: Ctrl-C between results.json and results.csv left the new JSON (two activities)
    # beside the earlier run's table (three) and its six pictures, named by no results file
    # (a rerun could not tell them stale: timeline_02.png, an activity no longer compared,
    # stayed for good); in a new folder, Ctrl-C as results.json was put in place left the
    # folder empty. Each time "posecbr compare: interrupted", nothing said of the files.
    out = tmp_path / "o"
    if earlier:  # three activities: three timelines
        _earlier_run_in(earlier_run, out)
        assert "timeline_02.png" in _pngs(out)
    assert _interrupted_in_first_write(where, out, capsys) == (
        f"posecbr compare: interrupted: results in {out}, with the 0 pictures drawn before it;"
        " the rest were not drawn"
    )
    # the new run's results, whole: both files, of the two activities compared, no picture
    assert sorted(p.name for p in out.iterdir()) == ["results.csv", "results.json"]
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    assert doc["dataset"]["classes"] == ["deep_squat", "sit_to_stand"] and doc["pictures"] == {}
    header = (out / "results.csv").read_text(encoding="utf-8").splitlines()[0].split(",")
    assert [c for c in header if c.startswith("recall:")] == [
        "recall:deep_squat",
        "recall:sit_to_stand",
    ]
    # a rerun draws its pictures beside them, and nothing else is there
    assert main([*TWO, "--out", str(out)]) == 0
    capsys.readouterr()
    assert sorted(p.name for p in out.iterdir()) == [
        "accuracy.png", "confusion_cbr_fluents_euclidean.png", "prevalence.png",
        "results.csv", "results.json", "timeline_00.png", "timeline_01.png",
    ]  # fmt: skip


def test_compare_interrupted_as_it_names_its_pictures_names_every_one(
    earlier_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: Ctrl-C as results.json was written again to name the pictures left all five
    # drawn and none named (results.json as first written: "pictures": {}), said as
    # "interrupted" alone; `report` then showed none of them
    out = tmp_path / "o"
    _earlier_run_in(earlier_run, out)  # three activities: three timelines
    assert _interrupted_in_first_write("last", out, capsys) == (
        f"posecbr compare: interrupted: results in {out}, with the 5 pictures drawn before it:"
        " all of them"
    )
    drawn = ["accuracy.png", "confusion_cbr_fluents_euclidean.png", "prevalence.png",
             "timeline_00.png", "timeline_01.png"]  # fmt: skip
    assert _pngs(out) == drawn
    pics = json.loads((out / "results.json").read_text(encoding="utf-8"))["pictures"]
    named = [pics["accuracy"], pics["prevalence"]]
    named += [c["file"] for c in pics["confusion"]] + [t["file"] for t in pics["timelines"]]
    assert sorted(named) == drawn


SQUAT_MP4 = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"


@pytest.fixture(scope="module")
def three(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A case base of three UI-PRMD movements (enough to judge unknown), for watch."""
    db = tmp_path_factory.mktemp("cb3") / "cb.sqlite"
    argv = ["train", str(LABELS), "--db", str(db), "--subjects", "s01", "--mirror", "off",
            "--labels", "deep_squat,sit_to_stand,standing_shoulder_abduction"]  # fmt: skip
    assert main(argv) == 0
    return db


def _fast_start(src: Path, dest: Path) -> bytes:
    """``src``'s frames remuxed (not encoded again) with the index first, as a web page's
    "fast start" MP4: the frames' box (mdat) is its last and runs to its end."""
    import av

    with (
        av.open(str(src)) as inp,
        av.open(str(dest), "w", options={"movflags": "+faststart"}) as out,
    ):
        video = inp.streams.video[0]
        stream = out.add_stream_from_template(video)
        for packet in inp.demux(video):
            if packet.dts is not None:
                packet.stream = stream
                out.mux(packet)
    data = dest.read_bytes()
    mdat = data.index(b"mdat") - 4
    assert data.index(b"moov") < mdat and mdat + int.from_bytes(
        data[mdat : mdat + 4], "big"
    ) == len(data)
    return data


def test_watch_of_a_served_mp4_cut_short_says_it_was_cut(
    three: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: cut 300 bytes short (inside its last frame) it was watched as whole, 64 frames,
    # exit 0; cut before its index (at its end) "cannot open camera or stream"; a file here
    # cut so is refused as "truncated MP4/MOV" (hunt 38f)
    pytest.importorskip("av")
    from tests.test_hunt34c import _serving

    whole = (shared_data / SQUAT_MP4).read_bytes()  # its index (moov) last: 508,341 bytes
    folder = tmp_path / "served"
    folder.mkdir()
    fast = _fast_start(shared_data / SQUAT_MP4, tmp_path / "fast.mp4")
    (folder / "fast.mp4").write_bytes(fast)
    (folder / "last_frame.mp4").write_bytes(fast[:-300])
    (folder / "no_index.mp4").write_bytes(whole[:-500])
    with _serving(folder) as url:
        argv = ["--db", str(three), "--speed", "0", "--unknown", "held-out"]
        assert main(["watch", f"{url}/fast.mp4", *argv]) == 0  # whole: as before
        assert "watched 65 frames" in capsys.readouterr().err
        assert main(["watch", f"{url}/last_frame.mp4", *argv]) == 1
        err = capsys.readouterr().err.splitlines()
        assert err[-1] == (
            f"posecbr watch: error: {url}/last_frame.mp4: truncated MP4/MOV: the served file "
            f"ends at byte {len(fast) - 300:,}, inside a box that runs to byte {len(fast):,}"
        )
        refused(["watch", f"{url}/no_index.mp4", *argv], folder, capsys,
                f"{url}/no_index.mp4: truncated MP4/MOV: the served file ends at byte "
                f"{len(whole) - 500:,}, inside a box that runs to byte {len(whole):,}")  # fmt: skip


def test_upgrade_that_cannot_leave_wal_mode_says_so(
    trained: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # another process reading the file keeps it in WAL mode: once WAL mode was left after
    # the schema check, upgrade said "already schema version 2, nothing to do" (exit 0) and
    # every reader went on sending the user to it (before: "database is locked")
    import functools

    import casebase_store

    monkeypatch.setattr(casebase_store, "upgrade_store",
                        functools.partial(casebase_store.upgrade_store, timeout_s=0.3))  # fmt: skip
    folder = tmp_path / "cb"
    db = _current_wal(trained, folder)
    holder = sqlite3.connect(db, isolation_level=None)
    try:
        holder.execute("BEGIN")
        assert holder.execute("SELECT count(*) FROM case_bases").fetchone() == (1,)
        assert main(["casebase", "upgrade", "--db", str(db)]) == 1
        captured = capsys.readouterr()
        assert captured.out == "" and captured.err == (
            f"posecbr casebase upgrade: error: {db}: the file is still in WAL mode: another "
            "process is reading or writing it; run `posecbr casebase upgrade --db FILE` again "
            "once it has closed it\n"
        )
    finally:
        holder.execute("ROLLBACK")
        holder.close()
    assert _header_modes(db) == b"\x02\x02"
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert capsys.readouterr().out == f"{db}: converted from WAL mode to a rollback journal\n"
    assert _header_modes(db) == b"\x01\x01" and sorted(p.name for p in folder.iterdir()) == [
        "cb.sqlite"
    ]
