"""Dataset loaders: every source of labelled clips becomes a stream of :class:`Clip`.

``iter_dataset(path)`` accepts, and tells apart by itself (:func:`detect_kind`):

==============  =================================================================================
kind            what ``path`` is
==============  =================================================================================
``uiprmd``      a UI-PRMD folder holding ``Segmented Movements/`` (or ``data/Segmented
                Movements/``); ``sensor="kinect"`` (also reads ``Incorrect Segmented Movements``)
                or ``"vicon"``. Label = movement slug (:data:`UIPRMD_MOVEMENTS`).
``csv``         a labels CSV ``path,label[,subject][,start,end]`` (header row required, more
                columns become extras), or a folder with a ``labels.csv``. Relative paths
                resolve against the CSV's folder; ``start``/``end`` are frame indices, end
                exclusive. A long recording labelled over time has a ``label_file`` instead of
                a ``label`` (:func:`read_label_track`: one label per frame, or per
                ``label_block_s`` seconds; codes named by a ``label_names`` file) and becomes
                one clip per labelled stretch.
``asf_amc``     a folder with ``.amc`` files (any depth) and the actor's ``.asf`` beside each:
                HDM05 (label = action in the file name, subject = actor) or CMU (label =
                the AMC's folder name).
``class_folders`` a folder with one subfolder per class holding pose files (``.npz``), BVH
                files or videos; label = subfolder name.
``pose_folder`` a folder of pose files whose metadata carries the label (what ``posecbr
                convert`` writes).
``pose_file``   a single pose file (or BVH, video, UI-PRMD text file).
==============  =================================================================================

Each :class:`Clip` holds a canonical sequence (33 BlazePose joints) whose metadata also carries
``label``, ``subject`` and the extras. Videos go through the pose estimator
(:mod:`features.pose_estimation`), imported only when a video is actually read.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
import sys
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import DataError
from features.fileio import as_path, file_head, path_exists, picture_words
from features.formats import SHOWN_VIDEO_SUFFIXES, TS_SUFFIX, is_mpeg_ts
from features.formats import VIDEO_SUFFIXES as VIDEO_SUFFIX_ORDER
from features.progress import progress
from features.text import spelt_among

from .handedness import right_handed
from .label_tracks import (
    LabelTrack,
    assumed_rate,
    check_count,
    code_order,
    frame_labels,
    labelled_stretches,
    read_label_names,
    read_label_track,
    refuse_inner_bom,
    track_labels,
    utf8_text,
)
from .poses import EXTRACTION_VERSION, PoseSequence, load_pose, pose_file_length, pose_file_metadata
from .readers.asfamc import hdm05_metadata, read_asf_amc
from .readers.bvh import read_bvh
from .readers.uiprmd import (
    UIPRMD_MOVEMENTS,
    read_uiprmd_kinect,
    read_uiprmd_vicon,
    uiprmd_metadata,
    uiprmd_sensor,
)

#: a file named as a clip with one of these suffixes is read as a video (``.ts`` among them)
VIDEO_SUFFIXES = frozenset(SHOWN_VIDEO_SUFFIXES)
POSE_SUFFIXES = frozenset({".npz"})
#: what a folder is searched for as clips; a ``.ts`` file too when it is MPEG-TS inside
#: (:func:`features.formats.is_mpeg_ts`: not a TypeScript source)
CLIP_SUFFIXES = POSE_SUFFIXES | frozenset(VIDEO_SUFFIX_ORDER) | {".bvh"}

CSV_REQUIRED = ("path", "label")
_CSV_COLUMNS = ("path", "label", "subject", "start", "end")  # any other column is an extra


@dataclass(frozen=True)
class Clip:
    """One labelled clip: a canonical pose sequence, its label, subject and extras."""

    seq: PoseSequence
    label: str
    subject: str | None
    extras: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class _Entry:
    """A clip not read yet: how to read it, and what is known about it from its name."""

    load: Callable[[], PoseSequence]
    label: str | None
    subject: str | None
    extras: dict[str, Any]
    name: str
    path: Path  # the file it is read from
    # a recording labelled over time: its labelled stretches, each with its label
    pieces: Callable[[PoseSequence], list[tuple[PoseSequence, str]]] | None = None
    # what can be checked before the file is read (a recording's label file), given the
    # frame rate that replaces the file's (None: the file's own)
    check: Callable[[float | None], None] | None = None
    track: LabelTrack | None = None  # a recording labelled over time: its label file


def _suffix(path: Path) -> str:
    return path.suffix.lower()


def _check_clip_file(path: Path) -> None:
    """A DataError naming ``path`` unless it is a file: missing, a folder, or a pipe, socket
    or device (reading a pipe waits for a writer that may never come)."""
    if not path_exists(path):
        raise DataError("no such file", path)
    if path.is_dir():
        raise DataError("is a folder, not a clip file (give one of the clips in it)", path)
    if not path.is_file():
        raise DataError("is a pipe, socket or device, not a clip file", path)


def load_clip(path: str | Path) -> PoseSequence:
    """One clip file as a canonical sequence: pose file, BVH, UI-PRMD text file or video.

    Raises PoseFileError/DataError naming the file when it cannot be read.
    """
    path = as_path(path, "path")
    _check_clip_file(path)
    suffix = _suffix(path)
    if suffix in POSE_SUFFIXES:
        pose = load_pose(path)
        note_older_extraction(pose, path)
        return right_handed(pose.to_canonical())
    if suffix == ".bvh":
        return read_bvh(path)
    if suffix in VIDEO_SUFFIXES:
        try:
            from features.pose_estimation import estimate_poses
        except ImportError:
            raise DataError("video input needs the pose estimator", path) from None
        seq: PoseSequence = estimate_poses(path)
        return seq.to_canonical()
    if re.search(r"_positions(_inc)?\.txt(\.gz)?$", path.name):
        if uiprmd_sensor(path) == "vicon":
            return read_uiprmd_vicon(path)
        return read_uiprmd_kinect(path)
    if suffix == ".amc":
        return read_asf_amc(find_asf(path), path)
    expected = (
        "expected .npz pose file, .bvh, .amc, UI-PRMD positions file or a"
        f" video: {', '.join(sorted(VIDEO_SUFFIXES))}"
    )
    picture = picture_words(file_head(path))  # a still, as --db given one says it
    if picture is not None:
        raise DataError(f"{picture}, not a clip ({expected})", path)
    raise DataError(f"unknown clip format ({expected})", path)


def source_video(meta: Mapping[str, Any], pose_path: Path) -> Path | None:
    """The video a pose file was extracted from (its metadata's ``source_video``), where it
    is, or None. ``extract`` writes the path as it was given, so a relative one is relative
    to the folder ``extract`` ran in: it is looked up from the current folder, then from the
    pose file's folder and each folder above it (``extract videos --out poses`` run in a
    project's folder: poses/lunge/x.npz names videos/lunge/x.mp4), the first found."""
    video = meta.get("source_video")
    if not isinstance(video, str) or not video:
        return None
    given = Path(video)
    folders = [] if given.is_absolute() else list(Path(os.path.abspath(pose_path)).parents)
    for where in [given, *(folder / given for folder in folders)]:
        try:  # a name the system cannot look up (over 255 bytes) is no video to look at
            if where.is_file():
                return where
        except (OSError, ValueError):
            return None
    return None


def note_older_extraction(seq: PoseSequence, path: Path) -> None:
    """Say on stderr when a pose file was made from a variable-frame-rate video by an older
    posecbr (:func:`features.pose_estimation.video.older_vfr_extraction`): its poses are not
    what ``extract`` gives now (which extracts it again). Only a file extracted from a video
    (its metadata names the pose model) without today's ``extraction_version`` is looked at,
    and the video itself only when it is found where the file says (:func:`source_video`)."""
    meta = seq.metadata
    if "pose_model" not in meta or meta.get("extraction_version") == EXTRACTION_VERSION:
        return  # not from a video, or made by today's extraction
    video = source_video(meta, path)
    have_video = video is not None
    if "variable_frame_rate" not in meta and not have_video:
        return  # nothing says it was a variable frame rate, and no video to look at
    try:
        from features.pose_estimation.video import older_vfr_extraction

        older = older_vfr_extraction(meta, str(video))
    except (ImportError, DataError):
        return
    if older:
        print(
            f"note: {path}: made from a variable-frame-rate video by an older posecbr (its"
            " frames timed differently): `posecbr extract` of the video makes it again",
            file=sys.stderr,
        )


# ---- kinds -----------------------------------------------------------------------------


def _uiprmd_root(path: Path) -> Path | None:
    for root in (path, path / "data"):
        if (root / "Segmented Movements").is_dir():
            return root
    return None


def is_uiprmd_folder(path: str | Path) -> bool:
    """Whether ``path`` is a UI-PRMD folder (the data of both sensors, one chosen to read)."""
    return Path(path).is_dir() and _uiprmd_root(Path(path)) is not None


def _amc_files(path: Path) -> list[Path]:
    """The AMC files under ``path`` (any depth), none hidden or in a hidden folder."""
    return sorted(
        p
        for p in path.rglob("*")
        if p.suffix.lower() == ".amc"
        and not any(part.startswith(".") for part in p.relative_to(path).parts)
        and p.is_file()
    )


def clip_files(folder: Path) -> list[Path]:
    """The clip files of ``folder`` (not its subfolders), in name order: files whose suffix
    is in :data:`CLIP_SUFFIXES`, or ``.ts`` with MPEG-TS inside (a TypeScript source is no
    clip), not hidden (``._clip.npz``, macOS's resource fork on a copied disk, is no clip);
    what every command reads from a folder of clips."""
    return sorted(
        p
        for p in folder.iterdir()
        if p.is_file()
        and not p.name.startswith(".")
        and (_suffix(p) in CLIP_SUFFIXES or (_suffix(p) == TS_SUFFIX and is_mpeg_ts(p)))
    )


def detect_kind(path: str | Path) -> str:
    """Which kind of dataset ``path`` is (see the module docstring); DataError if none."""
    path = Path(path)
    if not path_exists(path):
        raise DataError("no such file or folder", path)
    if path.is_file():
        return "csv" if _suffix(path) == ".csv" else "pose_file"
    if not path.is_dir():  # reading a pipe (``<(cat labels.csv)``) waits for a writer
        raise DataError(
            "is a pipe, socket or device, not a dataset (a labels CSV, a clip or a folder)", path
        )
    if _uiprmd_root(path) is not None:
        return "uiprmd"
    if (path / "labels.csv").is_file():
        return "csv"
    if _amc_files(path):
        return "asf_amc"
    subdirs = sorted(p for p in path.iterdir() if p.is_dir() and not p.name.startswith("."))
    if any(clip_files(d) for d in subdirs):
        return "class_folders"
    if clip_files(path):
        return "pose_folder"
    raise DataError(
        "cannot tell what dataset this is: expected a UI-PRMD or HDM05 folder, a labels.csv,"
        " one subfolder per class with pose files or videos, or pose files",
        path,
    )


def labelled_over_time(path: str | Path) -> bool:
    """Whether the dataset at ``path`` holds recordings labelled over time: a labels CSV (or a
    folder with one) with a row naming a ``label_file``. DataError as :func:`detect_kind` and
    :func:`read_labels_csv` give it."""
    path = Path(path)
    if detect_kind(path) != "csv":
        return False
    csv_path = path if path.is_file() else path / "labels.csv"
    return any(rec["track"] is not None for rec in read_labels_csv(csv_path))


def unlisted_pose_files(folder: str | Path) -> list[str]:
    """The pose files in ``folder`` and its subfolders (one level: class folders) that its
    labels.csv does not list, as paths relative to it in name order: a dataset read through
    that labels.csv (``train FOLDER``) leaves them out. Hidden files and folders are none.
    Empty for a folder :func:`detect_kind` reads otherwise than by its labels.csv (a UI-PRMD
    root) or a labels CSV given as a file (whose rows the user chose); DataError as
    :func:`read_labels_csv` gives it."""
    folder = Path(folder)
    if not folder.is_dir() or detect_kind(folder) != "csv":
        return []
    listed = {Path(rec["path"]).resolve() for rec in read_labels_csv(folder / "labels.csv")}
    there = [
        p
        for p in (*folder.glob("*"), *folder.glob("*/*"))
        if _suffix(p) in POSE_SUFFIXES
        and not any(part.startswith(".") for part in p.relative_to(folder).parts)
        and p.is_file()
    ]
    return sorted(p.relative_to(folder).as_posix() for p in there if p.resolve() not in listed)


def check_no_overlaps(
    path: str | Path, labels: Collection[str] | None = None, twice: bool = False
) -> None:
    """Refuse a labels CSV two of whose rows give frames of one file different labels: rows
    ``start,end`` that overlap, or a row of a whole file and a row of a stretch of it (rows of
    one label may overlap; a stretch listed twice is refused by the training), or a row
    naming a label file (which labels every frame) and another row of the same file. Only
    rows with a label in ``labels`` are compared when it is given (the others are not trained
    on; a label file's rows always are). ``twice``: also two rows of the same stretch (the
    same file's same ``start,end``, or the whole file twice) of one label. Anything but a
    labels CSV passes. DataError naming the CSV and both lines, read from the rows alone (no
    clip is read)."""
    path = Path(path)
    if detect_kind(path) != "csv":
        return
    csv_path = path if path.is_file() else path / "labels.csv"
    by_file: dict[Path, list[dict[str, Any]]] = {}
    tracked: dict[Path, dict[str, Any]] = {}
    for rec in read_labels_csv(csv_path):
        key = rec["path"].resolve()
        if rec["track"] is None and labels is not None and not spelt_among(rec["label"], labels):
            continue
        if key in tracked or (rec["track"] is not None and key in by_file):
            first = tracked.get(key) or by_file[key][0]
            raise DataError(_tracked_twice(first, rec), csv_path)
        if rec["track"] is not None:
            tracked[key] = rec
        else:
            by_file.setdefault(key, []).append(rec)
    for rows in by_file.values():
        if twice:
            _check_listed_once(rows, csv_path)
        _check_one_label(rows, csv_path)


def _check_listed_once(rows: list[dict[str, Any]], csv_path: Path) -> None:
    """Refuse two of ``rows`` (of one file) of the same stretch and label."""
    listed: dict[tuple[float, float], dict[str, Any]] = {}
    for rec in rows:
        first = listed.setdefault(_span(rec), rec)
        if first is not rec and first["label"] == rec["label"]:
            raise DataError(_listed_twice(first, rec), csv_path)


def _check_one_label(rows: list[dict[str, Any]], csv_path: Path) -> None:
    """Refuse two of ``rows`` (of one file) that share frames and differ in label: a sweep
    in order of start, keeping each label's row that reaches farthest."""
    reach: dict[str, dict[str, Any]] = {}
    for rec in sorted(rows, key=lambda r: (_span(r)[0], r["line"])):
        start, end = _span(rec)
        other = max(
            (r for lab, r in reach.items() if lab != rec["label"] and _span(r)[1] > start),
            key=lambda r: _span(r)[1],
            default=None,
        )
        if other is not None:
            raise DataError(_overlap(other, rec), csv_path)
        if rec["label"] not in reach or _span(reach[rec["label"]])[1] < end:
            reach[rec["label"]] = rec


def _tracked_twice(a: dict[str, Any], b: dict[str, Any]) -> str:
    """Why a row naming a label file and a later row of the same file cannot both be."""
    track = a if a["track"] is not None else b

    def shown(rec: dict[str, Any]) -> str:
        if rec["track"] is not None:
            return f"label file {rec['track'].path.name}"
        frames = "whole" if rec["start"] is None else f"frames {rec['start']},{rec['end']}"
        return f"{frames} ({rec['label']!r})"

    return (
        f"lines {a['line']} and {b['line']} both give frames of {b['path'].name}"
        f" ({shown(a)}; {shown(b)}): line {track['line']} labels all of it over time, so they"
        " would be cases twice; list the recording once"
    )


def _listed_twice(a: dict[str, Any], b: dict[str, Any]) -> str:
    """Why two rows of the same stretch and label cannot both be."""
    frames = "whole" if a["start"] is None else f"frames {a['start']},{a['end']}"
    return (
        f"lines {a['line']} and {b['line']} both give {b['path'].name} {frames}"
        f" ({a['label']!r}): the one stretch would be written twice; list it once"
    )


def _span(rec: dict[str, Any]) -> tuple[float, float]:
    """A row's frames ``[start, end)``; a whole file's from 0 to infinity."""
    return (0, math.inf) if rec["start"] is None else (rec["start"], rec["end"])


def _overlap(a: dict[str, Any], b: dict[str, Any]) -> str:
    """Why rows ``a`` and ``b`` (``a`` starting first, or the whole file) cannot both be."""

    def shown(rec: dict[str, Any]) -> str:
        frames = "whole" if rec["start"] is None else f"frames {rec['start']},{rec['end']}"
        return f"{frames} ({rec['label']!r})"

    first, second = sorted((a, b), key=lambda r: r["line"])
    lo, hi = max(_span(a)[0], _span(b)[0]), min(_span(a)[1], _span(b)[1])
    shared = "its frames" if math.isinf(hi) else f"frames {int(lo)}-{int(hi) - 1}"
    ranged = a["start"] is not None and b["start"] is not None
    return (
        f"lines {first['line']} and {second['line']} give {b['path'].name} {shown(first)}"
        f" and {shown(second)}: {shared} would be cases of two activities"
        + (" (end is exclusive: rows 0,300 and 300,600 meet)" if ranged else "")
    )


def _uiprmd_entries(path: Path, sensor: str) -> list[_Entry]:
    root = _uiprmd_root(path)
    assert root is not None
    if sensor not in ("kinect", "vicon"):
        raise DataError(f"UI-PRMD sensor must be 'kinect' or 'vicon', got {sensor!r}", path)
    folder = "Kinect" if sensor == "kinect" else "Vicon"
    reader = read_uiprmd_kinect if sensor == "kinect" else read_uiprmd_vicon
    files: list[Path] = []
    for top in ("Segmented Movements", "Incorrect Segmented Movements"):
        d = root / top / folder / "Positions"
        if d.is_dir():
            files += [p for p in d.iterdir() if "_positions" in p.name]
    if not files:
        raise DataError(f"no {folder} positions files under Segmented Movements/{folder}", path)
    entries = []
    for f in files:
        meta = uiprmd_metadata(f)
        if not meta:
            continue
        movement = str(meta["movement"])
        label = UIPRMD_MOVEMENTS.get(movement, movement)
        extras = {
            "movement": movement,
            "episode": meta["episode"],
            "correct": meta["correct"],
            "dataset": "ui-prmd",
            "sensor": sensor,
        }
        entries.append(
            _Entry(lambda f=f: reader(f), label, str(meta["subject"]), extras, f.name, f)  # type: ignore[misc]
        )
    entries.sort(
        key=lambda e: (
            e.extras["movement"],
            e.subject,
            e.extras["episode"],
            not e.extras["correct"],
        )
    )
    return entries


def find_asf(amc: Path, beside: Sequence[Path] | None = None) -> Path:
    """The skeleton beside an AMC file: the one named for its subject (``HDM_<actor>.asf``
    for an HDM05 take ``HDM_<actor>_...``, ``<subject>.asf`` for a CMU take
    ``<subject>_<trial>.amc``), else the only .asf. Another subject's skeleton (named so) is
    refused: the take would move on someone else's bones. ``beside``: the files of the AMC
    file's folder, when the caller has listed them already (one listing for a folder of many
    takes, not one per take)."""
    files = list(amc.parent.iterdir()) if beside is None else beside
    asfs = [p for p in files if p.suffix.lower() == ".asf" and not p.name.startswith(".")]
    subject, own, pattern = _asf_subject(amc)
    if subject is not None:
        for cand in asfs:
            if cand.name.lower() == own:
                return cand
        # another subject's skeleton would move this subject's take on the wrong bones
        others = [p for p in asfs if re.fullmatch(pattern, p.name.lower())]
        asfs = [p for p in asfs if p not in others]
        if not asfs and others:
            raise NoSkeletonError(
                f"no {own if own[0].isdigit() else own.replace('hdm_', 'HDM_')} (the skeleton of"
                f" subject {subject}) beside it; {others[0].name} is another subject's",
                amc,
            )
    if len(asfs) == 1:
        return asfs[0]
    if not asfs:
        raise NoSkeletonError("no .asf skeleton file beside it", amc, put_there=True)
    raise NoSkeletonError(
        f"{len(asfs)} .asf files beside it and none named for its actor: cannot pick one", amc
    )


class NoSkeletonError(DataError):
    """:func:`find_asf` found no skeleton to give an AMC file. The message says how to give
    one to ``convert`` (what the takes of a dataset folder need: no command takes a skeleton
    for them); a command that takes one (``--asf``) for the file it reads says that instead
    (:meth:`naming`)."""

    def __init__(self, problem: str, amc: Path, put_there: bool = False) -> None:
        self.problem = problem
        self.put_there = put_there
        super().__init__(
            self._with("convert the file alone: posecbr convert FILE.amc --asf SKELETON.asf"), amc
        )

    def _with(self, remedy: str) -> str:
        there = "put the subject's .asf there, or " if self.put_there else ""
        return f"{self.problem} ({there}{remedy})"

    def naming(self, option: str) -> DataError:
        """The same refusal for a command whose ``option`` (``--asf``) names the skeleton."""
        return DataError(self._with(f"give it: {option} FILE.asf"), self.source)


def _asf_subject(amc: Path) -> tuple[str | None, str, str]:
    """(subject, the name of its skeleton file in lower case, a pattern matching any
    subject's skeleton name) of an HDM05 or CMU take; (None, "", "") for another name."""
    meta = hdm05_metadata(amc)
    if meta:
        subject = str(meta["subject"])
        return subject, f"hdm_{subject.lower()}.asf", r"hdm_[a-z]+\.asf"
    m = re.fullmatch(r"(\d+)_\d+", amc.stem)
    if m:
        return m.group(1), f"{m.group(1)}.asf", r"\d+\.asf"
    return None, "", ""


def _asf_amc_entries(path: Path) -> list[_Entry]:
    entries = []
    for amc in _amc_files(path):
        meta = hdm05_metadata(amc)
        if meta:
            label, subject = str(meta["label"]), str(meta["subject"])
            extras: dict[str, Any] = {"dataset": "hdm05", "take": meta["take"]}
        else:
            label, subject, extras = amc.parent.name, None, {}
        entries.append(
            _Entry(
                lambda amc=amc: read_asf_amc(find_asf(amc), amc),  # type: ignore[misc]
                label,
                subject,
                extras,
                amc.name,
                amc,
            )
        )
    return entries


def _from_metadata(seq: PoseSequence) -> tuple[str | None, str | None, dict[str, Any]]:
    meta = dict(seq.metadata)
    label = meta.pop("label", None)
    subject = meta.pop("subject", None)
    meta.pop("frame_offset", None)
    return (
        None if label is None else str(label),
        None if subject is None else str(subject),
        meta,
    )


def check_not_nested(folder: Path, files: Callable[[Path], list[Path]]) -> None:
    """Refuse a class folder ``folder`` that holds no clip itself (``files``: the clips of a
    folder, not of its subfolders) while a subfolder of it does (``squat/day1/clip.mp4``):
    class folders are read one level deep, and the class would be dropped without a word."""
    if files(folder):
        return
    nested = sorted(
        d.name for d in folder.iterdir() if d.is_dir() and not d.name.startswith(".") and files(d)
    )
    if nested:
        raise DataError(
            f"this class folder holds no clip itself, its subfolder {nested[0]!r} does"
            f"{f' (and {len(nested) - 1} more)' if len(nested) > 1 else ''}: class folders are"
            " read one level deep (put the clips in the class folder, or list them in a labels"
            " CSV)",
            folder,
        )


def check_no_extracted_twin(files: list[Path]) -> None:
    """Refuse a folder's clip ``files`` that hold a video and a pose file ``posecbr extract``
    made of it (:func:`extracted_twin`): the one recording would be read twice, two cases of
    one take (each the other's "held-out" neighbour, so the confidence is calibrated on
    copies) or two clips counted."""
    twin = extracted_twin(files)
    if twin is not None:
        pose, video = twin
        raise DataError(
            f"{pose.name} holds the poses of the video {video.name} beside it (made by posecbr"
            " extract): the one recording would be read twice; keep the video or its pose"
            " file in this folder, not both",
            pose.parent,
        )


def extracted_twin(files: list[Path]) -> tuple[Path, Path] | None:
    """The first pose file of ``files`` that ``posecbr extract`` made of a video among them,
    with that video, or None: its metadata names a video of that name (``source_video``)
    and, when it records one, the video's SHA-256 matches. A pose file of another video of
    the same name (its SHA-256 differs) is no twin; one that cannot be read is left to be
    refused as the clip it is."""
    videos: dict[str, list[Path]] = {}
    for p in files:
        if _suffix(p) in VIDEO_SUFFIXES:
            videos.setdefault(p.name, []).append(p)
    if not videos:
        return None
    from features.errors import PosecbrError
    from features.poses import pose_file_metadata

    for f in files:
        if _suffix(f) not in POSE_SUFFIXES:
            continue
        try:
            meta = pose_file_metadata(f)
        except PosecbrError:
            continue
        source = meta.get("source_video", meta.get("made_from"))
        named = Path(source.replace("\\", "/")).name if isinstance(source, str) else ""
        for video in videos.get(named, []):
            if _same_content(video, meta.get("video_sha256")):
                return f, video
    return None


def _same_content(video: Path, sha256: Any) -> bool:
    """Whether ``video``'s bytes have the SHA-256 ``sha256`` (True when none is recorded)."""
    import hashlib

    if not isinstance(sha256, str):
        return True
    digest = hashlib.sha256()
    try:
        with open(video, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
    except OSError:
        return True  # refused as it is read
    return digest.hexdigest() == sha256


def _class_folder_entries(path: Path) -> list[_Entry]:
    entries = []
    for d in sorted(p for p in path.iterdir() if p.is_dir() and not p.name.startswith(".")):
        check_not_nested(d, clip_files)
        check_no_extracted_twin(clip_files(d))
        for f in clip_files(d):
            entries.append(_Entry(lambda f=f: load_clip(f), d.name, None, {}, f.name, f))  # type: ignore[misc]
    return entries


def _pose_folder_entries(path: Path) -> list[_Entry]:
    check_no_extracted_twin(clip_files(path))
    return [
        _Entry(lambda f=f: load_clip(f), None, None, {}, f.name, f)  # type: ignore[misc]
        for f in clip_files(path)
    ]


def _parse_bool(value: str) -> Any:
    low = value.strip().lower()
    if low in ("true", "yes"):
        return True
    if low in ("false", "no"):
        return False
    return value


def read_labels_csv(csv_path: str | Path, unlabelled: bool = False) -> list[dict[str, Any]]:
    """Rows of a labels CSV as dicts: path (resolved), label, subject, start, end, extras.

    Header row required with at least ``path`` and ``label``. Raises DataError naming the
    file and line for a malformed row or a missing clip file, or for an empty label unless
    ``unlabelled`` (clips to classify, not to train on: pieces of a new recording).
    """
    csv_path = Path(csv_path)
    rows = _unnamed_columns_dropped(_csv_rows(csv_path), csv_path)
    header = _csv_header(rows[0], csv_path)
    records = (
        _csv_record(header, row, line_no, csv_path, unlabelled)
        for line_no, row in enumerate(rows[1:], start=2)
        if row and any(c.strip() for c in row)  # blank rows are skipped
    )
    return list(records)


def _csv_rows(csv_path: Path) -> list[list[str]]:
    """Every row of the CSV file (at least one); one clear error for a missing, non-UTF-8,
    malformed or empty file."""
    if not csv_path.is_file():
        raise DataError("no such file", csv_path)
    rows: list[list[str]] = []
    try:
        data = csv_path.read_bytes()
    except OSError as exc:
        raise DataError(f"cannot read the labels CSV ({exc.strerror or exc})", csv_path) from None
    text = utf8_text(data, "labels CSV", csv_path)
    # two labels CSVs joined (cat a.csv b.csv), the second saved with a byte order mark: it
    # would begin a path or label unseen ("no such file \ufeffrec2.npz")
    refuse_inner_bom(text, "labels CSV", csv_path, "a path or label")
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    try:
        rows.extend(reader)
    except csv.Error as exc:
        # an unclosed quote runs to the end of the file: name the row it opened on
        raise DataError(f"line {len(rows) + 1}: malformed CSV ({exc})", csv_path) from None
    if not rows:
        raise DataError(
            "empty CSV: a header row path,label[,subject][,start,end] is required", csv_path
        )
    return rows


def _unnamed_columns_dropped(rows: list[list[str]], csv_path: Path) -> list[list[str]]:
    """``rows`` without the columns the header leaves unnamed, which no row fills: the empty
    columns a spreadsheet saves after the last one used (``path,label,,`` and ``a.npz,squat,,``:
    Excel writes them once a cell out there has been touched), which were refused as
    "repeated column names", or kept as a column named "". A value in an unnamed column is
    refused naming its line and column: no name says what it is. An unnamed FIRST column is
    a row index, as pandas' ``to_csv()`` and R's ``write.csv`` save one (``,path,label`` and
    ``0,a.npz,squat``): dropped with its values, as before it was read as a column ""."""
    unnamed = [i for i, name in enumerate(rows[0]) if not name.strip()]
    if not unnamed or len(unnamed) == len(rows[0]):
        return rows  # no column named at all: the header's own error says so
    if unnamed[0] == 0:  # a row index
        rows = [row[1:] for row in rows]
        return _unnamed_columns_dropped(rows, csv_path) if len(unnamed) > 1 else rows
    for line_no, row in enumerate(rows[1:], start=2):
        filled = next((i for i in unnamed if i < len(row) and row[i].strip()), None)
        if filled is not None:
            raise DataError(
                f"line {line_no}: column {filled + 1} holds {row[filled].strip()[:40]!r}, and"
                " the header (line 1) gives that column no name",
                csv_path,
            )
    drop = set(unnamed)
    return [[c for i, c in enumerate(row) if i not in drop] for row in rows]


def _csv_header(row: list[str], csv_path: Path) -> list[str]:
    """The column names: those the reader knows (``path``, ``label``, ``subject``, ``start``,
    ``end`` and those of a recording labelled over time) in lower case, written in any case;
    every other column as the file spells it (spaces around it stripped). ``path`` and
    ``label`` (or ``label_file``) present, none repeated (in any case), ``start`` and ``end``
    both or neither."""
    known = (*_CSV_COLUMNS, *_TRACK_COLUMNS)
    header = [h.strip().lower() if h.strip().lower() in known else h.strip() for h in row]
    missing = [c for c in CSV_REQUIRED if c not in header]
    if missing == ["label"] and "label_file" in header:
        missing = []  # recordings labelled over time
    other = next((c for c in (";", "\t") if len(row) == 1 and c in row[0]), None)
    if missing and other is not None:  # Excel in many locales saves "CSV" with semicolons
        raise DataError(
            f"line 1: the columns are separated by {'tabs' if other == chr(9) else repr(other)},"
            " not commas (header path,label[,subject][,start,end])",
            csv_path,
        )
    if missing:
        raise DataError(
            f"line 1: header must name columns path,label[,subject][,start,end]; missing"
            f" {', '.join(missing)} (header row required)",
            csv_path,
        )
    if len({h.lower() for h in header}) != len(header):
        raise DataError("line 1: repeated column names in the header", csv_path)
    if ("start" in header) != ("end" in header):
        raise DataError("line 1: columns start and end go together", csv_path)
    return header


def _csv_record(
    header: list[str], row: list[str], line_no: int, csv_path: Path, unlabelled: bool = False
) -> dict[str, Any]:
    """One data row as the record :func:`read_labels_csv` returns (an empty label refused
    unless ``unlabelled``)."""
    if len(row) != len(header):
        raise DataError(
            f"line {line_no}: {len(row)} fields, the header has {len(header)}", csv_path
        )
    rec = dict(zip(header, (c.strip() for c in row), strict=True))
    for column in ("label", "subject"):  # stored with each case: no store holds a NUL
        if "\x00" in rec.get(column, ""):
            raise DataError(
                f"line {line_no}: column {column}: {rec[column]!r} contains a NUL character "
                "(a case base cannot store it)",
                csv_path,
            )
    if not rec["path"]:
        raise DataError(f"line {line_no}: empty path", csv_path)
    track = _track_columns(rec, csv_path, line_no)
    if not rec.get("label") and track is None and not unlabelled:
        raise DataError(f"line {line_no}: empty label", csv_path)
    clip = _clip_path(rec["path"], line_no, csv_path)
    start, end = _frame_range(rec, line_no, csv_path)
    if track is not None and start is not None:
        raise DataError(
            f"line {line_no}: start and end do not go with a label_file (it labels the whole"
            " recording, frame by frame or block by block)",
            csv_path,
        )
    extras = {
        k: _parse_bool(v) for k, v in rec.items() if k not in (*_CSV_COLUMNS, *_TRACK_COLUMNS)
    }
    return {
        "path": clip,
        "label": rec.get("label", ""),
        "subject": rec.get("subject") or None,
        "start": start,
        "end": end,
        "extras": extras,
        "line": line_no,
        "track": track,
    }


def _clip_path(path: str, line_no: int, csv_path: Path) -> Path:
    """The clip a row names (relative to the CSV's folder), which must exist."""
    clip = Path(path)
    if not clip.is_absolute():
        clip = csv_path.parent / clip
    if not path_exists(clip, f"line {line_no}: ", csv_path):
        raise DataError(f"line {line_no}: {_no_such_file(path, clip, csv_path)}", csv_path)
    return clip


def _no_such_file(value: str, looked_for: Path, csv_path: Path) -> str:
    """What a labels CSV's missing file is, in words; a relative path says where it was
    looked for (from the CSV's folder, not the working folder), and a path written with
    Windows' backslashes between folders says so when the file is there with slashes. A URL
    is said to be one: the path looked for (``http:/me:secret@host/x.mp4``) would show its
    password, which messages hide only in a URL."""
    if re.match(r"[A-Za-z][A-Za-z0-9+.-]+://", value):
        return (
            f"{value[:200]} is a URL, not a file (a labels CSV names files on this machine;"
            " posecbr watch plays a stream)"
        )
    if "\\" in value:
        slashed = value.replace("\\", "/")
        there = Path(slashed) if Path(slashed).is_absolute() else csv_path.parent / slashed
        try:
            found = path_exists(there)
        except DataError:  # not a path the system can look up either
            found = False
        if found:
            return (
                f"no such file {value[:200]} ({slashed[:200]} is there: a path takes / between"
                " folders, not \\)"
            )
    if Path(value).is_absolute():
        return f"no such file {value[:200]}"
    where = str(looked_for)[:200]
    return f"no such file {value[:200]} (looked for {where}: paths are from the CSV's folder)"


def _frame_range(
    rec: dict[str, str], line_no: int, csv_path: Path
) -> tuple[int | None, int | None]:
    """A row's ``start`` and ``end`` frames (end exclusive); (None, None) without them."""
    if "start" not in rec or not (rec["start"] or rec["end"]):
        return None, None
    try:
        start, end = int(rec["start"]), int(rec["end"])
    except ValueError:
        raise DataError(
            f"line {line_no}: start and end must be whole frame numbers,"
            f" got {rec['start']!r}, {rec['end']!r}",
            csv_path,
        ) from None
    if start < 0 or end <= start:
        raise DataError(
            f"line {line_no}: need 0 <= start < end (end exclusive), got {start}, {end}",
            csv_path,
        )
    return start, end


def _check_csv_twins(records: list[dict[str, Any]], csv_path: Path) -> None:
    """Refuse a labels CSV whose rows name, whole, a video and the pose file ``extract`` made
    of it (:func:`extracted_twin`): the one recording would be read twice."""
    whole = [r for r in records if r["track"] is None and r["start"] is None]
    twin = extracted_twin([r["path"] for r in whole])
    if twin is not None:
        line = {r["path"]: r["line"] for r in whole}
        pose, video = twin
        raise DataError(
            f"line {line[pose]}: {pose.name} holds the poses of the video {video.name} of line"
            f" {line[video]} (made by posecbr extract): the one recording would be read twice;"
            " list the video or its pose file, not both",
            csv_path,
        )


def _csv_entries(csv_path: Path, unlabelled: bool = False) -> list[_Entry]:
    """The clips a labels CSV lists; a row with an empty label (``unlabelled`` only) has the
    label its pose file's metadata gives, or none."""
    entries = []
    records = read_labels_csv(csv_path, unlabelled)
    _check_csv_twins(records, csv_path)
    for rec in records:
        if rec["track"] is not None:
            entries.append(_track_entry(rec))
            continue

        def load(rec: dict[str, Any] = rec) -> PoseSequence:
            seq = load_clip(rec["path"])
            if rec["start"] is not None:
                if rec["end"] > seq.n_frames:
                    raise DataError(
                        f"line {rec['line']}: end {rec['end']} is past the clip's"
                        f" {seq.n_frames} frames",
                        csv_path,
                    )
                seq = seq.slice_frames(rec["start"], rec["end"])
            return seq

        entries.append(
            _Entry(
                load,
                rec["label"] or None,
                rec["subject"],
                rec["extras"],
                rec["path"].name,
                rec["path"],
            )
        )
    return entries


# ---- recordings labelled over time ---------------------------------------------------------

_TRACK_COLUMNS = ("label_file", "label_block_s", "label_names")


def _track_columns(rec: dict[str, str], csv_path: Path, line_no: int) -> LabelTrack | None:
    """The label track a labels CSV row names (``label_file``, ``label_block_s``,
    ``label_names``), or None."""
    if not rec.get("label_file"):
        stray = [c for c in ("label_block_s", "label_names") if rec.get(c)]
        if stray:
            raise DataError(
                f"line {line_no}: {' and '.join(stray)} go{'es' if len(stray) == 1 else ''}"
                " with a label_file, and the row has none",
                csv_path,
            )
        return None
    if rec.get("label"):
        raise DataError(f"line {line_no}: give a label or a label_file, not both", csv_path)

    def resolve(column: str) -> Path:
        value = rec[column]
        f = Path(value)
        f = f if f.is_absolute() else csv_path.parent / f
        # a path the system cannot look up (a name too long): one line, not a traceback
        if not path_exists(f, f"line {line_no}: column {column}: ", csv_path):
            raise DataError(f"line {line_no}: {_no_such_file(value, f, csv_path)}", csv_path)
        if not f.is_file():  # a pipe would wait for a writer
            raise DataError(
                f"line {line_no}: column {column}: {value[:200]} is a folder, pipe, socket or"
                " device, not a file",
                csv_path,
            )
        return f

    block: float | None = None
    if rec.get("label_block_s"):
        try:
            block = float(rec["label_block_s"])
        except ValueError:
            block = float("nan")
        if not (np.isfinite(block) and block > 0):
            raise DataError(
                f"line {line_no}: label_block_s must be a finite number of seconds > 0, got"
                f" {rec['label_block_s']!r}",
                csv_path,
            )
    names = resolve("label_names") if rec.get("label_names") else None
    return LabelTrack(resolve("label_file"), block, names)


def split_by_track(seq: PoseSequence, track: LabelTrack) -> list[tuple[PoseSequence, str]]:
    """One clip per labelled stretch of the recording ``seq``, with its label (frames shared
    with the recording, :func:`features.derived.stretch`)."""
    names = read_label_names(track.names) if track.names is not None else None
    labels = read_label_track(track.path, names)
    return split_by_labels(seq, labels, track.block_s, track.path)


def split_by_labels(
    seq: PoseSequence, labels: Sequence[str], block_s: float | None, where: str | Path
) -> list[tuple[PoseSequence, str]]:
    """One clip per labelled stretch of the recording ``seq`` labelled by ``labels`` (one per
    frame, or one per ``block_s`` seconds; a count that does not fit is a DataError naming
    ``where``), with its label (frames shared with the recording,
    :func:`features.derived.stretch`)."""
    from .derived import stretch

    recording = Path(seq.source).name if seq.source else ""
    rate = assumed_rate(seq.metadata)
    per_frame = frame_labels(list(labels), seq.n_frames, seq.fps, block_s, where, recording, rate)
    return [(stretch(seq, a, b), lab) for a, b, lab in labelled_stretches(per_frame)]


def check_track(path: Path, track: LabelTrack, fps: float | None = None) -> None:
    """What can be checked of a recording labelled over time before it is read: its label
    file (and names) read, and the count fitted to its frames where they are known
    (:func:`check_fits_before_read`). DataError naming the label file, as
    :func:`split_by_track`."""
    names = read_label_names(track.names) if track.names is not None else None
    labels = read_label_track(track.path, names)
    check_fits_before_read(path, len(labels), track.block_s, track.path, path.name, fps)


def check_fits_before_read(
    path: Path,
    n_labels: int,
    block_s: float | None,
    where: str | Path,
    recording: str = "",
    fps: float | None = None,
) -> None:
    """Refuse ``n_labels`` labels (one per frame, or per ``block_s`` seconds) that do not fit
    the recording ``path`` where its frames are known before it is read, in the words
    :func:`frame_labels` gives once it is (naming ``where`` and ``recording``): a pose
    file's (the header's frame count and rate, :func:`features.poses.pose_file_length`),
    and a constant-rate video's (its container's count and rate,
    :func:`features.pose_estimation.video.frames_before_decoding`: the pose model not run
    for minutes first). ``fps``: the rate it is read at (``--fps``). Other recordings (a
    variable-frame-rate video, mocap) are checked once read."""
    if _suffix(path) in POSE_SUFFIXES:
        n_frames, rate = pose_file_length(path)
        said = assumed_rate(pose_file_metadata(path)) if fps is None else ""
        check_count(n_labels, (n_frames, n_frames), rate if fps is None else fps, block_s,
                    where, recording, said)  # fmt: skip
    elif _suffix(path) in VIDEO_SUFFIXES:
        try:
            from features.pose_estimation.video import frames_before_decoding
        except ImportError:
            return  # no pose estimator: refused as such when read
        known = frames_before_decoding(path)
        if known is not None:
            fewest, most, rate = known
            check_count(n_labels, (fewest, most), rate if fps is None else fps, block_s,
                        where, recording)  # fmt: skip


def _track_entry(rec: dict[str, Any]) -> _Entry:
    track: LabelTrack = rec["track"]
    return _Entry(
        lambda: load_clip(rec["path"]),
        None,
        rec["subject"],
        rec["extras"],
        rec["path"].name,
        rec["path"],
        pieces=lambda seq: split_by_track(seq, track),
        check=lambda fps: check_track(rec["path"], track, fps),
        track=track,
    )


def iter_recording(
    path: str | Path, track: LabelTrack, subject: str | None = None
) -> Iterator[Clip]:
    """The labelled stretches of one recording (anything :func:`load_clip` reads) as clips."""
    return recording_clips(load_clip(path), track, subject)


def recording_clips(
    seq: PoseSequence, track: LabelTrack, subject: str | None = None
) -> Iterator[Clip]:
    """The labelled stretches of the recording ``seq`` as clips."""
    return stretch_clips(split_by_track(seq, track), subject)


def stretch_clips(
    stretches: Iterable[tuple[PoseSequence, str]], subject: str | None = None
) -> Iterator[Clip]:
    """Labelled stretches (:func:`split_by_track`, :func:`split_by_labels`) as clips of
    ``subject``, each with its label in its metadata."""
    for part, label in stretches:
        part = part.with_metadata(label=label, subject=subject)
        yield Clip(seq=part, label=label, subject=subject, extras={})


def _entries(path: Path, kind: str, sensor: str, unlabelled: bool = False) -> list[_Entry]:
    if kind == "uiprmd":
        return _uiprmd_entries(path, sensor)
    if kind == "csv":
        return _csv_entries(path if path.is_file() else path / "labels.csv", unlabelled)
    if kind == "asf_amc":
        return _asf_amc_entries(path)
    if kind == "class_folders":
        return _class_folder_entries(path)
    if kind == "pose_folder":
        return _pose_folder_entries(path)
    return [_Entry(lambda: load_clip(path), None, None, {}, path.name, path)]


def dataset_files(path: str | Path, *, sensor: str = "kinect") -> list[Path]:
    """Every file reading the dataset at ``path`` would open: the labels CSV (if any), each
    clip's file and the label files of recordings labelled over time, found from names and
    listings alone (no clip is read)."""
    path = Path(path)
    kind = detect_kind(path)
    files = [e.path for e in _entries(path, kind, sensor)]
    if kind == "csv":
        csv_path = path if path.is_file() else path / "labels.csv"
        files.insert(0, csv_path)
        for rec in read_labels_csv(csv_path):
            track: LabelTrack | None = rec["track"]
            if track is not None:
                files += [p for p in (track.path, track.names) if p is not None]
    return files


def _keep(
    label: str | None,
    subject: str | None,
    extras: dict[str, Any],
    labels: Collection[str] | None,
    subjects: Collection[str] | None,
    movements: Collection[str] | None,
    episodes: Collection[int] | None,
    correct: bool | None,
) -> bool:
    """Whether a clip passes the filters; unknown values (None) pass until they are known."""
    if labels is not None and label is not None and not spelt_among(label, labels):
        return False
    if subjects is not None and subject is not None and not spelt_among(subject, subjects):
        return False
    if movements is not None and extra(extras, "movement") not in movements:
        return False
    episode = extra(extras, "episode")
    episode = extra(extras, "take") if episode is None else episode
    if episodes is not None and episode is not None and int(episode) not in episodes:
        return False
    marked = extra(extras, "correct")
    return not (correct is not None and marked is not None and marked != correct)


def _unshadowed(meta: Mapping[str, Any], given: Mapping[str, Any]) -> dict[str, Any]:
    """The metadata of a clip file that no column ``given`` for it (a labels CSV's) names in
    any case: the CSV's ``Correct`` overrides the file's ``correct``, as its ``correct``
    does (:func:`extra` would find the file's, spelt exactly, first)."""
    names = {k.strip().lower() for k in given}
    return {k: v for k, v in meta.items() if k.strip().lower() not in names}


def extra(extras: Mapping[str, Any], column: str) -> Any:
    """The value of ``column`` among a clip's extras, its name in any case (a labels CSV's
    columns keep their spelling: ``Correct`` is the column ``correct``); None if absent."""
    if column in extras:
        return extras[column]
    low = column.strip().lower()
    return next((v for k, v in extras.items() if k.strip().lower() == low), None)


@dataclass(frozen=True)
class DatasetEntry:
    """One file of a dataset, not read yet: ``read()`` reads it (on this machine or on a
    cluster's worker, which must reach the same path) and gives its labelled clips (one, or
    one per labelled stretch of a recording), without those that what only the file tells
    (its subject, say) puts outside the filters."""

    entry: _Entry
    kind: str
    labels: Collection[str] | None = None
    subjects: Collection[str] | None = None
    movements: Collection[str] | None = None
    episodes: Collection[int] | None = None
    correct: bool | None = None
    fps: float | None = None  # the frame rate that replaces the file's, None: the file's
    unlabelled: bool = False  # a labels CSV's row may leave its label empty (to classify)

    @property
    def name(self) -> str:
        return self.entry.name

    def _keep(self, label: str | None, subject: str | None, extras: dict[str, Any]) -> bool:
        return _keep(label, subject, extras, self.labels, self.subjects, self.movements,
                     self.episodes, self.correct)  # fmt: skip

    def read(self) -> list[Clip]:
        """The clips it holds (decoded, labelled: one, or one per labelled stretch of a
        recording labelled over time), without those that fail the filters."""
        e = self.entry
        whole = e.load()
        if self.fps is not None:  # before a label file in seconds is laid over its frames
            whole = replace(whole, fps=float(self.fps)).with_metadata(fps_source="given")
        pieces = e.pieces(whole) if e.pieces is not None else [(whole, e.label)]
        out = []
        for seq, piece_label in pieces:
            meta_label, meta_subject, meta_extras = _from_metadata(seq)
            label = piece_label if piece_label is not None else meta_label
            subject = e.subject if e.subject is not None else meta_subject
            extras = {**_unshadowed(meta_extras, e.extras), **e.extras}
            if label is None:
                if self.kind != "pose_file" and not (self.unlabelled and self.kind == "csv"):
                    raise DataError(
                        "no label: its metadata has none (put it in a labels CSV)", seq.source
                    )
                label = ""
            if self._keep(label, subject, extras):
                seq = replace(seq, metadata=_unshadowed(seq.metadata, e.extras))
                seq = seq.with_metadata(label=label, subject=subject, **extras)
                out.append(Clip(seq=seq, label=label, subject=subject, extras=extras))
        return out


def dataset_entries(
    path: str | Path,
    *,
    sensor: str = "kinect",
    labels: Collection[str] | None = None,
    subjects: Collection[str] | None = None,
    movements: Collection[str] | None = None,
    episodes: Collection[int] | None = None,
    correct: bool | None = None,
    fps: float | None = None,
    unlabelled: bool = False,
) -> list[DatasetEntry]:
    """The clips of the dataset at ``path`` that may pass the filters (those of
    :func:`iter_dataset`), found from names alone: nothing is decoded yet. The label file
    of every recording labelled over time is read and fitted to the recording where that
    is cheap (:func:`check_track`), and every AMC file's skeleton found (:func:`find_asf`):
    one label file named for two recordings of different lengths, a malformed one, or an
    AMC file with no skeleton beside it is refused before the first file is worked on.
    ``fps``: the frame rate of every clip, in place of the files' own (None: their own);
    a label file in seconds is laid over the frames at that rate. ``unlabelled``: a labels
    CSV's rows may leave the label empty (clips to classify: the pose file's own label, or
    none)."""
    path = as_path(path, "path")
    kind = detect_kind(path)
    kept = [
        DatasetEntry(e, kind, labels, subjects, movements, episodes, correct, fps, unlabelled)
        for e in _entries(path, kind, sensor, unlabelled)
        if _keep(e.label, e.subject, e.extras, labels, subjects, movements, episodes, correct)
    ]
    listed: dict[Path, list[Path]] = {}  # each folder of AMC files listed once
    for d in kept:
        if _suffix(d.entry.path) == ".amc":
            folder = d.entry.path.parent
            if folder not in listed:
                listed[folder] = [p for p in folder.iterdir() if p.suffix.lower() == ".asf"]
            find_asf(d.entry.path, listed[folder])  # one without a skeleton: refused first
        if d.entry.check is not None:
            d.entry.check(fps)
    return kept


def dataset_labels(path: str | Path, *, sensor: str = "kinect") -> list[str]:
    """The labels the clips of the dataset at ``path`` have, each once, as a user is told
    them (whole-number codes by value, then the rest as text), found without decoding a
    clip: from names and labels CSVs, a recording's label file (its codes, or their names),
    a pose file's metadata. A clip whose label only reading it tells (a video, a BVH file
    in a folder of pose files) adds none. For the refusal of a ``--labels`` entry no clip
    has: the labels the user can give."""
    return _dataset_values(path, "label", sensor)


def dataset_subjects(path: str | Path, *, sensor: str = "kinect") -> list[str]:
    """The subjects the clips of the dataset at ``path`` have, each once, found as
    :func:`dataset_labels` finds the labels (names, labels CSVs, a pose file's metadata;
    none from a clip whose subject only reading it tells). For the refusal of a
    ``--subjects`` entry no clip has."""
    return _dataset_values(path, "subject", sensor)


def dataset_movements(path: str | Path, *, sensor: str = "kinect") -> list[str]:
    """The movements (UI-PRMD's "m01", a labels CSV's ``movement`` column) the clips of the
    dataset at ``path`` have, each once, found as :func:`dataset_labels` finds the labels.
    For the refusal of a ``--movements`` entry no clip has."""
    return _dataset_values(path, "movement", sensor)


def dataset_episodes(path: str | Path, *, sensor: str = "kinect") -> list[str]:
    """The episodes (UI-PRMD's episode, an HDM05 take, a labels CSV's ``episode`` or
    ``take`` column) the clips of the dataset at ``path`` have, each once, in order, found
    as :func:`dataset_labels` finds the labels. For the refusal of a ``--episodes`` entry no
    clip has."""
    return _dataset_values(path, "episode", sensor, "take")


def dataset_columns(path: str | Path, *, sensor: str = "kinect") -> list[str]:
    """The columns the clips of the dataset at ``path`` may have a value of (label, subject,
    a labels CSV's other columns, UI-PRMD's movement, episode and correct, ...), found from
    names and labels CSVs alone, as :func:`dataset_labels` finds the labels (a pose file's
    metadata is not read): the names a mistyped ``--target`` is likely to have meant."""
    path = Path(path)
    found = {"label", "subject"}
    for e in _entries(path, detect_kind(path), sensor, unlabelled=True):
        found.update(str(k) for k in e.extras)
    return sorted(found)


def _dataset_values(path: str | Path, field: str, sensor: str, or_else: str = "") -> list[str]:
    """:func:`dataset_labels` (``field`` "label"), :func:`dataset_subjects` ("subject"),
    :func:`dataset_movements` ("movement", one of a clip's extras) or
    :func:`dataset_episodes` ("episode", ``or_else`` "take": a clip's take when it has no
    episode, as the ``--episodes`` filter reads it)."""
    from .poses import pose_file_metadata

    path = Path(path)
    kind = detect_kind(path)
    found: set[str] = set()
    for e in _entries(path, kind, sensor):
        value = getattr(e, field) if field in ("label", "subject") else extra(e.extras, field)
        if value is None and or_else:
            value = extra(e.extras, or_else)
        if field == "label" and e.track is not None:
            found.update(track_labels(e.track))
        elif value is not None:
            found.add(str(value))
        elif _suffix(e.path) in POSE_SUFFIXES:
            meta = pose_file_metadata(e.path)
            stored = meta.get(field, meta.get(or_else) if or_else else None)
            found.update([] if stored is None else [str(stored)])
    return sorted(found, key=code_order)


def iter_dataset(
    path: str | Path,
    *,
    sensor: str = "kinect",
    progress_desc: str | None = None,
    labels: Collection[str] | None = None,
    subjects: Collection[str] | None = None,
    movements: Collection[str] | None = None,
    episodes: Collection[int] | None = None,
    correct: bool | None = None,
    limit: int | None = None,
    fps: float | None = None,
    unlabelled: bool = False,
) -> Iterator[Clip]:
    """Labelled clips of the dataset at ``path`` (kind detected by :func:`detect_kind`).

    Filters (None = all): ``labels``, ``subjects`` ("s01", "bd"), ``movements`` (UI-PRMD
    "m01"), ``episodes`` (UI-PRMD episode / HDM05 take), ``correct``; ``limit`` caps the
    number of clips; ``fps`` replaces every clip's frame rate before a recording labelled
    over time is cut by its label file. Clips are read one at a time, with a progress bar. A
    clip without a label (a pose file whose metadata has none) raises DataError naming it,
    unless ``unlabelled`` and it is a labels CSV's row (:func:`dataset_entries`).
    """
    path = as_path(path, "path")
    entries = dataset_entries(path, sensor=sensor, labels=labels, subjects=subjects,
                              movements=movements, episodes=episodes, correct=correct,
                              fps=fps, unlabelled=unlabelled)  # fmt: skip
    if limit is not None and entries and entries[0].kind not in ("class_folders", "pose_folder"):
        # Everything these filters test is known from the names; the folder kinds learn the
        # subject only from the file, so they stop after ``limit`` clips instead.
        entries = entries[: max(limit, 0)]
    desc = progress_desc or f"loading {path.name}"
    n_yielded = 0
    for entry in progress(entries, desc, total=len(entries), unit="clip"):
        if limit is not None and n_yielded >= limit:
            break
        for clip in entry.read():
            if limit is not None and n_yielded >= limit:
                break
            n_yielded += 1
            yield clip


def clip_column(clip: Clip, column: str) -> Any:
    """A clip's value of ``column``: label, subject, or a metadata extra (None if absent)."""
    if column == "label":
        return clip.label
    if column == "subject":
        return clip.subject
    value = extra(clip.extras, column)
    return extra(clip.seq.metadata, column) if value is None else value


def clip_target(clip: Clip, column: str) -> str | None:
    """A clip's value of ``column`` as a class name (:func:`target_value`); None when the clip
    has none (absent or empty)."""
    value = clip_column(clip, column)
    return None if value is None or value == "" else target_value(value)


def target_value(value: Any) -> str:
    """A column value as a class name: booleans (UI-PRMD's ``correct``) read "correct" /
    "incorrect"."""
    if isinstance(value, bool | np.bool_):
        return "correct" if bool(value) else "incorrect"
    return str(value)


_TRUE = frozenset({"true", "1", "yes", "y", "t", "correct"})
_FALSE = frozenset({"false", "0", "no", "n", "f", "incorrect"})


def truth_value(value: Any) -> bool | None:
    """A class name read as yes or no (``"true"``, ``"1"``, ``"correct"``, ... / ``"false"``,
    ``"0"``, ``"incorrect"``, ...; any case); None when it reads as neither."""
    text = str(value).strip().lower()
    return True if text in _TRUE else False if text in _FALSE else None


def load_dataset(path: str | Path, **kwargs: Any) -> list[Clip]:
    """All clips of :func:`iter_dataset` as a list (same keyword arguments)."""
    return list(iter_dataset(path, **kwargs))


__all__ = [
    "CLIP_SUFFIXES",
    "Clip",
    "clip_files",
    "LabelTrack",
    "check_no_overlaps",
    "check_fits_before_read",
    "check_track",
    "frame_labels",
    "iter_recording",
    "labelled_stretches",
    "read_label_names",
    "read_label_track",
    "split_by_track",
    "split_by_labels",
    "recording_clips",
    "stretch_clips",
    "unlisted_pose_files",
    "DatasetEntry",
    "clip_column",
    "clip_target",
    "extra",
    "dataset_files",
    "target_value",
    "truth_value",
    "UIPRMD_MOVEMENTS",
    "is_uiprmd_folder",
    "VIDEO_SUFFIXES",
    "dataset_entries",
    "detect_kind",
    "find_asf",
    "NoSkeletonError",
    "iter_dataset",
    "load_clip",
    "load_dataset",
    "read_labels_csv",
]
