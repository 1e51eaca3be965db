"""The file suffixes taken for videos, in one place for the readers and ``extract``."""

from __future__ import annotations

from pathlib import Path

#: what a folder is searched for as videos (a video file named alone is opened whatever its
#: name), in the order messages list them
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v", ".3gp", ".mts", ".m2ts",
                  ".mpg", ".mpeg", ".wmv", ".flv")  # fmt: skip

TS_SUFFIX = ".ts"
"""An MPEG-TS video's suffix (a broadcast's, a screen recorder's, an HLS segment's), which is
TypeScript's as well: a ``.ts`` file named as a clip is read as a video; one in a folder only
when its content is MPEG-TS (:func:`is_mpeg_ts`), so a project's TypeScript sources lying
beside the clips are not read as videos."""

_TS_PACKET = 188
_TS_SYNC = 0x47


def is_mpeg_ts(path: Path) -> bool:
    """Whether the file at ``path`` starts as an MPEG-TS stream: the sync byte (0x47) at the
    start of each of its first 188-byte packets (up to five; at least two). Text (a TypeScript
    source) has no such bytes at those steps; False where the file cannot be read."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(5 * _TS_PACKET)
    except OSError:
        return False
    packets = len(head) // _TS_PACKET
    return packets >= 2 and all(head[k * _TS_PACKET] == _TS_SYNC for k in range(packets))


def is_video_in_folder(path: Path) -> bool:
    """Whether a file found in a folder counts as a video: its suffix is one of
    :data:`VIDEO_SUFFIXES`, or it is ``.ts`` and MPEG-TS inside (:func:`is_mpeg_ts`)."""
    suffix = path.suffix.lower()
    return suffix in VIDEO_SUFFIXES or (suffix == TS_SUFFIX and is_mpeg_ts(path))


#: the video suffixes as messages list them, ``.ts`` among them
SHOWN_VIDEO_SUFFIXES = (*VIDEO_SUFFIXES, TS_SUFFIX)
