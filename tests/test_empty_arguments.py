"""An empty file argument (``posecbr train "$DATA" --db cb.sqlite`` with DATA unset) and the
usage errors of the parser.

An empty argument became ``Path("")``, the current folder: ``train ""`` trained on whatever
the folder held, ``convert ""`` listed it (a traceback when a file there vanished meanwhile),
``describe ""`` said ".: unknown clip format". Every file or folder argument of every command
now refuses it while the command line is read, before any work, in one line naming the
argument; and every usage error of the parser is one line (argparse printed the command's
usage first, ten lines for ``train``; a newline or escape sequence in an argument it quotes
went to the terminal as it was), exit 2.
"""

from __future__ import annotations

import argparse
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from posecbr.arguments import path_arg
from posecbr.cli import build_parser, main
from tests.badinput import snapshot

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def _commands(
    parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()
) -> Iterator[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    """Every (sub)command of ``parser`` with the words that name it (``casebase trim``)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*prefix, name), sub
                yield from _commands(sub, (*prefix, name))


def _path_arguments() -> list[tuple[tuple[str, ...], argparse.Action]]:
    return [
        (words, action)
        for words, sub in _commands(build_parser())
        for action in sub._actions
        if action.type is path_arg
    ]


@pytest.fixture
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A working folder holding what an empty argument would have been taken for: a pose
    file and a labels CSV naming it (the demo's first clip)."""
    shutil.copy2(DEMO / "m01_s01_e01.npz", tmp_path / "m01_s01_e01.npz")
    (tmp_path / "labels.csv").write_text("file,label\nm01_s01_e01.npz,deep_squat\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and captured.out == "", captured.err
    return lines[0]


def test_no_file_argument_of_any_command_is_a_plain_path() -> None:
    """Every Path argument goes through the check (a new one added with ``type=Path``
    would take an empty argument for the current folder again)."""
    plain = [(w, a.dest) for w, sub in _commands(build_parser()) for a in sub._actions
             if a.type is Path]  # fmt: skip
    assert plain == []
    # the ones users type most are among those checked
    names = {(w, a.dest) for w, a in _path_arguments()}
    assert {(("describe",), "posefile"), (("train",), "data"), (("classify",), "clips"),
            (("segment",), "recordings"), (("convert",), "source"), (("convert",), "out"),
            (("extract",), "out"), (("casebase", "export"), "out")} <= names  # fmt: skip


EMPTY = [
    (["describe", ""], "posecbr describe: error: argument posefile: is an empty path (an"
     " unset variable?); see posecbr describe --help"),
    (["train", "", "--db", "cb.sqlite"], "posecbr train: error: argument data: is an empty"
     " path (an unset variable?); see posecbr train --help"),
    (["convert", "", "--out", "poses"], "posecbr convert: error: argument source: is an"
     " empty path (an unset variable?); see posecbr convert --help"),
    (["classify", "m01_s01_e01.npz", "", "--db", "cb.sqlite"], "posecbr classify: error:"
     " argument clips: is an empty path (an unset variable?); see posecbr classify --help"),
    (["describe", "m01_s01_e01.npz", "--plot", ""], "posecbr describe: error: argument"
     " --plot: is an empty path (an unset variable?); see posecbr describe --help"),
]  # fmt: skip


def test_every_file_argument_refuses_an_empty_path(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = snapshot(folder)
    checked = 0
    for words, action in _path_arguments():
        empty = [action.option_strings[0], ""] if action.option_strings else [""]
        line = _refused([*words, *empty], capsys)
        command = " ".join(words)
        assert line.startswith(f"posecbr {command}: error: argument "), line
        assert line.endswith(f": is an empty path (an unset variable?); see posecbr {command}"
                             " --help"), line  # fmt: skip
        checked += 1
    assert checked >= 30
    assert snapshot(folder) == before


USAGE = [
    (["describe"], "posecbr describe: error: the following arguments are required:"
     " posefile; see posecbr describe --help"),
    (["train", "labels.csv"], "posecbr train: error: the following arguments are"
     " required: --db; see posecbr train --help"),
    (["casebase", "trim", "--db"], "posecbr casebase trim: error: argument --db: expected"
     " one argument; see posecbr casebase trim --help"),
    (["train", "labels.csv", "--db", "cb.sqlite", "--sensor", "k\ninect\x1b[2J"],
     "posecbr train: error: argument --sensor: invalid choice: 'k\\ninect\\x1b[2J'"
     " (choose from 'kinect', 'vicon'); see posecbr train --help"),
    (["no-such-command"], "posecbr: error: argument COMMAND: invalid choice:"
     " 'no-such-command' (choose from 'casebase', 'classify', 'compare', 'convert', 'dad',"
     " 'demo', 'describe', 'extract', 'report', 'reps', 'segment', 'thresholds', 'train',"
     " 'watch'); see posecbr --help"),
]  # fmt: skip


@pytest.mark.parametrize(("argv", "line"), EMPTY + USAGE)
def test_a_refused_command_line_is_one_line_and_changes_nothing(
    folder: Path, argv: list[str], line: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """An empty file argument is refused in one line before any work, as every usage error
    now is, saying where the usage is."""
    before = snapshot(folder)
    assert _refused(argv, capsys) == line
    assert snapshot(folder) == before
