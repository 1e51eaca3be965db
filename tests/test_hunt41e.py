"""Found by hunt 41e (the suite's costliest steps): every output ``convert`` writes was checked
against every file of the source, each resolved again for each output (two look-ups of each
input per clip written: 20 clips of UI-PRMD's 1,600 files took 7.6 s of CPU, the whole corpus
would have taken minutes). The files read are now looked up once (:class:`ReadFiles`); an
output is still refused when it is one of them by path, through a link or as a hard link."""

from __future__ import annotations

import os
import pathlib
import shutil
from pathlib import Path

import pytest

from features.errors import DataError
from features.fileio import ReadFiles, check_output
from posecbr.cli import main

ONE_MOVEMENT = ["--subjects", "s01", "--movements", "m01"]


def _resolves_to_convert(source: Path, out: Path, *only: str) -> int:
    """How many paths ``convert SOURCE --out OUT ONLY`` resolves."""
    calls = 0
    resolve = pathlib.Path.resolve

    def counted(self: Path, strict: bool = False) -> Path:
        nonlocal calls
        calls += 1
        return resolve(self, strict=strict)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(pathlib.Path, "resolve", counted)
        assert main(["convert", str(source), "--out", str(out), *ONE_MOVEMENT, *only]) == 0
    shutil.rmtree(out)
    return calls


def test_convert_looks_each_input_up_once_however_many_clips_it_writes(
    shared_data: Path, tmp_path: Path
) -> None:
    source = shared_data / "ui-prmd"
    one = _resolves_to_convert(source, tmp_path / "one", "--episodes", "1", "--correct")
    twenty = _resolves_to_convert(source, tmp_path / "twenty")  # 10 episodes x 2
    # the same inputs (every file of the source) either way: the 19 more clips may each cost
    # a few look-ups of their own output, not one of every input again (6,400 each before)
    assert one > 1600 and twenty - one <= 19 * 10, (one, twenty)


def test_an_output_that_is_an_input_is_found_by_path_link_or_hard_link(tmp_path: Path) -> None:
    first, second = tmp_path / "a.npz", tmp_path / "b.npz"
    first.write_bytes(b"a")
    second.write_bytes(b"b")
    reads = ReadFiles([first, second])
    os.link(second, tmp_path / "hard.npz")
    (tmp_path / "soft.npz").symlink_to(second)
    (tmp_path / "sub").mkdir()
    assert reads.overwritten_by(tmp_path / "sub" / ".." / "b.npz") == second
    assert reads.overwritten_by(tmp_path / "hard.npz") == second
    assert reads.overwritten_by(tmp_path / "soft.npz") == second
    assert reads.overwritten_by(tmp_path / "new.npz") is None
    (tmp_path / "c.npz").write_bytes(b"b")  # the same bytes, another file
    assert reads.overwritten_by(tmp_path / "c.npz") is None
    # of two inputs that are one file, the first listed is named
    assert (
        ReadFiles([tmp_path / "hard.npz", second]).overwritten_by(second) == tmp_path / "hard.npz"
    )
    with pytest.raises(DataError, match=r"would overwrite an input \(.*b\.npz\)"):
        check_output(tmp_path / "hard.npz", inputs=reads, what="pose file")
    assert check_output(tmp_path / "new.npz", inputs=reads) == tmp_path / "new.npz"


def test_a_folder_input_covers_its_labels_file(tmp_path: Path) -> None:
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "labels.csv").write_text("path,label\n")
    assert ReadFiles([tmp_path / "data"]).overwritten_by(tmp_path / "data" / "labels.csv") == (
        tmp_path / "data" / "labels.csv"
    )
