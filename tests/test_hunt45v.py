"""Hunt 45v: small defects left by this session's usability fixes (tests/test_hunt45u.py).

1. ``watch`` of a video with nobody in view, stopped by ``--max-frames`` (the user's own
   limit) before the video's end, was refused as "the stream ended after N frames ... with
   nobody in view in any of them": the stream had not ended, and the frames after the limit
   were never watched (the person may come later, as to a camera watching an empty room,
   which is not refused). It now ends with exit 0 and a note saying that ``--max-frames``
   stopped it; a watch stopped by the limit before the first window says so in its refusal;
   a camera lost before the limit is said to be lost (it ended with exit 0 in silence).
2. ``classify``'s note on a jog (steps shorter than a repetition can be, cut by ``train
   --split repetitions`` in left-and-right cycles) said to pair ``reps --json``'s rows "from
   the start_frame of one to the end_frame of the next": of an odd number of steps, the last
   step was then a row of its own, refused as too short, where ``train`` joins it to the
   cycle before. ``reps --json`` now gives ``"cases"``, the pieces ``train`` cuts, and the
   note points at them.
3. ``reps``/``segment``/``describe --plot DIR`` replaced a file already at ``DIR/<clip>.png``
   without a word (another command's picture, another recording's of the same name, the
   user's own). As ``compare --out DIR`` refuses a results file it did not write and
   ``convert --out DIR`` a pose file of another recording, each now replaces only the
   picture it drew there of the same recording before (run again), and refuses any other
   file, one line, before any work. A PNG it draws holds a text chunk ``posecbr`` saying
   which command drew it of which recording (``features.timeline.picture_mark``).
"""

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
from posecbr.cli import main
from tests.badinput import refused
from tests.test_hunt45u import jog_cases  # noqa: F401 - the fixture: a jog's and a squat's
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows


def _grey_video(path: Path, frames: int) -> Path:
    """A lossless video of ``frames`` plain grey frames at 10 fps: nobody in any."""
    from tests.test_video_vfr import _write

    grey = [np.full((120, 160, 3), 90, np.uint8) for _ in range(frames)]
    return _write(path, [100 * k for k in range(frames)], grey, rate=10)


def test_watch_stopped_by_max_frames_with_nobody_seen_is_not_refused(
    case_base: Path,  # noqa: F811 - the fixture imported above
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """40 grey frames at 10 fps watched with ``--max-frames 30``: one segment, nobody in
    view, frames 0-30; exit 0, and a note that the limit stopped the watch. Before: exit 1,
    "the stream ended after 30 frames (3.00 s) with nobody in view in any of them"."""
    video = _grey_video(tmp_path / "empty.mp4", 40)
    capsys.readouterr()
    argv = ["watch", str(video), "--db", str(case_base), "--speed", "0", "--max-frames", "30"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    segments = [json.loads(line) for line in captured.out.splitlines()]
    assert [(s["start_frame"], s["end_frame"], s["unknown"]) for s in segments] == [
        (0, 30, "nobody in view")
    ]
    assert (
        f"note: {video}: nobody in view in the 30 frames (3.00 s) watched (--max-frames 30"
        " stopped the watch: the video's frames after them, if any, were not watched)\n"
    ) in captured.err
    assert "error" not in captured.err and "stream ended" not in captured.err


def test_watch_stopped_by_max_frames_before_a_window_says_the_limit_stopped_it(
    case_base: Path,  # noqa: F811 - the fixture imported above
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """5 frames at 10 fps (0.5 s) are less than the shortest window (1 s): refused, naming
    ``--max-frames`` as what stopped the watch (it said "the stream ended")."""
    video = _grey_video(tmp_path / "empty.mp4", 40)
    argv = ["watch", str(video), "--db", str(case_base), "--speed", "0", "--max-frames", "5"]
    line = refused(argv, tmp_path, capsys)
    assert line == (
        f"posecbr watch: error: {video}: --max-frames 5 stopped the watch after 5 frames"
        " (0.50 s), before the shortest window (1 s) of the stream was seen: no segment to give"
    )


def _camera(n: int, fps: float = 30.0) -> Any:
    """A stand-in for ``stream_poses``: a camera that gives ``n`` frames with nobody in view,
    then none (lost), as tests/test_hunt39m.py's."""

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        limit = kwargs.get("max_frames")
        for i in range(n if limit is None else min(n, limit)):
            pose = FramePose(
                np.full((33, 5), np.nan), np.full((33, 3), np.nan), False, False, 0.0, None
            )
            rgb = np.zeros((48, 64, 3), dtype=np.uint8)
            yield StreamFrame(i, i / fps, pose, rgb, time.perf_counter())

    return stream


@pytest.mark.parametrize(("given", "code"), [(90, 0), (200, 1)])
def test_a_camera_lost_before_max_frames_is_said_lost(
    case_base: Path,  # noqa: F811 - the fixture imported above
    given: int,
    code: int,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera that gives 90 frames then none: with ``--max-frames 90`` the limit stopped
    it (exit 0, an empty room is no bad input); with ``--max-frames 200`` it was lost before
    the limit: "camera or connection lost?", exit 1, as without ``--max-frames`` (before, it
    ended with exit 0 without a word)."""
    monkeypatch.setattr(pose_estimation, "stream_poses", _camera(90))
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--max-frames", str(given)]) == code
    captured = capsys.readouterr()
    lost = "posecbr watch: error: 0: the stream ended after "
    if code:
        summary, error, end = captured.err.split("\n")  # the watch's summary (hunt 52y)
        assert summary.startswith("watched 90 frames in ") and end == "", captured.err
        assert error.startswith(lost), captured.err
        assert error.endswith(" frames (camera or connection lost?)"), captured.err
    else:
        assert "error" not in captured.err, captured.err


def test_classify_note_on_an_odd_jog_gives_rows_that_classify_takes(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    jog_cases: Path,  # noqa: F811 - the fixture imported above
) -> None:
    """The hand-built jog of tests/test_hunt44j.py (step k over frames 9k to 9k + 9, 0.3 s
    at 30 fps) of eight steps beside a squat clip, trained with ``--split repetitions``; a
    jog of nine steps classified whole. Its cycles by hand: steps 0-1, 2-3, 4-5, and the last
    three together (the ninth, 0.3 s, shorter than a case may be, joins the cycle before),
    the last ending with the clip (frame 81 its last): 0-18, 18-36, 36-54, 54-82. Each row
    classified (jog). Before, ``reps --json`` had no ``"cases"``, and the rows the note
    described paired 72-82 with nothing: refused as too short."""
    from features.poses import save_pose
    from tests.test_hunt44j import _jog

    db = str(jog_cases)
    query = save_pose(_jog(9), tmp_path / "query.npz")
    capsys.readouterr()
    assert main(["classify", str(query), "--db", db, "-q"]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "per repetition" in line]
    assert len(notes) == 1 and "(query.npz: 9 in 4 left-and-right cycles)" in notes[0]
    assert 'as train cuts them: the "cases" of reps --json' in notes[0]
    assert main(["reps", str(query), "--json"]) == 0
    cases = json.loads(capsys.readouterr().out)["cases"]
    assert [(c["start_frame"], c["end_frame"], c["repetitions"]) for c in cases] == [
        (0, 18, 2),
        (18, 36, 2),
        (36, 54, 2),
        (54, 82, 3),
    ]
    rows = "".join(f"query.npz,,{c['start_frame']},{c['end_frame']}\n" for c in cases)
    (tmp_path / "cycles.csv").write_text("path,label,start,end\n" + rows)
    assert main(["classify", str(tmp_path / "cycles.csv"), "--db", db, "--json"]) == 0
    answers = json.loads(capsys.readouterr().out)
    assert [a["label"] for a in answers["results"]] == ["jog"] * 4


def test_reps_json_cases_of_squats_are_their_repetitions(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A movement that does not alternate sides: ``"cases"`` are its repetitions, one each,
    with their frames."""
    from features.poses import save_pose
    from tests.moves import clip

    rec = save_pose(clip("squat", 6.0, 30.0), tmp_path / "squat.npz")
    capsys.readouterr()
    assert main(["reps", str(rec), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    reps = [(r["start_frame"], r["end_frame"], 1) for r in doc["repetitions"]]
    assert doc["count"] >= 2 and not doc["alternating"]
    assert [(c["start_frame"], c["end_frame"], c["repetitions"]) for c in doc["cases"]] == reps


def _squats(folder: Path) -> Path:
    from features.poses import save_pose
    from tests.moves import clip

    folder.mkdir(parents=True, exist_ok=True)
    return save_pose(clip("squat", 3.0, 30.0), folder / "squats.npz")


@pytest.mark.parametrize("there", ["describe", "text", "other recording"])
def test_reps_plot_folder_refuses_a_file_there_it_did_not_draw(
    there: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """pics/squats.png is already there: ``describe``'s picture of the same clip, a text
    file of the user's, or ``reps``'s picture of another folder's squats.npz. ``reps
    squats.npz --plot pics`` refuses it in one line and changes nothing (before: replaced
    it, exit 0)."""
    rec = _squats(tmp_path)
    pics = tmp_path / "pics"
    pics.mkdir()
    if there == "describe":
        assert main(["describe", str(rec), "--plot", str(pics)]) == 0
    elif there == "text":
        (pics / "squats.png").write_text("my notes\n")
    else:
        assert main(["reps", str(_squats(tmp_path / "other")), "--plot", str(pics)]) == 0
    capsys.readouterr()
    line = refused(["reps", str(rec), "--plot", str(pics)], tmp_path, capsys)
    assert line == (
        f"posecbr reps: error: {pics / 'squats.png'}: is already there, not a picture posecbr"
        f" reps drew of squats.npz: --plot {pics} would replace it; choose another folder, or"
        " name the picture"
    )


def test_segment_plot_folder_refuses_a_picture_reps_drew(
    case_base: Path,  # noqa: F811 - the fixture imported above
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``segment`` of a clip whose picture ``reps`` drew into the folder: refused, one line,
    nothing written (before: the repetitions' picture replaced by the segments')."""
    rec = _squats(tmp_path)
    pics = tmp_path / "pics"
    pics.mkdir()
    assert main(["reps", str(rec), "--plot", str(pics)]) == 0
    capsys.readouterr()
    argv = ["segment", str(rec), "--db", str(case_base), "--plot", str(pics)]
    refused(argv, tmp_path, capsys, "not a picture posecbr segment drew of squats.npz")


def test_plot_folder_replaces_the_picture_the_same_command_drew_and_marks_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Run again, ``reps --plot pics`` and ``describe --plot pics`` bring their own picture
    up to date (exit 0). The mark read by Pillow (a peer PNG reader): the command and the
    first 16 hex digits of the SHA-256 of the recording's resolved path, worked out here."""
    import hashlib

    from PIL import Image

    rec = _squats(tmp_path)
    digest = hashlib.sha256(str(rec.resolve()).encode()).hexdigest()[:16]
    for command in ("reps", "describe"):
        pics = tmp_path / command
        pics.mkdir()
        for _ in range(2):
            assert main([command, str(rec), "--plot", str(pics)]) == 0
            assert f"written to {pics / 'squats.png'}" in capsys.readouterr().err
        with Image.open(pics / "squats.png") as picture:
            assert picture.text["posecbr"] == f"{command} {digest}"
    # a picture the user names is theirs to replace: another command's, as before
    assert main(["reps", str(rec), "--plot", str(tmp_path / "describe" / "squats.png")]) == 0
