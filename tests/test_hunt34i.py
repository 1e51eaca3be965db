"""Hunt 34i: SIGTERM (``kill PID``, systemd, ``docker stop``, a supervisor's
``Popen.terminate()``) killed every command but ``watch`` on the spot (status -15, nothing
said): an output being written left its hidden temporary, a first ``train`` its half-built
case base and journal, ``compare --jobs 2``'s and ``extract --workers 2``'s worker processes
ran on after the command had ended (extract's writing pose files nobody asked for any more).
SIGTERM now stops a command as Ctrl-C does, cleaned up, with one line ("posecbr segment:
terminated (SIGTERM)") and status 143 (128 + 15, as Ctrl-C's is 130 = 128 + 2).

Each test runs the command in a process of its own and sends SIGTERM to it alone (not to its
process group, as a terminal's Ctrl-C is sent), at a moment it waits for (a hidden temporary
seen, the workers started, a pause inside the transaction), not at a time.
"""

from __future__ import annotations

import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import ROOT, small_case_base
from tests.processes import posecbr_process, terminal_job

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="signals and /proc: Linux")

ENV = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
SQUATS = ("videos", "squat", "tfjs_pose_squats_pexels4838220.mp4")  # 65 frames at 5 fps
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _command(argv: list[str], logs: Path) -> subprocess.Popen[bytes]:
    """``python -m posecbr ARGV`` in a process group of its own, its output in files (a
    worker left running would hold a pipe open)."""
    return subprocess.Popen(
        [sys.executable, "-m", "posecbr", *argv],
        cwd=logs,
        env=ENV,
        stdout=(logs / "out.txt").open("wb"),
        stderr=(logs / "err.txt").open("wb"),
        start_new_session=True,
    )


def _alive(pids: list[int]) -> list[int]:
    """Those of ``pids`` still running (a zombie has ended)."""
    out = []
    for pid in pids:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state != "Z":
            out.append(pid)
    return out


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (from /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            out.append(int(stat.parent.name))
    return out


def _gone_soon(pids: list[int]) -> list[int]:
    """``pids`` still running after up to 10 s (an ended process's zombie is reaped by init)."""
    for _ in range(50):
        if not _alive(pids):
            return []
        time.sleep(0.2)
    left = _alive(pids)
    for pid in left:  # not left behind by the test either
        os.kill(pid, signal.SIGKILL)
    return left


def squat_copies(shared_data: Path, root: Path) -> Path:
    """``root/videos``: class folders as in ``../shared/data/videos`` (edge, lunge, side_plank,
    squat, the last one clip, the others two), each clip a copy of the bundled 65-frame squat
    video. ``extract --workers 2 --overlay`` of it begins its first overlay after one such
    clip, not after the bundled folder's largest two (250-308 frames, taken first): the same
    stop, a third of the pose model's work. Only with ``--overlay``: an overlay's hidden
    file lasts while its frames are drawn, a 65-frame pose file's 6-9 ms, which a poll every
    20 ms can miss clip after clip (the tests without ``--overlay`` extract the bundled
    folder, whose larger pose files take longer to write)."""
    videos = root / "videos"
    for cls, n in (("edge", 2), ("lunge", 2), ("side_plank", 2), ("squat", 1)):
        (videos / cls).mkdir(parents=True)
        for i in range(n):
            shutil.copyfile(shared_data.joinpath(*SQUATS), videos / cls / f"clip{i}.mp4")
    return videos


def _hidden(*folders: Path) -> list[str]:
    return [str(p) for f in folders if f.exists() for p in f.rglob(".*")]


def _ended(proc: subprocess.Popen[bytes], logs: Path) -> tuple[int, str, str]:
    proc.wait(timeout=180)
    return (
        proc.returncode,
        (logs / "err.txt").read_text(),
        (logs / "out.txt").read_text(),
    )


def test_sigterm_of_segment_writing_an_overlay_leaves_no_temporary(
    case_base: Path, shared_data: Path, tmp_path: Path
) -> None:
    """``segment VIDEO --overlay OUT`` sent SIGTERM while the overlay is being written: the
    one line, status 143, and the output folder as it was (empty). It was killed, status
    -15, its 0600 temporary ``.o.mp4.pid...mp4`` left in the folder."""
    out = tmp_path / "out"
    out.mkdir()
    argv = ["segment", str(shared_data.joinpath(*SQUATS)), "--db", str(case_base)]
    proc = _command([*argv, "--overlay", str(out / "o.mp4")], tmp_path)
    while not _hidden(out) and proc.poll() is None:
        time.sleep(0.02)
    assert _hidden(out), "the overlay was never begun"
    proc.terminate()
    code, err, printed = _ended(proc, tmp_path)
    assert (code, printed) == (143, "")  # the line, beside the 5-fps video's frame-rate note
    assert [line for line in err.splitlines() if not line.startswith("note: ")] == [
        "posecbr segment: terminated (SIGTERM)"
    ]
    assert list(out.iterdir()) == []


def _cases(db: Path) -> tuple[int, str]:
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        n = con.execute("SELECT count(*) FROM cases").fetchone()[0]
        return int(n), str(con.execute("PRAGMA integrity_check").fetchone()[0])
    finally:
        con.close()


def test_sigterm_inside_a_first_trains_transaction_leaves_nothing(
    case_base: Path, tmp_path: Path
) -> None:
    """A first ``train`` builds its case base under a hidden name: SIGTERM inside its
    transaction rolls it back and removes that file, the one line, status 143. (Killed, it
    left the hidden file and its journal, for the next train to remove.)"""
    folder = tmp_path / "out"
    folder.mkdir()
    argv = ["train", str(case_base.parent / "train"), "--db", str(folder / "cb.sqlite"),
            "--mirror", "off", "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    proc = posecbr_process(*argv, pause_after="build")
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    assert len(_hidden(folder)) == 2  # the case base being built and its journal
    proc.terminate()
    out, err = proc.communicate(timeout=120)
    assert (proc.returncode, err, out) == (143, "posecbr train: terminated (SIGTERM)\n", "")
    assert list(folder.iterdir()) == []


def test_sigterm_inside_an_appending_trains_transaction_changes_nothing(
    case_base: Path, tmp_path: Path
) -> None:
    """``train --append`` sent SIGTERM inside its transaction: the case base as it was (the
    same cases, SQLite's integrity check "ok", no journal left to roll back), the one line,
    status 143; the same run left alone then adds its six clips (9 cases to 15)."""
    from tests.test_cbr_cli import _write_classes

    more = _write_classes(tmp_path / "more", 2, 6)  # two clips of each activity
    db = tmp_path / "cb.sqlite"
    db.write_bytes(case_base.read_bytes())
    before = db.read_bytes()
    assert _cases(db) == (9, "ok")  # three activities, three clips each
    argv = ["train", str(more), "--db", str(db), "--append"]
    proc = posecbr_process(*argv, pause_after="append")
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    assert (tmp_path / "cb.sqlite-journal").exists()  # the transaction has written
    proc.terminate()
    out, err = proc.communicate(timeout=120)
    assert (proc.returncode, err, out) == (143, "posecbr train: terminated (SIGTERM)\n", "")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cb.sqlite", "more"]  # no journal
    assert db.read_bytes() == before
    assert _cases(db) == (9, "ok")
    assert main(argv) == 0  # the same run left alone, here (only the stopped one needed a process)
    assert _cases(db) == (15, "ok")


def test_sigterm_of_compare_with_workers_ends_them(tmp_path: Path) -> None:
    """``compare --jobs 2`` sent SIGTERM (to it alone, as ``kill PID`` does) once its two
    workers run: it stops them and ends with the one line, status 143, no --out folder; no
    worker is left. (It was killed and its workers ran on, orphaned, holding its output
    pipes open.)"""
    out = tmp_path / "o"
    argv = ["compare", str(DEMO), "--peers", "none", "--jobs", "2", "--out", str(out)]
    proc = _command([*argv, "--labels", "deep_squat,hurdle_step,sit_to_stand"], tmp_path)
    workers: list[int] = []
    while len(workers) < 2 and proc.poll() is None:
        time.sleep(0.1)
        workers = [
            p
            for p in _children(proc.pid)
            if b"spawn_main" in Path(f"/proc/{p}/cmdline").read_bytes()
        ]
    assert len(workers) == 2, "the workers never started"
    proc.terminate()
    got = _ended(proc, tmp_path)
    assert _gone_soon(workers) == []
    assert got == (143, "posecbr compare: terminated (SIGTERM)\n", "")
    assert not out.exists()


def test_sigterm_of_extract_with_workers_ends_them_and_their_temporaries(
    shared_data: Path, tmp_path: Path
) -> None:
    """``extract VIDEOS --workers 2 --overlay`` sent SIGTERM once a worker is writing a
    file: the workers stop, each removing the hidden file it was writing, the one line,
    status 143, no hidden file anywhere, no worker left; a pose file a worker finished
    before the signal (under load, one did) is whole, and none began after it. (It was
    killed; its workers ran on orphaned and wrote the pose files after it had ended;
    stopped by Ctrl-C it waited for every clip queued.)"""
    out, overlays = tmp_path / "poses", tmp_path / "overlays"
    out.mkdir()
    argv = [
        "extract",
        str(squat_copies(shared_data, tmp_path)),
        "--out",
        str(out),
        "--workers",
        "2",
    ]
    proc = _command([*argv, "--overlay", str(overlays)], tmp_path)
    while not _hidden(out, overlays) and proc.poll() is None:
        time.sleep(0.02)
    assert _hidden(out, overlays), "no file was begun"
    workers = _children(proc.pid)
    finished = {p for p in out.rglob("*") if p.is_file() and not p.name.startswith(".")}
    proc.terminate()
    got = _ended(proc, tmp_path)
    assert _gone_soon(workers) == []
    assert got == (143, "posecbr extract: terminated (SIGTERM)\n", "")
    assert _hidden(out, overlays) == []
    # a clip a worker finished before the signal stays, whole; none is half-written, and no
    # worker went on to another clip (at most the one each had in hand as the signal came)
    from features.poses import load_pose

    left = {p for p in out.rglob("*") if p.is_file()}
    assert len(left - finished) <= len(workers), sorted(left - finished)
    for path in left:
        assert load_pose(path).n_frames > 0, path


def test_ctrl_c_of_extract_with_workers_stops_them_at_once(
    shared_data: Path, tmp_path: Path
) -> None:
    """Ctrl-C in a terminal (SIGINT to the whole process group) of ``extract --workers 2``:
    the workers' clips are unwound and the command ends, "interrupted", status 130, no pose
    file written, no process left. (Its pool's shutdown waited for every clip queued: the
    run went on for 44 s and wrote seven pose files after the Ctrl-C.)"""
    out = tmp_path / "poses"
    argv = ["extract", str(shared_data / "videos"), "--out", str(out), "--workers", "2"]
    proc = terminal_job(argv, tmp_path)
    while not _hidden(out) and proc.poll() is None:
        time.sleep(0.02)
    assert _hidden(out), "no file was begun"
    workers = _children(proc.pid)
    finished = {p for p in out.rglob("*") if p.is_file() and not p.name.startswith(".")}
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=180)
    assert (proc.returncode, err.decode()) == (130, "posecbr extract: interrupted\n")
    assert _gone_soon(workers) == []
    # as for SIGTERM: none half-written, none begun after the signal
    left = {p for p in out.rglob("*") if p.is_file()}
    assert not any(p.name.startswith(".") for p in left), sorted(left)
    assert len(left - finished) <= len(workers), sorted(left - finished)


# ---- in this process: the handler and where it is held --------------------------------------


def test_a_command_sent_sigterm_says_so_and_exits_143(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """The command's own code unwinds (its ``finally`` runs), the line names SIGTERM, 143;
    Ctrl-C is still "interrupted", 130; SIGTERM's handler is put back after the command."""
    import posecbr.commands.describe as describe

    unwound: list[str] = []

    def stopped_by(signum: int) -> object:
        def run(_args: object) -> int:
            try:
                os.kill(os.getpid(), signum)
                time.sleep(30)  # the signal's handler runs here
            finally:
                unwound.append(signal.Signals(signum).name)
            return 0

        return run

    before = signal.getsignal(signal.SIGTERM)
    clip = str(DEMO / "m01_s01_e01.npz")
    monkeypatch.setattr(describe, "run", stopped_by(signal.SIGTERM))
    capsys.readouterr()
    assert main(["describe", clip]) == 143
    assert capsys.readouterr().err == "posecbr describe: terminated (SIGTERM)\n"
    monkeypatch.setattr(describe, "run", stopped_by(signal.SIGINT))
    assert main(["describe", clip]) == 130
    assert capsys.readouterr().err == "posecbr describe: interrupted\n"
    assert unwound == ["SIGTERM", "SIGINT"]
    assert signal.getsignal(signal.SIGTERM) is before


def test_sigterm_while_workers_start_comes_after_they_have() -> None:
    """A SIGTERM that comes while worker processes are started is raised once they are all
    known (raised in the middle of starting one, it left that one running)."""
    from features.interrupts import sigterm_as_interrupt, sigterm_held, terminated

    steps: list[str] = []
    with pytest.raises(KeyboardInterrupt), sigterm_as_interrupt():
        with sigterm_held():
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)
            steps.append("every worker started")
        steps.append("not reached")
    assert steps == ["every worker started"]
    assert terminated()


def test_a_second_sigterm_stops_a_watch_at_once_and_says_sigterm() -> None:
    """The first SIGTERM ends a watch as the end of its file does (the event set); a second
    one stops it at once, said as SIGTERM (status 143), not as Ctrl-C."""
    from features.interrupts import sigterm_as_interrupt, terminated
    from posecbr.commands.watch import stop_on_interrupt

    assert threading.current_thread() is threading.main_thread()
    with sigterm_as_interrupt():
        with pytest.raises(KeyboardInterrupt), stop_on_interrupt() as stop:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)
            assert stop.is_set() and not terminated()
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(30)
        assert terminated()


def test_an_interrupt_as_a_temporary_is_made_leaves_none(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """Ctrl-C or SIGTERM taken just after the hidden file was created, before its name was
    returned (in ``tempfile.mkstemp``'s own Python code, where a handler can run): the file
    was left behind, the atomic write never having begun. (Seen: ``segment --overlay``
    sent SIGTERM as the overlay's temporary appeared, on a loaded machine.)"""
    import tempfile

    from features.fileio import atomic_path

    real = tempfile.mkstemp

    def interrupted(*args: object, **kwargs: object) -> tuple[int, str]:
        fd, name = real(*args, **kwargs)  # type: ignore[call-overload]
        os.close(fd)
        raise KeyboardInterrupt

    monkeypatch.setattr(tempfile, "mkstemp", interrupted)
    (tmp_path / "other.json").write_text("{}")  # not this output's: kept
    with pytest.raises(KeyboardInterrupt), atomic_path(tmp_path / "out.json"):
        pass
    assert [p.name for p in tmp_path.iterdir()] == ["other.json"]


WORKER_SCRIPT = """
import concurrent.futures as cf, multiprocessing, os, sys, time
from features.interrupts import run_task, worker_ends_on_sigterm

def task(path):
    try:
        open(path, "w").close()
        time.sleep(60)
    except KeyboardInterrupt:
        return "failed"  # as extract turns a clip's error into a failed clip
    return "done"

if __name__ == "__main__":
    folder = sys.argv[1]
    with cf.ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"),
                                initializer=worker_ends_on_sigterm) as pool:
        first = pool.submit(run_task, task, os.path.join(folder, "a"))
        pool.submit(run_task, task, os.path.join(folder, "b"))
        while not os.path.exists(os.path.join(folder, "a")):
            time.sleep(0.02)
        (worker,) = pool._processes.values()
        worker.terminate()
        worker.join(60)
        # The pool's own thread may reap the worker first; its status then lands a moment later.
        deadline = time.monotonic() + 30
        while worker.exitcode is None and time.monotonic() < deadline:
            time.sleep(0.02)
        print(worker.exitcode, type(first.exception(60)).__name__)
        print(sorted(os.listdir(folder)))
"""


def pool_script_lines(text: str, tmp_path: Path) -> list[str]:
    """The lines printed by the script ``text`` (a process pool whose tasks write into the
    folder it is given) run in a new interpreter; it must exit 0."""
    script = tmp_path / "pool.py"
    script.write_text(text)
    (tmp_path / "work").mkdir()
    run = subprocess.run([sys.executable, str(script), str(tmp_path / "work")], env=ENV,
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    assert run.returncode == 0, run.stderr
    return run.stdout.splitlines()


def test_a_worker_sent_sigterm_ends_after_unwinding_its_task(tmp_path: Path) -> None:
    """A worker's task that turns the interrupt into a result (a failed clip) still ends the
    worker, status 143, instead of going on to the next task queued ("b" never begun)."""
    assert pool_script_lines(WORKER_SCRIPT, tmp_path) == ["143 BrokenProcessPool", "['a']"]
