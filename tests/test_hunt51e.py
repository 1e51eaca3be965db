"""Hunt 51e: ``watch`` of a live source whose frames stop for a quarter to half a second and
resume on time (a drop-out: the camera's frames of the pause lost, not held up), and of one
whose rate rises after a burst put it on the grid by the wall clock
(:class:`posecbr.commands.watch.Regrid`).

- Since hunt 50m every such pause was taken as a burst's (frames held up on the way, then
  read at once): the frames after a drop-out were placed a frame interval apart by their
  count, each as early as the pause was long, until the lag was made up half a second later
  and the pause's grid times left missing there. The frame after the pause is now held until
  the next one comes: at once (a burst) or about a frame interval later (a drop-out, whose
  frames lie at the times they came and whose pause is left missing as a stall's).
- A rise of rate (a stream that starts slow) after a burst had put the source on the grid
  by the wall clock was followed on the first rate's grid for good: it is now taken, as
  before a burst, for the grid to be made again at the new rate.
"""

from __future__ import annotations

import argparse
import threading
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from features.errors import DataError
from posecbr.commands.watch import Regrid, Watcher
from tests.test_hunt49e import _frame
from tests.test_hunt50a import _taken


def _lost(fps: float, *pauses: tuple[float, float]) -> np.ndarray:
    """The frames of a ``fps`` camera (frame i taken at i / fps) taken strictly inside each
    pause (from, to) (s): lost."""
    i = np.arange(round(10 * fps))
    out = np.zeros(len(i), dtype=bool)
    for a, b in pauses:
        out |= (i > round(a * fps)) & (i < round(b * fps))
    return out


@pytest.mark.parametrize("fps", [30.0, 15.0])
def test_drop_outs_at_the_rate_begun_with_are_left_missing_where_they_were(
    fps: float, capsys: pytest.CaptureFixture[str]
) -> None:
    """A camera at ``fps`` for 10 s whose frames taken within 3.0-3.4 s and 6.0-6.33 s are
    lost (pauses of 0.40 and 0.33 s, longer than the quarter second bridged, shorter than
    ``BURST_S``), every other frame read when it was taken, its pose that time: grid time k
    (one to a frame, as a steady source's) has the pose of k / fps, the grid times strictly
    inside each pause are missing (the lost frames' own), the grid ending on the last frame,
    and each pause is said as a stall, neither as a burst. A burst read no faster than the
    pose model takes a frame is still a burst. Before, the first pause was taken
    as a burst's: every frame after it placed one grid time after the one before, 0.37 or
    0.40 s early, until half a second later the lag was made up (the grid times missing
    there)."""
    lost = _lost(fps, (3.0, 3.4), (6.0, 19.0 / 3.0))
    taken = np.arange(len(lost)) / fps
    kept = np.flatnonzero(~lost)
    values, _shown = _taken(
        Regrid(fps, "0"), [_frame(j, taken[i], taken[i]) for j, i in enumerate(kept)]
    )
    assert len(values) == len(lost)
    np.testing.assert_array_equal(np.isnan(values), lost)
    np.testing.assert_allclose(values[~lost], taken[~lost], atol=1e-9)
    err = capsys.readouterr().err
    assert err.count("the stream stalled") == 2
    assert "at once" not in err
    # the same camera with none lost, its frames taken within 3.0-3.3 s read only from 3.3 s
    # on, as fast as a busy reader takes them (0.6 of a frame interval apart: the pose
    # model's time), and those after as soon as the reader is free: a burst, the grid ending
    # on the last frame's grid time (a drop-out's stall would leave it 0.3 s late, the frames
    # then one to a grid time)
    came = taken.copy()
    for i in range(round(3.0 * fps), len(came)):
        came[i] = max(taken[i], 3.3, came[i - 1] + 0.6 / fps)
    frames = [_frame(i, c, t) for i, (c, t) in enumerate(zip(came, taken, strict=True))]
    values, _shown = _taken(Regrid(fps, "0"), frames)
    assert len(values) == len(lost)
    err = capsys.readouterr().err
    assert err.count("then frames at once") == 1


@pytest.mark.parametrize("fps", [30.0, 15.0])
def test_a_burst_read_at_the_readers_pace_is_not_taken_for_a_stall(
    fps: float, capsys: pytest.CaptureFixture[str]
) -> None:
    """A camera at ``fps`` whose frames taken from 3.0 s are read only from 3.4 s on (a
    0.43-s pause at 30 fps, 0.47 s at 15), each as soon as the reader is free again, 0.6 of
    a frame interval after the one before (the pose model's time on a busy machine), until
    it has caught up with the camera (taken = read) and reads each when taken: a burst, every
    frame kept on the grid, none missing, the grid ending on the last frame's grid time, no
    stall said. Before, once the frames before the pause had left the latest half second,
    the burst's frames, all still late, were taken for a lag of the stream's, a stall: the
    grid times up to the frame in hand left missing (11 at 30 fps, 6 at 15)."""
    taken = np.arange(round(10 * fps)) / fps
    came = taken.copy()
    for i in range(round(3.0 * fps), len(came)):
        came[i] = max(taken[i], 3.4, came[i - 1] + 0.6 / fps)
    frames = [_frame(i, c, t) for i, (c, t) in enumerate(zip(came, taken, strict=True))]
    values, _shown = _taken(Regrid(fps, "0"), frames)
    assert len(values) == len(taken)
    assert not np.isnan(values).any()
    err = capsys.readouterr().err
    assert err.count("then frames at once") == 1 and "stalled" not in err


def test_drop_outs_among_bursts_on_the_clock_are_left_missing_where_they_were(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera at 30 fps for 10 s whose frames from 3 s to 6 s and from 8 s come in bursts of
    eight, each read at once when its last frame was taken (0.27-s pauses: on the grid by
    the wall clock from the first), whose frames taken within 7.0-7.4 s are lost (a drop-out,
    the frames either side read when taken), and whose last burst, of the frames 8.8-9.03 s,
    is read at once only at 9.2 s, the frames taken within 9.03-9.4 s lost (a drop-out right
    after the burst: the frame after it, at 9.4 s, comes 0.2 s after the burst but 0.37 s
    after the burst's last frame's place). Grid time k has the pose of k / 30 s (each frame
    on the grid time it was taken at), the grid times strictly inside each drop-out missing,
    every frame sent on screen at some grid time. Before, the frames after each drop-out
    were placed by their count, 0.40 and 0.37 s early, until half a second later."""
    fps = 30.0
    lost = _lost(fps, (7.0, 7.4), (271 / fps, 9.4))
    taken = np.arange(len(lost)) / fps
    came = taken.copy()
    for start in [*range(90, 180, 8), *range(240, 272, 8)]:
        group = slice(start, min(start + 8, 180 if start < 180 else 272))
        came[group] = taken[group][-1]
    came[264:272] = 9.2
    kept = np.flatnonzero(~lost)
    frames = [_frame(j, came[i], taken[i]) for j, i in enumerate(kept)]
    values, shown = _taken(Regrid(fps, "0"), frames)
    assert len(values) == len(lost)
    np.testing.assert_array_equal(np.isnan(values), lost)
    np.testing.assert_allclose(values[~lost], taken[~lost], atol=1e-9)
    assert sorted(set(shown)) == list(range(len(kept)))
    err = capsys.readouterr().err
    assert err.count("then frames at once") == 1  # said once, when the grid takes the clock
    assert err.count("the stream stalled") == 2


def test_bursts_soon_after_a_drop_out_keep_their_frames_on_the_clock() -> None:
    """A camera at 30 fps whose frames taken within 3.0-3.4 s are lost (a drop-out at the
    rate begun with: left missing as a stall) and whose frames from 3.6 s come in bursts of
    eight, each read at once when its last frame was taken: grid time k has the pose of
    k / 30 s, the drop-out's 11 grid times missing. The burst's frames are placed by their
    count at the frame interval measured over the latest two seconds, the frames counted as
    the camera took them, the drop-out's lost ones too: counted as sent, that interval came
    out too long by the share of the frames counted that were lost (11 in some 50), and the
    bursts' frames were up to 0.08 s off."""
    fps = 30.0
    lost = _lost(fps, (3.0, 3.4))
    taken = np.arange(len(lost)) / fps
    came = taken.copy()
    for start in range(108, len(lost), 8):
        came[start : start + 8] = taken[min(start + 8, len(lost)) - 1]
    kept = np.flatnonzero(~lost)
    values, _shown = _taken(
        Regrid(fps, "0"), [_frame(j, came[i], taken[i]) for j, i in enumerate(kept)]
    )
    assert len(values) == len(lost)
    np.testing.assert_array_equal(np.isnan(values), lost)
    np.testing.assert_allclose(values[~lost], taken[~lost], atol=1e-9)


def _rise_taken(burst: bool) -> tuple[float | None, list[Any]]:
    """When (by the wall clock) the rise of the camera of the test below, with its burst or
    without, is taken (None: never), and what is given for that frame."""
    taken = np.concatenate([np.arange(30) / 15.0, 2.0 + np.arange(90) / 30.0])
    came = taken.copy()
    if burst:
        came[15:20] = taken[19]
    grid = Regrid(15.0, "0")
    grid.remakable = True
    for i, (c, t) in enumerate(zip(came, taken, strict=True)):
        given = grid.take(_frame(i, c, t))
        if grid.rose is not None:
            assert grid.rose == pytest.approx(30.0, rel=1e-6)
            return float(c), given
    return None, []


def test_a_rise_after_a_burst_is_taken_to_make_the_grid_again(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera at 15 fps for 2 s, whose frames taken at 1.0-1.27 s come in a burst read at
    once at 1.27 s (a 0.33-s pause: on the grid by the wall clock from there), then at 30 fps,
    every frame read when taken, watched on a grid that may be made again at a rate that
    rises (a stream's first seconds): the rise is taken as without the burst, once the rate
    over the latest half second (its frames, and the one before them) has been more than a
    fifth above 15 fps for 0.8 s: at 2.10 s it is 9 intervals over 0.50 s (18 fps, not
    above), at 2.13 s 10 over 0.53 s (18.75 fps), so the rise is taken at the frame of
    2.13 + 0.80 s, the rate it rose to 30 fps (its latest 0.8 s), and nothing is given for
    that frame (the grid is to be made again).
    Before, once the burst had put it on the clock, the rise was never taken: the stream
    followed on its 15-fps grid, half of its frames resampled away."""
    for burst in (False, True):
        rose_at, given = _rise_taken(burst)
        assert rose_at == pytest.approx(2.0 + 4 / 30.0 + 0.8)
        assert given == []
        assert ("then frames at once" in capsys.readouterr().err) == burst


def test_frames_that_each_come_after_a_pause_are_each_on_their_grid_time() -> None:
    """A camera at 30 fps whose frames from 1 s to 2 s come in bursts of eight (on the grid by
    the wall clock from the first), which from 3.0 s to 4.2 s sends one frame every 0.3 s
    (the others lost), then 30 fps again, every frame but the bursts' read when taken: each
    frame held for the next (each after a pause) and given with it, the grid times between
    the 0.3-s frames missing, each frame's pose on the grid time it was taken at, and for
    each take as many missing flags and image landmarks as grid times. Before the held
    frame's flags were set afresh, a frame held right after one given (the 0.3-s frames
    here) was given with the flags of the one before it too."""
    fps = 30.0
    taken = np.arange(150) / fps
    sent = (taken < 3.0) | (taken > 4.2 + 1e-9) | (np.arange(150) % 9 == 0)
    came = taken.copy()
    for start in range(30, 60, 8):
        came[start : min(start + 8, 60)] = taken[min(start + 8, 60) - 1]
    grid = Regrid(fps, "0")
    values: list[float] = []
    for j, i in enumerate(np.flatnonzero(sent)):
        given = grid.take(_frame(j, came[i], taken[i]))
        assert len(grid.absent) == len(grid.images) == len(given)
        np.testing.assert_array_equal(
            grid.absent, [bool(np.isnan(world).all()) for world, _vis, _shown in given]
        )
        values += [float(world[0, 0]) for world, _vis, _shown in given]
    assert len(values) == 150
    np.testing.assert_array_equal(np.isnan(values), ~sent)
    np.testing.assert_allclose(np.array(values)[sent], taken[sent], atol=1e-9)


class _Segmenter:
    """A :class:`cbr.live.LiveSegmenter` that keeps the poses pushed (one coordinate each)."""

    def __init__(self) -> None:
        self.poses: list[float] = []
        self.jumped = False
        self.fps = 30.0

    def push(self, world: Any, visibility: Any, absent: bool, image: Any) -> list[Any]:
        self.poses.append(float(world[0, 0]))
        return []


def test_the_last_frame_after_a_pause_is_watched_and_its_latency_counted() -> None:
    """A live stream of 60 frames at 30 fps (read at i / 30 s), then one more 0.33 s after
    the last (the stream ends there): the last frame, held to tell a burst from a drop-out
    by the frame after it, is given when the stream ends, as a drop-out's, at the time it
    came (grid time 69 of 70, grid times 60-68 missing), and each of the 61 frames has its
    latency counted once. Before hunt 51e it was placed on grid time 60 (a burst's first
    frame, 0.30 s early)."""
    times = [*(np.arange(60) / 30.0), 59 / 30.0 + 1.0 / 3.0]
    watcher, latencies = _watched(times, "the stream ended after 70 frames")
    poses = np.array(watcher.live.poses)
    assert len(poses) == 70
    assert np.isnan(poses[60:69]).all()
    assert poses[69] == pytest.approx(times[-1])
    np.testing.assert_allclose(poses[:60], times[:60])
    assert len(latencies) == 61


def _watched(times: list[float], ended: str) -> tuple[Watcher, list[float]]:
    """A live 30-fps stream's frames read at ``times`` (s, latencies counted from the clock's
    start) followed by a watcher with a segmenter that keeps its poses, until the stream ends
    (the refusal matching ``ended``); the watcher and every latency it counted."""
    frames = []
    for i, t in enumerate(times):
        frame = _frame(i, float(t))
        frame.read_at, frame.last = 0.0, False
        frames.append(frame)
    args = argparse.Namespace(source="0", max_frames=None, out=None, show=False)
    watcher = Watcher(None, None, args, 30.0)
    watcher.live, watcher._grid = _Segmenter(), Regrid(30.0, "0")
    latencies: list[float] = []
    watcher.latency = SimpleNamespace(add=latencies.append)  # type: ignore[assignment]
    with pytest.raises(DataError, match=ended):
        watcher.follow(iter(frames), False, threading.Event())
    return watcher, latencies
