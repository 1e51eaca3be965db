"""``posecbr watch`` left running for hours, as a robot runs it (hunt 48h2).

- Every frame's latency was kept to the end (a list of floats: about 32 bytes a frame, 83 MB a
  day at 30 fps, all sorted at the end); now tallied in a histogram of fixed size
  (:class:`posecbr.commands.watch.Latencies`).
- A live source's rate is measured over its first second; measured a little low (29.7 for a
  30-fps camera), the frames ran ahead of the clock the stall check counts by, a frame every
  3.3 s, and from about the fifth minute a stall was joined as if no frame were missing
  (:meth:`posecbr.commands.watch.Regrid._stalled`).
"""

from __future__ import annotations

import json
import os
import pickle
import signal
import threading
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import features.pose_estimation as pose_estimation
from posecbr.cli import main
from posecbr.commands import watch
from posecbr.commands.watch import Regrid
from tests.test_watch import (
    _mocap_stream,
    case_base,  # noqa: F401 - the fixture: CMU 13_29's windows
)


def test_the_latency_percentiles_are_numpys_within_half_a_bin() -> None:
    """100,000 latencies of a long-tailed spread (log-normal about 50 ms) and a handful of
    even ones: the median and 95th percentile within 0.05 % of numpy's exact ones (the bins
    grow by 0.1 %), the least and the worst exact."""
    from posecbr.commands.watch import Latencies  # new: every latency was kept

    rng = np.random.default_rng(48)
    for values in (rng.lognormal(np.log(0.05), 0.8, 100_000), rng.uniform(0.0, 0.2, 7)):
        tally = Latencies()
        for v in values:
            tally.add(float(v))
        assert tally.count == len(values)
        for q in (50, 95):
            assert tally.percentile(q) == pytest.approx(np.percentile(values, q), rel=5e-4)
        assert tally.percentile(0) == tally.least == values.min()
        assert tally.percentile(100) == tally.worst == values.max()


def test_a_watch_keeps_no_latency_per_frame(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera watched for 120 frames: what the watch holds of their latencies is no more
    than it holds before the first frame (it held the 120 of them, one per frame, and would
    have held 2.6 million after a day), and the latency is still printed."""
    watchers: list[Any] = []
    close = watch.Watcher.close

    def kept(self: Any, stop: Any) -> None:
        watchers.append(self)
        close(self, stop)

    monkeypatch.setattr(watch.Watcher, "close", kept)
    monkeypatch.setattr(pose_estimation, "stream_poses", _mocap_stream(shared_data, 120, "end"))
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--max-frames", "120"]) == 0
    assert "latency frame to label: median" in capsys.readouterr().err
    (watcher,) = watchers
    fresh = type(watcher.latency)()
    assert len(pickle.dumps(watcher.latency)) == len(pickle.dumps(fresh))


def _frame(index: int, time_s: float) -> SimpleNamespace:
    """A live source's frame (no time of its own in a video) read at ``time_s``."""
    pose = SimpleNamespace(image=np.zeros((33, 5)))
    return SimpleNamespace(
        index=index,
        time_s=time_s,
        video_time_s=float("nan"),
        seen_world=np.zeros((33, 3)),
        visibility=np.ones(33),
        pose=pose,
    )


@pytest.mark.parametrize("measured", [29.7, 30.3])
def test_a_stall_after_ten_minutes_is_left_missing_at_a_rate_measured_off(
    measured: float, capsys: pytest.CaptureFixture[str]
) -> None:
    """A camera sending 30 frames a second, its rate measured as 1 % off, streamed 10
    minutes, then silent for 3.0 s: the grid times in the stall, by hand 3.0 s at the rate
    measured less the frame that ends it (round(3.0 * 29.7) - 1 = 88, round(3.0 * 30.3) - 1
    = 90), are missing, and said so. Measured low, none was: the frames had run ahead of
    the clock counted from the first frame by 180 (0.3 a second for 600 s), more than the
    stall's."""
    grid = Regrid(measured, "0")
    n = 10 * 60 * 30
    for i in range(n):
        assert len(grid.take(_frame(i, i / 30.0))) == 1
    capsys.readouterr()
    after = grid.take(_frame(n, (n - 1) / 30.0 + 3.0))
    assert len(after) == round(3.0 * measured) - 1 + 1
    assert grid.absent == [True] * (round(3.0 * measured) - 1) + [False]
    assert "the stream stalled: 3.0 s without frames" in capsys.readouterr().err


def test_a_burst_after_a_hold_up_comes_off_the_next_stall_for_seconds() -> None:
    """30 fps for a minute, then a 1-s hold-up (29 frames missing) ended by 8 frames read at
    once (7 more than the clock allows: a buffer emptied), 2 s of frames at 30 a second and
    another 1-s hold-up: of its 29, the 7 frames of the burst come off, less the 3 that 2 s
    forgive (RATE_SLACK 5 % of 2 s at 30 fps), by hand 29 - (7 - 3) = 25; 29 once the
    burst is 5 s or more behind (7 frames at 1.5 a second)."""
    for spacing, second in ((2.0, 25), (5.0, 29)):
        grid = Regrid(30.0, "0")
        times = list(np.arange(1800) / 30.0)
        times += [times[-1] + 1.0 + j * 0.001 for j in range(8)]
        times += [times[-1] + (j + 1) / 30.0 for j in range(round(spacing * 30))]
        times += [times[-1] + 1.0 + j / 30.0 for j in range(30)]
        stalls = [
            len(out) - 1 for i, t in enumerate(times) if len(out := grid.take(_frame(i, t))) > 1
        ]
        assert stalls == [29, second]


@pytest.mark.parametrize("then", ["end", "stall"])
def test_a_stream_lost_gives_the_segments_of_the_frames_watched(
    then: str,
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera that sends 150 frames (5 s of CMU 13_30's jumping jacks) and then stops, or
    stalls past ``--stall``: the segments printed cover the 150 frames watched, one after
    the other from frame 0 (the segment in progress given as at the end of a file), then
    the watch's summary (hunt 52y) and the one line saying the stream was lost, exit 1. The
    segment in progress was never printed (here: no line at all), nor was an activity going
    on when the camera was lost."""
    monkeypatch.setattr(pose_estimation, "stream_poses", _mocap_stream(shared_data, 150, then))
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--stall", "0.5"]) == 1
    printed = capsys.readouterr()
    lines = [json.loads(line) for line in printed.out.splitlines()]
    assert lines and lines[0]["start_frame"] == 0 and lines[-1]["end_frame"] == 150
    for a, b in zip(lines[:-1], lines[1:], strict=True):
        assert a["end_frame"] == b["start_frame"]
    lost = "the stream ended after 150 frames" if then == "end" else "stalled: no frame for 0.5 s"
    summary, error, end = printed.err.split("\n")
    assert summary.startswith("watched 150 frames in ") and end == "", printed.err
    assert lost in error, printed.err


def test_sigterm_while_a_camera_sends_nothing_ends_the_watch_there(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera that sends 90 frames and then nothing (within ``--stall 20``), and SIGTERM
    (a supervisor stopping the watch) while it sends nothing: the watch ends there as at the
    end of a stream, the segments of the 90 frames printed and the latency, exit 0. The
    wait for a frame went on to the stall time, then said "the stream stalled", exit 1, as
    if the camera had failed (and a supervisor that kills after a grace period, ``docker
    stop``'s 10 s, killed it first)."""
    quiet = threading.Event()
    camera = _mocap_stream(shared_data, 90, "end")

    def stream(source: Any, **kwargs: Any) -> Any:
        yield from camera(source, **kwargs)
        threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGTERM)).start()
        quiet.wait(60)  # sends nothing

    monkeypatch.setattr(pose_estimation, "stream_poses", stream)
    capsys.readouterr()
    try:
        code = main(["watch", "0", "--db", str(case_base), "--stall", "20"])
    finally:
        quiet.set()
    printed = capsys.readouterr()
    assert code == 0, printed.err
    lines = [json.loads(line) for line in printed.out.splitlines()]
    assert lines and lines[0]["start_frame"] == 0 and lines[-1]["end_frame"] == 90
    assert "stalled" not in printed.err and "latency frame to label" in printed.err
