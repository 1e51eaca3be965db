"""``posecbr watch``: a real video played through BlazePose, and streams that stall or end
(a stand-in for a camera: real CMU mocap poses delivered frame by frame)."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest

import features.pose_estimation as pose_estimation
from features.pose_estimation import StreamFrame
from features.pose_estimation.tracker import FramePose
from features.readers.asfamc import read_asf_amc
from posecbr.cli import main
from tests.badinput import snapshot
from tests.empty_scene import empty_scene
from tests.once import made_once
from tests.test_hunt34c import _Quiet, _serving

if TYPE_CHECKING:
    from features.poses import PoseSequence


def _cmu_13_29_windows(folder: Path, shared_data: Path) -> Path:
    """Windows of CMU 13_29 (six exercises), trained by the command into ``folder``."""
    names = folder / "names.txt"
    names.write_text("1 JumpJack\n3 Squat\n4 KneeRaise\n5 ArmCircle\n6 Twist\n10 ToeTouch\n")
    from features.poses import save_pose

    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_29.amc",
    )
    pose = save_pose(seq, folder / "13_29.npz")
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_29.txt"
    db = folder / "cb.sqlite"
    argv = ["train", str(pose), "--frame-labels", str(labels), "--label-block", "0.1",
            "--label-names", str(names), "--split", "windows", "--db", str(db)]  # fmt: skip
    assert main(argv) == 0
    return db


@pytest.fixture(scope="module")
def case_base(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Windows of CMU 13_29 (six exercises), trained by the command: made once in the
    session for this module, tests/test_hunt34f.py and tests/test_video_gaps.py, which only
    read it (or copy it)."""
    return made_once(
        tmp_path_factory,
        "cmu-13-29-windows",
        lambda folder: _cmu_13_29_windows(folder, shared_data),
    )


def test_watch_a_real_video(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import cv2

    video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    out = tmp_path / "watched.mp4"
    capsys.readouterr()
    # the case base is one mocap recording of another person, the default judge
    # (activity-margin): the 2-s windows of these 4.8-s squats (at 5 fps) waver with the
    # squat's phase between squat, knee raise and unlike every activity, so the segments do
    # too; between them they cover the video once and count each of its squats
    assert main(["watch", str(video), "--db", str(case_base), "--out", str(out),
                 "--speed", "0"]) == 0  # fmt: skip
    captured = capsys.readouterr()
    lines = [json.loads(line) for line in captured.out.splitlines()]
    assert lines, "one JSON line per finished segment"
    assert lines[0]["start_frame"] == 0 and lines[-1]["end_frame"] == 65
    for a, b in zip(lines[:-1], lines[1:], strict=True):
        assert a["end_frame"] == b["start_frame"]
    assert {line["label"] for line in lines} <= {"Squat", "KneeRaise", None}, lines
    # three squats by hand (tests/fixtures/repetition_counts.json); segments shorter than a
    # squat each count the squat they cut, so one may be counted twice (the README quotes
    # four segments adding to 3, and six adding to 4 before; offline, counted on the
    # recording's own signals, none is: below)
    assert sum(line["repetitions"] for line in lines) >= 3
    assert "latency frame to label: median" in captured.err
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 65
    cap.release()


@pytest.fixture(scope="module")
def nobody(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding empty.mkv, 3 s of a still scene with nobody in it at 10 fps."""
    folder = tmp_path_factory.mktemp("nobody")
    empty_scene(folder / "empty.mkv", 30)
    return folder


def test_watch_a_scene_with_nobody_in_view(
    case_base: Path, nobody: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The first 2 s of a scene with nobody in it: one segment, unknown, told "nobody in
    view", counted 0, over every frame watched, printed as it finished; exit 0 with a note:
    ``--max-frames`` stopped the watch before the video's end (tests/test_hunt45v.py; it was
    refused as a video with nobody in it, "the stream ended", though the rest was not
    watched)."""
    video = nobody / "empty.mkv"
    capsys.readouterr()
    assert main(["watch", str(video), "--db", str(case_base), "--max-frames", "20",
                 "--speed", "0"]) == 0  # fmt: skip
    captured = capsys.readouterr()
    assert (
        f"note: {video}: nobody in view in the 20 frames (2.00 s) watched (--max-frames 20"
        " stopped the watch: the video's frames after them, if any, were not watched)\n"
    ) in captured.err
    lines = [json.loads(line) for line in captured.out.splitlines()]
    assert [(d["start_frame"], d["end_frame"], d["label"], d["unknown"], d["repetitions"],
             d["explanation"]) for d in lines] == [
        (0, 20, None, "nobody in view", 0, "nobody in view")]  # fmt: skip


def _squat_segments(
    factory: pytest.TempPathFactory, case_base: Path, shared_data: Path, judge: str
) -> list[dict[str, Any]]:
    """The segments ``posecbr segment --json`` gives the squat video by ``judge``: made once
    in the session (two tests read the margin judge's)."""

    def make(folder: Path) -> list[dict[str, Any]]:
        import contextlib
        import io

        video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
        argv = ["segment", str(video), "--db", str(case_base), "--json", "--unknown", judge]
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            assert main(argv) == 0
        segments: list[dict[str, Any]] = json.loads(out.getvalue())["segments"]
        return segments

    return made_once(factory, f"squat-segments-{judge}", make)


@pytest.mark.parametrize("judge", ["activity-margin", "margin"])
def test_segment_the_same_video_counts_each_squat_once(
    case_base: Path, shared_data: Path, judge: str, tmp_path_factory: pytest.TempPathFactory
) -> None:
    """The offline segmentation of the video above, by the default judge and by the margin
    (which leaves its windows wavering as above: several segments): its segments each last
    at least MIN_SEGMENT_S, no sliver between an unknown stretch and a change of activity,
    and hold the three squats once between them."""
    from cbr.segmentation import MIN_SEGMENT_S

    segments = _squat_segments(tmp_path_factory, case_base, shared_data, judge)
    assert judge != "margin" or len(segments) > 1, segments  # the wavering
    assert all(s["end_s"] - s["start_s"] >= MIN_SEGMENT_S for s in segments), segments
    assert sum(s["repetitions"] for s in segments) == 3, segments
    # an unknown segment's confidence is its evidence of unknown, never 0 for the verdict it
    # gives (it was the share of its own windows unlike: 0.00 for one unknown on the evidence
    # around it)
    assert all(s["confidence"] > 0.0 for s in segments if s["label"] is None), segments


def test_the_readme_quotes_the_segments_of_the_squat_video(
    case_base: Path, shared_data: Path, tmp_path_factory: pytest.TempPathFactory
) -> None:
    """README ("Live") quotes what `segment` makes of the 5-fps squat video with this case
    base, by the default judge and by the margin judge; it said five segments counting
    0 + 1 + 1 + 0 + 1 and, by the margin judge, three counting 2 + 0 + 1, which the code had
    not given since ff44302 (4 December: repetitions bounded where the movement leaves and
    returns to rest, which moved the repetition windows; hunt 38v). What it gives is written
    here from a run of the command and read back from the README."""
    found = {}
    for judge in ("spread-margin", "margin"):
        segments = _squat_segments(tmp_path_factory, case_base, shared_data, judge)
        found[judge] = [(s["label"], s["repetitions"]) for s in segments]
    assert found["spread-margin"] == [("KneeRaise", 2), (None, 0), ("Squat", 1)]
    assert found["margin"] == [("KneeRaise", 2), ("Squat", 1)]
    readme = " ".join((Path(__file__).resolve().parents[1] / "README.md").read_text().split())
    assert (
        "`segment` on the same video, counted on the recording's own signals: three segments "
        "(knee raise, unknown, squat) counting 2 + 0 + 1 = 3 (by the margin judge, two "
        "segments, knee raise and squat, counting 2 + 1 = 3;"
    ) in readme


def test_watch_sees_the_joints_that_segment_sees(
    case_base: Path,
    shared_data: Path,
    lunge_poses: PoseSequence,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """One slow reverse lunge (counted by hand: tests/fixtures/repetition_counts.json), filmed
    with the feet often below the frame's edge: ``watch`` must count it once, as ``segment``
    does on the same video, and give the same segments. It counted 3: the stream kept the
    model's guesses for joints outside the frame and joints it did not see (visibility below
    0.5), which ``extract`` and ``segment`` leave missing. ``segment`` reads the video's poses
    as extract finds them (the session's): its --json of the video, but for the path
    (checked), without the pose model again."""
    from features.poses import save_pose

    video = shared_data / "videos" / "lunge" / "fit_reverse_lunge_pexels8233047.mp4"
    poses = save_pose(lunge_poses, tmp_path / "fit_reverse_lunge_pexels8233047.npz")
    capsys.readouterr()
    # headless without --out: nothing drawn (the drawing is another test's)
    assert main(["watch", str(video), "--db", str(case_base), "--speed", "0"]) == 0
    watched = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert main(["segment", str(poses), "--db", str(case_base), "--json"]) == 0
    offline = json.loads(capsys.readouterr().out)["segments"]
    assert sum(d["repetitions"] for d in watched) == 1, watched

    def spans(segments: list[dict[str, Any]]) -> list[tuple[Any, ...]]:
        keys = ("start_frame", "end_frame", "label", "repetitions")
        return [tuple(d[k] for k in keys) for d in segments]

    assert spans(watched) == spans(offline)


def _mocap_stream(shared_data: Path, n: int, then: str, fps: float = 30.0) -> Any:
    """A stand-in for ``stream_poses``: real poses (13_30 at 120 fps, every 4th frame) as a
    camera would deliver them; after ``n`` frames it stalls ("stall") or stops ("end")."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    world = seq.positions[::4]

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        for i in range(n):
            image = np.full((33, 5), np.nan)
            image[:, 3] = 1.0  # every joint seen (mocap)
            pose = FramePose(image, world[i], True, False, 1.0, None)
            rgb = np.zeros((48, 64, 3), dtype=np.uint8)
            yield StreamFrame(i, i / fps, pose, rgb, time.perf_counter())
        if then == "stall":
            time.sleep(30)

    return stream


def test_watch_refuses_a_stream_that_stalls(
    case_base: Path,
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera that sends 90 frames and then nothing past ``--stall``: the watch's summary
    (the 90 frames watched, their latency), then one line saying it stalled and that the
    video of the 90 frames watched was written, exit 1 (the watch did
    not end as asked); the video is finished, every one of the 90 frames in it, and no
    temporary is left. (The hour's video was dropped as if half-written.)"""
    import cv2

    monkeypatch.setattr(pose_estimation, "stream_poses", _mocap_stream(shared_data, 90, "stall"))
    out = tmp_path / "out.mp4"
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--stall", "0.5", "--out", str(out)]) == 1
    summary, error, end = capsys.readouterr().err.split("\n")
    assert summary.startswith("watched 90 frames in ") and "latency frame to label" in summary
    assert error + end == (
        "posecbr watch: error: 0: the stream stalled: no frame for 0.5 s; the video of the 90"
        f" frames watched was written to {out}"
    )
    assert list(tmp_path.iterdir()) == [out]  # no temporary left
    cap = cv2.VideoCapture(str(out))
    decoded = 0
    while cap.read()[0]:
        decoded += 1
    cap.release()
    assert decoded == 90


def test_watch_reports_a_camera_that_stops_sending(
    case_base: Path,
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr(pose_estimation, "stream_poses", _mocap_stream(shared_data, 120, "end"))
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base)]) == 1
    captured = capsys.readouterr()
    summary, error, end = captured.err.split("\n")  # the watch's summary, then the loss
    assert summary.startswith("watched 120 frames in ") and end == ""
    assert "the stream ended after 120 frames" in error


def test_watch_a_stream_to_its_end_with_max_frames(
    case_base: Path,
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Asked for 120 frames of a camera: the finished segments cover them, with labels of the
    case base (or unknown), each line a finished segment's as without ``--progress``, and the
    latency is reported."""
    monkeypatch.setattr(pose_estimation, "stream_poses", _mocap_stream(shared_data, 120, "end"))
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "--max-frames", "120"]) == 0
    captured = capsys.readouterr()
    lines = [json.loads(line) for line in captured.out.splitlines()]
    assert lines[-1]["end_frame"] == 120
    # without --progress, each line a finished segment's, no "event" (tests/test_hunt52u.py)
    assert all("event" not in line for line in lines)
    known = {"JumpJack", "Squat", "KneeRaise", "ArmCircle", "Twist", "ToeTouch", None}
    assert {line["label"] for line in lines} <= known
    assert "latency frame to label" in captured.err


def test_watch_refuses_a_missing_file(case_base: Path, tmp_path: Path, capsys: Any) -> None:
    assert main(["watch", str(tmp_path / "none.mp4"), "--db", str(case_base)]) == 1
    assert "no such video file" in capsys.readouterr().err


SPEED = "must be 0 (as fast as possible) or a number >= 0.01"
STALL = "must be > 0 seconds and at most 86400 (a day)"


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--speed", "nan", f"--speed: {SPEED}, got nan"),
        ("--speed", "inf", f"--speed: {SPEED}, got inf"),
        ("--speed", "-1", f"--speed: {SPEED}, got -1"),
        # a wait of 1e300 s overflowed the clock: a traceback
        ("--speed", "1e-300", f"--speed: {SPEED}, got 1e-300"),
        ("--stall", "0", f"--stall: {STALL}, got 0"),
        ("--stall", "inf", f"--stall: {STALL}, got inf"),
        ("--stall", "1e300", f"--stall: {STALL}, got 1e+300"),
        ("--max-frames", "0", "--max-frames: must be >= 1, got 0"),
    ],
)
def test_watch_refuses_options_it_cannot_follow(
    shared_data: Path, tmp_path: Path, capsys: Any, option: str, value: str, message: str
) -> None:
    """One line naming the option once ("--speed: --speed must be >= 0"); a --speed of nan
    or inf played the video as fast as it could, exit 0. Refused before the case base is
    opened (there is none here)."""
    video = next((shared_data / "videos").rglob("*.mp4"))
    argv = ["watch", str(video), "--db", str(tmp_path / "none.sqlite"), option, value]
    before = video.read_bytes()
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err == f"posecbr watch: error: {message}\n"
    assert video.read_bytes() == before and list(tmp_path.iterdir()) == []


def test_watch_of_a_pose_file_points_to_segment(tmp_path: Path, capsys: Any) -> None:
    """A pose file is a recording, not a video ("not a video OpenCV can decode" said what
    it is not): one line saying which command reads it, before the case base is opened."""
    pose = tmp_path / "13_30.npz"
    pose.write_bytes(b"not read")
    assert main(["watch", str(pose), "--db", str(tmp_path / "none.sqlite")]) == 1
    assert pose.read_bytes() == b"not read" and sorted(tmp_path.iterdir()) == [pose]
    err = capsys.readouterr().err
    assert err == (
        f"posecbr watch: error: {pose}: watch plays videos, cameras and streams; segment this "
        "recording with posecbr segment\n"
    )


def test_watch_that_stalls_leaves_the_earlier_video(
    case_base: Path,
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The --out video of an earlier watch stays as it was when this one stalls before
    its first frame is drawn (nothing watched: no video, not an empty one)."""
    monkeypatch.setattr(pose_estimation, "stream_poses", _mocap_stream(shared_data, 0, "stall"))
    out = tmp_path / "out.mp4"
    out.write_bytes(b"the earlier video")
    assert main(["watch", "0", "--db", str(case_base), "--stall", "0.5", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err == "posecbr watch: error: 0: the stream stalled: no frame for 0.5 s\n"
    assert out.read_bytes() == b"the earlier video"
    assert list(tmp_path.iterdir()) == [out]  # no temporary left


def test_live_decoder_on_real_mocap_names_the_exercises_in_their_stretches(
    case_base: Path, shared_data: Path
) -> None:
    """CMU 13_30 (another recording of the same person) streamed at 30 fps into the live
    decoder with the case base of 13_29, which lacks 13_30's last exercise (jogging): the
    segments follow the label file's stretches (jumping jacks, twists, knee raises, squats,
    then jogging), at least 90 % of the blocks of the exercises it has right, and the
    jogging unknown from where its windows stop resembling knee raises: more than half of its
    blocks (before the one-person floor, :func:`cbr.unknown.one_person_floor`, was raised to
    catch 80 % of held-out novel cases, the jogging was all knee raises)."""
    from casebase_store import open_store
    from cbr.live import LiveSegmenter
    from cbr.stored import load_classifier

    store = open_store(str(case_base), readonly=True)
    clf = load_classifier(store, store.list_case_bases()[0].name).classifier
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    codes = np.array(labels.read_text().split(), dtype=int)  # per 0.1 s; 2 is jogging
    names = {1: "JumpJack", 3: "Squat", 4: "KneeRaise", 6: "Twist"}  # as the case base's
    truth = np.array([names.get(int(c)) for c in codes], dtype=object)
    seen = np.isin(codes, list(names))

    live = LiveSegmenter(clf, 30.0)  # the default judge
    segments = []
    for frame in seq.positions[::4]:  # 120 fps streamed at 30
        segments += live.push(frame)
        now = live.current()  # what watch draws on every frame
        assert now is None or (now.end_frame == live.n and now.label == live.label)
    segments += live.finish()
    blocks = np.full(len(codes), "", dtype=object)
    for s in segments:
        blocks[round(s.start_frame / 3) : round(s.end_frame / 3)] = s.label  # 3 frames a block
    assert np.mean(blocks[seen] == truth[seen]) >= 0.9
    labels = [s.label for s in segments]
    assert labels == ["JumpJack", "Twist", "KneeRaise", "Squat", "KneeRaise", None], labels
    assert np.mean([b is None for b in blocks[codes == 2]]) > 0.5
    # each explained as segment explains it: its nearest cases, or why it is like none
    for s in segments:
        text = "like no stored activity" if s.label is None else f"most similar cases are {s.label}"
        assert text in s.explanation, s.explanation
    assert all(np.isfinite(s.novelty) for s in segments)
    # unknown stretches live: tests/test_live.py (scripted) and benchmarks.segment_live


def test_a_stream_that_never_shows_anybody_is_one_unknown_segment(case_base: Path) -> None:
    """Three seconds with nobody in view (every joint missing): every window votes every
    activity alike and is as likely known as not, so the tie must not fall to an activity:
    one segment, unknown, no repetitions."""
    from casebase_store import open_store
    from cbr.live import LiveSegmenter
    from cbr.stored import load_classifier

    store = open_store(str(case_base), readonly=True)
    clf = load_classifier(store, store.list_case_bases()[0].name).classifier
    live = LiveSegmenter(clf, 30.0)
    segments = []
    for _ in range(90):
        segments += live.push(np.full((33, 3), np.nan))
        assert live.label is None
    segments += live.finish()
    assert [
        (s.start_frame, s.end_frame, s.label, s.repetitions, s.explanation) for s in segments
    ] == [(0, 90, None, 0, "nobody in view")]


@pytest.fixture
def served(nobody: Path) -> Iterator[str]:
    """The address of a folder holding empty.mkv (a scene with nobody in it, 10 fps) served
    over HTTP on this machine (a stream URL)."""
    with _serving(nobody) as url:
        yield url


def test_watch_a_stream_url(
    case_base: Path, served: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A scene with nobody in it served over HTTP, a file whose length OpenCV knows, so timed
    by its own frame rate (10 fps) as the file is: its first 20 frames are one segment with
    nobody in view, 0-2 s. A URL with nothing behind it: one line naming it, exit 1. (A URL
    was taken for a camera index: a traceback.)"""
    capsys.readouterr()
    url = f"{served}/empty.mkv"
    argv = ["watch", url, "--db", str(case_base), "--max-frames", "20", "--speed", "0"]
    # nobody in view in the 20 frames watched: --max-frames stopped it before the video's
    # end, so not refused (tests/test_hunt45v.py), a note says so
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert f"note: {url}: nobody in view in the 20 frames (2.00 s) watched" in captured.err
    lines = [json.loads(line) for line in captured.out.splitlines()]
    got = [
        (d["start_frame"], d["end_frame"], d["end_s"], d["label"], d["explanation"]) for d in lines
    ]
    assert got == [(0, 20, 2.0, None, "nobody in view")]
    assert main(["watch", f"{served}/none.avi", "--db", str(case_base)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{served}/none.avi: the server answered HTTP 404" in err


def test_watch_a_stream_shorter_than_a_window_says_so(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Four frames of the 5-fps squat video (0.8 s; segment takes 1 s or more): no segment
    can be given, so one line says why (--max-frames stopped it: tests/test_hunt45v.py),
    exit 1, and no --out video (it printed nothing, exit 0)."""
    video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    out = tmp_path / "out.mp4"
    capsys.readouterr()
    argv = ["watch", str(video), "--db", str(case_base), "--max-frames", "4", "--out", str(out)]
    assert main([*argv, "--speed", "0"]) == 1
    captured = capsys.readouterr()
    # one line, beside the note that the video's 5 fps may miscount repetitions
    errors = [line for line in captured.err.splitlines() if not line.startswith("note: ")]
    assert captured.out == "" and len(errors) == 1
    assert (
        "--max-frames 4 stopped the watch after 4 frames (0.80 s), before the shortest window"
        " (1 s)" in errors[0]
    )
    assert list(tmp_path.iterdir()) == []


def test_watch_a_stream_shorter_than_its_first_window_segments_it_as_segment_does(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The first 8 frames (1.6 s) of the 5-fps squat video: ``segment`` gives its segments
    (it takes 1 s or more), ``watch`` refused the stream ("before one window (2 s)")."""
    import cv2

    cap = cv2.VideoCapture(
        str(shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4")
    )
    frames = [cap.read()[1] for _ in range(8)]
    cap.release()
    short = tmp_path / "short.mp4"
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(short), cv2.VideoWriter_fourcc(*"mp4v"), 5.0, (w, h))
    for f in frames:
        writer.write(f)
    writer.release()
    capsys.readouterr()
    assert main(["segment", str(short), "--db", str(case_base), "--json"]) == 0
    offline = json.loads(capsys.readouterr().out)["segments"]
    assert main(["watch", str(short), "--db", str(case_base), "--speed", "0"]) == 0
    live = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    keys = ("start_frame", "end_frame", "label")
    assert [[s[k] for k in keys] for s in live] == [[s[k] for k in keys] for s in offline]
    assert live[0]["start_frame"] == 0 and live[-1]["end_frame"] == 8


def _watch(argv: list[str]) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "posecbr", "watch", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_a_watch_that_stalls_exits_with_one_line_not_an_abort(
    case_base: Path, silent_server: str, tmp_path: Path
) -> None:
    """A real process watching a server that accepts and never sends a frame, ``--stall
    0.5``: the stall is reported in one line naming the source, exit 1, no video. (The reader
    thread was left inside onnxruntime as Python shut down: "terminate called without an
    active exception", exit 134. It stalled then on a file while the pose model loaded; the
    model now loads before the stall clock runs, so a real stall stands in.)"""
    out = tmp_path / "out.mp4"
    run = _watch([silent_server, "--db", str(case_base), "--stall", "0.5", "--out", str(out)])
    stdout, stderr = run.communicate(timeout=120)
    assert run.returncode == 1, stderr
    assert (
        stderr == f"posecbr watch: error: {silent_server}: the stream stalled: no frame for 0.5 s\n"
    )
    assert stdout == "" and list(tmp_path.iterdir()) == []


def test_ctrl_c_ends_a_watch_as_the_end_of_the_stream_does(
    case_base: Path, shared_data: Path, tmp_path: Path
) -> None:
    """A real process watching the squat video at its own rate (13 s), sent SIGINT (Ctrl-C)
    once it has printed its first segment: it finishes the frame in hand, prints the segment
    in progress and the latency, writes the --out video with every frame it watched, exit 0.
    (Ctrl-C could land between writing a frame and counting it: "28 frames encoded but 29
    read back", the video dropped; or abort the process, exit 134.)"""
    import cv2

    video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    out = tmp_path / "out.mp4"
    run = _watch([str(video), "--db", str(case_base), "--out", str(out)])
    assert run.stdout is not None
    # the first segment ends near frame 12 of 65 (2.4 s): a window seen, about 10 s of the
    # video still to come however slowly the machine runs it. (A fixed 9.5 s after the first
    # frame drawn saw 1 frame on one busy core, 2 runs of 3: "the stream ended after 1
    # frame", exit 1.)
    first = run.stdout.readline()
    run.send_signal(signal.SIGINT)
    stdout, stderr = run.communicate(timeout=120)
    assert run.returncode == 0, stderr
    watched = int(stderr.split("watched ")[1].split(" frame")[0])
    assert 0 < watched < 65 and "latency frame to label" in stderr, stderr
    lines = [json.loads(line) for line in (first + stdout).splitlines()]
    assert lines and lines[-1]["end_frame"] == watched
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == watched
    cap.release()


def test_a_second_ctrl_c_interrupts_at_once() -> None:
    """Within a watch, the first SIGINT only sets the stop event; the second raises
    KeyboardInterrupt (the user does not want to wait); after it, SIGINT is handled as
    before."""
    import os

    from posecbr.commands.watch import stop_on_interrupt

    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt), stop_on_interrupt() as stop:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)  # the handler runs in this (the main) thread between bytecodes
        assert stop.is_set()
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)
        pytest.fail("the second Ctrl-C did not interrupt")
    assert signal.getsignal(signal.SIGINT) is before


def test_ctrl_c_during_a_long_wait_for_a_frame_ends_the_watch_there() -> None:
    """A file's next frame due 30 s on (a gap in a variable-frame-rate screen recording, or
    ``--speed 0.01``): Ctrl-C ends the wait and the stream there, as the end of the file
    does, instead of after the 30 s (the watch saw the Ctrl-C only with the next frame)."""
    import os

    from posecbr.commands.watch import Pacer, frames_in_background, stop_on_interrupt

    pacer = Pacer(10.0, 1.0)

    def frames() -> Iterator[int]:
        for i, t in enumerate([0.0, 30.0]):
            if not pacer(i, t):
                return
            yield i

    got = []
    with stop_on_interrupt(pacer.stop) as stop:
        for f in frames_in_background(frames(), 60.0, pacer, "screen.mkv"):
            got.append(f)
            threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT)).start()
    assert got == [0] and stop.is_set()


def _cut_avi(folder: Path) -> Path:
    """``folder/cut.avi``: an MJPG AVI of 60 frames cut to two thirds of its bytes (its
    header still says 60 frames), beside the whole one, ``folder/whole.avi``."""
    import cv2

    whole = folder / "whole.avi"
    writer = cv2.VideoWriter(str(whole), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (96, 96))
    rng = np.random.default_rng(0)
    for _ in range(60):
        writer.write(rng.integers(0, 255, (96, 96, 3), dtype=np.uint8))
    writer.release()
    cut = folder / "cut.avi"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size * 2 // 3])
    return cut


def _decoded(path: Path) -> int:
    """How many frames OpenCV decodes of the video ``path``."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    count = 0
    while cap.read()[0]:
        count += 1
    cap.release()
    return count


def test_watch_refuses_a_truncated_video_as_segment_does(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An MJPG AVI of 60 frames cut to two thirds of its bytes: its index still says 60.
    ``segment`` and ``reps`` refused it ("decoded 40 of 60 frames"); ``watch`` watched what
    decoded, exit 0, and wrote its --out video. Refused as they refuse it, one line, exit 1,
    and the --out video of the frames watched is written, as for a stream that stalls, every
    frame OpenCV decodes of the cut file in it (hunt 50d; it was dropped)."""
    cut = _cut_avi(tmp_path)
    given = cut.read_bytes()
    decoded = _decoded(cut)
    out = tmp_path / "out.mp4"
    capsys.readouterr()
    assert main(["watch", str(cut), "--db", str(case_base), "--speed", "0", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "truncated or corrupt: decoded" in err and str(cut) in err
    assert err.endswith(f"; the video of the {decoded} frames watched was written to {out}\n")
    assert cut.read_bytes() == given
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.avi", "out.mp4", "whole.avi"]
    assert _decoded(out) == decoded


def test_watch_refuses_a_truncated_video_served_over_http(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The cut MJPG AVI of the test above, served over HTTP (a file whose frame count OpenCV
    knows, so played as a file): refused as the file is, one line naming the URL, exit 1,
    and the --out video of the frames watched written, as the file's is (hunt 50d: there
    was none). (A served file was watched to where it broke off, exit 0.)"""
    decoded = _decoded(_cut_avi(tmp_path))
    before = snapshot(tmp_path)
    out = tmp_path / "out" / "out.mp4"
    out.parent.mkdir()
    capsys.readouterr()
    with _serving(tmp_path) as address:
        url = f"{address}/cut.avi"
        argv = ["watch", url, "--db", str(case_base), "--speed", "0", "--out", str(out)]
        assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{url}: truncated or corrupt: decoded" in err
    assert err.endswith(f"; the video of the {decoded} frames watched was written to {out}\n")
    assert [p.name for p in out.parent.iterdir()] == ["out.mp4"] and _decoded(out) == decoded
    after = snapshot(tmp_path)
    assert {k: v for k, v in after.items() if not k.startswith("out")} == before  # as they were


def test_watch_of_a_short_video_with_nobody_in_it_names_the_video(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """1.6 s of noise (40 frames, shorter than the first window; nobody in any): a segment
    with nobody in view, and the note naming the video (it named "stream") that
    ``--max-frames`` stopped the watch, exit 0, as a longer such watch ends (it was refused:
    "no person in view in enough frames", tests/test_hunt47w.py)."""
    _cut_avi(tmp_path)
    whole = tmp_path / "whole.avi"
    before = snapshot(tmp_path)
    capsys.readouterr()
    argv = ["watch", str(whole), "--db", str(case_base), "--speed", "0", "--max-frames", "40"]
    assert main(argv) == 0
    printed = capsys.readouterr()
    assert [json.loads(line)["unknown"] for line in printed.out.splitlines()] == ["nobody in view"]
    assert printed.err.startswith(f"note: {whole}: nobody in view in the 40 frames (1.60 s)")
    assert snapshot(tmp_path) == before


def test_watch_and_segment_agree_on_a_variable_frame_rate_video(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The reverse lunge of the test above re-timed at irregular intervals (gaps of 30, 50,
    40, 60 and 20 ms, 40 on average: the 25 fps it declares): both resample it to 25 fps
    (``watch`` as the frames come), so both give the same segments and repetitions; each
    says once that it resampled. Both had timed the frames as evenly spaced, silently."""
    pytest.importorskip("av", reason="PyAV writes the variable-frame-rate video")
    video, _ = _lunge_h264(shared_data, tmp_path / "lunge_vfr.mkv", (30, 50, 40, 60, 20))
    capsys.readouterr()
    assert main(["watch", str(video), "--db", str(case_base), "--speed", "0"]) == 0
    printed = capsys.readouterr()
    watched = [json.loads(line) for line in printed.out.splitlines()]
    assert printed.err.count("variable frame rate") == 1
    assert main(["segment", str(video), "--db", str(case_base), "--json"]) == 0
    printed = capsys.readouterr()
    offline = json.loads(printed.out)["segments"]
    assert printed.err.count("variable frame rate") == 1

    def spans(segments: list[dict[str, Any]]) -> list[tuple[Any, ...]]:
        keys = ("start_frame", "end_frame", "label", "repetitions")
        return [tuple(d[k] for k in keys) for d in segments]

    assert spans(watched) == spans(offline)


def test_watch_a_raw_stream_without_frame_times(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The reverse lunge as a raw H.264 stream (an IP camera's or a dashcam's ``.h264``): no
    frame times (OpenCV gives 0 ms for each), so it is played at the 25 fps it declares,
    every frame watched. It had been called a variable frame rate at frame 1 ("frame 1 is
    at 0.000 s, not 0.040 s") and every frame after the first dropped: "the stream ended
    after 1 frame", exit 1. The lunge's first 100 frames (4 s, two windows' worth) will do:
    the pose model's time is the test's."""
    pytest.importorskip("av", reason="PyAV writes the raw stream")
    video, k = _lunge_h264(shared_data, tmp_path / "lunge.h264", (40,), "h264", frames=100)
    assert k == 100
    capsys.readouterr()
    assert main(["watch", str(video), "--db", str(case_base), "--speed", "0"]) == 0
    printed = capsys.readouterr()
    lines = [json.loads(line) for line in printed.out.splitlines()]
    assert lines[0]["start_frame"] == 0 and lines[-1]["end_frame"] == k
    assert lines[-1]["end_s"] == pytest.approx(k / 25)
    assert "variable frame rate" not in printed.err


class _Ranges(_Quiet):
    """A server that answers range requests ("bytes=START-[END]"), as web servers do."""

    def send_head(self) -> Any:
        import os
        import re

        asked = re.fullmatch(r"bytes=(\d+)-(\d*)", self.headers.get("Range", ""))
        if asked is None:
            return super().send_head()
        path = self.translate_path(self.path)
        size = os.path.getsize(path)
        start = int(asked.group(1))
        end = min(int(asked.group(2) or size - 1), size - 1)
        fh = open(path, "rb")  # noqa: SIM115 (closed by the base class after copying)
        fh.seek(start)
        self.send_response(206)
        self.send_header("Content-Type", "application/octet-stream")
        self.send_header("Content-Range", f"bytes {start}-{end}/{size}")
        self.send_header("Content-Length", str(end - start + 1))
        self.send_header("Accept-Ranges", "bytes")
        self.end_headers()
        return fh


def test_a_served_mp4_that_gives_no_frame_says_why(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An MP4 whose index (moov) comes after its frames, as OpenCV's writer and cameras
    write it, served by a server that ignores range requests (``python -m http.server``):
    FFmpeg reads to the index at the end and cannot go back for the frames. One line says
    so, naming the URL, exit 1 (it said the whole file was "truncated or corrupt: decoded
    0 of 75 frames"). Served by one that answers range requests, it is watched: nobody in
    view for its 3 s."""
    import cv2

    video = tmp_path / "noise.mp4"  # 3 s of noise: 200 kB, more than FFmpeg reads ahead
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"mp4v"), 25.0, (96, 96))
    rng = np.random.default_rng(0)
    for _ in range(75):
        writer.write(rng.integers(0, 255, (96, 96, 3), dtype=np.uint8))
    writer.release()
    data = video.read_bytes()
    assert data.find(b"moov") > data.find(b"mdat")  # the index after the frames
    capsys.readouterr()
    with _serving(tmp_path) as address:
        url = f"{address}/noise.mp4"
        assert main(["watch", url, "--db", str(case_base), "--speed", "0"]) == 1
    err = capsys.readouterr().err
    assert err == (
        f"posecbr watch: error: {url}: read none of the 75 frames the served file holds:"
        " truncated or corrupt, or its index comes at its end (as cameras often write MP4 and"
        " MOV files) and the server does not answer range requests (python -m http.server"
        " does not)\n"
    )
    with _serving(tmp_path, _Ranges) as address:
        url = f"{address}/noise.mp4"
        assert main(["watch", url, "--db", str(case_base), "--speed", "0"]) == 1  # nobody
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [(d["start_frame"], d["end_frame"], d["explanation"]) for d in lines] == [
        (0, 75, "nobody in view")
    ]


def _lunge_h264(
    shared_data: Path,
    video: Path,
    gaps_ms: tuple[int, ...],
    container: str | None = None,
    frames: int | None = None,
) -> tuple[Path, int]:
    """The reverse lunge video at a quarter of its size (its first ``frames``; None: all
    250), written as lossless H.264 by PyAV with its frames ``gaps_ms`` apart in turn (1-ms
    time base; 25 fps declared), in ``container`` (None: by the file name); and its number
    of frames. Lossless (``qp`` 0) so that every run decodes to the same pixels: lossy x264
    did not, and the poses, labels and counts varied from run to run."""
    from fractions import Fraction

    import av
    import cv2

    src = cv2.VideoCapture(
        str(shared_data / "videos" / "lunge" / "fit_reverse_lunge_pexels8233047.mp4")
    )
    out = av.open(str(video), "w", format=container)
    stream = out.add_stream("libx264", rate=25)
    stream.codec_context.options = {"qp": "0"}
    tb = Fraction(1, 1000)
    stream.time_base = stream.codec_context.time_base = tb
    t, k = 0, 0
    while frames is None or k < frames:
        ok, bgr = src.read()
        if not ok:
            break
        small = cv2.resize(bgr, (bgr.shape[1] // 8 * 2, bgr.shape[0] // 8 * 2))
        if k == 0:
            stream.width, stream.height, stream.pix_fmt = small.shape[1], small.shape[0], "yuv420p"
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(small[:, :, ::-1]), format="rgb24")
        frame.pts, frame.time_base = t, tb
        for packet in stream.encode(frame):
            out.mux(packet)
        t += gaps_ms[k % len(gaps_ms)]
        k += 1
    for packet in stream.encode():
        out.mux(packet)
    out.close()
    src.release()
    return video, k


def test_watch_says_where_its_video_went(
    case_base: Path,
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``watch --out`` wrote its video and said nothing of it, where ``segment --overlay``
    says "overlay written to ...": it says "video written to ..." now, on stderr (stdout
    holds only the segments' JSON lines), after the latency line."""
    monkeypatch.setattr(pose_estimation, "stream_poses", _mocap_stream(shared_data, 120, "end"))
    out = tmp_path / "watched.mp4"
    capsys.readouterr()
    assert (
        main(["watch", "0", "--db", str(case_base), "--max-frames", "120", "--out", str(out)]) == 0
    )
    captured = capsys.readouterr()
    assert [json.loads(line)["end_frame"] for line in captured.out.splitlines()][-1] == 120
    lines = captured.err.splitlines()
    assert lines[-1] == f"video written to {out}"
    assert lines[-2].startswith("watched 120 frames in ")
    assert out.stat().st_size > 0
