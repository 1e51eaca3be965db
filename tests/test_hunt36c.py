"""Hunt 36c: video and ``watch`` defects.

- A ``.ts`` (MPEG-TS) video named on the command line was "unknown clip format" to ``reps``,
  ``segment``, ``classify`` and ``train`` (``extract`` and ``watch`` read it); in a folder it
  was passed over. Now a named ``.ts`` is a video, and one in a folder is when it is MPEG-TS
  inside (a TypeScript source beside the clips is not).

The videos are written here with PyAV: MPEG-2 in MPEG-TS (grey frames, nobody in view).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.datasets import clip_files
from posecbr.cli import main
from tests.badinput import refused

av = pytest.importorskip("av", reason="PyAV writes the videos")

TYPESCRIPT = 'const greeting: string = "hi";\nexport default greeting;\n'


def _grey_ts(path: Path, frames: int = 12) -> Path:
    """``frames`` grey frames at 25 fps, MPEG-2 video in MPEG-TS."""
    path.parent.mkdir(parents=True, exist_ok=True)
    out = av.open(str(path), "w", format="mpegts")
    video = out.add_stream("mpeg2video", rate=25)
    video.width, video.height, video.pix_fmt = 64, 48, "yuv420p"
    for k in range(frames):
        frame = av.VideoFrame.from_ndarray(np.full((48, 64, 3), 5 * k, np.uint8), "rgb24")
        frame.pts = k
        for packet in video.encode(frame):
            out.mux(packet)
    for packet in video.encode():
        out.mux(packet)
    out.close()
    return path


def test_a_named_ts_video_is_read_as_a_video(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``reps clip.ts``: the video is read (nobody in it: refused for that), not "unknown
    clip format"; a TypeScript source named ``.ts`` is tried as a video and refused as none."""
    from features.datasets import load_clip

    video = _grey_ts(tmp_path / "clip.ts")
    assert load_clip(video).n_frames == 12
    refused(["reps", str(video)], tmp_path, capsys, f"{video}: no person in view")
    source = tmp_path / "app.ts"
    source.write_text(TYPESCRIPT)
    refused(["reps", str(source)], tmp_path, capsys, f"{source}: not a video")


def test_a_ts_file_in_a_folder_is_a_clip_only_when_it_is_mpeg_ts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A folder of a recording (``clip.ts``, MPEG-TS), TypeScript sources (``app.ts``; one
    that begins with a "G", MPEG-TS's sync byte, as its first packet would) and an empty
    ``.ts``: only the recording is a clip, for ``extract`` as for the others."""
    from features.formats import is_mpeg_ts

    folder = tmp_path / "clips"
    video = _grey_ts(folder / "clip.ts")
    (folder / "app.ts").write_text(TYPESCRIPT)
    (folder / "g.ts").write_text("G" + "x" * 600)
    (folder / "empty.ts").write_bytes(b"")
    assert is_mpeg_ts(video) and not is_mpeg_ts(folder / "g.ts")
    assert clip_files(folder) == [video]
    assert main(["extract", str(folder), "--out", str(tmp_path / "poses")]) == 0
    assert "1 extracted, 0 up to date, 0 failed" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "poses").iterdir()) == ["clip.npz"]
