"""The ``posecbr`` console command.

Each subcommand lives in its own module under :mod:`posecbr.commands` and exposes
``register(subparsers)``, which adds a parser whose ``func(args) -> int`` runs it. Adding a
command means adding a module; nothing here changes.
"""

from __future__ import annotations

import argparse
import ast
import codecs
import errno
import importlib
import io
import os
import pkgutil
import re
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, NoReturn

from features.errors import PosecbrError
from features.interrupts import (
    INTERRUPTED_STATUS,
    TERMINATED_STATUS,
    sigterm_as_interrupt,
    terminated,
)
from features.text import did_you_mean, shown
from posecbr import __version__, commands

if TYPE_CHECKING:
    from casebase_store import NotADatabase

#: the actions that gather what each occurrence gives (``--param``): given again, not refused
REPEATABLE_ACTIONS = (
    argparse._AppendAction,
    argparse._AppendConstAction,
    argparse._ExtendAction,
    argparse._CountAction,
)


#: how argparse begins the error of a command line missing required arguments
REQUIRED = "the following arguments are required: "


class Parser(argparse.ArgumentParser):
    """argparse's parser (its subcommands' too) with a usage error in one line: the error
    and where the usage is, not the usage itself (a command's is many lines). The error
    quotes the user's arguments: escaped, they cannot break the line or drive the terminal.
    No option may be abbreviated (``--tru`` for ``--truth``): a new option sharing the
    prefix would change what an old command line means, and a typo would land on another
    option; a subcommand's parser is of this class, and so refuses them too."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self._given: dict[argparse.Action, list[str]] = {}
        self._words: list[str] = []
        self._namespace = argparse.Namespace()

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        self._given = {}
        self._words = [str(a) for a in (sys.argv[1:] if args is None else args)]
        # kept for :meth:`_required`: what the actions had gathered when argparse refused
        self._namespace = argparse.Namespace() if namespace is None else namespace
        return super().parse_known_args(args, self._namespace)

    def _get_values(self, action: argparse.Action, arg_strings: list[str]) -> Any:
        """An option that takes one value given twice with two values (``--labels squat
        --labels lunge``, ``--fps 30 --fps 60``, or under its two spellings, ``watch --out
        a.mp4 --overlay b.mp4``) is refused: argparse kept the last and dropped the first
        without a word. Options that gather what they are given (``--param``, ``--truth``:
        an append action, or one marked ``repeatable``) may be given again."""
        if (
            action.option_strings
            and not isinstance(action, REPEATABLE_ACTIONS)
            and not (getattr(action, "repeatable", False))
        ):
            before = self._given.setdefault(action, list(arg_strings))
            if before != list(arg_strings):
                first, then = (" ".join(v) for v in (before, arg_strings))
                raise argparse.ArgumentError(
                    action, f"given twice, {first!r} then {then!r}: give it once"
                )
        return super()._get_values(action, arg_strings)

    def error(self, message: str) -> NoReturn:
        message = self._required(message)
        guess = self._guess(message) or self._dashed(message)
        self.exit(2, f"{self.prog}: error: {shown(message)}{guess}; see {self.prog} --help\n")

    def _required(self, message: str) -> str:
        """argparse's "the following arguments are required: ..." with every argument
        missing named, in the order the usage lists them: an argument that argparse takes
        as optional and the command checks for itself (an action marked ``needed``:
        ``segment``'s RECORDING, which may come after ``--truth``) is missing too when
        nothing was gathered into it. ``posecbr segment`` given nothing said only that
        ``--db`` was missing, and given ``--db`` then that RECORDING was."""
        if not message.startswith(REQUIRED):
            return message
        named = {n.strip() for n in message[len(REQUIRED) :].split(",")}
        missing = [
            name
            for a in self._actions
            if (name := argparse._get_action_name(a)) in named
            or (getattr(a, "needed", False) and not getattr(self._namespace, a.dest, None))
        ]
        if not named <= set(missing):  # a name not of an action here: said as argparse said it
            return message
        return REQUIRED + ", ".join(str(n) for n in missing)

    def _dashed(self, message: str) -> str:
        """ " ('-x.npz' begins with '-': give it as ./-x.npz, or after --)" when an argument
        the command was given is a file whose name begins with "-", which argparse read as an
        option: "the following arguments are required: clip" where the clip had been given,
        "unrecognized arguments: -x.npz", or, given to an option, "argument --plot: expected
        one argument"."""
        valued = re.search(r": expected (at least )?one argument", message)  # an option's
        if not message.startswith(("the following arguments are required", "unrecognized")) and (
            not valued
        ):
            return ""
        after = "" if valued else ", or after --"  # after --: a positional argument
        options = {o for a in self._actions for o in a.option_strings}
        for word in self._words:
            if word == "--":
                break
            if (
                word.startswith("-")
                and word.split("=")[0] not in options
                and not self._negative_number_matcher.match(word)
                and os.path.lexists(word)
            ):
                return f" ({word!r} begins with '-': give it as {shown('./' + word)}{after})"
        return ""

    def _guess(self, message: str) -> str:
        """ " (did you mean 'classify'?)" for a mistyped command or option, when one is close."""
        typed: list[str] = []
        known: list[str] = []
        # the value as repr() gives it: in double quotes when it holds a single quote
        choice = re.match(
            r"argument (.*?): invalid choice: ('(?:[^'\\]|\\.)*'|\"(?:[^\"\\]|\\.)*\") "
            r"\(choose from",
            message,
        )
        if choice:  # a command, an action or an option's value (segment --unknown helt-out)
            typed = [str(ast.literal_eval(choice.group(2)))]
            for action in self._actions:
                if action.choices is not None and argparse._get_action_name(action) == (
                    choice.group(1)
                ):
                    known = [str(c) for c in action.choices]
            if typed == ["help"] and self._subcommands(choice.group(1)) is not None:
                return self._help_meant()
        elif message.startswith("unrecognized arguments: "):
            typed = [a.split("=")[0] for a in message.split(": ", 1)[1].split()]
            typed = [a for a in typed if a.startswith("--")]
            known = [o for a in self._actions for o in a.option_strings if o.startswith("--")]
        for word in typed:
            guess = did_you_mean(word, known)
            if guess:
                return guess
        return ""

    def _subcommands(self, name: str) -> Any:
        """The commands (or actions) of the positional argument ``name``, if it takes them."""
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction) and (
                argparse._get_action_name(action) == name
            ):
                return action.choices
        return None

    def _help_meant(self) -> str:
        """ " (did you mean 'posecbr segment --help'?)" for ``posecbr help segment`` (as git
        and pip take it): the command named after "help", if one is, else this parser's."""
        commands = next(
            (a.choices for a in self._actions if isinstance(a, argparse._SubParsersAction)), {}
        )
        words = self._words[self._words.index("help") + 1 :] if "help" in self._words else []
        named = [w for w in words[:1] if w in commands]
        return f" (did you mean {' '.join([self.prog, *named, '--help'])!r}?)"


#: the exit status of an internal error, a bug in posecbr rather than a problem with what it
#: was given: sysexits.h's EX_SOFTWARE ("an internal software error has been detected")
BUG_STATUS = 70

#: the environment variable that prints an internal error's traceback on stderr
DEBUG_VARIABLE = "POSECBR_DEBUG"

#: what ``posecbr --help`` says of every command: its options' help, exit status, progress
EPILOG = (
    "`posecbr COMMAND --help` lists a command's options. Exit status: 0 done; 1 a problem "
    "with the input, the data, an option's value or the system (a full disk, a file it may "
    "not write), said in one line; 2 a command line that cannot be read (a mistyped command "
    "or option, a missing argument, a number that is none; no command: this help); "
    f"{BUG_STATUS} an internal error, a bug in posecbr: one line naming the file its "
    f"traceback was written to ({DEBUG_VARIABLE}=1 prints it instead); "
    f"{INTERRUPTED_STATUS} stopped by Ctrl-C, {TERMINATED_STATUS} by SIGTERM (watch ends as "
    "at the end of its stream: 0). Progress bars show on a terminal; POSECBR_NO_PROGRESS=1 "
    "turns them off."
)

#: a write refused for want of room: a full disk, a quota used up, a file size limit
#: (RLIMIT_FSIZE, `ulimit -f`); said as posecbr's own writers say it
NO_ROOM_ERRNOS = frozenset({errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC), errno.EFBIG})

#: errors of the system, not of posecbr: said in one line, exit 1, as a problem with the
#: input is (a disk full as an output is written, a folder it may not write in)
SYSTEM_ERRNOS = NO_ROOM_ERRNOS | frozenset(
    {
        errno.EACCES,
        errno.EPERM,
        errno.EROFS,
        errno.EIO,
        errno.ELOOP,  # symbolic links that lead round in a loop
    }
)


def plain_text(doc: str) -> str:
    """A docstring as a terminal shows it: ``x`` as `x`, :mod:`features.repetitions` (any
    Sphinx role) as features.repetitions, a role's ~ dropped."""
    doc = re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", doc)
    return doc.replace("``", "`")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="posecbr",
        description="Interpretable human activity recognition: poses -> fluents and QMPs -> CBR.",
        epilog=EPILOG,
    )
    parser.add_argument("--version", action="version", version=f"posecbr {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{commands.__name__}.{info.name}")
        module.register(sub)
    _name_own_parser(parser)
    return parser


def _name_own_parser(parser: argparse.ArgumentParser) -> None:
    """Give every subcommand's (and action's) parser itself as the default ``_parser``, so
    that an argument none of them knows is refused by the command it was given to
    ("posecbr classify: error: unrecognized arguments: --verbse; see posecbr classify
    --help"), not by ``posecbr`` (whose help does not list the command's options); and one
    whose ``--help`` would say only its options the line ``posecbr --help`` gives it."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            said = {a.dest: a.help for a in action._choices_actions}
            for name, child in action.choices.items():
                child.set_defaults(_parser=child)
                if child.description is None and said.get(name):  # its --help says what it does
                    child.description = f"{str(said[name])[0].upper()}{str(said[name])[1:]}."
                if child.description:  # a module's docstring: its Sphinx markup read as text
                    child.description = plain_text(child.description)
                _name_own_parser(child)


def _given_to(
    parser: argparse.ArgumentParser,
    argv: list[str],
    unknown: list[str],
    deepest: argparse.ArgumentParser,
) -> tuple[argparse.ArgumentParser, list[str]]:
    """The parser the first of the ``unknown`` arguments was given to, and those given to
    it: ``posecbr casebase --bogus list`` gave ``--bogus`` to ``casebase`` (whose words
    come before its action's), not to ``casebase list``; ``deepest`` (the command or action
    run) when no level above it was given one. argparse gathers every level's unknown
    arguments in one list; each level's own words lie between its command and the next
    command (``posecbr`` and ``casebase`` take no option with a value, so the first word
    naming a command is the next command)."""
    while True:
        sub = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
        at = next((i for i, word in enumerate(argv) if sub and word in sub.choices), None)
        if sub is None or at is None:
            return deepest, unknown
        own = [word for word in argv[:at] if word in unknown]
        if own:
            return parser, own
        parser, argv = sub.choices[argv[at]], argv[at + 1 :]


def _belongs(unknown: list[str], command: argparse.ArgumentParser) -> str:
    """ " (--json is an option of posecbr describe: give it after describe)" when one of the
    ``unknown`` arguments, given before the command, is an option of the command run."""
    options = {o for a in command._actions for o in a.option_strings}
    for word in unknown:
        if word.split("=")[0] in options:
            where = command.prog.removeprefix("posecbr ")
            return f" ({word.split('=')[0]} is an option of {command.prog}: give it after {where})"
    return ""


def _said_for(
    exc: PosecbrError, args: argparse.Namespace, command: argparse.ArgumentParser
) -> PosecbrError:
    """``exc`` as the command says it: a file that is no case base, given to an option
    (``--db``, ``casebase copy --to``), is said with the option that takes the case base
    file (the store does not know the command line)."""
    store = sys.modules.get("casebase_store")  # never imported: none of its errors raised
    if store is None:
        return exc
    not_a_database: type[NotADatabase] = store.NotADatabase
    if not isinstance(exc, not_a_database) or exc.source is None:
        return exc
    for action in command._actions:
        given = getattr(args, action.dest, None)
        if action.option_strings and isinstance(given, str) and given == exc.source:
            return exc.taken_by(max(action.option_strings, key=len))
    return exc


#: what a character the output's encoding lacks is written as, when it has a plain spelling
PLAIN = {"\u2013": "-", "\u2014": "-", "\u2192": "->", "\u00d7": "x", "\u2026": "...",
         "\u00b7": ".", "\u00b0": " deg", "\u00b1": "+/-", "\u2212": "-"}  # fmt: skip

#: the name under which :func:`_plain` is registered as a codec error handler
PLAIN_ERRORS = "posecbr.plain"


def _plain(exc: UnicodeError) -> tuple[str | bytes, int]:
    """A codec error handler: the characters ``exc`` could not encode in their plain spelling
    (:data:`PLAIN`: "frames 67-72" for "frames 67\u201372"), else escaped as Python writes
    them ("\\u4e2d"); a file name's undecodable bytes (surrogate-escaped) as they were."""
    if not isinstance(exc, UnicodeEncodeError):
        raise exc
    text = exc.object[exc.start : exc.end]
    if all("\udc80" <= c <= "\udcff" for c in text):
        return bytes(ord(c) - 0xDC00 for c in text), exc.end
    said = "".join(PLAIN.get(c) or c.encode("ascii", "backslashreplace").decode() for c in text)
    return said, exc.end


def plain_output() -> None:
    """Standard output in an encoding that cannot write every character posecbr prints (a
    locale not UTF-8: ``LANG=en_US.ISO-8859-1``, or the C locale with ``PYTHONUTF8=0``):
    each it lacks written by :func:`_plain`. ``describe`` ("frames 67\u201372") printed up
    to the first and ended as a bug (UnicodeEncodeError, exit 70). Standard error escapes
    them already (Python's ``backslashreplace``)."""
    stream = sys.stdout
    if not isinstance(stream, io.TextIOWrapper) or stream.errors == PLAIN_ERRORS:
        return
    try:
        utf = codecs.lookup(stream.encoding).name.startswith("utf")
    except LookupError:
        utf = False
    if not utf:
        codecs.register_error(PLAIN_ERRORS, _plain)
        stream.reconfigure(errors=PLAIN_ERRORS)


def main(argv: Sequence[str] | None = None) -> int:
    plain_output()
    parser = build_parser()
    args, unknown = parser.parse_known_args(argv)
    own = args.__dict__.pop("_parser", parser)
    if unknown:
        given = list(sys.argv[1:] if argv is None else argv)
        deepest = own
        own, unknown = _given_to(parser, given, unknown, deepest)
        own.error(f"unrecognized arguments: {' '.join(unknown)}{_belongs(unknown, deepest)}")
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    # "posecbr casebase trim": a command with actions is named with its action
    command = " ".join(str(c) for c in (args.command, getattr(args, "action", None)) if c)
    try:
        # SIGTERM (kill, systemd, docker stop) stops the command as Ctrl-C does: cleaned up
        with sigterm_as_interrupt():
            return _run(args)
    except PosecbrError as exc:
        # The message quotes the user's files and labels: escaped, it cannot drive the terminal.
        print(f"posecbr {command}: error: {shown(_said_for(exc, args, own))}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:  # its text, if any: what was done before (escaped)
        said = f": {shown(exc)}" if str(exc) else ""
        if terminated():
            print(f"posecbr {command}: terminated (SIGTERM){said}", file=sys.stderr)
            return TERMINATED_STATUS
        print(f"posecbr {command}: interrupted{said}", file=sys.stderr)
        return INTERRUPTED_STATUS
    except BrokenPipeError:
        return 0
    except (OSError, MemoryError) as exc:
        return system_error(command, exc)
    except Exception as exc:  # a bug: one line and the traceback in a file, not a raw one
        loop = symlink_loop(exc)
        return internal_error(command, exc) if loop is None else system_error(command, loop)


def symlink_loop(exc: BaseException) -> OSError | None:
    """The system's error (ELOOP, naming the path) that ``exc`` stands for when it is
    Python's RuntimeError for symbolic links that lead round in a loop, met resolving a path
    (``Path.resolve`` before Python 3.13: "Symlink loop from '/data/x.npz'"); else None. An
    input or output given as such a link was said as a bug in posecbr."""
    found = re.fullmatch(r"Symlink loop from (.+)", str(exc)) if type(exc) is RuntimeError else None
    if found is None:
        return None
    try:
        where = ast.literal_eval(found.group(1))
    except (ValueError, SyntaxError):
        where = found.group(1)
    return OSError(errno.ELOOP, "symbolic links that lead round in a loop", str(where))


def _run(args: argparse.Namespace) -> int:
    """Run the command; an error raised from the user's stop (:func:`_interrupt_in`) is
    that stop."""
    try:
        return int(args.func(args) or 0)
    except Exception as exc:  # not one posecbr says: the user's stop, if it was one
        interrupt = None if isinstance(exc, PosecbrError) else _interrupt_in(exc)
        if interrupt is None:
            raise
        raise interrupt from None


def _interrupt_in(exc: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C (or SIGTERM, raised as one) that ``exc`` was raised from, if any: a
    compiled extension that was being imported when it came turns it into its own error
    (onnxruntime's, as pybind11 makes every module: ``ImportError: initialization failed``,
    raised from the KeyboardInterrupt), which was said as a bug in posecbr (exit 70) where
    the user had stopped the command."""
    seen: set[int] = set()
    at: BaseException | None = exc
    while at is not None and id(at) not in seen:
        if isinstance(at, KeyboardInterrupt):
            return at
        seen.add(id(at))
        at = at.__cause__ or at.__context__
    return None


def system_error(command: str, exc: OSError | MemoryError) -> int:
    """The system's refusal (a path it cannot look up, a full disk, a file posecbr may not
    write, memory run out) said in one line, exit 1, as a problem with the input; another
    OSError is a bug (:func:`internal_error`). A path over 255 bytes is met by whichever check
    asks about it first: refused before anything is written. The outputs are written
    atomically and the stores in transactions: a disk full halfway leaves none half-done."""
    if isinstance(exc, MemoryError):  # a recording or dataset too large for this machine
        print(f"posecbr {command}: error: out of memory", file=sys.stderr)
        return 1
    if exc.errno == errno.ENAMETOOLONG:
        where = exc.filename if exc.filename is not None else "a path"
        print(
            f"posecbr {command}: error: {shown(str(where)[:200])}: cannot use the path"
            f" ({exc.strerror})",
            file=sys.stderr,
        )
        return 1
    if exc.errno in SYSTEM_ERRNOS:
        from features.fileio import write_error

        where = f"{shown(str(exc.filename))}: " if exc.filename is not None else ""
        said = write_error(exc) if exc.errno in NO_ROOM_ERRNOS else exc.strerror
        print(f"posecbr {command}: error: {where}{said}", file=sys.stderr)
        return 1
    return internal_error(command, exc)


def internal_error(command: str, exc: BaseException) -> int:
    """Say that ``exc``, raised by ``posecbr command``, is a bug in posecbr, in one line on
    stderr with where its traceback was written (a file in the temporary folder), or with
    the traceback itself when ``POSECBR_DEBUG=1``; :data:`BUG_STATUS`. Before, Python printed
    the traceback and the exit status was 1, as for a problem with the input."""
    import tempfile
    import traceback

    told = f"{type(exc).__name__}: {shown(str(exc))[:300]}".rstrip(": ")
    head = f"posecbr {command}: internal error, a bug in posecbr ({told})"
    text = "".join(traceback.format_exception(exc))
    if os.environ.get(DEBUG_VARIABLE, "") not in ("", "0"):
        print(text, end="", file=sys.stderr)
        print(head, file=sys.stderr)
        return BUG_STATUS
    try:
        fd, name = tempfile.mkstemp(prefix="posecbr-bug-", suffix=".txt")
        with os.fdopen(fd, "w", encoding="utf-8", errors="backslashreplace") as f:
            f.write(f"posecbr {__version__} {command}\n{text}")
    except OSError:
        where = f"{DEBUG_VARIABLE}=1 prints the traceback"
    else:
        where = f"traceback in {shown(name)}; {DEBUG_VARIABLE}=1 prints it"
    print(f"{head}; {where}; please report it", file=sys.stderr)
    return BUG_STATUS


if __name__ == "__main__":
    sys.exit(main())
