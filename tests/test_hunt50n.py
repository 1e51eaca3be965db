"""A new user at the command line (hunt 50n): every ``--help`` shows an example that runs as
written, an option given twice with two values is refused, a file whose name begins with
"-" is told how to give it, and a locale not UTF-8 gets plain characters, not a crash."""

from __future__ import annotations

import argparse
import io
import shlex
import sys
from pathlib import Path

import pytest

from posecbr.cli import PLAIN_ERRORS, build_parser, main
from tests.badinput import ROOT


def _parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """Every command's parser and every action's (``casebase info``), not ``posecbr``'s."""
    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                found += [child, *_parsers(child)]
    return found


def test_every_command_help_ends_with_an_example_that_parses() -> None:
    """``posecbr reps --help`` listed the options and no command line using them: each
    command's (and ``casebase`` action's) help now ends with one, which the parser takes as
    that command (a shell's ``> file`` aside)."""
    root = build_parser()
    parsers = _parsers(root)
    assert len(parsers) == 14 + 6  # the commands, then casebase's actions
    for parser in parsers:
        last = parser.format_help().rstrip().splitlines()[-1]
        assert last.startswith(f"example: {parser.prog} "), (parser.prog, last)
        words = shlex.split(last.removeprefix("example: "))
        words = words[: words.index(">")] if ">" in words else words
        args = root.parse_args(words[1:])
        ran = " ".join(str(w) for w in (args.command, getattr(args, "action", None)) if w)
        assert f"posecbr {ran} ".startswith(f"{parser.prog} ") and callable(args.func)


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["reps", "none.npz", "--fps", "30", "--fps", "60"],
         "posecbr reps: error: argument --fps: given twice, '30' then '60': give it once"),
        (["classify", "none.npz", "--db", "cb.sqlite", "--labels", "squat", "--labels", "lunge"],
         "posecbr classify: error: argument --labels: given twice, 'squat' then 'lunge'"),
        # one option under its two spellings
        (["watch", "0", "--db", "cb.sqlite", "--out", "a.mp4", "--overlay", "b.mp4"],
         "posecbr watch: error: argument --out/--overlay: given twice, 'a.mp4' then 'b.mp4'"),
    ],
    ids=["--fps", "--labels", "--out/--overlay"],
)  # fmt: skip
def test_an_option_given_twice_with_two_values_is_refused(
    argv: list[str],
    said: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """argparse kept the last value and dropped the first without a word: ``classify
    --labels deep_squat --labels hurdle_step`` of the demo's 36 clips of the two classified
    the 18 hurdle steps alone. A command line that cannot be read: exit 2, one line."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1 and err.startswith(said), err
    # the same value twice, and an option that gathers (--truth), are still taken: the
    # missing file is what is refused
    for same in (["reps", "none.npz", "--fps", "30", "--fps=30"],
                 ["segment", "none.npz", "b.npz", "--db", "cb.sqlite", "--truth", "a.txt",
                  "--truth", "b.txt"]):  # fmt: skip
        assert main(same) == 1
        assert "none.npz: no such file" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_a_file_whose_name_begins_with_a_dash_is_told_how_to_give_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``posecbr reps -x.npz`` said "the following arguments are required: clip", the clip
    given; argparse reads a word beginning with "-" as an option. The line now says how to
    give the file; a word that is no file gets no such hint."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "-x.npz").write_bytes(b"")
    hint = "('-x.npz' begins with '-': give it as ./-x.npz"
    for argv, said in (
        (["reps", "-x.npz"], f"the following arguments are required: clip {hint}, or after --)"),
        (["reps", "a.npz", "-x.npz"], f"unrecognized arguments: -x.npz {hint}, or after --)"),
        (["reps", "a.npz", "--plot", "-x.npz"], f"argument --plot: expected one argument {hint})"),
        (["reps", "-y.npz"], "the following arguments are required: clip; see"),
    ):
        with pytest.raises(SystemExit) as exit_:
            main(argv)
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and err.count("\n") == 1, err
        assert err.startswith(f"posecbr reps: error: {said}"), err


def test_a_locale_not_utf8_gets_plain_characters_not_a_crash(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Standard output in ASCII (``LC_ALL=C PYTHONUTF8=0``; a Latin-1 locale lacks "\u2013"
    too): ``describe`` printed up to its first "frames 0\u20135" and ended as a bug in
    posecbr, UnicodeEncodeError, exit 70 (``dad`` and ``classify -v`` too). Each character
    the encoding lacks is now written plainly, else escaped; the rest is as in UTF-8."""
    clip = str(ROOT / "posecbr" / "demo_data" / "uiprmd" / "m01_s01_e01.npz")
    assert main(["describe", clip]) == 0
    utf8 = capsys.readouterr().out
    assert "\u2013" in utf8
    raw = io.BytesIO()
    monkeypatch.setattr(sys, "stdout", io.TextIOWrapper(raw, encoding="ascii"))  # strict
    assert main(["describe", clip]) == 0
    sys.stdout.flush()
    assert raw.getvalue().decode("ascii") == utf8.replace("\u2013", "-")
    # what has no plain spelling, escaped; a file name's undecodable byte, as it was
    assert "93\u00b0 \u4e2d".encode("ascii", PLAIN_ERRORS) == b"93 deg \\u4e2d"
    assert "bad\udcff.npz".encode("ascii", PLAIN_ERRORS) == b"bad\xff.npz"


def test_help_as_a_command_points_to_the_help(capsys: pytest.CaptureFixture[str]) -> None:
    """``posecbr help segment`` (as git and pip take it) was an invalid choice with no
    guess; the line now names the command line that shows that help."""
    for argv, meant in (
        (["help", "segment"], "posecbr segment --help"),
        (["help"], "posecbr --help"),
        (["casebase", "help", "trim"], "posecbr casebase trim --help"),
    ):
        with pytest.raises(SystemExit) as exit_:
            main(argv)
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and err.count("\n") == 1, err
        assert "invalid choice: 'help' (choose from " in err, err
        assert f" (did you mean {meant!r}?); see " in err, err


def test_every_labels_and_subjects_option_says_it_takes_a_comma_separated_list() -> None:
    """``compare --help`` said "--labels LIST: only these activity labels", not how a list
    is written (``train``, ``classify`` and ``convert`` said: commas)."""
    helps = {
        f"{parser.prog} {action.option_strings[0]}": action.help or ""
        for parser in _parsers(build_parser())
        for action in parser._actions
        if action.option_strings and action.dest in ("labels", "subjects")
    }
    assert len(helps) == 8  # train, classify, compare and convert
    assert [k for k, said in helps.items() if "comma" not in said] == []
