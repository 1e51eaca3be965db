"""DAD end to end on real exercise videos (pose estimation -> QMPs -> ADD), no training."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from cbr.dad import detect
from features.errors import DataError
from features.poses import PoseSequence


@pytest.mark.parametrize(
    ("video", "activity"),
    [
        ("squat/tfjs_pose_squats_pexels4838220.mp4", "squat"),
        ("edge/jumping_jack_two_people_pexels8402086.mp4", "jumping_jack"),
    ],
)
def test_dad_ranks_the_filmed_exercise_first(
    bundled_poses: Callable[[str], PoseSequence], video: str, activity: str
) -> None:
    """The video's poses as ``load_clip`` of it gives them (``estimate_video``, canonical),
    estimated once in the session: other files read the same videos' poses."""
    try:
        seq = bundled_poses(video).to_canonical()
    except DataError as exc:  # the pose estimator or its model is not installed
        pytest.skip(str(exc))
    result = detect(seq)
    assert result.status == "ok"
    assert result.activities[0].activity == activity
    assert result.activities[0].score >= 0.8
