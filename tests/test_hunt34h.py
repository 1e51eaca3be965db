"""Hunt 34h: video input. A Matroska/WebM file cut short on this machine (a browser's WebM,
whose frame count came from the frames that were there, was taken as whole)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from tests.badinput import refused, small_case_base
from tests.test_hunt34c import BROWSER_PTS_MS, _browser_webm, _encode


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _opencv_vp8(path: Path) -> Path:
    """A WebM from OpenCV's own VP8 writer: 60 grey frames at 25 fps."""
    import cv2

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"VP80"), 25, (64, 48))
    assert writer.isOpened()
    for k in range(60):
        writer.write(np.full((48, 64, 3), 3 * k, np.uint8))
    writer.release()
    return path


WEBMS: dict[str, Callable[[Path], Path]] = {
    # a browser's: no frame rate stated (OpenCV says 1000 fps), with a duration or without
    "browser": lambda p: _browser_webm(p, live=False),
    "browser-no-duration": lambda p: _browser_webm(p, live=True),
    "vp8-30fps": lambda p: _encode(p, [33 * k for k in range(120)], "libvpx", 30, {}),
    "opencv-vp8": _opencv_vp8,
}


def _whole_and_cut(kind: str, folder: Path) -> tuple[Path, Path]:
    whole = WEBMS[kind](folder / "whole.webm")
    data = whole.read_bytes()
    cut = folder / "cut.webm"
    cut.write_bytes(data[: len(data) // 2])
    return whole, cut


@pytest.mark.parametrize("kind", list(WEBMS))
def test_a_webm_cut_in_half_is_truncated(kind: str, tmp_path: Path) -> None:
    """Each WebM whole opens and decodes every frame; cut at half its bytes it is refused
    when opened, "truncated", naming the file. A browser's (its frame count taken from the
    frames that were there) gave the 54 frames before the cut as the whole video."""
    from features.errors import DataError
    from features.pose_estimation import iter_frames, open_video

    whole, cut = _whole_and_cut(kind, tmp_path)
    frames = {"opencv-vp8": 60}.get(kind, 120)
    assert sum(1 for _ in iter_frames(whole)) == frames
    with pytest.raises(DataError) as info:
        open_video(cut)
    line = str(info.value)
    assert line.startswith(f"{cut}: truncated Matroska/WebM: the file ends at byte")
    assert f"byte {cut.stat().st_size:,}," in line and "\n" not in line


def test_a_webm_cut_anywhere_inside_an_element_is_truncated(tmp_path: Path) -> None:
    """A browser's WebM without a duration (its segment and no size stated: written as it
    went) cut one byte short, or inside its header, is truncated; cut where a cluster starts
    it holds whole clusters and is taken as a recording stopped there."""
    from features.errors import DataError
    from features.pose_estimation import iter_frames, open_video

    whole = _browser_webm(tmp_path / "whole.webm", live=True)
    data = whole.read_bytes()
    for n in (len(data) - 1, 30, 5):
        cut = tmp_path / f"cut{n}.webm"
        cut.write_bytes(data[:n])
        with pytest.raises(DataError, match="truncated Matroska/WebM"):
            open_video(cut)
    clusters = [i for i in range(len(data)) if data.startswith(b"\x1f\x43\xb6\x75", i)]
    stopped = tmp_path / "stopped.webm"
    stopped.write_bytes(data[: clusters[-1]])
    shown = sum(1 for _ in iter_frames(stopped))
    assert 0 < shown < len(BROWSER_PTS_MS)


@pytest.mark.parametrize("kind", ["browser", "browser-no-duration", "vp8-30fps"])
@pytest.mark.parametrize("command", ["extract", "segment", "watch"])
def test_commands_refuse_a_cut_webm_in_one_line(
    kind: str, command: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract``, ``segment`` and ``watch`` of a cut WebM: one line naming the file and
    "truncated", exit 1, nothing written. ``extract`` had written poses of the frames before
    the cut of a browser's WebM, ``watch`` and ``segment`` labelled them, exit 0."""
    _whole, cut = _whole_and_cut(kind, tmp_path)
    argv = {
        "extract": ["extract", str(cut), "--out", str(tmp_path / "poses")],
        "segment": ["segment", str(cut), "--db", str(case_base)],
        "watch": ["watch", str(cut), "--db", str(case_base), "--speed", "0"],
    }[command]
    refused(argv, tmp_path, capsys, f"{cut}: truncated Matroska/WebM")
