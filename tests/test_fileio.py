"""features.fileio: outputs appear whole or not at all and never replace an input."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.fileio import (
    atomic_path,
    check_output,
    staged_folder,
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
    with pytest.raises(DataError, match="cannot write: File too large") as info:
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
