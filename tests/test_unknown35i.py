"""The spread-far judge (cbr.unknown.SpreadFar, ``--unknown spread-far``): the spread-margin
judge, or unknown when the window's distance to its nearest case lies beyond the distance
that 5 % of the case base's held-out known cases exceed; bounds and verdicts worked out by
hand on hand-made distances and case bases on a line."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from cbr.casebase import CaseBase
from cbr.problem import FeatureConfig
from cbr.similarity import Euclidean
from cbr.stored import load_classifier
from cbr.unknown import (
    AT_FIT,
    JUDGES,
    STORED,
    Offset,
    SpreadFar,
    SpreadMargin,
    calibrate_judges,
    for_person,
    judge_of,
    judges_from_dict,
    judges_to_dict,
    unknown_evidence,
)
from features.joining import join_repetitions
from features.poses import load_pose, save_pose
from posecbr.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


def _judge(far: float) -> SpreadFar:
    """tests/test_unknown28's spread-margin rule (thresholds 1 and 2, at the budget 0.5 and
    1, spreads 2 and 1, power 1) with the far bound ``far``."""
    return SpreadFar((1.0, 2.0), 1.0, "subject", 10, budget_thresholds=(0.5, 1.0), rate=0.01,
                     spreads=(2.0, 1.0), power=1.0, far=far)  # fmt: skip


def _plain() -> SpreadMargin:
    return SpreadMargin((1.0, 2.0), 1.0, "subject", 10, budget_thresholds=(0.5, 1.0),
                        rate=0.01, spreads=(2.0, 1.0), power=1.0)  # fmt: skip


def test_spread_far_rule_by_hand() -> None:
    """Far bound 10. (11, 100): score 0.11 * 11 / 2 = 0.605, below a's threshold 1 and above
    its budget threshold 0.5: spread-margin says known with evidence (0.605 - 0.5) / 0.5 =
    0.21; its nearest distance 11 lies beyond 10: unknown, evidence 1, told by its
    distance. (10, 100): 0.1 * 5 = 0.5, at the bound, not beyond it: known, evidence 0.
    (4, 5): 0.8 * 2 = 1.6 above 1: unknown by both, told as spread-margin tells it. (3,
    5): 0.6 * 1.5 = 0.9: evidence 0.8 from both."""
    plain, judge = _plain(), _judge(10.0)
    far = np.array([11.0, 100.0])
    assert not plain.unlike(far) and unknown_evidence(plain, far) == pytest.approx(0.21)
    assert judge.unlike(far) and unknown_evidence(judge, far) == 1.0
    words = judge.describe(far, ["a", "b"])
    assert "its nearest case (a) lies 11 away, farther than 10" in words
    assert "which 5 % of the case base's held-out cases exceed" in words
    at = np.array([10.0, 100.0])
    assert not judge.unlike(at) and unknown_evidence(judge, at) == 0.0
    both = np.array([4.0, 5.0])
    assert judge.unlike(both) and judge.describe(both, ["a", "b"]) == plain.describe(
        both, ["a", "b"]
    )
    assert unknown_evidence(judge, np.array([3.0, 5.0])) == pytest.approx(0.8)
    # no bound: spread-margin's verdicts
    assert not _judge(math.inf).unlike(far)
    assert unknown_evidence(_judge(math.inf), far) == pytest.approx(0.21)


def _line(xs: list[float], labels: list[str], people: list[str], subjects: bool) -> CaseBase:
    """Cases on a line: problem = (x, 0), every distance |x_i - x_j|; ``people`` the
    recordings, named as subjects too when ``subjects``."""
    return CaseBase(FeatureConfig(), Euclidean(exact=True), np.array([[x, 0.0] for x in xs]),
                    np.array(labels), ("x", "y"), ("x", "y"), sources=tuple(people),
                    subjects=tuple(people) if subjects else tuple([None] * len(xs)))  # fmt: skip


def test_spread_far_calibrated_on_two_people_by_hand() -> None:
    """tests/test_unknown28's two people (r1: a 0, b 10, c 20; r2: a 1 and 9, b 12, c 23),
    held out by person; spread-margin there is the margin alone against 3/8 for every
    activity. The seven held-out cases' distances to a, b, c: r1 (1, 12, 23), (1, 2, 13),
    (11, 8, 3); r2 (1, 9, 19), (9, 1, 11), (12, 2, 8), (23, 13, 3): nearest 1, 1, 3, 1, 1,
    2, 3; at most 5 % of seven (0.35) may exceed the bound: the largest, 3. At a budget of
    30 % (2.1 of them): 2. A window at (4, 40, 40) (margin 0.1) is unknown by its distance
    alone; one at (3, 40, 40) lies at the bound: known; (2.5, 2.6, 10) by its margin."""
    cb = _line([0.0, 10.0, 20.0, 1.0, 9.0, 12.0, 23.0], ["a", "b", "c", "a", "a", "b", "c"],
               ["r1"] * 3 + ["r2"] * 4, subjects=True)  # fmt: skip
    judge, plain = SpreadFar.of(cb), SpreadMargin.of(cb)
    assert judge.far == 3.0
    assert judge.thresholds == plain.thresholds == (0.375,) * 3 and judge.power == 0.0
    assert SpreadFar.of(cb, 0.3).far == 2.0
    assert judge.unlike(np.array([4.0, 40.0, 40.0]))
    assert not plain.unlike(np.array([4.0, 40.0, 40.0]))
    assert not judge.unlike(np.array([3.0, 40.0, 40.0]))
    assert judge.unlike(np.array([2.5, 2.6, 10.0])) and plain.unlike(np.array([2.5, 2.6, 10.0]))
    # held out by person: no person offset
    assert for_person(judge, np.full(20, 3.0)) is judge
    # calibrated with the others from one held-out scan, and stored at fit
    assert calibrate_judges(cb)["spread-far"] == judge
    assert calibrate_judges(cb, ["spread-far"]) == {"spread-far": judge}


def test_spread_far_with_one_person_compares_the_distances_less_the_offset() -> None:
    """One person's two recordings (r1 a 0, b -10, c 10; r2 a 1, b -11, c 11), held out by
    recording: every held-out case lies 1 from its own activity (far 1, reach 1) and the
    judge is the activity margin with its floor (the margin 80 % of the held-out cases with
    their own activity gone exceed: 11/21). A recording of 20 windows at 3 from their
    nearest case: offset (3 - 1) * 20 / 28 = 10/7. A window at (2.2, 30, 30): 0.771 less the
    offset, within the bound (2.2 without it: beyond); (3, 30, 30): 1.571, beyond; both
    margins far below the floor."""
    cb = _line([0.0, -10.0, 10.0, 1.0, -11.0, 11.0], ["a", "b", "c"] * 2,
               ["r1"] * 3 + ["r2"] * 3, subjects=False)  # fmt: skip
    judge = SpreadFar.of(cb)
    assert judge.basis == "recording" and judge.far == 1.0 and judge.reach == 1.0
    assert judge.floor == pytest.approx(11 / 21)
    mine = for_person(judge, np.full(20, 3.0))
    assert isinstance(mine, Offset) and mine.offset == pytest.approx(10 / 7)
    near, beyond = np.array([2.2, 30.0, 30.0]), np.array([3.0, 30.0, 30.0])
    assert judge.unlike(near) and not mine.unlike(near)
    assert unknown_evidence(mine, near) == 0.0
    assert mine.unlike(beyond) and unknown_evidence(mine, beyond) == 1.0
    plain = for_person(SpreadMargin.of(cb), np.full(20, 3.0))
    assert not plain.unlike(beyond)


def test_spread_far_is_named_stored_and_read_back() -> None:
    """A record of its fields, read back; a record without the bound (spread-margin's) is
    spread-margin's rule (far inf); a negative bound is refused naming the field; named
    among the judges (the default still first), calibrated at fit, a choice of the
    command line."""
    judge = _judge(10.0)
    assert judges_from_dict(judges_to_dict({"spread-far": judge})) == {"spread-far": judge}
    assert judges_to_dict({"spread-far": _judge(math.inf)})["spread-far"]["far"] == "inf"
    assert SpreadFar.from_dict(_plain().to_dict()).far == math.inf
    with pytest.raises(ValueError, match="spread-far: field 'far' must be a number >= 0"):
        judges_from_dict({"spread-far": {**judge.to_dict(), "far": -1.0}})
    assert JUDGES[0] == "spread-margin" and "spread-far" in JUDGES
    assert STORED["spread-far"] is SpreadFar and "spread-far" in AT_FIT
    parser = build_parser()
    for name in ("segment", "watch"):
        args = parser.parse_args([name, "x.npz", "--db", "cb.sqlite", "--unknown", "spread-far"])
        assert args.unknown == "spread-far", name


def test_train_stores_spread_far_and_segment_uses_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train --split windows`` on two subjects of the bundled UI-PRMD Kinect subset stores
    spread-far with the others (its bound the held-out scan's, the same scan as
    spread-margin's thresholds, its own the same); ``segment --unknown spread-far`` reads
    it and segments the recording (subject s03's squat, side lunge and hurdle step)."""
    db = tmp_path / "cb.sqlite"
    seen = "deep_squat,standing_shoulder_abduction,side_lunge"
    argv = ["train", str(DEMO / "labels.csv"), "--db", str(db), "--subjects", "s01,s02",
            "--labels", seen, "--split", "windows"]  # fmt: skip
    assert main(argv) == 0
    store = open_store(db, create=False, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    stored = clf.judges_["spread-far"]  # type: ignore[attr-defined]
    spread = clf.judges_["spread-margin"]  # type: ignore[attr-defined]
    assert isinstance(stored, SpreadFar) and math.isfinite(stored.far) and stored.far > 0
    assert stored == SpreadFar.of(clf.case_base_)  # type: ignore[attr-defined]
    assert stored.thresholds == spread.thresholds and stored.spreads == spread.spreads
    assert judge_of(clf, "spread-far") == stored

    names = [f"m{m}_s03_e01.npz" for m in ("01", "04", "02")]
    rec = save_pose(join_repetitions([load_pose(DEMO / n) for n in names]).seq, tmp_path / "r.npz")
    capsys.readouterr()
    assert main(["segment", str(rec), "--db", str(db), "--json", "--unknown", "spread-far"]) == 0
    segments = json.loads(capsys.readouterr().out)["segments"]
    assert segments and segments[0]["start_s"] == 0.0
