"""Session 52, task Z: ``watch --progress`` on the paths its first tests (tests/test_hunt52u.py)
left out: a stretch with nobody in view, a live source whose rate rises in its first seconds
(the stream watched again from its start: :meth:`posecbr.commands.watch.Watcher._remake`),
and ``--split repetitions`` (every line tagged with its ``"event"``)."""

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
from tests.test_hunt52u import (
    SEGMENT_KEYS,
    _camera,
    _twists_then_knee_raises,
    case_base,  # noqa: F401 - the fixture: CMU 13_29's windows
)


def _slow_start_with_nobody(shared_data: Path) -> Any:
    """A camera (a live source: ``time_s`` its clock) at 5 frames a second for its first 2 s,
    then 10, each frame showing the pose of its time: CMU 13_30's twists for 8 s, nobody in
    view (every joint missing) for 6 s, the twists again for 6 s; 190 frames, 20 s."""
    twists = _twists_then_knee_raises(shared_data)[:144]  # 14.4 s of twists at 10 fps
    world = np.concatenate([twists[:80], np.full((60, 33, 3), np.nan), twists[:60]])
    times = np.array([i / 5.0 if i < 10 else 2.0 + (i - 10) / 10.0 for i in range(190)])
    shown = np.round(times * 10.0).astype(int)  # the 10-fps pose at the frame's time

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        for i, t in enumerate(times):
            image = np.full((33, 5), np.nan)
            image[:, 3] = 1.0  # every joint seen (mocap)
            pose = FramePose(image, world[shown[i]], True, False, 1.0, None)
            yield StreamFrame(
                i, float(t), pose, np.zeros((48, 64, 3), np.uint8), time.perf_counter()
            )

    return stream


def test_progress_through_nobody_in_view_after_a_rate_that_rose(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--progress 1`` on a camera that starts at 5 fps and rises to 10 (the stream watched
    again from its start at 10 fps, said once), twisting 8 s, out of view 6 s, twisting
    6 s: three segments, 0-8 s Twist, 8-14 s nobody in view (0 repetitions), 14-20 s Twist,
    tiling the 200 grid times (20 s by the clock at 10 fps). Progress lines come one a
    second of the grid, in order, none twice (the frames watched again after the re-make
    print none again: no line comes before the re-make's 4 s), each at its frame; each
    names the segment a later line closes, with that line's label and why it is unknown, never more
    repetitions than it; those of the stretch out of view say so: no label, "nobody in
    view", 0 repetitions, as its closing line does."""
    monkeypatch.setattr(pose_estimation, "stream_poses", _slow_start_with_nobody(shared_data))
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--max-frames", "190",
                 "--progress", "1"]) == 0  # fmt: skip
    printed = capsys.readouterr()
    assert printed.err.count("the frame rate rose from 5 to 10 fps") == 1
    raw = printed.out.splitlines()
    assert len(raw) == len(set(raw))  # nothing printed twice
    lines = [json.loads(line) for line in raw]
    progress = [line for line in lines if line["event"] == "progress"]
    segments = [line for line in lines if line["event"] == "segment"]
    assert len(progress) + len(segments) == len(lines)
    for line in segments:
        assert list(line) == ["event", *SEGMENT_KEYS]
    spans = [(s["start_frame"], s["end_frame"], s["label"], s["unknown"]) for s in segments]
    assert spans == [(0, 80, "Twist", None), (80, 140, None, "nobody in view"),
                     (140, 200, "Twist", None)]  # fmt: skip
    assert segments[1]["repetitions"] == 0
    seconds = [line["t_s"] for line in progress]
    assert seconds == list(range(int(seconds[0]), 21)), seconds  # 20 s: the grid's end
    for line in progress:
        assert line["frame"] == 10 * line["t_s"]
        closing = [s for s in segments if s["start_frame"] == line["start_frame"]]
        assert len(closing) == 1, line
        assert lines.index(closing[0]) > lines.index(line)
        assert (line["label"], line["unknown"]) == (closing[0]["label"], closing[0]["unknown"])
        assert 0 <= line["repetitions"] <= closing[0]["repetitions"]
    away = [line for line in progress if line["start_frame"] == 80]
    assert away, "some progress line of the stretch with nobody in view"
    for line in away:
        assert (line["label"], line["unknown"], line["repetitions"], line["count"]) == (
            None, "nobody in view", 0, 0)  # fmt: skip
        assert line["start_s"] == 8.0 and line["since_s"] == pytest.approx(line["t_s"] - 8.0)


def _squats_then_held_at_the_bottom(shared_data: Path) -> np.ndarray:
    """Real poses at 10 fps: CMU 13_30's squat stretch (labelled 3, Squat, in its 0.1-s
    labels: 4.3 s, two squats, the hips lowest at its 13th and 36th frames) twice over to
    its 42nd frame (standing again), then once more to the second squat's bottom (36th
    frame), held there 10 s to the stream's end: five whole squats and a sixth held at its
    bottom; 220 frames, 22 s."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    labels = (shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt").read_text().split()
    blocks = [i for i, x in enumerate(labels) if x == "3"]
    squats = seq.positions[blocks[0] * 12 : (blocks[-1] + 1) * 12 : 12]  # 0.1 s at 120 fps
    assert len(squats) == 43
    return np.concatenate([squats[:42], squats[:42], squats[:36], np.repeat(squats[35:36], 100, 0)])


def test_progress_never_counts_more_than_the_closing_line_across_a_cut_in_a_hold(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Five squats, a sixth held at the bottom for 10 s to the stream's end: the squats'
    segment is cut in the hold (its last far point held on past the cut is left to the
    segment after, which counts it, the stream ending in the hold:
    ``LiveSegmenter._held_on``): the squats' line counts the five whole squats, the hold's
    the sixth. No progress line of the squats' segment counts more than its closing line
    (nor more than the five squats), the counts never falling."""
    world = _squats_then_held_at_the_bottom(shared_data)
    monkeypatch.setattr(pose_estimation, "stream_poses", _camera(world))
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--max-frames", "220",
                 "--progress", "1"]) == 0  # fmt: skip
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    segments = [line for line in lines if line["event"] == "segment"]
    progress = [line for line in lines if line["event"] == "progress"]
    assert [(s["label"], s["repetitions"]) for s in segments] == [("Squat", 5), (None, 1)]
    assert 120 <= segments[1]["start_frame"] < 220  # cut in the hold (from frame 120)
    assert progress and all(line["start_frame"] == 0 for line in progress)
    counts = [line["repetitions"] for line in progress]
    assert counts == sorted(counts) and counts[-1] <= 5, counts
    assert all(line["label"] == "Squat" for line in progress)
