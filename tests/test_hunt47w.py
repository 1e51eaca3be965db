"""Hunt 47w: ``watch`` at the start of a stream with nobody in view.

1. A video whose first exactly 1.0 s shows nobody: ``segment`` gives that second as a
   segment with nobody in view (every 0.1-s block from the first is judged), ``watch`` did
   not: its first decision is of the middle of its first 2-s window, one second in, just
   past the lead-in, so no hop lay in it and it joined the first segment, unknown by its
   half-empty windows ("like no stored activity"). Now the stream's first segment is the
   lead-in, as offline.
2. A stream shorter than its first window (1-2 s) in which no frame shows the person was
   refused with the wording of a recording too short to follow ("no person in view in
   enough frames to follow a movement (joint angles missing)"), even from a camera or when
   ``--max-frames`` stopped it, where a longer one gives a segment with nobody in view. Now
   it gives that segment too, and a video file watched whole is refused as a longer one is.
   ``segment`` refuses a recording with nobody in any frame saying that it shows no person,
   as ``reps`` does (it too said "joint angles missing", whatever its length):
   tests/test_hunt22.py's recording of no joints.

The videos are the still scene of ``tests/empty_scene.py`` (at the clip's size), then the
bundled 5-fps squat clip's own frames, lossless.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from posecbr.cli import main
from tests.badinput import snapshot
from tests.empty_scene import empty_scene, still_scene
from tests.test_video_vfr import _write
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows

SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"  # 720x1280, 5 fps


def _lead_in(shared_data: Path, path: Path, empty: int, shown: int) -> Path:
    """``empty`` frames of the still scene, then the squat clip's first ``shown`` frames, at
    the clip's 5 fps, FFV1 (lossless: every run decodes the same pixels)."""
    from itertools import islice

    import av

    with av.open(str(shared_data / SQUAT)) as clip:
        frames = [f.to_ndarray(format="rgb24") for f in islice(clip.decode(video=0), shown)]
    height, width = frames[0].shape[:2]
    frames = [still_scene(width, height)] * empty + frames
    return _write(path, [200 * k for k in range(len(frames))], frames, rate=5, codec="ffv1")


def _spans(segments: list[dict[str, object]]) -> list[tuple[object, ...]]:
    return [(s["start_frame"], s["end_frame"], s["unknown"]) for s in segments]


def test_watch_gives_a_lead_in_of_exactly_a_second_as_segment_does(
    case_base: Path,  # noqa: F811 - the fixture imported above
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """5 frames of nobody (exactly 1.0 s at 5 fps), then 5 of the squat clip: ``watch``
    gives frames 0-5 as nobody in view, then the person from frame 5, the segments
    ``segment`` gives the same video. Before, ``watch`` gave one segment, 0-10, unknown
    ("like no stored activity")."""
    video = _lead_in(shared_data, tmp_path / "lead.mkv", 5, 5)
    capsys.readouterr()
    assert main(["watch", str(video), "--db", str(case_base), "--speed", "0"]) == 0
    watched = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert main(["segment", str(video), "--db", str(case_base), "--json"]) == 0
    offline = json.loads(capsys.readouterr().out)["segments"]
    assert _spans(watched)[0] == (0, 5, "nobody in view")
    assert watched[0]["explanation"] == "nobody in view" and watched[0]["repetitions"] == 0
    assert _spans(watched) == _spans(offline)
    assert [s["start_s"] for s in watched] == [s["start_s"] for s in offline] == [0.0, 1.0]


def test_a_stream_shorter_than_a_window_showing_nobody_is_nobody_in_view(
    case_base: Path,  # noqa: F811 - the fixture imported above
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """1.5 s of the empty scene at 10 fps (its first window is 2 s), watched whole: one
    segment, frames 0-15, nobody in view, printed, then refused as a longer video with
    nobody in it is, one line, exit 1, nothing written (stopped by ``--max-frames`` it ends
    with exit 0 and a note, as a longer one: tests/test_watch.py). Before, refused "no person
    in view in enough frames to follow a movement (joint angles missing)", no segment."""
    video = empty_scene(tmp_path / "empty.mkv", 15)
    before = snapshot(tmp_path)
    capsys.readouterr()
    argv = ["watch", str(video), "--db", str(case_base), "--speed", "0"]
    assert main(argv) == 1
    printed = capsys.readouterr()
    assert _spans([json.loads(line) for line in printed.out.splitlines()]) == [
        (0, 15, "nobody in view")
    ]
    assert printed.err == (
        f"posecbr watch: error: {video}: the stream ended after 15 frames (1.50 s) with nobody"
        " in view in any of them: no activity to label\n"
    )
    assert snapshot(tmp_path) == before


def test_a_short_stream_of_nobody_from_python(
    case_base: Path,  # noqa: F811 - the fixture imported above
) -> None:
    """The library, as a camera's frames reach it: 1.5 s of frames with nobody (NaN) at 10
    fps, then finish(): one segment with nobody in view, 0-15 (it raised DataError)."""
    from casebase_store import open_store
    from cbr.live import LiveSegmenter
    from cbr.stored import load_classifier

    with open_store(case_base, readonly=True) as store:
        clf = load_classifier(store, "default").classifier
    live = LiveSegmenter(clf, 10.0, source="camera 0")
    for _ in range(15):
        assert live.push(np.full((33, 3), np.nan)) == []
    done = live.finish()
    assert [(s.start_frame, s.end_frame, s.label, s.repetitions, s.explanation) for s in done] == [
        (0, 15, None, 0, "nobody in view")
    ]
