"""Hunt 50a: ``watch`` of a live source whose frame rate rises, and whose frames come in
bursts (:class:`posecbr.commands.watch.Regrid`).

- A live source whose rate rose for good (15 to 30 fps: the light coming back, a stream that
  starts slow) had its change taken some 0.9 s late, its frames meanwhile one to a grid time
  at the old rate: the grid ran that far ahead of the wall clock and stayed so, every segment
  after it timed late. The lead is now made up over four times its length
  (``CATCH_UP``), no frame left out, and said in the change's note.
- Once a live source is put on the grid by the wall clock, its frames lay at the times they
  came: a burst (frames held up on the way and read at once: a network's jitter) fell on
  one grid time, all but its last frame lost, and the pause before it was a stall. Its
  frames are now placed a frame interval apart by their count, anchored to the clock
  (``Regrid._placed``); a stall is still left missing.
- A rate that fell straight into bursts was never taken as a change: the rate over the
  latest half second left each burst's pause out as a stall. The pauses up to half a second
  are now counted with their frames (``_frame_rate``'s ``longest_s``).
"""

from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np
import pytest

from posecbr.commands.watch import Regrid
from tests.test_hunt49e import _frame


def _taken(grid: Regrid, frames: list[SimpleNamespace]) -> tuple[np.ndarray, list[int]]:
    """The grid's poses (one coordinate each) and, per grid time, which frame was on screen."""
    values: list[float] = []
    shown: list[int] = []
    for frame in frames:
        for world, _vis, on_screen in grid.take(frame):
            values.append(float(world[0, 0]))
            shown.append(on_screen.index)
    return np.array(values), shown


def test_a_stream_whose_rate_rises_is_followed_by_the_wall_clock(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A stream at 15 fps (each interval off by up to 20 %, at random) for 5 s, then at
    30 fps for 10 s, every frame's pose its wall-clock time: the frames before the rise
    are passed one to a grid time, as they come. The rise is taken some 0.9 s after it (the
    rate over the latest half second off by a fifth 0.1 s after, then held 0.8 s): those
    0.9 s of frames, one to a 1/15-s grid time, ran 0.9 s ahead of the clock, said in the
    note, and made up over four times that. From then on each grid time's pose is the wall
    clock's time of that grid time (the last frame before the rise on its grid time: within
    a grid frame, the jitter of the frames before the rise), the grid ending within a grid
    frame of the last frame; no grid time missing, none given twice (the poses only move
    on). Before, every grid time after the rise lay 0.9-1.0 s late and the grid ended 1 s
    after the stream did."""
    rng = np.random.default_rng(50)
    times = [0.0]
    while times[-1] < 5.0 - 1.0 / 15.0:
        times.append(times[-1] + rng.uniform(0.8, 1.2) / 15.0)
    rose = len(times)
    times += [times[-1] + (j + 1) / 30.0 for j in range(300)]
    grid = Regrid(15.0, "0")
    values, _shown = _taken(grid, [_frame(i, t, t) for i, t in enumerate(times)])
    np.testing.assert_array_equal(values[:rose], times[:rose])  # one a frame, as it came
    assert not np.isnan(values).any()
    assert (np.diff(values) > 0).all()
    on_time = times[rose - 1] - (rose - 1) / 15.0  # the wall clock's time of grid time 0
    assert times[-1] - 1.0 / 15.0 < on_time + (len(values) - 1) / 15.0 <= times[-1]
    made_up = np.arange(len(values)) >= len(values) - 45  # the last 3 s
    late = values[made_up] - (on_time + np.flatnonzero(made_up) / 15.0)
    np.testing.assert_allclose(late, 0.0, atol=1.0 / 15.0)
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "note: 0: the frame rate changed from 15 to 30 fps" in err
    ahead = re.search(r"\(the grid (\d\.\d\d) s ahead of the clock, made up over the next", err)
    assert ahead is not None
    assert 0.7 <= float(ahead.group(1)) <= 1.1


def test_frames_that_come_in_bursts_keep_their_poses_and_a_stall_is_left_missing(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera at 30 fps for 3 s, then at 15 fps (taken as a change: the grid then follows
    the wall clock), whose frames from 6 s to 12 s come in bursts of five, each burst read at
    once when its last frame was taken (the average rate unchanged), then stall for 1 s
    (none taken from 12 to 13 s) and come on time again, every frame's pose the time it
    was taken. Every frame of the bursts is on screen at some grid time (none lost), each
    grid time's pose from 6.5 s to 12 s is the camera's at that grid time's wall-clock time
    (the frames taken 1/15 s apart, placed so), and the stall's grid times, strictly
    between the frames either side of it, are left missing, said once. Before, each burst's
    frames fell on one grid time, 66 of its 82 frames after 6.5 s lost, and the pause
    before each burst was left missing as a stall."""
    taken = [j / 30.0 for j in range(90)] + [3.0 + j / 15.0 for j in range(135)]
    taken += [13.0 + j / 15.0 for j in range(30)]
    came = list(taken)
    bursts = [i for i, t in enumerate(taken) if 6.0 <= t < 12.0]
    for start in range(bursts[0], bursts[-1] + 1, 5):
        came[start : start + 5] = [taken[start + 4]] * 5
    grid = Regrid(30.0, "0")
    frames = [_frame(i, c, t) for i, (c, t) in enumerate(zip(came, taken, strict=True))]
    values, shown = _taken(grid, frames)
    kept = [i for i in bursts if taken[i] >= 6.5 and i in shown]
    assert kept == [i for i in bursts if taken[i] >= 6.5]  # 82 frames
    steady = (np.arange(len(values)) >= 6.5 * 30) & (np.arange(len(values)) <= 11.9 * 30)
    np.testing.assert_allclose(values[steady], np.flatnonzero(steady) / 30.0, atol=1e-9)
    before, after = taken[bursts[-1]], 13.0
    between = (np.arange(len(values)) / 30.0 > before + 1e-9) & (
        np.arange(len(values)) / 30.0 < after - 1e-9
    )
    assert np.isnan(values[between]).all()
    assert not np.isnan(values[~between][-60:]).any()
    assert between.sum() == 31  # 11.933 to 13.0 s: grid times 359-389
    err = capsys.readouterr().err
    assert err.count("the stream stalled") == 1


def test_a_rate_that_falls_into_bursts_is_followed_by_the_clock(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera at 30 fps for 3 s, then at 15 fps with its frames coming in bursts of five
    from the fall on (each burst read at once when its last frame was taken), every frame's
    pose the time it was taken: from its first burst (a 0.30-s pause, then five frames at
    once) the source is put on the grid by the wall clock (hunt 50m: a pause shorter than
    ``BURST_S``; hunt 50a took the fall as a change of rate over the latest half second,
    some 1.1 s after it, the pauses before left missing as stalls), said once, no grid time
    missing; from 5 s on every frame is on screen at some grid time and each grid time's
    pose is the camera's at its wall-clock time. Before hunt 50a, each burst's pause was left
    out of the rate as a stall and the rest spanned too little to measure: the change was
    never taken, and every pause to the end was a stall, 27 of them said, a third of the
    grid times missing."""
    taken = [j / 30.0 for j in range(90)] + [3.0 + j / 15.0 for j in range(135)]
    came = list(taken)
    for start in range(90, len(taken), 5):
        came[start : start + 5] = [taken[start + 4]] * 5
    grid = Regrid(30.0, "0")
    frames = [_frame(i, c, t) for i, (c, t) in enumerate(zip(came, taken, strict=True))]
    values, shown = _taken(grid, frames)
    late = [i for i, t in enumerate(taken) if t >= 5.0]
    assert [i for i in late[:-1] if i in shown] == late[:-1]  # the last: no grid time after
    on = np.arange(len(values)) >= 5.0 * 30
    np.testing.assert_allclose(values[on], np.flatnonzero(on) / 30.0, atol=1e-9)
    assert not np.isnan(values).any()
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "0.30 s without frames at 3.0 s, then frames at once" in err
