"""``posecbr convert SOURCE --out DIR``: motion capture data -> pose files, one per clip.

SOURCE is a UI-PRMD folder, an HDM05 (or CMU) ASF/AMC folder, one ``.amc`` file (its ``.asf``
beside it or given with ``--asf``), a ``.bvh`` file, or any other dataset ``iter_dataset``
reads (labels CSV, class folders). Each clip is written to DIR as ``<name>.npz`` with its
label, subject and extras in the metadata, and DIR/labels.csv (``path,label,subject,...``)
lists them, so DIR is itself a dataset for every command.

The frame rate each clip is written with, and where it came from, is printed: AMC files carry
none (120 Hz, the CMU and HDM05 rate, is assumed unless an HDM05 name states one; a CMU name
such as ``13_29.amc`` is subject and trial, not a rate); ``--fps`` sets it for every clip.
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from features.errors import DataError

if TYPE_CHECKING:
    from features.datasets import Clip


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "convert",
        help="convert UI-PRMD, HDM05/ASF-AMC or BVH data into pose files",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("source", type=Path, help="dataset folder, .amc, .bvh, labels CSV, ...")
    p.add_argument("--out", type=Path, required=True, help="output folder (created)")
    p.add_argument("--sensor", choices=("kinect", "vicon"), default="kinect", help="UI-PRMD")
    p.add_argument("--asf", type=Path, help="skeleton for a single .amc (default: beside it)")
    p.add_argument("--subjects", help="comma list, e.g. s01,s02 (UI-PRMD) or bd,dg (HDM05)")
    p.add_argument("--movements", help="UI-PRMD movements, e.g. m01,m07")
    p.add_argument("--labels", help="comma list of labels to keep")
    p.add_argument("--episodes", help="episodes/takes, e.g. 1-3 or 1,4,7-9")
    p.add_argument("--correct", action="store_true", help="only correct repetitions (UI-PRMD)")
    p.add_argument("--incorrect", action="store_true", help="only incorrect repetitions (UI-PRMD)")
    p.add_argument("--limit", type=int, help="at most this many clips")
    p.add_argument(
        "--fps",
        type=float,
        help="frame rate of the source (frames per second), for every clip; default: from the"
        " files (AMC files carry none: 120, the CMU and HDM05 rate)",
    )
    p.add_argument(
        "--float32",
        action="store_true",
        help="store positions as float32 (half the size; readers cast back to float64)",
    )
    p.add_argument(
        "--bvh-unit",
        default="auto",
        help="BVH unit: m, cm, mm, inch or auto (default: guessed from the rest pose)",
    )
    p.set_defaults(func=run)


def _csv_list(value: str | None) -> set[str] | None:
    if value is None:
        return None
    items = {v.strip() for v in value.split(",") if v.strip()}
    return items or None


def parse_ranges(value: str | None) -> set[int] | None:
    """``"1-3,5"`` -> {1, 2, 3, 5}. Raises DataError for anything else."""
    if value is None:
        return None
    out: set[int] = set()
    for part in value.split(","):
        part = part.strip()
        if not part:
            continue
        try:
            if "-" in part:
                a, b = (int(x) for x in part.split("-", 1))
                if b < a:
                    raise ValueError
                out.update(range(a, b + 1))
            else:
                out.add(int(part))
        except ValueError:
            raise DataError(f"not a number or range a-b: {part!r}", "--episodes") from None
    return out


def _clip_name(clip: Clip, fallback: str) -> str:
    ex = clip.extras
    if ex.get("dataset") == "ui-prmd":
        inc = "" if ex.get("correct", True) else "_inc"
        return f"{ex['movement']}_{clip.subject}_e{int(ex['episode']):02d}{inc}"
    return fallback


def _write_text_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _single_clips(args: argparse.Namespace) -> list[tuple[Clip, str]]:
    from features.datasets import Clip, find_asf
    from features.readers.asfamc import read_asf_amc
    from features.readers.bvh import read_bvh

    src: Path = args.source
    suffix = src.suffix.lower()
    if suffix == ".bvh":
        unit: str | float = args.bvh_unit
        try:
            unit = float(unit)
        except ValueError:
            pass
        seq = read_bvh(src, unit=unit)
    else:
        asf = args.asf if args.asf is not None else find_asf(src)
        seq = read_asf_amc(asf, src, fps=args.fps)
    label = str(seq.metadata.get("label", src.stem))
    subject = seq.metadata.get("subject")
    extras = {k: v for k, v in seq.metadata.items() if k not in ("label", "subject")}
    seq = seq.with_metadata(label=label, subject=subject)
    return [(Clip(seq, label, None if subject is None else str(subject), extras), src.stem)]


def _rate_summary(rates: dict[tuple[float, str], int]) -> list[str]:
    """One line per frame rate written and where it came from."""
    return [
        f"frame rate {fps:g} fps for {n} clip{'s' if n > 1 else ''} ({why})"
        for (fps, why), n in sorted(rates.items())
    ]


def run(args: argparse.Namespace) -> int:
    from features.datasets import detect_kind, iter_dataset
    from features.poses import save_pose
    from features.progress import progress

    src: Path = args.source
    if not src.exists():
        raise DataError("no such file or folder", src)
    if args.fps is not None and not (0.0 < args.fps <= 10000.0):
        raise DataError(f"--fps must be a frame rate in (0, 10000], got {args.fps:g}", "--fps")
    if args.correct and args.incorrect:
        raise DataError("choose --correct or --incorrect, not both", "--correct")
    out: Path = args.out
    if out.exists() and not out.is_dir():
        raise DataError("exists and is not a folder", out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DataError(f"cannot create: {exc.strerror or exc}", out) from None

    written: list[dict[str, Any]] = []
    names: set[str] = set()
    rates: dict[tuple[float, str], int] = {}

    def emit(clip: Clip, fallback: str) -> None:
        name = _clip_name(clip, fallback)
        base, k = name, 2
        while name in names:  # two sources with one stem: keep both
            name, k = f"{base}_{k}", k + 1
        names.add(name)
        # Record where the clip came from relative to SOURCE (no machine-specific absolute
        # path), and leave ``source`` empty so a reader names the pose file itself.
        seq = clip.seq
        origin = seq.source
        if origin:
            try:
                origin = str(Path(origin).resolve().relative_to(src.resolve().parent))
            except ValueError:
                origin = Path(origin).name
        seq = replace(seq, source="").with_metadata(origin=origin)
        if args.fps is not None:
            seq = replace(seq, fps=float(args.fps)).with_metadata(fps_source="--fps")
        why = str(seq.metadata.get("fps_source", "from the file"))
        rates[(seq.fps, why)] = rates.get((seq.fps, why), 0) + 1
        path = save_pose(seq, out / f"{name}.npz", float32=args.float32)
        written.append(
            {"path": path.name, "label": clip.label, "subject": clip.subject or "", **clip.extras}
        )

    if src.is_file() and src.suffix.lower() in (".bvh", ".amc"):
        for clip, stem in _single_clips(args):
            emit(clip, stem)
    else:
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
        )
        for clip in clips:
            stem = Path(clip.seq.source).name.split(".")[0] if clip.seq.source else kind
            emit(clip, stem)
    if not written:
        raise DataError("no clips matched (check the filters)", src)

    # labels.csv: path,label,subject then every extra column any clip has, in first-seen order
    columns = ["path", "label", "subject"]
    for row in written:
        columns += [
            c
            for c in row
            if c not in columns and c not in ("source", "asf", "origin", "fps_source")
        ]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    for row in progress(written, "labels.csv", unit="row"):
        writer.writerow({c: _csv_value(row.get(c, "")) for c in columns})
    _write_text_atomic(out / "labels.csv", buf.getvalue())
    print(f"wrote {len(written)} pose files and labels.csv to {out}")
    for line in _rate_summary(rates):
        print(f"  {line}")
    return 0


def _csv_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return "" if value is None else str(value)


__all__ = ["parse_ranges", "register", "run"]
