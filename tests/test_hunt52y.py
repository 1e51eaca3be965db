"""Hunt 52Y: the ends of ``posecbr watch``.

- A live stream lost (``StreamLost``: the camera unplugged, the stream stalled) has the
  watch's summary said on stderr before the refusal, as at the end of a watch: the frames
  watched and their latency, and (``--split repetitions``) each repetition's verdict.
  Before, only the JSON lines of what was finished were printed.
- A live source whose rate rise is taken among the frames held when the stream ends
  (:meth:`posecbr.commands.watch.Watcher._flush`) is watched again at the rate it rose to,
  as when the rise is taken before the end: before, the frames held after the rise were
  dropped and the stream followed at its first rate.
- :meth:`cbr.live.LiveSegmenter.repetitions_from` refuses True and False as the frame to
  count from, as it refuses other values that are no frame number: before, True counted
  from frame 1.
"""

from __future__ import annotations

import argparse
import math
import threading
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from cbr.live import LiveSegmenter
from features.errors import DataError, InputError
from posecbr.commands.watch import Regrid, StreamLost, Watcher
from tests.test_hunt49e import _frame


class _Segmenter:
    """A :class:`cbr.live.LiveSegmenter` that keeps the poses pushed (one coordinate each)."""

    def __init__(self, clf: Any, fps: float, *_args: Any, **_kwargs: Any) -> None:
        self.poses: list[float] = []
        self.jumped = False
        self.fps = fps

    def push(self, world: Any, visibility: Any, absent: bool, image: Any) -> list[Any]:
        self.poses.append(float(world[0, 0]))
        return []

    def finish(self) -> list[Any]:
        return []


def rise_with_a_drop_out() -> list[Any]:
    """The stream's frames: 15 fps for 2 s (a burst at 1.6 s: frames 20-24 come at once),
    then 60 fps, the frames taken within 2.55-2.87 s lost (a drop-out), ending at 2.88 s."""
    taken = np.concatenate([np.arange(30) / 15.0, 2.0 + np.arange(54) / 60.0])
    came = taken.copy()
    came[20:25] = taken[24]
    sent = ~((taken > 2.55) & (taken < 2.0 + 52 / 60.0 - 1e-9))
    frames = []
    for j, i in enumerate(np.flatnonzero(sent)):
        frame = _frame(j, came[i], taken[i])
        frame.read_at, frame.last = 0.0, False
        frames.append(frame)
    return frames


def test_a_rise_taken_among_the_frames_held_at_the_end_is_watched_again_at_it(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A camera at 15 fps for 2 s (its frames taken at 1.33-1.6 s read at once at 1.6 s: on
    the grid by the wall clock from there), then at 60 fps, every other frame read when
    taken; those taken within 2.55-2.87 s are lost (a pause) and the stream ends at 2.88 s,
    the two frames after the pause held to tell a burst from a drop-out. Their rate over the
    latest half second has been more than a fifth above 15 fps since 2.08 s (10 intervals
    of 1/60 s over 0.5 s less 2 of 1/15 s: 18.75 fps): the rise is taken at the second held
    frame, 0.8 s on, while they are given at the end. The stream is then watched again from
    its start at the rate it rose to, as when another frame comes: the grid times up to the
    last frame before the pause at k / fps, each pose the time it lies at (the frames'
    poses are their times), and the last grid time past the first held frame's time (the
    last frame reached the grid). Before, the last frame
    was dropped and the stream followed on its 15-fps grid."""
    monkeypatch.setattr("cbr.live.LiveSegmenter", _Segmenter)
    frames = rise_with_a_drop_out()
    args = argparse.Namespace(source="0", max_frames=None, out=None, show=False, k=1)
    watcher = Watcher(None, None, args, None)
    with pytest.raises(DataError, match="the stream ended after"):
        watcher.follow(iter(frames), False, threading.Event())
    assert "the frame rate rose from 15 to" in capsys.readouterr().err
    fps = watcher.live.fps
    assert fps > 15.0 * 1.2
    poses = np.array(watcher.live.poses)
    before = np.arange(math.floor(2.55 * fps) + 1) / fps  # the grid times before the pause
    np.testing.assert_allclose(poses[: len(before)], before, atol=1e-9)
    taken = 2.0 + np.arange(52, 54) / 60.0  # the stream's last two frames' times
    assert taken[-2] < poses[-1] <= taken[-1] + 1e-9  # the last frame reached the grid


def test_a_lost_stream_says_the_watchs_summary(capsys: pytest.CaptureFixture[str]) -> None:
    """A live 30-fps stream of 45 frames, read when taken, that then stops sending (lost),
    watched with ``--split repetitions`` (one repetition judged, frames 0-29, ``good``):
    the watch's summary is on stderr when the loss is said: 45 frames watched, their
    latency, the repetition's line and the count of repetitions judged."""
    frames = []
    for i in range(45):
        frame = _frame(i, i / 30.0)
        frame.read_at, frame.last = 0.0, False
        frames.append(frame)
    args = argparse.Namespace(source="0", max_frames=None, out=None, show=False)
    watcher = Watcher(None, None, args, 30.0, SimpleNamespace(target="label"))
    watcher.live, watcher._grid = _Segmenter(None, 30.0), Regrid(30.0, "0")
    judged = SimpleNamespace(explanation=SimpleNamespace(text="good: like case 3\nmore"))
    verdict = SimpleNamespace(
        number=1, start_frame=0, end_frame=30, fps=30.0, label="good", judged=judged
    )
    watcher.verdicts = SimpleNamespace(given=[verdict], update=lambda ended=False: [])
    with pytest.raises(StreamLost, match="the stream ended after 45 frames"):
        watcher.watch(iter(frames), False, threading.Event())
    err = capsys.readouterr().err
    assert "watched 45 frames in " in err and "latency frame to label: median" in err
    assert "repetition 1, frames 0-29 (0.0-1.0 s): good: like case 3\n" in err
    assert "1 repetition judged: " in err


@pytest.mark.parametrize("start", [True, False])
def test_repetitions_are_counted_from_a_frame_number_only(start: Any) -> None:
    """The frame to count from is checked before the segmenter is read (a stand-in for it
    here): True and False are refused, as -1 and 1.0 are."""
    live = SimpleNamespace(source="stream")
    with pytest.raises(
        InputError, match=f"stream: start must be a frame number >= 0, got {start!r}"
    ):
        LiveSegmenter.repetitions_from(live, start)  # type: ignore[arg-type]
