"""Hunt 37c: a single frame stamped far ahead lost the frame after it too.

A variable-rate video with one frame stamped far ahead of the frames either side (0.9 s
between 0.38 and 0.4 s) had that frame taken, the next frame left out as the place the
clock went back, and the frames after it timed on from the stamp ahead (0.44 s became
0.98 s). Now the frame stamped ahead alone is left out and the others keep their own times;
on a constant-rate file it is timed by its place and nothing is left out. ``extract``
(FrameClock over the whole file, then resample_timed) and ``watch`` (FrameClock as the
frames come, then Regrid) alike.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.test_video_vfr import people  # noqa: F401 (a fixture)

AHEAD = [0.0, 0.02, 0.1, 0.18, 0.9, 0.4, 0.44, 0.52]  # 25 fps, strayed at 0.02 s


def stamped_video(
    folder: Path, name: str, pts_ms: list[int], frames: list[np.ndarray]
) -> tuple[Path, list[tuple[np.ndarray, float]], Any]:
    """The lunge ``frames`` written losslessly at ``pts_ms`` (their times checked as decoded)
    and extracted (no smoothing, no tracking): the video, its decoded frames and times, and
    the extraction."""
    pytest.importorskip("av", reason="PyAV writes the video")
    from features.pose_estimation import estimate_video
    from features.pose_estimation.video import iter_timed_frames
    from tests.test_hunt36c import _write_out_of_order

    path = _write_out_of_order(folder / name, pts_ms, frames)
    decoded = list(iter_timed_frames(path))
    assert [round(t * 1000) for _rgb, t in decoded] == pts_ms
    return path, decoded, estimate_video(path, smoothing=False, tracking=False, progress_bar=False)


def watched(path: Path, extracted: Any) -> list[Any]:
    """``watch``'s frames of ``path`` (stream_poses, no smoothing, no tracking), the rows
    Regrid pushes of them checked equal to ``extracted``'s rows."""
    from features.pose_estimation import PoseEstimator, stream_poses
    from posecbr.commands.watch import Regrid

    live = Regrid(25.0, str(path))
    frames = list(stream_poses(path, estimator=PoseEstimator(smoothing=False, tracking=False)))
    pushed = [w for f in frames for w, _v, _s in live.take(f)]
    np.testing.assert_array_equal(np.array(pushed), extracted.sequence.positions)
    return frames


def test_a_frame_stamped_far_ahead_is_left_out_and_the_next_kept() -> None:
    """0.9 s lies 0.72 s after 0.18 s (more than a bridged gap, 0.25 s) and the next frame,
    0.4 s, between the two: frame 4 alone is left out; 0.4, 0.44 and 0.52 s keep their
    times. Before: 0.9 s kept, 0.4 s left out, 0.44 s at 0.98 s."""
    from features.pose_estimation.video import FrameClock, clocked_times

    elapsed, strayed = clocked_times(AHEAD, 25.0)
    assert strayed
    np.testing.assert_allclose(elapsed, [0, 0.02, 0.1, 0.18, np.nan, 0.4, 0.44, 0.52], atol=1e-9)
    clock = FrameClock(25.0)
    after = [*AHEAD[1:], float("nan")]
    for i, t in enumerate(AHEAD):
        clock.take(i, t, after[i] if clock.needs_next(i, t) else float("nan"))
    assert clock.ahead == [(4, 0.18, 0.9, 0.4)]
    assert clock.went_back == []


@pytest.mark.parametrize(
    ("times", "want", "strays"),
    [
        # a constant-rate file with one stamp 5 s ahead: timed by its place (0.12 s), the
        # file still on the grid (before: strayed, 0.16 s left out, 0.2 s at 5.04 s)
        ([0.0, 0.04, 0.08, 5.0, 0.16, 0.2], [0.0, 0.04, 0.08, 0.12, 0.16, 0.2], False),
        # a gap (the next frame runs on from the one after it): all kept, as before
        ([0.0, 0.02, 0.1, 0.18, 5.0, 5.04], [0.0, 0.02, 0.1, 0.18, 5.0, 5.04], True),
        # the last frame far ahead: nothing after it to tell, kept (a gap)
        ([0.0, 0.02, 0.1, 0.18, 5.0], [0.0, 0.02, 0.1, 0.18, 5.0], True),
        # ahead by less than a bridged gap (0.18 -> 0.4 s): a few frames out of order, the
        # one going back left out, as before
        ([0.0, 0.02, 0.1, 0.18, 0.4, 0.36, 0.42], [0.0, 0.02, 0.1, 0.18, 0.4, np.nan, 0.42], True),
        # the next frame earlier than the last one taken: the clock went back (0.9 s kept,
        # 0.1 s left out, 0.14 s one interval on from its place), as before
        ([0.0, 0.02, 0.1, 0.18, 0.9, 0.1, 0.14], [0.0, 0.02, 0.1, 0.18, 0.9, np.nan, 0.98], True),
    ],
)
def test_only_a_frame_between_neighbours_is_taken_for_stamped_ahead(
    times: list[float], want: list[float], strays: bool
) -> None:
    from features.pose_estimation.video import clocked_times

    elapsed, strayed = clocked_times(times, 25.0)
    assert strayed is strays
    np.testing.assert_allclose(elapsed, want, atol=1e-9)


def test_watch_puts_the_same_rows_on_the_grid_as_extract() -> None:
    """The values are the frames' own times (the one stamped ahead -1): every row 0 to
    0.52 s holds its own time (0.18 to 0.4 s bridged), the last shows frame 7 (0.52 s).
    Before: rows 5 to 22 (0.2 to 0.88 s) a gap, missing, and 27 rows."""
    from features.pose_estimation.video import FrameClock, clocked_times, resample_timed
    from posecbr.commands.watch import Regrid
    from tests.test_video_vfr import _frame

    values = np.array([0.0, 0.02, 0.1, 0.18, -1.0, 0.4, 0.44, 0.52])
    elapsed, _ = clocked_times(AHEAD, 25.0)
    grid, shown = resample_timed(elapsed, values, 25.0)
    np.testing.assert_allclose(grid, np.arange(14) / 25.0, atol=1e-9)
    assert shown[-1] == 7
    live, clock = Regrid(25.0, "phone.mkv"), FrameClock(25.0)
    worlds = [np.full((33, 3), v) for v in values]
    after = [*AHEAD[1:], float("nan")]
    steps = []
    for i, t in enumerate(AHEAD):  # as stream_poses: the next time read only when wanted
        nxt = after[i] if clock.needs_next(i, t) else float("nan")
        steps.append(live.take(_frame(i, clock.take(i, t, nxt), worlds[i])))
    pushed = np.array([float(w[0, 0]) for step in steps for w, _vis, _shown in step])
    np.testing.assert_allclose(pushed, grid, atol=1e-12)


def test_a_video_with_a_frame_stamped_far_ahead_loses_that_frame_alone(
    people: list[np.ndarray],  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The 13 variable-rate lunge frames (lossless), the ninth stamped 0.9 s where 0.38 s and
    0.4 s lie either side of it: frame 8 is left out, the others keep their times: 14 rows
    at 25 fps (0 to 0.52 s), the last frame 11's pose (0.52 s; frame 12 at 0.54 s lies
    after the last row). Before: frame 9 (0.4 s) left out, the three after it at 0.98, 1.06
    and 1.08 s: 28 rows. ``watch`` pushes the same rows and says the same note once."""
    from features.pose_estimation import PoseEstimator

    pts_ms = [0, 20, 100, 180, 220, 260, 300, 380, 900, 400, 440, 520, 540]
    path, decoded, got = stamped_video(tmp_path, "ahead.mkv", pts_ms, people)
    assert got.sequence.n_frames == 14
    assert got.video_frames is not None
    assert got.video_frames.tolist()[-1] == 11 and 8 not in got.video_frames.tolist()
    raw = PoseEstimator(smoothing=False, tracking=False).process(decoded[11][0])
    assert raw.person
    np.testing.assert_allclose(got.image_landmarks[-1], raw.image, atol=1e-6)
    vfr = got.sequence.metadata["variable_frame_rate"]
    assert vfr["frames_left_out"]["frames"] == [8]
    assert vfr["stamped_ahead"]["frames"] == [8]
    assert "clock_went_back" not in vfr
    note = (
        f"note: {path}: frame 8 is stamped 0.900 s, far ahead of the frames either side"
        " (0.380 and 0.400 s): frame 8 left out, the frames after it keep their times"
    )
    assert note in capsys.readouterr().err.splitlines()
    frames = watched(path, got)
    assert [f.index for f in frames] == list(range(13))  # every frame read, in order
    assert capsys.readouterr().err.count(note) == 1


def test_a_constant_rate_video_with_one_frame_stamped_far_ahead_loses_nothing(
    people: list[np.ndarray],  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The 13 lunge frames 40 ms apart (25 fps), the sixth stamped 5 s: it is timed by its
    place (0.2 s) and the file stays constant-rate: 13 poses, each frame's own, no
    resampling. Before: resampled, frame 6 (0.24 s) left out and the later ones timed on
    from 5 s: 133 rows, 120 of them (0.2 to 4.96 s) a gap."""
    pytest.importorskip("av", reason="PyAV writes the video")
    from features.pose_estimation import PoseEstimator, estimate_video
    from features.pose_estimation.video import iter_timed_frames
    from tests.test_hunt36c import _write_out_of_order

    pts_ms = [40 * k for k in range(13)]
    pts_ms[5] = 5000
    path = _write_out_of_order(tmp_path / "one_ahead.mkv", pts_ms, people)
    got = estimate_video(path, smoothing=False, tracking=False, progress_bar=False)
    assert got.sequence.n_frames == 13
    assert got.video_frames is None
    assert "variable_frame_rate" not in got.sequence.metadata
    decoded = [rgb for rgb, _t in iter_timed_frames(path)]
    raw = PoseEstimator(smoothing=False, tracking=False).process(decoded[5])
    np.testing.assert_allclose(got.image_landmarks[5], raw.image, atol=1e-6)
    note = (
        f"note: {path}: frame 5 is stamped 5.000 s, far ahead of the frames either side"
        " (0.160 and 0.240 s): frame 5 timed by its place, the frames after it keep their"
        " times"
    )
    assert note in capsys.readouterr().err.splitlines()
    frames = watched(path, got)
    assert [f.video_time_s for f in frames] == pytest.approx([k / 25 for k in range(13)])
    assert capsys.readouterr().err.count(note) == 1
