"""Results files written as one, found by hunt 40j: compare wrote results.json, then
results.csv, each atomically but in turn, so a disk full or a write refused on the second left
the new results.json beside the earlier run's results.csv (or alone in a new --out folder);
convert's staged clips were moved into the folder one at a time, so a move refused halfway
left some clips new and the rest (and labels.csv) the earlier ones."""

from __future__ import annotations

import errno
import hashlib
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

import features.fileio as fileio
from features.errors import DataError
from features.fileio import replace_together, staged_folder, write_together
from posecbr.cli import main

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"

THREE = ["compare", str(DEMO), "--subjects", "s01", "--labels",
         "deep_squat,sit_to_stand,standing_shoulder_abduction", "--folds", "3",
         "--similarities", "euclidean", "--features", "fluents", "--no-dad", "--peers",
         "none", "--explain", "0"]  # fmt: skip
TWO = [*THREE]
TWO[TWO.index("--labels") + 1] = "deep_squat,sit_to_stand"

ENOSPC = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
EIO = OSError(errno.EIO, os.strerror(errno.EIO))


def _digests(folder: Path) -> dict[str, str]:
    """Every entry of ``folder`` (hidden ones too) and its bytes' digest."""
    return {p.name: hashlib.md5(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


@pytest.fixture
def earlier(compared_three: Path) -> Path:
    """The --out folder of an earlier comparison of three activities (six pictures): THREE's,
    made once in the session (tests/conftest.py), to copy."""
    return compared_three


def _refuse_making(monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    """The disk full as a file for output ``name`` is made (mkstemp's ENOSPC)."""
    real = fileio.temporary_file

    def temporary_file(dest: str | Path, suffix: str = ".tmp") -> Path:
        if Path(dest).name == name:
            raise ENOSPC
        return real(dest, suffix)

    monkeypatch.setattr(fileio, "temporary_file", temporary_file)


def _refuse_renaming(monkeypatch: pytest.MonkeyPatch, name: str, once: bool = True) -> None:
    """An I/O error as a file is first renamed to ``name`` (``once`` False: every time)."""
    real, refused = os.replace, []

    def replace(src: str | Path, dst: str | Path) -> None:
        if Path(dst).name == name and not (once and refused):
            refused.append(dst)
            raise EIO
        real(src, dst)

    monkeypatch.setattr(os, "replace", replace)


def _no_hard_links(monkeypatch: pytest.MonkeyPatch) -> None:
    """A file system without hard links (FAT): ``os.link`` refused (EPERM)."""

    def link(*args: object, **kwargs: object) -> None:
        raise OSError(errno.EPERM, os.strerror(errno.EPERM))

    monkeypatch.setattr(os, "link", link)


def _compare_refused(
    refuse: Callable[[pytest.MonkeyPatch, str], None],
    out: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> str:
    """The comparison of two activities into ``out``, results.csv refused by ``refuse``:
    exit 1; returns the last line it said."""
    capsys.readouterr()
    refuse(monkeypatch, "results.csv")
    assert main([*TWO, "--out", str(out)]) == 1
    return capsys.readouterr().err.splitlines()[-1]


@pytest.mark.parametrize("refuse", [_refuse_making, _refuse_renaming], ids=["enospc", "eio"])
def test_compare_results_csv_refused_keeps_the_earlier_run_whole(
    tmp_path: Path,
    earlier: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    refuse: Callable[[pytest.MonkeyPatch, str], None],
) -> None:
    # before: exit 1, "o/results.csv: cannot write: ...", and results.json of the two
    # activities beside results.csv and the six pictures of the earlier run of three
    out = tmp_path / "o"
    shutil.copytree(earlier, out)
    before = _digests(out)
    said = _compare_refused(refuse, out, capsys, monkeypatch)
    assert _digests(out) == before  # no hidden temporary left either
    why = "the disk is full (No space left on device): free some space and run again"
    why = why if refuse is _refuse_making else "Input/output error"
    assert said == (
        f"posecbr compare: error: {out / 'results.csv'}: cannot write: {why}; none of the 2 files"
        " written (the earlier results.json and results.csv kept as they were)"
    )


def test_compare_results_csv_refused_in_a_new_folder_leaves_no_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # before: the new folder held results.json alone, a table said nowhere to be missing
    out = tmp_path / "o"
    said = _compare_refused(_refuse_making, out, capsys, monkeypatch)
    assert sorted(p.name for p in tmp_path.iterdir()) == []
    assert said == (
        f"posecbr compare: error: {out / 'results.csv'}: cannot write: the disk is full (No"
        " space left on device): free some space and run again; none of the 2 files written"
    )


def _write(text: str):  # noqa: ANN202 - a writer for write_together
    return lambda path: Path(path).write_text(text, encoding="utf-8")


def test_write_together_puts_back_the_renames_done_before_one_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "a.json").write_text("old a", encoding="utf-8")
    files = [(tmp_path / n, _write(f"new {n}")) for n in ("a.json", "b.csv", "c.txt")]
    _refuse_renaming(monkeypatch, "c.txt")
    with pytest.raises(DataError) as err:
        write_together(files)
    assert str(err.value) == (
        f"{tmp_path / 'c.txt'}: cannot write: Input/output error; none of the 3"
        " files written (the earlier a.json kept as it was)"
    )
    # a.json as it was, b.csv (renamed before c.txt was refused) gone again, nothing hidden
    assert {p.name: p.read_text(encoding="utf-8") for p in tmp_path.iterdir()} == {
        "a.json": "old a"
    }
    monkeypatch.undo()
    write_together(files)
    assert {p.name: p.read_text(encoding="utf-8") for p in tmp_path.iterdir()} == {
        "a.json": "new a.json",
        "b.csv": "new b.csv",
        "c.txt": "new c.txt",
    }


def test_replace_together_puts_back_without_hard_links(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # a file system without hard links (FAT): the earlier file is set aside by renaming
    for n in ("x", "y"):
        (tmp_path / n).write_text(f"old {n}", encoding="utf-8")
        (tmp_path / f"new_{n}").write_text(f"new {n}", encoding="utf-8")
    _no_hard_links(monkeypatch)
    _refuse_renaming(monkeypatch, "y")
    moves = [(tmp_path / "new_x", tmp_path / "x"), (tmp_path / "new_y", tmp_path / "y")]
    with pytest.raises(DataError, match="cannot write: Input/output error"):
        replace_together(moves)
    assert (tmp_path / "x").read_text(encoding="utf-8") == "old x"
    assert (tmp_path / "y").read_text(encoding="utf-8") == "old y"
    hidden = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
    assert hidden == []


def test_staged_folder_with_a_move_refused_keeps_the_folder_as_it_was(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # before: a.npz and b.npz new (moved first), labels.csv the earlier one naming the
    # earlier clips: convert's output folder half of each run
    out = tmp_path / "out"
    out.mkdir()
    for n in ("a.npz", "b.npz", "labels.csv"):
        (out / n).write_text(f"old {n}", encoding="utf-8")
    _refuse_renaming(monkeypatch, "labels.csv")
    with pytest.raises(DataError), staged_folder(out, last={"labels.csv"}) as stage:
        for n in ("a.npz", "b.npz", "labels.csv"):
            (stage / n).write_text(f"new {n}", encoding="utf-8")
    assert {p.name: p.read_text(encoding="utf-8") for p in out.iterdir()} == {
        "a.npz": "old a.npz",
        "b.npz": "old b.npz",
        "labels.csv": "old labels.csv",
    }


def test_extract_listing_refused_keeps_the_earlier_label_file_copies(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # before: the disk full at labels.csv left the new copy of a.txt (its labels changed)
    # under the earlier labels.csv, which said nothing of it
    from features.label_tracks import LabelTrack
    from posecbr.commands.extract import Job, Listing, write_listing

    out = tmp_path / "out"
    out.mkdir()
    (tmp_path / "a.txt").write_text("squat\nsquat\nlunge\n", encoding="utf-8")
    (out / "a.txt").write_text("squat\nsquat\nsquat\n", encoding="utf-8")  # an earlier run's
    (out / "labels.csv").write_text("path,label_file\na.npz,a.txt\n", encoding="utf-8")
    before = _digests(out)
    job = Job(video=tmp_path / "a.mp4", out=out / "a.npz", track=LabelTrack(tmp_path / "a.txt"))
    listing = Listing(out / "labels.csv", {tmp_path / "a.txt": out / "a.txt"}, [])
    _refuse_making(monkeypatch, "labels.csv")
    with pytest.raises(DataError) as err:
        write_listing(listing, out, [job], {out / "a.npz"})
    assert _digests(out) == before
    assert str(err.value) == (
        f"{out / 'labels.csv'}: cannot write: the disk is full (No space left on device): free"
        " some space and run again; none of the 2 files"
        " written (the earlier a.txt and labels.csv kept as they were); the pose files are"
        " written (extract them again to list them)"
    )
    monkeypatch.undo()
    write_listing(listing, out, [job], {out / "a.npz"})
    assert (out / "a.txt").read_text(encoding="utf-8") == "squat\nsquat\nlunge\n"
    assert (out / "labels.csv").read_text(encoding="utf-8").splitlines() == [
        "path,label,subject,label_file,label_block_s,label_names",
        "a.npz,,,a.txt,,",
    ]


def test_an_earlier_file_that_cannot_be_put_back_is_named_where_it_is(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # no hard links, and every rename to y refused: y's earlier file, set aside by renaming,
    # cannot go back; the message names the hidden file holding it
    (tmp_path / "y").write_text("old y", encoding="utf-8")
    (tmp_path / "new_y").write_text("new y", encoding="utf-8")
    _no_hard_links(monkeypatch)
    _refuse_renaming(monkeypatch, "y", once=False)
    with pytest.raises(DataError) as err:
        replace_together([(tmp_path / "new_y", tmp_path / "y")])
    (aside,) = [p for p in tmp_path.iterdir() if p.name.startswith(".y.")]
    assert aside.read_text(encoding="utf-8") == "old y"
    assert str(err.value) == (
        f"{tmp_path / 'y'}: cannot write: Input/output error; not written; the earlier y"
        f" could not be put back: left as {aside.name}"
    )
