"""What makes a stretch unknown (cbr.unknown), on hand-made case bases whose margins and
thresholds are worked out by hand, and windows cut the way segment cuts them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cbr.casebase import CaseBase
from cbr.problem import FeatureConfig
from cbr.similarity import Euclidean
from cbr.unknown import (
    ACTIVITY_PRIOR,
    FALSE_UNKNOWN,
    JUDGES,
    NOVEL_CATCH,
    ActivityMargin,
    Margin,
    MarginDistance,
    Offset,
    activity_thresholds,
    calibration_margins,
    choose_weight,
    equal_error_threshold,
    false_unknown_threshold,
    for_person,
    held_out_basis,
    inner_scores,
    joint_thresholds,
    margin_of,
    person_offset,
    tell_unknown,
    unknown_evidence,
)
from features.datasets import Clip
from features.errors import ConfigError, DataError
from features.poses import PoseSequence
from features.repetitions import WINDOW_HOP_S, WINDOW_S, split_windows
from features.skeleton import BLAZEPOSE_33


def _line(
    xs: list[float],
    labels: list[str],
    sources: list[str],
    subjects: list[str | None] | None = None,
    frames: list[tuple[int, int]] | None = None,
) -> CaseBase:
    """Cases on a line: problem = (x, 0), so every distance is |x_i - x_j|."""
    p = np.array([[x, 0.0] for x in xs])
    return CaseBase(
        FeatureConfig(),
        Euclidean(exact=True),
        p,
        labels,
        ("x", "y"),
        ("x", "y"),
        sources=tuple(sources),
        subjects=tuple(subjects or [None] * len(xs)),
        frames=tuple(frames or []),
    )


def test_margin_of_by_hand() -> None:
    assert margin_of(np.array([3.0, 1.0, 4.0])) == pytest.approx(1 / 3)
    assert margin_of(np.array([2.0, math.inf, 5.0])) == pytest.approx(0.4)
    assert margin_of(np.array([0.0, 5.0])) == 0.0  # the window is a case
    assert margin_of(np.array([2.0, math.inf])) == 1.0  # nothing to compare with
    assert margin_of(np.array([0.0, 0.0])) == 1.0  # as near to both


def test_equal_error_threshold_by_hand() -> None:
    # at 0.35 one known value of four lies above (0.4) and one novel of four at or below
    # (0.35): 1/4 = 1/4; at 0.3, 1/4 vs 0; at 0.4, 0 vs 1/4
    known = np.array([0.1, 0.2, 0.3, 0.4])
    novel = np.array([0.35, 0.5, 0.6, 0.7])
    assert equal_error_threshold(known, novel) == pytest.approx(0.35)
    # apart: the first value with no error either side is the largest known one
    assert equal_error_threshold(np.array([0.1, 0.2]), np.array([0.5, 0.6])) == 0.2


def test_false_unknown_threshold_by_hand() -> None:
    """Twenty known margins 0.05, 0.10, ..., 1.00 (shuffled): at most 5 % of them (one) may
    lie above the threshold, so it is the 19th, 0.95; at 10 % (two) the 18th, 0.90; at 0 the
    largest. Never between two samples: of 0.2 and 0.4, at 40 % (0.8 of a value, so none
    above) 0.4."""
    known = np.random.default_rng(1).permutation(np.arange(1, 21) * 0.05)
    assert FALSE_UNKNOWN == 0.05
    assert false_unknown_threshold(known) == pytest.approx(0.95)
    assert false_unknown_threshold(known, 0.10) == pytest.approx(0.90)
    assert false_unknown_threshold(known, 0.0) == pytest.approx(1.00)
    assert false_unknown_threshold(np.array([0.4, 0.2]), 0.4) == pytest.approx(0.4)
    assert false_unknown_threshold(np.array([0.4, 0.2]), 0.5) == pytest.approx(0.2)
    with pytest.raises(ConfigError, match="false-unknown rate must be in"):
        false_unknown_threshold(known, 1.0)


def test_the_threshold_spends_the_false_unknown_budget_not_the_equal_error_point() -> None:
    """Known margins 0.1-0.9 with one in ten at 0.9 (a person the other people's cases fit
    badly), novel margins 0.5-1.0: at the equal-error point (0.5: 2 of 10 known above, 2 of
    10 novel at or below) a fifth of known windows would be called unknown; the budget of 5 %
    puts the threshold at the largest known margin but none (0.9 is one of ten: 10 % > 5 %,
    so 0.9 itself)."""
    known = np.array([0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5, 0.6, 0.9])
    novel = np.array([0.45, 0.5, 0.55, 0.6, 0.7, 0.75, 0.8, 0.85, 0.9, 1.0])
    assert equal_error_threshold(known, novel) == pytest.approx(0.5)
    assert false_unknown_threshold(known) == pytest.approx(0.9)
    assert false_unknown_threshold(known, 0.2) == pytest.approx(0.5)


def _two_recordings(people: bool = False) -> CaseBase:
    """Recording r1: a at 0, b at 10, c at 20; recording r2: a at 1, b at 12, c at 23
    (``people``: each recording named as a person of its own)."""
    sources = ["r1", "r1", "r1", "r2", "r2", "r2"]
    return _line(
        [0.0, 10.0, 20.0, 1.0, 12.0, 23.0],
        ["a", "b", "c", "a", "b", "c"],
        sources,
        subjects=list(sources) if people else None,
    )


def test_margin_is_calibrated_by_holding_out_recordings_and_activities() -> None:
    """Each case against the other recording's cases. Known margins (its own activity there):
    a@0: 1/12, b@10: 2/9, c@20: 3/8, a@1: 1/9, b@12: 2/8, c@23: 3/13. Novel margins (its
    activity gone too): a@0: 12/23, b@10: 9/13, c@20: 8/19, a@1: 9/19, b@12: 8/12, c@23:
    13/23. A budget of 5 % of 6 known margins (0.3) lets none lie above: the threshold is the
    largest known margin, 3/8, when the recordings are two people. As recordings of one
    person, no threshold lies below the novel margin at most 80 % (4.8) of the six exceed
    (sorted 8/19, 9/19, 12/23, 13/23, 8/12, 9/13: the second; five exceed the first), 9/19."""
    one = Margin.of(_two_recordings())
    assert (one.threshold, one.floor) == (pytest.approx(9 / 19), pytest.approx(9 / 19))
    assert not one.unlike(np.array([4.5, 10.0, 20.0]))  # margin 0.45
    assert one.unlike(np.array([5.0, 10.0, 20.0]))  # 0.5
    cb = _two_recordings(people=True)
    known, novel, basis = calibration_margins(cb)
    assert basis == "subject"
    np.testing.assert_allclose(known, [1 / 12, 2 / 9, 3 / 8, 1 / 9, 2 / 8, 3 / 13])
    np.testing.assert_allclose(novel, [12 / 23, 9 / 13, 8 / 19, 9 / 19, 8 / 12, 13 / 23])
    judge = Margin.of(cb)
    assert judge.threshold == pytest.approx(3 / 8) and judge.floor == 0.0
    assert (judge.known, judge.novel, judge.basis) == (6, 6, "subject")
    assert judge.unlike(np.array([5.0, 10.0, 20.0]))
    # a window at 5: a at 4, b at 5, c at 15 -> 4/5 = 0.8: between a and b, like neither
    assert judge.unlike(np.array([4.0, 5.0, 15.0]))
    assert "the nearest (a) is 0.80 as far as the next (b)" in judge.describe(
        np.array([4.0, 5.0, 15.0]), ["a", "b", "c"]
    )
    # a window at 11: a at 10, b at 1, c at 9 -> 1/9: b
    assert not judge.unlike(np.array([10.0, 1.0, 9.0]))
    # a budget of 20 %: at most 1.2 of the 6 known margins above, so one: sorted 1/12, 1/9,
    # 2/9, 3/13, 1/4, 3/8, the threshold is 1/4 (a window at margin 0.3 is now unknown)
    strict = Margin.of(cb, false_unknown=0.2)
    assert strict.threshold == pytest.approx(1 / 4) and strict.false_unknown == 0.2
    assert strict.unlike(np.array([3.0, 10.0, 20.0])) and not judge.unlike(
        np.array([3.0, 10.0, 20.0])
    )


def test_a_new_person_farther_from_everything_keeps_the_margin() -> None:
    """Scaling every distance changes no margin: what makes a window unknown is how its two
    nearest activities compare, not how far the person lies from the stored ones."""
    judge = Margin.of(_two_recordings())
    near = np.array([10.0, 1.0, 9.0])
    assert judge.ratio(near) == judge.ratio(5.0 * near) and not judge.unlike(5.0 * near)


def test_joint_thresholds_by_hand() -> None:
    """Ten held-out known cases, margin i/10 and nearest distance i (i = 1..10); the margin
    alone flags 1.0 (above 0.95); a budget of 10 % (one case) for the rest. At q = 0.70 the
    quantiles are 0.7 and 7 (three values above each): cases 8, 9 fall in the rule (10 is
    the margin's already), 20 %; just above 0.70 they are 0.8 and 8: case 9 alone, 10 %."""
    i = np.arange(1, 11, dtype=np.float64)
    a, b = joint_thresholds(i / 10, i, 0.95, 0.10)
    assert (a, b) == (pytest.approx(0.8), pytest.approx(8.0))
    # no budget: 0.9 and 9, beyond which lies case 10 only, which the margin flags already
    a0, b0 = joint_thresholds(i / 10, i, 0.95, 0.0)
    assert (a0, b0) == (pytest.approx(0.9), pytest.approx(9.0))
    # nothing flagged by the margin alone and no budget: no quantile is safe but the top
    assert joint_thresholds(i / 10, i, 1.0, 0.0) == (pytest.approx(1.0), pytest.approx(10.0))


def test_margin_distance_calibrated_by_hand() -> None:
    """The two recordings of the margin test: known margins 1/12, 2/9, 3/8, 1/9, 1/4, 3/13
    with nearest same-activity distances 1, 2, 3, 1, 2, 3. Budget 5 %, half each (0.15 of a
    case: none may fall in either rule): the margin alone 3/8 (the largest); the joint rule
    at q just above 2/3, where the quantiles are 1/4 and 3 (below: 3/13 and 2, which c@20,
    margin 3/8 at distance 3, would exceed both)."""
    judge = MarginDistance.of(_two_recordings())
    assert judge.margin == pytest.approx(3 / 8)
    assert (judge.joint_margin, judge.joint_distance) == (pytest.approx(1 / 4), 3.0)
    assert (judge.basis, judge.known) == ("recording", 6)
    # between a and b: 4/5 -> unknown by the margin alone
    assert judge.unlike(np.array([4.0, 5.0, 15.0]))
    # margin 4/13 (0.31: known by the margin alone) with its nearest case 4 away (> 3)
    assert judge.unlike(np.array([4.0, 13.0, 14.0]))
    assert "as far as held-out cases" in judge.describe(np.array([4.0, 13.0, 14.0]), "abc")
    # the same margin 2 away: near enough to be the activity
    assert not judge.unlike(np.array([2.0, 6.5, 7.0]))
    # far (15) but clear (margin 15/75 = 0.2 < 1/4): a new person doing a known movement
    assert not judge.unlike(np.array([15.0, 75.0, 90.0]))
    assert "margin-distance" in JUDGES


def test_activity_thresholds_by_hand() -> None:
    """Margins of activity 0: 0.1, 0.2 (own quantile at 5 %: the largest, 0.2); activity 1:
    0.4, 0.6 (0.6); activity 2 none. Pooled: the largest of the four, 0.6. With 2 cases'
    worth of prior: (2 * 0.2 + 2 * 0.6) / 4 = 0.4 for activity 0, 0.6 for 1 and 2."""
    m = np.array([0.1, 0.4, 0.2, 0.6])
    per, pooled = activity_thresholds(m, np.array([0, 1, 0, 1]), 3, FALSE_UNKNOWN, 2.0)
    assert pooled == pytest.approx(0.6)
    np.testing.assert_allclose(per, [0.4, 0.6, 0.6])
    own, _ = activity_thresholds(m, np.array([0, 1, 0, 1]), 3, FALSE_UNKNOWN, 0.0)
    np.testing.assert_allclose(own, [0.2, 0.6, 0.6])
    assert ACTIVITY_PRIOR == pytest.approx(1.0 / FALSE_UNKNOWN)


def _one_wrongly_named() -> CaseBase:
    """Person r1: a at 0, b at 10, c at 20; person r2: a at 1 and 9, b at 12, c at 23 (two
    people: held out by person, thresholds with no floor of one person's)."""
    return _line(
        [0.0, 10.0, 20.0, 1.0, 9.0, 12.0, 23.0],
        ["a", "b", "c", "a", "a", "b", "c"],
        ["r1", "r1", "r1", "r2", "r2", "r2", "r2"],
        subjects=["r1", "r1", "r1", "r2", "r2", "r2", "r2"],
    )


def test_activity_margin_calibrated_by_hand() -> None:
    """Each case held out against the other person. r1: a@0 (a 1, b 12: 1/12), b@10 (a@9
    at 1, b 2: nearest a, wrong, 1/2), c@20 (c 3, b 8: 3/8); r2: a@1 (a 1, b 9: 1/9), a@9
    (b@10 at 1, a 9: wrong, 1/9), b@12 (b 2, c 8: 1/4), c@23 (c 3, b 13: 3/13). The margin
    pools all seven, so its threshold is the wrong b@10's 1/2; the activity margin keeps the
    five named rightly: pooled 3/8 (the largest of five: 5 % of 5 lets none above); own
    thresholds a 1/9, b 1/4, c 3/8; with 20 cases' prior a (2/9 + 20 * 3/8) / 22, b (1/4 +
    20 * 3/8) / 21, c 3/8."""
    cb = _one_wrongly_named()
    assert Margin.of(cb).threshold == pytest.approx(1 / 2)
    judge = ActivityMargin.of(cb, prior=ACTIVITY_PRIOR)
    assert (judge.pooled, judge.known, judge.basis) == (pytest.approx(3 / 8), 5, "subject")
    expected = [(2 / 9 + 7.5) / 22, (1 / 4 + 7.5) / 21, 3 / 8]
    np.testing.assert_allclose(judge.thresholds, expected)
    own = ActivityMargin.of(cb, prior=0.0)
    np.testing.assert_allclose(own.thresholds, [1 / 9, 1 / 4, 3 / 8])
    # the same margin 0.36 nearest a (threshold 0.351) and nearest c (0.375); the margin's
    # pooled 1/2 calls neither unknown
    near_a, near_c = np.array([3.6, 10.0, 20.0]), np.array([20.0, 10.0, 3.6])
    assert judge.unlike(near_a) and not judge.unlike(near_c)
    assert not Margin.of(cb).unlike(near_a)
    assert "a known a comes nearer than 0.35" in judge.describe(near_a, ["a", "b", "c"])
    # with no prior a clear activity's own threshold is low: margin 0.2 nearest a is unknown
    assert own.unlike(np.array([2.0, 10.0, 20.0])) and not judge.unlike(np.array([2.0, 10.0, 20.0]))
    assert "activity-margin" in JUDGES


def test_activity_margin_chooses_its_weight_by_hand() -> None:
    """The rightly named cases of :func:`_one_wrongly_named` by person: r1 a 1/12, c 3/8;
    r2 a 1/9, b 1/4, c 3/13. r1 held out, thresholds from r2 (pooled 1/4, the largest of
    three at any rate up to 5 %): c's 3/8 lies above c's own 3/13 and the pooled 1/4, at any
    prior. r2 held out, from r1 (pooled 3/8, a's own 1/12): a's 1/9 lies above a's
    threshold (1/12 + 3/8 p) / (1 + p) at p = 0 only (at 5 it is 0.33). So 2 of 5 over at
    prior 0, 1 of 5 at every other: none keeps 5 %, and the least over-call with the largest
    rate and prior is taken: 5 % and inf, every threshold the pooled 3/8."""
    judge = ActivityMargin.of(_one_wrongly_named())
    assert (judge.rate, judge.prior, judge.false_unknown) == (FALSE_UNKNOWN, math.inf, 0.05)
    np.testing.assert_allclose(judge.thresholds, [3 / 8] * 3)
    assert "(in 95 % of the case base's held-out cases)" in judge.describe(
        np.array([3.6, 10.0, 20.0]), ["a", "b", "c"]
    )


def _two_people() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Held-out distances to activities a, b, c, d of one case of each per person p and q
    (``seen`` ``(8, 4)``, activity codes, groups). Margins: a 0.1 (p) and 0.2 (q), b and c
    0.8 (4 / 5: alike), d 1 / 7.2; with d gone, d's case lies 7.2 / 10 = 0.72 from a."""
    clear = [[1.0, 10.0, 10.0, 10.0], [2.0, 10.0, 10.0, 10.0]]
    alike = [[10.0, 4.0, 5.0, 10.0], [10.0, 5.0, 4.0, 10.0]]
    like_a = [7.2, 10.0, 10.0, 1.0]
    seen = np.array([clear[0], *alike, like_a, clear[1], *alike, like_a])
    return seen, np.array([0, 1, 2, 3] * 2), np.array(["p"] * 4 + ["q"] * 4)


def test_inner_scores_by_hand() -> None:
    """Known cases, q held out (thresholds from p: pooled 0.8, the largest of four at any
    rate up to 5 %; a's own 0.1): q's a (0.2) lies above a's (0.1 + 0.8 w) / (1 + w) at w =
    0 only; p held out: nothing above (a's 0.1 below q's 0.2; the others equal theirs, not
    above). Over: 1/8 at 0, 0 at 10. Gone activities: a's case (1.0, nearest b) above b's
    0.8, and b's (0.5, nearest c) above c's 0.4 (and so c's), in both people; d's (0.72,
    nearest a) above a's threshold (0.2 + 0.8 w) / (1 + w) from q (0.2 at 0, 0.7 at 5, 0.745
    at 10) and (0.1 + 0.8 w) / (1 + w) from p (0.1, 0.683, 0.736): caught at 0 and 5, not
    at 10. Caught: 8/8, 8/8, 6/8."""
    seen, codes, groups = _two_people()
    over, caught = inner_scores(seen, codes, groups, [(0.05, 0.0), (0.05, 5.0), (0.01, 10.0)])
    np.testing.assert_allclose(over, [1 / 8, 0.0, 0.0])
    np.testing.assert_allclose(caught, [1.0, 1.0, 6 / 8])


def test_choose_weight_by_hand() -> None:
    """Of :func:`test_inner_scores_by_hand`'s weights, prior 0 over-calls (1/8 > 5 %) and 5
    catches the most of those that keep the budget (every rate reads the same quantile from
    one or four cases: the largest rate is taken). Without an activity held out in two
    groups (each activity a recording of its own) the weight stays 20 at the budget."""
    seen, codes, groups = _two_people()
    assert choose_weight(seen, codes, groups) == (FALSE_UNKNOWN, 5.0)
    assert choose_weight(seen, codes, np.array(list("abcdabcd"))) == (
        FALSE_UNKNOWN,
        ACTIVITY_PRIOR,
    )


def test_activity_margin_stored_before_the_weight_was_chosen_reads_as_before() -> None:
    """A record without ``rate`` (stored when the weight was 20 and the rate the budget)
    comes back with the budget as its rate: the same thresholds and the same words."""
    judge = ActivityMargin.of(_one_wrongly_named(), prior=ACTIVITY_PRIOR)
    old = {k: v for k, v in judge.to_dict().items() if k != "rate"}
    back = ActivityMargin.from_dict(old)
    assert back == judge and (back.rate, back.prior) == (0.05, 20.0)


def test_held_out_by_subject_then_recording_then_time() -> None:
    by_subject = _line([0, 1, 10, 11, 20, 21], list("aabbcc"), ["v"] * 6, list("pqpqpq"))
    assert held_out_basis(by_subject)[0] == "subject"
    # one subject: recordings
    one_person = _line([0, 1, 10, 11, 20, 21], list("aabbcc"), list("rsrsrs"), ["p"] * 6)
    assert held_out_basis(one_person)[0] == "recording"
    # one recording: the cases overlapping in time are left out
    frames = [(0, 240), (120, 360), (480, 720), (800, 1040), (1100, 1340), (1400, 1640),
              (1700, 1940)]  # fmt: skip
    one = _line([0, 0.5, 2, 10, 11, 20, 22], list("aaabbcc"), ["rec"] * 7, frames=frames)
    known, novel, basis = calibration_margins(one)
    assert basis == "time"
    # a@0 held out without itself and a@0.5 (frames overlap): a@2 at 2, b@10 at 10 -> 2/10
    assert known[0] == pytest.approx(0.2)
    # and without any a: b@10 at 10, c@20 at 20 -> 1/2
    assert novel[0] == pytest.approx(0.5)


def test_margin_needs_three_activities() -> None:
    two = _line([0, 1, 10, 11], list("aabb"), ["r", "s", "r", "s"])
    with pytest.raises(DataError, match="fewer than three activities"):
        Margin.of(two)


def _clip(n_frames: int, fps: float) -> Clip:
    rng = np.random.default_rng(0)
    seq = PoseSequence(rng.normal(size=(n_frames, 33, 3)), BLAZEPOSE_33, fps, source="c.npz")
    return Clip(seq, "squat", "s1", {})


def test_split_windows_cuts_as_segment_does() -> None:
    """A 5.3-s clip at 30 fps (159 frames): windows of 60 frames starting every 15 frames,
    as many as fit whole: starts 0, 15, ..., 90 (7 windows); a 1.5-s clip stays whole."""
    assert (WINDOW_S, WINDOW_HOP_S) == (2.0, 0.5)
    split = split_windows([_clip(159, 30.0), _clip(45, 30.0)])
    assert split.kept_whole == 1 and len(split.clips) == 8
    windows = split.clips[:7]
    assert [w.seq.metadata["frame_offset"] for w in windows] == list(range(0, 91, 15))
    assert all(w.seq.n_frames == 60 and w.label == "squat" for w in windows)
    assert [w.extras["window"] for w in windows] == list(range(1, 8))
    assert split.clips[7].seq.n_frames == 45


def test_activity_margin_is_stored_as_a_record_with_its_thresholds_listed() -> None:
    """Its per-activity thresholds go to a list of numbers and come back as the same judge; a
    list holding a negative threshold is refused naming the field."""
    judge = ActivityMargin.of(_one_wrongly_named())
    record = judge.to_dict()
    assert record["thresholds"] == list(judge.thresholds)
    assert ActivityMargin.from_dict(record) == judge
    with pytest.raises(ValueError, match="'thresholds'"):
        ActivityMargin.from_dict({**record, "thresholds": [0.3, -0.1, 0.2]})
    with pytest.raises(ValueError, match="'thresholds'"):
        ActivityMargin.from_dict({**record, "thresholds": 0.3})


def test_activity_margin_evidence_is_graded_between_the_budget_and_its_threshold() -> None:
    """Thresholds (0.8, 0.9, 0.7) at the chosen rate, (0.6, 0.9, 0.5) at the whole budget.
    Nearest activity 0: a margin 0.5 (1/2) is no evidence, 0.7 (0.7/1) is half-way, (0.7 -
    0.6) / (0.8 - 0.6) = 0.5, 0.85 above the threshold is 1 (and unlike). Activity 1, whose
    two thresholds are one: 0.89 is 0, 0.95 is 1. A record stored without the budget's
    thresholds judges all or nothing: 0.7 for activity 0 gives 0."""
    judge = ActivityMargin((0.8, 0.9, 0.7), 0.8, "subject", 12, rate=0.03,
                           budget_thresholds=(0.6, 0.9, 0.5))  # fmt: skip
    assert judge.evidence(np.array([1.0, 2.0, 5.0])) == 0.0
    assert judge.evidence(np.array([0.7, 1.0, 5.0])) == pytest.approx(0.5)
    assert judge.evidence(np.array([0.85, 1.0, 5.0])) == 1.0 and judge.unlike(
        np.array([0.85, 1.0, 5.0])
    )
    assert judge.evidence(np.array([5.0, 0.89, 1.0])) == 0.0
    assert judge.evidence(np.array([5.0, 0.95, 1.0])) == 1.0
    old = ActivityMargin.from_dict(
        {k: v for k, v in judge.to_dict().items() if k != "budget_thresholds"}
    )
    assert old.budget_thresholds == () and old.evidence(np.array([0.7, 1.0, 5.0])) == 0.0
    with pytest.raises(ValueError, match="'budget_thresholds' has 1 values for 3 activities"):
        ActivityMargin.from_dict({**judge.to_dict(), "budget_thresholds": [0.6]})
    # every other judge: all or nothing, as its unlike says
    margin = Margin(0.6, "subject", 10, 10)
    assert unknown_evidence(margin, np.array([0.7, 1.0, 5.0])) == 1.0
    assert unknown_evidence(margin, np.array([0.5, 1.0, 5.0])) == 0.0
    assert unknown_evidence(judge, np.array([0.7, 1.0, 5.0])) == pytest.approx(0.5)


def test_activity_margin_budget_thresholds_lie_at_or_below_its_own() -> None:
    """Read at the whole budget, a quantile lies at or below one read at a smaller rate; with
    the prior given the rate is the budget and the two are one (evidence all or nothing)."""
    cb = _one_wrongly_named()
    chosen = ActivityMargin.of(cb)
    assert len(chosen.budget_thresholds) == len(chosen.thresholds)
    assert all(b <= t for b, t in zip(chosen.budget_thresholds, chosen.thresholds, strict=True))
    fixed = ActivityMargin.of(cb, prior=ACTIVITY_PRIOR)
    assert fixed.budget_thresholds == fixed.thresholds


def _between() -> CaseBase:
    """Two recordings (r1, r2) of activities a, b, c on a line, a between the other two:
    r1 a@0, b@-10, c@10; r2 a@1, b@-11, c@11."""
    xs = [0.0, -10.0, 10.0, 1.0, -11.0, 11.0]
    return _line(xs, ["a", "b", "c"] * 2, ["r1"] * 3 + ["r2"] * 3)


def test_one_person_thresholds_call_most_held_out_novel_cases_unknown() -> None:
    """Each case of :func:`_between` held out against the other recording. Known margins
    (own activity in): a@0 1/11, b@-10 1/11, c@10 1/9, a@1 1/9, b@-11 1/11, c@11 1/11: every
    threshold at most 1/9. Novel margins (own activity gone): a@0 11/11 (b and c both 11
    away), b@-10 11/21, c@10 9/21, a@1 9/11, b@-11 11/21, c@11 11/21; sorted 9/21, 11/21
    (three times), 9/11, 1: at most 80 % (4.8) of the six lie above the second (five above
    the first), 11/21: the floor, so every threshold is 11/21. The same cases named as two
    people are held out by person, and keep their own thresholds."""
    assert NOVEL_CATCH == 0.8
    judge = ActivityMargin.of(_between())
    assert judge.basis == "recording"
    assert judge.floor == pytest.approx(11 / 21)
    np.testing.assert_allclose(judge.thresholds, [11 / 21] * 3)
    np.testing.assert_allclose(judge.budget_thresholds, [11 / 21] * 3)
    assert not judge.unlike(np.array([5.0, 10.0, 20.0]))  # margin 0.5 < 11/21
    assert judge.unlike(np.array([6.0, 10.0, 20.0]))  # 0.6
    assert judge.evidence(np.array([5.0, 10.0, 20.0])) == 0.0
    people = _line(
        [0.0, -10.0, 10.0, 1.0, -11.0, 11.0], ["a", "b", "c"] * 2, ["r1"] * 3 + ["r2"] * 3,
        subjects=["p"] * 3 + ["q"] * 3,
    )  # fmt: skip
    by_person = ActivityMargin.of(people)
    assert (by_person.basis, by_person.floor) == ("subject", 0.0)
    assert max(by_person.thresholds) <= 1 / 9 + 1e-12
    assert by_person.unlike(np.array([5.0, 10.0, 20.0]))
    # a record stored before the floor loads with none
    old = {k: v for k, v in judge.to_dict().items() if k != "floor"}
    assert ActivityMargin.from_dict(old).floor == 0.0


def test_person_offset_by_hand() -> None:
    """The tenth quantile of the windows' distances to their nearest case (numpy's linear
    one: of 0, 1, ..., 9 it is 0.9) less the reach, shrunk by 8 windows' worth: 10 windows,
    reach 0.4: (0.9 - 0.4) * 10 / 18 = 5/18. Windows at no finite distance are not counted;
    a recording nearer than the reach has no offset; an unmeasured reach (inf) none."""
    assert person_offset(np.arange(10.0), 0.4) == pytest.approx(5 / 18)
    assert person_offset(np.r_[np.arange(10.0), np.inf], 0.4) == pytest.approx(5 / 18)
    assert person_offset(np.full(24, 5.0), 1.0) == pytest.approx(4 * 24 / 32)
    assert person_offset(np.full(24, 0.5), 1.0) == 0.0
    assert person_offset(np.full(24, 5.0), math.inf) == 0.0
    assert person_offset(np.zeros(0), 1.0) == 0.0


def test_a_person_farther_from_every_case_is_measured_and_taken_off() -> None:
    """:func:`_two_recordings` as one person's: held out from the other recording, the
    nearest case of each lies 1 (a), 2 (b) or 3 (c) away, twice; the reach, their tenth
    quantile (sorted 1, 1, 2, 2, 3, 3: half-way between the first two), is 1. A recording
    whose 24 windows lie 5 from their nearest case lies 4 farther, shrunk to 4 * 24 / 32 =
    3. A window at 6, 10, 20 (margin 0.6, above the threshold 9/19) is 3, 7, 17 less the
    offset: 3/7, below it."""
    judge = Margin.of(_two_recordings())
    assert judge.reach == pytest.approx(1.0)
    person = for_person(judge, np.full(24, 5.0))
    assert isinstance(person, Offset) and person.offset == pytest.approx(3.0)
    w = np.array([6.0, 10.0, 20.0])
    assert judge.unlike(w) and not person.unlike(w)
    assert person.ratio(w) == pytest.approx(3 / 7)
    assert "each distance taken 3 shorter first" in person.describe(w, ["a", "b", "c"])
    assert for_person(judge, np.full(24, 0.5)).offset == 0.0  # type: ignore[attr-defined]
    # held out by person, the held-out cases already lie as far as a new person: no offset
    people = Margin.of(_two_recordings(people=True))
    assert math.isinf(people.reach) and for_person(people, np.full(24, 5.0)) is people
    # the reach is stored; a record stored before it has none (inf) and takes no offset
    assert Margin.from_dict(judge.to_dict()) == judge
    old = Margin.from_dict({k: v for k, v in judge.to_dict().items() if k != "reach"})
    assert math.isinf(old.reach) and for_person(old, np.full(24, 5.0)) is old


def test_the_activity_margin_grades_the_distances_less_the_offset() -> None:
    """:func:`_between`: every held-out known case's nearest lies 1 away (the reach 1), every
    threshold and budget threshold 11/21. A window at 6, 10, 20 (margin 0.6) is unknown; less
    the offset 3 of 24 windows at 5 (3, 7, 17: 3/7) it is known, evidence 0; at 6.5, 8, 20
    (0.8125) it is unknown either way (3.5/5 = 0.7)."""
    judge = ActivityMargin.of(_between())
    assert judge.reach == pytest.approx(1.0)
    person = for_person(judge, np.full(24, 5.0))
    w = np.array([6.0, 10.0, 20.0])
    assert unknown_evidence(judge, w) == 1.0 and unknown_evidence(person, w) == 0.0
    far = np.array([6.5, 8.0, 20.0])
    assert unknown_evidence(judge, far) == 1.0 and unknown_evidence(person, far) == 1.0
    assert person.ratio(far) == pytest.approx(0.7)


def test_an_unknown_stretch_is_told_by_a_window_unlike_every_activity() -> None:
    """Four windows of an unknown stretch with margins 0.5, 0.6, 0.7 and 0.95 (distances a, b,
    c: margin = a / b), the threshold 0.8: only 0.95 is unlike, so it tells the stretch (the
    median of all four, 0.7, lies under the threshold and would contradict "like no stored
    activity"). Of two unlike windows (0.9, 0.95), the upper one. None unlike (0.5, 0.6):
    the words say the stretch is unknown on the evidence around it, quoting no margin."""
    judge = Margin(threshold=0.8, basis="groups", known=10, novel=10)
    classes = ["a", "b", "c"]

    def windows(*margins: float) -> list[tuple[Margin, np.ndarray]]:
        return [(judge, np.array([m, 1.0, 5.0])) for m in margins]

    text = tell_unknown(windows(0.5, 0.6, 0.7, 0.95), classes)
    assert text.startswith("like no stored activity: the nearest (a) is 0.95 as far as")
    assert "is 0.95 as far" in tell_unknown(windows(0.9, 0.5, 0.95), classes)
    quiet = tell_unknown(windows(0.5, 0.6), classes)
    assert quiet == (
        "unknown on the evidence around it; its own windows (nearest: a) are not unlike every"
        " stored activity"
    )
    assert tell_unknown([], classes) == ""
