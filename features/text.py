"""User data shown on a terminal: labels, names, paths and messages printed safely.

A label or file name comes from the user's files, and a terminal obeys the control characters
in what it prints: an ANSI/OSC escape in a label can set the window title, recolour or clear
the screen, and a bidirectional override can make a line read differently from what it holds.
:func:`shown` makes such characters visible instead (``\\x1b``, ``\\u202e``), so every command
prints user data through it. :func:`percent` is how every command writes an accuracy, share
or rate for people ("75.0 %"; ``--json`` keeps fractions 0-1).
"""

from __future__ import annotations

import dataclasses
import difflib
import re
import unicodedata
from collections.abc import Iterable, Sequence
from typing import Any

# C0 and C1 controls and DEL, the Unicode line/paragraph separators, and every format
# character (bidirectional overrides and isolates, zero-width joiners, the BOM, ...).
_UNSAFE = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def _escape(ch: str) -> str:
    code = ord(ch)
    if code <= 0xFF:
        return f"\\x{code:02x}"
    if code <= 0xFFFF:
        return f"\\u{code:04x}"
    return f"\\U{code:08x}"


def _unsafe(ch: str) -> bool:
    return bool(_UNSAFE.match(ch)) or unicodedata.category(ch) in ("Cf", "Cs", "Co", "Cn")


# a URL's password: after "scheme://user:" up to the last "@" before the path (a password
# typed as it is may hold "@", "?" or "#": hiding more than the password beats showing some)
_URL_PASSWORD = re.compile(r"([^\s:/?#@]*://[^:/?#@\s]*:)[^/\s]*@")
# libpq's password given as a URL parameter (postgresql://host/db?password=...)
# (up to the ": " after a URL a message names)
_QUERY_PASSWORD = re.compile(r"([?&]password=)[^&#\s]*?(?=:?(?:[&#\s]|$))", re.IGNORECASE)


def hide_passwords(text: str) -> str:
    """``text`` with the password of every URL in it replaced by ``***``, as SQLAlchemy's
    ``render_as_string(hide_password=True)`` shows a database URL:
    ``hide_passwords("http://me:secret@host/x.mp4: cannot open")`` is
    ``"http://me:***@host/x.mp4: cannot open"``."""
    if "://" not in text:
        return text  # the common case: no URL
    return _QUERY_PASSWORD.sub(r"\1***", _URL_PASSWORD.sub(r"\1***@", text))


def shown(value: object) -> str:
    """``str(value)`` with every control, format or unassigned character escaped, and the
    password of a URL in it hidden (:func:`hide_passwords`): every message that names a
    stream or database URL is printed through it.

    Printable text, including non-ASCII letters, is kept as it is: ``shown("squat é")`` is
    ``"squat é"``; ``shown("a\\x1b]0;pwned\\x07")`` is ``"a\\\\x1b]0;pwned\\\\x07"``.
    """
    text = hide_passwords(str(value))
    if text.isascii() and text.isprintable():
        return text  # the common case, without a per-character pass
    return "".join(_escape(ch) if _unsafe(ch) else ch for ch in text)


def size_words(n_bytes: float) -> str:
    """A number of bytes as people read it: ``"9.50 GB"``, ``"15.8 MB"``, ``"512 bytes"``."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n_bytes >= scale:
            value = n_bytes / scale
            return f"{value:.2f} {unit}" if value < 10 else f"{value:.1f} {unit}"
    return f"{int(n_bytes)} bytes"


def counted(n: int, noun: str) -> str:
    """``n`` and the noun, plural unless ``n`` is 1: ``"1 frame"``, ``"5 frames"`` (nouns with
    a plain -s plural)."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def first_few(names: Sequence[str], n: int = 3) -> str:
    """The first ``n`` of ``names`` joined by commas, and how many more: ``"a, b, c and 2
    more"`` (a refusal or note naming a few of many files)."""
    more = f" and {len(names) - n} more" if len(names) > n else ""
    return ", ".join(names[:n]) + more


def percent(share: float | None, digits: int = 1) -> str:
    """A share, rate or accuracy (a fraction 0-1) as every command prints it for people: a
    percentage with its sign, a space before it, ``percent(0.75)`` is ``"75.0 %"``,
    ``percent(0.02, 0)`` ``"2 %"``; one not known (None or NaN) is ``"n/a"``. Confidences
    are printed as they are (0-1, labelled "confidence"); ``--json`` holds fractions."""
    if share is None or share != share:
        return "n/a"
    return f"{100 * share:.{digits}f} %"


__all__ = [
    "counted",
    "dataclass_line",
    "did_you_mean",
    "hide_passwords",
    "percent",
    "same_text",
    "shown",
    "size_words",
    "spelt_among",
    "spelt_as",
]


def spelt_as(values: Iterable[object], known: Iterable[object]) -> list[str]:
    """Each of ``values`` as text, written as one of ``known`` is when it is the same text in
    other Unicode characters (its canonical composition, NFC, the same: "Plié" typed, its é
    one character, and "Plié" from a file name some systems save as e and a combining
    accent); any other value as it is. A truth read from the user's files is compared with a
    case base's labels so: written otherwise, every one of its clips or blocks was counted
    wrong, or as a label the case base lacks, without a word. A value of ``known`` itself,
    or one two of ``known`` write alike, is kept."""
    canonical: dict[str, str | None] = {}
    for k in map(str, known):
        key = unicodedata.normalize("NFC", k)
        canonical[key] = k if canonical.get(key, k) == k else None  # two spellings: neither
    have = set(map(str, known))
    out = []
    for value in map(str, values):
        like = None if value in have else canonical.get(unicodedata.normalize("NFC", value))
        out.append(like if like is not None else value)
    return out


def same_text(value: object) -> str:
    """``value`` as text in its canonical composition (NFC), what :func:`spelt_as` compares:
    "Plié" typed (é one character) and "Plié" from a macOS file name (e and a combining
    accent) give one key."""
    return unicodedata.normalize("NFC", str(value))


def spelt_among(value: object, values: Iterable[object]) -> bool:
    """Whether ``value`` is one of ``values``, as it is or in other Unicode characters
    (:func:`same_text`): a ``--labels`` entry typed "Plié" keeps the clips a file names
    "Plié" with e and a combining accent, where it kept none and was refused naming labels
    that looked the same."""
    key = same_text(value)
    return any(same_text(v) == key for v in values)


def did_you_mean(typed: str, known: Iterable[object]) -> str:
    """``" (did you mean 'euclidean'?)"`` when one of ``known`` is close to ``typed`` (a
    mistyped name: ``difflib`` ratio 0.75 or more, which one wrong, missing, extra or swapped
    letter in a word of four or more letters reaches), or, failing that, when exactly one of
    ``known`` is ``typed`` with two neighbouring letters swapped (``dwt`` for ``dtw``: in a
    word of three letters any one edit leaves the ratio at 0.67, but a swap keeps every
    letter; a wrong letter, ``cnm`` for ``cnn``, keeps two of three and gets no guess);
    else ``""``."""
    names = [str(k) for k in known]
    close = difflib.get_close_matches(typed, names, n=1, cutoff=0.75)
    if not close:
        swapped = [name for name in dict.fromkeys(names) if _one_swap(typed, name)]
        close = swapped if len(swapped) == 1 else []
    return f" (did you mean {close[0]!r}?)" if close else ""


def _one_swap(typed: str, name: str) -> bool:
    """Whether ``name`` is ``typed`` with two neighbouring (different) letters swapped."""
    if len(typed) != len(name):
        return False
    differ = [i for i, (a, b) in enumerate(zip(typed, name, strict=True)) if a != b]
    return (
        len(differ) == 2
        and differ[1] == differ[0] + 1
        and typed[differ[0]] == name[differ[1]]
        and typed[differ[1]] == name[differ[0]]
    )


#: values of a sequence a repr shows before its count (more are left out)
SHOWN_VALUES = 2


def dataclass_line(obj: Any, most: int = 4) -> str:
    """The dataclass ``obj``'s repr in one readable line: its fields as its own repr gives
    them, but a tuple or list of more than ``most`` values shown by its first values and its
    count (``states=('left_arm_bent.bent', 'left_arm_bent.straight', ... 84 values)``): a
    fitted measure's learned weights, one per column, ran to tens of thousands of characters."""
    parts = []
    for f in dataclasses.fields(obj):
        if not f.repr:
            continue
        value = getattr(obj, f.name)
        if isinstance(value, tuple | list) and len(value) > most:
            first = ", ".join(repr(v) for v in value[:SHOWN_VALUES])
            ends = "()" if isinstance(value, tuple) else "[]"
            said = f"{ends[0]}{first}, ... {len(value)} values{ends[1]}"
        else:
            said = repr(value)
        parts.append(f"{f.name}={said}")
    return f"{type(obj).__name__}({', '.join(parts)})"
