"""Hunt 40e: the README's workout example, run as a new user would.

``python tools/make_workout.py workout/`` without the bundled videos beside the repository
(a clone with no ``../shared/data``, or ``$POSECBR_SHARED_DATA`` pointing elsewhere) printed
"wrote workout/workout.mp4 (0.0 s)" and exited 0, leaving a workout of no frames and four
training "videos" OpenCV cannot decode; the README's next command, ``posecbr train
workout/train``, then refused the first of them as "not a video OpenCV can decode", naming a
file the user never made. Now make_workout refuses in one line naming the clip it could not
read and where it looks for them, exit 1, before it writes anything.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

from cbr.evaluation.segments import score_segmentation

ROOT = Path(__file__).resolve().parents[1]
# the four clips tools/make_workout.py joins, as its PARTS name them (README "Long recordings")
CLIPS = (
    "edge/jumping_jack_two_people_pexels8402086.mp4",
    "squat/tfjs_pose_squats_pexels4838220.mp4",
    "edge/incline_pushup_cropped_pexels6970145.mp4",
    "glute_bridge/fit_glute_bridge_pexels6525487.mp4",
)


def _make_workout(data: Path, out: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "POSECBR_SHARED_DATA": str(data)}
    return subprocess.run([sys.executable, str(ROOT / "tools" / "make_workout.py"), str(out)],
                          capture_output=True, text=True, timeout=120, env=env)  # fmt: skip


def test_make_workout_without_the_videos_refuses_and_writes_nothing(tmp_path: Path) -> None:
    data = tmp_path / "data"  # no videos folder at all
    data.mkdir()
    out = tmp_path / "workout"
    proc = _make_workout(data, out)
    assert proc.returncode == 1, proc.stdout
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert str(data / "videos" / CLIPS[0]) in lines[0]
    assert "no such file" in lines[0] and "POSECBR_SHARED_DATA" in lines[0]
    assert "Traceback" not in proc.stderr
    assert proc.stdout == ""
    assert not out.exists()


def test_make_workout_with_a_clip_that_does_not_decode_refuses_naming_it(
    tmp_path: Path,
) -> None:
    data = tmp_path / "data"
    for name in CLIPS:
        (data / "videos" / name).parent.mkdir(parents=True, exist_ok=True)
        (data / "videos" / name).write_bytes(b"not a video at all\n" * 10)
    out = tmp_path / "workout"
    proc = _make_workout(data, out)
    assert proc.returncode == 1, proc.stdout
    lines = proc.stderr.strip().splitlines()
    clip = data / "videos" / CLIPS[0]
    assert lines == [
        f"make_workout.py: error: {clip}: not a video OpenCV can decode (unknown format,"
        " truncated or corrupt)"
    ], proc.stderr
    assert not out.exists()


def test_labels_the_case_base_lacks_are_listed_as_a_user_counts_them() -> None:
    # six 0.1-s blocks at 10 fps, all called unknown, one segment; the truth's codes 2, 10
    # and 1, none an activity of the case base
    result = SimpleNamespace(blocks=[None] * 6, fps=10.0, segments=[SimpleNamespace(start_frame=0)])
    scores = score_segmentation(result, ["2", "2", "10", "10", "1", "1"], ["Squat"], 0.1)
    assert scores.unseen_labels == ("1", "2", "10")
    assert scores.unseen_blocks == 6 and scores.unseen_unknown == 6


def test_boundary_errors_are_free_of_rounding_noise() -> None:
    """A segment starting at frame 51 of a 30-fps recording starts at 1.7 s, where the labels
    change after 17 blocks of 0.1 s: 0 s off, which ``--json`` gave as 2.2e-16 (51 / 30 and
    17 * 0.1 differ in the last bit); frame 57 is 0.2 s from 1.7 s, given as 0.19999999999999973."""
    truth = ["a"] * 17 + ["b"] * 17
    for frame, error in ((51, 0.0), (57, 0.2)):
        result = SimpleNamespace(blocks=truth, fps=30.0,
                                 segments=[SimpleNamespace(start_frame=0),
                                           SimpleNamespace(start_frame=frame)])  # fmt: skip
        assert score_segmentation(result, truth, ["a", "b"], 0.1).boundary_errors_s == (error,)
