"""The "unlike the stored cases" flag's feature score (cbr.novelty): summary features outside
the ranges the cases span, calibrated on held-out training clips, per answered label. Synthetic
case bases whose answer is known by construction; each test well under a second."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cbr.novelty import (
    RANGE_FOLDS,
    SUMMARY_SCORES,
    Combined,
    FeatureRanges,
    NoveltyCalibration,
    combine,
    distance_limit,
    fit_activities,
    fit_ranges,
    flag_threshold,
    fold_of,
    nearest_rms,
    outside_share,
    summary,
)

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd" / "labels.csv"


def test_a_sequence_is_summarised_by_its_columns_over_time() -> None:
    seq = np.array([[1.0, 10.0], [3.0, np.nan], [5.0, 30.0]])
    # by hand: means 3 and 20, minima 1 and 10, maxima 5 and 30, standard deviations
    # sqrt(8/3) and 10 (the missing value left out)
    want = [3.0, 20.0, 1.0, 10.0, 5.0, 30.0, np.sqrt(8.0 / 3.0), 10.0]
    assert summary(seq) == pytest.approx(want)
    vec = np.array([0.5, -2.0])
    assert summary(vec) is not None and np.array_equal(summary(vec), vec)


def test_the_outside_share_counts_features_beyond_either_end() -> None:
    lo, hi = np.zeros(4), np.ones(4)
    s = np.array([[0.5, -0.1, 1.2, np.nan], [0.0, 1.0, 0.3, 0.7]])
    # first row: one feature below, one above, one missing (not outside) of four
    assert outside_share(s, lo, hi) == pytest.approx([0.5, 0.0])


def test_each_group_lands_in_one_of_at_most_the_folds() -> None:
    groups = np.array([f"s{i % 12}" for i in range(60)], dtype=object)
    fold = fold_of(groups)
    assert len(set(fold.tolist())) == RANGE_FOLDS
    for g in set(groups.tolist()):
        assert len(set(fold[groups == g].tolist())) == 1
    assert sorted(set(fold_of(np.array(["a", "b", "a"], dtype=object)).tolist())) == [0, 1]


def _case_base(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Six subjects, twenty clips each of "A" and "B", 60 summary features. A is done alike
    by everyone (the same spread); B each subject does its own way (subject j far off in
    features 5j to 5j + 4), so a held-out B clip leaves the other subjects' ranges in those
    five features: held out, B clips are five features outside, A clips none or one."""
    rows, groups, labels = [], [], []
    for j in range(6):
        for label in ("A", "B"):
            x = rng.normal(0.0, 1.0, (20, 60))
            if label == "B":
                x[:, 5 * j : 5 * j + 5] += 10.0  # subject j's way of doing B
            rows.append(x)
            groups += [f"s{j}"] * 20
            labels += [label] * 20
    return np.concatenate(rows), np.array(groups, dtype=object), np.array(labels, dtype=object)


def test_clips_like_the_cases_pass_and_clips_beyond_their_range_are_flagged() -> None:
    rng = np.random.default_rng(1)
    cases, groups, labels = _case_base(rng)
    ranges = fit_ranges(cases, groups, cases, groups, labels)
    assert ranges is not None and ranges.lo.shape == (6, 60)
    # new A clips drawn as A's cases were: few flagged (the quantile is 0.995)
    like = rng.normal(0.0, 1.0, (300, 60))
    assert np.mean([ranges.unlike(x, "A") for x in like]) <= 0.05
    # the same clips with 20 features far beyond every case: every one flagged, answered A
    # or B (held-out B clips lie five features outside, not twenty)
    away = like.copy()
    away[:, 30:50] += 20.0
    assert all(ranges.unlike(x, "A") for x in away)
    assert all(ranges.unlike(x, "B") for x in away)


def test_the_answer_sets_how_far_outside_is_usual() -> None:
    """A clip as far outside the ranges as held-out B clips are is ordinary for B, unlike the
    cases when answered A: A's held-out clips stay inside."""
    rng = np.random.default_rng(2)
    cases, groups, labels = _case_base(rng)
    ranges = fit_ranges(cases, groups, cases, groups, labels)
    assert ranges is not None
    assert ranges.scale("B") > 4 * ranges.scale("A")
    # a new person's B: the usual spread and a way of its own, in five features of no subject's
    new_b = rng.normal(0.0, 1.0, (100, 60))
    new_b[:, 50:55] += 10.0
    flagged_as_b = np.mean([ranges.unlike(x, "B") for x in new_b])
    flagged_as_a = np.mean([ranges.unlike(x, "A") for x in new_b])
    assert flagged_as_b <= 0.1 and flagged_as_a >= 0.9
    # a label the ranges never saw takes the scale of all clips
    assert ranges.scale("C") == ranges.default


def test_one_group_cannot_be_held_out() -> None:
    x = np.zeros((5, 3))
    one = np.array(["s1"] * 5, dtype=object)
    assert fit_ranges(x, one, x, one, ["A"] * 5) is None


def test_the_calibration_names_the_score_that_flags() -> None:
    rng = np.random.default_rng(3)
    cases, groups, labels = _case_base(rng)
    ranges = fit_ranges(cases, groups, cases, groups, labels)
    cal = NoveltyCalibration(1.0, 2.0, 0.995, "leave-one-subject-out", 240, ("asf_amc",), ranges)
    ordinary = rng.normal(0.0, 1.0, 60)
    odd = ordinary.copy()
    odd[:10] = 50.0
    assert cal.measured(0.5, ordinary, "A") == ""
    assert cal.measured(0.5, odd, "A") == "features"
    assert cal.measured(3.0, odd, "A") == "distance"  # the distance is named first
    assert cal.reason(0.5, "uiprmd_kinect", ordinary, "A") == "sensor"
    assert cal.reason(0.5, "asf_amc", odd, "A") == "features"
    # without the clip's problem only the distance is judged (segmentation windows, old calls)
    assert cal.reason(0.5, "asf_amc") == "" and not cal.unlike(0.5)


def test_the_feature_ranges_survive_storage() -> None:
    rng = np.random.default_rng(4)
    cases, groups, labels = _case_base(rng)
    cases[0, 5] = np.nan  # a missing value among the cases
    ranges = fit_ranges(cases, groups, cases, groups, labels)
    cal = NoveltyCalibration(1.0, 2.0, 0.995, "leave-one-subject-out", 240, (), ranges)
    stored = json.loads(json.dumps(cal.to_dict(), allow_nan=False))  # the store's JSON
    assert NoveltyCalibration.from_dict(stored) == cal
    before = {k: v for k, v in cal.to_dict().items() if k != "features"}
    assert NoveltyCalibration.from_dict(before).features is None  # stored before the ranges
    short = cal.describe()["features"]
    assert short["folds"] == 6 and short["features"] == 60 and "lo" not in short
    with pytest.raises(ValueError, match="paired"):
        FeatureRanges.from_dict({**ranges.to_dict(), "hi": [[0.0]]} if ranges else {})


def test_a_fitted_case_base_keeps_its_ranges_and_flags_few_new_people() -> None:
    from cbr.estimator import CaseBaseClassifier
    from features.datasets import load_dataset

    train = load_dataset(DEMO, subjects={"s01", "s02"})
    test = load_dataset(DEMO, subjects={"s03"})
    clf = CaseBaseClassifier().fit([c.seq for c in train], [c.label for c in train])
    ranges = clf.novelty_.features
    assert ranges is not None and ranges.lo.shape[0] == 2  # the two subjects, each held out
    combined = clf.novelty_.combined
    assert combined is not None and combined.budget == 0.02
    assert set(combined.held) == {"distance", "summary", "activity", *SUMMARY_SCORES}
    solved = clf.solve([c.seq for c in test])
    flagged = [s.unlike_reason for s in solved if s.unlike_cases]
    assert len(flagged) <= 6, f"{flagged} of 60 ordinary clips flagged"
    # a new person's clip with a quarter of its features beyond every case: unlike them,
    # whatever it is answered
    values = solved[0].problem.values.copy()
    values[::4] = ranges.hi.max(axis=0)[::4] + 1.0
    for label in clf.classes_:
        assert clf.novelty_.measured(0.0, values, str(label)) == "features"


def _records(
    seq: object, qmp: np.ndarray, names: tuple[str, ...], summary_of: np.ndarray, shift: float
) -> tuple[list[object], list[str]]:
    """Training records of a QMP case base, built by hand as :func:`cbr.described.describe_clip`
    builds them: six subjects, five clips each of "A" (exactly the QMP vector ``qmp``) and "B"
    (its first four criteria flipped); every clip's fluent summary is ``summary_of`` moved by
    ``shift`` in every feature, with a little spread of its own."""
    from cbr.casebase import skeleton_of
    from cbr.described import DescribedClip

    rng = np.random.default_rng(5)
    flipped = qmp.copy()
    flipped[:4] = 1.0 - flipped[:4]
    out, labels = [], []
    for j in range(6):
        for label, values in (("A", qmp), ("B", flipped)):
            for e in range(5):
                described = summary_of + shift + rng.normal(0.0, 0.05, summary_of.shape)
                out.append(DescribedClip(
                    values.copy(), None, None, np.zeros(0, dtype=bool), 1.0, f"s{j}_{label}{e}",
                    f"s{j}", (0, 100), skeleton_of(seq), names, names, described,
                    np.ones(len(summary_of) // 4, dtype=bool),
                ))  # fmt: skip
                labels.append(label)
    return out, labels


def test_a_qmp_case_base_flags_a_clip_whose_fluent_summary_is_unlike_its_cases() -> None:
    """A QMP case base whose cases hold exactly the clip's QMP vector (nearest-case distance
    0: its own problem is as ordinary as can be) but whose clips' fluent summaries all lie a
    whole unit above the clip's, in every feature: the clip is unlike the cases by its
    features. The same case base with the summaries around the clip's: not flagged."""
    from cbr.estimator import CaseBaseClassifier
    from cbr.novelty import DESCRIPTION
    from cbr.problem import candidate_config, extract_problem
    from features.datasets import load_dataset

    seq = load_dataset(DEMO, subjects={"s03"})[0].seq
    problem = extract_problem(seq, candidate_config(CaseBaseClassifier("qmp").wanted_config()))
    summary_of = extract_problem(seq, candidate_config(DESCRIPTION)).values
    flagged = []
    for shift in (1.0, 0.0):
        records, labels = _records(seq, problem.values, problem.names, summary_of, shift)
        clf = CaseBaseClassifier("qmp", mirror="off", feature_weights="none")
        clf.fit_described(records, labels)
        assert clf.novelty_.description is not None  # judged on the fluent summary
        (solved,) = clf.solve([seq])
        assert solved.solution.label == "A" and float(solved.retrieval.distances[0]) < 1e-6
        assert solved.description is not None and solved.description.shape == summary_of.shape
        flagged.append(solved.unlike_reason)
        stored = json.loads(json.dumps(clf.novelty_.to_dict(), allow_nan=False))
        assert NoveltyCalibration.from_dict(stored) == clf.novelty_  # the description kept
    assert flagged == ["features", ""]
    # stored before descriptions: the ranges summarise the problem itself, as they did
    old = {k: v for k, v in stored["features"].items() if k != "description"}
    assert FeatureRanges.from_dict(old).description is None


def test_the_description_is_the_problem_fluents_euclidean_has() -> None:
    """Every configuration's feature score judges the default case base's clip summary
    (fluent states, joint angles and positions over 32 frames; without phase means): a dtw
    or signature sequence of the same columns summarised over time is that summary (worked
    out two ways on a real clip: the sequence's columns over time, and the summary problem);
    a QMP case base computes it beside its problems."""
    from cbr.estimator import CaseBaseClassifier
    from cbr.novelty import DESCRIPTION, own_description
    from cbr.problem import candidate_config, extract_problem
    from features.datasets import load_dataset

    assert CaseBaseClassifier(phases=0).wanted_config() == DESCRIPTION
    assert own_description(CaseBaseClassifier().wanted_config())
    assert not own_description(CaseBaseClassifier("qmp").wanted_config())
    assert not own_description(
        CaseBaseClassifier(similarity="dtw", positions=False).wanted_config()
    )
    seq = load_dataset(DEMO, subjects={"s03"})[5].seq
    want = extract_problem(seq, candidate_config(DESCRIPTION)).values
    for similarity in ("dtw", "signature"):
        config = candidate_config(CaseBaseClassifier(similarity=similarity).wanted_config())
        assert own_description(config)
        sequence = extract_problem(seq, config).values
        assert sequence.ndim == 2 and summary(sequence) == pytest.approx(want, abs=1e-12)


def test_the_nearest_clip_distance_is_the_root_mean_square_over_shared_features() -> None:
    cases = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, np.nan]])
    queries = np.array([[1.0, 2.0, 2.0], [3.0, np.nan, 9.0], [np.nan, np.nan, np.nan]])
    d, at = nearest_rms(queries, cases)
    # by hand: first query to case 0 sqrt((1 + 4 + 4) / 3) = sqrt(3), to case 1 sqrt((4 + 4) /
    # 2) = 2; second to case 0 sqrt((9 + 81) / 2), to case 1 0 over the one shared feature;
    # the third shares no feature with any case: nothing near
    assert at[:2].tolist() == [0, 1]
    assert d[:2] == pytest.approx([np.sqrt(3.0), 0.0])
    assert d[2] == np.inf


def test_tail_probabilities_and_the_threshold_follow_the_held_out_clips() -> None:
    # four held-out values: 2.5 has two at or above it, (1 + 2) / (4 + 1); beyond all, 1 / 5
    c = Combined({"a": np.array([1.0, 2.0, 3.0, 4.0])}, 0.1, 0.02, 1.0)
    assert c.tail("a", 2.5) == pytest.approx(3 / 5) and c.tail("a", 9.0) == pytest.approx(1 / 5)
    assert c.tail("unknown score", 9.0) == 1.0 and c.tail("a", float("nan")) == 1.0
    # four held-out clips ranked alike by every score: clip i's tails are (5 - i) / 5 in
    # each, so its Fisher statistic is -3 log((5 - i) / 5) and its summary tail (5 - i) / 5
    # again; the smaller of the summary's and the distance's tails: 1, 4/5, 3/5, 2/5, whose
    # lower quartile (budget 0.25) is 2/5
    same = np.array([1.0, 2.0, 3.0, 4.0])
    held = {"distance": same, **{k: same for k in SUMMARY_SCORES}}
    c = combine(held, np.arange(4), budget=0.25, weight=1.0)
    assert c.held["summary"] == pytest.approx(-3 * np.log([1.0, 0.8, 0.6, 0.4]))
    assert c.threshold == pytest.approx(2 / 5)
    # at the 2 % budget, four held-out clips are too few: a new ordinary clip beyond all of
    # them (chance 1 / 5) would be flagged; the summary flags nothing
    assert combine(held, np.arange(4), budget=0.02, weight=1.0).threshold == 0.0
    tails = {k: np.array([2 / 5]) for k in SUMMARY_SCORES}
    assert c.summary(tails) == pytest.approx([2 / 5])
    # one score far beyond every held-out clip, the others ordinary: Fisher's statistic
    # -log(1/5) - 2 log(1) = 1.61 lies between the third and fourth held-out clips' (1.53,
    # 2.75): one clip at or above it, tail 2/5
    one = {"outside": np.array([1 / 5]), "outside_label": np.array([1.0]),
           "neighbour": np.array([1.0])}  # fmt: skip
    assert c.summary(one) == pytest.approx([2 / 5])
    # the distance's own limit flags exactly the values whose tail is at most the threshold
    rng = np.random.default_rng(6)
    ratios = rng.gamma(2.0, 1.0, 300)
    for threshold in (0.005, 0.02, 0.1):
        limit = distance_limit(ratios, threshold)
        probe = rng.uniform(0.0, 12.0, 2000)
        d = Combined({"distance": np.sort(ratios)}, threshold, 0.02, 1.0)
        assert [x > limit for x in probe] == [d.tail("distance", x) <= threshold for x in probe]
    assert distance_limit(ratios, 0.001) == np.inf  # 300 clips cannot say 1 in 1000


def test_the_threshold_counts_the_summary_on_every_clip_and_the_distance_on_its_sample() -> None:
    # twenty held-out clips whose summary tails are 0.05, 0.10, ..., 1.00; the distance
    # measured on the ten least unusual of them (clips 10-19). At a 10 % budget two of the
    # twenty may be flagged (floor(0.1 * 19) + 1, as the budget quantile rounds): the
    # summary's two smallest, threshold 0.10 (the budget quantile of the ten sampled clips
    # alone would be 0.55, flagging eleven of the twenty)
    summary_tails = np.arange(1, 21) / 20
    sample = np.arange(10, 20)
    ordinary = np.ones(10)
    assert flag_threshold(summary_tails, ordinary, sample, 0.1, 0.25) == pytest.approx(0.10)
    # the last clip's distance tail 0.02 flags it (0.02 <= 0.25 t) from t = 0.08 on: one of
    # the ten sampled clips, 10 %, and with the summary's 0.05 the share 0.15 passes 0.10, so
    # the threshold stays at the summary's smallest, 0.05
    near = ordinary.copy()
    near[9] = 0.02
    assert flag_threshold(summary_tails, near, sample, 0.1, 0.25) == pytest.approx(0.05)
    # the distance flags at least at its floor: a distance tail of 0.03 at a floor of 0.03
    # flags from the first threshold on, already 0.05 + 0.10 over the budget: nothing flags
    near[9] = 0.03
    assert flag_threshold(summary_tails, near, sample, 0.1, 0.25, floor=0.03) == 0.0


def test_the_threshold_is_the_last_before_the_flagged_share_passes_the_budget() -> None:
    """:func:`flag_threshold` against its definition counted clip by clip: at each value a
    flag can change at (a summary tail, or where weight t reaches a distance tail), the share
    of clips flagged, the summary's over every clip and the distance's alone over its
    sample."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        n = int(rng.integers(20, 120))
        q = int(rng.integers(1, n + 1))
        ps = np.round(rng.uniform(0.0, 1.0, n), 2)  # rounded: ties, as tail probabilities have
        sample = np.sort(rng.choice(n, q, replace=False))
        # sixty-fourths over powers of two: weight t reaches a distance tail exactly at t = its
        # tail over the weight, no rounding between the two
        pd = rng.integers(0, 65, q) / 64
        budget, weight = float(rng.uniform(0.05, 0.3)), float(rng.choice([0.125, 0.25, 1.0]))
        floor = float(rng.choice([0.0, 3 / 64]))
        events = sorted({*ps.tolist(), *[p / weight for p in pd if p > floor]})
        allowed = (np.floor(budget * (n - 1)) + 1) / n
        expected = 0.0
        for t in events:
            by_summary = sum(p <= t for p in ps) / n
            alone = sum(
                d <= max(weight * t, floor) and ps[j] > t for d, j in zip(pd, sample, strict=True)
            )
            if by_summary + alone / q > allowed + 1e-12:
                break
            expected = t
        got = flag_threshold(ps, pd, sample, budget, weight, floor)
        assert got == pytest.approx(expected, abs=1e-12)


def _combined(rng: np.random.Generator) -> NoveltyCalibration:
    """A calibration of :func:`_case_base` with every score: the distance's held-out ratios
    drawn, the feature scores fitted as the estimator fits them."""
    from cbr.novelty import combined_calibration, fit_neighbours, ranges_and_held

    cases, groups, labels = _case_base(rng)
    got = ranges_and_held(cases, groups, cases, groups, labels)
    near = fit_neighbours(cases, groups, labels, cases, groups)
    spread = fit_activities(cases, groups, labels, cases, groups)
    assert got is not None and near is not None and spread is not None
    base = NoveltyCalibration(1.0, 2.0, 0.99, "leave-one-subject-out", 240, ())
    nearest = rng.gamma(4.0, 0.25, len(cases))
    return combined_calibration(base, nearest, *got, *near, np.arange(len(cases)),
                                activities=spread)  # fmt: skip


def test_the_combined_flag_judges_a_clip_alike_whatever_the_answer() -> None:
    """The summary scores do not read the answered label (the same clip flags the same under
    every measure), flag new clips drawn as the cases were about as often as the budget says
    and flag clips far outside in a fifth of their features, or lying far from every clip."""
    rng = np.random.default_rng(7)
    cal = _combined(rng)
    assert cal.combined is not None and cal.neighbours is not None
    like = [rng.normal(0.0, 1.0, 60) for _ in range(300)]
    flagged = [cal.scores(0.5, x, "A")[1] for x in like]
    assert all(cal.scores(0.5, x, "B")[1] == f for x, f in zip(like, flagged, strict=True))
    assert np.mean(flagged) <= 0.06
    away = [x.copy() for x in like[:50]]
    for x in away:
        x[30:42] += 20.0
    assert all(cal.measured(0.5, x, "A") == "features" for x in away)
    # the distance alone: beyond its limit it flags whatever the features say
    assert cal.measured(cal.unlike_ratio * 1.01, like[0], "A") == "distance"
    assert cal.unlike(cal.unlike_ratio * 1.01) and not cal.unlike(cal.unlike_ratio * 0.99)
    # and the nearest clip in summary space is a case of the label drawn: a clip made as B's
    # clips of subject 0 lies nearest a B case
    b = rng.normal(0.0, 1.0, 60)
    b[0:5] += 10.0
    assert cal.neighbours.nearest(b)[1] == "B"


def test_the_combined_flag_survives_storage_and_a_damaged_one_is_refused() -> None:
    rng = np.random.default_rng(8)
    cal = _combined(rng)
    stored = json.loads(json.dumps(cal.to_dict(), allow_nan=False))  # the store's JSON
    back = NoveltyCalibration.from_dict(stored)
    assert back == cal
    x = rng.normal(0.0, 1.0, 60)
    x[30:42] += 20.0
    assert back.measured(0.5, x, "A") == cal.measured(0.5, x, "A") == "features"
    short = cal.describe()
    assert short["combined"]["budget"] == 0.02 and "held" not in short["combined"]
    damaged = {
        "the combined flag needs": {k: v for k, v in stored.items() if k != "combined"},
        "scales must be finite and positive": {
            **stored, "neighbours": {**stored["neighbours"], "scale": [0.0] * 60}},
        "a label each": {**stored, "neighbours": {**stored["neighbours"], "labels": ["A"]}},
        "not a stored array": {**stored, "neighbours": {**stored["neighbours"],
                                                        "cases": "not base64!"}},
        "increasing list": {**stored, "combined": {**stored["combined"],
                                                   "held": {"outside": [2.0, 1.0]}}},
        "must be probabilities": {**stored, "combined": {**stored["combined"],
                                                         "threshold": 1.5}},
        "distance weight must be": {**stored, "combined": {**stored["combined"],
                                                           "distance_weight": 0.0}},
    }  # fmt: skip
    for reason, d in damaged.items():
        with pytest.raises(ValueError, match=reason):
            NoveltyCalibration.from_dict(d)


def test_the_description_is_read_off_a_problem_as_computed_from_the_clip() -> None:
    """A fluents/euclidean case base (a summary with phase means) and a dtw one (a sequence
    of the same columns) give the clip's description from their problems as recorded: the
    same values as computing the description from the clip (two ways on a real clip)."""
    from cbr.estimator import CaseBaseClassifier
    from cbr.novelty import DESCRIPTION, describe, from_problem, same_columns
    from cbr.problem import availability, candidate_config, extract_problem, resolve_counts
    from features.datasets import load_dataset

    seq = load_dataset(DEMO, subjects={"s03"})[7].seq
    has = availability(seq, candidate_config(DESCRIPTION))
    has[3] = False  # a column too few training clips have: left out of the description
    resolved = resolve_counts(DESCRIPTION, has.astype(np.int64), 1)
    want = describe(seq, resolved)
    assert want.shape == (4 * len(resolved.states),)
    for wanted in (CaseBaseClassifier(phases=2).wanted_config(),
                   CaseBaseClassifier(similarity="dtw").wanted_config()):  # fmt: skip
        assert same_columns(wanted)
        candidates = candidate_config(wanted)
        values = extract_problem(seq, candidates).values
        assert from_problem(values, candidates, resolved) == pytest.approx(want, abs=1e-12)
    assert not same_columns(CaseBaseClassifier(positions=False).wanted_config())


def test_the_activity_score_is_the_nearest_activity_in_its_own_spread(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import cbr.novelty
    from cbr.novelty import CLIP_SD, SPREAD_FLOOR, spread_of

    # two activities of four clips, two features: A at (0|4, 0|4), C at (20|24, 20|24); by
    # hand each activity's mean is (2, 2) and (22, 22) and its standard deviation 2, the
    # standard deviation over all eight clips sqrt(104) = 10.2, so the unit is at least a
    # quarter of it: 2.55
    a = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 4.0], [4.0, 4.0]])
    cases = np.concatenate([a, a + 20.0])
    labels = np.array(["A"] * 4 + ["C"] * 4, dtype=object)
    spread = spread_of(cases, labels)
    assert SPREAD_FLOOR == 0.25 and CLIP_SD == 3.0
    unit = 0.25 * np.sqrt(104.0)
    assert spread.centres.ravel() == pytest.approx([2.0, 2.0, 22.0, 22.0])
    assert spread.units.ravel() == pytest.approx(np.full(4, unit))
    # (3, 2): one unit-less 1 / 2.55 from A in the first feature, 0 in the second; C is far
    assert spread.score(np.array([3.0, 2.0])) == pytest.approx((1.0 / unit) ** 2 / 2)
    # (2, 22): within both activities' ranges feature by feature (each feature's value is
    # some activity's mean) but A's in one and C's in the other: 20 / 2.55 = 7.8 units from
    # either in one feature, counted at most 3 (9 squared), so (0 + 9) / 2 from both
    assert spread.score(np.array([2.0, 22.0])) == pytest.approx(4.5)
    # a feature the clip lacks counts 0; a summary of other columns is no score
    assert spread.score(np.array([np.nan, 3.0])) == pytest.approx((1.0 / unit) ** 2 / 2)
    assert spread.score(np.zeros(3)) == np.inf
    # many clips a block at a time (here one clip per block): the same scores
    monkeypatch.setattr(cbr.novelty, "SPREAD_BLOCK", 4)
    clips = np.array([[3.0, 2.0], [2.0, 22.0], [np.nan, 3.0]])
    assert spread.scores(clips) == pytest.approx(
        [(1.0 / unit) ** 2 / 2, 4.5, (1.0 / unit) ** 2 / 2]
    )


def _mixed_case_base(
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Six subjects, twenty clips each of two activities over 40 features: "up" raises the
    first 20 features by 4 (standard deviation 1), "down" the last 20."""
    rows, groups, labels = [], [], []
    for j in range(6):
        for label, part in (("up", slice(0, 20)), ("down", slice(20, 40))):
            x = rng.normal(0.0, 1.0, (20, 40))
            x[:, part] += 4.0
            rows.append(x)
            groups += [f"s{j}"] * 20
            labels += [label] * 20
    return np.concatenate(rows), np.array(groups, dtype=object), np.array(labels, dtype=object)


def test_a_clip_whose_features_fit_no_one_activity_is_flagged_by_the_activity_score() -> None:
    """Every feature of the clip but one lies well within the cases' ranges (each is the
    value one of the activities holds it at), but together they are neither activity: 4
    standard deviations from each in half the features. Held-out clips score about 1 (a mean
    square of standard normal deviations); this one about 4.5 (half its features at the
    3-deviation limit, 9): beyond every held-out clip. With one feature just beyond the
    cases' range besides, the four summary scores flag it; the three before it did not (one
    feature outside of 40 is what a held-out clip shows one time in three)."""
    from cbr.novelty import combined_calibration, fit_neighbours, ranges_and_held

    rng = np.random.default_rng(11)
    cases, groups, labels = _mixed_case_base(rng)
    got = ranges_and_held(cases, groups, cases, groups, labels)
    near = fit_neighbours(cases, groups, labels, cases, groups)
    spread = fit_activities(cases, groups, labels, cases, groups)
    assert got is not None and near is not None and spread is not None
    assert np.median(spread[1]) == pytest.approx(1.0, abs=0.15)
    base = NoveltyCalibration(1.0, 2.0, 0.99, "leave-one-subject-out", 240, ())
    cal = combined_calibration(base, rng.gamma(4.0, 0.25, len(cases)), *got, *near,
                               np.arange(len(cases)), activities=spread)  # fmt: skip
    three = combined_calibration(base, rng.gamma(4.0, 0.25, len(cases)), *got, *near,
                                 np.arange(len(cases)))  # fmt: skip
    neither = rng.normal(0.0, 0.3, 40)  # both halves as the activity not raising them
    assert cal.features is not None and cal.features.outside(neither) == 0.0
    assert spread[0].score(neither) > spread[1].max()
    tails = cal.tails(neither)
    assert tails["activity"] == pytest.approx(1.0 / (len(cases) + 1.0))
    neither[0] = cases[:, 0].max() + 0.5
    assert cal.features.outside(neither) == pytest.approx(1 / 40)
    assert cal.measured(0.5, neither, "up") == "features"
    assert three.measured(0.5, neither, "up") == ""
    # a clip of either activity, drawn as its cases were, is not
    ordinary = rng.normal(0.0, 1.0, 40)
    ordinary[:20] += 4.0
    assert cal.measured(0.5, ordinary, "up") == ""


def test_a_calibration_stored_before_the_activity_score_judges_as_before() -> None:
    """Stored without the activity spread: the three summary scores alone, as before (its
    Fisher statistic is theirs); the spread without its held-out scores is refused."""
    from cbr.novelty import ACTIVITY_SCORE, combined_calibration, fit_neighbours, ranges_and_held

    rng = np.random.default_rng(12)
    cases, groups, labels = _case_base(rng)
    got = ranges_and_held(cases, groups, cases, groups, labels)
    near = fit_neighbours(cases, groups, labels, cases, groups)
    assert got is not None and near is not None
    base = NoveltyCalibration(1.0, 2.0, 0.99, "leave-one-subject-out", 240, ())
    old = combined_calibration(base, rng.gamma(4.0, 0.25, len(cases)), *got, *near,
                               np.arange(len(cases)))  # fmt: skip
    stored = json.loads(json.dumps(old.to_dict(), allow_nan=False))
    assert "activities" not in stored and ACTIVITY_SCORE not in stored["combined"]["held"]
    back = NoveltyCalibration.from_dict(stored)
    assert back == old and back.activities is None
    x = rng.normal(0.0, 1.0, 60)
    x[30:42] += 20.0
    tails = back.tails(x)
    assert set(tails) == {*SUMMARY_SCORES, "summary"}
    assert back.combined is not None
    fisher = -sum(np.log(tails[k]) for k in SUMMARY_SCORES)
    assert tails["summary"] == pytest.approx(back.combined.tail("summary", fisher))
    spread = fit_activities(cases, groups, labels, cases, groups)
    assert spread is not None
    with pytest.raises(ValueError, match="stored together"):
        NoveltyCalibration.from_dict({**stored, "activities": spread[0].to_dict()})
