"""A clip: one file (a pose file, BVH, ASF/AMC with its skeleton found beside it, a UI-PRMD
text file or a video) read as a canonical sequence, which a :class:`Clip` holds with its label."""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from features.errors import DataError, PosecbrError
from features.fileio import as_path, file_head, path_exists, picture_words
from features.formats import SHOWN_VIDEO_SUFFIXES
from features.formats import VIDEO_SUFFIXES as VIDEO_SUFFIX_ORDER

from .handedness import METADATA_KEY as HANDEDNESS_KEY
from .handedness import right_handed
from .poses import EXTRACTION_VERSION, PoseSequence, load_pose, load_pose_arrays
from .readers.asfamc import hdm05_metadata, read_asf_amc
from .readers.bvh import read_bvh
from .readers.uiprmd import read_uiprmd_kinect, read_uiprmd_vicon, uiprmd_sensor

#: the columns reading a clip may add from its frames, to some clips and not to others: a
#: recording found written left-handed says so (:func:`features.handedness.right_handed`)
FRAME_COLUMNS = frozenset({HANDEDNESS_KEY})
#: a file named as a clip with one of these suffixes is read as a video (``.ts`` among them)
VIDEO_SUFFIXES = frozenset(SHOWN_VIDEO_SUFFIXES)
POSE_SUFFIXES = frozenset({".npz"})
#: what a folder is searched for as clips; a ``.ts`` file too when it is MPEG-TS inside
#: (:func:`features.formats.is_mpeg_ts`: not a TypeScript source)
CLIP_SUFFIXES = POSE_SUFFIXES | frozenset(VIDEO_SUFFIX_ORDER) | {".bvh"}


@dataclass(frozen=True)
class Clip:
    """One labelled clip: a canonical pose sequence, its label, subject and extras."""

    seq: PoseSequence
    label: str
    subject: str | None
    extras: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class ListedClip:
    """A clip as its dataset's listing tells it, its frames not decoded: its file's name,
    label, subject and extras, as reading it gives them; ``adds``: the columns reading it
    adds to these extras (none to a pose file's metadata read alone; a reader's own to what a
    UI-PRMD file's or an AMC take's name tells, :data:`features.readers.uiprmd.UIPRMD_COLUMNS`,
    :data:`features.readers.asfamc.ASF_AMC_COLUMNS`), None when only reading it tells.
    Reading any clip may also add one of :data:`FRAME_COLUMNS`."""

    name: str
    label: str
    subject: str | None
    extras: dict[str, Any]
    adds: frozenset[str] | None


def clip_suffix(path: Path) -> str:
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
    suffix = clip_suffix(path)
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
    _note_kept_not_in_picture(seq, path)
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


def _note_kept_not_in_picture(seq: PoseSequence, path: Path) -> None:
    """Say on stderr when a pose file of an older extraction keeps joint positions the model
    judged not in the picture (:func:`features.pose_estimation.video.kept_not_in_picture`):
    today's extraction stores them missing, so fluents are not stated on them."""
    try:
        from features.pose_estimation.video import kept_not_in_picture

        image = load_pose_arrays(path).get("image_landmarks")
    except (ImportError, PosecbrError):
        return
    if image is None:
        return
    kept = kept_not_in_picture(seq.metadata, seq.positions, image)
    if kept:
        print(
            f"note: {path}: made by an older posecbr, which kept {kept} joint positions the"
            " pose model judged not in the picture (presence below 0.5; fluents are stated on"
            " them): `posecbr extract` of the video makes it again without them",
            file=sys.stderr,
        )


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
