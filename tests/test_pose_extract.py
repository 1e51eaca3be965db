"""``posecbr extract``: pose files from videos, labels carried, skips, bad input.

Short clips are cut at test time from the real squat video in ../shared/data/videos (first
frames, re-encoded smaller) so every case runs in about a second.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest

# Imported before any video is opened here: it silences FFmpeg's own stderr messages, which
# OpenCV configures once per process on first use.
import features.pose_estimation  # noqa: F401
from features.errors import DataError
from features.pose_estimation import iter_frames
from features.poses import load_pose, load_pose_arrays
from posecbr.cli import main
from posecbr.commands.extract import Job, longest_first

SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"


def _cut(src: Path, dst: Path, frames: int, start: int = 0) -> Path:
    """Re-encode frames [start, start + frames) of ``src`` at half size as MP4."""
    cap = cv2.VideoCapture(str(src))
    fps = cap.get(cv2.CAP_PROP_FPS)
    writer = None
    k = 0
    while k < start + frames:
        ok, bgr = cap.read()
        assert ok
        if k >= start:
            bgr = cv2.resize(bgr, (bgr.shape[1] // 2, bgr.shape[0] // 2))
            if writer is None:
                fourcc = cv2.VideoWriter.fourcc(*"mp4v")
                writer = cv2.VideoWriter(str(dst), fourcc, fps, (bgr.shape[1], bgr.shape[0]))
            writer.write(bgr)
        k += 1
    assert writer is not None
    writer.release()
    cap.release()
    return dst


@pytest.fixture(scope="module")
def clip(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _cut(shared_data / SQUAT, tmp_path_factory.mktemp("clips") / "squat8.mp4", 8)


def _only_line(text: str) -> str:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert len(lines) == 1, lines
    return lines[0]


def test_single_video_writes_pose_file_then_skips(
    clip: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "poses"
    assert main(["extract", str(clip), "--out", str(out)]) == 0
    pose_file = out / "squat8.npz"
    seq = load_pose(pose_file)
    assert seq.n_frames == 8 and seq.fps == 5.0  # the squat video's rate
    assert seq.positions.shape == (8, 33, 3)
    assert not np.isnan(seq.positions[:, :25]).any()  # head, arms, hips seen in every frame
    extras = load_pose_arrays(pose_file)
    assert extras["image_landmarks"].shape == (8, 33, 5)
    # Image landmarks lie in the 360 x 640 frame, on the person (hips near mid-width).
    hips = extras["image_landmarks"][:, 23:25, :2]
    assert np.all((hips[..., 0] > 90) & (hips[..., 0] < 270))
    assert seq.metadata["video_sha256"] and seq.metadata["missing_frames"] == []
    mtime = pose_file.stat().st_mtime_ns
    capsys.readouterr()
    assert main(["extract", str(clip), "--out", str(out)]) == 0
    assert "up to date" in capsys.readouterr().out
    assert pose_file.stat().st_mtime_ns == mtime
    # A different option is a different output: re-extracted.
    assert main(["extract", str(clip), "--out", str(out), "--no-smoothing"]) == 0
    assert pose_file.stat().st_mtime_ns != mtime


def test_class_folders_and_csv_carry_labels(clip: Path, tmp_path: Path, shared_data: Path) -> None:
    data = tmp_path / "data"
    (data / "squat").mkdir(parents=True)
    (data / "other").mkdir()
    os.symlink(clip, data / "squat" / "a.mp4")
    _cut(shared_data / SQUAT, data / "other" / "b.mp4", 6, start=20)
    out = tmp_path / "out"
    assert main(["extract", str(data), "--out", str(out), "--workers", "2"]) == 0
    assert load_pose(out / "squat" / "a.npz").label == "squat"
    other = load_pose(out / "other" / "b.npz")
    assert other.label == "other" and other.n_frames == 6

    # A stretch and the whole video of one label (under two labels, they are refused: the
    # frames 2-6 would be poses of two activities; tests/test_hunt39b.py)
    csv_path = tmp_path / "labels.csv"
    csv_path.write_text(
        f"path,label,subject,start,end\n{clip},deep_squat,s01,2,7\n{clip},deep_squat,s02,,\n"
    )
    out2 = tmp_path / "out2"
    assert main(["extract", str(csv_path), "--out", str(out2)]) == 0
    part = load_pose(out2 / "deep_squat" / "squat8_2-7.npz")
    assert (part.label, part.metadata["subject"], part.n_frames) == ("deep_squat", "s01", 5)
    whole = load_pose(out2 / "deep_squat" / "squat8.npz")
    assert whole.n_frames == 8 and whole.metadata["subject"] == "s02"
    # The slice is the same frames as the whole clip's frames 2..6.
    np.testing.assert_allclose(part.positions, whole.positions[2:7])


def test_overlay_has_every_frame(
    clip: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    overlay = tmp_path / "check.mp4"
    capsys.readouterr()
    assert (
        main(["extract", str(clip), "--out", str(tmp_path / "o"), "--overlay", str(overlay)]) == 0
    )
    # said where it went, as segment --overlay says it (it was not said)
    assert capsys.readouterr().err.splitlines()[-1] == f"overlay written to {overlay}"
    cap = cv2.VideoCapture(str(overlay))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 8
    ok, frame = cap.read()
    assert ok and frame.shape[:2] == (640, 360)
    cap.release()


def _bad_inputs(tmp: Path, shared_data: Path) -> dict[str, Path]:
    good = (shared_data / SQUAT).read_bytes()
    avi = (shared_data / "media" / "vtest.avi").read_bytes()
    jpeg = (shared_data / "media" / "messi5.jpg").read_bytes()
    files = {
        "truncated_mp4": (tmp / "trunc.mp4", good[: len(good) // 2]),
        "truncated_avi": (tmp / "trunc.avi", avi[: len(avi) // 3]),
        "corrupt_header": (tmp / "corrupt.mp4", b"\0" * 4096 + good[4096:]),
        "not_a_video": (tmp / "notes.mp4", b"these are my notes, not a video\n"),
        "text_file": (tmp / "readme.txt", b"hello\n"),
        "empty_file": (tmp / "empty.mp4", b""),
        # a labels CSV with its header alone (a ZeroDivisionError before: no clip, no worker)
        "header_only_csv": (tmp / "header.csv", b"path,label\n"),
        # OpenCV decodes the first half of a cut-off JPEG and greys the rest: refused
        "truncated_jpeg": (tmp / "cut.jpg", jpeg[: len(jpeg) // 2]),
    }
    out = {}
    for name, (path, data) in files.items():
        path.write_bytes(data)
        out[name] = path
    zero = tmp / "zero.avi"
    cv2.VideoWriter(str(zero), cv2.VideoWriter.fourcc(*"MJPG"), 25, (64, 64)).release()
    out["zero_frames"] = zero
    out["missing_path"] = tmp / "does_not_exist.mp4"
    return out


def test_bad_input_one_line_exit_1_no_file(
    tmp_path: Path, shared_data: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    bad = _bad_inputs(tmp_path, shared_data)
    for name, path in bad.items():
        out = tmp_path / f"out_{name}"
        before = path.read_bytes() if path.exists() else None
        capfd.readouterr()
        assert main(["extract", str(path), "--out", str(out)]) == 1, name
        assert (path.read_bytes() if path.exists() else None) == before, name
        captured = capfd.readouterr()
        line = _only_line(captured.err)
        assert line.startswith("posecbr extract: error: ") and path.name in line, line
        assert captured.out == ""
        assert not out.exists() or not any(out.iterdir()), f"{name}: files left in {out}"


def test_still_images_in_a_folder_are_clips_of_one_frame(tmp_path: Path, shared_data: Path) -> None:
    """A class folder of photos (a JPEG and a PNG) beside a video: each image is a clip of
    one frame, labelled by its folder, as one image given alone is; the images' people are
    found (one person in each: ../shared/data/README.md)."""
    data = tmp_path / "data"
    (data / "pose").mkdir(parents=True)
    for name in ("messi5.jpg", "basketball1.png"):
        os.symlink(shared_data / "media" / name, data / "pose" / name)
    _cut(shared_data / SQUAT, data / "squat.mp4", 3)
    out = tmp_path / "out"
    assert main(["extract", str(data), "--out", str(out)]) == 0
    for stem in ("messi5", "basketball1"):
        seq = load_pose(out / "pose" / f"{stem}.npz")
        assert (seq.label, seq.n_frames) == ("pose", 1)
        assert np.isfinite(seq.positions).any(), stem
    assert load_pose(out / "squat.npz").n_frames == 3


def test_out_may_name_the_pose_file_of_one_video(
    tmp_path: Path, shared_data: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """``--out x.npz`` for one video (here a one-frame image) writes that file, not a folder
    named x.npz holding one; for a folder of videos it is refused, with nothing made."""
    image = shared_data / "media" / "messi5.jpg"
    out = tmp_path / "poses" / "messi.npz"
    out.parent.mkdir()  # a pose file's folder must exist, as an overlay's
    assert main(["extract", str(image), "--out", str(out)]) == 0
    assert out.is_file() and sorted(p.name for p in out.parent.iterdir()) == ["messi.npz"]
    assert load_pose(out).n_frames == 1
    assert "messi.npz (1 frame" in capfd.readouterr().out
    assert main(["extract", str(image), "--out", str(out)]) == 0  # up to date: skipped
    assert "skipped" in capfd.readouterr().out
    folder = tmp_path / "videos"
    folder.mkdir()
    (folder / "one.mp4").write_bytes((shared_data / SQUAT).read_bytes())
    assert main(["extract", str(folder), "--out", str(tmp_path / "all.npz")]) == 1
    assert _only_line(capfd.readouterr().err).endswith(
        "all.npz: for a folder or labels CSV, --out names the folder for the pose files, not"
        " one pose file"
    )
    assert not (tmp_path / "all.npz").exists()


def test_unwritable_output_is_one_line(
    clip: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    not_a_dir = tmp_path / "file.txt"
    not_a_dir.write_text("x")
    assert main(["extract", str(clip), "--out", str(not_a_dir)]) == 1
    assert "output is not a folder" in _only_line(capfd.readouterr().err)
    assert main(["extract", str(clip), "--out", str(not_a_dir / "sub")]) == 1
    assert "cannot write" in _only_line(capfd.readouterr().err)
    assert not_a_dir.read_text() == "x"
    # one clip's overlay in a folder that does not exist: refused as segment --overlay
    # refuses it (a mistyped folder was made), before the pose file is written
    out, missing = tmp_path / "o", tmp_path / "no-such-folder"
    argv = ["extract", str(clip), "--out", str(out), "--overlay", str(missing / "x.mp4")]
    assert main(argv) == 1
    line = _only_line(capfd.readouterr().err)
    assert "the folder of the overlay does not exist" in line and str(missing) in line
    assert not missing.exists() and not (out / f"{clip.stem}.npz").exists()
    # a folder's overlays go to a folder: one named like a video was made as a folder
    folder = tmp_path / "videos"
    folder.mkdir()
    (folder / "a.mp4").write_bytes(clip.read_bytes())
    argv = ["extract", str(folder), "--out", str(out), "--overlay", str(tmp_path / "all.mp4")]
    assert main(argv) == 1
    line = _only_line(capfd.readouterr().err)
    assert line.endswith(
        "all.mp4: for a folder or labels CSV, --overlay names the folder for the overlay "
        "videos, not one video file"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt", "videos"]
    # one video is extracted in this process: a --scheduler (even a bogus one) was ignored
    argv = ["extract", str(clip), "--out", str(out), "--scheduler", "tcp://nowhere:1"]
    assert main(argv) == 1
    assert _only_line(capfd.readouterr().err).endswith(
        "--scheduler: one video is extracted here, in this process; the cluster takes a folder "
        "or labels CSV of clips"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt", "videos"]


def test_cli_process_prints_only_one_line_for_a_corrupt_video(
    tmp_path: Path, shared_data: Path
) -> None:
    # A real process, so FFmpeg's own stderr output (C level) would show if not silenced.
    avi = (shared_data / "media" / "vtest.avi").read_bytes()
    bad = tmp_path / "damaged.avi"
    # cut mid-frame: FFmpeg complains while decoding (at a twentieth, after 27 of its 795
    # frames: fewer frames for the pose model than a quarter's 197, the same complaints)
    bad.write_bytes(avi[: len(avi) // 20])
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "posecbr", "extract", str(bad), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 1
    assert "truncated or corrupt" in _only_line(proc.stderr)
    assert not out.exists()  # the folder the run made goes with it (it was left empty)


def test_dataset_with_one_bad_clip_reports_it_and_keeps_the_rest(
    clip: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data" / "squat"
    data.mkdir(parents=True)
    os.symlink(clip, data / "good.mp4")
    (data / "bad.mp4").write_bytes(b"not a video")
    out = tmp_path / "out"
    capfd.readouterr()
    assert main(["extract", str(tmp_path / "data"), "--out", str(out)]) == 1
    err = capfd.readouterr().err
    assert err.count("posecbr extract: error:") == 1 and "bad.mp4" in err
    assert (out / "squat" / "good.npz").is_file()
    assert not (out / "squat" / "bad.npz").exists()
    assert [p.name for p in (out / "squat").iterdir()] == ["good.npz"]  # no temp files left


def _members(path: Path) -> dict[str, np.ndarray]:
    """Every array of a pose file (the archive's bytes hold the time it was written)."""
    with np.load(path, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


def test_outputs_that_cannot_be_written_leave_the_old_ones(
    clip: Path,
    tmp_path: Path,
    capfd: pytest.CaptureFixture[str],
    file_size_limit: Callable[[int], None],
) -> None:
    """A full disk while writing the overlay or the pose file (a file size limit here): one
    line, exit 1, the output that failed as the earlier run left it, no temporary file."""
    out, overlay = tmp_path / "o", tmp_path / "check.mp4"
    argv = ["extract", str(clip), "--out", str(out), "--overlay", str(overlay), "--force"]
    assert main(argv) == 0
    pose_file = out / "squat8.npz"
    pose, video = _members(pose_file), overlay.read_bytes()
    capfd.readouterr()

    def refused(what: Path) -> None:
        assert main(argv) == 1
        line = _only_line(capfd.readouterr().err)
        assert line.startswith(f"posecbr extract: error: {what}: cannot write"), line
        assert overlay.read_bytes() == video
        assert sorted(p.name for p in tmp_path.iterdir()) == ["check.mp4", "o"]
        assert [p.name for p in out.iterdir()] == ["squat8.npz"]

    # The pose file fits under the limit (it is written again, with the same poses), the
    # overlay does not.
    assert len(video) > pose_file.stat().st_size + 1024
    file_size_limit(pose_file.stat().st_size + 1024)
    refused(overlay)
    again = _members(pose_file)
    assert again.keys() == pose.keys()
    for name, array in pose.items():
        np.testing.assert_array_equal(again[name], array, err_msg=name)
    # Neither fits: the pose file is the one refused, and left byte for byte.
    before = pose_file.read_bytes()
    file_size_limit(len(before) // 2)
    refused(pose_file)
    assert pose_file.read_bytes() == before


def test_the_longest_clips_are_sent_first(tmp_path: Path) -> None:
    # costs by hand: a 300 bytes, c 200, the cuts of c by their share of its largest end
    # frame (200): [50, 200) 150, [0, 50) 50; b 100; a missing video 0 (its worker reports it)
    for name, size in (("a", 300), ("b", 100), ("c", 200)):
        (tmp_path / f"{name}.mp4").write_bytes(b"x" * size)
    out = tmp_path / "out"

    def job(name: str, start: int | None = None, end: int | None = None) -> Job:
        return Job(tmp_path / f"{name}.mp4", out / f"{name}{start}.npz", start=start, end=end)

    jobs = [job("b"), job("c", 0, 50), job("gone"), job("a"), job("c", 50, 200), job("c")]
    order = [(j.video.stem, j.start) for j in longest_first(jobs)]
    assert order == [("a", None), ("c", None), ("c", 50), ("b", None), ("c", 0), ("gone", None)]


def _decoded(path: Path, threads: int | None) -> tuple[str, object]:
    """("frames", sha256 of every frame) or ("error", the one-line message)."""
    try:
        digest = hashlib.sha256()
        for rgb in iter_frames(path, threads):
            digest.update(rgb.tobytes())
        return "frames", digest.hexdigest()
    except DataError as exc:
        return "error", str(exc)


def test_decoding_on_one_thread_gives_the_same_frames_and_the_same_errors(
    tmp_path: Path, shared_data: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # FFmpeg's frame threads change when a frame is decoded, never what: a worker decoding
    # on its one thread reads the same pixels, and refuses a bad file with the same line
    videos = [shared_data / SQUAT, shared_data / "media" / "vtest.avi"]
    bad = _bad_inputs(tmp_path, shared_data)
    capfd.readouterr()
    one_thread = {}  # each file decoded once each way (vtest.avi's 795 frames: ~2 s of CPU)
    for path in [*videos, *bad.values()]:
        one_thread[path] = _decoded(path, 1)
        assert one_thread[path] == _decoded(path, None), path.name
    assert [one_thread[v][0] for v in videos] == ["frames", "frames"]
    assert all(one_thread[p][0] == "error" for p in bad.values())
    assert capfd.readouterr().err == ""  # OpenCV's own warnings stay off stderr
