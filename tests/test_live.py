"""The live decoder (cbr.live): segments are finished where the best path over the votes
goes, checked against every path tried by brute force."""

from __future__ import annotations

import itertools
from types import SimpleNamespace

import numpy as np

from cbr.live import LiveSegment, LiveSegmenter, _Forward


def _best_path(score: np.ndarray, cost: np.ndarray) -> list[int]:
    """The path of greatest total score less costs, found by trying every path."""
    n, k = score.shape
    best, value = None, -np.inf
    for path in itertools.product(range(k), repeat=n):
        v = sum(score[t, s] for t, s in enumerate(path))
        v -= sum(cost[a, b] for a, b in zip(path[:-1], path[1:], strict=True))
        if v > value:
            best, value = list(path), v
    assert best is not None
    return best


def test_settled_hops_follow_the_best_path_whatever_comes_after() -> None:
    """Random votes over three states, a change costing 1.5 (2.5 from state 0 to 2): the
    hops settled as the votes come, then the rest at the end, give the best path over all
    the votes, the one brute force finds; and a settled hop is never changed."""
    rng = np.random.default_rng(7)
    cost = np.full((3, 3), 1.5) - 1.5 * np.eye(3)
    cost[0, 2] = 2.5
    early = 0  # hops settled before the votes ended
    for _ in range(12):
        score = np.log(rng.dirichlet(np.ones(3) * 0.7, size=8))
        best = _best_path(score, cost)
        forward = _Forward(cost)
        settled: list[int] = []
        for t in range(len(score)):
            forward.step(score[t])
            settled += forward.settle()
            assert settled == best[: len(settled)]
        early += len(settled)
        settled += forward.settle(final=True)
        assert settled == best
    assert early > 0


class _Scripted(LiveSegmenter):
    """The live segmenter with each window's vote given by where its frames lie: for
    activity 0 while most of the window lies before frame ``change``, activity 1 after (a
    window is classified as the movement that fills most of it). Tests where the decoder
    puts the change, apart from any classifier."""

    change = 0

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        centre = n - self.window / 2
        return np.eye(2)[int(centre >= self.change)], 0.0

    def _repetition_windows(self, n: int) -> None:
        """The fixed windows only (the stream is noise: no repetition to script)."""


def test_a_change_is_placed_where_the_windows_say_not_a_window_late() -> None:
    """30 fps, 2-s windows every 0.5 s (a hop), the movement changing at 10.0-10.5 s: the
    windows centred after the change vote for the second activity; the change settles a few
    hops after it happens, but is placed within a hop of it (the decoder's resolution), not
    where the first window that voted for the new activity ends or its middle (1-2 s late)."""
    clf = SimpleNamespace(
        classes_=np.array(["a", "b"]), case_base_=SimpleNamespace(labels=np.array(["a", "b"]))
    )
    fps = 30.0
    rng = np.random.default_rng(0)
    for change in (300, 306, 311):
        live = _Scripted(clf, fps, judge=SimpleNamespace())
        live.change = change
        segments: list[LiveSegment] = []
        for _ in range(int(20 * fps)):
            segments += live.push(rng.normal(size=(33, 3)))
        segments += live.finish()
        assert [s.label for s in segments] == ["a", "b"]
        assert abs(segments[0].end_frame - change) <= live.hop
        assert segments[1].start_frame == segments[0].end_frame


class _Straddling(_Scripted):
    """Windows for activity 0 before frame ``change`` and 1 after, as :class:`_Scripted`; but
    the windows centred in the second after the change are unlike every activity, their
    nearest still the old one (a window across a change is like neither side)."""

    change = 0

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        centre = n - self.window / 2
        if 0 <= centre - self.change < self.fps:
            return np.eye(2)[0], 1.0
        return np.eye(2)[int(centre >= self.change)], 0.0


def test_windows_like_no_activity_do_not_vote_for_their_nearest() -> None:
    """The straddling windows say nothing of which activity their stretch is (as offline,
    cbr.segmentation.decode_activities): the change goes where the windows like an activity
    put it, at 10 s (to within half a hop); counted as votes for the old activity they hold
    the change back a hop (0.5 s)."""
    labels = np.array(["a", "b"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    live = _Straddling(clf, 30.0, judge=SimpleNamespace())
    live.change = 300
    rng = np.random.default_rng(1)
    segments: list[LiveSegment] = []
    for _ in range(600):
        segments += live.push(rng.normal(size=(33, 3)))
    segments += live.finish()
    assert [s.label for s in segments] == ["a", "b"]
    assert abs(segments[0].end_frame - live.change) < live.hop / 2


class _Novel(_Scripted):
    """Activity 0 throughout, but the windows centred in frames [300, 540) (8 s at 30 fps)
    are of a movement the case base lacks: unlike every activity, their nearest activity 1
    or 2 by turns of 2 s (a left-out movement lies about as far from two stored ones)."""

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        centre = n - self.window / 2
        if 300 <= centre < 540:
            return np.eye(3)[1 + int((centre - 300) // 60) % 2], 1.0
        return np.eye(3)[0], 0.0


def test_a_movement_like_no_activity_is_one_unknown_segment() -> None:
    """The novel stretch comes out as one unknown segment, its nearest activities' turns
    unseen under it (a change of activity under unknown costs nothing, as offline), its
    ends within a hop and a half of where the novel windows' centres begin and end (10 s,
    18 s); the stretches before and after are activity 0."""
    labels = np.array(["a", "b", "c"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    live = _Novel(clf, 30.0, judge=SimpleNamespace())
    rng = np.random.default_rng(2)
    segments: list[LiveSegment] = []
    for _ in range(900):
        segments += live.push(rng.normal(size=(33, 3)))
    segments += live.finish()
    assert [s.label for s in segments] == ["a", None, "a"]
    assert abs(segments[1].start_frame - 300) <= 1.5 * live.hop
    assert abs(segments[1].end_frame - 540) <= 1.5 * live.hop
    assert segments[1].confidence > 0.5  # the share of its windows unlike every activity


class _Pause(_Scripted):
    """Activity 0 for a long stream, its windows centred in frames [300, 540) unlike every
    activity (still nearest 0), and activity 1 for the windows centred in the last 20 s."""

    length = 0

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        centre = n - self.window / 2
        return np.eye(2)[int(centre >= self.length - 600)], float(300 <= centre < 540)


def test_a_long_stream_keeps_bounded_memory_and_finishes_what_it_settled() -> None:
    """5 minutes at 30 fps, longer than repetitions are counted over (MAX_SEGMENT_S): the
    pause is finished as unknown while the activity goes on (pass 2 does not wait for the
    activity to change, so its frames are still kept), and the change to activity 1 comes
    out at the end; the windows and hops kept stay those of the last seconds, the frames
    those of at most MAX_SEGMENT_S, two windows and a hop."""
    from cbr.live import MAX_SEGMENT_S

    labels = np.array(["a", "b"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    live = _Pause(clf, 30.0, judge=SimpleNamespace())
    live.length = 9000
    frame = np.random.default_rng(3).normal(size=(33, 3))
    segments: list[LiveSegment] = []
    for _ in range(live.length):
        segments += live.push(frame)
        assert len(live.windows) < 100 and len(live.hop_centres) < 100
        assert len(live.frames) <= MAX_SEGMENT_S * 30.0 + 2 * live.window + live.hop
    segments += live.finish()
    assert [s.label for s in segments] == ["a", None, "a", "b"]
    assert abs(segments[1].start_frame - 300) <= 1.5 * live.hop
    assert abs(segments[1].end_frame - 540) <= 1.5 * live.hop
    assert abs(segments[3].start_frame - (live.length - 600)) <= live.hop
