"""DAD end to end on real exercise videos (pose estimation -> QMPs -> ADD), no training."""

from __future__ import annotations

from pathlib import Path

import pytest

from cbr.dad import detect
from features.datasets import load_clip
from features.errors import DataError
from features.poses import PoseSequence


def _clip(path: Path) -> PoseSequence:
    try:
        return load_clip(path)
    except DataError as exc:  # the pose estimator or its model is not installed
        pytest.skip(str(exc))


@pytest.mark.parametrize(
    ("video", "activity"),
    [
        ("squat/tfjs_pose_squats_pexels4838220.mp4", "squat"),
        ("edge/jumping_jack_two_people_pexels8402086.mp4", "jumping_jack"),
    ],
)
def test_dad_ranks_the_filmed_exercise_first(shared_data: Path, video: str, activity: str) -> None:
    result = detect(_clip(shared_data / "videos" / video))
    assert result.status == "ok"
    assert result.activities[0].activity == activity
    assert result.activities[0].score >= 0.8
