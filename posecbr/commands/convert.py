"""``posecbr convert SOURCE --out DIR``: motion capture data -> pose files, one per clip.

SOURCE is a UI-PRMD folder, an HDM05 (or CMU) ASF/AMC folder, one ``.amc`` file (its ``.asf``
beside it or given with ``--asf``), a ``.bvh`` file, or any other dataset ``iter_dataset``
reads (labels CSV, class folders). Each clip is written to DIR as ``<name>.npz`` with its
label, subject and extras in the metadata, and DIR/labels.csv (``path,label,subject,...``)
lists them, so DIR is itself a dataset for every command; converting into a folder that has
a labels.csv adds to it (a clip converted again replaces its row; another recording whose
pose file would take the name, or the name but for case, of a file there is refused).

The frame rate each clip is written with, and where it came from, is printed: AMC files carry
none (120 Hz, the CMU and HDM05 rate, is assumed unless an HDM05 name states one; a CMU name
such as ``13_29.amc`` is subject and trial, not a rate); ``--fps`` sets it for every clip.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
from collections.abc import Iterable, Iterator
from collections.abc import Set as AbstractSet
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from features.errors import ConfigError, DataError
from features.fileio import (
    ReadFiles,
    binary_kind,
    check_not_in_walked_folder,
    check_output,
    file_head,
    path_exists,
    staged_folder,
    unique_name,
    write_text_atomic,
)
from features.text import counted, first_few, shown
from posecbr.arguments import check_each_found, held_words, path_arg
from posecbr.recordings import add_sensor_option, check_fps, sensor_for

if TYPE_CHECKING:
    from features.clips import Clip
    from features.poses import PoseSequence


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = subparsers.add_parser(
        "convert",
        epilog="example: posecbr convert UI-PRMD/ --out poses/ --subjects s01,s02",
        help="convert UI-PRMD, HDM05/ASF-AMC or BVH data into pose files",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("source", type=path_arg, help="dataset folder, .amc, .bvh, labels CSV, ...")
    p.add_argument(
        "--out", type=path_arg, required=True, metavar="DIR", help="output folder (created)"
    )
    add_sensor_option(p)
    p.add_argument(
        "--asf",
        type=path_arg,
        metavar="FILE.asf",
        help="skeleton for a single .amc (default: the one beside it)",
    )
    p.add_argument(
        "--subjects", help="comma list, e.g. s01,s02 (UI-PRMD) or bd,dg (HDM05) (default all)"
    )
    p.add_argument("--movements", help="UI-PRMD movements, e.g. m01,m07 (default all)")
    p.add_argument("--labels", help="comma list of labels to keep (default all)")
    p.add_argument("--episodes", help="episodes/takes, e.g. 1-3 or 1,4,7-9 (default all)")
    p.add_argument("--correct", action="store_true", help="only correct repetitions (UI-PRMD)")
    p.add_argument("--incorrect", action="store_true", help="only incorrect repetitions (UI-PRMD)")
    p.add_argument(
        "--limit", type=int, metavar="N", help="at most this many clips (default: no limit)"
    )
    p.add_argument(
        "--fps",
        type=float,
        help="frame rate of the source (frames per second), for every clip; default: from the"
        " files (an AMC file carries none: the rate its HDM05 name states, else 120, the CMU"
        " and HDM05 rate)",
    )
    p.add_argument(
        "--float32",
        action="store_true",
        help="store positions as float32 (half the size; readers cast back to float64)",
    )
    p.add_argument(
        "--bvh-unit",
        default="auto",
        help="BVH unit: m, cm, mm, inch, cmu (the CMU database's inches/0.45) or auto"
        " (default: guessed from the rest pose)",
    )
    p.add_argument(
        "--bvh-up",
        choices=("y", "z"),
        default="y",
        help="the axis a BVH file has pointing up: y (default; most exporters) or z (e.g."
        " 3ds Max, MotionBuilder set to z up); turned so that y is up, handedness kept",
    )
    p.set_defaults(func=run)


def _csv_list(value: str | None) -> set[str] | None:
    if value is None:
        return None
    items = {v.strip() for v in value.split(",") if v.strip()}
    return items or None


class Ranges(AbstractSet[int]):
    """Whole numbers given as ranges (``"1-3,5"``); membership without listing them, so
    ``1-1000000000`` costs nothing."""

    def __init__(self, ranges: Iterable[range], texts: Iterable[str] = ()) -> None:
        self.ranges = tuple(ranges)
        #: each range as it was written ("1-3", "5"), for naming one no clip lies in
        self.texts = tuple(texts) or tuple(f"{r.start}-{r.stop - 1}" for r in self.ranges)

    def __contains__(self, value: object) -> bool:
        return any(value in r for r in self.ranges)

    def __iter__(self) -> Iterator[int]:
        seen: set[int] = set()
        for r in self.ranges:
            for v in r:
                if v not in seen:
                    seen.add(v)
                    yield v

    def __len__(self) -> int:
        return sum(1 for _ in self)


def parse_ranges(value: str | None) -> Ranges | None:
    """``"1-3,5"`` -> the numbers 1, 2, 3, 5. Raises DataError for anything else."""
    if value is None:
        return None
    out: list[range] = []
    texts: list[str] = []
    for part in value.split(","):
        part = part.strip()
        if not part:
            continue
        try:
            if "-" in part:
                a, b = (int(x) for x in part.split("-", 1))
            else:
                a = b = int(part)
        except ValueError:
            raise DataError(f"not a number or range a-b: {part[:40]!r}", "--episodes") from None
        if b < a:
            raise DataError(f"the range {part!r} runs backwards: write {b}-{a}", "--episodes")
        out.append(range(a, b + 1))
        texts.append(part)
    return Ranges(out, texts)


_RESERVED_COLUMNS = ("path", "label", "subject", "start", "end")
# a clip's extras not made columns
_INTERNAL = ("source", "asf", "origin", "fps_source", "x_reflected")
# What a pose file convert writes says itself, in any case: a labels CSV column of that name
# would be overwritten, or read back as something else, so it is refused.
_WRITTEN = {
    "origin": "where each clip came from",
    "source": "what a pose file was made from",
    "made_from": "what a pose file was made from",
    "fps_source": "where the frame rate came from",
    "asf": "an AMC clip's skeleton file",
    "x_reflected": "why a recording written left-handed was read with x negated",
}


def _safe_name(name: str) -> str:
    """A clip name as a file name: no separators, controls or leading dots."""
    cleaned = "".join("_" if (c in "/\\" or not c.isprintable()) else c for c in name)
    cleaned = cleaned.strip().lstrip(".")
    return cleaned[:200] or "clip"


def _clip_name(clip: Clip, fallback: str) -> str:
    ex = clip.extras
    if ex.get("dataset") == "ui-prmd":
        inc = "" if ex.get("correct", True) else "_inc"
        return _safe_name(f"{ex['movement']}_{clip.subject}_e{int(ex['episode']):02d}{inc}")
    return _safe_name(fallback)


def _single_clips(args: argparse.Namespace) -> list[tuple[Clip, str]]:
    from features.clips import Clip, find_asf
    from features.readers.asfamc import read_asf_amc
    from features.readers.bvh import read_bvh

    src: Path = args.source
    suffix = src.suffix.lower()
    if suffix == ".bvh":
        seq = read_bvh(src, unit=_bvh_unit(args.bvh_unit), up=args.bvh_up)
    else:
        asf = args.asf if args.asf is not None else find_asf(src)
        seq = read_asf_amc(asf, src, fps=args.fps)
    label = str(seq.metadata.get("label", src.stem))
    subject = seq.metadata.get("subject")
    extras = {k: v for k, v in seq.metadata.items() if k not in ("label", "subject")}
    seq = seq.with_metadata(label=label, subject=subject)
    return [(Clip(seq, label, None if subject is None else str(subject), extras), src.stem)]


def _bvh_unit(text: str) -> str | float:
    """``--bvh-unit``: a unit name, ``auto``, or metres per file unit (a positive number)."""
    try:
        unit = float(text)
    except ValueError:
        return text
    if not (math.isfinite(unit) and unit > 0):
        raise DataError(f"must be a unit name or a positive number, got {text!r}", "--bvh-unit")
    return unit


def _inputs(args: argparse.Namespace) -> list[Path]:
    """Every file the conversion reads (from names and listings; nothing is read yet)."""
    from features.clips import find_asf
    from features.datasets import dataset_files

    src: Path = args.source
    if src.is_file() and src.suffix.lower() == ".bvh":
        return [src]
    if src.is_file() and src.suffix.lower() == ".amc":
        return [src, args.asf if args.asf is not None else find_asf(src)]
    return dataset_files(src, sensor=args.sensor)


def _check_no_overwrite(out: Path, inputs: list[Path]) -> None:
    """Refuse an output folder that holds inputs the conversion would write over: pose files
    (``<name>.npz``) and labels.csv go into it, names decided only as clips are read."""
    here = out.resolve()
    clash = [
        f
        for f in inputs
        if f.resolve().parent == here and (f.suffix.lower() == ".npz" or f.name == "labels.csv")
    ]
    if clash:
        raise DataError(
            f"the output folder holds inputs of this conversion ({clash[0].name}"
            f"{f' and {len(clash) - 1} more' if len(clash) > 1 else ''}): writing pose files"
            " and labels.csv there would overwrite them; choose another --out",
            out,
        )


def _check_not_in_source(args: argparse.Namespace) -> None:
    """Refuse an output folder inside a SOURCE read as one subfolder per class (or as a
    folder of clips, which one subfolder of clips turns into class folders): the pose files
    written there would be read as one more class the next time SOURCE is read. Into SOURCE
    itself is allowed: its labels.csv then names the clips (and a pose file there that
    would be replaced is refused by :func:`_check_no_overwrite`)."""
    from features.datasets import detect_kind

    src: Path = args.source
    if src.is_dir() and detect_kind(src) in ("class_folders", "pose_folder"):
        check_not_in_walked_folder(args.out, src, "output folder", same_too=False)


def _check_args(args: argparse.Namespace) -> None:
    src: Path = args.source
    if not path_exists(src):
        raise DataError("no such file or folder", src)
    check_fps(args.fps)  # the rates a pose file takes: 0.005 was refused only when written
    if args.correct and args.incorrect:
        raise DataError("choose --correct or --incorrect, not both", "--correct")
    if args.limit is not None and args.limit < 1:
        raise DataError(f"must be at least 1, got {args.limit}", "--limit")
    if args.out.exists() and not args.out.is_dir():
        raise DataError("exists and is not a folder", args.out)
    _bvh_unit(args.bvh_unit)
    parse_ranges(args.episodes)
    _check_one_file_options(args)
    _check_folder_options(args)
    _check_columns(src)
    _check_overlaps(args)
    args.sensor = sensor_for(args.sensor, [src])


def _check_one_file_options(args: argparse.Namespace) -> None:
    """Refuse, for one .amc or .bvh file, what would be ignored: the filters of a dataset
    folder (it is converted as it is), ``--asf`` for a BVH file, ``--bvh-unit`` and
    ``--bvh-up`` for an AMC file, and the UI-PRMD options."""
    src: Path = args.source
    suffix = src.suffix.lower()
    if not (src.is_file() and suffix in (".bvh", ".amc")):
        return
    for flag, given in (
        ("--subjects", args.subjects), ("--movements", args.movements),
        ("--labels", args.labels), ("--episodes", args.episodes),
        ("--correct", args.correct), ("--incorrect", args.incorrect),
    ):  # fmt: skip
        if given:
            raise DataError(
                f"filters the clips of a dataset folder; {src.name} is one file, converted as it"
                " is",
                flag,
            )
    if suffix == ".bvh" and args.asf is not None:
        raise DataError(f"goes with an AMC file, not {src.name}", "--asf")
    for flag, given in (("--bvh-unit", args.bvh_unit != "auto"), ("--bvh-up", args.bvh_up != "y")):
        if suffix == ".amc" and given:
            raise DataError(f"goes with BVH files, not {src.name}", flag)


def _check_folder_options(args: argparse.Namespace) -> None:
    """Refuse, for a dataset (a folder or labels CSV), what would be ignored: ``--asf``,
    ``--bvh-unit`` and ``--bvh-up`` (they go with one .amc or .bvh file) and, for an HDM05 or
    CMU folder, the UI-PRMD options."""
    from features.datasets import detect_kind

    src: Path = args.source
    if src.is_file() and src.suffix.lower() in (".bvh", ".amc"):
        return
    if args.asf is not None:
        raise DataError(f"goes with one .amc file, not the dataset {src.name}", "--asf")
    for flag, given in (("--bvh-unit", args.bvh_unit != "auto"), ("--bvh-up", args.bvh_up != "y")):
        if given:
            raise DataError(f"goes with one .bvh file, not the dataset {src.name}", flag)
    if detect_kind(src) == "asf_amc":
        for flag, given in (("--correct", args.correct), ("--incorrect", args.incorrect)):
            if given:
                raise DataError(
                    f"goes with UI-PRMD; {src.name} is an ASF/AMC folder, whose clips are not"
                    " marked correct or incorrect",
                    flag,
                )


def _check_columns(src: Path) -> None:
    """Refuse a labels CSV with a column named as something convert writes in each pose file
    itself (:data:`_WRITTEN`, in any case): the column's values would be lost or misread."""
    from features.datasets import detect_kind
    from features.labels_csv import read_labels_csv

    if (src.is_file() and src.suffix.lower() in (".bvh", ".amc")) or detect_kind(src) != "csv":
        return
    csv_path = src if src.is_file() else src / "labels.csv"
    columns = {k for rec in read_labels_csv(csv_path) for k in rec["extras"]}
    for column in sorted(columns):
        what = _WRITTEN.get(column.strip().lower())
        if what is not None:
            raise DataError(
                f"column {column!r}: convert writes {column.strip().lower()!r} in each pose file"
                f" itself ({what}); rename the column",
                csv_path,
            )


def _check_overlaps(args: argparse.Namespace) -> None:
    """Refuse a labels CSV listing one stretch twice or giving frames of one file two labels
    (:func:`features.datasets.check_no_overlaps`), before any clip is read: the pose files
    written would be the same frames twice, which ``train`` of the folder cannot tell (it
    refuses such rows of the CSV itself)."""
    from features.datasets import check_no_overlaps

    src: Path = args.source
    if not (src.is_file() and src.suffix.lower() in (".bvh", ".amc")):
        labels = [s.strip() for s in args.labels.split(",")] if args.labels else None
        check_no_overlaps(src, labels, twice=True)


def _clips(args: argparse.Namespace) -> Iterator[tuple[Clip, str]]:
    from features.datasets import detect_kind, iter_dataset

    src: Path = args.source
    if src.is_file() and src.suffix.lower() in (".bvh", ".amc"):
        yield from _single_clips(args)
        return
    correct = True if args.correct else (False if args.incorrect else None)
    kind = detect_kind(src)
    clips = iter_dataset(
        src,
        sensor=args.sensor,
        progress_desc=f"converting {src.name}",
        labels=_csv_list(args.labels),
        subjects=_csv_list(args.subjects),
        movements=_csv_list(args.movements),
        episodes=parse_ranges(args.episodes),
        correct=correct,
        limit=args.limit,
        fps=args.fps,  # a label file in seconds is laid over the frames at this rate
    )
    for clip in clips:
        stem = Path(clip.seq.source).name.split(".")[0] if clip.seq.source else kind
        yield clip, stem


def _origin(seq_source: str, src: Path) -> str:
    """Where a clip came from, from the folder SOURCE is in (no machine-specific absolute
    path): ``hdm05/train/1/x.amc`` for the folder ``hdm05``; for a file (one recording, a
    labels CSV) from the folder above the one it is in, ``takes/x.bvh``: its name alone would
    take another folder's ``x.bvh`` for the same recording, and replace its pose file."""
    if not seq_source:
        return seq_source
    base = src.resolve().parent if src.is_dir() else src.resolve().parent.parent
    try:
        return str(Path(seq_source).resolve().relative_to(base))
    except (ValueError, OSError):
        return Path(seq_source).name


Rates = dict[tuple[float, str], int]  # clips written per (frame rate, where it came from)


def _write_clips(
    args: argparse.Namespace, stage: Path, inputs: ReadFiles
) -> tuple[list[dict[str, Any]], Rates]:
    """Each clip as a pose file in ``stage``; the rows of labels.csv and the frame rates."""
    from features.poses import save_pose

    written: list[dict[str, Any]] = []
    names: set[str] = set()
    rates: Rates = {}
    there = {p.name.lower(): p.name for p in args.out.iterdir()} if args.out.is_dir() else {}
    for clip, fallback in _clips(args):
        name = unique_name(_clip_name(clip, fallback), names)  # two sources, one stem: both
        check_output(args.out / f"{name}.npz", inputs=inputs, what="pose file")
        # ``source`` left empty so a reader names the pose file itself.
        seq = replace(clip.seq, source="").with_metadata(
            origin=_origin(clip.seq.source, args.source)
        )
        _check_replaces(args.out, f"{name}.npz", seq, there)
        if args.fps is not None:
            seq = replace(seq, fps=float(args.fps)).with_metadata(fps_source="--fps")
        why = str(seq.metadata.get("fps_source", "from the file"))
        rates[(seq.fps, why)] = rates.get((seq.fps, why), 0) + 1
        path = save_pose(seq, stage / f"{name}.npz", float32=args.float32)
        extras = {
            k: v
            for k, v in clip.extras.items()
            if k.strip().lower() not in _RESERVED_COLUMNS and k.strip().lower() not in _INTERNAL
        }
        written.append(
            {**extras, "path": path.name, "label": clip.label, "subject": clip.subject or ""}
        )
    _check_asked(args, written)
    if not written:
        filters = ("subjects", "labels", "movements", "episodes", "correct", "incorrect")
        if any(getattr(args, f, None) for f in filters):
            raise DataError("no clips matched (check the filters)", args.source)
        raise DataError("holds no clip to convert", args.source)
    return written, rates


def _check_asked(args: argparse.Namespace, written: list[dict[str, Any]]) -> None:
    """Refuse a ``--labels``, ``--subjects``, ``--movements`` or ``--episodes`` entry no clip
    converted has (mistyped), naming those the data hold, as ``train``, ``compare`` and
    ``classify`` refuse it: the clips of the others alone were converted without a word
    (``--labels deep_squat,bogus``, ``--movements m01,m7``, ``--episodes 1,99``), and one
    entry alone was "holds no clip to convert" ("no clips matched (check the filters)" for
    ``--movements m1``). Checked once every clip is staged, before any is moved into --out;
    when ``--limit`` stopped the conversion, against every clip of the data (one past the
    limit may have it)."""
    from features.datasets import (
        dataset_episodes,
        dataset_labels,
        dataset_movements,
        dataset_subjects,
    )
    from features.targets import extra

    limited = args.limit is not None and len(written) >= args.limit
    asked = []
    for flag, given, key, what, held_by in (
        ("--labels", args.labels, "label", "labelled", dataset_labels),
        ("--subjects", args.subjects, "subject", "of subject", dataset_subjects),
        ("--movements", args.movements, "movement", "of movement", dataset_movements),
    ):
        values = _csv_list(given)
        if values is None:
            continue

        def held(held_by: Any = held_by) -> list[str]:
            return list(held_by(args.source, sensor=args.sensor))

        found = held() if limited else [extra(row, key) for row in written]
        asked.append((found, sorted(values), flag, what, held))
    episodes = parse_ranges(args.episodes)
    if episodes is None:
        check_each_found(asked, args.source)
        return
    data_has = dataset_episodes(args.source, sensor=args.sensor)
    _check_episodes(episodes, data_has, args.source)  # held nowhere (mistyped) first
    check_each_found(asked, args.source)
    converted = data_has if limited else [_episode(row) for row in written]
    _check_episodes(episodes, converted, args.source, data_has)


def _episode(row: dict[str, Any]) -> Any:
    """A converted clip's episode (UI-PRMD) or take (HDM05), as ``--episodes`` filters them."""
    from features.targets import extra

    episode = extra(row, "episode")
    return extra(row, "take") if episode is None else episode


def _check_episodes(
    episodes: Ranges, found: list[Any], source: Path, held: list[str] | None = None
) -> None:
    """Refuse a ``--episodes`` entry (a number or a range) in which none of the episodes
    ``found`` lies, as :func:`posecbr.arguments.check_found` refuses a ``--subjects`` entry:
    ``found`` the data's own episodes (``held`` None), naming them; else those of the clips
    the other filters kept (``held``: the data's), "passes the other filters". A range is a
    bound: ``1-10`` over episodes 1 to 6 is not refused (1,99 converted episode 1 alone
    without a word)."""
    numbers = {int(e) for e in found if e is not None and str(e).strip().isdigit()}
    missing = [
        text
        for text, r in zip(episodes.texts, episodes.ranges, strict=True)
        if not any(n in r for n in numbers)
    ]
    if not missing:
        return
    listed_missing = ", ".join(repr(m) for m in missing)
    if held is not None:
        raise ConfigError(
            f"no clip of episode {listed_missing} in {source} passes the other filters",
            "--episodes",
        )
    said = held_words([str(e) for e in found], "of episode") or ": its clips have no episodes"
    raise ConfigError(f"no clip of episode {listed_missing} in {source}{said}", "--episodes")


def _same_origin(a: str, b: str) -> bool:
    """Whether two origins name one source file: the shorter's parts end the longer's (an
    origin is relative to the folder above SOURCE, which may be given at another depth)."""
    pa, pb = Path(a).parts, Path(b).parts
    n = min(len(pa), len(pb))
    return n > 0 and pa[-n:] == pb[-n:]


def _check_replaces(out: Path, file: str, seq: PoseSequence, there: dict[str, str]) -> None:
    """Refuse to write ``file`` (the clip ``seq``) into ``out`` over another file (``there``:
    the names in ``out`` by their lower-case spelling): one whose name differs only in case,
    or a pose file that is not this clip converted before (another recording, same name; or
    another stretch of the same recording: the whole of it where a piece goes, or a piece cut
    at other frames)."""
    from features.errors import PosecbrError
    from features.poses import load_pose

    old = there.get(file.lower())
    if old is None:
        return
    if old != file:
        raise DataError(
            f"differs only in case from {old} already there; choose another --out", out / file
        )
    origin = str(seq.metadata["origin"])
    try:
        held: PoseSequence | None = load_pose(out / file)
    except PosecbrError:
        held = None
    meta = held.metadata if held is not None else {}  # older conversions: made_from
    was = str(meta.get("origin") or meta.get("made_from") or "")
    if held is None or not _same_origin(was, origin):
        raise DataError(
            f"already there from another recording ({was or 'not converted from a source'}),"
            f" not from {origin}: converting would overwrite it; choose another --out",
            out / file,
        )
    if _frames(held) != _frames(seq):
        raise DataError(
            f"already there from {origin}, {_frames_words(held)}, where this conversion"
            f" writes {_frames_words(seq)}: converting would overwrite it; choose another --out",
            out / file,
        )


def _frames(seq: PoseSequence) -> tuple[int, int]:
    """The frames of its recording a clip holds: its first and one past its last."""
    first = int(seq.metadata.get("frame_offset", 0))
    return first, first + seq.n_frames


def _frames_words(seq: PoseSequence) -> str:
    first, stop = _frames(seq)
    return f"frames {first}-{stop - 1} of it"


def _rate_summary(rates: dict[tuple[float, str], int]) -> list[str]:
    """One line per frame rate written and where it came from."""
    return [
        f"frame rate {fps:g} fps for {n} clip{'s' if n > 1 else ''} ({why})"
        for (fps, why), n in sorted(rates.items())
    ]


def _labels_csv(written: list[dict[str, Any]], header: list[str] | None = None) -> str:
    """labels.csv: path,label,subject, the columns of ``header`` (that of the file already
    there, every one kept and spelled as it is), then every extra column any clip has, in
    first-seen order (one column per name as a reader sees it: case and spaces do not make
    another)."""
    from features.progress import progress

    spelling = {c.strip().lower(): c for c in reversed(header or [])}
    columns = [spelling.get(c, c) for c in ("path", "label", "subject")]
    seen = {"path", "label", "subject"}
    for row in [dict.fromkeys(header or []), *written]:
        for c in row:
            key = c.strip().lower()
            if key not in seen:
                seen.add(key)
                columns.append(c)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in progress(written, "labels.csv", unit="row"):
        values = {c.strip().lower(): v for c, v in row.items() if c is not None}
        writer.writerow([_csv_value(values.get(c.strip().lower(), "")) for c in columns])
    return buf.getvalue()


def _listed_before(labels: Path) -> tuple[list[dict[str, Any]], list[str]]:
    """The rows of a labels.csv already in the output folder and its header (none when there
    is none): converting into a folder adds to its dataset. DataError naming it when it cannot
    be read as one (no ``path`` column)."""
    if not labels.is_file():
        return [], []
    try:
        with open(labels, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            # blank rows (a trailing blank line, one of commas alone) list no clip: train
            # skips them, and they are neither counted as kept nor written back
            rows = [_named(row) for row in reader if any(_filled(v) for v in row.values())]
            columns = [c for c in reader.fieldnames or [] if c.strip()]
    except UnicodeDecodeError as exc:
        kind = binary_kind(file_head(labels))
        said = f"it is {kind}" if kind else f"not UTF-8 text: {exc.reason} at byte {exc.start}"
        raise DataError(f"cannot read the labels file already there ({said})", labels) from None
    except (OSError, csv.Error) as exc:
        raise DataError(f"cannot read the labels file already there ({exc})", labels) from None
    if "path" not in (c.strip().lower() for c in columns):
        raise DataError("the labels file already there has no 'path' column", labels)
    from features.datasets import check_no_overlaps
    from features.labels_csv import read_labels_csv

    try:  # every row a clip with its label, as train and classify will read it
        read_labels_csv(labels)
        check_no_overlaps(labels, twice=True)  # no stretch twice, no frames of two labels
    except DataError as exc:
        raise DataError(
            f"the labels file already there cannot be added to: {exc.message}; nothing written",
            labels,
        ) from None
    return rows, list(columns)


def _check_not_hidden(out: Path) -> None:
    """Refuse an output folder holding pose files and no labels.csv (an earlier ``extract``
    or ``convert`` of one clip, class folders of pose files): the labels.csv written would
    list this conversion's clips alone, and ``train OUT``, which reads it and walks nothing,
    would leave those out unsaid. A folder with a labels.csv is added to (its rows kept)."""
    if not out.is_dir() or (out / "labels.csv").exists():
        return
    there = sorted(
        p.relative_to(out).as_posix()
        for p in (*out.glob("*.npz"), *out.glob("*/*.npz"))
        if not any(part.startswith(".") for part in p.relative_to(out).parts)
    )
    if there:
        raise DataError(
            f"holds {counted(len(there), 'pose file')} and no labels.csv"
            f" ({first_few(there)}): the labels.csv written would list this"
            " conversion's clips alone, and train of the folder would leave those out;"
            " list them in a labels.csv there first (path,label), which convert adds to,"
            " or choose another --out",
            out,
        )


def _named(row: dict[Any, Any]) -> dict[str, Any]:
    """A labels.csv row without the cells of columns the header leaves unnamed: the empty
    columns a spreadsheet saves after the last one used (``path,label,,``), which train
    leaves out (:func:`features.labels_csv.read_labels_csv` refuses one holding a value) and
    which were written back as a column named ""."""
    return {k: v for k, v in row.items() if k is not None and k.strip()}


def _filled(value: Any) -> bool:
    """Whether a labels.csv cell holds something (csv.DictReader gives a list for the cells
    past the header's columns, None for those missing)."""
    if isinstance(value, list):
        return any(_filled(v) for v in value)
    return value is not None and bool(str(value).strip())


def _merged(before: list[dict[str, Any]], written: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows of labels.csv: those listed before whose pose file was not written again,
    in their order, then the ones written now."""
    now = {str(row["path"]) for row in written}
    return [row for row in before if _path_of(row) not in now] + written


def _path_of(row: dict[str, Any]) -> str:
    """A row's path as train reads it (the column in any case, spaces around it ignored)."""
    return next((str(v).strip() for c, v in row.items() if c and c.strip().lower() == "path"), "")


def run(args: argparse.Namespace) -> int:
    _check_args(args)
    out: Path = args.out
    inputs = _inputs(args)
    _check_no_overwrite(out, inputs)
    _check_not_in_source(args)
    reads = ReadFiles(inputs)  # looked up once, not once per clip written
    if out.is_dir():
        check_output(out / "labels.csv", inputs=reads, what="labels file")
    before, header = _listed_before(out / "labels.csv")
    _check_not_hidden(out)
    # Clips and labels.csv are staged first: a bad clip halfway leaves the output folder as it
    # was; labels.csv, which names the clips, is moved in last.
    with staged_folder(out, last={"labels.csv"}) as stage:
        written, rates = _write_clips(args, stage, reads)
        rows = _merged(before, written)
        write_text_atomic(stage / "labels.csv", _labels_csv(rows, header))
    kept = len(rows) - len(written)
    listed = f" ({counted(kept, 'clip')} listed before kept)" if kept else ""
    print(f"wrote {counted(len(written), 'pose file')} and labels.csv to {shown(out)}{listed}")
    for line in _rate_summary(rates):
        print(f"  {line}")
    return 0


def _csv_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return "" if value is None else str(value)


__all__ = ["parse_ranges", "register", "run"]
