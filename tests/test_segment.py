"""Segmentation of long recordings (cbr.segmentation, posecbr segment) on CMU subject 13:
stretches cut at known frames and joined, the labelled recordings, exercises left out of the
case base, the decoder on hand-worked votes, windows across a change of activity, and bad
input."""

from __future__ import annotations

import hashlib
import json
import math
import re
import shutil
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.segmentation import (
    BLOCK_S,
    MIN_SEGMENT_S,
    NOBODY,
    SWITCH_ODDS,
    Segmentation,
    _Solved,
    block_evidence,
    counted_segments,
    decode,
    decode_activities,
    decode_unknown,
    finish,
    keep_whole,
    period_outliers,
    place_changes,
    segment,
    solve_recording,
    unknown_blocks,
    unknown_shares,
)
from cbr.unknown import ActivityMargin, Margin
from features.body import mirrored, moves_left_more
from features.datasets import Clip
from features.derived import stretch
from features.label_tracks import LabelTrack, frame_labels, read_label_names, read_label_track
from features.poses import PoseSequence, save_pose
from features.readers.asfamc import read_asf_amc
from features.repetitions import Repetition, movement_signals, split_windows
from posecbr.cli import main
from tests.badinput import refused
from tests.bodies import to_sequence
from tests.moves import MOVES, clip
from tests.once import made_once

NAMES = "1 JumpJack\n2 Jog\n3 Squat\n4 KneeRaise\n5 ArmCircle\n6 Twist\n10 ToeTouchOneHand\n"


def test_decode_ignores_a_short_blip_and_follows_a_long_change() -> None:
    """Two states; a change costs MIN_SEGMENT_S / BLOCK_S blocks x ln(SWITCH_ODDS) = 10 ln 2
    = 6.93. Three blocks at 0.9 vs 0.1 gain 3 ln 9 = 6.59 < 2 x 6.93 (out and back): no change.
    Twenty such blocks gain 43.9: the path changes there and back."""
    assert (MIN_SEGMENT_S / BLOCK_S) * math.log(SWITCH_ODDS) == pytest.approx(10 * math.log(2))
    votes = np.tile([0.9, 0.1], (60, 1))
    votes[10:13] = [0.1, 0.9]
    assert (decode(votes) == 0).all()
    votes[30:50] = [0.1, 0.9]
    path = decode(votes)
    assert (path[30:50] == 1).all() and (path[:30] == 0).all() and (path[50:] == 0).all()


def test_decode_unknown_charges_every_change_seen_once() -> None:
    """40 blocks; activity 0 up to block 30, then activity 1; a change seen costs
    10 ln 2 = 6.93. Unknown votes 0.9 over blocks 10-24, 0.4 over 25-29, 0.1 elsewhere.
    Known again at 25 (a 0.5-s sliver of activity 0 before the change to activity 1): three
    changes seen, 20.79, plus 5 (-ln 0.6) = 2.55 there: 23.34. Unknown up to the change:
    two changes, 13.86, plus 5 (-ln 0.4) = 4.58: 18.44, the least. (Known/unknown decoded
    alone would pay only for its own two changes either way and keep the sliver.)"""
    path = np.r_[np.zeros(30, dtype=np.int64), np.ones(10, dtype=np.int64)]
    votes = np.tile([0.9, 0.1], (40, 1))
    votes[10:25] = [0.1, 0.9]
    votes[25:30] = [0.6, 0.4]
    assert decode_unknown(votes, path).tolist() == [False] * 10 + [True] * 20 + [False] * 10
    # a short known stretch the votes hold firmly stays: 5 (-ln 0.001) = 34.5 to make it
    # unknown, against the one change (6.93) it costs
    votes[25:30] = [0.999, 0.001]
    assert decode_unknown(votes, path).tolist() == [False] * 10 + [True] * 15 + [False] * 15
    # the activity changes at 25 instead and the votes over 25-29 are even: unknown up to 25
    # or up to 30 costs the same (one change seen each way, 5 ln 2 either side); a tie is known
    path = np.r_[np.zeros(25, dtype=np.int64), np.ones(15, dtype=np.int64)]
    votes[25:30] = [0.5, 0.5]
    assert decode_unknown(votes, path).tolist() == [False] * 10 + [True] * 15 + [False] * 15


def test_a_change_of_activity_under_unknown_costs_nothing() -> None:
    """Activity 0 up to block 20, then 1; unknown votes 0.6 over blocks 10-29, 0.1 elsewhere.
    Unknown over 10-29: two changes seen, 13.86, plus 20 (-ln 0.6) = 10.22: 24.08 (the
    change of activity at 20 is not seen). Known throughout: one change seen (at 20), 6.93,
    plus 20 (-ln 0.4) = 18.33: 25.26. Were the change under unknown charged too, unknown
    would cost 31.0 and lose."""
    path = np.r_[np.zeros(20, dtype=np.int64), np.ones(20, dtype=np.int64)]
    votes = np.tile([0.9, 0.1], (40, 1))
    votes[10:30] = [0.4, 0.6]
    assert decode_unknown(votes, path).tolist() == [False] * 10 + [True] * 20 + [False] * 10


def _rep(peak: int) -> Repetition:
    return Repetition(peak - 10, peak + 10, peak)


def test_a_far_point_at_a_cut_counts_once() -> None:
    """A segment of frames [100, 200), one counted sample = 4 frames, far points at 101 (at
    its start), 150 and 197 (at its end): the one at its end is where the segment was cut,
    not where the movement turns (left out); the one at its start counts only when the
    segment before also had one at that cut (the movement turned at the cut: counted once,
    here); at the recording's own start or end a far point counts as in a clip."""
    reps = (_rep(101), _rep(150), _rep(197))
    peaks = [[r.peak_frame for r in keep_whole(reps, 100, 200, 4, turn, cut)]
             for turn, cut in ((False, True), (True, True), (False, False))]  # fmt: skip
    assert peaks == [[150], [101, 150], [150, 197]]
    first = (_rep(1), _rep(50))
    assert [r.peak_frame for r in keep_whole(first, 0, 100, 4, False, True)] == [1, 50]


@pytest.mark.parametrize(("length_s", "offset_s"), [(0.5, -0.25), (0.5, 0.0), (1.0, -0.5)])
def test_a_fragment_across_a_change_counts_no_repetition_twice(
    recordings: dict[str, PoseSequence], length_s: float, offset_s: float
) -> None:
    """13_30's two squats (11.8-16.1 s) then its four knee raises (6.7-11.8 s), counted by
    hand (tests/fixtures/repetition_counts.json), cut into three segments with a short one
    (0.5-1 s, shorter than a repetition) around the change: still six repetitions in all
    (counted alone, the fragment would count the movement at both its cut ends)."""
    rec = recordings["13_30"]
    squat = rec.positions[int(11.8 * 120) : int(16.1 * 120)]
    knee = rec.positions[int(6.7 * 120) : int(11.8 * 120)]
    joined = PoseSequence(np.concatenate([squat, knee]), rec.joint_names, 120.0, source="joined")
    seq = joined.to_canonical()
    a = len(squat) + int(offset_s * 120)
    b = a + int(length_s * 120)
    bounds = [(0, a), (a, b), (b, seq.n_frames)]
    counts = [len(r) for r in counted_segments(movement_signals(seq), bounds, seq.n_frames)]
    assert sum(counts) == 6, counts
    assert counts[0] == 2, counts


def test_the_counted_angles_of_a_recording_are_computed_once(
    recordings: dict[str, PoseSequence],
) -> None:
    """Segmenting reads the joint angles repetitions are counted on from the recording's
    cache (computed with its other features, timed apart by benchmarks.segment): the same
    numbers as computed afresh, and the same object when asked again."""
    from features.derived import movement_signals_of

    rec = recordings["13_30"]
    seq = PoseSequence(rec.positions[:600], rec.joint_names, 120.0, source="cut").to_canonical()
    first = movement_signals_of(seq)
    assert movement_signals_of(seq) is first
    fresh = movement_signals(seq)
    np.testing.assert_array_equal(first.values, fresh.values)
    assert first.names == fresh.names
    assert (first.fps, first.step) == (30.0, 4)  # 120 fps read at 30 Hz: every 4th frame


def _crossing_windows() -> list[_Solved]:
    """10 fps (one frame per block), windows of 20 frames starting every 5 (0, 5, ..., 40);
    those with at least half their frames before frame 40 (starts up to 30) lie at distance 1
    from activity 0 and 2 from activity 1, the others (35, 40) at 3 and 1."""
    return [
        _Solved(a, a + 20, np.ones(2) / 2, np.array([1.0, 2.0] if a <= 30 else [3.0, 1.0]), None)
        for a in range(0, 41, 5)
    ]


@pytest.mark.parametrize("decoded_at", [30, 50])
def test_a_change_is_moved_to_where_the_distances_cross(decoded_at: int) -> None:
    """Worked by hand for _crossing_windows: moving the change from t to t+1 charges every
    window over frame t (start < t < start + 20) 1/20 of (ln d0 - ln d1): -ln 2 for an early
    window, +ln 3 for a late one. From 35 to 40 three early windows (20, 25, 30) and one late
    (35) lie over it: -3 ln 2 + ln 3 < 0, the charge falls; from 40 to 45 two and two:
    -2 ln 2 + 2 ln 3 > 0, it rises; before 35 early windows only, after 45 more late ones
    than early. The least charge is at frame 40, from a change decoded before or after it."""
    path = np.r_[np.zeros(decoded_at, dtype=np.int64), np.ones(60 - decoded_at, dtype=np.int64)]
    placed = place_changes(_crossing_windows(), 10.0, path)
    assert (placed[:40] == 0).all() and (placed[40:] == 1).all()


def test_a_change_to_unknown_stays_where_it_was_decoded() -> None:
    """A run of the state past the activities (2: unknown) is not moved: the distances say
    nothing of where an unknown stretch begins."""
    path = np.r_[np.zeros(30, dtype=np.int64), np.full(30, 2, dtype=np.int64)]
    assert (place_changes(_crossing_windows(), 10.0, path) == path).all()


class _NeverUnknown:
    """A judge that calls no window unknown: the test below is about the activities' changes."""

    def unlike(self, nearest: np.ndarray) -> bool:
        return False

    def ratio(self, nearest: np.ndarray) -> float:
        return 0.0

    def describe(self, nearest: np.ndarray, classes: object) -> str:
        return ""


class _AlwaysUnknown(_NeverUnknown):
    """A judge that calls every window unknown."""

    def unlike(self, nearest: np.ndarray) -> bool:
        return True


def test_synthetic_recording_changes_within_a_quarter_second() -> None:
    """Squats for 5 s (cut at the deepest point, 1.25 s into a 2.5-s repetition), jumping
    jacks for 4 s, knee lifts for 6 s, built from tests/moves.py at 30 fps: the changes lie at
    5.0 and 9.0 s by construction. The case base holds 2-s windows of 7.5-s clips of those
    and of arm abductions. Each change found lies within 0.25 s of the true one."""
    names = ("squat", "jumping_jack", "knee_lift", "arm_abduction")
    train = [Clip(clip(n).with_metadata(label=n, subject="s"), n, "s", {}) for n in names]
    clf = _fit(train)
    fps, parts = 30.0, (("squat", 5.0, 1.25), ("jumping_jack", 4.0, 0.5), ("knee_lift", 6.0, 0.0))
    frames = [MOVES[n](offset + i / fps) for n, s, offset in parts for i in range(int(s * fps))]
    result = segment(clf, to_sequence(*frames, fps=fps), _NeverUnknown())
    assert [s.label for s in result.segments] == ["squat", "jumping_jack", "knee_lift"]
    found = [s.start_frame / fps for s in result.segments[1:]]
    assert found == pytest.approx([5.0, 9.0], abs=0.25), found
    # solved once, finished by two judges: the first gives what segment gave, the second
    # (every window unlike) leaves no block known
    done = solve_recording(clf, to_sequence(*frames, fps=fps))
    again = finish(clf, done, _NeverUnknown())
    assert again.blocks == result.blocks and again.windows == result.windows
    assert set(finish(clf, done, _AlwaysUnknown()).blocks) == {None}


def _cmu(shared_data: Path) -> dict[str, PoseSequence]:
    asf = shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf"
    return {
        t: read_asf_amc(asf, shared_data / "cmu-mocap6" / "amc" / f"{t}.amc")
        for t in ("13_29", "13_30", "13_31")
    }


@pytest.fixture(scope="module")
def recordings(
    shared_data: Path, tmp_path_factory: pytest.TempPathFactory
) -> dict[str, PoseSequence]:
    """CMU 13_29, 13_30 and 13_31, read once in the session (each module of each worker gets
    its own copy)."""
    return made_once(tmp_path_factory, "cmu-13-29-31", lambda _: _cmu(shared_data))


@pytest.fixture(scope="module")
def names(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("names") / "names.txt"
    path.write_text(NAMES, encoding="utf-8")
    return path


def _stretches(
    recordings: dict[str, PoseSequence], shared_data: Path, names: Path, which: tuple[str, ...]
) -> list[Clip]:
    out = []
    for t in which:
        labels = shared_data / "cmu-mocap6" / "truelabels" / f"{t}.txt"
        seq = recordings[t]
        # the stretches of the recording as clips: the same path iter_recording takes
        from features.datasets import split_by_track

        for part, label in split_by_track(seq, LabelTrack(labels, 0.1, names)):
            out.append(Clip(part.with_metadata(label=label, subject="13"), label, "13", {}))
    return out


def _fit(clips: list[Clip]) -> CaseBaseClassifier:
    """The classifier ``train --split windows`` makes: 2-s windows every 0.5 s, no weights."""
    windows = split_windows(clips).clips
    return CaseBaseClassifier(feature_weights="none").fit(
        [c.seq for c in windows], [c.label for c in windows]
    )


@pytest.fixture(scope="module")
def classifier(
    recordings: dict[str, PoseSequence],
    shared_data: Path,
    names: Path,
    tmp_path_factory: pytest.TempPathFactory,
) -> CaseBaseClassifier:
    """Windows of 13_29 and 13_31 (every exercise of 13_30 is among them), fitted once in the
    session (each worker gets its own copy)."""
    return made_once(
        tmp_path_factory,
        "segment-classifier",
        lambda _: _fit(_stretches(recordings, shared_data, names, ("13_29", "13_31"))),
    )


def test_two_exercises_joined_at_a_known_frame(
    recordings: dict[str, PoseSequence], classifier: CaseBaseClassifier
) -> None:
    """13_30's squats (labelled 11.8-16.1 s) followed by its knee raises (6.7-11.8 s): one
    recording whose change of exercise lies at a frame known by construction."""
    rec = recordings["13_30"]
    squat = rec.positions[int(11.8 * 120) : int(16.1 * 120)]
    knee = rec.positions[int(6.7 * 120) : int(11.8 * 120)]
    joined = PoseSequence(np.concatenate([squat, knee]), rec.joint_names, 120.0, source="joined")
    cut_s = len(squat) / 120.0
    result = segment(classifier, joined)
    labels = [s.label for s in result.segments]
    assert labels == ["Squat", "KneeRaise"], labels
    assert abs(result.segments[1].start_frame / 120.0 - cut_s) <= 0.5
    # the segments cover every frame once, in order
    assert result.segments[0].start_frame == 0
    assert result.segments[-1].end_frame == joined.n_frames
    for a, b in zip(result.segments[:-1], result.segments[1:], strict=True):
        assert a.end_frame == b.start_frame
    # two squats and four knee raises by hand (tests/fixtures/repetition_counts.json)
    assert [len(s.repetitions) for s in result.segments] == [2, 4]
    assert all(0.0 <= s.confidence <= 1.0 for s in result.segments)
    assert "Squat" in result.segments[0].explanation


def _with_gap(rec: PoseSequence) -> tuple[PoseSequence, int]:
    """13_30 (``rec``)'s squats (labelled 11.8-16.1 s), 5 s with every joint missing, its knee
    raises (6.7-11.8 s), at 120 fps; and the frames of the squats."""
    squat = rec.positions[int(11.8 * 120) : int(16.1 * 120)]
    knee = rec.positions[int(6.7 * 120) : int(11.8 * 120)]
    gap = np.full((5 * 120, *squat.shape[1:]), np.nan)
    joined = np.concatenate([squat, gap, knee])
    return PoseSequence(joined, rec.joint_names, 120.0, source="gap"), len(squat)


def test_a_stretch_with_nobody_in_view_is_a_segment_that_says_so(
    recordings: dict[str, PoseSequence], classifier: CaseBaseClassifier
) -> None:
    """13_30's squats, then 5 s in which nobody is in view (every joint missing), then its
    knee raises: the empty stretch is unknown, told as nobody in view, counted 0, from where
    the squats end (4.3 s by construction) to where the knee raises start (9.3 s); the
    exercises around it as alone. (Its windows, half empty at its edges, voted an exercise
    the case base has, jogging.)"""
    joined, squat = _with_gap(recordings["13_30"])
    result = segment(classifier, joined)
    assert [s.label for s in result.segments] == ["Squat", None, "KneeRaise"]
    empty = result.segments[1]
    assert empty.explanation == "nobody in view" and not empty.repetitions
    assert abs(empty.start_frame - squat) <= 12 and abs(empty.end_frame - squat - 600) <= 12
    assert [len(s.repetitions) for s in result.segments] == [2, 0, 4]
    doc = result.to_dict()["segments"]
    assert doc[1]["novelty"] is None
    # for machines, why each is unknown (or not): not only in the explanation's words
    assert [d["unknown"] for d in doc] == [None, "nobody in view", None]
    assert result.blocks[int(6.0 / 0.1)] is None
    # the overlay's words and the timeline's bands say so too
    from posecbr.commands.segment import _bands, frame_words

    words = frame_words(result)
    assert words[squat - 1][0] == "Squat" and words[squat + 300] == [
        NOBODY,
        "repetitions: 0",
    ]
    assert [b.text for b in _bands(result)] == ["Squat x2", f"{NOBODY} x0", "KneeRaise x4"]


def test_live_nobody_in_view_is_a_segment_as_offline(
    recordings: dict[str, PoseSequence], classifier: CaseBaseClassifier
) -> None:
    """The recording above streamed at 30 fps (every 4th frame) through watch's segmenter:
    the same three segments, the empty one exactly from the frame the squats end (129 by
    construction) to the frame the knee raises start (279), counted 2 / 0 / 4 by hand; it
    says nobody is in view from a second after the squats end to where the knee raises
    start, each frame's sighting known 3 frames (0.1 s, a glitch of the pose model aside)
    after it. (Its windows, before, made an unknown segment from 5.0 to 9.5 s told by
    distances.)"""
    from cbr.live import LiveSegmenter

    joined, at_120 = _with_gap(recordings["13_30"])
    squat = -(-at_120 // 4)  # frames of the squats streamed (129)
    live = LiveSegmenter(classifier, 30.0)
    segments = []
    for i, frame in enumerate(joined.positions[::4]):
        segments += live.push(frame)
        assert live.nobody_in_view == (squat + 30 + 3 <= i + 1 <= squat + 150 + 3)
    segments += live.finish()
    assert [(s.label, s.explanation == NOBODY) for s in segments] == [
        ("Squat", False), (None, True), ("KneeRaise", False)
    ]  # fmt: skip
    assert (segments[1].start_frame, segments[1].end_frame) == (squat, squat + 150)
    assert [s.repetitions for s in segments] == [2, 0, 4]


def test_a_labelled_recording(
    recordings: dict[str, PoseSequence],
    classifier: CaseBaseClassifier,
    shared_data: Path,
    names: Path,
) -> None:
    rec = recordings["13_30"]
    truth = frame_labels(
        read_label_track(
            shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt", read_label_names(names)
        ),
        rec.n_frames,
        rec.fps,
        0.1,
        "13_30",
    )[::12]
    result = segment(classifier, rec)
    pred = np.array(result.blocks, dtype=object)
    assert len(pred) == len(truth)
    # same person, another recording: nearly all blocks right (the benchmark gives figures)
    assert np.mean(pred == truth) >= 0.9
    doc = result.to_dict()
    assert set(doc) >= {"recording", "fps", "segments"}
    for s in doc["segments"]:
        assert set(s) >= {"start_s", "end_s", "start_frame", "end_frame", "label",
                          "confidence", "repetitions", "explanation"}  # fmt: skip
        assert s["start_s"] == pytest.approx(s["start_frame"] / 120.0, abs=1e-3)


def _same_segments(pieces: Segmentation, whole: Segmentation) -> None:
    assert pieces.blocks == whole.blocks and pieces.windows == whole.windows
    assert len(pieces.segments) == len(whole.segments)
    for a, b in zip(pieces.segments, whole.segments, strict=True):
        assert (a.start_frame, a.end_frame, a.label) == (b.start_frame, b.end_frame, b.label)
        assert a.repetitions == b.repetitions and a.explanation == b.explanation
        # a piece's fluents are evaluated from its own first frame: the same float32
        # confidences as the whole recording's to within one ulp
        assert a.confidence == pytest.approx(b.confidence, abs=1e-6)
        assert a.novelty == pytest.approx(b.novelty, rel=1e-6)


def test_a_recording_segmented_a_piece_at_a_time_gives_the_same_segments(
    recordings: dict[str, PoseSequence], classifier: CaseBaseClassifier
) -> None:
    """13_30 in pieces of 500 frames (its windows cut from them, each piece evaluated from
    the history its motion states read) and whole: the same segments, repetitions and
    explanations (the explained window is solved again from its piece)."""
    rec = recordings["13_30"]
    assert rec.n_frames > 4 * 500
    whole = segment(classifier, rec, chunk_frames=0)
    pieces = segment(classifier, rec, chunk_frames=500)
    assert len({s.label for s in whole.segments}) >= 3  # a recording with changes to place
    _same_segments(pieces, whole)


def test_the_segments_of_a_piece_are_explained_from_it_computed_once(
    recordings: dict[str, PoseSequence],
    classifier: CaseBaseClassifier,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A recording in pieces keeps only its windows' votes and distances; each segment's
    explanation solves its window again from its piece. Segments whose windows lie in one
    piece share it: every piece is computed once to solve its windows and at most once more
    to explain (before: once more per segment, 143 times a 20,000-frame piece for a 503-s
    recording, three quarters of its run)."""
    import cbr.segmentation as segmentation

    computed: list[tuple[int, int]] = []
    real = segmentation._piece

    def piece(rec: PoseSequence, bounds: tuple[int, int], config: object) -> PoseSequence:
        computed.append(bounds)
        return real(rec, bounds, config)  # type: ignore[arg-type]

    monkeypatch.setattr(segmentation, "_piece", piece)
    rec = recordings["13_30"]
    result = segment(classifier, rec, chunk_frames=2000)
    pieces = set(computed)
    assert len(pieces) == math.ceil(rec.n_frames / 2000)  # the windows start in every piece
    assert len([s for s in result.segments if s.label is not None]) > len(pieces)
    assert max(computed.count(b) for b in pieces) <= 2, sorted(computed)


def test_a_long_recording_checked_then_segmented_computes_its_counted_angles_once(
    recordings: dict[str, PoseSequence],
    classifier: CaseBaseClassifier,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A recording longer than CHUNK_FRAMES (made 500 here) is read in pieces; ``segment``
    checks every recording before segmenting any, and the check's joint angles are the ones
    the segmenting counts on: computed once, not once per step."""
    from cbr import long_clip
    from cbr.segmentation import check_segmentable, solve_recording

    monkeypatch.setattr(long_clip, "CHUNK_FRAMES", 500)
    computed = []
    real = long_clip.count_signals  # the counted angles from the pieces' joint angles

    def counted(seq: PoseSequence) -> object:
        computed.append(seq.n_frames)
        return real(seq)

    monkeypatch.setattr(long_clip, "count_signals", counted)
    rec = recordings["13_30"]
    cut = PoseSequence(rec.positions[:1500], rec.joint_names, 120.0, source="cut")
    check_segmentable(cut)
    done = solve_recording(classifier, cut)
    assert computed == [1500]
    assert len(done.windows) > 0


def test_a_canonical_side_case_base_segments_the_same_in_pieces() -> None:
    """Mirror images of the pieces (side canonical): the synthetic recording of
    test_synthetic_recording_changes_within_a_quarter_second, mirrored, in pieces of 97
    frames."""
    names = ("squat", "jumping_jack", "knee_lift", "arm_abduction")
    train = [Clip(clip(n).with_metadata(label=n, subject="s"), n, "s", {}) for n in names]
    windows = split_windows(train).clips
    clf = CaseBaseClassifier(feature_weights="none", mirror="canonical", phases=3).fit(
        [c.seq for c in windows], [c.label for c in windows]
    )
    fps, parts = 30.0, (("squat", 5.0, 1.25), ("jumping_jack", 4.0, 0.5), ("knee_lift", 6.0, 0.0))
    frames = [MOVES[n](offset + i / fps) for n, s, offset in parts for i in range(int(s * fps))]
    rec = mirrored(to_sequence(*frames, fps=fps))  # the knee lifts with the left leg
    assert clf.feature_config_.side == "canonical"
    assert moves_left_more(rec.slice_frames(330, 390))  # so their windows are mirrored
    whole = segment(clf, rec, _NeverUnknown(), chunk_frames=0)
    _same_segments(segment(clf, rec, _NeverUnknown(), chunk_frames=97), whole)
    assert [s.label for s in whole.segments] == ["squat", "jumping_jack", "knee_lift"]


def test_an_exercise_left_out_of_the_case_base_is_unknown(
    recordings: dict[str, PoseSequence], shared_data: Path, names: Path
) -> None:
    """Squats removed from the case base: 13_30's squats (11.8-16.1 s) are no known activity;
    its knee raises (6.7-11.8 s) still are, by the margin and by the activity margin."""
    clips = [
        c
        for c in _stretches(recordings, shared_data, names, ("13_29", "13_31"))
        if c.label != "Squat"
    ]
    clf = _fit(clips)
    judge = Margin.of(clf.case_base_)
    assert judge.basis == "recording" and 0.0 < judge.threshold < 1.0
    rec = recordings["13_30"]
    for j in (judge, ActivityMargin.of(clf.case_base_)):
        squats = segment(clf, stretch(rec, int(11.8 * 120), int(16.1 * 120)), j)
        assert np.mean([b is None for b in squats.blocks]) >= 0.8, (j, squats.segments)
        assert all(s.label != "Squat" for s in squats.segments)
        unknown = [s for s in squats.segments if s.label is None]
        assert "like no stored activity" in unknown[0].explanation
        assert unknown[0].to_dict(rec.fps)["unknown"] == "unlike every activity"
        knees = segment(clf, stretch(rec, int(6.7 * 120), int(11.8 * 120)), j)
        assert np.mean([b == "KneeRaise" for b in knees.blocks]) >= 0.8, (j, knees.segments)


class _FirstFar:
    """A judge that calls a window unlike when its distance to the first activity exceeds 1."""

    def unlike(self, nearest: np.ndarray) -> bool:
        return bool(nearest[0] > 1.0)

    def ratio(self, nearest: np.ndarray) -> float:
        return float(nearest[0])

    def describe(self, nearest: np.ndarray, classes: object) -> str:
        return ""


def test_a_window_across_a_change_of_activity_is_no_evidence_of_unknown() -> None:
    """10 fps (one frame per block), 60 blocks decoded as activity 0 then 1 from block 30.
    Windows of 20 frames every 5: those starting at 15, 20 and 25 lie across the change and
    are judged unlike, as are those wholly after it (30, 35, 40); those before it (0, 5, 10)
    are not. Left out, the three across the change move nothing: blocks 0-29 stay known and
    30-59 (covered only by windows judged unlike) are unknown. Counted, they would outvote
    the known windows over blocks 20-29 (2 or 3 of 3 or 4)."""

    path = np.r_[np.zeros(30, dtype=np.int64), np.ones(30, dtype=np.int64)]
    windows = [
        _Solved(a, a + 20, np.ones(2) / 2, np.array([2.0 if a >= 15 else 0.5, 3.0]), None)
        for a in range(0, 41, 5)
    ]
    unknown = unknown_blocks(windows, 60, 10.0, _FirstFar(), path)
    assert not unknown[:30].any() and unknown[30:].all()
    # the evidence decoded: all or nothing from this judge, 0 before the change, 1 after
    shares = unknown_shares(windows, 60, 10.0, _FirstFar(), path)
    assert list(shares) == [0.0] * 30 + [1.0] * 30


# ---- the command ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def case_base(
    recordings: dict[str, PoseSequence],
    shared_data: Path,
    names: Path,
    tmp_path_factory: pytest.TempPathFactory,
) -> Path:
    """``posecbr train recordings.csv --split windows`` on 13_29 and 13_31, made once in the
    session (the tests only read it)."""
    return made_once(
        tmp_path_factory,
        "segment-case-base",
        lambda folder: _case_base(folder, recordings, shared_data, names),
    )


def _case_base(
    folder: Path, recordings: dict[str, PoseSequence], shared_data: Path, names: Path
) -> Path:
    rows = ["path,label_file,label_block_s,label_names,subject"]
    for t in ("13_29", "13_31"):
        pose = save_pose(recordings[t], folder / f"{t}.npz")
        labels = shared_data / "cmu-mocap6" / "truelabels" / f"{t}.txt"
        rows.append(f"{pose},{labels},0.1,{names},13")
    (folder / "recordings.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    db = folder / "cb.sqlite"
    argv = ["train", str(folder / "recordings.csv"), "--db", str(db), "--split", "windows"]
    assert main(argv) == 0
    return db


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_segment_notes_a_recording_too_slow_to_follow_a_repetition(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """13_30 read at 2 fps (every 60th frame) with 13_30 at 10 fps: the 2-fps recording is
    noted, naming it, as `reps` notes it (tests/test_repetitions.py); both are segmented."""
    from tests.test_repetitions import LOW_RATE_NOTE

    rec = recordings["13_30"]
    slow, fast = tmp_path / "slow.npz", tmp_path / "fast.npz"
    save_pose(PoseSequence(rec.positions[::60], rec.joint_names, 2.0), slow)
    save_pose(PoseSequence(rec.positions[::12], rec.joint_names, 10.0), fast)
    capsys.readouterr()
    assert main(["segment", str(slow), str(fast), "--db", str(case_base), "--json"]) == 0
    captured = capsys.readouterr()
    notes = [line for line in captured.err.splitlines() if line.startswith("note:")]
    assert notes == [LOW_RATE_NOTE.format(path=slow)], captured.err
    assert [doc["fps"] for doc in json.loads(captured.out)] == [2.0, 10.0]


def test_segment_command_json_text_and_plot(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    rec = save_pose(recordings["13_30"], tmp_path / "13_30.npz")
    capsys.readouterr()
    plot = tmp_path / "timeline.png"
    assert main(["segment", str(rec), "--db", str(case_base), "--json", "--plot", str(plot)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["recording"] == str(rec) and doc["fps"] == 120.0
    segs = doc["segments"]
    assert segs[0]["start_frame"] == 0 and segs[-1]["end_frame"] == 2465
    known = {"JumpJack", "Jog", "Squat", "KneeRaise", "ArmCircle", "Twist", "ToeTouchOneHand"}
    assert all(s["label"] is None or s["label"] in known for s in segs)
    # the help names every key the JSON holds (it left out "frames")
    from posecbr.commands import segment as segment_command

    named = set(re.findall(r'"(\w+)"', segment_command.__doc__ or ""))
    assert set(doc) <= named and set(segs[0]) <= named
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["segment", str(rec), "--db", str(case_base)]) == 0
    text = capsys.readouterr().out
    # 2465 / 120 = 20.5417 s: the header rounds as the table's seconds do (it said 20.5)
    assert "2465 frames at 120 fps (20.54 s)" in text and "activity" in text
    fields = [line.split() for line in text.splitlines()[2:]]
    rows = [f for f in fields if len(f) > 2 and f[2].replace("-", "", 1).isdigit()]
    assert rows[-1][1] == "20.54" and rows[-1][2].endswith("-2464")  # end frame inclusive


def test_segment_command_refuses_a_recording_shorter_than_a_window(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    short = save_pose(recordings["13_30"].slice_frames(0, 60), tmp_path / "short.npz")
    before = _sha(short), _sha(case_base)
    plot = tmp_path / "p.png"
    assert main(["segment", str(short), "--db", str(case_base), "--plot", str(plot)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "shorter than" in err and str(short) in err
    assert (_sha(short), _sha(case_base)) == before and not plot.exists()


def test_segment_command_refuses_a_recording_with_no_person(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from features.skeleton import BLAZEPOSE_33

    empty = PoseSequence(np.full((240, 33, 3), np.nan), BLAZEPOSE_33, 120.0)
    path = save_pose(empty, tmp_path / "empty.npz")
    before = _sha(path)
    assert main(["segment", str(path), "--db", str(case_base), "--json"]) == 1
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "no person" in captured.err and "Traceback" not in captured.err
    assert _sha(path) == before


def test_segment_command_refuses_outputs_over_inputs(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    rec = save_pose(recordings["13_30"].slice_frames(0, 600), tmp_path / "r.npz")
    before = _sha(rec)
    assert main(["segment", str(rec), "--db", str(case_base), "--plot", str(rec)]) == 1
    assert "would overwrite an input" in capsys.readouterr().err
    assert main(["segment", str(rec), "--db", str(tmp_path / "none.sqlite")]) == 1
    assert capsys.readouterr().err.count("\n") == 1
    assert _sha(rec) == before and not (tmp_path / "none.sqlite").exists()


def test_segment_outputs_never_overwrite_the_case_base(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A case base named like a picture or a video: ``--plot`` or ``--overlay`` onto it
    replaced it (the case base lost)."""
    rec = save_pose(recordings["13_30"].slice_frames(0, 600), tmp_path / "r.npz")
    for name, option in (("cb.png", "--plot"), ("cb.mp4", "--overlay")):
        db = tmp_path / name
        shutil.copy(case_base, db)
        before = _sha(db)
        assert main(["segment", str(rec), "--db", str(db), option, str(db)]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "would overwrite an input" in err, err
        assert _sha(db) == before


def test_segment_refuses_options_the_recordings_would_ignore(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    rec = save_pose(recordings["13_30"].slice_frames(0, 600), tmp_path / "r.npz")
    before = _sha(rec), _sha(case_base)
    argv = ["segment", str(rec), "--db", str(case_base)]
    assert main([*argv, "--asf", str(tmp_path / "none.asf")]) == 1
    assert capsys.readouterr().err == (
        "posecbr segment: error: --asf: goes with an AMC recording, not r.npz\n"
    )
    assert main([*argv, "--fps", "0.001"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--fps: must be a frame rate in [0.01, 10000]" in err
    assert (_sha(rec), _sha(case_base)) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.npz"]


def test_a_bad_recording_among_several_leaves_no_picture_of_the_others(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The first recording was segmented and its picture written before the second (too
    short) was refused: a picture of a run that failed, exit 1. A missing recording is
    refused before the first is read."""
    good = save_pose(recordings["13_30"].slice_frames(0, 600), tmp_path / "good.npz")
    short = save_pose(recordings["13_30"].slice_frames(0, 60), tmp_path / "short.npz")
    pictures = tmp_path / "pictures"
    pictures.mkdir()
    before = _sha(good), _sha(short), _sha(case_base)
    for second in (short, tmp_path / "missing.npz"):
        argv = ["segment", str(good), str(second), "--db", str(case_base), "--plot"]
        assert main([*argv, str(pictures), "--json"]) == 1
        captured = capsys.readouterr()
        assert captured.out == "" and captured.err.count("\n") == 1
        assert str(second) in captured.err
        assert list(pictures.iterdir()) == []
    assert (_sha(good), _sha(short), _sha(case_base)) == before


def test_train_split_windows_of_one_activity_is_refused_in_one_line(
    recordings: dict[str, PoseSequence],
    names: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Every 0.1-s block of 13_29 labelled squat: "cut 1 clip into 73 windows" came on
    stderr before the refusal (two lines); the refusal comes before any cutting."""
    rec = save_pose(recordings["13_29"], tmp_path / "13_29.npz")
    blocks = math.ceil(recordings["13_29"].n_frames / 12)  # of 0.1 s at 120 fps
    labels = tmp_path / "labels.txt"
    labels.write_text("3\n" * blocks, encoding="utf-8")
    db = tmp_path / "cb.sqlite"
    before = _sha(rec), _sha(labels)
    argv = ["train", str(rec), "--frame-labels", str(labels), "--label-block", "0.1"]
    capsys.readouterr()
    assert main([*argv, "--label-names", str(names), "--split", "windows", "--db", str(db)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert "hold only one activity ('Squat')" in err
    assert not db.exists() and (_sha(rec), _sha(labels)) == before


def test_segment_command_tells_nobody_in_view_in_its_table(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """13_30's squats, 5 s with every joint missing, its knee raises, as a pose file: the
    table's empty row says "(nobody in view)" from 4.30 to 9.30 s (by construction), counted
    0, and says it once (no explanation line repeating it)."""
    path = save_pose(_with_gap(recordings["13_30"])[0], tmp_path / "gap.npz")
    capsys.readouterr()
    assert main(["segment", str(path), "--db", str(case_base)]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if "nobody in view" in line]
    assert len(rows) == 1, out
    start, end, _, *label, _, reps = rows[0]
    assert (start, end, " ".join(label), reps) == ("4.30", "9.30", "(nobody in view)", "0")


def test_segment_overlay_on_a_real_video(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The squat video (5 fps, 65 frames) segmented with the mocap case base, the segments
    drawn on every frame of the overlay."""
    import cv2

    video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    out = tmp_path / "overlay.mp4"
    assert main(["segment", str(video), "--db", str(case_base), "--overlay", str(out)]) == 0
    cap = cv2.VideoCapture(str(out))
    frames = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    cap.release()
    assert frames == 65
    assert "segments" in capsys.readouterr().out
    # --fps is the recording's frame rate with --overlay too (it was the video's, 5 fps)
    argv = ["segment", str(video), "--db", str(case_base), "--overlay", str(out), "--fps", "10"]
    assert main([*argv, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["fps"] == 10.0


def test_train_split_windows_makes_a_case_of_every_window(
    recordings: dict[str, PoseSequence], case_base: Path, shared_data: Path
) -> None:
    """Every labelled stretch of 13_29 and 13_31 gives floor((frames - 240) / 60) + 1 windows
    of 2 s every 0.5 s at 120 fps (its label runs x 12 frames; the last runs to the end of the
    recording); one shorter than a window (13_31's second twist, 1.8 s) stays whole. The
    stored model weighs no feature (near-copy windows tell nothing of an activity's spread)."""
    from posecbr.commands.segment import load_stored

    expected = 0
    for t in ("13_29", "13_31"):
        codes = (shared_data / "cmu-mocap6" / "truelabels" / f"{t}.txt").read_text().split()
        change = [0] + [i for i in range(1, len(codes)) if codes[i] != codes[i - 1]]
        starts = [12 * i for i in change]
        ends = [*starts[1:], recordings[t].n_frames]
        for a, b in zip(starts, ends, strict=True):
            expected += (b - a - 240) // 60 + 1 if b - a >= 240 else 1
    clf = load_stored(str(case_base), None)
    assert len(clf.case_base_) == expected
    assert clf.weighting_ == "none"


def test_segment_command_refuses_a_margin_it_cannot_calibrate(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Two activities: leaving one out leaves nothing to compare the other with. train says
    so when it makes the case base (segment refused it later, with nothing said before)."""
    db = tmp_path / "two.sqlite"
    csv = case_base.parent / "recordings.csv"
    argv = ["train", str(csv), "--db", str(db), "--split", "windows", "--labels", "Squat,Jog"]
    capsys.readouterr()
    assert main(argv) == 0
    note = capsys.readouterr().err.splitlines()[-1]
    assert note == (
        "note: segment and watch cannot tell stretches unlike every activity with this case "
        "base (fewer than three activities) by default: run them with --unknown held-out"
    )
    rec = save_pose(recordings["13_30"].slice_frames(0, 600), tmp_path / "r.npz")
    before = _sha(rec), _sha(db)
    plot = tmp_path / "p.png"
    capsys.readouterr()
    assert main(["segment", str(rec), "--db", str(db), "--plot", str(plot)]) == 1
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "fewer than three activities" in captured.err and "--unknown held-out" in captured.err
    assert captured.err.startswith(f"posecbr segment: error: {db}: its case base cannot judge ")
    assert (_sha(rec), _sha(db)) == before and not plot.exists()
    assert main(["segment", str(rec), "--db", str(db), "--unknown", "held-out"]) == 0


def test_segment_command_refuses_a_margin_with_no_activity_seen_twice(
    recordings: dict[str, PoseSequence], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One 2-s clip per exercise, each its own file: no activity has two cases apart (from two
    recordings, or apart in time), so nothing tells how far a new performance of a known one
    lies: refused in one line, with the other judges named."""
    rec = recordings["13_29"]
    rows = ["path,label"]
    for label, start_s in (("JumpJack", 1.0), ("Twist", 5.0), ("Squat", 33.0)):
        a = int(start_s * 120)
        path = save_pose(rec.slice_frames(a, a + 240), tmp_path / f"{label}.npz")
        rows.append(f"{path},{label}")
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    db = tmp_path / "one_each.sqlite"
    assert main(["train", str(tmp_path / "labels.csv"), "--db", str(db), "--split", "windows"]) == 0
    test = save_pose(recordings["13_30"].slice_frames(0, 600), tmp_path / "r.npz")
    before = _sha(test), _sha(db)
    capsys.readouterr()
    assert main(["segment", str(test), "--db", str(db), "--json"]) == 1
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "no activity has cases apart" in captured.err
    assert "--unknown held-out" in captured.err and "Traceback" not in captured.err
    assert (_sha(test), _sha(db)) == before


def _steady_periods() -> tuple[np.ndarray, np.ndarray]:
    """Repetition windows of a steady movement (periods of 29-34 frames, found at two phases,
    half a period apart), one window twice as long over the middle (index 9: a period read
    across a change, or two repetitions) and a 60-frame default window (index 10)."""
    spans = [(0, 30), (30, 61), (61, 90), (90, 119), (119, 150),  # one phase
             (15, 44), (44, 78), (78, 105), (105, 135),  # the other, one period of 34
             (40, 100), (0, 60)]  # fmt: skip
    repetition = np.array([True] * 10 + [False])
    return np.array(spans, dtype=np.int64), repetition


def test_a_period_twice_its_neighbours_is_an_outlier() -> None:
    """By construction: every steady window's neighbours have periods of 29-34 frames (their
    log lengths differ from their neighbours' median by at most ln(34/30) = 0.13, below 3
    times the floor of one 4-frame sample over the median period, 3 x 4/30 = 0.4); the long
    window's neighbours are all steady, ln(60/30) = 0.69 above. A default window is never
    one, whatever its length."""
    spans, repetition = _steady_periods()
    assert np.flatnonzero(period_outliers(spans, repetition, 4)).tolist() == [9]


def test_without_three_repetition_windows_nothing_is_an_outlier() -> None:
    """Two repetition windows have no scale of disagreement to be judged by."""
    spans = np.array([(0, 30), (15, 75), (0, 60)], dtype=np.int64)
    flagged = period_outliers(spans, np.array([True, True, False]), 4)
    assert not flagged.any()


def _change_with_straddlers() -> list[_Solved]:
    """10 fps (a frame per block), 60 frames: activity 0 until frame 30, then 1. Windows of
    20 frames: [0, 20), [5, 25), [10, 30) vote 0 and lie at 1 from it, 3 from the others;
    [30, 50), [35, 55), [40, 60) vote 1 likewise; five across the change, starting at 15,
    18, 20, 22 and 25, vote activity 2 (the legs of one movement and the arms of the
    other) and lie at 2 from all three."""

    def window(a: int, activity: int, nearest: list[float]) -> _Solved:
        return _Solved(a, a + 20, np.eye(3)[activity], np.array(nearest), None)

    return (
        [window(a, 0, [1.0, 3.0, 3.0]) for a in (0, 5, 10)]
        + [window(a, 1, [3.0, 1.0, 3.0]) for a in (30, 35, 40)]
        + [window(a, 2, [2.0, 2.0, 2.0]) for a in (15, 18, 20, 22, 25)]
    )


def test_windows_like_no_activity_do_not_vote() -> None:
    """The five windows across the change, judged unlike every activity, do not vote: frames
    0-29 are voted 0 only, 30-59 1 only, and the change goes where the distances cross, at
    30 (the three windows of activity 0 end by 30, those of 1 start there). When they vote,
    blocks 25-34 are 5 to 1 for activity 2 (each ln 5 = 1.61 of evidence, 16.1 over the ten
    blocks, more than the 2 x 10 ln 2 = 13.9 two changes cost): a segment of 2 appears."""
    solved = _change_with_straddlers()
    across = np.array([w.vote[2] == 1.0 for w in solved])
    none = np.zeros(len(solved), dtype=bool)
    _, path = decode_activities(solved, none, across, 60, 10.0, 3)
    assert path.tolist() == [0] * 30 + [1] * 30
    _, voted = decode_activities(solved, none, none, 60, 10.0, 3)
    assert 2 in voted.tolist()
    # an outlier does not vote either: the same windows flagged as outliers instead
    _, path = decode_activities(solved, across, none, 60, 10.0, 3)
    assert path.tolist() == [0] * 30 + [1] * 30


def test_no_voting_window_leaves_every_activity_alike() -> None:
    """Every window unlike: no block has a vote, each activity gets 1/3 (no evidence)."""
    solved = _change_with_straddlers()
    votes, _ = decode_activities(solved, np.zeros(len(solved), dtype=bool),
                                 np.ones(len(solved), dtype=bool), 60, 10.0, 3)  # fmt: skip
    assert votes == pytest.approx(np.full((60, 3), 1.0 / 3.0))


def test_a_block_no_window_covers_takes_its_neighbours_evidence_by_nearness() -> None:
    """10 fps (one frame per block), 10 blocks: a window over frames 0-2 with evidence 1, one
    over 7-9 with 0, and one over 0-1 with 0 (blocks 0-1: mean 0.5). Blocks 3-6, covered by
    none, lie 1-4 blocks from block 2 (1.0) and 4-1 from block 7 (0.0): 0.8, 0.6, 0.4, 0.2.
    No window at all: 0.5 everywhere (no evidence either way)."""
    windows = [_Solved(a, b, np.ones(2), np.ones(3), None) for a, b in ((0, 3), (7, 10), (0, 2))]
    got = block_evidence(windows, np.array([1.0, 0.0, 0.0]), 10, 10.0)
    assert got == pytest.approx([0.5, 0.5, 1.0, 0.8, 0.6, 0.4, 0.2, 0.0, 0.0, 0.0])
    assert block_evidence([], np.zeros(0), 10, 10.0) == pytest.approx(np.full(10, 0.5))


def test_a_gap_in_the_evidence_at_a_change_is_split_by_nearness() -> None:
    """10 fps, 60 blocks decoded as activity 0 up to block 19, then 1. Windows judged unlike
    cover blocks 0-19 (frames 0-19, within activity 0), windows judged like cover 40-59;
    blocks 20-39 no window covers. Interpolated, block t has evidence (40 - t) / 21 of
    unknown: above 0.5 up to block 29, below from 30: blocks 0-29 unknown, 30-59 known (one
    change of the label seen either way; the change of activity at 20 lies under unknown).
    At even odds (before) the gap went whole to the known side: only blocks 0-19 were
    unknown."""

    path = np.r_[np.zeros(20, dtype=np.int64), np.ones(40, dtype=np.int64)]
    windows = [_Solved(a, a + 10, np.ones(2) / 2, np.array([2.0, 3.0]), None) for a in (0, 5, 10)]
    windows += [
        _Solved(a, a + 10, np.ones(2) / 2, np.array([0.5, 3.0]), None) for a in (40, 45, 50)
    ]
    unknown = unknown_blocks(windows, 60, 10.0, _FirstFar(), path)
    assert unknown.tolist() == [True] * 30 + [False] * 30


def test_a_segment_too_short_for_a_window_centre_is_told_by_the_windows_over_it() -> None:
    """An unknown segment of frames 11-15 (10 fps, one block a frame) between the centres of
    the two windows over it (frames 0-20 and 14-34): its novelty is the median of their
    margins (0.95 and 0.5: 0.725), its confidence the mean evidence of unknown of its
    blocks (0.4, 0.6, 0.8, 1.0: 0.7), its explanation the median window's (the upper one of
    two: 0.95), and its JSON is strict (no NaN) even when no window lies over it."""
    from types import SimpleNamespace

    from cbr.segmentation import Segment, _segment_of

    classes = ["a", "b", "c"]
    clf = SimpleNamespace(classes_=np.array(classes))
    rec = SimpleNamespace(fps=10.0, n_frames=100)
    judge = Margin(threshold=0.8, basis="groups", known=10, novel=10)
    windows = [  # distances to the nearest case of a, b, c: margins 0.95 and 0.5
        _Solved(0, 20, np.eye(3)[0], np.array([0.95, 1.0, 3.0]), None),
        _Solved(14, 34, np.eye(3)[0], np.array([1.0, 2.0, 3.0]), None),
    ]
    votes = np.zeros((100, 4))  # per block: the three activities' votes, unknown's evidence
    votes[11:15, 3] = [0.4, 0.6, 0.8, 1.0]
    seg = _segment_of(clf, rec, (11, 15, 3), windows, votes, judge, [True, True], ())
    assert (seg.start_frame, seg.end_frame, seg.label) == (11, 15, None)
    assert seg.novelty == pytest.approx(0.725)
    assert seg.confidence == pytest.approx(0.7)
    assert "the nearest (a) is 0.95 as far as the next (b)" in seg.explanation
    alone = Segment(11, 15, None, 1.0, (), "", float("nan"))
    doc = json.loads(json.dumps(alone.to_dict(10.0), allow_nan=False))
    assert doc["novelty"] is None


def test_an_unknown_segment_is_explained_by_a_window_unlike_every_activity() -> None:
    """An unknown segment (frames 20-40, 10 fps) whose four windows centred in it have
    margins 0.5, 0.6, 0.7 and 0.95 against a threshold of 0.8: the explanation quotes the one
    window over the threshold (the median of all four, 0.7, would read "like no stored
    activity" beside a margin a known activity stays under). With no window unlike, the
    explanation says the segment is unknown on the evidence around it. Either way the
    confidence is its blocks' mean evidence of unknown (it was the share of its windows
    unlike: 0 for the verdict it gave)."""
    from types import SimpleNamespace

    from cbr.segmentation import _segment_of

    clf = SimpleNamespace(classes_=np.array(["a", "b", "c"]))
    rec = SimpleNamespace(fps=10.0, n_frames=100)
    judge = Margin(threshold=0.8, basis="groups", known=10, novel=10)

    def windows(*margins: float) -> list[_Solved]:  # centres 25, 28, 31, 34
        return [
            _Solved(15 + 3 * i, 35 + 3 * i, np.eye(3)[0], np.array([m, 1.0, 5.0]), None)
            for i, m in enumerate(margins)
        ]

    votes = np.zeros((100, 4))
    votes[20:40, 3] = np.linspace(0.45, 0.65, 20)  # unknown's evidence: from its neighbours
    seg = _segment_of(clf, rec, (20, 40, 3), windows(0.5, 0.6, 0.7, 0.95), votes, judge,
                      [True] * 4, ())  # fmt: skip
    assert seg.label is None and seg.confidence == pytest.approx(0.55)
    assert "the nearest (a) is 0.95 as far as the next (b)" in seg.explanation
    quiet = _segment_of(clf, rec, (20, 40, 3), windows(0.5, 0.6), votes, judge, [True] * 2, ())
    assert quiet.confidence == pytest.approx(0.55)
    assert quiet.explanation.startswith("unknown on the evidence around it")
    assert "like no stored activity" not in quiet.explanation


def test_segment_pictures_of_recordings_that_share_a_name_are_all_kept(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Two recordings both named 13_30.npz (in two folders) with --plot FOLDER: two pictures,
    13_30.png and 13_30_2.png (the second overwrote the first), in the folder made for them
    (it was refused as not there; hunt 47c). A --plot file name in no picture format: one
    line, exit 1, nothing written."""
    part = recordings["13_30"].slice_frames(0, 600)
    a = save_pose(part, tmp_path / "a" / "13_30.npz")
    b = save_pose(recordings["13_30"].slice_frames(600, 1200), tmp_path / "b" / "13_30.npz")
    plots = tmp_path / "plots"  # not there: made, as convert --out DIR makes its folder
    assert main(["segment", str(a), str(b), "--db", str(case_base), "--plot", str(plots)]) == 0
    assert sorted(p.name for p in plots.iterdir()) == ["13_30.png", "13_30_2.png"]
    assert (plots / "13_30.png").read_bytes() != (plots / "13_30_2.png").read_bytes()
    capsys.readouterr()
    text = tmp_path / "timeline.txt"
    before = _sha(a), _sha(case_base)
    assert main(["segment", str(a), "--db", str(case_base), "--plot", str(text)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the picture must be a file name ending in a format" in err
    assert not text.exists() and (_sha(a), _sha(case_base)) == before
    # several recordings and a --plot that is a file: said so, the file kept
    notes = tmp_path / "notes.txt"
    notes.write_text("mine\n", encoding="utf-8")
    assert main(["segment", str(a), str(b), "--db", str(case_base), "--plot", str(notes)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{notes}: with several recordings --plot names a" in err
    assert err.rstrip().endswith("this one is a file")
    assert (_sha(a), _sha(case_base), notes.read_text()) == (*before, "mine\n")


DEMO_CLIP = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


@pytest.mark.parametrize("name", ["timeline.SVG", "timeline.pdf"])
def test_segment_plot_is_written_in_the_format_its_name_asks(
    name: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--plot timeline.svg`` or ``.pdf`` (the suffix in any case) for a real recording: an
    SVG or a PDF, as ``describe --plot`` and ``reps --plot`` write (segment refused any name
    but .png)."""
    rec = Path(shutil.copy(DEMO_CLIP / "m01_s01_e01.npz", tmp_path / "m01_s01_e01.npz"))
    out = tmp_path / name
    assert main(["segment", str(rec), "--db", str(case_base), "--json", "--plot", str(out)]) == 0
    assert json.loads(capsys.readouterr().out)["segments"]
    data = out.read_bytes()
    if name.lower().endswith(".svg"):
        assert ElementTree.fromstring(data).tag.endswith("svg")
    else:
        assert data.startswith(b"%PDF-")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([rec.name, name])


@pytest.mark.parametrize("name", ["timeline.txt", "timeline.mp4", "timeline"])
def test_segment_plot_named_in_no_picture_format_is_refused(
    name: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec = Path(shutil.copy(DEMO_CLIP / "m01_s01_e01.npz", tmp_path / "m01_s01_e01.npz"))
    before = _sha(case_base)
    line = refused(["segment", str(rec), "--db", str(case_base), "--plot", str(tmp_path / name)],
                   tmp_path, capsys, str(tmp_path / name), "the picture must be a file name",
                   ".png, .svg, .pdf")  # fmt: skip
    suffix = Path(name).suffix
    assert (repr(suffix) if suffix else "no suffix") in line
    assert _sha(case_base) == before


def test_segment_k_beyond_what_a_window_retrieves_is_refused(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The case base retrieves its k (5, CaseBaseClassifier's default) nearest cases per
    window: -k 6 or 1000 is refused in one line (they were taken silently as 5); -k 5
    segments."""
    from cbr.estimator import CaseBaseClassifier

    k = CaseBaseClassifier().k
    rec = save_pose(recordings["13_30"].slice_frames(0, 600), tmp_path / "r.npz")
    before = _sha(rec), _sha(case_base)
    for bad in (k + 1, 1000):
        assert main(["segment", str(rec), "--db", str(case_base), "-k", str(bad)]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"-k: must be from 1 to the case base's k ({k}" in err
    assert (_sha(rec), _sha(case_base)) == before
    assert main(["segment", str(rec), "--db", str(case_base), "-k", str(k), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["segments"]


def test_segment_k_beyond_the_case_base_is_refused_before_any_recording_is_read(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """-k beyond the case base's k is known once the case base is open: refused then, before
    the recordings are read (before, after every recording was read and checked: a video's
    poses estimated for 12 s, then "-k: must be from 1 to the case base's k")."""
    import posecbr.commands.segment as command

    read: list[Path] = []
    real = command.load_recording

    def load(path: Path, *args: object) -> object:
        read.append(path)
        return real(path, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(command, "load_recording", load)
    rec = save_pose(recordings["13_30"].slice_frames(0, 600), tmp_path / "r.npz")
    line = refused(["segment", str(rec), "--db", str(case_base), "-k", "6"], tmp_path, capsys)
    assert "-k: must be from 1 to the case base's k (5" in line
    assert read == []


def test_a_recording_at_micrometre_scale_is_refused_naming_the_unit(
    recordings: dict[str, PoseSequence],
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A recording in metres scaled by 1e-6 (a person 2 µm tall): its pelvis still rises and
    falls, but no body frame can be built (shoulders under a micrometre apart). It was
    segmented as one stretch of "nobody in view", exit 0; refused in one line naming the
    unit, the case base and the recording unchanged."""
    from dataclasses import replace

    rec = recordings["13_30"].slice_frames(0, 600)
    tiny = save_pose(replace(rec, positions=rec.positions * 1e-6, source=""), tmp_path / "r.npz")
    before = _sha(tiny), _sha(case_base)
    assert main(["segment", str(tiny), "--db", str(case_base)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"posecbr segment: error: {tiny}: shows no")
    assert "within 1 µm of each other in every frame: positions must be metres" in err
    assert (_sha(tiny), _sha(case_base)) == before


def test_classifying_a_micrometre_recording_names_the_unit(
    recordings: dict[str, PoseSequence], classifier: CaseBaseClassifier
) -> None:
    from dataclasses import replace

    from features.errors import DataError

    rec = recordings["13_30"].slice_frames(0, 240)
    tiny = replace(rec, positions=rec.positions * 1e-6, source="tiny.npz")
    with pytest.raises(DataError, match="within 1 µm of each other in every frame: positions"):
        classifier.predict([tiny])
    assert classifier.predict([rec])[0] in set(classifier.classes_)  # metres: classified
