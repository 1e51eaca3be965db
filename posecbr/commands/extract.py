"""``posecbr extract VIDEO|FOLDER|LABELS.csv --out DIR``: videos -> pose files (BlazePose).

One pose file per clip (``DIR/<stem>.npz``, or ``DIR/<label>/<stem>.npz`` for labelled
datasets) holding the world landmarks (canonical frame, fps from the video), visibility as
confidence, the image landmarks (``extra_image_landmarks``), the label/subject and the
frames with no person. A labels CSV row naming a ``label_file`` (a recording labelled over
time) keeps its recording whole (``DIR/<stem>.npz``), its label file copied beside it, and
``DIR/labels.csv`` names every pose file with its label file, as ``train`` reads the CSV.
Outputs whose video content (sha256), model version and options are unchanged are skipped.
Every file is written under a temporary name and renamed (features.fileio).
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import json
import os
import sys
import tempfile
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from features.cluster import SCHEDULER_HELP, check_scheduler
from features.errors import ConfigError, DataError, PosecbrError
from features.fileio import (
    ReadFiles,
    check_not_in_walked_folder,
    check_output,
    folders_to_make,
    path_digest,
    path_exists,
    remove_empty,
)
from features.formats import SHOWN_VIDEO_SUFFIXES, is_video_in_folder
from features.interrupts import interrupts_held, run_task, stop_workers, worker_ends_on_sigterm
from features.progress import progress
from features.text import counted, first_few, shown
from posecbr.arguments import (
    NOT_A_PATH,
    SCHEDULER,
    PathOption,
    as_options,
    check_mp4_name,
    is_url,
    path_arg,
)

if TYPE_CHECKING:  # imported where used: start-up
    import numpy as np

    from features.poses import PoseSequence

# FFmpeg prints decoder complaints straight to stderr; the user should get posecbr's one line.
# OpenCV reads this once, when it first opens a video, so it is set as early as possible.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

IMAGE_SUFFIXES = (  # one frame each
    ".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".heic", ".heif", ".avif"
)  # fmt: skip
# what is a recording already, not a video: refused by name
RECORDING_SUFFIXES = {".npz": "a pose file", ".bvh": "a BVH recording", ".amc": "an AMC recording"}


@dataclass(frozen=True)
class Job:
    """One clip to extract: the video, where its pose file (and overlay) go, its labels."""

    video: Path
    out: Path
    label: str | None = None
    subject: str | None = None
    start: int | None = None
    end: int | None = None
    extras: dict[str, Any] = field(default_factory=dict)
    overlay: Path | None = None
    listed: str | None = None  # where a labels CSV lists it ("labels.csv, line 3")
    track: Any = None  # a recording labelled over time: its LabelTrack (label_file row)


@dataclass(frozen=True)
class Options:
    smoothing: bool = True
    tracking: bool = True
    keep_outside: bool = False
    force: bool = False
    fluents: bool = True


Outcome = tuple[
    str, Path, str
]  # (status "done", "skipped", "drawn" or "failed", pose file, detail)
# "drawn": the pose file was up to date, its overlay alone was drawn (from the stored landmarks)


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "extract",
        epilog="example: posecbr extract squat.mp4 --out poses/",
        help="estimate 3D poses from videos (BlazePose on onnxruntime) and write pose files",
        description="Run BlazePose (full) on every frame and write one pose file per clip. "
        "INPUT is a video or still image, a folder of them, a folder with one subfolder per "
        "class (label = subfolder name), or a labels CSV path,label[,subject][,start,end] "
        "(start/end: frame indices, end exclusive); a row naming a label_file keeps its recording "
        "whole, its label file beside it and OUT/labels.csv naming both, as train reads the "
        "CSV. Up-to-date outputs are skipped.",
    )
    # a str, not a Path: Path("") is the current folder, which an empty argument is not
    p.add_argument("input", metavar="INPUT", help="video, folder or labels CSV")
    p.add_argument(
        "--out",
        type=path_arg,
        required=True,
        metavar="DIR",
        help="output folder (for one video, a pose file name x.npz may be given instead)",
    )
    p.add_argument(
        "--workers",
        "--jobs",  # as compare's worker processes are asked for
        dest="workers",
        type=int,
        default=1,
        metavar="N",
        help="clips processed in parallel (default 1; each uses cores/N threads)",
    )
    p.add_argument(
        "--overlay",
        action=PathOption,
        metavar="OUT.mp4|DIR",
        help="also write the video with the stick figure (and the fluents that hold) drawn"
        " on it: for one video an .mp4 file, or a folder (one there, or a name ending in /,"
        " made if it is not there) for <video>.mp4, as --out; a folder's or labels CSV's"
        " clips, one <video>.mp4 each in a folder",
    )
    p.add_argument(
        "--no-smoothing",
        action="store_true",
        help="no temporal filtering (raw per-frame landmarks)",
    )
    p.add_argument(
        "--detect-every-frame",
        action="store_true",
        help="run the person detector on every frame instead of tracking",
    )
    p.add_argument(
        "--keep-outside",
        action="store_true",
        help="keep joints the model places outside the frame or judges not in the picture"
        " (presence below 0.5) (default: missing)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS|local:N", help=SCHEDULER_HELP)
    p.add_argument("--force", action="store_true", help="re-extract even if up to date")
    p.set_defaults(func=run, overlay_folder=False)  # fmt: skip


# ---- finding clips ------------------------------------------------------------------------


def _videos_in(folder: Path) -> list[Path]:
    """The videos and still images in ``folder`` (not its subfolders), by name: a ``.ts``
    file only when it is MPEG-TS inside (not a TypeScript source); a still picture beside a
    video of its name is left out (:func:`_live_stills`)."""
    found = _clips_in(folder)
    live = _live_stills(found)
    return [p for p in found if p not in live]


def _clips_in(folder: Path) -> list[Path]:
    """Every video and still image in ``folder`` (:func:`_videos_in`, no picture left out)."""
    return sorted(
        p for p in folder.iterdir()
        if p.is_file() and not p.name.startswith(".")
        and (p.suffix.lower() in IMAGE_SUFFIXES or is_video_in_folder(p))
    )  # fmt: skip


def _live_stills(paths: list[Path]) -> list[Path]:
    """The still pictures among ``paths`` (of one folder) with a video of the same name
    beside them: a phone's live photo, the picture and the seconds around it filmed (an
    iPhone's IMG_0001.HEIC or .JPG and IMG_0001.MOV, copied off the phone together). Both
    would be written to one pose file; the video holds the moment the picture does."""
    videos = {p.stem for p in paths if p.suffix.lower() not in IMAGE_SUFFIXES}
    return [p for p in paths if p.suffix.lower() in IMAGE_SUFFIXES and p.stem in videos]


def _csv_jobs(csv_path: Path, out: Path) -> list[Job]:
    from features.labels_csv import read_labels_csv

    jobs = []
    for rec in read_labels_csv(csv_path):
        video: Path = rec["path"]
        stem = video.stem
        if rec["start"] is not None:
            stem += f"_{rec['start']}-{rec['end']}"
        # a recording labelled over time (label_file): whole, beside labels.csv, which names
        # its label file as the CSV did (:func:`write_listing`); no one label to file it under
        track = rec["track"]
        jobs.append(
            Job(
                video=video,
                out=out / f"{stem}.npz" if track else out / _safe(rec["label"]) / f"{stem}.npz",
                label=None if track else rec["label"],
                track=track,
                subject=rec["subject"],
                start=rec["start"],
                end=rec["end"],
                extras=dict(rec["extras"]),
                listed=f"{csv_path.name}, line {rec['line']}",
            )
        )
    if not jobs:
        raise DataError("the labels CSV lists no clip", csv_path)
    return jobs


def _safe(name: str) -> str:
    """A label as a folder name (path separators replaced)."""
    cleaned = name.replace("/", "_").replace("\\", "_").strip()
    return cleaned if cleaned not in ("", ".", "..") else "_"


def _names_pose_file(out: Path) -> bool:
    """Whether ``--out`` names one pose file (``x.npz``, not an existing folder) rather than
    the folder the pose files go in."""
    return out.suffix.lower() == ".npz" and not out.is_dir()


def _folder_jobs(source: Path, out: Path) -> list[Job]:
    """The videos of a folder, directly in it or one subfolder per class (label = name)."""
    try:
        subdirs = sorted(d for d in source.iterdir() if d.is_dir() and not d.name.startswith("."))
    except OSError as exc:
        raise DataError(f"cannot list folder ({exc.strerror or exc})", source) from None
    from features.clip_folders import check_not_nested

    if any(_videos_in(d) for d in subdirs):  # read as class folders, as train reads them
        for d in subdirs:
            check_not_nested(d, _videos_in)
    jobs = [
        Job(video=v, out=out / _safe(d.name) / f"{v.stem}.npz", label=d.name)
        for d in subdirs
        for v in _videos_in(d)
    ]
    jobs += [Job(video=v, out=out / f"{v.stem}.npz") for v in _videos_in(source)]
    _note_live_stills([source, *subdirs])
    if not jobs:
        raise DataError(
            f"no videos or images found ({', '.join(SHOWN_VIDEO_SUFFIXES + IMAGE_SUFFIXES)}),"
            " directly or one subfolder per class",
            source,
        )
    return jobs


def _note_live_stills(folders: list[Path]) -> None:
    """Say on stderr which still pictures in ``folders`` are left out as live photos'
    (:func:`_live_stills`), the first few named."""
    left = [p for folder in folders for p in _live_stills(_clips_in(folder))]
    if left:
        named = first_few([shown(p.name) for p in left])
        print(
            f"note: {counted(len(left), 'still picture')} beside a video of the same name left"
            f" out ({named}): a phone's live photo, whose video is extracted",
            file=sys.stderr,
        )


def find_jobs(
    source: Path, out: Path, overlay: Path | None, overlay_folder: bool = False
) -> list[Job]:
    """The clips ``source`` names, with their output paths (see the command's help). One
    video's ``overlay`` names its overlay file or, ``overlay_folder`` (a folder there, or a
    name written ending in "/"), the folder of its ``<stem>.mp4``, as several clips'
    ``overlay`` names the folder of theirs (and ``out`` the folder of the pose files)."""
    if not path_exists(source):
        raise DataError("no such file or folder", source)
    if not source.is_file() and not source.is_dir():
        raise DataError("is a pipe, socket or device, not a video, folder or labels CSV", source)
    if out.suffix.lower() in (*SHOWN_VIDEO_SUFFIXES, *IMAGE_SUFFIXES) and not out.is_dir():
        # made a folder named out.mp4 holding the pose file (or, the input video named,
        # "output is not a folder"): a video was meant, which is --overlay's
        raise DataError(
            "--out names the folder for the pose files or, for one video, its .npz pose"
            " file, not a video or picture (--overlay writes a video of the stick figure)",
            out,
        )
    if _one_video(source):
        _check_not_recording(source)
        name = out if _names_pose_file(out) else out / f"{source.stem}.npz"
        if overlay is not None and overlay_folder:
            overlay = overlay / f"{source.stem}.mp4"
        return [Job(video=source, out=name, overlay=overlay)]
    if _names_pose_file(out):
        raise DataError(
            "for a folder or labels CSV, --out names the folder for the pose files, not one"
            " pose file",
            out,
        )
    jobs = _listed_jobs(source, out)
    seen: dict[Path, Job] = {}
    for job in jobs:
        if job.out in seen:
            first, second = _shown_job(seen[job.out]), _shown_job(job)
            what = f"{first} is listed twice" if first == second else f"{first} and {second}"
            raise DataError(f"{what}: both would be written to {job.out}", source)
        seen[job.out] = job
    if overlay is not None:
        jobs = [
            Job(**{**vars(j), "overlay": overlay / j.out.relative_to(out).with_suffix(".mp4")})
            for j in jobs
        ]
    return jobs


def _check_not_recording(clip: Path, listed_in: Path | None = None) -> None:
    """Refuse a pose file or mocap recording where a video is wanted (each would fail as
    "not a video"): the other commands read it as it is."""
    what = RECORDING_SUFFIXES.get(clip.suffix.lower())
    if what is not None:
        where = f" (listed in {listed_in})" if listed_in is not None else ""
        raise DataError(
            f"is {what} already{where}: extract makes pose files from videos and pictures;"
            " the other commands read it as it is",
            clip,
        )


def _listed_jobs(source: Path, out: Path) -> list[Job]:
    """The clips of a labels CSV (``source``, or its labels.csv) or of a folder of videos;
    a recording listed is refused, and so are rows giving frames of one video two labels
    (:func:`features.datasets.check_no_overlaps`, as ``train``, ``compare`` and ``convert``
    refuse them): the pose files written would be those frames under two labels, which a
    ``train`` of the folder cannot tell and a ``train`` of the CSV refuses."""
    from features.datasets import check_no_overlaps
    from features.stretches import check_track

    csv_path = source if source.is_file() else source / "labels.csv"
    if not csv_path.is_file():
        return _folder_jobs(source, out)
    jobs = _csv_jobs(csv_path, out)
    for job in jobs:
        _check_not_recording(job.video, csv_path)
    check_no_overlaps(csv_path)
    for job in jobs:  # a label file that does not fit its video: before the model runs
        if job.track is not None:
            check_track(job.video, job.track)
    return jobs


# ---- recordings labelled over time: labels.csv ---------------------------------------------


@dataclass(frozen=True)
class Listing:
    """The labels.csv written into ``--out`` when a labels CSV has rows naming a label file:
    every pose file of the CSV, each recording labelled over time with a copy of its label
    file (and names file) beside it, so that ``train OUT`` reads what ``train CSV`` reads.
    ``copies``: where each label or names file goes (source -> file in ``--out``)."""

    path: Path
    copies: dict[Path, Path]
    extras: list[str]


def plan_listing(csv_source: Path, out: Path, jobs: list[Job]) -> Listing | None:
    """The labels.csv to write for ``jobs`` (None when no row names a label file); refused,
    before any work, where it would hide or replace what ``--out`` holds: pose files (or an
    earlier labels.csv's rows) it would not list, which ``train OUT`` would then leave out,
    or the labels CSV being read itself."""
    if not any(job.track is not None for job in jobs):
        return None
    listing = out / "labels.csv"
    read = csv_source if csv_source.is_file() else csv_source / "labels.csv"
    if listing.exists() and listing.resolve() == read.resolve():
        raise DataError(
            "is the labels CSV being read, and extract writes a labels.csv there naming the"
            " pose files and label files (rows with a label_file); choose another --out",
            listing,
        )
    copies = _label_file_copies(out, jobs)
    ours = {p.resolve() for p in (*(job.out for job in jobs), *copies.values())}
    there = [*out.glob("*.npz"), *out.glob("*/*.npz")] if out.is_dir() else []
    there += _listed_in(listing)
    other = sorted({str(p.relative_to(out)) if p.is_relative_to(out) else str(p)
                    for p in there if p.resolve() not in ours})  # fmt: skip
    if other:
        raise DataError(
            f"holds pose files this labels CSV does not list ({first_few(other)}):"
            " the labels.csv written for its recordings labelled over time would leave them"
            " out of a train of the folder; choose another --out",
            out,
        )
    for dest in copies.values():
        check_output(dest, inputs=[job.video for job in jobs], what="label file")
    _check_copies_replace_own(copies, listing)
    extras = list(dict.fromkeys(k for job in jobs for k in job.extras))
    return Listing(listing, copies, extras)


def _label_file_copies(out: Path, jobs: list[Job]) -> dict[Path, Path]:
    """Where each label file and names file the jobs' rows name goes in ``out``: its own
    name, or ``<stem>_2<suffix>``... when a pose file, labels.csv or another file copied
    takes it; one inside ``out`` already stays where it is."""
    taken = {job.out.name.lower() for job in jobs if job.out.parent == out}
    taken.add("labels.csv")
    copies: dict[Path, Path] = {}
    for job in jobs:
        if job.track is None:
            continue
        for src in (job.track.path, job.track.names):
            if src is None or src in copies:
                continue
            if src.resolve().is_relative_to(out.resolve()):  # there already: named as it is
                copies[src] = src
                continue
            name, k = src.name, 2
            while name.lower() in taken:
                name, k = f"{src.stem}_{k}{src.suffix}", k + 1
            taken.add(name.lower())
            copies[src] = out / name
    return copies


def _check_copies_replace_own(copies: dict[Path, Path], listing: Path) -> None:
    """Refuse, before any work, a label or names file copy (``copies``: source -> place in
    ``--out``) over a file already there that is neither the same bytes nor a label file
    the labels.csv there (``listing``, an earlier extract's) names: a file of the user's, or
    another label file of that name, is not replaced in silence."""
    listed: set[Path] | None = None
    for src, dest in copies.items():
        if dest == src or not (dest.exists() or dest.is_symlink()):
            continue
        if listed is None:
            columns = ("label_file", "label_names")
            listed = {p.resolve() for p in _listed_in(listing, columns)}
        if dest.is_symlink() or not (_same_bytes(src, dest) or dest.resolve() in listed):
            raise DataError(
                f"is already there, not a label file the labels.csv there names:"
                f" copying {shown(src.name)} there would replace it; move it away, or"
                " choose another --out",
                dest,
            )


def _same_bytes(a: Path, b: Path) -> bool:
    """Whether the files ``a`` and ``b`` hold the same bytes (False when one is unreadable)."""
    try:
        return a.stat().st_size == b.stat().st_size and a.read_bytes() == b.read_bytes()
    except OSError:
        return False


def _listed_in(listing: Path, columns: tuple[str, ...] = ("path",)) -> list[Path]:
    """The files an existing labels.csv in ``--out`` names in ``columns`` (none when
    unreadable)."""
    import csv

    try:
        with listing.open(newline="", encoding="utf-8-sig") as fh:
            rows = list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error):
        return []
    return [
        listing.parent / r[c] for r in rows for c in columns if isinstance(r.get(c), str) and r[c]
    ]


def write_listing(listing: Listing, out: Path, jobs: list[Job], written: set[Path]) -> None:
    """Copy the label files and write labels.csv naming the pose files ``written`` (a clip
    that failed is not listed), paths relative to ``out``, as ``train`` reads them: the
    copies and labels.csv as one write (before, each in turn: a disk full at labels.csv
    left the new label files under the earlier labels.csv)."""
    from features.fileio import write_together

    files: list[tuple[Path, Callable[[Path], object]]] = []
    for src, dest in listing.copies.items():
        if dest != src:
            try:
                data = src.read_bytes()
            except OSError as exc:
                raise DataError(
                    f"cannot copy the label file ({exc.strerror or exc})", src
                ) from None
            files.append((dest, _writer_of(data)))
    text = _listing_text(listing, out, jobs, written)
    files.append((listing.path, lambda path: path.write_text(text, encoding="utf-8", newline="")))
    try:
        write_together(files)
    except DataError as exc:  # the pose files are written, each whole
        raise DataError(
            f"{exc.message}; the pose files are written (extract them again to list them)",
            exc.source,
        ) from None


def _writer_of(data: bytes) -> Callable[[Path], object]:
    """What writes ``data`` to the path it is given."""
    return lambda path: path.write_bytes(data)


def _listing_text(listing: Listing, out: Path, jobs: list[Job], written: set[Path]) -> str:
    """labels.csv's text: a row per pose file ``written``."""
    import csv
    import io

    header = ["path", "label", "subject", "label_file", "label_block_s", "label_names"]
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow([*header, *listing.extras])
    for job in jobs:
        if job.out not in written:
            continue
        track = job.track
        cells = [job.out.relative_to(out).as_posix(), job.label or "", job.subject or ""]
        if track is None:
            cells += ["", "", ""]
        else:
            cells += [
                _relative(listing.copies[track.path], out),
                "" if track.block_s is None else repr(track.block_s),
                "" if track.names is None else _relative(listing.copies[track.names], out),
            ]
        cells += [_cell(job.extras.get(k)) for k in listing.extras]
        writer.writerow(cells)
    return text.getvalue()


def _relative(path: Path, out: Path) -> str:
    """``path`` (inside ``out``) as labels.csv names it, from ``out``."""
    return path.resolve().relative_to(out.resolve()).as_posix()


def _cell(value: Any) -> str:
    """An extra column's value as a labels CSV spells it (read back as it was)."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _shown_job(job: Job) -> str:
    """A clip as the user listed it: the video, its frames and its subject."""
    shown = str(job.video) if job.start is None else f"{job.video} frames {job.start}-{job.end}"
    return shown if job.subject is None else f"{shown} (subject {job.subject})"


def longest_first(jobs: list[Job]) -> list[Job]:
    """``jobs`` by decreasing estimated cost, for workers that take the next job as they free
    up: the short jobs come last and the workers finish together instead of one running the
    last long clip alone. The cost is the video's size in bytes, times the cut's share of the
    video for a cut (its frames over the largest end frame asked of that video). Equal costs
    keep their order; an unreadable video counts 0 (its worker reports it)."""
    ends: dict[Path, int] = {}
    for job in jobs:
        if job.end is not None:
            ends[job.video] = max(ends.get(job.video, 0), job.end)
    sizes: dict[Path, int] = {}
    for video in {job.video for job in jobs}:
        try:
            sizes[video] = video.stat().st_size
        except OSError:
            sizes[video] = 0

    def cost(job: Job) -> float:
        if job.start is None or job.end is None or ends[job.video] <= 0:
            return float(sizes[job.video])
        return sizes[job.video] * (job.end - job.start) / ends[job.video]

    return sorted(jobs, key=cost, reverse=True)


# ---- one clip -----------------------------------------------------------------------------


def sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError as exc:
        raise DataError(f"cannot read ({exc.strerror or exc})", path) from None
    return h.hexdigest()


def extract_key(job: Job, options: Options, video_sha256: str) -> dict[str, Any]:
    """What an output depends on; an existing output with the same key is up to date."""
    from features.pose_estimation import model_version

    return {
        "video_sha256": video_sha256,
        "pose_model": model_version(),
        "smoothing": options.smoothing,
        "tracking": options.tracking,
        "keep_outside": options.keep_outside,
        "start": job.start,
        "end": job.end,
        "label": job.label,
        "subject": job.subject,
    }


def stored_metadata(path: Path) -> dict[str, Any] | None:
    """The metadata of an existing pose file, or None (absent or unreadable)."""
    import numpy as np

    from features.poses import check_archive

    try:
        check_archive(path, ["metadata"])
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["metadata"]))
    except (PosecbrError, OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError):
        return None
    return meta if isinstance(meta, dict) else None


def stored_key(path: Path) -> dict[str, Any] | None:
    """The ``extract_key`` of an existing pose file, or None (absent or unreadable)."""
    meta = stored_metadata(path)
    key = meta.get("extract_key") if meta is not None else None
    return key if isinstance(key, dict) else None


STALE_VFR = "made from a variable-frame-rate video by an older posecbr: extracted again"
"""Said of a pose file ``older_vfr_extraction`` found stale (the clip's line; a note)."""

STALE_PRESENCE = (
    "made by an older posecbr, which kept joints the model judged not in the picture:"
    " extracted again"
)
"""Said of a pose file ``kept_not_in_picture`` found stale (the clip's line; a note)."""


def _kept_not_in_picture(path: Path, meta: dict[str, Any]) -> bool:
    """Whether the pose file at ``path`` (its metadata ``meta``) is an older extraction's that
    kept joints the model judged not in the picture
    (:func:`features.pose_estimation.video.kept_not_in_picture`); False when it cannot tell."""
    from features.pose_estimation.video import PRESENCE_VERSION, kept_not_in_picture
    from features.poses import load_pose, load_pose_arrays

    version = meta.get("extraction_version")
    if isinstance(version, int | float) and version >= PRESENCE_VERSION:
        return False  # no need to read its arrays
    try:
        image = load_pose_arrays(path).get("image_landmarks")
        positions = load_pose(path).positions
    except PosecbrError:
        return False
    return image is not None and kept_not_in_picture(meta, positions, image) > 0


def _stale(job: Job, meta: dict[str, Any]) -> str:
    """Why the pose file ``job.out`` (its metadata ``meta``), made with today's options, is
    made again (:data:`STALE_VFR`, :data:`STALE_PRESENCE`); "" when it is up to date."""
    from features.pose_estimation.video import older_vfr_extraction

    if older_vfr_extraction(meta, job.video):
        return STALE_VFR
    return STALE_PRESENCE if _kept_not_in_picture(job.out, meta) else ""


# onnxruntime threads per model in this process (None: default). FFmpeg keeps its own
# decoding threads: pinned to the worker's one thread, 2 workers on 2 cores went from 103.5 to
# 94.3 frames/s (python -m benchmarks.scale --only-video --skip-training, quiet machine)
_THREADS: int | None = None
_ESTIMATOR: Any = None  # one PoseEstimator per process, made on first use (after any fork)


def _init_worker(threads: int) -> None:
    global _THREADS
    _THREADS = threads
    worker_ends_on_sigterm()  # stopped, a worker removes the hidden file it was writing
    # Per-clip bars from several processes would garble the terminal; the overall bar stays.
    os.environ["POSECBR_NO_PROGRESS"] = "1"


def _estimator(options: Options) -> Any:
    global _ESTIMATOR
    from features.pose_estimation import PoseEstimator

    if _ESTIMATOR is None or (
        _ESTIMATOR.smoothing != options.smoothing or _ESTIMATOR.tracking != options.tracking
    ):
        _ESTIMATOR = PoseEstimator(
            smoothing=options.smoothing, tracking=options.tracking, threads=_THREADS
        )
    return _ESTIMATOR


def _fluent_words(seq: Any, top: int = 4) -> list[list[str]] | None:
    """Per frame, up to ``top`` fluent phrases that hold (confidence >= 0.8), motion first."""
    import numpy as np

    try:
        from features.fluents import evaluate
        from features.timeline import background
    except ImportError:
        return None
    result = evaluate(seq)
    conf = np.nan_to_num(result.confidence, nan=0.0)
    conf[:, background(result)] = 0.0
    # Motion states first among equally confident ones: they are what changes on screen.
    order_key = np.round(conf, 1) + 0.05 * np.asarray(result.temporal, dtype=float)
    best = np.argsort(-order_key, axis=1, kind="stable")[:, :top]  # (frames, top)
    holds = np.take_along_axis(conf, best, axis=1) >= 0.8
    return [
        [result.words[i] for i, ok in zip(row, row_ok, strict=True) if ok]
        for row, row_ok in zip(best, holds, strict=True)
    ]


def _estimate(job: Job, options: Options, key: dict[str, Any], digest: str) -> tuple[Any, Any, Any]:
    """Run the pose model over ``job``'s video: the sequence its pose file holds, its image
    landmarks and (a variable frame rate resampled) the decoded frame of each row."""
    from features.pose_estimation import estimate_video

    meta: dict[str, Any] = {**job.extras, "extract_key": key, "video_sha256": digest}
    meta["source_video_digest"] = path_digest(job.video)  # which file, wherever extract ran
    if job.label is not None:
        meta["label"] = job.label
    if job.subject is not None:
        meta["subject"] = job.subject
    vp = estimate_video(
        job.video,
        smoothing=options.smoothing,
        tracking=options.tracking,
        keep_outside=options.keep_outside,
        progress_bar=True,
        estimator=_estimator(options),
        metadata=meta,
        announce=False,  # said in the clip's line (a worker's stderr may be lost)
    )
    seq, image_lm, video_frames = vp.sequence, vp.image_landmarks, vp.video_frames
    if job.start is not None and job.end is not None:
        if job.end > seq.n_frames:
            listed = f" (as {job.listed} gives it)" if job.listed else ""
            raise DataError(
                f"end frame {job.end}{listed} is past the video's {seq.n_frames} frames",
                job.video,
            )
        seq = seq.slice_frames(job.start, job.end)
        image_lm = image_lm[job.start : job.end]
        if video_frames is not None:
            video_frames = video_frames[job.start : job.end]
    return seq, image_lm, video_frames


def _write(
    job: Job, seq: Any, image_lm: Any, video_frames: Any, draw: Callable[[Path], object] | None
) -> None:
    """Write ``job``'s pose file (``seq``, its image landmarks and, a variable frame rate
    resampled, the decoded frame of each row; None: the one stored there is up to date) and
    its overlay, drawn by ``draw`` into the path it is given (None: no overlay): both or,
    one failing (a full disk, Ctrl-C), neither, each file there before left as it was
    (:func:`features.fileio.write_together`), as a clip that fails leaves none of its
    outputs. Before, the pose file was written first: an overlay that failed left its clip
    failed and its pose file new (with ``--force``, the earlier one replaced)."""
    from features.fileio import write_together
    from features.poses import save_pose

    extra = {"image_landmarks": image_lm}
    if video_frames is not None:  # the overlay draws row i on this decoded frame
        extra["video_frames"] = video_frames
    if draw is None or job.overlay is None:
        save_pose(seq, job.out, extra_arrays=extra)
        return
    files: list[tuple[Path, Callable[[Path], object]]] = [(job.overlay, draw)]
    if seq is not None:
        files.insert(0, (job.out, lambda path: save_pose(seq, path, extra_arrays=extra)))
    write_together(files, suffixed=True, make_parents=True)


def process(job: Job, options: Options) -> Outcome:
    """Extract one clip. Returns (status, path, detail); status "done", "skipped", "drawn"
    (the pose file up to date, its missing overlay drawn from it) or "failed"."""
    import numpy as np

    from features.pose_estimation import open_video
    from features.pose_estimation.overlay import check_mp4_size, padding_words, write_overlay
    from features.pose_estimation.video import gap_words
    from features.poses import gap_rows, load_pose, load_pose_arrays, recorded_gaps
    from features.repetitions import person_jumps

    try:
        digest = sha256_file(job.video)
        key = extract_key(job, options, digest)
        meta = None if options.force or not job.out.is_file() else stored_metadata(job.out)
        up_to_date = meta is not None and meta.get("extract_key") == key
        stale = _stale(job, meta or {}) if up_to_date else ""
        up_to_date = up_to_date and not stale
        if up_to_date and (job.overlay is None or job.overlay.is_file()):
            return "skipped", job.out, "up to date"
        padded = ""
        if job.overlay is not None:  # before the model runs and the pose file is written
            cap, info = open_video(job.video)
            cap.release()
            check_mp4_size(info.width, info.height, job.overlay)
            padded = padding_words(info.width, info.height)
        if up_to_date:
            seq = load_pose(job.out)
            stored = load_pose_arrays(job.out)
            image_lm, video_frames = stored["image_landmarks"], stored.get("video_frames")
        else:
            seq, image_lm, video_frames = _estimate(job, options, key, digest)
        holes = recorded_gaps(seq.metadata)
        vfr_note = (
            "" if video_frames is None else f"; variable frame rate: resampled to {seq.fps:g} fps"
        )
        if holes:
            vfr_note += f"; {gap_words([(a, b) for a, b, _r0, _r1 in holes])}"
        jumps = person_jumps(seq)
        if jumps:  # the tracked person left and the model took someone else in view
            where = first_few([f"{f} ({f / seq.fps:.2f} s)" for f in jumps])
            vfr_note += f"; the pose jumps to another person at frame {where}"
        draw = None
        if job.overlay is not None:
            draw = functools.partial(
                write_overlay,
                job.video,
                image_lm,
                fps=seq.fps,
                words=_fluent_words(seq) if options.fluents else None,
                frame_offset=job.start or 0,
                video_frames=video_frames,
                gaps=gap_rows(seq),  # no frames there: said so, not "no person"
                mark=_overlay_mark(job.video),
            )
            if padded:
                vfr_note += f"; its overlay's {padded}"
        _write(job, None if up_to_date else seq, image_lm, video_frames, draw)
        # a row inside a gap has no frame at all, not a frame without a person
        nobody = np.isnan(seq.positions).all(axis=(1, 2)) & ~gap_rows(seq)
        n_missing = int(nobody.sum())
        unseen = out_of_view(seq, nobody | gap_rows(seq))
        detail = f"{_frames_at(seq, video_frames)}, {n_missing} without a person{unseen}{vfr_note}"
        if up_to_date:
            return "drawn", job.out, f"up to date, {detail}; its overlay drawn"
        return "done", job.out, f"{detail}; {stale}" if stale else detail
    except PosecbrError as exc:
        return "failed", job.out, str(exc)


BODY_PARTS: dict[str, tuple[str, ...]] = {
    "face": ("nose", "eye", "ear", "mouth"),
    "shoulders": ("shoulder",),
    "elbows": ("elbow",),
    "wrists": ("wrist",),
    "hands": ("pinky", "index", "thumb"),
    "hips": ("hip",),
    "knees": ("knee",),
    "ankles": ("ankle",),
    "feet": ("heel", "foot_index"),
}
"""The body's parts, head to feet, as :func:`out_of_view` names them, each by what its
landmarks' names (``features.skeleton.JOINT_INDEX``) hold (``foot_index`` before ``index``)."""


def out_of_view(seq: PoseSequence, nobody: np.ndarray) -> str:
    """What the pose file ``seq`` (extracted: canonical) lacks in the frames that show the
    person (not ``nobody`` ``(frames,)``), in words for ``extract``'s line: each body part
    (:data:`BODY_PARTS`) with a landmark missing in some of them, and in what share ("; out of
    view in the frames with a person: hips 100 %, knees 100 %, ankles 100 %, feet 100 %"); ""
    when none is. A landmark
    the model placed outside the frame is stored missing (``--keep-outside`` aside), so this
    says once, plainly, what the camera did not show: a phone close up, the legs below its
    edge (before, only the files' NaN said so, and `describe` listed fluents "unavailable")."""
    import numpy as np

    from features.skeleton import JOINT_INDEX

    seen = np.flatnonzero(~nobody)
    if not len(seen):
        return ""
    missing = np.isnan(seq.positions[seen]).any(axis=2)  # (frames with a person, 33)
    said = []
    for part, marks in BODY_PARTS.items():
        cols = [
            i
            for name, i in JOINT_INDEX.items()
            if any(m in name for m in marks) and not (part == "hands" and "foot" in name)
        ]
        share = float(missing[:, cols].any(axis=1).mean())
        if share > 0:  # 100 % when missing in every one of them, never rounded up to it
            said.append(f"{part} {_share_words(share)} %")
    return f"; out of view in the frames with a person: {', '.join(said)}" if said else ""


def _share_words(share: float) -> str:
    """A share in (0, 1] in whole percent, as :func:`out_of_view` says it: "<1" and ">99"
    for a share that would round to 0 or, not being all, to 100."""
    if share < 0.005:
        return "<1"
    return ">99" if 0.995 <= share < 1.0 else f"{100 * share:.0f}"


def _frames_at(seq: PoseSequence, video_frames: np.ndarray | None) -> str:
    """A pose file's frames and the rate read from its video ("390 frames at 29.97 fps"); a
    video resampled (``video_frames``) says its rate in its note instead, and a still
    picture, one frame, has none to say."""
    frames = counted(seq.n_frames, "frame")
    if video_frames is not None or seq.n_frames == 1:
        return frames
    return f"{frames} at {seq.fps:g} fps"


def process_on_worker(job: Job, options: Options) -> Outcome:
    """:func:`process` on a Dask worker: onnxruntime and OpenCV get the worker's threads (one
    per worker with ``local:N``), so N workers share the cores instead of fighting over them."""
    global _THREADS
    if _THREADS is None:
        import cv2
        from dask.distributed import get_worker

        _THREADS = max(1, int(get_worker().state.nthreads))
        cv2.setNumThreads(_THREADS)  # OpenCV's own pool (colour conversion, resizing)
    return process(job, options)


def _on_cluster(scheduler: str, jobs: list[Job], options: Options) -> list[Outcome]:
    """Every job on the Dask cluster; a job whose worker failed it is reported like a failed
    clip (by its video), the others finish."""
    from features.cluster import connect, map_outcomes

    jobs = longest_first(jobs)  # Dask starts them in the order they are sent
    results = []
    with as_options(SCHEDULER), connect(scheduler) as client:
        names = [str(j.video) for j in jobs]
        for o in map_outcomes(client, process_on_worker, jobs, names, options,
                              desc="extract", unit="clip"):  # fmt: skip
            if o.ok and o.value is not None:
                results.append(o.value)
            else:
                results.append(("failed", jobs[o.index].out, f"{o.name}: {o.error}"))
    return results


# ---- the command --------------------------------------------------------------------------


def _check_out_dir(out: Path) -> None:
    if out.exists() and not out.is_dir():
        raise DataError("output is not a folder", out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        raise DataError(f"cannot write to the output folder ({exc.strerror or exc})", out) from None


def _check_outputs(jobs: list[Job]) -> None:
    """No pose file or overlay may be one of the videos (or a folder): refused before any work."""
    videos = ReadFiles([job.video for job in jobs])  # looked up once, not once per output
    for job in jobs:
        check_output(job.out, inputs=videos, what="pose file", make_parents=True)
        if job.overlay is not None:
            check_output(job.overlay, inputs=videos, what="overlay", make_parents=True)


def _options(args: argparse.Namespace) -> Options:
    """The extraction options the arguments ask for (after checking --workers, --scheduler)."""
    if args.workers < 1:
        raise ConfigError(f"must be at least 1, got {args.workers}", "--workers (--jobs)")
    with as_options(SCHEDULER):
        check_scheduler(args.scheduler)
    return Options(
        smoothing=not args.no_smoothing,
        tracking=not args.detect_every_frame,
        keep_outside=args.keep_outside,
        force=args.force,
    )


def _check_before_work(args: argparse.Namespace, jobs: list[Job]) -> None:
    """Every output path refused or prepared before the first clip is read."""
    single = _one_video(args.input)
    if single and args.scheduler is not None:
        raise ConfigError(
            "one video is extracted here, in this process; the cluster takes a folder or "
            "labels CSV of clips",
            "--scheduler",
        )
    if args.overlay is not None and single and not args.overlay_folder:
        try:
            check_mp4_name(args.overlay, False, "overlay")
        except DataError as exc:
            if args.overlay.suffix:
                raise
            made = f"; a folder to be made for it is written ending in / ({args.overlay}/)"
            raise DataError(exc.message + made, args.overlay) from None
        # one file, as segment --overlay and watch --out: its folder must exist (a folder
        # of overlays is made, with the class folders inside)
        check_output(args.overlay, inputs=[args.input], what="overlay")
    elif args.overlay is not None and not args.overlay.is_dir():
        if args.overlay.suffix.lower() in SHOWN_VIDEO_SUFFIXES:
            raise DataError(
                "for a folder or labels CSV, --overlay names the folder for the overlay "
                "videos, not one video file",
                args.overlay,
            )
    # the folder of the overlays: their files are extract's own to replace, not the user's
    overlays = args.overlay if args.overlay_folder or not single else None
    if single and jobs[0].out == args.out:  # --out names the pose file itself
        check_output(args.out, inputs=[args.input], what="pose file")  # one file: as --overlay
        _check_outputs(jobs)
        _check_not_replaced(jobs, args.out.parent, overlays, pose_files=False)
        _check_not_hidden(args.out.parent, jobs)
        return
    if args.out.exists() and not args.out.is_dir():
        raise DataError("output is not a folder", args.out)
    _check_outputs(jobs)
    _check_not_replaced(jobs, args.out, overlays)
    _check_not_read_again(args, single)
    _check_out_dir(args.out)
    _check_not_hidden(args.out, jobs)


def _one_video(source: Path) -> bool:
    """Whether ``source`` is one video or picture (its own pose file and overlay names),
    not a folder or a labels CSV (a folder of each, a CSV of one row too: its overlay named
    ``ovl.mp4`` made a folder of that name, and ``ovl`` was told to end in .mp4)."""
    return source.is_file() and source.suffix.lower() != ".csv"


def _check_not_replaced(
    jobs: list[Job], out: Path, overlays: Path | None, pose_files: bool = True
) -> None:
    """Refuse, before any work, a file already where the folder ``out`` puts a clip's pose
    file unless it is the pose file ``extract`` made of that same video before (run again,
    after Ctrl-C or with other options: it is brought up to date): a pose file of another
    video of the same name (``a/squat.mp4`` extracted, then ``b/squat.mp4``) or a file of
    the user's is not replaced in silence, as ``convert --out DIR`` refuses a pose file of
    another recording and ``--plot DIR`` a picture it did not draw. So is a file where
    extract names an overlay in the folder ``overlays`` (``--overlay DIR``) unless it
    is the overlay extract drew of that same video (marked so: :func:`_overlay_mark`), the
    pose file there or not. A file the user named (``--out x.npz``: not ``pose_files``, one
    video's ``--overlay x.mp4``) is theirs to replace."""
    from features.pose_estimation.overlay import mp4_mark

    digests: dict[Path, str | None] = {}
    for job in jobs:
        if pose_files and _there(job.out) and not _made_of(job.out, job.video, digests):
            raise DataError(_replaced_words(job, "a pose file", out), job.out)
        if overlays is not None and job.overlay is not None and _there(job.overlay):
            if job.overlay.is_symlink() or mp4_mark(job.overlay) != _overlay_mark(job.video):
                raise DataError(_replaced_words(job, "an overlay", overlays), job.overlay)


def _overlay_mark(video: Path) -> str:
    """What an overlay extract draws of ``video`` is marked with
    (:func:`features.pose_estimation.overlay.mark_mp4`), as a picture ``--plot`` draws is
    (:func:`features.timeline.picture_mark`): the command and a digest of the video's
    resolved path."""
    from features.timeline import picture_mark

    return picture_mark("extract", video)


def _there(path: Path) -> bool:
    """Whether anything (a file, a folder, a link, a broken link) is at ``path``."""
    return path.exists() or path.is_symlink()


def _made_of(pose: Path, video: Path, digests: dict[Path, str | None]) -> bool:
    """Whether ``pose`` is a pose file ``extract`` made of ``video`` (not a link): its
    metadata names this very video file (edited since, or not: a rerun reads no byte of it
    here) or records the video's SHA-256 (a copy of it, or the folders moved). The file is
    known by the digest of its resolved path (``source_video_digest``); a pose file made
    before that was kept, by its ``source_video`` looked up from here (a path relative to
    the folder extract ran in: from another folder it may name another video). A video that
    cannot be read passes (its clip fails, writing nothing); its digest is kept in
    ``digests`` (a labels CSV lists one video in several rows)."""
    from features.clips import source_video

    if pose.is_symlink() or not pose.is_file():
        return False
    meta = stored_metadata(pose)
    if meta is None or "pose_model" not in meta:
        return False
    if isinstance(meta.get("source_video_digest"), str):
        if meta["source_video_digest"] == path_digest(video):
            return True
    else:
        named = source_video(meta, pose)
        try:
            if named is not None and named.samefile(video):
                return True
        except OSError:
            pass
    if video not in digests:
        try:
            digests[video] = sha256_file(video)
        except DataError:
            digests[video] = None
    return digests[video] is None or meta.get("video_sha256") == digests[video]


def _replaced_words(job: Job, what: str, out: Path) -> str:
    """The refusal of a file at ``job``'s pose file or overlay (``what``) in the folder
    ``out`` (``--out``'s or ``--overlay``'s)."""
    return (
        f"is already there, not {what} posecbr extract made of {shown(job.video.name)}:"
        f" extracting into {shown(out)} would replace it; move it away, or choose another"
        f" {'--out' if what == 'a pose file' else '--overlay'}"
    )


def _check_not_hidden(out: Path, jobs: list[Job]) -> None:
    """Refuse, before any work, pose files written into a folder whose ``labels.csv`` does
    not list them: ``train OUT`` reads that labels.csv alone (an earlier ``extract`` of rows
    naming label files, ``convert``, or the user's) and would leave them out unsaid. Whose
    file it is cannot be told from the file, and a hand-written one is never rewritten, so
    none is: the user adds the rows, or extracts elsewhere. A run whose own rows name label
    files writes labels.csv itself (:func:`plan_listing` refuses what it would hide)."""
    listing = out / "labels.csv"
    if any(job.track is not None for job in jobs) or not listing.is_file():
        return
    listed = {p.resolve() for p in _listed_in(listing)}
    new = [job.out for job in jobs if job.out.resolve() not in listed]
    if not new:
        return
    names = [p.relative_to(out).as_posix() if p.is_relative_to(out) else str(p) for p in new]
    raise DataError(
        f"lists the pose files train of {shown(out)} reads, and not the"
        f" {counted(len(new), 'pose file')} this extract would write there"
        f" ({first_few(names)}): train would leave them out; add a row for each"
        " to it (path,label[,subject]) before extracting, or choose another --out",
        listing,
    )


def _check_not_read_again(args: argparse.Namespace, single: bool) -> None:
    """Refuse output folders where the next ``extract`` or ``train`` of the input, or a
    ``train`` of the pose files, would read what this run writes as clips: the pose files or
    overlays in the input folder when it is walked for class folders (no labels.csv), the
    overlays in the folder of the pose files (several clips: both are folders; one video's
    overlay is one file, put where the user likes, beside the video in ``--out .``)."""
    if args.input.is_dir() and not (args.input / "labels.csv").is_file():
        check_not_in_walked_folder(args.out, args.input, "output folder")
        if args.overlay is not None:
            check_not_in_walked_folder(args.overlay, args.input, "overlay folder")
    if args.overlay is not None and not single:
        check_not_in_walked_folder(
            args.overlay, args.out, "overlay folder", folder_what="the folder of the pose files"
        )


def _run_single(job: Job, options: Options) -> int:
    """A single video: its problem is THE error (one line from the CLI, exit 1)."""
    status, path, detail = process(job, options)
    if status == "failed":
        raise PosecbrError(detail)
    print(f"{'skipped' if status == 'drawn' else status}: {shown(path)} ({shown(detail)})")
    if status in ("done", "drawn") and job.overlay is not None:  # as segment --overlay says it
        print(f"overlay written to {shown(job.overlay)}", file=sys.stderr)
    return 0


def _in_processes(jobs: list[Job], options: Options, workers: int) -> list[Outcome]:
    """Every job on a pool of ``workers`` local processes, each with its share of the cores."""
    import concurrent.futures as cf
    import multiprocessing
    from concurrent.futures.process import BrokenProcessPool

    threads = max(1, (os.cpu_count() or 1) // workers)
    # spawn, not fork: a forked child would inherit onnxruntime's thread pools (and any
    # session already made here) in a state it cannot use, and hang.
    with cf.ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_init_worker,
        initargs=(threads,),
    ) as pool:
        try:
            with interrupts_held():  # Ctrl-C and SIGTERM: not in the middle of starting one
                futures = [pool.submit(run_task, process, job, options)
                           for job in longest_first(jobs)]  # fmt: skip
            return [fut.result() for fut in progress(cf.as_completed(futures), "extract",
                                                     len(futures), "clip")]  # fmt: skip
        except KeyboardInterrupt:  # Ctrl-C or SIGTERM: the workers stop, each clip unwound
            stop_workers(pool)
            raise
        except BrokenProcessPool:  # killed (out of memory, kill -9): the pool ends
            raise PosecbrError(
                "a worker process died (out of memory? try fewer --workers); the pose files "
                "finished before it are written (extract again: they are skipped as up to "
                "date)",
                "--workers (--jobs)",
            ) from None


def _run_all(jobs: list[Job], options: Options, args: argparse.Namespace) -> list[Outcome]:
    """Every job on the cluster, in this process, or on a pool of local processes."""
    workers = min(args.workers, len(jobs))
    if args.scheduler is not None:
        return _on_cluster(args.scheduler, jobs, options)
    if workers == 1:
        return [process(job, options) for job in progress(jobs, desc="extract", unit="clip")]
    return _in_processes(jobs, options, workers)


def _remarks(status: str, detail: str) -> list[str]:
    """What a clip's line says beyond its counts (``process``'s detail): a variable frame
    rate resampled, a gap left missing, the pose jumping to another person, the overlay's
    frames padded to even sides, a stale pose file extracted again. A single video's line
    says them; a run of several clips prints none."""
    parts = detail.split("; ")
    if status == "done":
        return parts[1:]
    if status == "drawn":  # "up to date, COUNTS; ...; its overlay drawn"
        return parts[1:-1]
    return []


def _summary(results: list[Outcome], out: Path) -> int:
    """A note per clip its line would say more of (:func:`_remarks`), one line per failed
    clip and the counts; the exit status (1 if any clip failed)."""
    failed = [r for r in results if r[0] == "failed"]
    for status, path, detail in results:
        remarks = _remarks(status, detail)
        if remarks:  # a run of several prints no clip's line: what it would say, said here
            print(f"note: {shown(path)}: {'; '.join(remarks)}", file=sys.stderr)
    for _, _, detail in failed:
        print(f"posecbr extract: error: {shown(detail)}", file=sys.stderr)
    done = sum(r[0] == "done" for r in results)
    drawn = sum(r[0] == "drawn" for r in results)
    skipped = sum(r[0] == "skipped" for r in results) + drawn
    overlays = f" ({counted(drawn, 'overlay')} drawn from them)" if drawn else ""
    print(
        f"{done} extracted, {skipped} up to date{overlays}, {len(failed)} failed -> {shown(out)}",
        file=sys.stderr if failed else sys.stdout,
    )
    return 1 if failed else 0


def run(args: argparse.Namespace) -> int:
    if not str(args.input):  # an unset shell variable ("$VIDEO"): not the current folder
        raise DataError(
            "the input is an empty path: name a video, still image, folder or labels CSV"
        )
    if is_url(args.input):  # as a path "//" became "/": a file not found, its password shown
        raise DataError(NOT_A_PATH, args.input)
    args.input = Path(args.input)
    options = _options(args)
    source: Path = args.input
    if args.overlay is not None and args.overlay.is_dir():  # a folder there, "/" or not
        args.overlay_folder = True
    jobs = find_jobs(source, args.out, args.overlay, args.overlay_folder)
    # out and the folders of the pose files and overlays (a class folder out/edge, made by
    # whichever worker writes in it first): those that are not there are removed when the
    # run fails and nothing was written into them
    made = folders_to_make([args.out / "_", *(d for j in jobs for d in (j.out, j.overlay) if d)])
    status = 1
    try:
        _check_before_work(args, jobs)
        if _one_video(source):
            status = _run_single(jobs[0], options)
            return status
        listing = plan_listing(source, args.out, jobs)
        results = _run_all(jobs, options, args)
        if listing is not None:
            written = {path for st, path, _ in results if st != "failed"}
            if written:
                write_listing(listing, args.out, jobs, written)
        status = _summary(results, args.out)
        if listing is not None and written:
            print(
                f"wrote {shown(listing.path)}: the recordings labelled over time whole, each"
                " with its label file (train reads the folder as the labels CSV)",
                file=sys.stderr,
            )
        return status
    finally:
        if status != 0:
            remove_empty(made)  # a failed run leaves no trace
