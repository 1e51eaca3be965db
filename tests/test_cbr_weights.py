"""Feature weighting, clip summaries, joint-angle columns and mirror-image cases of the CBR
classifier: hand-worked values and synthetic clips whose answer is known by construction."""

from __future__ import annotations

import numpy as np
import pytest

from casebase_store import config_hash
from cbr.estimator import CaseBaseClassifier
from cbr.problem import FeatureConfig, extract_problem, resolve_config, summarise
from cbr.similarity import Euclidean, get_measure
from cbr.weights import confusing_mirrors, fisher_ratio, learn_weights, mirror_penalty
from features.body import arm_planes, mirrored
from features.errors import ConfigError
from features.poses import PoseSequence
from tests.bodies import rot_x, rot_y, rot_z, rotate, standing, to_sequence
from tests.test_cbr_clips import ARM

# ---------------------------------------------------------------- weights (hand-worked)


def test_fisher_ratio_by_hand() -> None:
    # column 0: classes at 0,2 and 10,12 -> class means 1, 11, grand 6
    # between = 2*25 + 2*25 = 100; within = 4 * 1 = 4 -> 100 / (4 + 1e-3 * 104)
    # column 1: identical spread in both classes -> between 0
    X = np.array([[0.0, 5.0], [2.0, 7.0], [10.0, 5.0], [12.0, 7.0]])
    y = np.array(["a", "a", "b", "b"])
    r = fisher_ratio(X, y)
    assert r[0] == pytest.approx(100.0 / (4.0 + 0.104))
    assert r[1] == pytest.approx(0.0)


def test_learn_weights_normalises_and_zeroes_constant_columns() -> None:
    X = np.array([[0.0, 1.0, 3.0], [2.0, 3.0, 3.0], [10.0, 1.0, 3.0], [12.0, 3.0, 3.0]])
    y = np.array([0, 0, 1, 1])
    fw = learn_weights(X, y)
    np.testing.assert_allclose(fw.centre, [6.0, 2.0, 3.0])
    np.testing.assert_allclose(fw.scale, [np.sqrt(26.0), 1.0, 1e-3])  # population std
    assert fw.weight[2] == 0.0 and fw.weight[1] == pytest.approx(0.0)
    assert fw.weight.mean() == pytest.approx(1.0) and fw.weight[0] == pytest.approx(3.0)
    # weighted distance between rows 0 and 2: only column 0 counts, (10/sqrt(26))^2 * 3
    d2 = ((fw.apply(X[0]) - fw.apply(X[2])) ** 2).sum()
    assert d2 == pytest.approx(100.0 / 26.0 * 3.0)
    with pytest.raises(ConfigError, match="feature weighting"):
        learn_weights(X, y, "relief")


def test_weighting_finds_a_planted_feature_and_rescues_nearest_neighbour() -> None:
    rng = np.random.default_rng(3)
    n, noise = 200, 30
    y = rng.integers(0, 2, n)
    X = rng.normal(scale=5.0, size=(n, noise + 1))  # loud uninformative columns
    X[:, 7] = y + rng.normal(scale=0.1, size=n)  # one quiet column carries the label
    fw = learn_weights(X[:100], y[:100])
    assert int(np.argmax(fw.weight)) == 7 and fw.weight[7] > 10 * np.median(fw.weight)

    def nn_accuracy(a: np.ndarray, b: np.ndarray) -> float:
        d = ((b[:, None, :] - a[None, :, :]) ** 2).sum(axis=2)
        return float((y[:100][np.argmin(d, axis=1)] == y[100:]).mean())

    plain = nn_accuracy(X[:100], X[100:])
    weighted = nn_accuracy(fw.apply(X[:100]), fw.apply(X[100:]))
    assert plain < 0.75 and weighted > 0.95


def test_euclidean_measure_applies_the_weighting() -> None:
    m = get_measure("euclidean", centre=(1.0, 0.0), multiplier=(2.0, 0.5), exact=True)
    reps = m.represent(np.array([[1.0, 0.0], [2.0, 2.0]]))
    np.testing.assert_allclose(reps, [[0.0, 0.0], [2.0, 1.0]])
    d = m.distances(m.represent_query(np.array([1.0, 0.0])), m.build_index(reps))
    np.testing.assert_allclose(d, [0.0, np.sqrt(5.0)])
    with pytest.raises(ConfigError, match="go together"):
        get_measure("euclidean", centre=(1.0,))
    with pytest.raises(ConfigError, match="columns"):
        m.represent(np.zeros((1, 3)))


def test_mirror_penalty_is_the_median_same_activity_neighbour_distance() -> None:
    # one column, unit weight after z-normalisation: a at 0, 1, 3 and b at 10, 14
    real = np.array([[0.0], [1.0], [3.0], [10.0], [14.0]])
    y = np.array(["a", "a", "a", "b", "b"])
    fw = learn_weights(real, y, "none")
    s = fw.scale[0]
    # nearest same-activity neighbours: 1, 1, 2, 4, 4 (raw) -> median 2 -> 2 / s weighted
    out = mirror_penalty(fw, real, y)
    assert out.weight[-1] == pytest.approx((2.0 / s) ** 2)
    assert out.centre[-1] == 0.0 and out.scale[-1] == 1.0
    np.testing.assert_allclose(out.multiplier()[-1], 2.0 / s)


def test_side_twin_activities_lose_their_mirror_images() -> None:
    # columns: (left arm up, right arm up, both up); mirroring swaps the first two
    real = np.array([[1, 0, 0], [0.9, 0, 0], [0, 1, 0], [0, 0.9, 0], [0, 0, 1], [0, 0, 0.9]])
    mirror = real[:, [1, 0, 2]]
    y = np.array(["left", "left", "right", "right", "both", "both"])
    fw = learn_weights(real, y, "none")
    bad = confusing_mirrors(fw, real, mirror, y, penalty=0.1)  # each image IS a twin clip
    np.testing.assert_array_equal(bad, [True, True, True, True, False, False])


# ---------------------------------------------------------------- problems


def _elbow_clip(bend_deg: float, frames: int = 4) -> PoseSequence:
    body = standing()
    forearm = ("left_wrist", "left_pinky", "left_index", "left_thumb")
    bent = rotate(body, forearm, rot_x(bend_deg), body["left_elbow"])
    return to_sequence(*([bent] * frames))


def test_angle_columns_are_the_joint_angles_over_pi() -> None:
    seq = _elbow_clip(90.0)  # forearm forward: a right angle at the left elbow
    cfg = resolve_config(FeatureConfig(length=4, angles=True), [seq])
    assert "angle:left_elbow" in cfg.states and "angle:right_elbow" in cfg.states
    p = extract_problem(seq, cfg)
    col = p.names.index("angle:left_elbow")
    np.testing.assert_allclose(p.values[:, col], 0.5, atol=1e-9)
    np.testing.assert_allclose(p.values[:, p.names.index("angle:right_elbow")], 1.0, atol=1e-9)
    assert p.words[col] == "left elbow angle"


def test_arm_plane_reads_forward_sideways_and_undefined_when_hanging() -> None:
    body = standing()
    left = tuple(f"left_{j}" for j in ARM)
    right = tuple(f"right_{j}" for j in ARM)
    # left arm straight out to the side (abduction 90 deg), right arm straight forward
    b = rotate(body, left, rot_z(-90.0), body["left_shoulder"])
    b = rotate(b, right, rot_x(-90.0), body["right_shoulder"])
    planes = arm_planes(to_sequence(b, body))
    np.testing.assert_allclose(planes[0], [np.pi / 2, 0.0], atol=1e-9)
    assert np.isnan(planes[1]).all()  # hanging arms have no plane of elevation
    # 45 deg between forward and sideways: scaption-like
    c = rotate(body, left, rot_z(-90.0), body["left_shoulder"])
    c = rotate(c, left, rot_y(-45.0), body["left_shoulder"])
    assert arm_planes(to_sequence(c))[0, 0] == pytest.approx(np.pi / 4)


def test_summary_statistics_by_hand() -> None:
    values = np.array([[0.0, 1.0], [1.0, 1.0], [0.5, 1.0], [0.5, 1.0]])
    p = summarise(values, ("a.x", "angle:b"), ("a x", "b angle"))
    np.testing.assert_allclose(p.values, [0.5, 1.0, 0.0, 1.0, 1.0, 1.0, np.sqrt(0.125), 0.0])
    assert p.names[:3] == ("a.x@mean", "angle:b@mean", "a.x@min")
    assert p.words[0] == "a x" and p.words[2] == "a x (lowest confidence)"
    assert p.words[3] == "b angle (lowest)" and p.words[7] == "b angle (variation)"


def test_new_options_keep_old_configuration_hashes() -> None:
    old = {"level": "fluents", "length": 32, "states": "angles", "min_available": 0.5,
           "fill": 0.0, "qmp_part": "binary"}  # fmt: skip
    assert config_hash(FeatureConfig().to_dict()) == config_hash(old)
    assert FeatureConfig.from_dict(old) == FeatureConfig()
    assert config_hash(FeatureConfig(summary=True).to_dict()) != config_hash(old)


def test_mirrored_clip_swaps_sides_and_negates_x() -> None:
    seq = _elbow_clip(90.0)
    m = mirrored(seq)
    li, ri = seq.joint_names.index("left_wrist"), seq.joint_names.index("right_wrist")
    expect = seq.positions[:, li] * np.array([-1.0, 1.0, 1.0])
    np.testing.assert_allclose(m.positions[:, ri], expect)
    np.testing.assert_allclose(mirrored(m).positions, seq.positions)
    cfg = resolve_config(FeatureConfig(length=4, angles=True), [seq])
    pm = extract_problem(m, cfg)
    np.testing.assert_allclose(pm.values[:, pm.names.index("angle:right_elbow")], 0.5, atol=1e-9)


# ---------------------------------------------------------------- the classifier


def _arm_clip(arm: str, motion: str, subject: str, rng: np.random.Generator) -> PoseSequence:
    """One arm ("left"/"right"/"both") raised sideways or forward and lowered again."""
    body = standing()
    peak = rng.uniform(110, 150)
    out = []
    for a in peak * np.sin(np.linspace(0, np.pi, 30)):
        b = body
        for side in ("left", "right") if arm == "both" else (arm,):
            sign = -1.0 if side == "left" else 1.0
            r = rot_z(sign * a) if motion == "sideways" else rot_x(-a)
            b = rotate(b, tuple(f"{side}_{j}" for j in ARM), r, b[f"{side}_shoulder"])
        out.append({k: v + rng.normal(scale=0.005, size=3) for k, v in b.items()})
    return to_sequence(*out).with_metadata(subject=subject)


def test_mirror_images_recognise_the_other_side_and_weights_come_from_training_only() -> None:
    rng = np.random.default_rng(5)
    # training subjects do "one arm sideways" with the right arm only
    kinds = {"one arm sideways": ("right", "sideways"), "both arms forward": ("both", "forward"),
             "left arm forward": ("left", "forward")}  # fmt: skip
    X, y = [], []
    for subject in ("s1", "s2", "s3"):
        for label, (arm, motion) in kinds.items():
            for _ in range(3):
                X.append(_arm_clip(arm, motion, subject, rng))
                y.append(label)
    # a new person raises the LEFT arm sideways: the same activity on the other side
    Xt = [_arm_clip("left", "sideways", "s9", rng) for _ in range(4)]
    clf = CaseBaseClassifier(similarity="euclidean", k=1, mirror="augment").fit(X, y)
    assert clf.mirror_ and clf.mirror_cases_ == len(X)  # no side twins here: all images kept
    assert list(clf.predict(Xt)) == ["one arm sideways"] * 4
    exp = clf.explain(Xt[:1])[0]
    assert exp.neighbours[0]["source"].endswith("(mirrored)")
    # the case base's heaviest weights are said once, by casebase info, not in every clip
    # the weights are those of the training clips alone, and predicting does not move them
    real = np.stack([extract_problem(s, clf.feature_config_).values for s in X])
    fw = learn_weights(real, np.array(y))
    measure = clf.measure_
    assert isinstance(measure, Euclidean) and measure.multiplier is not None
    multiplier = np.array(measure.multiplier)
    np.testing.assert_allclose(multiplier[:-1], fw.multiplier())
    clf.predict(Xt)
    assert clf.measure_ is measure  # frozen measure, same object: predicting learns nothing


def test_side_specific_activities_stay_apart_with_mirroring_on() -> None:
    rng = np.random.default_rng(6)
    X, y = [], []
    for subject in ("s1", "s2"):
        for arm in ("left", "right", "both"):
            for _ in range(4):
                X.append(_arm_clip(arm, "sideways", subject, rng))
                y.append(f"{arm} sideways")
    Xt = [_arm_clip(arm, "sideways", "s9", rng) for arm in ("left", "right", "both")]
    clf = CaseBaseClassifier(similarity="euclidean", k=3, mirror=True).fit(X, y)
    # left and right are each other's mirror image: their images are dropped, both's kept
    assert clf.mirror_cases_ == 8
    assert list(clf.predict(Xt)) == ["left sideways", "right sideways", "both sideways"]


def test_bad_options_are_config_errors() -> None:
    X = [_arm_clip("left", "sideways", "s1", np.random.default_rng(0)) for _ in range(2)]
    with pytest.raises(ConfigError, match="feature_weights"):
        CaseBaseClassifier(feature_weights="relief").fit(X, ["a", "b"])
    with pytest.raises(ConfigError, match="mirror: must be"):
        CaseBaseClassifier(mirror="yes").fit(X, ["a", "b"])
    with pytest.raises(ConfigError, match="learned feature weights need vector problems"):
        CaseBaseClassifier(similarity="dtw", feature_weights="fisher").fit(X, ["a", "b"])
