"""Session 52, task U: ``watch --progress SECONDS``, a line on the segment in progress every
SECONDS of the stream, so that a program reading stdout hears of one long activity before
it ends (before, an hour of one exercise gave its one line at the end of the hour)."""

from __future__ import annotations

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
from tests.once import made_once
from tests.test_watch import _cmu_13_29_windows

FPS = 10.0
SEGMENT_KEYS = ["start_s", "end_s", "start_frame", "end_frame", "label", "confidence",
                "unknown", "repetitions", "explanation", "novelty", "count"]  # fmt: skip


@pytest.fixture(scope="module")
def case_base(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/test_watch.py's case base (windows of CMU 13_29), made once in the session."""
    return made_once(
        tmp_path_factory, "cmu-13-29-windows", lambda f: _cmu_13_29_windows(f, shared_data)
    )


def _twists_then_knee_raises(shared_data: Path) -> np.ndarray:
    """Real poses at 10 fps: CMU 13_30's twist stretch (labelled 6, Twist, in its 0.1-s
    labels) three times over (14.4 s), then its knee-raise stretch (4, KneeRaise) once
    (5.4 s): 198 frames, one long activity and a change the decoders settle seconds late."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    labels = (shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt").read_text().split()
    parts = []
    for label, times in (("6", 3), ("4", 1)):
        blocks = [i for i, x in enumerate(labels) if x == label]
        start, end = blocks[0] * 12, (blocks[-1] + 1) * 12  # 0.1 s at 120 fps
        parts += [seq.positions[start:end:12]] * times
    return np.concatenate(parts)


def _camera(world: np.ndarray) -> Any:
    """A stand-in for ``stream_poses``: ``world`` delivered frame by frame at :data:`FPS`,
    as a camera would (tests/test_watch.py's ``_mocap_stream``), then the stream ends."""

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        for i in range(len(world)):
            image = np.full((33, 5), np.nan)
            image[:, 3] = 1.0  # every joint seen (mocap)
            pose = FramePose(image, world[i], True, False, 1.0, None)
            yield StreamFrame(
                i, i / FPS, pose, np.zeros((48, 64, 3), np.uint8), time.perf_counter()
            )

    return stream


def test_progress_lines_come_every_second_and_never_outrun_the_segment_that_closes(
    case_base: Path,
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--progress 1`` on 14.4 s of twists then 5.4 s of knee raises: a progress line at
    every whole second of the stream from the first whose label the decoders have settled
    to the end, each at its frame (10 per second); each names the segment that a later
    line closes (its start), with that line's label, and repetitions never more than that
    line's, never falling; the finished segments' lines say ``"event": "segment"``, their
    fields otherwise as ever. (The segment in progress as drawn, ``current()``, counted the
    twists' segment 13 at 19 s, up from 5 at 9 s and down once, where its line, cut at
    14.5 s, says 9: the knee raises' frames counted in it.)"""
    world = _twists_then_knee_raises(shared_data)
    assert len(world) == 198
    monkeypatch.setattr(pose_estimation, "stream_poses", _camera(world))
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--max-frames", "198",
                 "--progress", "1"]) == 0  # fmt: skip
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert {line["event"] for line in lines} == {"progress", "segment"}
    progress = [line for line in lines if line["event"] == "progress"]
    segments = [line for line in lines if line["event"] == "segment"]
    for line in segments:
        assert list(line) == ["event", *SEGMENT_KEYS]
    assert segments[0]["start_frame"] == 0 and segments[-1]["end_frame"] == 198
    assert segments[0]["label"] == "Twist"  # 13_30's label over its first 14.4 s
    # every second, at the frame of that second, from the first line to the stream's end
    seconds = [line["t_s"] for line in progress]
    assert seconds == list(range(int(seconds[0]), 20)), seconds
    assert 5 <= seconds[0] <= 12  # once the first hops are settled
    for line in progress:
        assert line["frame"] == 10 * line["t_s"]
        assert line["since_s"] == pytest.approx(line["t_s"] - line["start_s"])
        assert line["start_s"] <= line["settled_s"] <= line["t_s"]
        closing = [s for s in segments if s["start_frame"] == line["start_frame"]]
        assert len(closing) == 1, line
        assert lines.index(closing[0]) > lines.index(line)  # closed after it
        assert line["label"] == closing[0]["label"]
        assert line["unknown"] == closing[0]["unknown"] is None
        assert 0 <= line["repetitions"] == line["count"] <= closing[0]["repetitions"]
    counts = [line["repetitions"] for line in progress if line["start_frame"] == 0]
    assert counts == sorted(counts) and counts[-1] > 0, counts  # some counted before the end


@pytest.mark.parametrize("seconds", ["0", "-1", "nan", "inf"])
def test_progress_must_be_seconds_above_zero(
    seconds: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One line naming the option, as ``--max-frames 0`` is refused (exit 1), before any case
    base is read."""
    video = tmp_path / "clip.mp4"
    video.write_bytes(b"")
    argv = ["watch", str(video), "--db", str(tmp_path / "none.sqlite"), "--progress", seconds]
    assert main(argv) == 1
    assert capsys.readouterr().err == (
        f"posecbr watch: error: --progress: must be a number of seconds > 0, got {seconds}\n"
    )
