"""Hunt 50m: ``watch`` of a live source whose frames come in bursts before any change of
rate, and of one that starts slow (:class:`posecbr.commands.watch.Regrid`).

- At the rate it began with, a live source whose frames came in bursts after pauses longer
  than a quarter second (frames held up on the way and read at once: a network's jitter)
  had the first pause left missing as a stall, then every burst's frames, one to a grid
  time, ran that far ahead of the clock for good. A frame after a pause shorter than
  ``BURST_S`` now puts the source on the grid by the wall clock (``Regrid._burst_begins``),
  as a changed rate does.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from posecbr.commands.watch import Regrid
from tests.test_hunt40h import _stream, _watched
from tests.test_hunt49e import _frame
from tests.test_hunt50a import _taken
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows


@pytest.mark.parametrize(("fps", "burst"), [(30.0, 8), (15.0, 5)])
def test_bursts_at_the_rate_begun_with_keep_their_poses_on_the_clock(
    fps: float, burst: int, capsys: pytest.CaptureFixture[str]
) -> None:
    """A camera at ``fps`` for 3 s, then, its rate unchanged, its frames in bursts of
    ``burst`` to 10 s, each burst read at once when its last frame was taken (pauses of
    0.27 and 0.33 s: longer than the quarter second bridged, not a change of rate over the
    latest half second), every frame's pose the time it was taken: every frame is on screen
    at some grid time, and grid time k's pose is k / fps (the camera's at that time), none
    missing, the grid ending on the last frame, said once on stderr. Before, the first pause
    left burst - 1 grid times missing as a stall, and every grid time after it lay that
    many frames late (0.23 and 0.27 s), the grid ending so late."""
    n = round(10 * fps)
    taken = [j / fps for j in range(n)]
    came = list(taken)
    for start in range(round(3 * fps), n, burst):
        group = came[start : start + burst]
        came[start : start + burst] = [group[-1]] * len(group)
    values, shown = _taken(
        Regrid(fps, "0"),
        [_frame(i, c, t) for i, (c, t) in enumerate(zip(came, taken, strict=True))],
    )
    assert len(values) == n
    np.testing.assert_allclose(values, np.arange(n) / fps, atol=1e-9)
    assert sorted(set(shown)) == list(range(n))
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "then frames at once (held up on the way?)" in err and "stalled" not in err


def test_a_stream_that_starts_slow_is_watched_at_the_rate_it_rises_to(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera that sends 15 frames a second for its first second, then 30 (CMU 13_30's
    jumping jacks, each frame the pose at the time it was taken): its rise is taken before
    any segment is given, and it is watched again from its start at 30 fps, said once. Its
    grid is then 30 fps by the wall clock from the first frame: the last frame, 1.0 + 149 /
    30 s after it, on grid time 179, the last segment ending at frame 180, 6.0 s. Before, the
    grid kept the first second's 15 fps (half the 30-fps frames resampled away): 90 grid
    times, the grid 0.9 s ahead of the clock at the rise, made up over 3.6 s."""
    n = 15 + 150
    times = np.array([i / 15.0 if i < 15 else 1.0 + (i - 15) / 30.0 for i in range(n)])
    skip = np.array([i if i < 15 else 15 for i in range(n)])  # frame i: 30-fps pose i + skip
    segments, err = _watched(case_base, monkeypatch, capsys, _stream(shared_data, times, skip), n)
    assert err.count("the frame rate rose from 15 to 30 fps") == 1
    assert "ahead of the clock" not in err
    # grid times 0, 1/30, ... 179/30 s = the last frame's time by the clock, end exclusive
    assert (segments[-1]["end_frame"], segments[-1]["end_s"]) == (180, pytest.approx(6.0))
