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


def _moving(n: int, size: tuple[int, int] = (96, 64)) -> list[np.ndarray]:
    """``n`` frames of a bright square crossing a gradient (BGR, uint8)."""
    w, h = size
    base = np.add.outer(np.arange(h), np.arange(w)).astype(np.uint8)
    frames = []
    for i in range(n):
        bgr = np.stack([base, base[::-1], np.full_like(base, 80)], axis=-1)
        bgr[10:30, 2 * i : 2 * i + 20] = 250
        frames.append(bgr)
    return frames


def test_a_recording_holds_each_frame_when_written_and_copies_it_into_its_mp4(
    tmp_path: Path,
) -> None:
    """The ``--out`` video's recording: after each frame written, a copy of its NUT file
    (what a kill would leave) decodes every frame written so far (FFmpeg wrote it 256 KiB at
    a time: none of these small frames until the end), its pipe gone once released; its
    MP4 decodes to the frames OpenCV's own MP4 writer gives of the same frames, bit for bit,
    with the same key frames and times (PyAV), the frames encoded once."""
    import av
    import cv2

    from features.pose_estimation.recording import Recording

    frames = _moving(30)
    nut = tmp_path / "seen.partial.nut"
    recording = Recording(nut, 25.0, (96, 64), "seen.mp4")
    for i, frame in enumerate(frames):
        recording.write(frame)
        if i in (0, 9, 29):
            left = tmp_path / "left.nut"
            left.write_bytes(nut.read_bytes())
            assert len(_frames(left, scale=1)) == i + 1
    recording.to_mp4(tmp_path / "made.mp4")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["left.nut", "made.mp4", nut.name]
    direct = cv2.VideoWriter(str(tmp_path / "direct.mp4"), cv2.VideoWriter.fourcc(*"mp4v"),
                             25.0, (96, 64))  # fmt: skip
    for frame in frames:
        direct.write(frame)
    direct.release()

    def packets(path: Path) -> list[tuple[bool, int | None, int | None]]:
        with av.open(str(path)) as container:
            return [(p.is_keyframe, p.pts, p.dts) for p in container.demux(video=0) if p.size]

    assert packets(tmp_path / "made.mp4") == packets(tmp_path / "direct.mp4")
    assert sum(k for k, _, _ in packets(tmp_path / "made.mp4")) < len(frames)  # not all key
    made, given = _frames(tmp_path / "made.mp4", 1), _frames(tmp_path / "direct.mp4", 1)
    assert len(made) == len(frames) and all(
        np.array_equal(a, b) for a, b in zip(made, given, strict=True)
    )
