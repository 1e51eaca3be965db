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


def test_a_frame_waiting_when_the_watch_looks_late_is_taken_not_called_a_stall(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``watch``'s thread taking the frames woken after the stall time (a busy machine: seen
    waking 3.4 s after asking, for a 1.5-s stall) with a frame waiting: it takes the frame.
    It said "the stream stalled: no frame for 1 s" although the frame had come in time. With
    nothing waiting, late, it is a stall as before. The clock here jumps 10 s at each look,
    so every look is late."""
    import itertools
    from types import SimpleNamespace

    from features.errors import DataError
    from posecbr.commands import watch

    reader = watch._Reader(iter(["frame 0"]))
    reader.thread.join(30)  # the frame and the end are in the box
    assert not reader.thread.is_alive()
    ticks = itertools.count(0.0, 10.0)
    monkeypatch.setattr(watch, "time", SimpleNamespace(perf_counter=lambda: next(ticks)))
    assert reader.get(1.0, "camera") == ("frame", "frame 0")
    assert reader.get(1.0, "camera") == ("end", None)
    with pytest.raises(DataError, match="camera: the stream stalled: no frame for 1 s"):
        reader.get(1.0, "camera")
    reader.close()
