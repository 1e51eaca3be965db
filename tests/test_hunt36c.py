"""Hunt 36c: video and ``watch`` defects.

- A ``.ts`` (MPEG-TS) video named on the command line was "unknown clip format" to ``reps``,
  ``segment``, ``classify`` and ``train`` (``extract`` and ``watch`` read it); in a folder it
  was passed over. Now a named ``.ts`` is a video, and one in a folder is when it is MPEG-TS
  inside (a TypeScript source beside the clips is not).
- ``watch --out`` drew "nobody in view" over the frames of a gap in the video (a stretch
  with no frames), which ``segment`` and ``watch`` itself call "no frames in the video".

The videos are written here with PyAV: MPEG-2 in MPEG-TS (grey frames, nobody in view).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from features.datasets import clip_files
from posecbr.cli import main
from tests.badinput import refused
from tests.test_video_vfr import _write
from tests.test_watch import case_base  # noqa: F401 (a fixture)

av = pytest.importorskip("av", reason="PyAV writes the videos")

LUNGE_NAME = "fit_reverse_lunge_pexels8233047.mp4"
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


@pytest.fixture(scope="module")
def lunge_gap(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The reverse lunge's first 120 frames at a quarter size, 25 fps, lossless (FFV1 in
    Matroska: each run decodes the same), its clock jumping 3 s after frame 59 (2.36 s): the
    frames 60 on from 5.4 s. Grid rows 60 to 134 (2.4 to 5.36 s) lie in the gap."""
    import cv2

    cap = cv2.VideoCapture(str(shared_data / "videos" / "lunge" / LUNGE_NAME))
    frames = []
    while len(frames) < 120:
        ok, bgr = cap.read()
        assert ok
        small = cv2.resize(bgr, (bgr.shape[1] // 8 * 2, bgr.shape[0] // 8 * 2))
        frames.append(np.ascontiguousarray(small[:, :, ::-1]))
    cap.release()
    pts = [40 * k + (3000 if k >= 60 else 0) for k in range(len(frames))]
    return _write(tmp_path_factory.mktemp("gap") / "lunge_gap.mkv", pts, frames, codec="ffv1")


def test_watch_draws_no_frames_not_nobody_in_view_inside_a_gap(
    case_base: Path,  # noqa: F811
    lunge_gap: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Each grid row drawn by ``watch --out``: rows 60 to 134 (the gap) say "no frames in the
    video", as the segment of the gap printed does; no row says "nobody in view" (a person
    is in every frame of the video). Before, the gap's rows said "nobody in view" from a
    second into it."""
    from features.pose_estimation import overlay

    drawn: list[list[str]] = []
    real = overlay.draw_pose

    def draw_pose(bgr: np.ndarray, landmarks: np.ndarray, words: list[str] = ()) -> np.ndarray:
        drawn.append(list(words))
        return real(bgr, landmarks, words)

    monkeypatch.setattr(overlay, "draw_pose", draw_pose)
    out = tmp_path / "seen.mp4"
    argv = ["watch", str(lunge_gap), "--db", str(case_base), "--speed", "0", "--out", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr()
    assert out.is_file() and len(drawn) == 195  # 0 to 7.76 s at 25 fps
    firsts = [words[0] if words else "" for words in drawn]
    assert firsts[60:135] == ["no frames in the video"] * 75
    assert "nobody in view" not in firsts
    segments = [json.loads(line) for line in printed.out.splitlines()]
    assert any(s["unknown"] == "no frames in the video" for s in segments)
