"""Variable-frame-rate videos (phones make them): frame times read from the decoder, poses put
on a uniform grid at the declared rate by linear interpolation, the user told in one line; a
constant-rate video as before.

The videos are written here with PyAV (FFmpeg bundled) at presentation times chosen by the
test: frames of the real lunge video in ../shared/data/videos where a person is needed, plain
grey frames where only the timing matters.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from fractions import Fraction
from pathlib import Path

import cv2
import numpy as np
import pytest

import features.pose_estimation  # noqa: F401  (silences FFmpeg before any video is opened)
from features.errors import DataError
from features.pose_estimation import PoseEstimator, StreamFrame, estimate_video, iter_frames
from features.pose_estimation.tracker import FramePose
from features.pose_estimation.video import (
    check_whole,
    iter_timed_frames,
    outside_frame,
    resample_to_grid,
)
from features.poses import EXTRACTION_VERSION, load_pose, load_pose_arrays
from posecbr.cli import main
from posecbr.commands.watch import Regrid

av = pytest.importorskip("av", reason="PyAV writes the variable-frame-rate videos")

LUNGE = Path("videos") / "lunge" / "fit_reverse_lunge_pexels8233047.mp4"
# presentation times (ms): gaps of 20, 40 and 80 ms where 25 fps would be 40 ms throughout
PTS_MS = [0, 20, 100, 180, 220, 260, 300, 380, 400, 440, 520, 540, 620]
LEFT_HIP = 23


def _write(
    path: Path,
    pts_ms: list[int],
    frames: list[np.ndarray],
    rate: int | None = 25,
    codec: str = "libx264",
    options: dict[str, str] | None = None,
) -> Path:
    """A video of RGB ``frames`` with these presentation times (1 ms time base); ``rate``:
    the nominal rate the stream declares (None: none, as a browser's MediaRecorder writes);
    ``options``: the container's (``{"live": "1"}``: a WebM written as it goes). H.264 is
    lossless (``qp`` 0): lossy x264 decodes to different pixels from run to run (measured:
    4 encodings of the same frames, 4 different decodings), and with them the poses, the
    labels and the counts a test asserts."""
    tb = Fraction(1, 1000)
    out = av.open(str(path), "w", options=options or {})
    stream = out.add_stream(codec, rate=rate) if rate else out.add_stream(codec)
    if codec == "libx264":
        stream.codec_context.options = {"qp": "0"}
    h, w = frames[0].shape[:2]
    stream.width, stream.height, stream.pix_fmt = w, h, "yuv420p"
    stream.time_base = tb
    stream.codec_context.time_base = tb
    if rate is None:
        stream.codec_context.framerate = Fraction(0, 1)
    for t, rgb in zip(pts_ms, frames, strict=True):
        frame = av.VideoFrame.from_ndarray(rgb, format="rgb24")
        frame.pts, frame.time_base = t, tb
        for packet in stream.encode(frame):
            out.mux(packet)
    for packet in stream.encode():
        out.mux(packet)
    out.close()
    return path


def _per_frame(path: Path, tracking: bool) -> np.ndarray:
    """Each decoded frame's world landmarks as estimate_video keeps them (a joint outside the
    picture missing), unsmoothed; ``tracking``: the ROI from the frame before (False: the
    model run on each frame alone)."""
    est = PoseEstimator(smoothing=False, tracking=tracking)
    world = []
    for rgb in iter_frames(path):
        pose = est.process(rgb)
        w = pose.world.copy()
        w[outside_frame(pose.image, rgb.shape[1], rgb.shape[0])] = np.nan
        world.append(w)
    return np.array(world)


def _grey(n: int) -> list[np.ndarray]:
    return [np.full((48, 64, 3), 8 * k, np.uint8) for k in range(n)]


@pytest.fixture(scope="module")
def people(shared_data: Path) -> list[np.ndarray]:
    """The lunge video's first frames, RGB, a quarter size (a person in each)."""
    cap = cv2.VideoCapture(str(shared_data / LUNGE))
    frames = []
    while len(frames) < len(PTS_MS):
        ok, bgr = cap.read()
        assert ok
        size = (bgr.shape[1] // 8 * 2, bgr.shape[0] // 8 * 2)  # even: H.264's 4:2:0 needs it
        small = cv2.resize(bgr, size)
        frames.append(np.ascontiguousarray(small[:, :, ::-1]))
    cap.release()
    return frames


@pytest.fixture(scope="module")
def vfr_mkv(people: list[np.ndarray], tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _write(tmp_path_factory.mktemp("vfr") / "lunge_vfr.mkv", PTS_MS, people)


@pytest.mark.parametrize("suffix", [".mp4", ".mkv", ".mov"])
def test_frame_times_read_back_are_the_times_written(tmp_path: Path, suffix: str) -> None:
    path = _write(tmp_path / f"grey{suffix}", PTS_MS, _grey(len(PTS_MS)))
    times = [t for _rgb, t in iter_timed_frames(path)]
    assert times == pytest.approx([t / 1000 for t in PTS_MS], abs=1e-9)


def test_resample_to_grid_is_linear_between_neighbours_and_keeps_missing_missing() -> None:
    times = np.array([0.0, 0.1, 0.15, 0.4])
    values = np.array([[0.0, 1.0], [2.0, 3.0], [4.0, np.nan], [9.0, 8.0]])
    grid, before = resample_to_grid(times, values, 10.0)
    # grid 0, 0.1, 0.2, 0.3, 0.4 s; 0.2 and 0.3 lie between 0.15 and 0.4: weights 0.2, 0.6
    expected = np.array(
        [
            [0.0, 1.0],
            [2.0, 3.0],  # on frame 1: its own value, the missing joint of frame 2 no matter
            [0.8 * 4.0 + 0.2 * 9.0, np.nan],
            [0.4 * 4.0 + 0.6 * 9.0, np.nan],
            [9.0, 8.0],
        ]
    )
    np.testing.assert_allclose(grid, expected, rtol=0, atol=1e-12)
    assert before.tolist() == [0, 1, 2, 2, 3]


def test_extract_and_watch_resample_the_same_way() -> None:
    """Frames at 0, 0.08, 0.2, 0.35 and 0.4 s of a 10 fps file: 0.08 s lies within a quarter
    frame of 0.1 s, so it is on the grid, as ``watch`` takes it while no frame has strayed yet
    (it cannot know the future); 0.35 s strays. Both give v0, v1, v2, then 0.3 s two thirds
    of the way from 0.2 to 0.35 s, then the last frame. ``extract`` had blended 0.1 s from
    0.08 and 0.2 s, so ``segment`` and ``watch`` of one video could label it differently."""
    times = [0.0, 0.08, 0.2, 0.35, 0.4]
    values = np.array([0.0, 1.0, 4.0, 10.0, 7.0])
    expected = [0.0, 1.0, 4.0, 4.0 + (10.0 - 4.0) * 2 / 3, 7.0]
    grid, before = resample_to_grid(np.array(times), values, 10.0)
    np.testing.assert_allclose(grid, expected, rtol=0, atol=1e-12)
    assert before.tolist() == [0, 1, 2, 2, 4]
    live = Regrid(10.0, "phone.mp4")
    worlds = [np.full((33, 3), v) for v in values]
    steps = [live.take(_frame(i, t, worlds[i])) for i, t in enumerate(times)]
    pushed = [float(w[0, 0]) for step in steps for w, _vis, _shown in step]
    assert pushed == pytest.approx(expected, abs=1e-12)


def test_a_frame_without_a_time_after_straying_is_left_out_by_extract_as_by_watch() -> None:
    """Frames at 0, 0.1, 0.25, 0.25 (repeated), 0.4, 0.35 (going back) and 0.5 s of a 10 fps
    file: 0.25 s strays, so ``watch`` (FrameClock, then Regrid) leaves out the frames with a
    repeated or earlier time and puts the others on the grid: v0, v1, then 0.2 s two thirds
    of the way from 0.1 to 0.25 s (1 + 3 * 2/3 = 3), 0.3 s a third of the way from 0.25 to
    0.4 s (4 + 6 / 3 = 6), then the frames at 0.4 and 0.5 s. ``extract`` found the times not
    strictly increasing and took all seven frames as evenly spaced, so ``segment`` and
    ``watch`` of one video saw different poses."""
    from features.pose_estimation.video import FrameClock, clocked_times, resample_timed

    times = [0.0, 0.1, 0.25, 0.25, 0.4, 0.35, 0.5]
    values = np.array([0.0, 1.0, 4.0, 100.0, 10.0, 200.0, 7.0])
    expected = [0.0, 1.0, 3.0, 6.0, 10.0, 7.0]
    elapsed, strayed = clocked_times(times, 10.0)
    assert strayed and np.isnan(elapsed[[3, 5]]).all()
    grid, shown = resample_timed(elapsed, values, 10.0)
    np.testing.assert_allclose(grid, expected, rtol=0, atol=1e-12)
    assert shown.tolist() == [0, 1, 1, 2, 4, 6]  # the decoded frame on screen at each
    live, clock = Regrid(10.0, "phone.mkv"), FrameClock(10.0)
    worlds = [np.full((33, 3), v) for v in values]
    steps = [live.take(_frame(i, clock.take(i, t), worlds[i])) for i, t in enumerate(times)]
    pushed = [float(w[0, 0]) for step in steps for w, _vis, _shown in step]
    assert pushed == pytest.approx(expected, abs=1e-12)
    assert [s.index for step in steps for _w, _vis, s in step] == [0, 1, 1, 2, 4, 6]


def test_a_video_with_a_repeated_frame_time_is_resampled_without_that_frame(
    people: list[np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The variable-rate lunge frames (lossless, so each decodes the same in both files),
    once as they are and once with a grey frame at 180 ms again after the frame at 180 ms
    (Matroska keeps a repeated time; MP4 and a time going back are refused when written).
    The repeated frame is left out and the rest resampled: the same 16 poses as the video
    without it. ``extract`` had refused the file as "truncated or corrupt: decoded 14 of 17
    frames" (its frames' times not increasing, they could not show it whole), and would have
    taken all 14 frames as evenly spaced at 25 fps."""
    rep_ms = [*PTS_MS[:4], 180, *PTS_MS[4:]]
    assert PTS_MS[3] == 180
    grey = np.full_like(people[0], 128)
    clean = _write(tmp_path / "clean.mkv", PTS_MS, people, codec="ffv1")
    frames = [*people[:4], grey, *people[4:]]
    repeated = _write(tmp_path / "repeated.mkv", rep_ms, frames, codec="ffv1")
    options = {"smoothing": False, "tracking": False, "progress_bar": False}
    want = estimate_video(clean, **options)
    got = estimate_video(repeated, **options)
    assert got.sequence.n_frames == want.sequence.n_frames == 16
    np.testing.assert_array_equal(got.sequence.positions, want.sequence.positions)
    assert want.video_frames is not None and got.video_frames is not None
    assert got.video_frames.tolist() == [i + (i >= 4) for i in want.video_frames.tolist()]
    vfr = got.sequence.metadata["variable_frame_rate"]
    assert vfr["decoded_frames"] == 14 and vfr["frames_left_out"]["frames"] == [4]
    assert vfr["frame_interval_s"] == {"min": 0.02, "max": 0.08}
    assert got.sequence.metadata["missing_frames"] == want.sequence.metadata["missing_frames"]


def test_a_variable_rate_video_is_resampled_to_its_declared_rate(
    vfr_mkv: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    vp = estimate_video(vfr_mkv, smoothing=False, progress_bar=False)
    seq = vp.sequence
    # 0 to 620 ms at the 25 fps the stream declares: floor(0.62 * 25) + 1 = 16 frames
    assert seq.fps == 25.0
    assert seq.n_frames == 16
    assert vp.image_landmarks.shape == (16, 33, 5)
    # grid 120 ms lies between the frames at 100 and 180 ms (0.25 of the way);
    # grid 400 ms is the frame at 400 ms itself
    hip = _per_frame(vfr_mkv, tracking=True)[:, LEFT_HIP]
    assert np.isfinite(hip).all()
    np.testing.assert_allclose(seq.positions[3, LEFT_HIP], 0.75 * hip[2] + 0.25 * hip[3])
    np.testing.assert_array_equal(seq.positions[10, LEFT_HIP], hip[8])
    assert vp.video_frames is not None
    assert vp.video_frames.tolist()[:4] == [0, 1, 1, 2]  # 0, 40, 80, 120 ms
    vfr = seq.metadata["variable_frame_rate"]
    assert vfr["resampled_to_fps"] == 25.0 and vfr["decoded_frames"] == len(PTS_MS)
    assert vfr["frame_interval_s"] == {"min": 0.02, "max": 0.08}
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"note: {vfr_mkv}: variable frame rate (frames 20 to 80 ms apart):"
        " poses resampled to 25 fps"
    ]


def test_a_joint_missing_beside_a_grid_time_stays_missing(
    vfr_mkv: Path, people: list[np.ndarray], tmp_path: Path
) -> None:
    """Frame 3 (180 ms) shows nobody: grid times 160 and 200 ms, which lean on it, have no
    person; 120 ms leans on it too (100 to 180 ms); 240 ms (220 to 260 ms) does not."""
    frames = list(people)
    frames[3] = np.zeros_like(frames[3])
    path = _write(tmp_path / "gap.mkv", PTS_MS, frames)
    vp = estimate_video(path, smoothing=False, progress_bar=False, announce=False)
    assert vp.missing == (3, 4, 5)
    assert np.isnan(vp.sequence.positions[[3, 4, 5]]).all()
    assert np.isfinite(vp.sequence.positions[[2, 6], LEFT_HIP]).all()
    assert vp.sequence.metadata["missing_frames"] == [3, 4, 5]


def test_a_constant_rate_video_is_as_it_was_decoded(
    people: list[np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Frames 40 ms apart (25 fps): no resampling, and each frame's pose is what the model
    gives it at index / fps, bit for bit (as before frame times were read)."""
    path = _write(tmp_path / "cfr.mp4", [40 * k for k in range(len(PTS_MS))], people)
    vp = estimate_video(path, progress_bar=False)
    est = PoseEstimator()
    world, image = [], []
    for i, rgb in enumerate(iter_frames(path)):
        pose = est.process(rgb, i / 25.0)
        w = pose.world.copy()
        w[outside_frame(pose.image, rgb.shape[1], rgb.shape[0])] = np.nan
        world.append(w)
        image.append(pose.image)
    assert vp.video_frames is None and not vp.resampled
    assert vp.sequence.fps == 25.0
    np.testing.assert_array_equal(vp.sequence.positions, np.array(world))
    np.testing.assert_array_equal(vp.image_landmarks, np.array(image))
    assert "variable_frame_rate" not in vp.sequence.metadata
    assert capsys.readouterr().err == ""


def test_jitter_within_a_quarter_frame_is_constant_rate(tmp_path: Path) -> None:
    pts = [40 * k + (5 if k % 2 else 0) for k in range(10)]  # 5 ms of 40: an eighth
    path = _write(tmp_path / "jitter.mkv", pts, _grey(10))
    vp = estimate_video(path, progress_bar=False, announce=False)
    assert not vp.resampled and vp.sequence.n_frames == 10


def test_a_variable_rate_matroska_is_whole_not_truncated(tmp_path: Path) -> None:
    """Matroska states no frame count: OpenCV estimates duration x rate (23 at 25 fps for
    these 0.9 s), more than the 13 frames there are; the frames' times reach the end."""
    path = _write(tmp_path / "grey.mkv", PTS_MS + [900], _grey(len(PTS_MS) + 1))
    assert sum(1 for _ in iter_frames(path)) == len(PTS_MS) + 1
    # a file that really ends early is still refused
    with pytest.raises(DataError, match="decoded 13 of 23 frames"):
        check_whole(13, 23, path, span=0.66, fps=25.0)


def test_extract_says_it_resampled_and_draws_the_overlay_in_step(
    vfr_mkv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, overlay = tmp_path / "poses", tmp_path / "overlay.mp4"
    assert main(["extract", str(vfr_mkv), "--out", str(out), "--overlay", str(overlay)]) == 0
    printed = capsys.readouterr()
    assert "variable frame rate: resampled to 25 fps" in printed.out + printed.err
    pose_file = out / "lunge_vfr.npz"
    seq = load_pose(pose_file)
    assert seq.n_frames == 16 and seq.fps == 25.0
    assert seq.metadata["variable_frame_rate"]["resampled_to_fps"] == 25.0
    rows = load_pose_arrays(pose_file)["video_frames"]
    assert rows.tolist() == [0, 1, 1, 2, 2, 3, 4, 5, 6, 6, 8, 9, 9, 10, 11, 11]
    cap = cv2.VideoCapture(str(overlay))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 16  # one frame per pose row, at 25 fps
    assert cap.get(cv2.CAP_PROP_FPS) == pytest.approx(25.0)
    cap.release()
    # the up-to-date pose file still gives the overlay its rows
    overlay.unlink()
    assert main(["extract", str(vfr_mkv), "--out", str(out), "--overlay", str(overlay)]) == 0
    cap = cv2.VideoCapture(str(overlay))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 16
    cap.release()
    json.loads(json.dumps(seq.metadata))  # the note in the file is plain JSON


def _frame(index: int, video_time_s: float, world: np.ndarray) -> StreamFrame:
    image = np.full((33, 5), np.nan)
    image[:, 3] = 1.0
    pose = FramePose(image, world, True, False, 1.0, None)
    return StreamFrame(index, index / 10, pose, np.zeros((4, 4, 3), np.uint8), 0.0, video_time_s)


def test_watch_puts_a_variable_rate_file_on_the_grid_as_it_comes(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Frames at 0, 0.1, 0.15 and 0.4 s of a 10 fps file: the first two lie on the grid and
    pass as they are; 0.15 s strays (told once); 0.2 and 0.3 s lie 0.2 and 0.6 of the way
    from 0.15 to 0.4 s, and 0.4 s is the last frame itself."""
    worlds = [np.full((33, 3), v) for v in (0.0, 2.0, 4.0, 9.0)]
    worlds[2][5] = np.nan  # a joint not seen at 0.15 s
    grid = Regrid(10.0, "phone.mp4")
    taken = [grid.take(_frame(i, t, worlds[i])) for i, t in enumerate([0.0, 0.1, 0.15, 0.4])]
    assert [len(t) for t in taken] == [1, 1, 0, 3]
    pushed = [w for step in taken for w, _vis, _shown in step]
    assert [float(w[0, 0]) for w in pushed] == pytest.approx(
        [0.0, 2.0, 0.8 * 4.0 + 0.2 * 9.0, 0.4 * 4.0 + 0.6 * 9.0, 9.0], abs=1e-12
    )
    assert np.isnan(pushed[2][5]).all() and np.isnan(pushed[3][5]).all()
    assert np.isfinite(pushed[4][5]).all()
    assert [shown.index for step in taken for _w, _v, shown in step] == [0, 1, 2, 2, 3]
    err = capsys.readouterr().err.splitlines()
    assert err == [
        "note: phone.mp4: variable frame rate (frame 2 is at 0.150 s, not 0.200 s):"
        " poses resampled to 10 fps as they come"
    ]


def test_watch_paces_each_frame_by_its_own_time(tmp_path: Path) -> None:
    """``watch FILE`` holds each frame until its own presentation time over ``--speed``
    (:func:`due_s`), read from the frames as ``stream_poses`` hands them to its pacer, not
    at index / the declared 25 fps (a variable-rate file's gaps of 20 to 80 ms had all been
    played 40 ms apart). A frame with no time to trust is due at index / fps."""
    from features.pose_estimation import stream_poses
    from posecbr.commands.watch import due_s

    path = _write(tmp_path / "grey.mkv", PTS_MS, _grey(len(PTS_MS)))
    seen: list[tuple[int, float]] = []

    def pace(index: int, video_time_s: float) -> bool:
        seen.append((index, video_time_s))
        return True

    frames = list(stream_poses(path, smoothing=False, pace=pace))
    assert [f.index for f in frames] == list(range(len(PTS_MS)))
    assert [i for i, _t in seen] == list(range(len(PTS_MS)))
    assert [t for _i, t in seen] == pytest.approx([t / 1000 for t in PTS_MS], abs=1e-9)
    # by hand: at --speed 1 the times themselves; at --speed 2 half of them
    dues = [due_s(i, t, 25.0, 1.0) for i, t in seen]
    assert dues[:4] == pytest.approx([0.0, 0.02, 0.1, 0.18], abs=1e-9)
    assert due_s(2, 0.1, 25.0, 2.0) == pytest.approx(0.05)
    assert due_s(3, float("nan"), 25.0, 1.0) == pytest.approx(0.12)  # 3 / 25
    assert due_s(3, float("nan"), 25.0, 0.5) == pytest.approx(0.24)
    # a pacer that says stop ends the stream there, before the frame is read
    stop_at: list[int] = []

    def stop(index: int, video_time_s: float) -> bool:
        stop_at.append(index)
        return index < 4

    assert [f.index for f in stream_poses(path, smoothing=False, pace=stop)] == [0, 1, 2, 3]
    assert stop_at == [0, 1, 2, 3, 4]


def test_the_pacer_counts_each_due_time_from_the_first_frame() -> None:
    """The clock time a frame is held until: the first frame's arrival plus its due time.
    With ``stop`` set no wait is made (the watch is ending), and the pacer says stop."""
    from posecbr.commands.watch import Pacer

    pacer = Pacer(25.0, 2.0)
    pacer.stop.set()
    assert not pacer(0, 0.0)
    started = pacer.started
    assert started is not None and pacer.until == started
    assert not pacer(1, 0.02)
    assert pacer.until - started == pytest.approx(0.01)
    assert not pacer(2, float("nan"))
    assert pacer.until - started == pytest.approx(0.03)  # (0.02 + 1 / 25) / 2
    untimed = Pacer(25.0, 2.0)  # a file with no frame times: index / fps
    untimed.stop.set()
    untimed(0, float("nan"))
    untimed(2, float("nan"))
    assert untimed.started is not None
    assert untimed.until - untimed.started == pytest.approx(0.04)  # 2 / 25 / 2


def test_a_long_gap_in_a_paced_file_is_not_a_stall() -> None:
    """A variable-rate file may have a gap longer than ``--stall`` between two frames (a
    screen recording of nothing moving): waiting for the frame's time is not a stalled
    stream. Frames due 1.5 s apart, a stall of 1 s: all three come, no error (the reader
    had given up after the stall time whatever the wait was for). The stall leaves the
    reader thread a second to be scheduled after a frame is due: with 0.1 s (frames 0.3 s
    apart) it stalled by chance on a busy machine, 4 runs of 40 on one core at load 16."""
    from posecbr.commands.watch import Pacer, frames_in_background

    pacer = Pacer(10.0, 1.0)

    def frames() -> Iterator[int]:
        for i in range(3):
            if not pacer(i, 1.5 * i):
                return
            yield i

    assert list(frames_in_background(frames(), 1.0, pacer, "screen.mkv")) == [0, 1, 2]


def test_a_stream_that_stalls_after_its_due_time_is_still_a_stall() -> None:
    from posecbr.commands.watch import Pacer, frames_in_background

    pacer = Pacer(10.0, 1.0)

    def frames() -> Iterator[int]:
        pacer(0, 0.0)
        yield 0
        pacer(1, 0.05)
        time.sleep(1.0)  # due at 0.05 s, nothing for 1 s after it
        yield 1

    got = []
    with pytest.raises(DataError, match=r"screen.mkv: the stream stalled: no frame for 0.2 s"):
        for f in frames_in_background(frames(), 0.2, pacer, "screen.mkv"):
            got.append(f)
    assert got == [0]


def test_a_raw_stream_without_frame_times_is_read_at_its_declared_rate(
    people: list[np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A raw H.264 stream (an IP camera's or a dashcam's ``.h264``) carries no frame times:
    OpenCV gives 0 ms for every frame. That is no variable frame rate: the frames are taken
    at index / fps as a constant-rate video's, smoothed as one (frame 1 at 0 s, not after
    frame 0, had left the filters with no time step: every later frame passed through
    unsmoothed), and ``stream_poses`` gives them no time (``watch`` had called frame 1 off
    the grid and dropped every frame after the first)."""
    from features.pose_estimation import stream_poses

    path = _write(tmp_path / "camera.h264", [40 * k for k in range(len(PTS_MS))], people)
    assert [t for _rgb, t in iter_timed_frames(path)] == [0.0] * len(PTS_MS)
    vp = estimate_video(path, progress_bar=False)
    est = PoseEstimator()
    world = []
    for i, rgb in enumerate(iter_frames(path)):
        pose = est.process(rgb, i / 25.0)
        w = pose.world.copy()
        w[outside_frame(pose.image, rgb.shape[1], rgb.shape[0])] = np.nan
        world.append(w)
    assert not vp.resampled and vp.sequence.n_frames == len(PTS_MS)
    np.testing.assert_array_equal(vp.sequence.positions, np.array(world))
    streamed = list(stream_poses(path))
    assert [f.video_time_s == f.video_time_s for f in streamed] == [True] + [False] * (
        len(PTS_MS) - 1
    )  # frame 0 at 0 s, the others NaN: no time to trust
    np.testing.assert_array_equal([f.seen_world for f in streamed], np.array(world))
    assert "variable frame rate" not in capsys.readouterr().err


def _as_older(pose_file: Path, *drop: str) -> None:
    """Rewrite a pose file as older extraction code left it: without the metadata ``drop``
    (and, no longer resampled, without ``video_frames``); its ``extract_key`` as it was."""
    import dataclasses

    from features.poses import save_pose

    seq = load_pose(pose_file)
    image = load_pose_arrays(pose_file)["image_landmarks"]
    meta = {k: v for k, v in seq.metadata.items() if k not in drop}
    save_pose(
        dataclasses.replace(seq, metadata=meta), pose_file, extra_arrays={"image_landmarks": image}
    )


def test_a_pose_file_of_a_variable_rate_video_from_older_code_is_extracted_again(
    vfr_mkv: Path, people: list[np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A pose file of a variable-frame-rate video made before frame times were read (no
    ``extraction_version``, no ``variable_frame_rate``: its frames timed as evenly spaced),
    or made before extraction kept the frames before the first stray as they are (it has
    ``variable_frame_rate`` but no version), has its ``extract_key`` (same video, model,
    options) yet not today's poses: ``extract`` counted it up to date and kept it. It is now
    extracted again, said in the clip's line. A constant-rate video's pose file without the
    version stays up to date: its poses are what they were."""
    from posecbr.commands.extract import STALE_VFR

    out = tmp_path / "poses"
    pose_file = out / "lunge_vfr.npz"
    assert main(["extract", str(vfr_mkv), "--out", str(out)]) == 0
    assert load_pose(pose_file).metadata["extraction_version"] == EXTRACTION_VERSION
    for older in (("extraction_version", "variable_frame_rate"), ("extraction_version",)):
        _as_older(pose_file, *older)
        capsys.readouterr()
        assert main(["extract", str(vfr_mkv), "--out", str(out)]) == 0
        line = capsys.readouterr().out.strip()
        assert line.startswith(f"done: {pose_file}") and line.endswith(f"; {STALE_VFR})")
        seq = load_pose(pose_file)
        assert seq.metadata["extraction_version"] == EXTRACTION_VERSION and seq.n_frames == 16
        assert seq.metadata["variable_frame_rate"]["resampled_to_fps"] == 25.0
        assert main(["extract", str(vfr_mkv), "--out", str(out)]) == 0  # now up to date
        assert "up to date" in capsys.readouterr().out
    cfr = _write(tmp_path / "cfr.mkv", [40 * k for k in range(len(PTS_MS))], people)
    assert main(["extract", str(cfr), "--out", str(out)]) == 0
    _as_older(out / "cfr.npz", "extraction_version")
    capsys.readouterr()
    assert main(["extract", str(cfr), "--out", str(out)]) == 0
    assert capsys.readouterr().out.startswith(f"skipped: {out / 'cfr.npz'} (up to date)")


def test_extract_of_a_folder_notes_each_pose_file_extracted_again(
    vfr_mkv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import shutil

    from posecbr.commands.extract import STALE_VFR

    videos, out = tmp_path / "videos", tmp_path / "poses"
    (videos / "lunge").mkdir(parents=True)
    for name in ("a.mkv", "b.mkv"):
        shutil.copy(vfr_mkv, videos / "lunge" / name)
    capsys.readouterr()
    assert main(["extract", str(videos), "--out", str(out)]) == 0
    # a run of several clips prints no clip's line: each resampled one is told in a note
    # (hunt 39h: before, nothing said so)
    resampled = "variable frame rate: resampled to 25 fps"
    assert capsys.readouterr().err.splitlines() == [
        f"note: {out / 'lunge' / name}: {resampled}" for name in ("a.npz", "b.npz")
    ]
    _as_older(out / "lunge" / "a.npz", "extraction_version", "variable_frame_rate")
    assert main(["extract", str(videos), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    assert printed.err.splitlines() == [
        f"note: {out / 'lunge' / 'a.npz'}: {resampled}; {STALE_VFR}"
    ]
    assert printed.out.strip().endswith(f"1 extracted, 1 up to date, 0 failed -> {out}")


def test_segment_and_train_note_a_pose_file_of_older_vfr_extraction(
    vfr_mkv: Path, people: list[np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``segment``, ``classify`` and ``train`` read pose files through ``load_clip``: one made
    from a variable-frame-rate video by older extraction code is read (its poses are all
    there is) with one note saying ``extract`` makes it again; it was read in silence. A
    current file, and an older one of a constant-rate video, are read without a word."""
    from features.datasets import load_clip

    out = tmp_path / "poses"
    cfr = _write(tmp_path / "cfr.mkv", [40 * k for k in range(len(PTS_MS))], people)
    for video in (vfr_mkv, cfr):
        assert main(["extract", str(video), "--out", str(out)]) == 0
    capsys.readouterr()
    vfr_file, cfr_file = out / "lunge_vfr.npz", out / "cfr.npz"
    load_clip(vfr_file)
    load_clip(cfr_file)
    assert capsys.readouterr().err == ""
    note = (
        f"note: {vfr_file}: made from a variable-frame-rate video by an older posecbr (its"
        " frames timed differently): `posecbr extract` of the video makes it again"
    )
    for older in (("extraction_version", "variable_frame_rate"), ("extraction_version",)):
        _as_older(vfr_file, *older)
        assert load_clip(vfr_file).n_frames == 16
        assert capsys.readouterr().err.splitlines() == [note]
    _as_older(cfr_file, "extraction_version")
    load_clip(cfr_file)
    assert capsys.readouterr().err == ""


def test_an_older_pose_file_is_noted_from_any_folder_its_video_named_relative(
    vfr_mkv: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``extract videos/lunge_vfr.mkv --out poses`` run in a project's folder writes
    ``source_video`` as given, relative to that folder. A pose file of the oldest code (no
    version, nothing saying it was resampled) needs the video to be found older: read from
    the project's folder or from any other, it is noted the same. From another folder the
    video was looked up there and not found, and the file was read in silence."""
    import shutil

    from features.datasets import load_clip

    project = tmp_path / "project"
    (project / "videos").mkdir(parents=True)
    shutil.copy(vfr_mkv, project / "videos" / "lunge_vfr.mkv")
    monkeypatch.chdir(project)
    assert main(["extract", "videos/lunge_vfr.mkv", "--out", "poses"]) == 0
    pose_file = project / "poses" / "lunge_vfr.npz"
    assert load_pose(pose_file).metadata["source_video"] == "videos/lunge_vfr.mkv"
    _as_older(pose_file, "extraction_version", "variable_frame_rate")
    capsys.readouterr()
    note = (
        f"note: {pose_file}: made from a variable-frame-rate video by an older posecbr (its"
        " frames timed differently): `posecbr extract` of the video makes it again"
    )
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    for folder in (project, elsewhere, project / "poses"):
        monkeypatch.chdir(folder)
        assert load_clip(pose_file).n_frames == 16  # its poses, read as they are
        assert capsys.readouterr().err.splitlines() == [note], folder


def _browser_webm(path: Path, pts_ms: list[int], frames: list[np.ndarray]) -> Path:
    """A WebM as a browser's MediaRecorder writes it: VP8 on a millisecond clock, no frame
    rate stated (FFmpeg, and so OpenCV, then guesses 1000 fps from the clock)."""
    return _write(path, pts_ms, frames, rate=None, codec="libvpx")


# a browser's frame times: 28 to 39 ms apart (about 30 fps), on no regular pattern
BROWSER_GAPS_MS = [33, 34, 37, 39, 28, 29, 37, 39, 30, 31, 38, 33, 31, 37, 31, 32, 35, 34, 29,
                   28, 38, 37, 38, 34, 37, 31, 33, 37, 29, 31, 29, 33, 39, 29, 32, 32, 38, 30,
                   34]  # fmt: skip


def test_a_webm_that_states_no_frame_rate_is_taken_at_its_frames_rate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A browser's recording states no frame rate: for 40 frames 28 to 39 ms apart, OpenCV
    gives 1000 fps (FFmpeg's guess: the millisecond clock). They were resampled to 1000 fps:
    1307 pose frames for 40 decoded, each movement spread over 33 times as many frames. They
    are now taken at their own average rate, 39 intervals in 1.306 s (29.862 fps), and,
    irregular at that rate, resampled to it: 40 frames again (k / rate up to 1.306 s)."""
    import cv2

    from features.pose_estimation import open_video

    pts = [sum(BROWSER_GAPS_MS[:k]) for k in range(40)]
    assert pts[-1] == 1306
    path = _browser_webm(
        tmp_path / "recording.webm", pts, [np.full((48, 64, 3), 6 * k, np.uint8) for k in range(40)]
    )
    cap = cv2.VideoCapture(str(path))
    assert cap.get(cv2.CAP_PROP_FPS) == 1000.0  # what OpenCV states
    cap.release()
    cap, info = open_video(path)
    cap.release()
    assert info.fps == pytest.approx(39 / 1.306, rel=1e-12) and info.frames == 40
    vp = estimate_video(path, smoothing=False, progress_bar=False, announce=False)
    assert vp.sequence.fps == info.fps and vp.sequence.n_frames == 40
    assert vp.sequence.metadata["variable_frame_rate"]["decoded_frames"] == 40
    out = tmp_path / "poses"
    capsys.readouterr()
    assert main(["extract", str(path), "--out", str(out)]) == 0
    assert capsys.readouterr().out == (
        f"done: {out / 'recording.npz'} (40 frames, 40 without a person; variable frame rate:"
        " resampled to 29.8622 fps)\n"
    )


def test_the_frame_clock_trusts_times_until_they_fail_on_the_grid() -> None:
    """By hand, at 10 fps: times that fail (repeat) while the frames lie on the grid are no
    times at all (a raw stream's zeros): NaN from there on, even if later ones increase.
    Once the frames have strayed, a repeated time is that frame's alone (NaN), the next
    frame's is its own."""
    from features.pose_estimation.video import FrameClock

    raw = FrameClock(10.0)
    got = [raw.take(i, t) for i, t in enumerate([0.0, 0.0, 0.2, 0.3])]
    assert got[0] == 0.0 and np.isnan(got[1:]).all() and raw.on_grid
    assert raw.filter_time(2, got[2]) == pytest.approx(0.2)  # index / fps
    vfr = FrameClock(10.0)
    got = [vfr.take(i, t) for i, t in enumerate([1.0, 1.1, 1.25, 1.25, 1.4])]
    assert got[:3] == pytest.approx([0.0, 0.1, 0.25]) and np.isnan(got[3])
    assert got[4] == pytest.approx(0.4) and not vfr.on_grid
    assert vfr.filter_time(2, got[2]) == pytest.approx(0.25)  # its own time, off the grid
    assert np.isnan(vfr.filter_time(3, got[3]))  # left out: not smoothed, filters untouched


def test_a_frame_without_a_time_among_timed_ones_is_paced_after_the_last() -> None:
    """At 10 fps a frame at 0.25 s, then one with no time: due 0.35 s (a frame interval
    after the last timed frame), not 0.2 s (index / fps, behind the frames' own clock)."""
    from posecbr.commands.watch import Pacer

    pacer = Pacer(10.0, 1.0)
    pacer.stop.set()
    for i, t in enumerate([0.0, 0.25, float("nan")]):
        pacer(i, t)
    assert pacer.started is not None
    assert pacer.until - pacer.started == pytest.approx(0.35)


def test_a_video_declaring_a_faster_rate_than_its_frames_is_stale_as_extract_resamples_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A video declaring 60 fps whose 25 frames come every 40 ms (25 fps): 60 is not above
    ``SUSPECT_FPS``, so ``open_video`` keeps it, frame 1 at 0.04 s lies 2.4 frames from 1/60
    s, and ``estimate_video`` resamples the frames to 60 fps. The check for a pose file of
    older code took the frames' own rate instead (60 is more than twice 25) and found them
    regular at it: ``extract`` kept a pose file the oldest code made of evenly spaced frames,
    and ``load_clip`` said nothing. Both now take the rate ``open_video`` takes."""
    from features.pose_estimation import open_video
    from features.pose_estimation.video import (
        container_frame_times,
        older_vfr_extraction,
        variable_rate,
    )
    from posecbr.commands.extract import STALE_VFR

    path = _write(tmp_path / "d60.mkv", [40 * k for k in range(25)], _grey(25), rate=60)
    cap, info = open_video(path)
    cap.release()
    assert info.fps == 60.0
    times, fps = container_frame_times(path)
    assert fps == 60.0 and times == pytest.approx([0.04 * k for k in range(25)], abs=1e-9)
    assert variable_rate(path) and older_vfr_extraction({}, path)
    out = tmp_path / "poses"
    assert main(["extract", str(path), "--out", str(out)]) == 0
    pose_file = out / "d60.npz"
    assert load_pose(pose_file).metadata["variable_frame_rate"]["resampled_to_fps"] == 60.0
    _as_older(pose_file, "extraction_version", "variable_frame_rate")
    capsys.readouterr()
    assert main(["extract", str(path), "--out", str(out)]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"done: {pose_file}") and line.endswith(f"; {STALE_VFR})")


def test_a_pose_file_of_a_newer_extraction_is_not_called_older(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A pose file a newer posecbr wrote (``extraction_version`` 3) of a variable-frame-rate
    video was taken as older code's: ``load_clip`` said "made ... by an older posecbr" and
    ``extract`` would make it again with today's, older, code. Only a version below today's
    (or none) is older."""
    from features.datasets import load_clip
    from features.pose_estimation.video import older_vfr_extraction
    from features.poses import PoseSequence, save_pose
    from features.skeleton import BLAZEPOSE_33

    meta = {"pose_model": "blazepose", "variable_frame_rate": {"resampled_to_fps": 25.0}}
    newer = {**meta, "extraction_version": EXTRACTION_VERSION + 1}
    assert older_vfr_extraction({**meta, "extraction_version": 2}, "x")
    assert older_vfr_extraction(meta, "x")
    assert not older_vfr_extraction(newer, "x")
    pose_file = tmp_path / "newer.npz"
    positions = np.zeros((3, 33, 3))
    save_pose(PoseSequence(positions, BLAZEPOSE_33, 25.0, metadata=newer), pose_file)
    capsys.readouterr()
    assert load_clip(pose_file).n_frames == 3
    assert capsys.readouterr().err == ""
