"""``posecbr watch --out``: the video of what was watched (hunt 50d).

A served file refused as cut short kept no video of the frames watched before the cut,
where a stalled stream keeps it (tests/test_watch.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from posecbr.cli import main
from tests.badinput import small_case_base
from tests.test_hunt34c import _serving
from tests.test_hunt49b import _frames


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))  # any: the video is looked at


def test_a_served_mp4_cut_short_keeps_the_video_of_the_frames_watched(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The first 20 % of the glute-bridge MP4's bytes (its index first, its frames in the
    ``mdat`` box that ends the file) served over HTTP, watched with ``--out``: refused as
    cut short in one line, exit 1, as before, and the line says the video of the frames
    watched was written, every frame OpenCV decodes of the cut file here, each the file's
    frame of its index (the drawing on top aside), no temporary left. (No video was written:
    the frames watched were dropped as if half-written.)"""
    import cv2

    whole = shared_data / "videos" / "glute_bridge" / "fit_glute_bridge_pexels6525487.mp4"
    data = whole.read_bytes()
    folder, out = tmp_path / "served", tmp_path / "out" / "seen.mp4"
    folder.mkdir()
    out.parent.mkdir()
    cut = folder / "cut.mp4"
    cut.write_bytes(data[: len(data) // 5])
    here = _frames(cut)  # what a decoder makes of the cut file here
    assert 10 <= len(here) < int(cv2.VideoCapture(str(whole)).get(cv2.CAP_PROP_FRAME_COUNT))
    capsys.readouterr()
    with _serving(folder) as address:
        url = f"{address}/cut.mp4"
        code = main(["watch", url, "--db", str(case_base), "--speed", "0", "--out", str(out)])
    err = capsys.readouterr().err.splitlines()
    assert code == 1
    assert err[-1] == (
        f"posecbr watch: error: {url}: truncated MP4/MOV: the served file ends at byte"
        f" {cut.stat().st_size:,}, inside a box that runs to byte {len(data):,}; the video of"
        f" the {len(here)} frames watched was written to {out}"
    )
    assert [p.name for p in out.parent.iterdir()] == ["seen.mp4"]
    seen = _frames(out)
    assert len(seen) == len(here)
    for i, frame in enumerate(seen):
        differences = [np.abs(frame - h).mean() for h in here]
        assert int(np.argmin(differences)) == i, (i, differences)
