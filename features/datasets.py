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
                a ``label`` (:func:`features.label_tracks.read_label_track`: one label per
                frame, or per ``label_block_s`` seconds; codes named by a ``label_names``
                file) and becomes one clip per labelled stretch.
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

from collections.abc import Callable, Collection, Iterator, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from features.errors import DataError
from features.fileio import as_path, path_exists
from features.progress import progress
from features.text import spelt_among

from .clip_folders import check_no_extracted_twin, check_not_nested, clip_files, extracted_twin
from .clips import (
    POSE_SUFFIXES,
    Clip,
    ListedClip,
    clip_suffix,
    find_asf,
    load_clip,
)
from .label_tracks import (
    LabelTrack,
    code_order,
    track_labels,
)
from .labels_csv import check_rows_apart, read_labels_csv
from .poses import PoseSequence, loaded_metadata, pose_file_metadata
from .readers.asfamc import ASF_AMC_COLUMNS, hdm05_metadata, read_asf_amc
from .readers.uiprmd import (
    UIPRMD_COLUMNS,
    UIPRMD_MOVEMENTS,
    read_uiprmd_kinect,
    read_uiprmd_vicon,
    uiprmd_metadata,
)
from .stretches import (
    check_fits_before_read,
    check_track,
    iter_recording,
    split_by_labels,
    split_by_track,
)
from .targets import clip_target, extra


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
    # the columns its reader adds to those its name tells (None: only reading it tells)
    adds: frozenset[str] | None = None


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


def detect_kind(path: str | Path) -> str:
    """Which kind of dataset ``path`` is (see the module docstring); DataError if none."""
    path = Path(path)
    if not path_exists(path):
        raise DataError("no such file or folder", path)
    if path.is_file():
        return "csv" if clip_suffix(path) == ".csv" else "pose_file"
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
        if clip_suffix(p) in POSE_SUFFIXES
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
    clip is read; :func:`features.labels_csv.check_rows_apart`)."""
    path = Path(path)
    if detect_kind(path) != "csv":
        return
    check_rows_apart(path if path.is_file() else path / "labels.csv", labels, twice)


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
            _Entry(
                lambda f=f: reader(f),  # type: ignore[misc]
                label,
                str(meta["subject"]),
                extras,
                f.name,
                f,
                adds=UIPRMD_COLUMNS | set(meta),
            )
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
                adds=ASF_AMC_COLUMNS | set(meta),
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

    def listed(self, metadata: bool = True) -> tuple[ListedClip, ...] | None:
        """The clip as the listing tells it, its frames not decoded: its label, subject and
        extras as :meth:`read` gives them (a pose file's metadata read alone; not read
        without ``metadata``), none when it fails the filters; None when only decoding (or
        the metadata not read) tells its label or subject (a recording labelled over time, a
        file other than a pose file its listing gives neither, unless its reader gives none
        either: a CMU take's subject)."""
        e = self.entry
        if e.pieces is not None:
            return None
        meta: dict[str, Any] = {}
        pose_file = clip_suffix(e.path) in POSE_SUFFIXES and metadata
        if pose_file:
            meta = loaded_metadata(e.path)
        if self.fps is not None:
            meta["fps_source"] = "given"
        meta_label = meta.pop("label", None)
        meta_subject = meta.pop("subject", None)
        meta.pop("frame_offset", None)
        label = e.label if e.label is not None else meta_label
        subject = e.subject if e.subject is not None else meta_subject
        told = e.adds is not None and "subject" not in e.adds  # none a read can give
        if label is None or (subject is None and not pose_file and not told):
            return None
        extras = {**_unshadowed(meta, e.extras), **e.extras}
        label, subject = str(label), None if subject is None else str(subject)
        if not self._keep(label, subject, extras):
            return ()
        return (ListedClip(e.name, label, subject, extras, frozenset() if pose_file else e.adds),)

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
        if clip_suffix(d.entry.path) == ".amc":
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
        elif clip_suffix(e.path) in POSE_SUFFIXES:
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


def load_dataset(path: str | Path, **kwargs: Any) -> list[Clip]:
    """All clips of :func:`iter_dataset` as a list (same keyword arguments)."""
    return list(iter_dataset(path, **kwargs))


__all__ = [
    "Clip",
    "DatasetEntry",
    "LabelTrack",
    "POSE_SUFFIXES",
    "UIPRMD_MOVEMENTS",
    "check_fits_before_read",
    "check_no_extracted_twin",
    "check_no_overlaps",
    "check_not_nested",
    "check_track",
    "clip_files",
    "clip_target",
    "dataset_columns",
    "dataset_entries",
    "dataset_episodes",
    "dataset_files",
    "dataset_labels",
    "dataset_movements",
    "dataset_subjects",
    "detect_kind",
    "extra",
    "find_asf",
    "is_uiprmd_folder",
    "iter_dataset",
    "iter_recording",
    "labelled_over_time",
    "load_clip",
    "load_dataset",
    "read_labels_csv",
    "split_by_labels",
    "split_by_track",
    "unlisted_pose_files",
]
