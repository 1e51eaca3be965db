"""Session 53, task D: two faults of ``watch``'s live figures.

- ``watch --progress``: while the person holds still at the end of a segment, the decoders
  settle nothing (no window of the hold votes for any activity), so the progress lines'
  label and count stand still though time goes on; each line now says the person holds
  still, and since when (``"still_s"``), and still says no more than the finished line.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from features.readers.asfamc import read_asf_amc
from tests.once import made_once
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
