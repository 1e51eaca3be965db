"""The file suffixes taken for videos, in one place for the readers and ``extract``."""

from __future__ import annotations

#: what a folder is searched for as videos (a video file named alone is opened whatever its
#: name), in the order messages list them
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v", ".3gp", ".mts", ".m2ts",
                  ".mpg", ".mpeg", ".wmv", ".flv")  # fmt: skip
