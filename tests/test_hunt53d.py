"""Session 53, task D: two faults of ``watch``'s live figures.

- ``watch --progress``: while the person holds still at the end of a segment, the decoders
  settle nothing (no window of the hold votes for any activity), so the progress lines'
  label and count stand still though time goes on; each line now says the person holds
  still, and since when (``"still_s"``), and still says no more than the finished line.
- A live source's rate measured over a window with a drop-out in it (a pause after which
  the stream resumed at its own pace, its frames lost) is no longer read low: the pause is
  left out, as a stall's is, where a burst's (frames held up, then read at once) still
  counts (:func:`posecbr.commands.watch._frame_rate`).
"""

from __future__ import annotations

import argparse
import json
import threading
from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.readers.asfamc import read_asf_amc
from posecbr.commands.watch import BURST_S, CHANGE_WINDOW_S, Watcher, _frame_rate
from tests.once import made_once
from tests.test_hunt52y import _Segmenter, rise_with_a_drop_out
from tests.test_watch import _cmu_13_29_windows

FPS = 10.0


@pytest.fixture(scope="module")
def case_base(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/test_watch.py's case base (windows of CMU 13_29), made once in the session."""
    return made_once(
        tmp_path_factory, "cmu-13-29-windows", lambda f: _cmu_13_29_windows(f, shared_data)
    )


def _twists_then_held(shared_data: Path, held_s: float) -> tuple[np.ndarray, int]:
    """Real poses at 10 fps: CMU 13_30's twist stretch (labelled 6, Twist, in its 0.1-s
    labels) twice over, then its last frame held for ``held_s`` (the person holding still);
    and the first frame of the hold."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    labels = (shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt").read_text().split()
    blocks = [i for i, x in enumerate(labels) if x == "6"]
    start, end = blocks[0] * 12, (blocks[-1] + 1) * 12  # 0.1 s at 120 fps
    moving = np.concatenate([seq.positions[start:end:12]] * 2)
    held = np.repeat(moving[-1:], int(held_s * FPS), axis=0)
    return np.concatenate([moving, held]), len(moving)


def test_progress_lines_say_the_person_holds_still_and_no_more_than_the_finished_line(
    case_base: Path, shared_data: Path
) -> None:
    """Twists for 9.8 s, then the last pose held 7 s, pushed into the live segmenter with
    its progress asked every second (as ``watch --progress 1`` asks it). The 2-s window
    that ends at a line lies wholly in the hold from 11.8 s on (frame 98 + 20): every line
    from then on says the person holds still, since no later than the hold began (the
    first window wholly in it starts at frame 98, 9.8 s); a line whose window ends before
    the hold (10 s at the latest: frames 80-99 hold the twist's last second) says nothing of
    it, as before (no key). Every line names the twist segment (start 0, Twist) and counts
    no more than the line that closes it. Before, no line said the person held still: the
    same label and count for every second of the hold."""
    from casebase_store import open_store
    from cbr.live import LiveSegmenter
    from cbr.stored import load_classifier

    store = open_store(str(case_base), readonly=True)
    clf = load_classifier(store, store.list_case_bases()[0].name).classifier
    world, hold = _twists_then_held(shared_data, 7.0)
    live = LiveSegmenter(clf, FPS)
    lines, segments = [], []
    for i, frame in enumerate(world):
        segments += live.push(frame)
        if (i + 1) % int(FPS) == 0 and (now := live.progress()) is not None:
            lines.append(json.loads(json.dumps(now.to_dict(FPS))))
    segments += live.finish()
    twist = segments[0]
    assert (twist.start_frame, twist.label) == (0, "Twist")
    assert lines and all(line["start_s"] == 0.0 and line["label"] == "Twist" for line in lines)
    assert all(line["repetitions"] <= twist.repetitions for line in lines)
    held = [line for line in lines if line["frame"] >= hold + 2 * FPS]
    moving = [line for line in lines if line["frame"] <= hold + 2]
    assert len(held) >= 4 and moving  # 12 to 16 s; 9 and 10 s
    assert all(line["still_s"] <= hold / FPS for line in held)
    assert all("still_s" not in line for line in moving)


@pytest.mark.parametrize("pause_s", [0.3, 0.45])
def test_a_drop_out_is_left_out_of_the_rate_and_a_bursts_pause_is_not(pause_s: float) -> None:
    """60 fps for half a second, a pause, then 60 fps again for 0.3 s (the camera's frames
    of the pause lost): the rate over the latest frames (as a change of rate is measured,
    the longest interval counted half a second) is 1 / the median interval, 60 fps, the
    pause left out (before, one no longer than half a second was counted: 49 intervals
    over 0.8 s and the pause, 0.3 s read 44.5 fps, 0.45 s 39.2 fps; a longer one was left
    out as a stall's, as it still is). A burst is not a drop-out: 30 fps for half a second,
    then the ten frames taken in the next 0.3 s read at once (1 ms apart) when the last was
    taken, then 30 fps: 30 fps, the pause counted with the frames read at once (hand: 30
    intervals in 1 s)."""
    dropped = np.concatenate([np.arange(31) / 60.0, 0.5 + pause_s + np.arange(19) / 60.0])
    gaps = np.diff(dropped)
    assert 1.0 / np.median(gaps) == pytest.approx(60.0)
    assert _frame_rate(dropped.tolist(), CHANGE_WINDOW_S, BURST_S) == pytest.approx(60.0)
    taken = np.arange(31) / 30.0
    came = taken.copy()
    came[16:26] = taken[25] + 0.001 * np.arange(10)  # 0.5 s, then 0.33 s without a frame
    assert came[16] - came[15] == pytest.approx(0.3 + 1 / 30.0)
    assert np.all(np.diff(came) > 0) and came[-1] - came[0] == pytest.approx(1.0)
    assert _frame_rate(came.tolist(), CHANGE_WINDOW_S, BURST_S) == pytest.approx(30.0)


def test_a_rise_with_a_drop_out_before_the_end_is_watched_again_at_its_rate(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """tests/test_hunt52y.py's stream: 15 fps for 2 s (a burst at 1.6 s), then 60 fps, the
    frames taken within 2.55-2.87 s lost (a drop-out, the two frames after it 1/60 s
    apart), the stream ending at 2.88 s. The rise is watched again at the camera's new
    rate, 60 fps (hand: the frames' interval after the rise, 1/60 s); before, at 37.5 fps
    (the frames of the latest 0.8 s over their span, the pause in it: 30 intervals in 0.8
    s)."""
    monkeypatch.setattr("cbr.live.LiveSegmenter", _Segmenter)
    frames = rise_with_a_drop_out()
    args = argparse.Namespace(source="0", max_frames=None, out=None, show=False, k=1)
    watcher = Watcher(None, None, args, None)
    with pytest.raises(DataError, match="the stream ended after"):
        watcher.follow(iter(frames), False, threading.Event())
    assert watcher.live.fps == pytest.approx(60.0)
