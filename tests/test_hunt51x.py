"""Hunt 51x: a write past a file size limit said as every writer says it, and a tab-separated
label file with an empty cell.

- Every writer of the command line (pose files of ``convert`` and ``extract``, ``casebase
  export``, JSON results, timeline pictures) says a full disk, a quota used up and a file
  size limit (``ulimit -f``, RLIMIT_FSIZE: EFBIG) as the case base store, overlays and
  ``watch --out`` do, through :func:`features.fileio.write_error`; before, a pose file said
  Python's "cannot write: File too large", ``convert`` named its hidden staging folder's
  copy instead of the pose file, and a raw EFBIG reaching the command was "a bug in posecbr"
  (exit 70).
- Under a file size limit no compiled module (``.pyc``) is written: Python 3.11 wrote each
  in one write(2) and took the short write for the whole, so a ``posecbr`` run under
  ``ulimit -f 16`` left its modules' ``.pyc`` cut at the limit, and every later run, with
  no limit, ended in a raw traceback ("EOFError: marshal data too short").
- A label file saved as a spreadsheet's "Tab delimited" text with a cell left empty
  (``walk<tab><tab>sit``) is refused naming its line, as the same row saved as CSV is:
  a run of tabs was one separator, and every label after the gap was read a frame early.
"""

from __future__ import annotations

import errno
import marshal
import os
import resource
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from features.errors import DataError
from features.fileio import write_together
from features.label_tracks import read_label_track
from features.poses import BLAZEPOSE_33, PoseSequence, save_pose
from posecbr.cli import main
from tests.badinput import ROOT, good_pose_file, small_case_base

LIMIT = "cannot write: the file would grow past a size limit such as `ulimit -f` (File too large)"


def _noise_pose(path: Path, frames: int) -> Path:
    """A pose file of random positions: it hardly compresses (33 x 3 x 8 bytes a frame)."""
    positions = np.random.default_rng(0).normal(size=(frames, len(BLAZEPOSE_33), 3))
    return save_pose(PoseSequence(positions, tuple(BLAZEPOSE_33), 30.0), path)


def _error_line(capsys: pytest.CaptureFixture[str]) -> str:
    [line] = capsys.readouterr().err.splitlines()
    return line


def test_convert_past_a_file_size_limit_names_the_pose_file_and_the_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], file_size_limit: Callable[[int], None]
) -> None:
    """Before: "<out>/.posecbr-stage.<pid>@<host>.<random>/a.npz: cannot write: File too
    large" (the hidden copy named, Python's words)."""
    _noise_pose(tmp_path / "ds" / "walk" / "a.npz", 100)  # about 80 kB
    out = tmp_path / "out"
    capsys.readouterr()
    file_size_limit(16 << 10)
    assert main(["convert", str(tmp_path / "ds"), "--out", str(out)]) == 1
    assert _error_line(capsys) == f"posecbr convert: error: {out / 'a.npz'}: {LIMIT}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds"]  # the folder it made gone


def test_casebase_export_past_a_file_size_limit_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], file_size_limit: Callable[[int], None]
) -> None:
    db = small_case_base(tmp_path)
    out = tmp_path / "cases.npz"
    out.write_bytes(b"earlier")
    capsys.readouterr()
    file_size_limit(1 << 10)
    assert main(["casebase", "export", "--db", str(db), "--out", str(out)]) == 1
    assert _error_line(capsys) == f"posecbr casebase export: error: {out}: {LIMIT}"
    assert out.read_bytes() == b"earlier"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cases.npz", "cb.sqlite", "train"]


def test_files_written_together_past_a_limit_say_so_and_leave_none(
    tmp_path: Path, file_size_limit: Callable[[int], None]
) -> None:
    """What ``extract`` (a pose file and its overlay), ``segment`` and ``compare`` (results
    and pictures) write as one; the second file over the limit."""
    small, large = tmp_path / "small.json", tmp_path / "large.npz"
    large.write_bytes(b"earlier")
    file_size_limit(4 << 10)
    files: list[tuple[Path, Callable[[Path], Any]]] = [
        (small, lambda p: p.write_bytes(bytes(100))),
        (large, lambda p: p.write_bytes(bytes(8 << 10))),
    ]
    with pytest.raises(DataError) as caught:
        write_together(files)
    assert str(caught.value) == (
        f"{large}: {LIMIT}; none of the 2 files written (the earlier large.npz kept as it was)"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["large.npz"]
    assert large.read_bytes() == b"earlier"


@pytest.mark.parametrize(
    ("code", "said"),
    [
        (errno.EFBIG, LIMIT),
        (
            errno.ENOSPC,
            "cannot write: the disk is full (No space left on device): free some space and run"
            " again",
        ),
    ],
    ids=["EFBIG", "ENOSPC"],
)
def test_a_write_refused_for_room_outside_posecbr_s_writers_is_said_as_theirs(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    code: int,
    said: str,
) -> None:
    """A raw OSError reaching the command (a library's own cache file, written as it works).
    Before: EFBIG "internal error, a bug in posecbr" (exit 70); ENOSPC the bare "No space
    left on device"."""
    import features.fluents

    pose = good_pose_file(tmp_path / "clip.npz")

    def fail(*args: Any, **kwargs: Any) -> None:
        raise OSError(code, os.strerror(code), str(tmp_path / "cache.nbc"))

    monkeypatch.setattr(features.fluents, "evaluate", fail)
    monkeypatch.delenv("POSECBR_DEBUG", raising=False)
    capsys.readouterr()
    assert main(["describe", str(pose)]) == 1
    assert _error_line(capsys) == f"posecbr describe: error: {tmp_path / 'cache.nbc'}: {said}"


def test_a_command_under_a_file_size_limit_leaves_no_compiled_module_cut(tmp_path: Path) -> None:
    """The command's modules compiled afresh (a cache folder of their own) under a limit of
    4 KiB, which most of their ``.pyc`` files pass. Before: 25 of the 40 written (posecbr/cli.py
    among them) were left 4096 bytes long, and the next run failed importing them."""
    prefix = tmp_path / "pyc"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONPYCACHEPREFIX": str(prefix)}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    hard = resource.getrlimit(resource.RLIMIT_FSIZE)[1]

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, hard))

    done = subprocess.run(
        [sys.executable, "-m", "posecbr", "thresholds"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, preexec_fn=limit,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "fluents" in done.stdout  # the thresholds table printed

    def cut(pyc: Path) -> bool:
        try:
            marshal.loads(pyc.read_bytes()[16:])  # after the 16-byte header
        except (EOFError, ValueError):
            return True
        return False

    project = prefix / ROOT.relative_to(ROOT.anchor)  # the stdlib's: before posecbr runs
    venv = prefix / Path(sys.prefix).relative_to(Path(sys.prefix).anchor)  # as site's: before
    cuts = [p for p in project.rglob("*.pyc") if not p.is_relative_to(venv) and cut(p)]
    assert [p.name for p in cuts] == []


def test_a_tab_separated_label_file_with_an_empty_cell_is_refused(tmp_path: Path) -> None:
    """Frame 4's cell left empty on the second row of a "Tab delimited" save: read as one
    separator, sit would fall on frame 4, a frame early. Before: read as 7 labels."""
    path = tmp_path / "labels.txt"
    path.write_text("walk\twalk\nwalk\t\tsit\tsit\tsit\tsit\n")
    with pytest.raises(DataError) as caught:
        read_label_track(path)
    assert str(caught.value) == (
        f"{path}: line 2: an empty label between tabs after label 3 ('walk'); a label file"
        " gives every frame or block a label (read without one, the labels after it would"
        " fall a frame or block early): write one there (to line labels up, use spaces)"
    )
    # a tab and spaces in one cell's place: empty too (label 1 on line 1)
    path.write_text("walk\t \tsit\n")
    with pytest.raises(
        DataError, match=r"^\S+: line 1: an empty label between tabs after label 1 "
    ):
        read_label_track(path)
    # one tab between labels, runs of spaces, a line indented, empty cells ending a row
    path.write_text("walk\twalk  walk\n\t\tsit\tsit   sit\tsit\t\t\n")
    assert read_label_track(path) == ["walk"] * 3 + ["sit"] * 4
