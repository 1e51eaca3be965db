"""Hunt 37j: defects found by this session's hunts.

A frame left out for its time once a video's frames have strayed from the grid (a repeated,
missing or far-ahead stamp) still gave the smoothing filters ``index / fps``: where that lay
after the frames' own times, the filters took it as their latest time and passed the frames
after it through unsmoothed until the video's times caught up with it. Now such a frame
has no filter time (NaN): its pose passes unsmoothed and the filters are left as they were,
so the frames after it are smoothed as they would be without it.
"""

from __future__ import annotations

import math

import numpy as np

from tests.test_video_vfr import people  # noqa: F401 (a fixture)


def test_frames_after_a_left_out_one_are_smoothed_as_without_it(
    people: list[np.ndarray],  # noqa: F811
) -> None:
    """At 25 fps, frames 20 ms apart (strayed at frame 1), frame 3 repeating 0.04 s: it is
    left out. Before, the filters got 3 / 25 = 0.12 s for it, after 0.06, 0.08, 0.1 and
    0.12 s, so frames 4 to 7 passed through unsmoothed (each the raw pose). Now every frame
    after it is smoothed exactly as in a run without frame 3 (the times 0 to 0.16 s)."""
    from features.pose_estimation import PoseEstimator
    from features.pose_estimation.video import FrameClock

    times = [0.0, 0.02, 0.04, 0.04, 0.06, 0.08, 0.10, 0.12, 0.14, 0.16]
    clock = FrameClock(25.0)
    with_it = PoseEstimator(smoothing=True, tracking=False)
    poses = []
    for i, t in enumerate(times):
        elapsed = clock.take(i, t)
        at = clock.filter_time(i, elapsed)
        assert (i == 3) is math.isnan(elapsed)
        poses.append(with_it.process(people[i], at))
    assert not clock.on_grid
    without = PoseEstimator(smoothing=True, tracking=False)
    kept = [i for i in range(len(times)) if i != 3]
    alone = {i: without.process(people[i], times[i]) for i in kept}
    raw = PoseEstimator(smoothing=False, tracking=False)
    assert all(poses[i].person for i in kept)
    for i in kept:
        np.testing.assert_array_equal(poses[i].image, alone[i].image)
        np.testing.assert_array_equal(poses[i].world, alone[i].world)
    # the smoothing did something after frame 3: frame 4 is not its raw pose
    assert not np.allclose(poses[4].image[:, :2], raw.process(people[4]).image[:, :2], atol=1e-6)
    # the left-out frame itself: its raw pose, the filters untouched
    np.testing.assert_allclose(poses[3].image, raw.process(people[3]).image, atol=1e-9)
