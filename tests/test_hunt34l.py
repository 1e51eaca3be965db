"""Hunt 34l: review of the day's changes. A ``file:`` URL is watched as its path is, so what
it lacks is said as for its path, not as for a file on a server."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.badinput import refused, small_case_base


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _undecodable_avi(path: Path) -> Path:
    """An MJPG AVI whose container states 30 frames at 25 fps and whose every frame (each
    ``00dc`` chunk) is zeroed after its JPEG start marker: it opens, and no frame decodes."""
    import cv2

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (64, 48))
    assert writer.isOpened()
    for k in range(30):
        writer.write(np.full((48, 64, 3), 3 * k, np.uint8))
    writer.release()
    data = bytearray(path.read_bytes())
    chunks = 0
    at = data.find(b"00dc")
    while at >= 0:
        size = int.from_bytes(data[at + 4 : at + 8], "little")
        if data[at + 8 : at + 10] == b"\xff\xd8":  # a frame's chunk (not the index's entry)
            data[at + 10 : at + 8 + size] = bytes(size - 2)
            chunks += 1
        at = data.find(b"00dc", at + 4)
    assert chunks == 30
    path.write_bytes(bytes(data))
    return path


def test_a_file_url_that_decodes_no_frame_is_refused_as_its_path_is(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """None of the 30 frames decodes: the path is refused "truncated or corrupt: decoded 0
    of 30 frames", and so is ``file://PATH`` (it said "read none of the 30 frames the served
    file holds: ... the server does not answer range requests", of a file on this
    machine)."""
    folder = tmp_path / "in"
    folder.mkdir()
    video = _undecodable_avi(folder / "clip.avi")
    for source in (str(video), f"file://{video}"):
        line = refused(
            ["watch", source, "--db", str(case_base), "--speed", "0"],
            folder,
            capsys,
            f"{source}: truncated or corrupt: decoded 0 of 30 frames",
        )
        assert "server" not in line


def test_the_chance_note_counts_the_clips_held_out_not_the_edited_cases(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two people whose correct and incorrect arm raises are each other's (every clip held
    out by person is answered wrong), 6 correct and 2 incorrect clips each: the commonest
    class is "correct", 12 of the 16 clips held out, 75 %. With ``--editor cnn`` the note
    gave the share among the cases the editor kept (10 of 16: "(60 %)"), not among the
    clips answered. The counts are unequal (12 against 4), so a repetition check's vote is
    class-balanced and the note compares the classes' mean held-out recall (0 %) with one
    over the classes (50 %) instead."""
    from features.poses import save_pose
    from posecbr.cli import main
    from tests.test_hunt34e import _arm_raises

    rows = ["path,label,subject,correct"]
    for subject, (good, bad) in (("s1", (40.0, 90.0)), ("s2", (90.0, 40.0))):
        for truth, top, n in (("true", good, 6), ("false", bad, 2)):
            for i in range(n):
                name = f"{subject}_{truth}_{i}.npz"
                # s2's a degree higher: no clip a copy of s1's (train refuses copies)
                save_pose(_arm_raises(top + 2.0 * i + (subject == "s2")), tmp_path / name)
                rows.append(f"{name},raise,{subject},{truth}")
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    argv = ["train", str(tmp_path / "labels.csv"), "--target", "correct", "--editor", "cnn"]
    assert main([*argv, "--db", str(tmp_path / "cb.sqlite")]) == 0
    out, err = capsys.readouterr()
    assert "CNN: 16 -> " in out  # the editor left fewer cases than clips
    notes = [line for line in err.splitlines() if "no better than" in line]
    assert len(notes) == 1
    assert "clips of each class were answered right 0 % of the time on average" in notes[0]
    assert "no better than always answering one of the 2 (50 %)" in notes[0]


def test_a_worker_whose_sigterm_cut_its_last_task_short_begins_no_other() -> None:
    """A SIGTERM that comes as a task returns, before ``run_task``'s ``finally`` has ended
    the worker, raises there, cutting that ``finally`` short: the pool took the interrupt as
    the task's result and handed the worker the next task queued, which it ran whole (the
    command, stopping its workers, waited for it). That worker, told to stop, now ends
    (status 143) before beginning it."""
    import subprocess
    import sys

    script = (
        "import features.interrupts as i\n"
        "i._TERMINATED.append(15)  # as raise_interrupt left it\n"
        "i.run_task(lambda: print('the next task ran', flush=True))\n"
    )
    root = Path(__file__).resolve().parents[1]
    run = subprocess.run(
        [sys.executable, "-c", script],
        cwd=root,
        env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert (run.returncode, run.stdout) == (143, ""), run.stderr
