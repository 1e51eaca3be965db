"""features.fileio: outputs appear whole or not at all and never replace an input."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from features.errors import DataError
from features.fileio import atomic_path, check_output, write_json_atomic, write_text_atomic


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
