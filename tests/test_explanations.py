"""Explanations a person can check: short, with the true reason, counterfactuals that hold,
no contradictions, a clip's mirror image never a second neighbour.

The squats of tests.bodies are built so the reason is known: deep and shallow squats differ
in how far down they go (knee angle 180 - 130 x depth degrees, by construction), while the
lean of the torso, how far the arms are raised and the pace vary at random within both.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cbr.consistency import contradictions, exclusive
from cbr.counterfactual import MAX_CHANGES
from cbr.estimator import CaseBaseClassifier
from cbr.explain import MAX_TEXT, Claim, Explanation, clip_of, label_words
from cbr.profiles import view_of
from features.poses import PoseSequence
from tests.bodies import squat_clip
from tests.once import made_once

DEPTHS = {"deep": (0.9, 1.0), "shallow": (0.45, 0.55)}
#: the joints depth moves: the knees and hips, and the torso, whose lean grows with depth;
#: not the arms (shoulders, elbows, hands), whose raise is random in both kinds
DEPTH_FEATURES = {
    "joint:torso",
    *(f"joint:{side} {joint}" for side in ("left", "right") for joint in ("knee", "hip", "foot")),
}


def _knee_min_deg(depth: float) -> float:
    return 180.0 - 130.0 * depth


def _squats(labels: dict[str, str], seed: int = 0) -> tuple[list[PoseSequence], list[str]]:
    """Four subjects, four clips of each kind; ``labels`` names the kinds' labels."""
    rng = np.random.default_rng(seed)
    X, y = [], []
    for subject in ("s1", "s2", "s3", "s4"):
        for kind, (lo, hi) in DEPTHS.items():
            for i in range(4):
                clip = squat_clip(
                    rng.uniform(lo, hi), int(rng.integers(40, 60)), rng.uniform(30, 50),
                    rng.uniform(0, 20), f"{subject}_{kind}_{i}.npz",
                )  # fmt: skip
                X.append(clip.with_metadata(subject=subject))
                y.append(labels[kind])
    return X, y


def _fitted(labels: dict[str, str]) -> CaseBaseClassifier:
    X, y = _squats(labels)
    return CaseBaseClassifier().fit(X, y)


# made once in the run (the tests only explain with them), not once per worker
@pytest.fixture(scope="module")
def squats(tmp_path_factory: pytest.TempPathFactory) -> CaseBaseClassifier:
    labels = {"deep": "deep squat", "shallow": "shallow squat"}
    return made_once(tmp_path_factory, "explanations-squats", lambda _: _fitted(labels))


@pytest.fixture(scope="module")
def repetitions(tmp_path_factory: pytest.TempPathFactory) -> CaseBaseClassifier:
    labels = {"deep": "correct", "shallow": "incorrect"}
    return made_once(tmp_path_factory, "explanations-repetitions", lambda _: _fitted(labels))


def _made_shallower() -> PoseSequence:
    """A deep squat (lean 40 degrees, arms raised 10) that only goes half way down."""
    return squat_clip(0.5, 50, 40.0, 10.0).with_metadata(subject="s9")


def test_a_squat_made_shallower_is_explained_by_how_far_the_knees_bend(
    squats: CaseBaseClassifier,
) -> None:
    exp = squats.explain([_made_shallower()])[0]
    assert exp.label == "shallow squat"
    why = [c for c in exp.claims if c.part == "why"]
    assert why and all(c.feature in DEPTH_FEATURES for c in why)
    # the counterfactual: back to a deep squat, by the knees and hips alone, checked
    c = exp.contrast
    assert c is not None and c.label == "deep squat" and c.valid and c.answer == "deep squat"
    assert 1 <= len(c.changes) <= MAX_CHANGES
    assert {ch.feature for ch in c.changes} <= DEPTH_FEATURES
    knees = [ch for ch in c.changes if ch.column in ("angle:left_knee@min", "angle:right_knee@min")]
    assert knees  # the knees must bend further
    for ch in knees:  # in degrees: this clip's lowest knee angle, and a deep squat's
        assert ch.unit == "degrees"
        assert ch.here == pytest.approx(_knee_min_deg(0.5), abs=1.0)  # 32 resampled frames
        assert _knee_min_deg(1.0) - 1.0 <= ch.there <= _knee_min_deg(0.9) + 1.0
    assert "To be deep squat" in exp.text and "→" in exp.text


def test_the_counterfactual_copies_a_real_case_and_the_classifier_agrees(
    squats: CaseBaseClassifier,
) -> None:
    solved = squats.solve([_made_shallower()])[0]
    exp = squats.explain_solved(solved)
    c = exp.contrast
    assert c is not None and c.guide is not None
    cb = squats.case_base_
    view = view_of(cb)
    changed = np.array(solved.problem.values, copy=True)
    for feature in {ch.feature for ch in c.changes}:
        f = view.features.index(feature)
        mask = view.feature_mask(changed.shape, f)
        changed[mask] = cb.problems[c.guide][mask]
    assert str(cb.labels[c.guide]) == "deep squat"
    # the clip as changed goes through the same retrieve and reuse and comes out a deep squat
    assert squats.answer(changed) == "deep squat"
    # every change is needed: undoing any one of them leaves a shallow squat
    for feature in {ch.feature for ch in c.changes}:
        f = view.features.index(feature)
        mask = view.feature_mask(changed.shape, f)
        undone = np.where(mask, solved.problem.values, changed)
        if len(c.changes) > 1:
            assert squats.answer(undone) == "shallow squat"


def test_a_repetition_check_leads_with_what_was_done_differently(
    repetitions: CaseBaseClassifier,
) -> None:
    exp = repetitions.explain([_made_shallower()], target="correct")[0]
    lines = exp.text.splitlines()
    assert lines[0].startswith("an incorrect repetition, confidence ")
    assert lines[1].startswith("Done differently from correct repetitions: ")
    outside = [c for c in exp.claims if c.part == "outside"]
    assert outside and all(c.feature in DEPTH_FEATURES for c in outside)
    for c in outside:  # each value lies outside the range of the correct ones, in units
        assert c.low is not None and c.high is not None
        assert not c.low <= c.here <= c.high
        assert c.unit in ("degrees", "torso lengths", "share")
    assert "To be a correct repetition" in lines[3]


@pytest.mark.parametrize(
    ("label", "target", "said"),
    [
        ("true", "correct", "a correct repetition"),
        ("0", "correct", "an incorrect repetition"),
        ("incorrect", None, "an incorrect repetition"),
        ("1", "label", "1"),
        ("deep_squat", "correct", "deep_squat"),
    ],
)
def test_target_values_read_as_words(label: str, target: str | None, said: str) -> None:
    assert label_words(label, target) == said


def test_default_text_is_four_lines_and_at_most_400_characters(
    squats: CaseBaseClassifier,
) -> None:
    clips = [squat_clip(d, 45, 35.0, 5.0).with_metadata(subject="s9") for d in (0.3, 0.6, 0.95)]
    for exp in squats.explain(clips):
        assert len(exp.text.splitlines()) <= 4 and len(exp.text) <= MAX_TEXT
        assert exp.verbose.startswith(exp.text)  # --verbose adds, never says otherwise


def test_a_clip_and_its_mirror_image_are_one_neighbour() -> None:
    X, y = _squats({"deep": "deep squat", "shallow": "shallow squat"})
    clf = CaseBaseClassifier(mirror="augment", k=5).fit(X, y)
    solved = clf.solve([_made_shallower()])[0]
    sources = [clf.case_base_.sources[i] for i in solved.retrieval.indices]
    # a squat is left-right symmetric: a clip and its mirror image are both retrieved
    assert any(s.endswith(" (mirrored)") and clip_of(s) in sources for s in sources)
    exp = clf.explain_solved(solved)
    shown = [clip_of(n["source"]) for n in exp.neighbours]
    assert len(shown) == len(set(shown))
    # a neighbour left out is the mirror twin of one shown, never a clip of its own
    assert {clip_of(s) for s in sources} == set(shown)


def test_explanations_of_squats_have_no_contradictions(squats: CaseBaseClassifier) -> None:
    clips = [squat_clip(d, 45, 30.0 + 20 * d, 15.0).with_metadata(subject="s9")
             for d in (0.4, 0.5, 0.7, 0.9, 1.0)]  # fmt: skip
    for solved in squats.solve(clips):
        exp = squats.explain_solved(solved)
        assert contradictions(exp, squats.case_base_, solved.problem) == []


def _planted(exp: Explanation, *claims: Claim) -> Explanation:
    return dataclasses.replace(exp, claims=exp.claims + claims)


def test_the_checker_finds_planted_contradictions(squats: CaseBaseClassifier) -> None:
    solved = squats.solve([_made_shallower()])[0]
    exp = squats.explain_solved(solved)
    cb = squats.case_base_
    x = dict(zip(cb.names, solved.problem.values, strict=True))
    bent, straight = "left_leg_bent.bent@mean", "left_leg_bent.straight@mean"
    wrong_value = Claim("why", "angle:left_knee@min", "signal:left_knee", "left knee angle",
                        x["angle:left_knee@min"] * 180.0 + 30.0, "degrees")  # fmt: skip
    both_steady = (
        Claim("matched", bent, "signal:left_knee", "left knee bent", x[bent], "share",
              steady=True),
        Claim("matched", straight, "signal:left_knee", "left knee straight", x[straight],
              "share", steady=True),
    )  # fmt: skip
    two_lists = Claim("not_seen", straight, "signal:left_knee", "left knee straight",
                      x[straight], "share", there=0.0)  # fmt: skip
    found = contradictions(_planted(exp, wrong_value), cb, solved.problem)
    assert any("said to be" in f for f in found)
    found = contradictions(_planted(exp, *both_steady), cb, solved.problem)
    assert any("exclusive states" in f for f in found)
    assert any("said to hold steadily" in f for f in found)  # one of them is held < 50 %
    found = contradictions(_planted(exp, both_steady[1], two_lists), cb, solved.problem)
    assert any("in two lists" in f for f in found)


@pytest.mark.parametrize(
    ("a", "b", "expected"),
    [
        ("left_leg_bent.bent", "left_leg_bent.straight", True),
        ("left_leg_bent.bending", "left_leg_bent.straightening", True),
        ("left_leg_bent.bent", "left_leg_bent.bending", False),  # a state and a motion
        ("left_leg_bent.bent", "right_leg_bent.straight", False),
        ("torso_tilted_forward.upright", "torso_tilted_left.tilted_left", True),
        ("torso_tilted_forward.tilted_forward", "torso_tilted_left.tilted_left", False),
        ("torso_tilted_forward.tilt_steady", "torso_tilted_left.tilting_right", True),
    ],
)
def test_exclusive_states_follow_the_fluent_table(a: str, b: str, expected: bool) -> None:
    assert exclusive(a, b) is expected
    assert exclusive(b + "@mean", a + "@mean") is expected


def test_how_many_cases_hold_a_state_is_read_once_and_follows_the_case_base() -> None:
    """The share of the case base's cases that hold each state for at least SEEN_FRACTION of
    the time (how distinctive a shared state is) is counted once per case base, not per
    explanation, and counted again when the cases change."""
    from cbr.casebase import CaseBase
    from cbr.explain import SEEN_FRACTION, read
    from cbr.problem import FeatureConfig, Problem
    from cbr.similarity import Euclidean

    # two states' clip means (the rest of the summary ignored): 0.1, 0.2, 0.6, 0.9 of the
    # time for the first, 0.0, 0.0, 0.0, 0.5 for the second: held by 3/4 and 1/4 of the cases
    names = ("a@mean", "b@mean")
    problems = np.array([[0.1, 0.0], [0.2, 0.0], [0.6, 0.0], [0.9, 0.5]])
    labels = np.array(["x", "x", "y", "y"], dtype=object)
    cb = CaseBase(FeatureConfig(), Euclidean(exact=True), problems, labels, names, ("a", "b"))
    query = Problem(np.array([0.5, 0.5]), names, ("a", "b"), "fluents")
    assert SEEN_FRACTION == 0.15
    np.testing.assert_array_equal(read(cb, query).seen, [0.75, 0.25])
    assert read(cb, query).seen is read(cb, query).seen  # kept with the case base
    cb.set_problem(0, np.array([0.1, 0.3]))  # the first case now holds b for 30 % of the time
    np.testing.assert_array_equal(read(cb, query).seen, [0.75, 0.5])


def test_a_clip_without_its_legs_is_not_explained_by_leg_values(
    squats: CaseBaseClassifier,
) -> None:
    """Knees, ankles and feet missing in every frame: their angles and fluents were filled
    (90 degrees, never held) and the explanation quoted the fills as measurements ("knee
    bent" not seen, a knee angle of 90 degrees). Nothing it cites may rest on them."""
    clip = _made_shallower()
    pos = clip.positions.copy()
    legs = [i for i, n in enumerate(clip.joint_names) if n.split("_", 1)[-1] in LEG_JOINTS]
    pos[:, legs] = np.nan
    blind = dataclasses.replace(clip, positions=pos)
    problem = squats.problems([blind])[0]
    assert {"angle:left_knee", "angle:right_knee"} <= problem.unseen
    whole = squats.problems([clip])[0].unseen  # (the arms hang: their plane is undefined)
    assert not {n for n in whole if "knee" in n or "leg" in n}, whole
    exp = squats.explain([blind])[0]
    assert exp.claims
    # a counterfactual may change what was not seen ("left knee height not seen -> -0.95"):
    # it then quotes no value of the clip's
    quoted = {c.column.split("@", 1)[0] for c in exp.claims if c.here is not None}
    assert not quoted & problem.unseen, quoted & problem.unseen
    assert not any(c.part != "change" for c in exp.claims if c.here is None)
    for line in exp.text.splitlines():
        assert "knee" not in line or "not seen" in line, exp.text
    assert contradictions(exp, squats.case_base_, problem) == []


LEG_JOINTS = {"knee", "ankle", "heel", "foot_index"}
