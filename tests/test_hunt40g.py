"""Hunt 40g: bad input to the long-recording commands (``segment``, ``reps``, ``watch``,
``train --split``, label files, ``convert --fps``).

A recording shorter than a tenth of a second with a joint missing throughout (a BVH file of
one or two frames without hands, a two-frame pose file whose wrist the pose model never
saw) made ``segment`` exit 70, "a bug in posecbr (ValueError: array of sample points is
empty)": an angle seen in no frame counted as followed, its whole clip being one gap no
longer than the 0.1 s that is filled between an angle's values either side, and there were
no values to fill it from. ``segment`` read the movement before it checked the recording
was as long as one window.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError, PoseFileError
from features.poses import load_pose, save_pose
from features.repetitions import movement_signals
from features.skeleton import JOINT_INDEX
from tests.badinput import ROOT, pose_file, refused, small_case_base
from tests.bodies import rot_x, rotate, standing, to_sequence

DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("hunt40g_cb"))


def _bending(frames: int, fps: float, missing: tuple[str, ...]) -> object:
    """A person bending the right elbow to and fro, the joints ``missing`` NaN throughout."""
    poses = []
    for k in range(frames):
        body = standing()
        turn = rot_x(60.0 * np.sin(k / 5.0))
        poses.append(rotate(body, ("right_wrist",), turn, about=body["right_elbow"]))
    seq = to_sequence(*poses, fps=fps)
    pos = seq.positions.copy()
    for name in missing:
        pos[:, JOINT_INDEX[name]] = np.nan
    return replace(seq, positions=pos, source="")


@pytest.mark.parametrize("frames", [1, 2, 3])
def test_segment_of_a_recording_shorter_than_a_window_with_a_joint_never_seen(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], case_base: Path, frames: int
) -> None:
    rec = save_pose(_bending(frames, 30.0, ("left_wrist",)), tmp_path / "short.npz")
    duration = f"{frames / 30.0:.2f} s"
    refused(["segment", str(rec), "--db", str(case_base)], tmp_path, capsys,
            str(rec), f"lasts {duration}, shorter than the shortest window")  # fmt: skip


def test_an_angle_seen_in_no_frame_is_not_followed() -> None:
    # 12 frames at 240 fps (0.05 s): the left wrist never seen, a gap shorter than the 0.1 s
    # (24 frames) filled between an angle's values, but there are none to fill it from
    sig = movement_signals(_bending(12, 240.0, ("left_wrist",)))
    assert "left_elbow" not in sig.names
    assert "right_elbow" in sig.names
    assert np.isfinite(sig.values).all()


def test_no_angle_seen_in_any_frame_is_no_person() -> None:
    with pytest.raises(DataError, match="no person in view"):
        movement_signals(_bending(12, 240.0, tuple(JOINT_INDEX)))


def _with_offset(src: Path, dest: Path, offset: int) -> Path:
    """A copy of the pose file ``src`` whose metadata says it starts at frame ``offset``."""
    arrays = dict(np.load(src, allow_pickle=False))
    meta = json.loads(str(arrays["metadata"]))
    arrays["metadata"] = np.array(json.dumps({**meta, "frame_offset": offset}))
    np.savez(dest, **arrays)
    return dest


@pytest.mark.parametrize("offset", [2**53, 2**63 - 1, 10**30])
def test_a_frame_offset_no_recording_reaches_is_refused_as_the_file_is_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], offset: int
) -> None:
    # a frame_offset past 2**53 (what JSON readers and float64 hold exactly) was read, and
    # `train --split repetitions` then held the pieces' frames as 64-bit integers: exit 70,
    # "OverflowError: Python int too large to convert to C long"
    clips = [_with_offset(DEMO / f"m01_s0{s}_e01.npz", tmp_path / f"squat{s}.npz", offset)
             for s in (1, 2)]  # fmt: skip
    rows = [f"{c.name},deep_squat,s0{s}" for s, c in zip((1, 2), clips, strict=True)]
    rows += [f"{DEMO}/m07_s0{s}_e01.npz,standing_shoulder_abduction,s0{s}" for s in (1, 2)]
    csv = tmp_path / "labels.csv"
    csv.write_text("path,label,subject\n" + "\n".join(rows) + "\n")
    db = tmp_path / "cb.sqlite"
    refused(["train", str(csv), "--db", str(db), "--split", "repetitions"], tmp_path, capsys,
            str(clips[0]), "frame_offset", f"{offset:.3g}")  # fmt: skip
    with pytest.raises(PoseFileError, match="frame_offset"):
        load_pose(clips[0])


def test_the_largest_frame_offset_is_read(tmp_path: Path) -> None:
    clip = tmp_path / "clip.npz"
    pose_file(clip, metadata=json.dumps({"frame_offset": 2**53 - 8}))  # 8 frames: up to 2**53
    assert load_pose(clip).metadata["frame_offset"] == 2**53 - 8


def test_one_activity_left_after_short_stretches_says_the_others_were_too_short(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a recording labelled 'squat' throughout but for two flickers of 'lunge' and 'raise'
    # (each 3 frames, 0.1 s, under the shortest repetition, 0.4 s): the flickers are left
    # out, and the refusal said "only one activity ('squat')" of a file holding three
    rec = save_pose(_bending(90, 30.0, ()), tmp_path / "rec.npz")
    labels = ["squat"] * 90
    labels[30:33] = ["lunge"] * 3
    labels[60:63] = ["raise"] * 3
    track = tmp_path / "labels.txt"
    track.write_text("\n".join(labels) + "\n")
    db = tmp_path / "cb.sqlite"
    line = refused(["train", str(rec), "--frame-labels", str(track), "--db", str(db)],
                   tmp_path, capsys, "only one activity ('squat')")  # fmt: skip
    assert "(the stretches labelled lunge, raise are all shorter than 0.4 s: left out)" in line


def _refused_in_time(argv: list[str], root: Path, *needles: str) -> str:
    """``posecbr argv`` in its own process: refused in one line (exit 1) within a minute,
    nothing added under ``root`` (its files not read: one is a pipe). A process still running
    then is killed: a reader that opened a pipe waits for a writer that never comes (Ctrl-C
    did not stop it)."""
    before = sorted(root.rglob("*"))
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "posecbr", *argv],
            cwd=ROOT,
            env={**os.environ, "POSECBR_NO_PROGRESS": "1"},
            capture_output=True,
            text=True,
            timeout=60,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"posecbr {' '.join(argv)} still waiting after 60 s")
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 1, (proc.returncode, proc.stderr[-2000:])
    assert len(lines) == 1, proc.stderr
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    assert sorted(root.rglob("*")) == before
    return lines[0]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes on this system")
@pytest.mark.parametrize("where", ["--asf", "beside"])
def test_a_skeleton_that_is_a_pipe_is_refused_not_waited_on(tmp_path: Path, where: str) -> None:
    # `reps take.amc --asf pipe.asf` (or the only .asf beside it a named pipe) opened the pipe
    # to read the skeleton and waited for a writer, for ever
    take = tmp_path / "take.amc"
    take.write_text(":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\n")
    pipe = tmp_path / "skeleton.asf"
    os.mkfifo(pipe)
    argv = ["reps", str(take), *(["--asf", str(pipe)] if where == "--asf" else [])]
    _refused_in_time(argv, tmp_path, str(pipe), "is a pipe, socket or device, not a file")
