"""The argparse types of the commands' arguments, and what is checked of them against the data."""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from features.errors import ConfigError, DataError, PosecbrError
from features.text import same_text, spelt_among

#: what ``-k N`` means in every command that votes with the nearest cases (train, classify,
#: compare, segment, watch): one meaning for one letter, said in the same words; what differs
#: is the default and the most it may be (``segment -k N`` votes among the case base's own k)
K_VOTES = "the N nearest cases vote, each weighed by 1/distance"


def add_k_option(p: argparse.ArgumentParser, default: int | None, said: str) -> None:
    """``-k N`` (also ``--k N``): :data:`K_VOTES`, then ``said`` (where, the default)."""
    p.add_argument("-k", "--k", type=int, default=default, metavar="N", help=f"{K_VOTES}{said}")


#: what the commands that take ``--scheduler`` (extract, train, compare) call the argument
SCHEDULER = {"scheduler": "--scheduler"}

#: what the commands that read a case base of a store (``--db``) call the name of the one
#: chosen (:meth:`casebase_store.CaseStore.choose`)
NAME = {"name": "--name"}

#: what the commands call the store :func:`casebase_store.open_store` opens
DB = {"url_or_path": "--db"}


#: an argument the library's words name in a sentence, as code: `` `k` ``, `` `k=3` ``,
#: `` `target='correct'` `` (the name, then ``=`` and its value if given)
_NAMED = re.compile(r"`([A-Za-z_][A-Za-z0-9_]*)(?:=([^`]*))?`")


def said_as_options(text: str, options: Mapping[str, str]) -> str:
    """``text`` of a library's refusal with each argument of ``options`` (argument: option)
    it names in a sentence said as the option: `` `trim` `` as ``--trim``, `` `k=6` `` as
    ``--k 6``, `` `target='corect'` `` as ``--target corect`` (a value's quotes off, as it is
    typed), `` `new_label=True` `` as ``--new-label`` (a flag). An argument not in
    ``options`` stays in the library's words."""

    def option(m: re.Match[str]) -> str:
        said = options.get(m.group(1))
        if said is None:
            return m.group(0)
        value = m.group(2)
        if value is None or value == "True":
            return said
        if len(value) >= 2 and value[0] == value[-1] and value[0] in "'\"":
            value = value[1:-1]
        return f"{said} {value}"

    return _NAMED.sub(option, text)


@contextmanager
def as_options(options: Mapping[str, str]) -> Iterator[None]:
    """A refusal inside, of a Python call naming its argument ("folds: must be at least 2"),
    said of the option of ``options`` (argument: option) that set it ("--folds: must be at
    least 2"), and each argument its message names (`` `k=6` ``, :func:`said_as_options`)
    as the option ("give --k 6 or less"); any other error as it is."""
    try:
        yield
    except PosecbrError as exc:
        option = options.get(exc.source or "")
        message = said_as_options(exc.message, options)
        if option is not None or message != exc.message:
            exc.source = option or exc.source
            exc.message = message
            exc.args = (f"{exc.source}: {message}" if exc.source else message,)
        raise


#: a URL's scheme and "://" (two letters at least: not a drive letter)
_URL = re.compile(r"[A-Za-z][A-Za-z0-9+.-]+://")


def path_arg(text: str) -> Path:
    """A file or folder argument. An empty one (``posecbr describe "$CLIP"`` with CLIP unset)
    is refused: ``Path("")`` is the current folder, which nobody named. So is a URL: as a
    path its "//" became "/" (``http:/me:secret@host/x.mp4``), and the file of that name
    was not found, said with the password shown (the messages hide a URL's password, not
    a path's)."""
    if not text:
        raise argparse.ArgumentTypeError("is an empty path (an unset variable?)")
    if is_url(text):
        raise argparse.ArgumentTypeError(f"{text} {NOT_A_PATH}")
    return Path(text)


#: what a URL given for a file is told
NOT_A_PATH = (
    "is a URL, not a path on this machine (posecbr watch plays a stream; the other commands"
    " read and write files)"
)


def is_url(text: str) -> bool:
    """Whether ``text`` begins as a URL does (``http://``, ``rtsp://``, ``file://``)."""
    return bool(_URL.match(text))


#: the largest whole number a ``--param`` value may be: past it no float (nor a C long, which
#: numba and numpy read parameters as) holds it
MAX_PARAM_INT = 2**63 - 1


def param_value(key: str, raw: str) -> Any:
    """The value of ``--param KEY=RAW``: RAW read as JSON when it parses (numbers, lists,
    true, null), else the string itself. A number past any float or of more digits than
    Python reads is refused here, naming the key: it was a traceback of the check that meets
    it (``float(10**400)``)."""
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        return raw
    except RecursionError:  # json's decoder recurses once per level of nesting
        raise ConfigError(f"the value of {key} is nested too deeply", "--param") from None
    except ValueError:  # a whole number of more digits than Python reads
        raise ConfigError(
            f"the value of {key} is a number of more than {sys.get_int_max_str_digits()} digits",
            "--param",
        ) from None
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, list):
            stack.extend(item)
        elif isinstance(item, dict):
            stack.extend(item.values())
        elif isinstance(item, int) and not isinstance(item, bool) and abs(item) > MAX_PARAM_INT:
            raise ConfigError(f"the value of {key} holds too large a number", "--param")
    return value


def check_found(
    found: Iterable[Any],
    asked: Collection[str] | None,
    flag: str,
    what: str,
    data: str | Path | None = None,
    held: Callable[[], Sequence[str]] | None = None,
) -> None:
    """Refuse a ``--labels`` or ``--subjects`` entry (``asked``) that none of the clips' values
    ``found`` is (mistyped): the work on the others alone would be taken for the one asked
    for. ``what`` says what a clip is to have it ("labelled", "of subject"); ``data``: where
    the clips are from (DATA); ``held``: called on a refusal alone, the values the data hold
    (the clips ``found`` are filtered already), named so the user sees what to give. An
    entry is a value in other Unicode characters too (:func:`features.text.same_text`), as
    the filters keep the clips."""
    have = {same_text(v) for v in found if v is not None}
    missing = sorted(m for m in set(asked or ()) if same_text(m) not in have)
    if missing:
        where = "the data" if data is None else str(data)
        values = list(held()) if held is not None else []
        unknown = [m for m in missing if not spelt_among(m, values)]
        if values and not unknown:  # there, but the other filters leave them out
            listed = ", ".join(repr(m) for m in missing)
            raise ConfigError(f"no clip {what} {listed} in {where} passes the other filters", flag)
        text = f"no clip {what} {', '.join(repr(m) for m in unknown or missing)} in {where}"
        raise ConfigError(text + held_words(values, what), flag)


#: one filter's check for :func:`check_each_found`: the values of the clips the filters kept,
#: the entries asked for, the flag, what a clip is to have one, the values the data hold
Asked = tuple[Iterable[Any], Collection[str] | None, str, str, Callable[[], Sequence[str]]]


def check_each_found(asked: Sequence[Asked], data: str | Path | None = None) -> None:
    """:func:`check_found` of each filter (``--labels``, ``--subjects``) in ``asked``, a value
    the data hold nowhere (mistyped) first, whichever flag names it, with the values the
    data hold: a subject no clip has left no clip of the labels asked, and was blamed on
    ``--labels`` ("passes the other filters"). Then a value there that the other filter
    leaves out."""
    checks = [(list(found), values, flag, what, held) for found, values, flag, what, held in asked]
    for found, values, flag, what, held in checks:
        have = {same_text(v) for v in found if v is not None}
        if values and any(same_text(v) not in have for v in values):
            data_has = list(held())
            check_found(data_has, values, flag, what, data, data_has.copy)
    for found, values, flag, what, held in checks:
        check_found(found, values, flag, what, data, held)


HELD_SHOWN = 10  # values named on a refusal; "and N more" for the rest


def held_words(values: Sequence[str], what: str) -> str:
    """``: its labels are 1, 3 and 5`` (at most :data:`HELD_SHOWN` named, then "and N more")
    for :func:`check_found`'s refusal; whole-number labels alone are codes a label names file
    names. Empty for no values (nothing to say)."""
    if not values:
        return ""
    nouns = {"labelled": "labels", "of movement": "movements", "of episode": "episodes"}
    noun = nouns.get(what, "subjects")
    many = len(values) > 1
    text = f": its {noun if many else noun[:-1]} {'are' if many else 'is'} {listed(values)}"
    codes = noun == "labels" and whole_numbers(values)
    return text + (" (codes: --label-names or a label_names column names them)" if codes else "")


def listed(values: Sequence[str]) -> str:
    """``1, 3 and 5``: at most :data:`HELD_SHOWN` values named, then "and N more"; a value
    that is empty, has spaces about it or holds a comma quoted."""
    named = [repr(v) if not v or v != v.strip() or "," in v else v for v in values]
    if len(named) > HELD_SHOWN:
        named = [*named[:HELD_SHOWN], f"{len(values) - HELD_SHOWN} more"]
    return named[0] if len(named) == 1 else f"{', '.join(named[:-1])} and {named[-1]}"


def whole_numbers(values: Iterable[str]) -> bool:
    """Whether every value is a whole number (codes a label names file names): ``"6"``."""
    return all(v.isascii() and v.isdigit() for v in values)


class PathOption(argparse.Action):
    """A path option (``--plot``, an ``--overlay`` or ``--out`` video): the path, as
    :func:`path_arg` reads it, and in ``<dest>_folder`` whether it was written as a folder
    (ending in "/", which the Path drops): ``--plot figs/`` names a folder, made if it is not
    there, as ``convert``, ``extract`` and ``compare --out DIR`` make theirs (it was refused
    as no picture's name); ``--overlay clips/`` is told it names a folder
    (:func:`check_mp4_name`), not that it lacks ".mp4"."""

    def __call__(
        self,
        _parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        _option_string: str | None = None,
    ) -> None:
        text = str(values)
        try:
            path = path_arg(text)
        except argparse.ArgumentTypeError as exc:
            raise argparse.ArgumentError(self, str(exc)) from None
        setattr(namespace, self.dest, path)
        setattr(namespace, f"{self.dest}_folder", text.endswith(("/", os.sep)))


def add_plot_option(p: argparse.ArgumentParser, said: str, several: bool = False) -> None:
    """``--plot PICTURE`` (:class:`PathOption`): ``said`` what the picture shows; the help
    adds how it is named (``several``: the command takes several recordings, whose pictures
    go in a folder)."""
    folder = "a folder, a name ending in /" + (" or several recordings" if several else "")
    p.add_argument(
        "--plot",
        action=PathOption,
        metavar="PICTURE",
        help=f"{said} (.png, .svg, .pdf: by the name; {folder}: <recording>.png in it, the"
        " folder made if it is not there)",
    )
    p.set_defaults(plot_folder=False)


def check_mp4_name(video: Path, folder: bool, what: str) -> None:
    """Refuse, naming it, a video to be written (``what``: "overlay", "output video") that is
    not named as an MP4 file: one that is a folder, or is written as one (``folder``: ending
    in "/", :class:`PathOption`), is told to name the file in it (it was told only that it
    must be an .mp4 file name, as if its suffix were the mistake)."""
    if video.is_dir():
        raise DataError(f"the {what} is a folder: name the .mp4 file to write in it", video)
    if folder:
        raise DataError(
            f"the {what} is named as a folder (ending in /): name the .mp4 file to write in it",
            f"{video}{os.sep}",
        )
    if video.suffix.lower() != ".mp4":
        raise DataError(f"the {what} must be an .mp4 file name", video)


def plot_targets(
    plot: Path, recordings: list[Path], folder: bool = False, suffix: str = ".png"
) -> list[Path]:
    """Where each recording's picture goes: ``plot`` itself, or in the folder ``plot`` (one
    there, or ``folder``: one named so, to be made) one ``<name>.png`` per recording, a
    name that two recordings share (``a/rec.npz``, ``b/rec.npz``) numbered from the second
    on (``rec_2.png``), as ``convert`` names pose files: no picture overwrites another.
    ``segment``, ``reps`` and ``describe`` take ``--plot`` so, as ``extract --out`` takes a
    folder or, for one video, a file name; ``segment --overlay DIR`` names its videos so,
    ``suffix`` ".mp4"."""
    from features.fileio import unique_name

    if not (folder or plot.is_dir()):
        return [plot]
    taken: set[str] = set()
    return [plot / f"{unique_name(path.stem, taken)}{suffix}" for path in recordings]


def check_plot(
    plot: Path,
    folder: bool,
    recordings: list[Path],
    inputs: Sequence[Path],
    command: str,
) -> list[Path]:
    """The pictures ``--plot`` names (:func:`plot_targets`), each refused before any work
    as :func:`features.fileio.check_output` refuses an output (in a folder to be made when
    ``folder``: a picture named in a missing folder, ``--plot new/x.png``, is refused naming
    it, as every output file is), and as :func:`check_folder_pictures` and
    :func:`features.timeline.picture_format` refuse it. A name with no suffix that is no
    folder is told the trailing "/" that makes it one."""
    from features.fileio import check_output
    from features.timeline import picture_format

    targets = plot_targets(plot, recordings, folder)
    for target in targets:
        check_output(target, inputs=inputs, what="picture", make_parents=folder)
    check_folder_pictures(plot, targets, recordings, command)
    if targets == [plot]:
        try:
            picture_format(plot)
        except DataError as exc:
            if plot.suffix:
                raise
            made = f"; a folder to be made for it is written ending in / ({plot}/)"
            raise DataError(exc.message + made, plot) from None
    return targets


def check_folder_pictures(
    plot: Path, targets: list[Path], recordings: list[Path], command: str
) -> None:
    """Refuse, before any work, a file already at a name that the folder ``plot``
    (``--plot DIR``) gives one of ``recordings``' pictures (``targets``,
    :func:`plot_targets`), unless it is the picture ``command`` drew there of that same
    recording before (run again: brought up to date): another command's picture, another
    recording's, or a file of the user's is not replaced in silence, as ``compare --out DIR``
    refuses a results file it did not write and ``convert --out DIR`` a pose file of another
    recording. A picture named by the user (``--plot x.png``) is theirs to replace."""
    from features.text import shown
    from features.timeline import picture_mark, png_mark

    if not plot.is_dir():
        return
    for target, recording in zip(targets, recordings, strict=True):
        if not (target.exists() or target.is_symlink()):
            continue
        if target.is_symlink() or png_mark(target) != picture_mark(command, recording):
            raise DataError(
                f"is already there, not a picture posecbr {command} drew of"
                f" {shown(recording.name)}: --plot {shown(plot)} would replace it; choose"
                " another folder, or name the picture",
                target,
            )
