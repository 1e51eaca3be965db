"""Side handling and its choice inside fit (cbr.fitting), and `posecbr train` = fit.

Hand-built arm movements (tests.test_cbr_weights._arm_clip): which side moves is known by
construction, so the side a clip is filed under, and what a new person's other-side clip must
be recognised as, are known without running the code under test.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.fitting import inner_loso_accuracy
from cbr.problem import FeatureConfig, extract_problem, resolve_config, summarise
from features.body import mirrored, moves_left_more, swap_side
from features.poses import save_pose
from posecbr.cli import main
from tests.test_cbr_weights import _arm_clip

KINDS = {
    "one arm sideways": ("right", "sideways"),
    "both arms forward": ("both", "forward"),
    "left arm forward": ("left", "forward"),
}


def _data(subjects: dict[str, str], per: int, seed: int) -> tuple[list, list]:
    """Clips of KINDS; ``subjects`` maps a subject to the arm it uses for "one arm sideways"."""
    rng = np.random.default_rng(seed)
    X, y = [], []
    for subject, arm in subjects.items():
        for label, (a, motion) in KINDS.items():
            for _ in range(per):
                X.append(_arm_clip(arm if label == "one arm sideways" else a, motion, subject, rng))
                y.append(label)
    return X, y


def test_moves_left_more_follows_the_moving_arm() -> None:
    rng = np.random.default_rng(1)
    left = _arm_clip("left", "sideways", "s1", rng)
    right = _arm_clip("right", "forward", "s1", rng)
    assert moves_left_more(left) and not moves_left_more(right)
    assert not moves_left_more(mirrored(left)) and moves_left_more(mirrored(right))


def test_canonical_side_describes_a_left_arm_clip_as_its_mirror_image() -> None:
    rng = np.random.default_rng(2)
    left = _arm_clip("left", "sideways", "s1", rng)
    right = _arm_clip("right", "sideways", "s1", rng)
    base = resolve_config(FeatureConfig(length=8, angles=True, summary=True), [left, right])
    canon = FeatureConfig.from_dict({**base.to_dict(), "side": "canonical"})
    p = extract_problem(left, canon)
    assert p.mirrored
    # the left arm's armpit angle opens to the peak: as the mirror image it is the right one
    mean = {n: v for n, v in zip(p.names, p.values, strict=True)}
    assert mean["angle:right_armpit@max"] > 0.55 > mean["angle:left_armpit@max"]
    assert not extract_problem(right, canon).mirrored
    # the option is part of the stored configuration (and absent, hash unchanged, when off)
    assert "side" not in base.to_dict() and canon.to_dict()["side"] == "canonical"


def test_phase_means_are_the_means_of_each_third() -> None:
    # a column rising 0, 1, ..., 8 over nine frames: thirds 0-2, 3-5, 6-8
    values = np.arange(9.0)[:, None]
    p = summarise(values, ("angle:left_knee",), ("left knee angle",), phases=3)
    np.testing.assert_allclose(p.values, [4.0, 0.0, 8.0, np.std(np.arange(9.0)), 1.0, 4.0, 7.0])
    assert p.words[-3:] == (
        "left knee angle (first third)",
        "left knee angle (middle third)",
        "left knee angle (last third)",
    )
    assert p.names[-1] == "angle:left_knee@phase3"


def test_auto_picks_a_side_invariant_handling_and_recognises_the_other_arm() -> None:
    # the training subjects all use the right arm; a new person uses the left
    X, y = _data({"s1": "right", "s2": "right", "s3": "right"}, 3, 3)
    rng = np.random.default_rng(4)
    Xt = [_arm_clip("left", "sideways", "s9", rng) for _ in range(3)]
    clf = CaseBaseClassifier(k=1).fit(X, y)
    assert clf.side_ in ("canonical", "augment")
    assert set(clf.selection_) == {
        f"{s}/{w}/{p} phases"
        for s in ("canonical", "augment", "off")
        for w in ("none", "fisher")
        for p in (0, 3)
    }
    assert list(clf.predict(Xt)) == ["one arm sideways"] * 3


def test_a_clip_compared_as_its_mirror_image_is_explained_with_its_own_sides() -> None:
    X, y = _data({"s1": "right", "s2": "right", "s3": "right"}, 3, 3)
    clip = _arm_clip("left", "sideways", "s9", np.random.default_rng(4))
    clf = CaseBaseClassifier(k=1, mirror="canonical").fit(X, y)
    solved = clf.solve([clip])[0]
    assert solved.problem.mirrored  # the left arm moves: compared as the right-arm cases
    exp = clf.explain_solved(solved)
    assert exp.mirrored and "compared as its mirror image" in exp.verbose
    words = dict(zip(clf.case_base_.names, clf.case_base_.words, strict=True))
    for c in exp.claims:  # every claim names the clip's own side: the case base's, swapped
        assert c.words == swap_side(words[c.column])
    # what decided it is the arm the clip moves: its left arm
    why = [c for c in exp.claims if c.part == "why"]
    assert why and all("right" not in c.words for c in why)
    assert any("left" in c.words for c in why)


def test_the_verbose_counterfactual_names_the_changed_features_by_the_clips_own_sides() -> None:
    # the changes are found in the compared (mirrored) frame: "joint:right shoulder" there is
    # the clip's left shoulder, and the verbose line said "right shoulder" beside "left upper
    # arm plane angle 90° → 2°"
    X, y = _data({"s1": "right", "s2": "right", "s3": "right"}, 3, 3)
    clip = _arm_clip("left", "sideways", "s9", np.random.default_rng(4))
    clf = CaseBaseClassifier(k=1, mirror="canonical").fit(X, y)
    exp = clf.explain_solved(clf.solve([clip])[0])
    assert exp.mirrored and exp.contrast is not None and exp.contrast.changes
    line = next(x for x in exp.verbose.splitlines() if "Counterfactual (" in x)
    named = line.split(": ", 1)[1].split(", every value", 1)[0]
    features = [c.feature.removeprefix("joint:") for c in exp.contrast.changes]
    assert named == ", ".join(swap_side(f) for f in features)
    assert all(c.words.startswith("left") for c in exp.contrast.changes)  # the moving arm
    assert "right" not in named


def test_auto_keeps_side_twins_apart() -> None:
    rng = np.random.default_rng(6)
    X, y = [], []
    for subject in ("s1", "s2", "s3"):
        for arm in ("left", "right", "both"):
            for _ in range(3):
                X.append(_arm_clip(arm, "sideways", subject, rng))
                y.append(f"{arm} sideways")
    Xt = [_arm_clip(arm, "sideways", "s9", rng) for arm in ("left", "right", "both")]
    clf = CaseBaseClassifier(k=3).fit(X, y)
    # filing left-arm clips under the right arm would merge the two activities: inner
    # cross-validation sees that
    assert clf.side_ != "canonical"
    chosen = f"{clf.weighting_}/{clf.phases_} phases"
    assert clf.selection_[f"canonical/{chosen}"] < clf.selection_[f"{clf.side_}/{chosen}"]
    assert list(clf.predict(Xt)) == ["left sideways", "right sideways", "both sideways"]


@pytest.mark.parametrize("side", ["off", "canonical", "augment"])
@pytest.mark.parametrize("weighting", ["none", "fisher"])
def test_inner_score_equals_refitting_the_classifier_per_held_out_subject(
    side: str, weighting: str
) -> None:
    X, y = _data({"s1": "right", "s2": "left", "s3": "right"}, 2, 7)
    subjects = np.array([s.metadata["subject"] for s in X], dtype=object)
    labels = np.array(y, dtype=object)
    hits = 0
    for s in ("s1", "s2", "s3"):
        tr = [i for i in range(len(X)) if subjects[i] != s]
        te = [i for i in range(len(X)) if subjects[i] == s]
        clf = CaseBaseClassifier(k=3, mirror=side, feature_weights=weighting, phases=3)
        clf.fit([X[i] for i in tr], labels[tr])
        hits += int((clf.predict([X[i] for i in te]) == labels[te]).sum())
    # the vectorised inner score on the matrices fit builds
    cfg = resolve_config(CaseBaseClassifier(phases=3).wanted_config(), X)
    R = np.stack([extract_problem(s, cfg).values for s in X])
    M = np.stack([extract_problem(mirrored(s), cfg).values for s in X])
    left = np.array([moves_left_more(s) for s in X])
    # fit resolves the states on the training subjects of each fold; with these clean clips
    # every state is available everywhere, so one resolution serves all folds
    got = inner_loso_accuracy(R, M, left, labels, subjects, side, weighting, 3)
    assert got == pytest.approx(hits / len(X))


def test_posecbr_train_stores_what_fit_learns(tmp_path: Path) -> None:
    X, y = _data({"s1": "right", "s2": "left", "s3": "right"}, 2, 8)
    for i, (seq, label) in enumerate(zip(X, y, strict=True)):
        save_pose(seq.with_metadata(label=label), tmp_path / "train" / f"clip{i:02d}.npz")
    db = str(tmp_path / "cb.sqlite")
    assert main(["train", str(tmp_path / "train"), "--db", db, "-k", "3", "--json"]) == 0
    clf = CaseBaseClassifier(k=3).fit(X, y)
    from casebase_store import open_store

    store = open_store(db)
    try:
        arrays = store.load_cases("default")
        info = store.get_case_base("default")
    finally:
        store.close()
    assert len(arrays.ids) == len(clf.case_base_)
    assert tuple(info.feature_names) == clf.case_base_.names
    np.testing.assert_allclose(arrays.features, clf.case_base_.problems, atol=1e-6)


def test_posecbr_train_predicts_like_fit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    X, y = _data({"s1": "right", "s2": "left", "s3": "right"}, 2, 10)
    for i, (seq, label) in enumerate(zip(X, y, strict=True)):
        save_pose(seq.with_metadata(label=label), tmp_path / "train" / f"clip{i:02d}.npz")
    rng = np.random.default_rng(11)
    Xt = [_arm_clip(a, m, "s9", rng) for a, m in (("left", "sideways"), ("both", "forward"))]
    for i, seq in enumerate(Xt):
        save_pose(seq, tmp_path / "test" / f"q{i}.npz")
    db = str(tmp_path / "cb.sqlite")
    assert main(["train", str(tmp_path / "train"), "--db", db, "-k", "3"]) == 0
    capsys.readouterr()
    assert main(["classify", str(tmp_path / "test"), "--db", db, "-k", "3", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    clf = CaseBaseClassifier(k=3).fit(X, y)
    got = [r["label"] for r in doc["results"]]  # the folder's files in name order
    assert got == ["one arm sideways", "both arms forward"]
    assert list(clf.predict(Xt)) == got


def test_append_to_a_mirror_augmented_case_base_keeps_its_columns(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    X, y = _data({"s1": "right", "s2": "right"}, 2, 12)
    for i, (seq, label) in enumerate(zip(X, y, strict=True)):
        folder = "a" if i % 2 == 0 else "b"
        save_pose(seq.with_metadata(label=label), tmp_path / folder / f"clip{i:02d}.npz")
    db = str(tmp_path / "cb.sqlite")
    # unweighted: Fisher weights from six clips would be mostly noise
    train = ["train", str(tmp_path / "a"), "--db", db, "--mirror", "augment"]
    assert main([*train, "--feature-weights", "none"]) == 0
    assert main(["train", str(tmp_path / "b"), "--db", db, "--append", "--json"]) == 0
    out = capsys.readouterr().out
    doc = json.loads(out[out.index("{") :])
    # 6 real clips + 6 mirror images first, then 6 appended real clips (no images: the
    # stored weights and columns are kept, nothing is re-learned)
    assert doc["cases"] == 6
    from casebase_store import open_store

    store = open_store(db)
    try:
        arrays = store.load_cases("default")
        names = store.get_case_base("default").feature_names
    finally:
        store.close()
    assert names[-1] == "mirror_image" and len(arrays.ids) == 18
    np.testing.assert_array_equal(arrays.features[:, -1], [0.0] * 6 + [1.0] * 6 + [0.0] * 6)
    rng = np.random.default_rng(13)
    save_pose(_arm_clip("left", "sideways", "s9", rng), tmp_path / "q" / "q.npz")
    assert main(["classify", str(tmp_path / "q"), "--db", db, "--json"]) == 0
    res = json.loads(capsys.readouterr().out)["results"][0]
    assert res["label"] == "one arm sideways"


def test_weights_are_judged_only_with_three_or_more_subjects() -> None:
    # with two people an inner fold would learn the weights from one person: fisher is kept
    X, y = _data({"s1": "right", "s2": "right"}, 2, 14)
    clf = CaseBaseClassifier(k=1).fit(X, y)
    assert clf.weighting_ == "fisher"
    assert {key.split("/")[1] for key in clf.selection_} == {"fisher"}
    X3, y3 = _data({"s1": "right", "s2": "right", "s3": "right"}, 2, 15)
    clf3 = CaseBaseClassifier(k=1).fit(X3, y3)
    assert {key.split("/")[1] for key in clf3.selection_} == {"none", "fisher"}


@pytest.mark.parametrize("seed", [21, 22])
def test_plain_choice_stays_unless_another_is_better_by_a_standard_error(seed: int) -> None:
    # Breiman's one-standard-error rule over the inner leave-one-subject-out scores: the plain
    # choice (canonical side, fisher weights, no phase means) unless the best beats it by more
    # than sqrt(p (1 - p) / n) of the best inner accuracy p over the n training clips
    X, y = _data({"s1": "right", "s2": "left", "s3": "right", "s4": "right"}, 2, seed)
    clf = CaseBaseClassifier(k=3).fit(X, y)
    scores = clf.selection_
    best = max(scores.values())
    plain = scores["canonical/fisher/0 phases"]
    chosen = scores[f"{clf.side_}/{clf.weighting_}/{clf.phases_} phases"]
    if best - plain <= np.sqrt(best * (1 - best) / len(X)):
        assert (clf.side_, clf.weighting_, clf.phases_) == ("canonical", "fisher", 0)
    else:
        assert chosen == best


def test_side_twins_beat_the_plain_choice_by_more_than_a_standard_error() -> None:
    rng = np.random.default_rng(31)
    X, y = [], []
    for subject in ("s1", "s2", "s3"):
        for arm in ("left", "right"):
            for _ in range(3):
                X.append(_arm_clip(arm, "sideways", subject, rng))
                y.append(f"{arm} sideways")
    clf = CaseBaseClassifier(k=3).fit(X, y)
    # filing the left-arm clips under the right arm leaves nothing to tell the two apart
    assert clf.selection_["canonical/fisher/0 phases"] <= 0.75
    assert clf.side_ != "canonical"


def test_one_subject_keeps_the_side_asked_for() -> None:
    # one subject: nobody to hold out, so nothing is chosen; a side asked for is still the
    # side used (the phases left to choose do not undo it), and a new person's left-arm clip
    # is then recognised as the right-arm cases' activity
    X, y = _data({"s1": "right"}, 3, 7)
    clip = _arm_clip("left", "sideways", "s9", np.random.default_rng(8))
    clf = CaseBaseClassifier(k=1, mirror="canonical").fit(X, y)
    assert clf.side_ == "canonical"
    assert clf.solve([clip])[0].problem.mirrored
    assert list(clf.predict([clip])) == ["one arm sideways"]
    assert CaseBaseClassifier(k=1).fit(X, y).side_ == "off"  # auto with one subject
