"""A therapist's small case base, one recording per exercise (hunt 35k): the "unlike the
stored cases" flag calibrated on the pieces of each recording that do not overlap in time,
not on whole recordings held out (each then an exercise the case base lacks)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from cbr.estimator import _pieces_frames, _recording_blocks
from features.poses import PoseSequence, save_pose
from posecbr.cli import main


def _clips(*frames: tuple[int, int]) -> list[Any]:
    return [SimpleNamespace(frames=f) for f in frames]


def test_pieces_of_two_recordings_overlap_only_within_their_own() -> None:
    """Each recording moved to frame numbers of its own (the largest end + 1 apart, by
    recording name), the cases given the frames of the clip they are of."""
    clips = _clips((0, 50), (25, 75), (0, 50))
    sources = np.array(["a.npz", "a.npz", "b.npz"], dtype=object)
    got = _pieces_frames(clips, sources, np.array([0, 1, 2, 0]))
    assert got is not None
    assert got[0].tolist() == [[0, 50], [25, 75], [76, 126]]
    assert got[1].tolist() == [[0, 50], [25, 75], [76, 126], [0, 50]]


@pytest.mark.parametrize(
    ("frames", "sources"),
    [
        (((0, 50), (0, 50)), ["a", "b"]),  # a whole clip per recording: no piece stands in
        (((0, 50), (0, 40)), ["a", "a"]),  # two clips of one file both from frame 0
        (((0, 50), (25, 75)), ["a", ""]),  # a clip of no named recording
    ],
)
def test_no_pieces_when_nothing_can_stand_in(
    frames: tuple[tuple[int, int], ...], sources: list[str]
) -> None:
    clips = _clips(*frames)
    assert _pieces_frames(clips, np.array(sources, dtype=object), np.arange(len(clips))) is None


def test_time_blocks_are_dealt_within_each_recording() -> None:
    """Each recording's pieces by start frame, in runs of consecutive pieces (5 folds): the
    first of a recording of five is block 0 and its last block 4, whatever the other holds."""
    ranges = np.array([[40, 90], [0, 50], [10, 60], [20, 70], [30, 80], [500, 550], [400, 450]])
    sources = np.array(["a"] * 5 + ["b"] * 2, dtype=object)
    assert _recording_blocks(ranges, sources).tolist() == [4, 0, 1, 2, 3, 1, 0]


def _classified(db: Path, clip: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    import json

    capsys.readouterr()
    assert main(["classify", str(clip), "--db", str(db), "--json"]) == 0
    return dict(json.loads(capsys.readouterr().out)["results"][0])


def test_one_video_per_exercise_flags_an_exercise_it_never_saw(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    shared_data: Path,
    bundled_poses: Callable[[str], PoseSequence],
) -> None:
    """Trained on one video each of squat, reverse lunge and glute bridge (cut into 2-s
    windows), 2.4 s of jumping jacks came out "squat, confidence 1.00" without the flag: the
    threshold was set on whole recordings held out, each an exercise the rest lacked, so
    every clip of a new exercise lay nearer than they did (0.8x the usual distance). The
    training videos themselves stay unflagged. Their poses are the session's (as ``extract``
    finds them: the same case base), the jumping jacks' cut is extracted here."""
    videos = shared_data / "videos"
    trained = {
        "squat": "tfjs_pose_squats_pexels4838220",
        "lunge": "fit_reverse_lunge_pexels8233047",
        "glute_bridge": "fit_glute_bridge_pexels6525487",
    }
    jumps = videos / "edge" / "jumping_jack_two_people_pexels8402086.mp4"
    csv = tmp_path / "labels.csv"
    csv.write_text(f"path,label,start,end\n{jumps},jumping_jack,0,60\n")
    poses, train = tmp_path / "poses", tmp_path / "train"
    assert main(["extract", str(csv), "--out", str(poses)]) == 0
    for folder, name in trained.items():
        (train / folder).mkdir(parents=True)
        save_pose(bundled_poses(f"{folder}/{name}.mp4"), train / folder / f"{name}.npz")
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(train), "--db", str(db), "--split", "windows"]) == 0
    (cut,) = (poses / "jumping_jack").glob("*.npz")
    got = _classified(db, cut, capsys)
    assert got["unlike_cases"] is True, got["novelty"]
    for clip in sorted(train.glob("*/*.npz")):
        seen = _classified(db, clip, capsys)
        assert seen["unlike_cases"] is False and seen["label"] == clip.parent.name, clip
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db)]) == 0
    assert "leave-overlapping-out training windows" in capsys.readouterr().out
