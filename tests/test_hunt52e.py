"""Hunt 52e: a robot that watches for hours. A segment that runs on for longer than the
frames kept (``MAX_SEGMENT_S``) counted only the repetitions of its last frames kept: 58
squats in one 141-s segment counted 46. Tested here on the mechanism, the frames kept and the
tally made short (a long stream's worth in a few hundred frames). And the counter's SVD, run
at every hop over what the segment drawn is counted on, on one BLAS thread."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import cbr.live
from cbr.live import LiveSegment, LiveSegmenter
from features.poses import load_pose

SQUAT = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd" / "m01_s01_e01.npz"
FPS = 10.0


class _Scripted(LiveSegmenter):
    """Activity "a" in every window, "b" in those centred at or after frame ``change``; no
    classifier behind it, the repetition windows left out (the fixed windows alone vote)."""

    change = 10**9

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        return np.eye(2)[int(n - self.window / 2 >= self.change)], 0.0

    def _repetition_windows(self, n: int) -> None:
        """The fixed windows only."""


@pytest.fixture
def short_memory(monkeypatch: pytest.MonkeyPatch) -> None:
    """Frames of at most the last 20 s kept, the tally made at 5 s (TALLY_S; raising=False:
    set too where the code has none, so the test fails on its count there, not on a name)."""
    monkeypatch.setattr(cbr.live, "MAX_SEGMENT_S", 20.0)
    monkeypatch.setattr(cbr.live, "TALLY_S", 5.0, raising=False)


def _squats(loops: int) -> np.ndarray:
    """One UI-PRMD deep squat (one repetition from standing to standing, as the dataset cuts
    its clips) at 10 fps, ``loops`` times over: that many squats, 2.4 s each."""
    one = load_pose(SQUAT).positions[::3]
    return np.concatenate([one] * loops)


def _watched(frames: np.ndarray, change: int = 10**9) -> list[LiveSegment]:
    labels = np.array(["a", "b"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    live = _Scripted(clf, FPS, judge=SimpleNamespace())
    live.change = change
    out: list[LiveSegment] = []
    for frame in frames:
        out += live.push(frame)
        assert len(live.frames) <= 20.0 * FPS + 2 * live.window + live.hop
    return out + live.finish()


@pytest.mark.usefixtures("short_memory")
def test_a_segment_longer_than_the_frames_kept_counts_every_repetition() -> None:
    """40 squats (96 s) in one segment, 20 s of frames kept: 40, each loop of the clip one
    squat (before, 8: those of the last 20 s)."""
    segments = _watched(_squats(40))
    assert [(s.label, s.repetitions) for s in segments] == [("a", 40)]


@pytest.mark.usefixtures("short_memory")
def test_a_tally_stops_at_the_change_that_finishes_the_segment() -> None:
    """30 squats, then 10 more of another activity (the windows say so from the 31st): the
    tally of the long first segment keeps to its own squats, the two counting the 40 between
    them, 30 in the first give or take the squat the change cuts."""
    change = 30 * len(_squats(1))
    segments = _watched(_squats(40), change)
    assert [s.label for s in segments] == ["a", "b"]
    assert abs(segments[0].end_frame - change) <= 2 * FPS
    assert sum(s.repetitions for s in segments) == 40
    assert abs(segments[0].repetitions - 30) <= 1


class _Pool:
    """A BLAS library's thread setting as threadpoolctl gives it: two threads, each change
    recorded."""

    def __init__(self) -> None:
        self.threads, self.set = 2, []

    def get_num_threads(self) -> int:
        return self.threads

    def set_num_threads(self, n: int) -> None:
        self.set.append(n)
        self.threads = n


def test_the_direction_of_a_minute_of_movement_is_found_on_one_blas_thread(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A minute of a segment's samples at 30 Hz by 16 angles (the counter's SVD of what the
    segment drawn is counted on, at every hop): on one BLAS thread, the threads put back
    after. Before, only from 65,536 values: on the busy 2-core machine such an SVD took
    150-200 ms on OpenBLAS's threads and 0.2-0.3 ms on one, and a watch drawing a long
    segment spent most of its time waiting for them. The direction itself is the one the
    movement was made along (the first angle, by construction)."""
    import features.blas
    from features.repetitions import movement_direction

    pool = _Pool()
    monkeypatch.setattr(features.blas, "_POOLS", [pool])
    t = np.arange(1800) / 30.0
    x = np.zeros((1800, 16))
    x[:, 0] = np.sin(2 * np.pi * t / 2.4)
    x[:, 1:] = 0.01 * np.random.default_rng(0).normal(size=(1800, 15))
    direction = movement_direction(x)
    assert pool.set == [1, 2]
    assert abs(direction[0]) > 0.99
