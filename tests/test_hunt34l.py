"""Hunt 34l: review of the day's changes. A ``file:`` URL is watched as its path is, so what
it lacks is said as for its path, not as for a file on a server."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.badinput import refused, small_case_base


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _undecodable_avi(path: Path) -> Path:
    """An MJPG AVI whose container states 30 frames at 25 fps and whose JPEGs' data is
    zeroed (300 bytes from each start marker found): it opens, and no frame decodes."""
    import cv2

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (64, 48))
    assert writer.isOpened()
    for k in range(30):
        writer.write(np.full((48, 64, 3), 3 * k, np.uint8))
    writer.release()
    data = bytearray(path.read_bytes())
    at = data.find(b"\xff\xd8")
    while at >= 0:
        data[at + 2 : at + 300] = bytes(298)
        at = data.find(b"\xff\xd8", at + 300)
    path.write_bytes(bytes(data))
    return path


def test_a_file_url_that_decodes_no_frame_is_refused_as_its_path_is(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """None of the 30 frames decodes: the path is refused "truncated or corrupt: decoded 0
    of 30 frames", and so is ``file://PATH`` (it said "read none of the 30 frames the served
    file holds: ... the server does not answer range requests", of a file on this
    machine)."""
    folder = tmp_path / "in"
    folder.mkdir()
    video = _undecodable_avi(folder / "clip.avi")
    for source in (str(video), f"file://{video}"):
        line = refused(
            ["watch", source, "--db", str(case_base), "--speed", "0"],
            folder,
            capsys,
            f"{source}: truncated or corrupt: decoded 0 of 30 frames",
        )
        assert "server" not in line
