"""``watch`` live (hunt 40h): its latency counted from when a file's frame was due, a live
stream that stalls and resumes, and a live stream's rate measured over a wait.

- A file played at its own rate stands in for a camera: each frame is held until its time
  (:class:`posecbr.commands.watch.Pacer`). The latency printed ran from when the reader
  took the frame, so a watch that fell behind (frames waiting in the reader's queue, a
  camera's buffer) hid it: 250 frames of a 30-fps 640x480 video watched at 12.5 frames/s on
  a loaded machine said "median 71 ms", each label coming up to 11 s after its frame.
- A live source (camera, ``rtsp://``) that sent no frame for 3 s, shorter than ``--stall``,
  then resumed: the frames either side were joined as if none were missing, so every later
  segment was timed 3 s early and the movement ran across the stall.
- A live source's frame rate, measured over its first second, counted a wait in it as frame
  time: a webcam slow to send its second frame was taken for 13 fps instead of 30.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import features.pose_estimation as pose_estimation
from features.pose_estimation import StreamFrame
from features.pose_estimation.tracker import FramePose
from features.readers.asfamc import read_asf_amc
from posecbr.cli import main
from posecbr.commands.watch import Pacer, Watcher
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows


class _NoGrid:
    """A :class:`posecbr.commands.watch.Regrid` that gives no grid time: only the latency
    is kept."""

    absent: list[bool] = []
    images: list[Any] = []
    held: list[Any] = []  # no frame held for the next

    def take(self, frame: Any) -> list[Any]:
        return []


class _Kept(list[float]):
    """The latencies added, each kept."""

    def add(self, seconds: float) -> None:
        self.append(seconds)


def _frame(index: int, read_at: float) -> StreamFrame:
    pose = FramePose(np.full((33, 5), np.nan), np.full((33, 3), np.nan), False, False, 0.0, None)
    return StreamFrame(index, index / 30.0, pose, np.zeros((4, 4, 3), np.uint8), read_at)


def test_the_latency_of_a_file_played_at_its_rate_runs_from_when_its_frame_was_due() -> None:
    """A 30-fps file whose first frame came 10 s ago: frame 3 was due 0.1 s after it, 9.9 s
    ago; the watch fell behind and read it just now. Its latency runs from 9.9 s ago (it
    was 0.0 s and a little: from the read)."""
    pacer = Pacer(30.0, 1.0)
    pacer.stop.set()  # no wait: the frames are long due
    pacer.started = time.perf_counter() - 10.0
    for i in range(4):
        pacer(i, i / 30.0)
    due = pacer.started + 3 / 30.0  # by hand: frame 3 at 0.1 s
    watcher = Watcher(None, None, argparse.Namespace(), 30.0)
    watcher.pacer = pacer
    watcher._grid = _NoGrid()
    watcher.latency = _Kept()  # each latency as it is added (the watch tallies them)
    before = time.perf_counter()
    watcher._take(_frame(3, read_at=before))
    after = time.perf_counter()
    assert len(watcher.latency) == 1
    assert before - due <= watcher.latency[0] <= after - due
    # a frame no pacer held (a camera's): from its read
    watcher.pacer = None
    read = time.perf_counter()
    watcher._take(_frame(4, read_at=read))
    assert 0.0 <= watcher.latency[1] <= time.perf_counter() - read


def test_the_pacer_keeps_the_due_times_of_its_latest_frames() -> None:
    """Each frame's due time, by hand (started + index / fps), for its latest 64 frames (more
    than the reader's queue holds): an older one has none, and is timed from its read."""
    pacer = Pacer(30.0, 1.0)
    pacer.stop.set()
    for i in range(100):
        pacer(i, i / 30.0)
    assert pacer.due_at(99) == pytest.approx(pacer.started + 99 / 30.0)
    assert pacer.due_at(0) is None  # long gone


FPS = 30.0


def _stream(shared_data: Path, times_s: np.ndarray, skip: np.ndarray) -> Any:
    """A stand-in for a live ``stream_poses``: real poses (CMU 13_30 at 120 fps, every 4th
    frame: 30 fps), frame ``i`` read at ``times_s[i]`` by the wall clock (a live source's
    ``time_s``), showing the pose of stream frame ``i + skip[i]`` (the frames a stall lost)."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    world = seq.positions[::4]

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        for i, t in enumerate(times_s):
            image = np.full((33, 5), np.nan)
            image[:, 3] = 1.0  # every joint seen (mocap)
            pose = FramePose(image, world[i + skip[i]], True, False, 1.0, None)
            rgb = np.zeros((48, 64, 3), dtype=np.uint8)
            yield StreamFrame(i, float(t), pose, rgb, time.perf_counter())

    return stream


def _watched(
    case_base: Path,  # noqa: F811
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    stream: Any,
    n: int,
) -> tuple[list[dict[str, Any]], str]:
    monkeypatch.setattr(pose_estimation, "stream_poses", stream)
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--max-frames", str(n)]) == 0
    printed = capsys.readouterr()
    return [json.loads(line) for line in printed.out.splitlines()], printed.err


def test_a_live_stream_that_stalls_and_resumes_leaves_the_stall_missing(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """300 frames at 30 fps, none sent for 3 s after the 150th (4.97 s; the poses of those
    3 s lost): the stream lasts 13.0 s by the clock, 390 frames at 30 fps, the 90 after
    frame 149 (5.0-8.0 s) missing, a segment of their own said to have no frames, and one
    note on stderr. It ended at frame 300, 10.0 s, no note: the knee raises after the stall
    were placed at 5.0 s, where the twists had been."""
    times = np.arange(300) / FPS
    times[150:] += 3.0
    skip = np.where(np.arange(300) >= 150, 90, 0)
    segments, err = _watched(case_base, monkeypatch, capsys, _stream(shared_data, times, skip), 300)
    assert segments[-1]["end_frame"] == 390 and segments[-1]["end_s"] == pytest.approx(13.0)
    stall = [s for s in segments if s["unknown"] == "no frames in the video"]
    assert [(s["start_frame"], s["end_frame"]) for s in stall] == [(150, 240)]
    for a, b in zip(segments[:-1], segments[1:], strict=True):
        assert a["end_frame"] == b["start_frame"]
    notes = [line for line in err.splitlines() if line.startswith("note:")]
    assert notes == ["note: 0: the stream stalled: 3.0 s without frames at 5.0-8.0 s left missing"]
    assert "watched 390 frames" in err


def test_a_live_stream_with_jittered_frame_times_has_no_stall(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Frames read 33 ms +-20 % apart (a camera's clock and the machine's load): nothing is
    missing, the 300 frames are the stream's 300 frames, no note."""
    rng = np.random.default_rng(40)
    gaps = (1 + rng.uniform(-0.2, 0.2, 299)) / FPS
    times = np.concatenate([[0.0], np.cumsum(gaps)])
    segments, err = _watched(
        case_base, monkeypatch, capsys, _stream(shared_data, times, np.zeros(300, int)), 300
    )
    assert segments[-1]["end_frame"] == 300
    assert "no frames in the video" not in {s["unknown"] for s in segments}
    assert "stalled" not in err and "watched 300 frames" in err


def test_a_webcam_slow_to_send_its_second_frame_is_measured_at_its_rate(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A webcam's first frame, then none for 0.6 s (warming up), then 30 a second: its rate
    is 30 fps, the 0.6 s without frames left missing as a stall is (17 frames: 0.6 s at 30
    fps, less the one that ends it), the stream 10.57 s long by its clock (0.6 s, then 299
    intervals of 1/30 s). It was measured over its first second as 13 frames in 1.0 s, 13
    fps, and every segment timed 2.3 times too long (the stream "23.6 s")."""
    times = np.concatenate([[0.0], 0.6 + np.arange(299) / FPS])
    segments, err = _watched(
        case_base, monkeypatch, capsys, _stream(shared_data, times, np.zeros(300, int)), 300
    )
    assert segments[-1]["end_frame"] == 300 + 17
    assert segments[-1]["end_s"] == pytest.approx(0.6 + 299 / FPS, abs=1e-3)
    assert "0.6 s without frames at 0.0-0.6 s left missing" in err


def test_a_live_rate_leaves_out_the_intervals_no_frame_was_sent_in() -> None:
    """The rate over the first second of intervals: 30 fps by hand, with a 0.6-s wait
    after the first frame, or a 0.5-s stall in the middle, left out; under a second of
    intervals sent: not yet known."""
    from posecbr.commands.watch import _frame_rate

    def frames(times: np.ndarray) -> list[float]:  # the frames' times, as the watch takes them
        return [float(t) for t in times]

    steady = np.arange(40) / FPS  # 39 intervals: 1.3 s
    assert _frame_rate(frames(steady)) == pytest.approx(30.0)
    waited = np.concatenate([[0.0], 0.6 + steady])
    assert _frame_rate(frames(waited)) == pytest.approx(30.0)
    stalled = np.concatenate([steady[:15], steady[15:] + 0.5])
    assert _frame_rate(frames(stalled)) == pytest.approx(30.0)
    # 19 intervals sent, 0.63 s, and the wait: not yet known (it was: 20 / 1.23 s)
    assert _frame_rate(frames(np.concatenate([[0.0], 0.6 + steady[:20]]))) is None
