"""Writing outputs safely: every file posecbr writes appears whole or not at all, and never
replaces one of the inputs it was made from.

- :func:`atomic_path`: a temporary file beside the destination, renamed over it only when the
  writer finished without error (a crash or kill leaves the old file, or none, plus no stray
  temporary file once the ``with`` block is left);
- :func:`write_text_atomic`, :func:`write_bytes_atomic`, :func:`write_json_atomic`: the usual
  cases of that;
- :func:`staged_folder`: several files into one folder as one write (all of them, or the
  folder as it was);
- :func:`write_together`: several files, in one folder or not, as one write (all of them,
  or each as it was); :func:`replace_together`, the renames that end it;
- :func:`check_output`: before any work starts, refuse an output path that is a folder, lies in
  a folder that does not exist, or is one of the inputs;
- :func:`temporary_file`, :func:`staging_folder`: the hidden temporaries those writers use,
  named after their process (``.NAME.pid1234@host.x8k2.tmp``), so that a writer killed
  before it could clean up (``kill -9``, power loss) does not leave them forever: the next
  writer of the same output removes those of processes of this machine that are gone
  (:func:`remove_stale_temporaries`), but for a temporary named as one worth keeping
  (:data:`PARTIAL`: a copy of a video being written, playable as far as it goes), which it
  keeps under a visible name and says so;
- :func:`unique_name`: one output name per input when two inputs share a name.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import re
import shutil
import socket
import sys
import tempfile
from collections.abc import Callable, Collection, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import DataError, InputError, PosecbrError
from .text import shown

#: How a message names a picture given where a clip or a case base belongs (by its first
#: bytes: :func:`is_picture`).
PICTURE_WORDS = "a PNG or JPEG picture"


def is_picture(head: bytes) -> bool:
    """Whether a file's first bytes ``head`` are a PNG or JPEG picture's."""
    return head.startswith((b"\x89PNG\r\n\x1a\n", b"\xff\xd8\xff"))


HEIF_STILL_BRANDS = frozenset(
    (b"mif1", b"mif2", b"heic", b"heix", b"heim", b"heis", b"avif", b"avci", b"vvic")
)
"""The ftyp brands of a HEIF file of still pictures (ISO/IEC 23008-12: HEIC, AVIF...): a
phone's photo. Its pictures are items its top-level meta box indexes, with no moov box: no
recording left unfinished. An image sequence (msf1, a moov track of pictures) is a video."""


def heif_brand(head: bytes) -> str | None:
    """What a file whose first bytes are ``head`` is when its first box, ftyp, names a brand
    of :data:`HEIF_STILL_BRANDS` (major or compatible): "HEIC" (HEVC pictures, an iPhone's),
    "AVIF" (AV1) or "HEIF"; None for any other file."""
    if len(head) < 16 or head[4:8] != b"ftyp":
        return None
    end = min(len(head), int.from_bytes(head[:4], "big"))
    brands = {head[8:12]} | {head[i : i + 4] for i in range(16, end - 3, 4)}
    if not brands & HEIF_STILL_BRANDS:
        return None
    if brands & {b"heic", b"heix", b"heim", b"heis"}:
        return "HEIC"
    return "AVIF" if b"avif" in brands else "HEIF"


def picture_words(head: bytes) -> str | None:
    """What a still picture whose first bytes are ``head`` is, in a refusal's words: a PNG
    or JPEG as :data:`PICTURE_WORDS`; a phone's WebP, HEIC or AVIF photo (:func:`heif_brand`)
    or a TIFF by its format; None for anything else."""
    if is_picture(head):
        return PICTURE_WORDS
    if head.startswith(b"RIFF") and head[8:12] == b"WEBP":
        return "a WebP picture"
    if head.startswith((b"II*\x00", b"MM\x00*")):
        return "a TIFF picture"
    brand = heif_brand(head)
    if brand is not None:
        return f"{'an' if brand == 'AVIF' else 'a'} {brand} picture"
    return None


#: The first bytes of every SQLite database file (a case base).
SQLITE_MAGIC = b"SQLite format 3\x00"


#: the first two bytes of every gzip file (RFC 1952)
GZIP_MAGIC = b"\x1f\x8b"


def binary_kind(head: bytes) -> str | None:
    """What a file whose first bytes are ``head`` is, when it is a binary file a user could
    give in the place of another (a case base, a pose file, a zip archive, a video, a
    picture): words for the one line refusing it ("a NumPy file, such as a pose file"); None
    for any other file."""
    if head.startswith(SQLITE_MAGIC):
        return "a SQLite database, such as a case base"
    if head.startswith(b"\x93NUMPY") or _first_zip_member(head).endswith(b".npy"):
        return "a NumPy file, such as a pose file"
    if head.startswith(b"PK\x03\x04"):  # a .zip, an .xlsx spreadsheet: no arrays in it
        return "a zip archive, not a pose file"
    if head.startswith(GZIP_MAGIC):  # a file kept compressed (x.txt.gz, x.csv.gz)
        return "a gzip-compressed file (gunzip it first)"
    if (picture := picture_words(head)) is not None:  # before video: a HEIF photo's ftyp
        return picture
    if is_video(head):
        return "a video file"
    return None


@dataclass(frozen=True)
class NotUTF8:
    """What bytes that are not UTF-8 text are (:func:`not_utf8`), for the one line refusing
    them: ``binary``, a binary file a user could give in the place of a text file
    (:func:`binary_kind`'s words; None for none); ``utf16``, UTF-16 text by its byte order
    mark (Notepad's "Unicode", Excel's "Unicode Text", PowerShell's ``>``); ``where``, where
    its first byte that is not UTF-8 stands ("invalid start byte at byte 4, line 2")."""

    binary: str | None
    utf16: bool
    where: str


def not_utf8(data: bytes, exc: UnicodeDecodeError) -> NotUTF8:
    """What ``data``, the bytes of a text file that did not decode as UTF-8 (``exc``), are."""
    line = data.count(b"\n", 0, exc.start) + 1
    return NotUTF8(
        binary_kind(data[:512]),
        data.startswith((b"\xff\xfe", b"\xfe\xff")),
        f"{exc.reason} at byte {exc.start}, line {line}",
    )


def is_video(head: bytes) -> bool:
    """Whether a file's first bytes ``head`` are a video's: MP4 or QuickTime (an ``ftyp``
    box first), AVI (RIFF ... AVI) or Matroska/WebM (its EBML signature)."""
    return (
        head[4:8] == b"ftyp"
        or (head.startswith(b"RIFF") and head[8:12] == b"AVI ")
        or head.startswith(b"\x1a\x45\xdf\xa3")
    )


def _first_zip_member(head: bytes) -> bytes:
    """The name of the first member of a zip file whose first bytes are ``head``, from its
    local file header (the name's length at bytes 26-27, the name from byte 30); b"" for
    what is not a zip. A .npz (a pose file) is a zip of ``<array>.npy`` members."""
    if not head.startswith(b"PK\x03\x04") or len(head) < 30:
        return b""
    return head[30 : 30 + int.from_bytes(head[26:28], "little")]


def file_head(path: str | Path, n: int = 512) -> bytes:
    """The first ``n`` bytes of the file at ``path`` (b"" for one that cannot be read)."""
    try:
        with open(path, "rb") as f:
            return f.read(n)
    except OSError:
        return b""


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def path_digest(path: str | Path) -> str:
    """The first 16 hex digits of the SHA-256 of ``path`` resolved: which file it is, from
    any folder, without the path itself (which a file passed on would give away)."""
    where = str(Path(path).resolve()).encode("utf-8", "surrogateescape")
    return hashlib.sha256(where).hexdigest()[:16]


@contextmanager
def atomic_path(
    path: str | Path, *, make_parents: bool = True, suffix: str = ".tmp"
) -> Iterator[Path]:
    """A temporary path beside ``path``; renamed to ``path`` when the block ends normally.

    The temporary file has the permissions of an ordinary new file (umask applied). On an error
    inside the block it is removed and ``path`` is left as it was. ``suffix``: the temporary
    name's ending, for writers that choose the format by it (OpenCV's video writer).
    ``path`` itself a temporary this process is writing (:func:`write_together`'s, given to
    a writer that writes atomically) is written in place: its own writer renames it, and
    removes it on an error (a temporary of a temporary, named after it, would be left by a
    kill, which no later writer of the file removes as its own).
    """
    dest = Path(path)
    if dest in _UNFINISHED:
        yield dest
        return
    _refuse_special(dest, "output")
    try:
        if make_parents:
            dest.parent.mkdir(parents=True, exist_ok=True)
        tmp = temporary_file(dest, suffix)
    except OSError as exc:
        raise DataError(write_error(exc), dest) from None
    try:
        _UNFINISHED.add(tmp)
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; outputs are ordinary files
        os.replace(tmp, dest)
    except BrokenPipeError:  # standard output's reader has gone: not this file's fault
        raise
    except OSError as exc:
        raise DataError(write_error(exc), dest) from None
    finally:
        tmp.unlink(missing_ok=True)
        _UNFINISHED.discard(tmp)


WRITE_PROBE = 1 << 16
"""How many bytes :func:`write_failure` writes: more than FFmpeg writes at once (its 32-KiB
buffer), so that the room left in the last block of a full disk does not hold them."""


def write_failure(path: Path) -> int | None:
    """The error (errno) writing :data:`WRITE_PROBE` more bytes at the end of ``path``, a file
    a writer that only warns when a write fails (OpenCV's video writer) did not write whole, a
    temporary removed after, gives: ENOSPC where the disk is full, EFBIG past a file size
    limit; None where they are written (it failed for another reason)."""
    try:
        with open(path, "ab") as fh:
            fh.write(bytes(WRITE_PROBE))
    except OSError as exc:
        return exc.errno
    return None


def cannot_write(code: int | None, seen: str) -> str:
    """Why a file was not written, from the error (errno, :func:`write_failure`; None: not
    known) and what was ``seen`` of the failure: the disk full (as the case base store says
    it), a file size limit, else ``seen`` alone."""
    if code in (errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)):
        quota = "" if code == errno.ENOSPC else " (its quota used up)"
        return f"cannot write: the disk is full{quota} ({seen}): free some space and run again"
    if code == errno.EFBIG:
        return f"cannot write: the file would grow past a size limit such as `ulimit -f` ({seen})"
    return f"cannot write: {seen}"


def write_error(exc: OSError) -> str:
    """Why a file was not written, from ``exc`` raised writing it: the disk full, its quota
    used up or a file size limit as :func:`cannot_write` says them (as the case base store,
    overlays and ``watch --out`` say them), another error in its own words. Every writer of
    the command line says its failures through this."""
    return cannot_write(exc.errno, exc.strerror or str(exc))


# the temporaries of atomic_path and write_together being written in this process
_UNFINISHED: set[Path] = set()


def remove_unfinished_temporaries() -> None:
    """Remove the hidden temporaries this process is writing (:func:`atomic_path`,
    :func:`write_together`), for a process about to end without unwinding their writers: a
    worker whose task, told to stop, did not stop in time (:mod:`features.interrupts`)."""
    for tmp in list(_UNFINISHED):
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)


def stdout_gone() -> None:
    """Standard output's reader has gone (``| head``, a consumer that exited): what is left
    to print goes nowhere (the file descriptor too, so the interpreter's flush at exit does
    not fail again)."""
    devnull = open(os.devnull, "w")  # noqa: SIM115 - kept open to the end of the process
    try:
        os.dup2(devnull.fileno(), sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no file descriptor (a captured stream)
        pass
    sys.stdout = devnull


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname()) or "host"


#: the longest output name a temporary carries whole: a file name has at most 255 bytes, and
#: a temporary adds its writer, a random part and a suffix (SQLite's "-journal") to it
NAME_KEPT = 160


def temporary_name(name: str) -> str:
    """``name`` as the temporaries of an output so called carry it: whole, or when longer
    than :data:`NAME_KEPT` bytes its start and a digest of the whole (a legal name of 250
    bytes would make a temporary's name too long to create)."""
    data = name.encode("utf-8", "surrogateescape")
    if len(data) <= NAME_KEPT:
        return name
    start = data[: NAME_KEPT - 17].decode("utf-8", "ignore")
    return f"{start}~{hashlib.sha256(data).hexdigest()[:16]}"


def temporary_prefix(name: str) -> str:
    """The start of this process's hidden temporaries for an output called ``name``:
    ``.NAME.pidPID@HOST.`` (NAME shortened as :func:`temporary_name` says)."""
    return f".{temporary_name(name)}.pid{os.getpid()}@{_host()}."


def temporary_file(dest: str | Path, suffix: str = ".tmp") -> Path:
    """A new empty hidden file beside ``dest`` to write it in (then renamed over it), after
    removing the stale ones a dead writer of ``dest`` left (:func:`remove_stale_temporaries`).
    Raises OSError."""
    dest = Path(dest)
    remove_stale_temporaries(dest.parent, dest.name)
    prefix = temporary_prefix(dest.name)
    try:
        fd, name = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=dest.parent)
        os.close(fd)
        return Path(name)
    except (KeyboardInterrupt, SystemExit):
        _remove_own(dest.parent, prefix, suffix)
        raise


def _remove_own(folder: Path, prefix: str, suffix: str) -> None:
    """Ctrl-C or SIGTERM came while a temporary was being made, after its file was created
    but before its name was returned (it was left behind): this process's temporaries of
    that output are removed (no command writes one output twice at once)."""
    with contextlib.suppress(OSError):
        for path in folder.iterdir():
            if path.name.startswith(prefix) and path.name.endswith(suffix) and path.is_file():
                path.unlink(missing_ok=True)


def staging_folder(folder: str | Path, name: str) -> Path:
    """A new hidden folder in ``folder`` to build outputs in (``name`` says whose, e.g.
    ``posecbr-convert``), after removing the stale ones of dead writers. Raises OSError."""
    remove_stale_temporaries(folder, name)
    return Path(tempfile.mkdtemp(prefix=temporary_prefix(name), dir=folder))


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


#: How a temporary worth keeping ends, before its own suffix (``.partial.nut``): a copy of
#: an output being written that is playable as far as it goes (a video in a container that
#: needs no index at its end), which a writer killed before it finished (``kill -9``, power
#: loss) leaves as all there is of its work. The next writer of the output keeps it under
#: a visible name (:func:`remove_stale_temporaries`); the writer itself removes it as any
#: temporary when it ends.
PARTIAL = ".partial"

_PARTIAL_END = re.compile(rf"{re.escape(PARTIAL)}(\.[A-Za-z0-9]{{1,8}})$")


def _keep_partial(entry: Path, name: str, pid: int) -> None:
    """A dead writer's temporary ``entry`` of output ``name`` worth keeping (:data:`PARTIAL`)
    renamed ``STEM.partial.EXT`` beside it (``STEM.partial-2.EXT``, ... when that is taken:
    never over another file), said on stderr; left as it is when it cannot be renamed."""
    ext = _PARTIAL_END.search(entry.name)
    if ext is None:
        return
    stem = temporary_name(Path(name).stem)
    for i in range(1, 1000):
        target = entry.parent / f"{stem}{PARTIAL}{'' if i == 1 else f'-{i}'}{ext.group(1)}"
        try:
            os.link(entry, target, follow_symlinks=False)  # fails on a file there: not over it
        except FileExistsError:
            continue
        except OSError:  # no hard links on this file system: renamed where no file is
            if os.path.lexists(target):
                continue
            try:
                os.replace(entry, target)
            except OSError:
                return
        else:
            entry.unlink(missing_ok=True)
        print(
            f"note: {shown(entry.parent / name)}: a writer of it (process {pid}) was killed"
            f" before it finished: what it had written is kept as {shown(target)}",
            file=sys.stderr,
        )
        return


def remove_stale_temporaries(folder: str | Path, name: str) -> int:
    """Remove the hidden temporaries (files or staging folders) for output ``name`` in
    ``folder`` whose writer, a process of this machine, is gone; returns how many. Those of
    live processes (a writer at work) and of other machines (a shared folder: their processes
    cannot be asked) are kept; so are temporaries named otherwise. A dead writer's file
    named as one worth keeping (:data:`PARTIAL`) is kept under a visible name, and said."""
    pattern = re.compile(rf"^\.{re.escape(temporary_name(name))}\.pid(\d+)@([A-Za-z0-9-]*)\.")
    host, removed = _host(), 0
    try:
        entries = list(Path(folder).iterdir())
    except OSError:
        return 0
    for entry in entries:
        m = pattern.match(entry.name)
        if m is None or m.group(2) != host or _alive(int(m.group(1))):
            continue
        if _PARTIAL_END.search(entry.name) and entry.is_file() and not entry.is_symlink():
            _keep_partial(entry, name, int(m.group(1)))
            continue
        try:
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
            removed += 1
        except OSError:  # another writer removed it first, or it is not ours to remove
            pass
    return removed


def write_bytes_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8, newlines as given) to ``path`` atomically."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
    return Path(path)


def write_json_atomic(path: str | Path, obj: Any, *, indent: int | None = 1) -> Path:
    """Write ``obj`` as JSON (UTF-8, non-ASCII kept, NaN allowed) to ``path`` atomically."""
    text = json.dumps(obj, indent=indent, ensure_ascii=False, allow_nan=True)
    return write_text_atomic(path, text + "\n")


def _set_aside(dest: Path) -> tuple[Path | None, bool]:
    """A hidden second name for the file at ``dest``, to put it back with (``None`` when
    there is no file), and whether the file was moved to it: it is a hard link, or where the
    file system has none (FAT, some network shares) the file itself, renamed."""
    if not os.path.lexists(dest):
        return None, False
    aside = temporary_file(dest, ".old")  # a stale one (a writer killed) only a link: removed
    aside.unlink()
    try:
        os.link(dest, aside, follow_symlinks=False)
    except OSError:  # the earlier file itself: under a name no later writer removes as stale
        fd, name = tempfile.mkstemp(
            prefix=f".{temporary_name(dest.name)}.earlier.", dir=dest.parent
        )
        os.close(fd)
        os.replace(dest, name)
        return Path(name), True
    return aside, False


def _nothing_written(
    n: int,
    earlier: Sequence[Path],
    lost: Sequence[Path] = (),
    asides: Sequence[Path] = (),
    before: str = "the earlier",
) -> str:
    """What a write of ``n`` files as one that failed says after its reason; ``lost``: the
    earlier files that could not be put back, left under the hidden names ``asides``;
    ``before``: what the files there before are called."""
    said = "not written" if n == 1 else f"none of the {n} files written"
    kept = [p for p in earlier if p not in lost]
    if kept:
        said += f" ({before} {_names(kept)} kept as {'they were' if len(kept) > 1 else 'it was'})"
    if lost:
        said += f"; {before} {_names(lost)} could not be put back: left as {_names(asides)}"
    return said


def replace_together(moves: Sequence[tuple[Path, Path]], before: str = "the earlier") -> None:
    """Rename each staged file onto its destination (``(staged, destination)`` pairs) as one.
    When a rename fails (or Ctrl-C comes), those done are undone: each destination back to
    its earlier file, or gone when it had none. A failure is raised as a DataError naming
    the destination, saying nothing was written, and naming any earlier file that could not
    be put back (it stays under its hidden name); ``before``: what the files there before
    are called in it (the earlier ones, unless the caller wrote them itself)."""
    earlier = [dest for _, dest in moves if os.path.lexists(dest)]
    done: list[tuple[Path, Path | None]] = []  # each destination replaced, its earlier file
    dest = moves[0][1] if moves else Path()
    try:
        for staged, dest in moves:
            aside, moved = _set_aside(dest)
            try:
                os.replace(staged, dest)
            except BaseException:
                if moved:  # the destination is gone: its earlier file goes back
                    done.append((dest, aside))
                elif aside is not None:  # a link: the destination is still the earlier file
                    aside.unlink(missing_ok=True)
                raise
            done.append((dest, aside))
    except OSError as exc:
        lost = _put_back(done)
        lost_, asides = [d for d, _ in lost], [a for _, a in lost]
        why = _nothing_written(len(moves), earlier, lost_, asides, before)
        said = f"{write_error(exc)}; {why}"
        raise DataError(said, dest) from None
    except BaseException:
        _put_back(done)
        raise
    for _, aside in done:
        if aside is not None:
            with contextlib.suppress(OSError):
                aside.unlink()


def _put_back(done: list[tuple[Path, Path | None]]) -> list[tuple[Path, Path]]:
    """Each destination of ``done`` as it was before its rename; returns those that could
    not be, each with the hidden name its earlier file is left under."""
    failed = []
    for dest, aside in reversed(done):
        try:
            if aside is None:
                dest.unlink(missing_ok=True)
            else:
                os.replace(aside, dest)
        except OSError:
            if aside is not None:
                failed.append((dest, aside))
    return failed


def _names(paths: Sequence[Path]) -> str:
    """``paths`` as a message lists them: by name when they share a folder."""
    one_folder = len({p.parent for p in paths}) == 1
    names = [p.name if one_folder else str(p) for p in paths]
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def write_together(
    files: Sequence[tuple[Path, Callable[[Path], object]]],
    before: str = "the earlier",
    *,
    suffixed: bool = False,
    make_parents: bool = False,
) -> None:
    """Several files written as one: each by its function, given a hidden temporary beside
    the file (:func:`temporary_file`; ``suffixed``: its name ending ``.tmp`` and the file's
    own suffix, for writers that choose the format by the name, OpenCV's video writer and
    matplotlib's; ``make_parents``: its folder made if need be, which a failure leaves:
    :func:`remove_empty`), then all renamed into place together (:func:`replace_together`). A
    failure anywhere (a disk full, a write refused, an I/O error) leaves every file as it
    was, its earlier version or none, and raises one DataError naming the file that failed
    and saying so (``before``: what it calls the files there before); Ctrl-C leaves them so
    too."""
    staged: list[tuple[Path, Path]] = []
    try:
        for dest, write in files:
            try:
                _refuse_special(dest, "output")
                if make_parents:
                    dest.parent.mkdir(parents=True, exist_ok=True)
                staged.append(
                    (temporary_file(dest, f".tmp{dest.suffix if suffixed else ''}"), dest)
                )
                _UNFINISHED.add(staged[-1][0])
                write(staged[-1][0])
                os.chmod(staged[-1][0], 0o666 & ~_umask())  # as atomic_path's
            except (OSError, PosecbrError) as exc:
                why = exc.message if isinstance(exc, PosecbrError) else write_error(exc)
                earlier = [d for d, _ in files if os.path.lexists(d)]
                said = _nothing_written(len(files), earlier, before=before)
                raise DataError(f"{why}; {said}", dest) from None
        replace_together(staged, before)
    finally:
        for tmp, _ in staged:
            with contextlib.suppress(OSError):
                tmp.unlink(missing_ok=True)
            _UNFINISHED.discard(tmp)


def folders_to_make(files: Iterable[Path]) -> list[Path]:
    """The folders writing ``files`` makes, deepest first: each file's folder and those of its
    parents that do not exist yet (:func:`remove_empty` takes them away again when the write
    fails)."""
    missing: set[Path] = set()
    for dest in files:
        for folder in dest.parents:
            if folder in missing or folder.exists():
                break
            missing.add(folder)
    return sorted(missing, key=lambda p: (-len(p.parts), str(p)))


def remove_empty(folders: Sequence[Path]) -> None:
    """Remove those of ``folders`` (deepest first, :func:`folders_to_make`) that nothing was
    written into: a failed write leaves no folder it made. One that is not empty stays, and
    so does any it is in."""
    for folder in folders:
        try:
            folder.rmdir()  # only an empty folder goes
        except OSError:
            continue


@contextmanager
def staged_folder(folder: str | Path, *, last: Collection[str] = ()) -> Iterator[Path]:
    """A hidden staging folder inside ``folder`` (made if need be) to write several files as one.

    When the block ends normally each file written in the staging folder (flat, no subfolders)
    is moved into ``folder`` under its name, those named in ``last`` after the others (an index
    that names the rest); a move that fails puts back those done (:func:`replace_together`).
    On an error the staging folder is removed, and ``folder`` too if the block made it:
    ``folder`` is left as it was.
    """
    out = Path(folder)
    created = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
        stage = staging_folder(out, "posecbr-stage")
    except OSError as exc:
        raise DataError(f"cannot create: {exc.strerror or exc}", out) from None
    try:
        yield stage
        staged = sorted(stage.iterdir(), key=lambda p: (p.name in last, p.name))
        # one rename failing puts back those done: the folder's earlier files, not half new
        replace_together([(path, out / path.name) for path in staged])
        stage.rmdir()
    except BaseException as exc:
        if isinstance(exc, PosecbrError) and exc.source and Path(exc.source).parent == stage:
            exc.named(out / Path(exc.source).name)  # the file as it is to be, not as staged
        shutil.rmtree(stage, ignore_errors=True)
        if created:
            shutil.rmtree(out, ignore_errors=True)
        raise


def unique_name(stem: str, taken: set[str]) -> str:
    """``stem``, or ``stem_2``, ``stem_3``, ... the first not in ``taken`` (lower-case names,
    to which it is added): outputs of several inputs with one name each keep their own."""
    name, k = stem, 2
    while name.lower() in taken:
        name, k = f"{stem}_{k}", k + 1
    taken.add(name.lower())
    return name


def _identity(path: Path) -> tuple[Path, tuple[int, int] | None] | None:
    """``path`` resolved, and the device and inode of the file it names (None for a file
    that is not there); None if the system cannot resolve it (an input so named is never
    the output's file)."""
    try:
        resolved = path.resolve()
    except (OSError, RuntimeError):  # RuntimeError: a loop of symbolic links (Python < 3.13)
        return None
    try:
        st = path.stat()
    except OSError:
        return resolved, None
    return resolved, (st.st_dev, st.st_ino)


class ReadFiles:
    """What a command reads (:func:`_read_from` of every input), each file resolved and
    looked up once: :func:`check_output` asks of every output whether it is one of them,
    and a command with many outputs and many inputs (``convert`` of a corpus: each clip's
    pose file against every file of the source) asks in constant time, not one look-up of
    every input per output. Two paths are one file when they resolve to the same path or,
    both there, are the same file on one device (a hard link)."""

    def __init__(self, inputs: Iterable[str | Path]) -> None:
        self._by_path: dict[Path, tuple[int, Path]] = {}
        self._by_file: dict[tuple[int, int], tuple[int, Path]] = {}
        reads = (read for src in inputs for read in _read_from(Path(src)))
        for order, read in enumerate(reads):
            found = _identity(read)
            if found is None:
                continue
            resolved, file_id = found
            self._by_path.setdefault(resolved, (order, read))
            if file_id is not None:
                self._by_file.setdefault(file_id, (order, read))

    def overwritten_by(self, out: Path) -> Path | None:
        """The first input (in the order read) that writing ``out`` would overwrite."""
        found = _identity(out)
        if found is None:
            return None
        resolved, file_id = found
        by_file = None if file_id is None else self._by_file.get(file_id)
        hits = [self._by_path.get(resolved), by_file]
        first = min((h for h in hits if h is not None), default=None)
        return None if first is None else first[1]


def _names_an_open_stream(out: Path) -> bool:
    """``out`` names one of this process's open files: ``/dev/stdout``, ``/dev/fd/1``,
    ``/proc/self/fd/1`` or a link to one of them, each a link into ``/proc``. With standard
    output redirected to a file the link leads to a regular file, but writing there replaces
    the link itself (``/dev/stdout`` made an ordinary file for every process of the machine)."""
    p = Path(os.path.abspath(out))
    for _ in range(40):  # the kernel's own limit on links followed
        parent = Path(os.path.realpath(p.parent))
        if parent.parts[:2] == ("/", "proc"):
            return parent.name == "fd"  # /proc/<pid>/fd/N; elsewhere in /proc no stream
        if not p.is_symlink():
            return False
        p = Path(os.path.abspath(p.parent / os.readlink(p)))
    return False


def _kernel_folder(out: Path) -> str | None:
    """``/proc`` or ``/sys`` when ``out`` (its folder resolved) lies in one: file systems the
    kernel makes up, in which no file can be made, whatever the permissions say (root's
    check passed: ``segment --plot /proc/x.png`` was called standard output, and ``/sys``
    failed only once the work was done)."""
    top = Path(os.path.realpath(Path(os.path.abspath(out)).parent)).parts[:2]
    return top[1] if len(top) == 2 and top[0] == "/" and top[1] in ("proc", "sys") else None


def as_path(value: Any, name: str) -> Path:
    """A file or folder argument ``value`` as a Path; what is no path (None: an unset
    variable; a number) is an InputError naming the argument ``name``, where ``Path(None)``
    said "expected str, bytes or os.PathLike object, not NoneType"."""
    if not isinstance(value, str | os.PathLike):
        raise InputError(f"must be a file path, got {value!r}", name)
    return Path(value)


def path_exists(path: Path, lead: str = "", where: Path | None = None) -> bool:
    """Whether ``path`` exists; a path the system cannot even look up (too long, a NUL
    character, symbolic links that lead round in a loop) is a DataError naming ``where``
    (default: the path), its message after ``lead``. Python's ``exists`` calls a loop of
    links missing, and every input in one was refused as "no such file"."""
    try:
        return _exists(path)
    except (OSError, ValueError) as exc:
        reason = _lookup_failed(exc)
        raise DataError(f"{lead}cannot use the path ({reason})", where or path) from None


def _exists(path: Path) -> bool:
    """``path.exists()``, but symbolic links that lead round in a loop raise the system's
    OSError (ELOOP), which ``exists`` takes for a missing file."""
    if path.exists():
        return True
    try:
        os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return False
    return True  # made between the two looks


def _lookup_failed(exc: OSError | ValueError) -> str:
    """Why the system could not look a path up, in words."""
    if isinstance(exc, OSError) and exc.errno == errno.ELOOP:
        return "symbolic links that lead round in a loop"
    return exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)


def check_lookup(path: Path, what: str) -> None:
    """A DataError naming ``path`` when the system cannot even look it up (a file name over
    255 bytes): asked whether it is a folder, Python raises there, a traceback."""
    try:
        _exists(path)
    except OSError as exc:
        raise DataError(f"cannot use the {what} path ({_lookup_failed(exc)})", path) from None


def _refuse_special(out: Path, what: str) -> None:
    """A device, pipe or socket at ``out`` is not replaced by a file (``--plot /dev/null``
    would put a picture where the system's null device was); nor is "-", the usual name of
    standard output (which no output here is), made a file of that name, nor a name of
    standard output or another open stream such as ``/dev/stdout``."""
    if str(out) == "-":
        raise DataError(f"the {what} goes to a file, not standard output: name the file", out)
    if _names_an_open_stream(out):
        raise DataError(
            f"names standard output or another open stream, not a file: name a file for the {what}",
            out,
        )
    kernel = _kernel_folder(out)
    if kernel is not None:
        raise DataError(
            f"cannot write the {what}: /{kernel} is the kernel's view of the system, where no"
            " file can be made; name a file elsewhere",
            out,
        )
    if out.exists() and not out.is_file():
        raise DataError(f"the {what} is not a regular file (a device, pipe or socket)", out)


def _read_from(src: Path) -> list[Path]:
    """What reading ``src`` reads: the file; of a folder, also its ``labels.csv`` (the
    clips' labels when it has one); of a file, the companions its reader opens with it: a
    UI-PRMD positions file's angles file, an AMC recording's skeleton (every ``.asf`` beside
    it: the reader picks one of them)."""
    if src.is_dir():
        return [src, src / "labels.csv"]
    if "_positions" in src.name:
        from .readers.uiprmd import angles_path_for  # the reader's own rule

        return [src, angles_path_for(src)]
    if src.suffix.lower() == ".amc" and src.parent.is_dir():
        return [src, *(p for p in src.parent.iterdir() if p.suffix.lower() == ".asf")]
    return [src]


def _check_folders_to_make(out: Path, what: str) -> None:
    """The folders of ``out`` a writer makes can be made: the nearest one there is a folder,
    and none to make is a symbolic link to nothing (making it fails, after the work)."""
    parent = next((p for p in out.parents if p.exists()), None)
    if parent is not None and not parent.is_dir():
        raise DataError(f"cannot write the {what}: {parent} is a file, not a folder", out)
    link = next((p for p in out.parents if p.is_symlink() and not p.exists()), None)
    if link is not None:
        raise DataError(
            f"cannot write the {what}: {link} is a symbolic link to {os.readlink(link)},"
            " which does not exist",
            out,
        )


def check_not_in_walked_folder(
    out: str | Path,
    folder: str | Path,
    what: str,
    *,
    same_too: bool = True,
    folder_what: str = "the input folder",
) -> None:
    """Refuse an output folder inside ``folder`` (or ``folder`` itself when ``same_too``), a
    folder read as one subfolder per class (``folder_what``: what it is, for the message):
    what is written there would be read as one more class (or each clip twice) the next time
    the folder is read. One line naming both."""
    out_r, folder_r = Path(out).resolve(), Path(folder).resolve()
    if out_r == folder_r and same_too:
        raise DataError(
            f"the {what} is {folder_what}, read as one subfolder per class: what is written"
            " there would be read as clips the next time; choose a folder outside it",
            out,
        )
    if folder_r in out_r.parents:
        raise DataError(
            f"the {what} is inside {folder_what} {folder}, read as one subfolder per class:"
            " what is written there would be read as another class the next time; choose a"
            " folder outside it",
            out,
        )


def check_output(
    path: str | Path,
    *,
    inputs: Iterable[str | Path] | ReadFiles = (),
    what: str = "output",
    must_not_exist: bool = False,
    make_parents: bool = False,
) -> Path:
    """Check an output path before any work starts; returns it as a Path.

    Refused, with one line naming the path: "-" (taken for standard output, it was a file
    named "-"); a folder; a file inside a folder that does not
    exist (unless ``make_parents``: the writer creates it, so only a file in its way is
    refused); a file in a folder this process cannot write (a read-only mount: found before
    the work, not when the result is written); one of ``inputs`` or, of a folder among them,
    its ``labels.csv`` (an output never overwrites an input; a :class:`ReadFiles` made once
    serves many outputs); an existing file when ``must_not_exist``.
    """
    out = Path(path)
    check_lookup(out, what)
    if out.is_dir():
        raise DataError(f"the {what} is a folder, not a file", out)
    _refuse_special(out, what)
    if make_parents:
        _check_folders_to_make(out, what)
    elif out.parent.exists() and not out.parent.is_dir():
        raise DataError(f"cannot write the {what} into it: it is a file, not a folder", out.parent)
    elif not out.parent.is_dir():
        raise DataError(f"the folder of the {what} does not exist", out.parent)
    folder = next((p for p in out.parents if p.exists()), None)
    if folder is not None and folder.is_dir() and not os.access(folder, os.W_OK | os.X_OK):
        raise DataError(f"cannot write the {what}: the folder {folder} is read-only", out)
    read = (inputs if isinstance(inputs, ReadFiles) else ReadFiles(inputs)).overwritten_by(out)
    if read is not None:
        raise DataError(f"the {what} would overwrite an input ({read})", out)
    if must_not_exist and out.exists():
        raise DataError(f"the {what} already exists", out)
    return out
