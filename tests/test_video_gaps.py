"""A gap in a video's frame times (a phone or a stream that dropped frames, a jump in an
MPEG-TS clock) stays missing: the grid times inside it are NaN in ``extract``, ``watch`` and
every command that reads a video, not blended across the gap as made-up motion. Frames a
normal variable rate puts 20 to 100 ms apart are still blended (test_video_vfr.py).

The videos are written with PyAV at presentation times chosen here: the real lunge frames of
test_video_vfr.py, lossless (FFV1 in Matroska) where two files must decode the same, H.264 in
MPEG-TS as a stream with a jump in its clock comes.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from features.pose_estimation import PoseEstimator, estimate_video, stream_poses
from features.pose_estimation.video import older_vfr_extraction, resample_to_grid
from features.poses import EXTRACTION_VERSION, load_pose, load_pose_arrays, save_pose
from posecbr.cli import main
from posecbr.commands.extract import STALE_VFR
from posecbr.commands.watch import Regrid
from tests.test_video_vfr import (  # noqa: F401 (people: a fixture)
    LEFT_HIP,
    _frame,
    _per_frame,
    _write,
    people,
)
from tests.test_watch import case_base  # noqa: F401 (a fixture)

# 12 lunge frames at 25 fps (40 ms), but 1 s from the sixth (200 ms) to the seventh (1.2 s)
GAP_MS = [40 * k for k in range(6)] + [1200 + 40 * k for k in range(6)]
# the grid at 25 fps: 0 to 1.4 s, 36 rows; rows 6 to 29 (0.24 to 1.16 s) lie inside the gap
GAP_ROWS = list(range(6, 30))
LUNGE_NAME = "fit_reverse_lunge_pexels8233047.mp4"
OPTIONS = {"smoothing": False, "tracking": False, "progress_bar": False}


def test_the_bridge_limit_is_a_quarter_second_or_three_frames() -> None:
    from features.pose_estimation.video import bridge_limit_s

    assert bridge_limit_s(25.0) == 0.25
    assert bridge_limit_s(30.0) == 0.25
    assert bridge_limit_s(4.0) == 0.75  # three frame intervals at 4 fps


def test_resample_to_grid_leaves_a_gap_missing_and_blends_a_normal_interval() -> None:
    """Frames at 0, 0.1, 0.15, 0.4 (0.25 s after: bridged), 1.0 (0.6 s after: a gap) and
    1.1 s of a 10 fps file. 0.2 and 0.3 s blend 0.15 and 0.4 s as before (0.2, 0.6 of the
    way); 0.5 to 0.9 s lie inside the gap: missing; 1.0 and 1.1 s are the frames."""
    times = np.array([0.0, 0.1, 0.15, 0.4, 1.0, 1.1])
    values = np.array([0.0, 2.0, 4.0, 9.0, 20.0, 30.0])
    grid, before = resample_to_grid(times, values, 10.0)
    nan = np.nan
    expected = [0.0, 2.0, 0.8 * 4 + 0.2 * 9, 0.4 * 4 + 0.6 * 9, 9.0]
    expected += [nan] * 5 + [20.0, 30.0]
    np.testing.assert_allclose(grid, expected, rtol=0, atol=1e-12)
    assert before.tolist() == [0, 1, 2, 2, 3, 3, 3, 3, 3, 3, 4, 5]
    from features.pose_estimation.video import unbridged_gaps

    holes, rows = unbridged_gaps(times, 10.0)
    assert holes == [(0.4, 1.0)]
    assert np.flatnonzero(rows).tolist() == [5, 6, 7, 8, 9]


def test_watch_leaves_the_same_gap_missing_as_the_frames_come(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``watch`` (Regrid) of the frames above pushes the same grid values, the gap's as
    missing joints with missing visibility, and says the gap once, as it passes it."""
    times = [0.0, 0.1, 0.15, 0.4, 1.0, 1.1]
    values = [0.0, 2.0, 4.0, 9.0, 20.0, 30.0]
    live = Regrid(10.0, "phone.ts")
    steps = [live.take(_frame(i, t, np.full((33, 3), values[i]))) for i, t in enumerate(times)]
    pushed = [(w, vis, shown.index) for step in steps for w, vis, shown in step]
    assert len(pushed) == 12
    for k in range(5, 10):
        world, vis, shown = pushed[k]
        assert np.isnan(world).all() and np.isnan(vis).all() and shown == 3
    assert [float(w[0, 0]) for w, _v, _s in pushed[10:]] == [20.0, 30.0]
    assert float(pushed[3][0][0, 0]) == pytest.approx(0.4 * 4 + 0.6 * 9, abs=1e-12)
    err = capsys.readouterr().err.splitlines()
    assert err[1:] == ["note: phone.ts: 0.6 s without frames at 0.4-1.0 s left missing"]


# on one xdist worker: the module's gap_ts, lunge_jump, lunge_gap_mkv made once, not once per worker
pytestmark = pytest.mark.xdist_group("video_gaps")


@pytest.fixture(scope="module")
def gap_ts(people: list[np.ndarray], tmp_path_factory: pytest.TempPathFactory) -> Path:  # noqa: F811
    return _write(tmp_path_factory.mktemp("gap") / "jump.ts", GAP_MS, people[:12])


def test_a_gap_stays_missing_and_the_frames_around_it_are_their_own_poses(
    people: list[np.ndarray],  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The 12 frames losslessly, with the 1-s jump and at a constant 25 fps: with the jump,
    36 rows whose 24 inside the gap are all missing (they had been blended from the frames
    at 0.2 and 1.2 s: a made-up second of motion) and the 12 others the constant-rate copy's
    poses, bit for bit. The metadata and the one-line note say where the gap was."""
    jump = _write(tmp_path / "jump.mkv", GAP_MS, people[:12], codec="ffv1")
    even = _write(tmp_path / "even.mkv", [40 * k for k in range(12)], people[:12], codec="ffv1")
    want = estimate_video(even, **OPTIONS).sequence.positions
    capsys.readouterr()
    got = estimate_video(jump, **OPTIONS)
    seq = got.sequence
    assert seq.n_frames == 36 and seq.fps == 25.0
    assert np.isnan(seq.positions[GAP_ROWS]).all()
    assert np.isnan(got.image_landmarks[GAP_ROWS]).all()
    np.testing.assert_array_equal(seq.positions[:6], want[:6])
    np.testing.assert_array_equal(seq.positions[30:], want[6:])
    assert np.isfinite(want[:, LEFT_HIP]).all()  # a person in each frame: the NaN is the gap's
    assert got.video_frames is not None
    assert got.video_frames[GAP_ROWS].tolist() == [5] * 24  # the overlay holds the last frame
    gaps = seq.metadata["variable_frame_rate"]["gaps_left_missing"]
    assert gaps["longer_than_s"] == 0.25 and gaps["n_rows"] == 24
    assert gaps["gaps"] == [{"start_s": 0.2, "end_s": 1.2, "seconds": 1.0, "rows": [6, 30]}]
    assert seq.metadata["missing_frames"] == GAP_ROWS
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"note: {jump}: variable frame rate (frames 40 to 1000 ms apart): poses resampled"
        " to 25 fps; 1.0 s without frames at 0.2-1.2 s left missing"
    ]


def test_a_normal_variable_rate_is_still_blended(
    people: list[np.ndarray],  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Frames 20 to 100 ms apart (a phone's): no gap, every grid time blended from the
    frames around it as before (row 3, 120 ms: a quarter of the way from 100 to 180 ms;
    row 9, 360 ms: 0.6 of the way from 300 to 400 ms, the frames' own poses), nothing said
    of gaps, nothing recorded."""
    pts = [0, 20, 100, 180, 220, 260, 300, 400, 440, 520, 540, 620]
    path = _write(tmp_path / "phone.mkv", pts, people[:12], codec="ffv1")
    got = estimate_video(path, **OPTIONS)
    hip = _per_frame(path, tracking=False)[:, LEFT_HIP]
    assert np.isfinite(hip).all()
    seq = got.sequence
    assert seq.n_frames == 16 and not np.isnan(seq.positions[:, LEFT_HIP]).any()
    np.testing.assert_allclose(seq.positions[3, LEFT_HIP], 0.75 * hip[2] + 0.25 * hip[3])
    np.testing.assert_allclose(seq.positions[9, LEFT_HIP], 0.4 * hip[6] + 0.6 * hip[7])
    assert "gaps_left_missing" not in seq.metadata["variable_frame_rate"]
    assert "without frames" not in capsys.readouterr().err


def test_extract_and_watch_agree_frame_for_frame_across_a_gap(gap_ts: Path) -> None:
    """The MPEG-TS with its 1-s jump: ``watch``'s poses (stream_poses, then Regrid) equal
    ``extract``'s row for row, the gap's rows missing in both."""
    offline = estimate_video(gap_ts, announce=False, **OPTIONS).sequence.positions
    live = Regrid(25.0, str(gap_ts))
    est = PoseEstimator(smoothing=False, tracking=False)
    pushed = [w for f in stream_poses(gap_ts, estimator=est) for w, _v, _s in live.take(f)]
    assert len(pushed) == offline.shape[0] == 36
    np.testing.assert_array_equal(np.array(pushed), offline)
    assert np.isnan(offline[GAP_ROWS]).all()
    frames = _per_frame(gap_ts, tracking=False)
    np.testing.assert_array_equal(offline[:6], frames[:6])
    np.testing.assert_array_equal(offline[30:], frames[6:])


def test_extract_of_an_mpeg_ts_with_a_jump_writes_the_gap_missing(
    gap_ts: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract``'s line for the clip: the 24 rows in the gap are no frames "without a
    person" (it had said "24 without a person"); the gap is said."""
    out = tmp_path / "poses"
    assert main(["extract", str(gap_ts), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    assert printed.out == (
        f"done: {out / 'jump.npz'} (36 frames, 0 without a person; variable frame rate:"
        " resampled to 25 fps; 1.0 s without frames at 0.2-1.2 s left missing)\n"
    )
    pose_file = out / "jump.npz"
    seq = load_pose(pose_file)
    assert seq.n_frames == 36
    assert np.isnan(seq.positions[GAP_ROWS]).all()
    assert not np.isnan(seq.positions[[0, 5, 30, 35], LEFT_HIP]).any()
    assert load_pose_arrays(pose_file)["video_frames"][GAP_ROWS].tolist() == [5] * 24
    json.loads(json.dumps(seq.metadata))  # plain JSON
    # as version 2 left it (the gap blended, no record of it): extracted again, said so
    vfr = {k: v for k, v in seq.metadata["variable_frame_rate"].items() if "gaps" not in k}
    meta = {**seq.metadata, "extraction_version": 2, "variable_frame_rate": vfr}
    image = load_pose_arrays(pose_file)["image_landmarks"]
    save_pose(replace(seq, metadata=meta), pose_file, extra_arrays={"image_landmarks": image})
    capsys.readouterr()
    assert main(["extract", str(gap_ts), "--out", str(out)]) == 0
    assert capsys.readouterr().out.rstrip().endswith(f"left missing; {STALE_VFR})")
    assert load_pose(pose_file).metadata["extraction_version"] == EXTRACTION_VERSION


def test_a_version_2_pose_file_is_older_only_where_it_blended_across_a_gap() -> None:
    """Version 2 blended every grid time: its poses differ from today's only when its frames
    lay further apart than is bridged now (its record's longest interval says so)."""
    meta = {"pose_model": "blazepose", "extraction_version": 2}
    phone = {"resampled_to_fps": 25.0, "frame_interval_s": {"min": 0.02, "max": 0.1}}
    jump = {"resampled_to_fps": 25.0, "frame_interval_s": {"min": 0.04, "max": 1.0}}
    assert not older_vfr_extraction({**meta, "variable_frame_rate": phone}, "x")
    assert older_vfr_extraction({**meta, "variable_frame_rate": jump}, "x")
    assert older_vfr_extraction({**meta, "variable_frame_rate": {"resampled_to_fps": 25}}, "x")


def test_a_stretch_mostly_without_frames_is_no_frames_not_nobody_in_view() -> None:
    """The reason a stretch with nobody in view is unknown: "no frames in the video" when
    most of its frames lie in a recorded gap; a pose file cut from the video (its
    ``frame_offset``) has the gap's rows where they fall in it."""
    from cbr.segmentation import NO_FRAMES, NOBODY, nobody_explanation, unknown_reason
    from features.poses import PoseSequence, gap_rows
    from features.skeleton import BLAZEPOSE_33

    assert nobody_explanation(np.array([True, True, False])) == NO_FRAMES
    assert nobody_explanation(np.array([True, False])) == NOBODY
    assert unknown_reason(None, NO_FRAMES) == "no frames in the video"
    assert unknown_reason(None, NOBODY) == "nobody in view"
    assert unknown_reason("squat", NO_FRAMES) is None
    gap = {"start_s": 0.2, "end_s": 1.2, "seconds": 1.0, "rows": [6, 30]}
    meta = {"variable_frame_rate": {"gaps_left_missing": {"gaps": [gap]}}}
    seq = PoseSequence(np.zeros((36, 33, 3)), BLAZEPOSE_33, 25.0, metadata=meta)
    assert np.flatnonzero(gap_rows(seq)).tolist() == GAP_ROWS
    assert np.flatnonzero(gap_rows(seq.slice_frames(10, 32))).tolist() == list(range(20))
    assert not gap_rows(seq.slice_frames(30, None)).any()


def lunge_frames(shared_data: Path, n: int | None = None) -> list[np.ndarray]:
    """The bundled reverse lunge's first ``n`` frames (all 250: None), RGB, at a quarter of
    its size."""
    import cv2

    cap = cv2.VideoCapture(str(shared_data / "videos" / "lunge" / LUNGE_NAME))
    frames = []
    while n is None or len(frames) < n:
        ok, bgr = cap.read()
        if not ok:
            assert n is None, f"the lunge has fewer than {n} frames"
            break
        small = cv2.resize(bgr, (bgr.shape[1] // 8 * 2, bgr.shape[0] // 8 * 2))
        frames.append(np.ascontiguousarray(small[:, :, ::-1]))
    cap.release()
    return frames


@pytest.fixture(scope="module")
def lunge_jump(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The whole reverse lunge (250 frames, 10 s at 25 fps) at a quarter size, its clock
    jumping 3 s after frame 124 (4.96 s): the second half from 8.0 s, 13 s in all. Lossless
    H.264 (``_write``): the same poses each run."""
    frames = lunge_frames(shared_data)
    pts = [40 * k + (3000 if k >= 125 else 0) for k in range(len(frames))]
    return _write(tmp_path_factory.mktemp("jump") / "lunge_jump.mts", pts, frames)


def test_segment_and_watch_agree_across_a_gap_and_call_it_no_frames(
    case_base: Path,  # noqa: F811
    lunge_jump: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The lunge with a 3-s jump in its clock (an MPEG-TS, ``.mts``): ``segment`` and
    ``watch`` give the same segment for the gap (rows 125 to 199, 5.0 to 8.0 s): one
    segment of its own, unknown because the video has no frames there ("no frames in the
    video", counted 0), where it was blended motion; each says the gap once."""
    assert main(["segment", str(lunge_jump), "--db", str(case_base), "--json"]) == 0
    printed = capsys.readouterr()
    offline = json.loads(printed.out)["segments"]
    assert printed.err.count("3.0 s without frames at 5.0-8.0 s left missing") == 1
    assert main(["watch", str(lunge_jump), "--db", str(case_base), "--speed", "0"]) == 0
    printed = capsys.readouterr()
    watched = [json.loads(line) for line in printed.out.splitlines()]
    assert printed.err.count("3.0 s without frames at 5.0-8.0 s left missing") == 1
    # the stretches around the gap may differ where the labels waver (watch decides as the
    # frames come, segment on the whole; by design): the gap's own segment is compared
    keys = ("start_frame", "end_frame", "label", "repetitions", "unknown")
    gap_of = [
        [tuple(d[k] for k in keys) for d in found if d["unknown"] == "no frames in the video"]
        for found in (watched, offline)
    ]
    assert gap_of[0] == gap_of[1] and watched[-1]["end_frame"] == offline[-1]["end_frame"]
    assert not any(d["unknown"] == "nobody in view" for d in watched)
    gaps = [d for d in offline if d["unknown"] == "no frames in the video"]
    assert len(gaps) == 1 and gaps[0]["repetitions"] == 0
    assert gaps[0]["start_frame"] <= 125 and gaps[0]["end_frame"] >= 200
    assert gaps[0]["explanation"] == "no frames in the video"
    assert not any(d["unknown"] == "nobody in view" for d in offline)
    assert offline[-1]["end_frame"] == 325  # 13 s at 25 fps


def test_reps_and_classify_of_a_video_with_a_gap_do_not_count_through_it(
    case_base: Path,  # noqa: F811
    lunge_jump: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``reps`` of the lunge with its 3-s jump: no repetition runs across the gap (rows 125
    to 199; by hand, the blended gap once gave one from 1.92 to 10.60 s, through 3 s of
    made-up motion, though not every lossy encoding of the file did); ``classify`` of it
    answers, exit 0, and says the gap."""
    assert main(["reps", str(lunge_jump), "--json"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert found["count"] >= 1
    for rep in found["repetitions"]:
        assert rep["end_frame"] <= 125 or rep["start_frame"] >= 200, rep
    assert main(["classify", str(lunge_jump), "--db", str(case_base), "--json"]) == 0
    assert "without frames at 5.0-8.0 s" in capsys.readouterr().err


@pytest.fixture(scope="module")
def lunge_gap_mkv(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The reverse lunge's first 100 frames at a quarter size, lossless (FFV1 in Matroska: the
    same poses each run), its clock jumping 2 s after frame 49 (1.96 s): frames 50 to 99 at
    4.0 to 5.96 s, 6 s in all; grid rows 50 to 99 (2.0 to 3.96 s) lie inside the gap."""
    frames = lunge_frames(shared_data, 100)
    pts = [40 * k + (2000 if k >= 50 else 0) for k in range(100)]
    folder = tmp_path_factory.mktemp("gap_mkv")
    return _write(folder / "lunge_gap.mkv", pts, frames, codec="ffv1")


def _drawn_words(monkeypatch: pytest.MonkeyPatch) -> list[list[str]]:
    """Filled as overlays are written: per frame drawn, the texts written on it, in order."""
    import features.pose_estimation.overlay as overlay

    drawn: list[list[str]] = []
    draw_pose, write = overlay.draw_pose, overlay._write

    def drawing(*args: object, **kwargs: object) -> object:
        drawn.append([])
        return draw_pose(*args, **kwargs)  # type: ignore[arg-type]

    def writing(bgr: np.ndarray, text: str, org: tuple[int, int], scale: float) -> None:
        drawn[-1].append(text)
        write(bgr, text, org, scale)

    monkeypatch.setattr(overlay, "draw_pose", drawing)
    monkeypatch.setattr(overlay, "_write", writing)
    return drawn


def test_the_overlays_say_no_frames_in_a_gap_not_no_person(
    case_base: Path,  # noqa: F811
    lunge_gap_mkv: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``segment --overlay`` of the lunge with its 2-s gap: the 50 frames of the gap (rows 50
    to 99) say "no frames in the video" and the count, as ``watch --out`` draws them, where
    they said "no person" above it; ``extract --overlay`` says the same there. The person is
    in every frame of the video: "no person" is drawn nowhere."""
    drawn = _drawn_words(monkeypatch)
    out = tmp_path / "segment.mp4"
    argv = ["segment", str(lunge_gap_mkv), "--db", str(case_base), "--json", "--overlay"]
    assert main([*argv, str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    gap = [s for s in doc["segments"] if s["unknown"] == "no frames in the video"]
    assert [(s["start_frame"], s["end_frame"]) for s in gap] == [(50, 100)]
    assert len(drawn) == doc["frames"] == 150 and out.is_file()
    for row in range(50, 100):
        assert drawn[row] == ["no frames in the video", "repetitions: 0"], row
    assert not any("no person" in words for words in drawn)
    assert all(drawn[row][0] != "no frames in the video" for row in [*range(50), *range(100, 150)])
    drawn.clear()
    video = tmp_path / "overlay.mp4"
    assert main(["extract", str(lunge_gap_mkv), "--out", str(tmp_path / "poses"),
                 "--overlay", str(video)]) == 0  # fmt: skip
    assert len(drawn) == 150 and video.is_file()
    assert all(drawn[row][0] == "no frames in the video" for row in range(50, 100))
    assert not any("no person" in words for words in drawn)
    assert not any("no frames in the video" in drawn[row] for row in [*range(50), *range(100, 150)])
