"""Hunt 51b: a command line missing several required arguments names them all; repetitions
cut off where the person is lost from view.

``posecbr segment`` given nothing said only that ``--db`` was missing (its RECORDING is
optional to argparse, for ``--truth``, and was checked after ``--db``): the user added
``--db`` and was then told of RECORDING. Every command given nothing now names everything
its usage asks for, in one line, exit 2.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Iterator

import pytest

from posecbr.cli import build_parser, main


def _commands(
    parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()
) -> Iterator[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    """Every (sub)command of ``parser`` with the words that name it (``casebase trim``)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*prefix, name), sub
                yield from _commands(sub, (*prefix, name))


def _asked(usage: str, prog: str) -> set[str]:
    """What the usage line of command ``prog`` asks for, read from its text: the words
    outside brackets, an option by its name (its value's word after it dropped), an
    argument by its own word."""
    words = usage.split(":", 1)[1].split()[len(prog.split()) :]
    text = " ".join(words)
    while re.search(r"\[[^\[\]]*\]", text):  # innermost [optional] first: they nest
        text = re.sub(r"\[[^\[\]]*\]", "", text)
    out: set[str] = set()
    tokens = iter(t for t in text.split() if t != "...")
    for token in tokens:
        out.add(token)
        if token.startswith("-"):
            next(tokens, None)  # the option's value
    return out


def _said(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    capsys.readouterr()
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    return err.rstrip("\n")


def test_segment_given_nothing_names_the_recording_and_the_case_base(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Given nothing, or options that are neither (``--json``, a label file), ``segment``
    names both; given the one, the other."""
    both = (
        "posecbr segment: error: the following arguments are required: RECORDING, --db;"
        " see posecbr segment --help"
    )
    assert _said(["segment"], capsys) == both
    assert _said(["segment", "--json"], capsys) == both
    assert _said(["segment", "--truth", "labels.txt"], capsys) == both
    assert _said(["segment", "--db", "cb.sqlite"], capsys) == both.replace(", --db", "")
    assert _said(["segment", "walk.npz"], capsys) == both.replace("RECORDING, ", "")


def test_every_command_given_nothing_names_all_its_usage_asks_for(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Each command (and ``casebase`` action) whose usage asks for something, given nothing,
    names exactly what its usage line asks for (read from the usage's text, not from the
    parser's actions)."""
    checked = 0
    for words, sub in _commands(build_parser()):
        prog = "posecbr " + " ".join(words)
        asked = _asked(sub.format_usage(), prog)
        if not asked:  # demo, thresholds: nothing to give
            continue
        line = _said(list(words), capsys)
        head = f"{prog}: error: the following arguments are required: "
        assert line.startswith(head) and line.endswith(f"; see {prog} --help"), line
        named = line[len(head) : -len(f"; see {prog} --help")].split(", ")
        assert set(named) == asked and len(named) == len(asked), (words, named, asked)
        checked += 1
    assert checked >= 17  # 12 commands and 6 casebase actions ask for something
