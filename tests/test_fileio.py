"""features.fileio: outputs appear whole or not at all and never replace an input."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.fileio import (
    atomic_path,
    check_output,
    remove_stale_temporaries,
    staged_folder,
    staging_folder,
    write_json_atomic,
    write_text_atomic,
)
from features.poses import PoseSequence, save_pose


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    out = tmp_path / "r.json"
    out.write_text("old")
    with pytest.raises(RuntimeError), atomic_path(out) as tmp:
        tmp.write_text("half")
        raise RuntimeError("killed mid-write")
    assert out.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.json"]


def test_a_finished_write_replaces_the_file_with_the_usual_permissions(tmp_path: Path) -> None:
    out = write_text_atomic(tmp_path / "a.txt", "héllo\r\n")
    assert out.read_bytes() == "héllo\r\n".encode()
    mask = os.umask(0)
    os.umask(mask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~mask
    write_json_atomic(out, {"x": float("nan"), "y": "é"})
    assert out.read_text(encoding="utf-8") == '{\n "x": NaN,\n "y": "é"\n}\n'


def test_check_output_refuses_folders_missing_folders_and_inputs(tmp_path: Path) -> None:
    src = tmp_path / "in.npz"
    src.write_bytes(b"x")
    with pytest.raises(DataError, match="is a folder"):
        check_output(tmp_path)
    with pytest.raises(DataError, match="does not exist"):
        check_output(tmp_path / "no" / "out.json")
    with pytest.raises(DataError, match="overwrite an input"):
        check_output(tmp_path / "." / "in.npz", inputs=[src])
    link = tmp_path / "link.npz"
    link.symlink_to(src)
    with pytest.raises(DataError, match="overwrite an input"):
        check_output(link, inputs=[src])
    with pytest.raises(DataError, match="already exists"):
        check_output(src, must_not_exist=True)
    assert check_output(tmp_path / "new.json", inputs=[src]) == tmp_path / "new.json"


def _pose(frames: int, seed: int) -> PoseSequence:
    """Random ``(frames, 3, 3)`` positions: a pose file that hardly compresses (72 bytes a
    frame)."""
    positions = np.random.default_rng(seed).normal(size=(frames, 3, 3))
    return PoseSequence(positions=positions, joint_names=("a", "b", "c"), fps=30.0)


def test_a_pose_file_that_cannot_be_written_leaves_the_old_one(
    tmp_path: Path, file_size_limit: Callable[[int], None]
) -> None:
    out = save_pose(_pose(10, 0), tmp_path / "clip.npz")
    before = out.read_bytes()
    file_size_limit(16 * 1024)  # the new file (~70 kB of random floats) does not fit
    limit = r"cannot write: the file would grow past a size limit such as `ulimit -f` \(File"
    with pytest.raises(DataError, match=limit + r" too large\)$") as info:
        save_pose(_pose(1000, 1), out)
    assert str(out) in str(info.value)
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.npz"]


def test_a_staged_folder_is_all_or_nothing(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "labels.csv").write_text("old")
    with pytest.raises(RuntimeError), staged_folder(out) as stage:
        (stage / "a.npz").write_bytes(b"new a")
        raise RuntimeError("the second clip is bad")
    assert sorted(p.name for p in out.iterdir()) == ["labels.csv"]
    assert (out / "labels.csv").read_text() == "old"
    new = tmp_path / "new"
    with pytest.raises(RuntimeError), staged_folder(new) as stage:
        raise RuntimeError("nothing written")
    assert not new.exists()  # the folder the block made is gone again
    with staged_folder(out, last={"labels.csv"}) as stage:
        (stage / "labels.csv").write_text("a.npz")
        (stage / "a.npz").write_bytes(b"new a")
    assert sorted(p.name for p in out.iterdir()) == ["a.npz", "labels.csv"]
    assert (out / "labels.csv").read_text() == "a.npz"


def _dead_pid() -> int:
    """The id of a process that has finished (and been reaped)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_the_next_writer_removes_temporaries_of_dead_writers_only(tmp_path: Path) -> None:
    host = socket.gethostname()
    dead, live = _dead_pid(), os.getppid()
    out = tmp_path / "r.json"
    stale = tmp_path / f".r.json.pid{dead}@{host}.k2x9.tmp"
    working = tmp_path / f".r.json.pid{live}@{host}.a7q1.tmp"
    elsewhere = tmp_path / f".r.json.pid{dead}@another-machine.b3z0.tmp"
    other_output = tmp_path / f".s.json.pid{dead}@{host}.c4y8.tmp"
    for p in (stale, working, elsewhere, other_output):
        p.write_text("half")
    write_json_atomic(out, {"x": 1})
    assert json.loads(out.read_text()) == {"x": 1}
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted([out.name, working.name, elsewhere.name, other_output.name])


def test_a_killed_writer_s_temporary_goes_with_the_next_write(tmp_path: Path) -> None:
    """A real kill -9 in the middle of a write, then the next write of the same file."""
    out = tmp_path / "r.txt"
    code = (
        "import sys, time; from features.fileio import atomic_path\n"
        "with atomic_path(sys.argv[1]) as tmp:\n"
        "    tmp.write_text('half'); print('WRITING', flush=True); time.sleep(60)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    proc = subprocess.Popen([sys.executable, "-c", code, str(out)], stdout=subprocess.PIPE,
                            text=True, env=env)  # fmt: skip
    assert proc.stdout is not None and proc.stdout.readline().strip() == "WRITING"
    proc.kill()
    proc.wait()
    left = [p.name for p in tmp_path.iterdir()]
    assert len(left) == 1 and left[0].startswith(f".r.txt.pid{proc.pid}@")
    write_text_atomic(out, "whole")
    assert [p.name for p in tmp_path.iterdir()] == ["r.txt"]
    assert out.read_text() == "whole"


def test_a_stale_staging_folder_is_removed_by_the_next_one(tmp_path: Path) -> None:
    dead = _dead_pid()
    stale = tmp_path / f".posecbr-convert.pid{dead}@{socket.gethostname()}.x1"
    stale.mkdir()
    (stale / ".clip.npz.tmp").write_text("half")
    stage = staging_folder(tmp_path, "posecbr-convert")
    assert sorted(p.name for p in tmp_path.iterdir()) == [stage.name]
    assert remove_stale_temporaries(tmp_path, "posecbr-convert") == 0  # its writer: alive


def test_an_output_with_a_long_legal_name_is_written(tmp_path: Path) -> None:
    """A 250-byte name is legal (the file system takes 255), but its temporary, the name
    with the writer and a random part added, was not: "File name too long" for a name
    ``touch`` creates. The temporary carries the name's start and a digest of it, and a dead
    writer's temporary of that output is still found and removed."""
    name = "é" * 120 + "x.json"  # 246 bytes in UTF-8
    assert len(name.encode()) == 246
    out = tmp_path / name
    host = socket.gethostname()
    digest = __import__("hashlib").sha256(name.encode()).hexdigest()[:16]
    start = name.encode()[:143].decode("utf-8", "ignore")  # 160 bytes kept, 17 the digest's
    stale = tmp_path / f".{start}~{digest}.pid{_dead_pid()}@{host}.k2x9.tmp"
    stale.write_text("half")
    write_json_atomic(out, {"x": 1})
    assert json.loads(out.read_text()) == {"x": 1}
    assert [p.name for p in tmp_path.iterdir()] == [name]


def test_an_output_on_a_device_or_pipe_is_refused_and_left_as_it_was(tmp_path: Path) -> None:
    """``--plot`` onto a special file replaced the node with a regular file (as root,
    ``/dev/null`` became a picture)."""
    import stat

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(DataError, match="not a regular file"):
        check_output(fifo)
    with pytest.raises(DataError, match="not a regular file"), atomic_path(fifo) as tmp:
        tmp.write_bytes(b"never")
    assert stat.S_ISFIFO(fifo.lstat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe"]  # no temporary either


def test_check_output_refuses_the_files_a_reader_opens_beside_its_input(tmp_path: Path) -> None:
    """A UI-PRMD positions file is read with its angles file (beside it or in ``Angles/``),
    an AMC recording with an ``.asf`` beside it: neither may be overwritten by an output."""
    kinect = tmp_path / "Kinect"
    (kinect / "Positions").mkdir(parents=True)
    (kinect / "Angles").mkdir()
    positions = kinect / "Positions" / "m01_s01_e01_positions.txt"
    angles = kinect / "Angles" / "m01_s01_e01_angles.txt"
    for p in (positions, angles):
        p.write_text("1,2,3\n")
    with pytest.raises(DataError, match="overwrite an input"):
        check_output(angles, inputs=[positions])
    amc, asf = tmp_path / "13_29.amc", tmp_path / "skeleton.ASF"
    amc.write_text(":FULLY-SPECIFIED\n")
    asf.write_text(":version 1.10\n")
    with pytest.raises(DataError, match=r"overwrite an input \(.*skeleton\.ASF\)"):
        check_output(asf, inputs=[amc])
    assert check_output(tmp_path / "new.png", inputs=[positions, amc]) == tmp_path / "new.png"
