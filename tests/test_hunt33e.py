"""A new user's walkthrough (hunt 33e): the README from the top, every command's help, the
JSON outputs, plausible mistakes and the words and units the commands share."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from features.errors import DataError
from features.fileio import check_output
from posecbr.cli import main
from tests.badinput import good_pose_file, refused


@pytest.fixture
def stream_link(tmp_path: Path) -> Iterator[Path]:
    """``root/out.png``, a link to ``/proc/self/fd/N`` for a file this process has open,
    as ``/dev/stdout`` is a link to ``/proc/self/fd/1`` (a regular file at its end when
    standard output is redirected to one: ``posecbr ... --json /dev/stdout > results``)."""
    root = tmp_path / "root"
    root.mkdir()
    with open(tmp_path / "redirected.txt", "w") as stream:
        link = root / "out.png"
        link.symlink_to(f"/proc/self/fd/{stream.fileno()}")
        assert link.is_file()  # what let it through: the link leads to a regular file
        yield link


def test_check_output_refuses_a_name_of_an_open_stream(stream_link: Path) -> None:
    # before: accepted, and the writer's rename then replaced the link itself with a file: run
    # as root with standard output redirected, `compare --json /dev/stdout` made /dev/stdout
    # an ordinary file for every process on the machine
    for path in (stream_link, Path(f"/proc/self/fd/{os.open(os.devnull, os.O_RDONLY)}")):
        with pytest.raises(DataError, match="names standard output or another open stream"):
            check_output(path, what="report")
    assert check_output(stream_link.parent / "real.json") == stream_link.parent / "real.json"


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="no /proc")
def test_describe_plot_to_a_name_of_standard_output_is_refused(
    stream_link: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = good_pose_file(stream_link.parent / "clip.npz", frames=12)
    line = refused(["describe", str(clip), "--plot", str(stream_link)], stream_link.parent,
                   capsys, "out.png: names standard output")  # fmt: skip
    assert line.endswith("name a file for the picture")
    assert stream_link.is_symlink()


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="no /proc")
def test_train_db_to_a_name_of_standard_output_is_refused(
    stream_link: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the SQLite database was written through the link into the redirected output
    data = stream_link.parent / "data"
    for label in ("stand", "wait"):
        (data / label).mkdir(parents=True)
        for i in range(2):
            good_pose_file(data / label / f"c{i}.npz", frames=40)
    refused(["train", str(data), "--db", str(stream_link)], stream_link.parent, capsys,
            "out.png: names standard output", "case base file")  # fmt: skip
    assert (stream_link.parent.parent / "redirected.txt").read_bytes() == b""


@pytest.mark.parametrize(
    ("argv", "command"),
    [
        (["classify", "clip.npz", "--db", "cb.sqlite", "--verbse"], "posecbr classify"),
        (["casebase", "info", "--db", "cb.sqlite", "--jsn"], "posecbr casebase info"),
        (["describe", "clip.npz", "other.npz"], "posecbr describe"),
    ],
)
def test_an_unknown_argument_is_refused_by_the_command_it_was_given_to(
    argv: list[str], command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "posecbr: error: unrecognized arguments: --verbse; see posecbr --help", whose
    # help lists the commands, not the options of the command the typo was made in
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    extra = argv[-1]
    assert capsys.readouterr().err == (
        f"{command}: error: unrecognized arguments: {extra}; see {command} --help\n"
    )


def test_an_unknown_argument_before_the_command_is_still_posecbrs(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        main(["--jsn"])
    assert capsys.readouterr().err.startswith("posecbr: error: unrecognized arguments: --jsn;")
