"""Hunt 36c: video and ``watch`` defects.

- A ``.ts`` (MPEG-TS) video named on the command line was "unknown clip format" to ``reps``,
  ``segment``, ``classify`` and ``train`` (``extract`` and ``watch`` read it); in a folder it
  was passed over. Now a named ``.ts`` is a video, and one in a folder is when it is MPEG-TS
  inside (a TypeScript source beside the clips is not).
- ``watch --out`` drew "nobody in view" over the frames of a gap in the video (a stretch
  with no frames), which ``segment`` and ``watch`` itself call "no frames in the video".
- A variable-rate video whose frame times went back (a frame stamped far ahead of the
  others, a clock reset) lost every frame after that place until the times passed the
  frame's again; now only the frame where they went back is left out, with a note (a single
  frame stamped far ahead is now left out itself: tests/test_hunt37c.py).
- A looped video of exact copies of one repetition: ``reps`` counts one repetition per loop
  and puts each in its own loop (checked: it did so before too; these tests hold it).

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
from tests.test_video_gaps import lunge_frames
from tests.test_video_vfr import _write, people  # noqa: F401 (a fixture)
from tests.test_watch import case_base  # noqa: F401 (a fixture)

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
    refused(["reps", str(video)], tmp_path, capsys, f"{video}: shows no person")
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


# on one xdist worker: the module's lunge_gap, squat_loops made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt36c")


@pytest.fixture(scope="module")
def lunge_gap(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The reverse lunge's first 120 frames at a quarter size, 25 fps, lossless (FFV1 in
    Matroska: each run decodes the same), its clock jumping 3 s after frame 59 (2.36 s): the
    frames 60 on from 5.4 s. Grid rows 60 to 134 (2.4 to 5.36 s) lie in the gap."""
    frames = lunge_frames(shared_data, 120)
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


def test_the_clock_going_back_loses_one_frame_not_every_later_one() -> None:
    """Frame times (s) of a 25 fps file that strays at 0.02 s. A clock reset to 0 after
    0.4 s: the frame at 0 s is left out and the later ones run on from 0.4 s, each one
    interval (0.04 s) on from the left-out frame's place: 0.04 s is 0.48 s. A single frame
    out of order (0.35 s between 0.4 and 0.5 s) is left out alone, as before. ``watch``
    (FrameClock, then Regrid) puts the same values on the grid as ``extract``
    (resample_timed). Before, every frame after the one that went back had no time: left
    out. (A single frame stamped far ahead: tests/test_hunt37c.py.)"""
    from features.pose_estimation.video import FrameClock, clocked_times, resample_timed
    from posecbr.commands.watch import Regrid
    from tests.test_video_vfr import _frame

    reset = [0.0, 0.02, 0.1, 0.18, 0.22, 0.26, 0.3, 0.38, 0.4, 0.0, 0.04, 0.08]
    elapsed, _ = clocked_times(reset, 25.0)
    want = [0, 0.02, 0.1, 0.18, 0.22, 0.26, 0.3, 0.38, 0.4, np.nan, 0.48, 0.52]
    np.testing.assert_allclose(elapsed, want, atol=1e-9)
    clock = FrameClock(25.0)
    for i, t in enumerate(reset):
        clock.take(i, t)
    assert clock.went_back == [(9, 0.4, 0.0)]
    once = [0.0, 0.1, 0.25, 0.4, 0.35, 0.5]
    elapsed, _ = clocked_times(once, 10.0)
    np.testing.assert_allclose(elapsed, [0, 0.1, 0.25, 0.4, np.nan, 0.5], atol=1e-9)
    # two frames out of order, 40 ms back (less than a bridged gap, 0.25 s): left out, the
    # times not shifted
    small = [0.0, 0.02, 0.1, 0.18, 0.4, 0.36, 0.37, 0.42]
    elapsed, _ = clocked_times(small, 25.0)
    want = [0, 0.02, 0.1, 0.18, 0.4, np.nan, np.nan, 0.42]
    np.testing.assert_allclose(elapsed, want, atol=1e-9)
    # the values are the times themselves (as run on): the grid is the time at each row
    values = np.array([0.0, 0.02, 0.1, 0.18, 0.22, 0.26, 0.3, 0.38, 0.4, -1.0, 0.48, 0.52])
    elapsed, _ = clocked_times(reset, 25.0)
    grid, shown = resample_timed(elapsed, values, 25.0)
    assert grid.shape == (14,)  # 0 to 0.52 s
    np.testing.assert_allclose(grid, np.arange(14) / 25.0, atol=1e-9)
    assert shown[-1] == 11  # 0.52 s: the frame stamped 0.08 s (0.52 s) on screen
    live, clock = Regrid(25.0, "phone.mkv"), FrameClock(25.0)
    worlds = [np.full((33, 3), v) for v in values]
    steps = [live.take(_frame(i, clock.take(i, t), worlds[i])) for i, t in enumerate(reset)]
    pushed = np.array([float(w[0, 0]) for step in steps for w, _vis, _shown in step])
    np.testing.assert_allclose(pushed, grid, atol=1e-12)


def _write_out_of_order(path: Path, pts_ms: list[int], frames: list[np.ndarray]) -> Path:
    """Lossless (FFV1 in Matroska) ``frames`` at these presentation times (ms), in order or
    not: each packet's decoding time is its index (ms), always increasing, as the muxer needs,
    and its presentation time is set after encoding (Matroska stores that one alone)."""
    from fractions import Fraction

    tb = Fraction(1, 1000)
    out = av.open(str(path), "w")
    stream = out.add_stream("ffv1", rate=25)
    h, w = frames[0].shape[:2]
    stream.width, stream.height, stream.pix_fmt = w, h, "yuv420p"
    stream.time_base = stream.codec_context.time_base = tb
    for k, rgb in enumerate(frames):
        frame = av.VideoFrame.from_ndarray(rgb, format="rgb24")
        frame.pts, frame.time_base = k, tb
        for packet in stream.encode(frame):
            packet.dts, packet.pts = packet.pts, pts_ms[packet.pts]
            out.mux(packet)
    for packet in stream.encode():
        packet.dts, packet.pts = packet.pts, pts_ms[packet.pts]
        out.mux(packet)
    out.close()
    return path


SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
LOOP = 25  # the squat video's second repetition: frames 25 to 49 (5 s at 5 fps)


@pytest.fixture(scope="module")
def squat_loops(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    """The squat video's second repetition (rest, down, up, rest) at half size, looped once
    and four times: MJPG AVIs at the video's 5 fps (each decodes the same every run)."""
    import cv2

    cap = cv2.VideoCapture(str(shared_data / SQUAT))
    frames = []
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        frames.append(cv2.resize(bgr, (bgr.shape[1] // 2, bgr.shape[0] // 2)))
    cap.release()
    one = frames[LOOP : 2 * LOOP]
    folder = tmp_path_factory.mktemp("loops")
    videos = {}
    for n in (1, 4):
        videos[n] = folder / f"loop{n}.avi"
        h, w = one[0].shape[:2]
        writer = cv2.VideoWriter(str(videos[n]), cv2.VideoWriter.fourcc(*"MJPG"), 5.0, (w, h))
        for bgr in one * n:
            writer.write(bgr)
        writer.release()
    return videos


def test_reps_of_a_looped_video_counts_one_repetition_per_loop(
    squat_loops: dict[int, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """The repetition alone: one, its far point at some frame p. Looped four times: four,
    the k-th's far point at 25 k + p (within a frame: the pose model's tracking carries
    over from loop to loop), each within its own loop give or take the rest either side
    (5 frames), none overlapping."""
    assert main(["reps", str(squat_loops[1]), "--json"]) == 0
    alone = json.loads(capsys.readouterr().out)["repetitions"]
    assert len(alone) == 1
    p = alone[0]["peak_frame"]
    assert main(["reps", str(squat_loops[4]), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    reps = got["repetitions"]
    assert got["count"] == len(reps) == 4
    for k, rep in enumerate(reps):
        assert abs(rep["peak_frame"] - (LOOP * k + p)) <= 1, (k, rep)
        assert LOOP * k - 5 <= rep["start_frame"] < rep["peak_frame"] < rep["end_frame"]
        assert rep["end_frame"] <= LOOP * (k + 1) + 5, (k, rep)
    assert all(a["end_frame"] <= b["start_frame"] for a, b in zip(reps, reps[1:], strict=False))


def test_reps_of_exact_copies_of_one_repetition_cut_at_the_seams(
    squat_loops: dict[int, Path],
) -> None:
    """The poses of the repetition alone, repeated six times exactly (no pose model between
    the copies): six repetitions, the k-th's far point at 25 k + p, the spans following one
    another, the ones between two others from the standing between two copies to the next
    (frames where the copy's knees and hips are all straighter than 160 degrees: its last 9
    and first 3, one rest across the seam). Where in that rest a span starts is where the
    line is lowest in it: at the seam itself while 5 fps read no running median (hunt 45c:
    a pose model's poses take three frames below 10 fps), 2 frames before it now; the rest's
    angles vary by 3-4 degrees there."""
    import dataclasses

    from features.datasets import load_clip
    from features.repetitions import COUNTED_ANGLES, count_repetitions, counted_angles

    one = load_clip(squat_loops[1])
    p = count_repetitions(one).repetitions[0].peak_frame
    assert one.confidence is not None
    six = dataclasses.replace(
        one,
        positions=np.concatenate([one.positions] * 6),
        confidence=np.concatenate([one.confidence] * 6),
        metadata={},
    )
    reps = count_repetitions(six).repetitions
    assert len(reps) == 6
    assert [r.peak_frame for r in reps] == [LOOP * k + p for k in range(6)]
    legs = [COUNTED_ANGLES.index(f"{s}_{j}") for s in ("left", "right") for j in ("knee", "hip")]
    standing = (counted_angles(one)[:, legs] > np.radians(160.0)).all(axis=1)
    assert np.flatnonzero(~standing).tolist() == list(range(3, LOOP - 9))
    spans = [(r.start_frame, r.end_frame) for r in reps]
    assert all(b == a for (_, b), (a, _) in zip(spans, spans[1:], strict=False)), spans
    for k, (a, b) in enumerate(spans[1:-1], start=1):
        assert abs(a - LOOP * k) <= 9 and standing[a % LOOP] and standing[b % LOOP], (k, a, b)
