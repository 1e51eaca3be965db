"""The clip files of a folder, as every command reads them: each recording once (a video and the
pose file ``posecbr extract`` made of it are one), none nested out of sight."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from features.errors import DataError
from features.formats import TS_SUFFIX, is_mpeg_ts

from .clips import CLIP_SUFFIXES, POSE_SUFFIXES, VIDEO_SUFFIXES, clip_suffix


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
        and (clip_suffix(p) in CLIP_SUFFIXES or (clip_suffix(p) == TS_SUFFIX and is_mpeg_ts(p)))
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
        if clip_suffix(p) in VIDEO_SUFFIXES:
            videos.setdefault(p.name, []).append(p)
    if not videos:
        return None
    from features.errors import PosecbrError
    from features.poses import pose_file_metadata

    for f in files:
        if clip_suffix(f) not in POSE_SUFFIXES:
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
