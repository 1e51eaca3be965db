"""A clip's problem does not depend on its frame rate: area resampling (cbr.problem.resample).

Before, a clip's columns were read at ``length`` evenly spaced instants, linearly between
frames, so a peak one frame long counted fully, partly or not at all depending on where the
instants fell: the same movement recorded at 30 and at 60 fps could be answered differently.
Now each of the ``length`` rows is the mean of the stretch of the clip it stands for.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from casebase_store import config_hash
from cbr.problem import FeatureConfig, resample, summarise
from features.errors import ConfigError
from features.poses import PoseSequence


def _summary(x: np.ndarray, length: int) -> np.ndarray:
    return summarise(resample(x, length), ("spike",), ("spike",)).values


def test_a_one_frame_spike_gives_the_same_summary_at_twice_the_frames() -> None:
    # 16 frames, a spike of 1 at frame 5, resampled to 8 rows: row r stands for frames 2r and
    # 2r + 1, so row 2 (frames 4, 5) is 0.5 and every other row 0. The same clip at twice the
    # frame rate, 32 frames with the spike at frames 10 and 11: row r stands for frames 4r to
    # 4r + 3, row 2 (frames 8-11) is 2 / 4 = 0.5 again.
    # mean 0.5 / 8 = 0.0625; lowest 0; highest 0.5; variation: one row 0.4375 from the mean,
    # seven 0.0625 from it: sqrt((0.4375^2 + 7 * 0.0625^2) / 8) = sqrt(0.02734375)
    at_n = np.zeros((16, 1))
    at_n[5] = 1.0
    at_2n = np.repeat(at_n, 2, axis=0)
    want = [0.0625, 0.0, 0.5, np.sqrt(0.02734375)]
    np.testing.assert_allclose(resample(at_n, 8)[:, 0], [0, 0, 0.5, 0, 0, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(_summary(at_n, 8), want, rtol=0, atol=1e-12)
    np.testing.assert_allclose(_summary(at_2n, 8), want, rtol=0, atol=1e-12)
    # before: read at instants r * 31 / 7 of the 32 frames, none of which lies within the
    # spike's frames 10 and 11 (8.86 lies between frames 8 and 9, 13.29 between 13 and 14):
    # the spike was gone at 60 fps; at 30 fps it was 2 / 7 (instant 30 / 7 = 4.29 of 15)


def test_rows_that_do_not_divide_the_frames_share_the_frame_on_their_border() -> None:
    # 10 frames to 4 rows: each row stands for 2.5 frames. A spike of 1 at frame 3: row 1
    # stands for frames 2.5-5 (half of frame 2, frames 3 and 4): 1 / 2.5 = 0.4. At 20 frames
    # (spike at 6 and 7) row 1 stands for frames 5-9: 2 / 5 = 0.4.
    x = np.zeros((10, 1))
    x[3] = 1.0
    np.testing.assert_allclose(resample(x, 4)[:, 0], [0, 0.4, 0, 0], atol=1e-15)
    np.testing.assert_allclose(resample(np.repeat(x, 2, axis=0), 4)[:, 0], [0, 0.4, 0, 0],
                               atol=1e-15)  # fmt: skip
    # a ramp 0..4 to 3 rows of 5/3 frames: (0 + 1 * 2/3) / (5/3) = 0.4, (1/3 + 2 + 3 * 1/3) /
    # (5/3) = 2, (3 * 2/3 + 4) / (5/3) = 3.6
    np.testing.assert_allclose(resample(np.arange(5.0)[:, None], 3)[:, 0], [0.4, 2.0, 3.6])


def test_a_row_whose_whole_stretch_is_missing_stays_missing() -> None:
    # 6 frames to 3 rows of 2 frames: frames 0-1 (1, NaN) -> 1, frames 2-3 all NaN -> NaN (not
    # 0), frames 4-5 (3, NaN) -> 3
    x = np.array([[1.0], [np.nan], [np.nan], [np.nan], [3.0], [np.nan]])
    out = resample(x, 3)[:, 0]
    assert out[0] == 1.0 and np.isnan(out[1]) and out[2] == 3.0
    assert np.isnan(resample(np.full((4, 2), np.nan), 2)).all()


def test_fewer_frames_than_rows_repeat_each_frame_over_its_time() -> None:
    # 2 frames to 4 rows: rows 0, 1 stand for frame 0 and rows 2, 3 for frame 1
    np.testing.assert_allclose(resample(np.array([[1.0], [3.0]]), 4)[:, 0], [1, 1, 3, 3])
    np.testing.assert_allclose(resample(np.array([[1.0], [3.0]]), 4, "linear")[:, 0],
                               [1, 5 / 3, 7 / 3, 3])  # fmt: skip


def test_stored_case_bases_keep_the_resampling_they_were_built_with() -> None:
    # a configuration stored before area resampling has no "resampling" key: it reads as
    # linear, so its cases and every clip compared with them are described as they were, and
    # its hash (which names its stored matrices) is unchanged
    stored = FeatureConfig(states=("left_knee_bent.bent",), summary=True).to_dict()
    del stored["resampling"]
    old = FeatureConfig.from_dict(stored)
    assert old.resampling == "linear"
    assert old.to_dict() == stored and config_hash(old.to_dict()) == config_hash(stored)
    new = FeatureConfig(states=("left_knee_bent.bent",), summary=True)
    assert new.resampling == "area" and new.to_dict()["resampling"] == "area"
    assert FeatureConfig.from_dict(new.to_dict()) == new
    with pytest.raises(ConfigError, match="resampling must be one of area, linear"):
        FeatureConfig(resampling="cubic")


# -- real data: UI-PRMD Kinect (30 fps), the held-out people at half and a quarter the rate


def _decimated(seq: PoseSequence, k: int) -> PoseSequence:
    """Every ``k``-th frame, at a ``k``-th of the frame rate."""
    conf = None if seq.confidence is None else seq.confidence[::k]
    return dataclasses.replace(seq, positions=seq.positions[::k], confidence=conf,
                               fps=seq.fps / k)  # fmt: skip
