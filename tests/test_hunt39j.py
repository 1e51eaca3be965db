"""Hunt 39j: tests that could fail by chance. Each test here pins down that an input other
tests assert on is the same every run."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.pose_estimation.video import iter_frames
from tests.test_video_vfr import _write, people  # noqa: F401 (a fixture)


@pytest.mark.parametrize("name", ["lunge.mkv", "lunge.mts", "lunge.h264"])
def test_the_h264_test_videos_decode_to_the_same_pixels_every_run(
    people: list[np.ndarray],  # noqa: F811
    tmp_path: Path,
    name: str,
) -> None:
    """``_write``'s H.264 (the variable-frame-rate, gap and raw-stream videos of
    test_video_vfr, test_video_gaps and others) decodes to exactly what lossless FFV1 of the
    same frames decodes to, however many times it is written. It was lossy x264, whose
    pixels differed from one encoding to the next (4 encodings of 40 lunge frames, 4
    decodings), and with them the poses, labels and counts the tests asserted."""
    times = [40 * k for k in range(len(people))]
    reference = np.array(
        list(iter_frames(_write(tmp_path / "ref.mkv", times, people, codec="ffv1")))
    )
    assert reference.shape[0] == len(people)
    for k in range(3):
        folder = tmp_path / str(k)
        folder.mkdir()
        decoded = np.array(list(iter_frames(_write(folder / name, times, people))))
        np.testing.assert_array_equal(decoded, reference)
