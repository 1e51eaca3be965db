"""Helpers for the bad-input suites (``tests/test_bad_input_*.py``): run a command on a
folder of files and check that it refused with one clear line and left every file as it was.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import shutil
import sqlite3
import subprocess
import sys
import uuid
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from features.poses import PoseSequence, save_pose
from features.skeleton import BLAZEPOSE_33
from posecbr.cli import main
from tests.bodies import standing, to_sequence

ROOT = Path(__file__).resolve().parents[1]


def snapshot(root: Path) -> dict[str, str]:
    """Every file under ``root`` with its sha256, and every folder: what "unchanged" means."""
    out: dict[str, str] = {}
    for p in sorted(root.rglob("*")):
        key = str(p.relative_to(root))
        if p.is_symlink():
            out[key] = "link -> " + os.readlink(p)
        elif p.is_dir():
            out[key] = "folder"
        else:
            out[key] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def refused(
    argv: list[str],
    root: Path,
    capsys: pytest.CaptureFixture[str],
    *needles: str,
) -> str:
    """Run ``posecbr argv`` in-process: it must exit 1 with one line on stderr holding every
    needle, print nothing on stdout, and leave every file and folder under ``root`` as it
    was (no output, no temporary file). Returns the line."""
    before = snapshot(root)
    code = main(argv)
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 1, (code, captured.err)
    assert len(lines) == 1, captured.err
    assert "Traceback" not in captured.err
    command = " ".join(argv[:2]) if argv[0] == "casebase" else argv[0]  # with its action
    assert lines[0].startswith(f"posecbr {command}: error: "), lines[0]
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    assert captured.out == ""
    assert_unchanged(root, before)
    return lines[0]


def assert_unchanged(root: Path, before: dict[str, str]) -> None:
    """Every file and folder under ``root`` as in ``before``; names what differs."""
    after = snapshot(root)
    changed = sorted(k for k in before.keys() & after.keys() if before[k] != after[k])
    added, removed = sorted(after.keys() - before.keys()), sorted(before.keys() - after.keys())
    assert after == before, f"changed {changed}, added {added}, removed {removed}"


def refused_in_process(
    argv: list[str], root: Path, *needles: str, env: dict[str, str] | None = None
) -> str:
    """As :func:`refused`, in a real ``python -m posecbr`` process (the exit status and the
    absence of a crash are the point)."""
    before = snapshot(root)
    proc = subprocess.run(
        [sys.executable, "-m", "posecbr", *argv],
        cwd=ROOT,
        env={**os.environ, "POSECBR_NO_PROGRESS": "1", **(env or {})},
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 1, (proc.returncode, proc.stderr[-2000:])
    assert len(lines) == 1, proc.stderr[-2000:]
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    assert_unchanged(root, before)
    return lines[0]


def standing_clip(frames: int = 8) -> PoseSequence:
    """A person standing still, every BlazePose joint present (no source: a file written
    from it names itself)."""
    return replace(to_sequence(*[standing()] * frames), source="")


def good_arrays(frames: int = 8) -> dict[str, object]:
    """The arrays of a valid pose file, to spoil one at a time."""
    seq = standing_clip(frames)
    return {
        "positions": seq.positions,
        "joint_names": np.array(BLAZEPOSE_33),
        "fps": 30.0,
        "confidence": np.full(seq.positions.shape[:2], 0.9),
        "metadata": json.dumps({"label": "squat", "subject": "s01"}),
    }


def pose_file(path: Path, **changes: object) -> Path:
    """A pose file written with ``np.savez`` from :func:`good_arrays` with ``changes``
    (a value of None drops the key)."""
    arrays = {**good_arrays(), **changes}
    np.savez(path, **{k: v for k, v in arrays.items() if v is not None})
    return path


def good_pose_file(dest: Path, /, frames: int = 8, **metadata: object) -> Path:
    """A valid pose file of a person standing, with ``metadata``."""
    seq = standing_clip(frames).with_metadata(**metadata)
    return save_pose(seq, dest)


def small_case_base(folder: Path) -> Path:
    """A small real case base (SQLite) in ``folder``, trained by the command from synthetic
    arm movements (three activities, three clips each, in ``folder/train/<activity>``).

    Trained once in each process (:func:`_small_template`; about 60 callers, 0.3 s of CPU
    each): ``folder`` gets a copy of its clips and of its case base, with what training the
    copied clips in ``folder`` would store differently: each case's source (the copy's
    clip) and the case base's identity (a new one)."""
    template = _small_template()
    shutil.copytree(template / "train", folder / "train", copy_function=shutil.copyfile,
                    dirs_exist_ok=True)  # fmt: skip
    db = folder / "cb.sqlite"
    shutil.copyfile(template / "cb.sqlite", db)
    con = sqlite3.connect(db)
    try:
        with con:
            con.execute(
                "UPDATE cases SET source = ? || substr(source, ?)",
                (str(folder / "train"), len(str(template / "train")) + 1),
            )
            con.execute("UPDATE case_bases SET uid = ?", (uuid.uuid4().hex,))
    finally:
        con.close()
    return db


_SMALL_TEMPLATE: dict[int, Path] = {}


def _small_template() -> Path:
    """The folder of this process's small case base (``cb.sqlite`` and its ``train`` clips),
    trained by the command the first time it is asked for, removed when the process ends."""
    if os.getpid() not in _SMALL_TEMPLATE:
        import atexit
        import tempfile

        from tests.test_cbr_cli import _write_classes

        folder = Path(tempfile.mkdtemp(prefix="posecbr-small-case-base-"))
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
        data = _write_classes(folder / "train", 3, 5)
        argv = ["train", str(data), "--db", str(folder / "cb.sqlite"), "--mirror", "off",
                "--feature-weights", "none", "--phases", "0"]  # fmt: skip
        said = io.StringIO()
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            assert main(argv) == 0, said.getvalue()
        _SMALL_TEMPLATE[os.getpid()] = folder
    return _SMALL_TEMPLATE[os.getpid()]


def read_only_mounts_work() -> bool:
    """Whether this machine can make a private read-only mount (``unshare -rm``, ``mount``):
    how tests give a folder that not even root can write to."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        script = f"mount --bind {d} {d} && mount -o remount,ro,bind {d} {d}"
        try:
            done = subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True)
        except OSError:
            return False
        return done.returncode == 0


def posecbr_on_read_only_mount(
    target: Path, argv: list[str], writable: Path | None = None
) -> subprocess.CompletedProcess[str]:
    """``python -m posecbr argv`` in a child process with ``target`` (a folder or a file) on a
    private read-only mount, which not even root can write to (:func:`read_only_mounts_work`).
    Exit 99 without running it when the mount is not really read-only: a file could be made
    in the folder ``target``, or, given ``writable``, that file is writable (access(2))."""
    really = (
        f"touch {target}/probe 2>/dev/null && exit 99; "
        if writable is None
        else f"[ -w {writable} ] && exit 99; "
    )
    script = (
        f"mount --bind {target} {target} && mount -o remount,ro,bind {target} {target} && "
        f'{really}exec "$0" -m posecbr "$@"'
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
    return subprocess.run(
        ["unshare", "-rm", "sh", "-c", script, sys.executable, *argv],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=300,
    )  # fmt: skip


LEG_BVH_HIERARCHY = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 -40 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 -40 0
      }
    }
  }
}
"""
"""A hand-made BVH skeleton of one left leg (lengths in the file's unit): the root Hips with
position and rotation channels, LeftUpLeg 10 along +x from it, LeftLeg (the knee) 40 below
that and the foot's end site 40 below the knee."""


def leg_bvh(frame_time: str, *frames: str) -> str:
    """A BVH file of :data:`LEG_BVH_HIERARCHY` whose motion is ``frames`` (one line of 12
    channel values a frame), ``frame_time`` as its Frame Time line writes it."""
    motion = "".join(f"{line}\n" for line in frames)
    return f"{LEG_BVH_HIERARCHY}MOTION\nFrames: {len(frames)}\nFrame Time: {frame_time}\n{motion}"


def too_wide_video(path: Path, frames: int) -> Path:
    """An MJPG AVI of ``frames`` grey frames 8192 x 16 pixels (one pixel wider than an MP4
    frame can be; nobody in view)."""
    import cv2

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 10.0, (8192, 16))
    for k in range(frames):
        writer.write(np.full((16, 8192, 3), 5 * k, np.uint8))
    writer.release()
    return path
