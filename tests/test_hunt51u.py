"""A HEIF picture's transformative properties, and a full disk under an overlay (hunt 51u).

HEIF (ISO/IEC 23008-12) turns a picture as seen by the transformative properties its ipma
box lists for it, applied in that order, as libheif applies them: ``irot`` (quarter turns
counter-clockwise), ``imir`` (axis 0: upside down; 1: left to right) and ``clap`` (a clean
aperture: the window of the given width and height centred at the picture's centre plus the
given offsets, its left edge rounded down, its top to the nearest). OpenCV (FFmpeg's mov
demuxer) applied a picture coded whole's irot and read its imir as a turn (axis 0 not at
all, axis 1 as a half turn) and its clap not at all; a grid's clap was ignored. The
expected pictures here are made with numpy from the picture before it was coded.

OpenCV's video writer only warns when a write fails, so an overlay written to a full disk
was refused as "N frames encoded but 0 read back"; it now says the disk is full, as the
case base store says it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest

from features.errors import DataError
from features.pose_estimation.overlay import write_overlay
from tests.badinput import ROOT, read_only_mounts_work


def _noise_video(path: Path) -> Path:
    """Six frames of 320x240 noise at 5 fps (MP4, mp4v): some 30 kB each once coded."""
    rng = np.random.default_rng(51)
    out = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), 5.0, (320, 240))
    for _ in range(6):
        out.write(rng.integers(0, 256, (240, 320, 3), np.uint8))
    out.release()
    return path


def _overlay(video: Path, folder: Path) -> None:
    write_overlay(video, np.full((6, 33, 5), np.nan), folder / "over.mp4", 5.0)


#: in a private tmpfs of 16 kB mounted on the folder sys.argv[2]: the overlay of the video
#: sys.argv[1], then its frames recorded as ``watch --out`` records them (a NUT file beside
#: the MP4, copied into it); what each says, the folder's files after
FULL_DISK = """
import sys
from pathlib import Path
import cv2
from features.errors import DataError
from features.pose_estimation.recording import Recording
from tests.test_hunt51u import _overlay
folder = Path(sys.argv[2])
try:
    _overlay(Path(sys.argv[1]), folder)
except DataError as exc:
    print(exc)
print(sorted(p.name for p in folder.iterdir()))
recording = Recording(folder / "w.nut", 5.0, (320, 240), "w.mp4")
cap = cv2.VideoCapture(sys.argv[1])
while (got := cap.read())[0]:
    recording.write(got[1])
try:
    recording.to_mp4(folder / "w.mp4")
except DataError as exc:
    print(exc)
"""


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private mount (unshare -rm, mount)",
)
def test_an_overlay_written_to_a_full_disk_says_the_disk_is_full(tmp_path: Path) -> None:
    """Before: "cannot write: 6 frames encoded but 0 read back", OpenCV's writer's failed
    writes seen only in the file it left; ``watch --out``'s recording: "cannot write: the
    video could not be copied to MP4"."""
    video = _noise_video(tmp_path / "noise.mp4")
    folder = tmp_path / "small"
    folder.mkdir()
    mount = f'mount -t tmpfs -o size=16k tmpfs {folder} || exit 99; exec "$0" "$@"'
    done = subprocess.run(
        ["unshare", "-rm", "sh", "-c", mount, sys.executable, "-c", FULL_DISK, str(video),
         str(folder)],
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True,
        timeout=120,
    )  # fmt: skip
    if done.returncode == 99:
        pytest.skip("no tmpfs can be mounted here")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        f"{folder / 'over.mp4'}: cannot write: the disk is full (6 frames encoded but 0 read"
        " back): free some space and run again",
        "[]",
        "w.mp4: cannot write: the disk is full (the video could not be copied to MP4): free"
        " some space and run again",
    ]


def test_an_overlay_past_a_file_size_limit_says_so(
    tmp_path: Path, file_size_limit: Callable[[int], None]
) -> None:
    """Before: "cannot write: 6 frames encoded but 0 read back"."""
    video = _noise_video(tmp_path / "noise.mp4")
    file_size_limit(16 << 10)
    with pytest.raises(DataError) as caught:
        _overlay(video, tmp_path)
    assert str(caught.value) == (
        f"{tmp_path / 'over.mp4'}: cannot write: the file would grow past a size limit such as"
        " `ulimit -f` (6 frames encoded but 0 read back)"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["noise.mp4"]
