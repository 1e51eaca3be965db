"""The confidence's soft vote: hand-computed weights, a temperature recovered from answers drawn
with it, and a calibration checked against the true probability of synthetic data.

The synthetic people: three activities whose clips lie around the corners of a triangle
(spread ``SIGMA`` in every direction), so a new person's clip of activity c lies at
``N(mu_c, SIGMA^2)`` and the probability that an answer is right is that answer's posterior
under these Gaussians (equal priors), worked out in closed form below rather than by the code
under test."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cbr.calibration import (
    ConfidenceCalibration,
    calibrate_confidence,
    calibrate_soft,
    fit_temperature,
    held_out_votes,
    soft_vote,
)
from cbr.reuse import vote

MEANS = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, math.sqrt(3.0)]])
SIGMA = 0.6
CLASSES = np.array(["a", "b", "c"])
K, WIDE = 5, 10


def test_soft_vote_by_hand() -> None:
    # d / d_1 = 1, 2, 3 at T = 1: weights e^-1, e^-4, e^-9 for classes 0, 1, 0
    p = soft_vote(np.array([[1.0, 2.0, 3.0]]), np.array([[0, 1, 0]]), 3, 1.0)[0]
    total = math.exp(-1) + math.exp(-4) + math.exp(-9)
    assert p == pytest.approx([(math.exp(-1) + math.exp(-9)) / total, math.exp(-4) / total, 0])
    # only relative distances count: the same clip twice as far from every case
    assert soft_vote(np.array([[2.0, 4.0, 6.0]]), np.array([[0, 1, 0]]), 3, 1.0)[0] == (
        pytest.approx(p)
    )
    # an exact match takes the whole vote; a missing case (inf) none
    exact = soft_vote(np.array([[0.0, 0.5, np.inf]]), np.array([[2, 1, 0]]), 3, 1.0)[0]
    assert exact == pytest.approx([0.0, 0.0, 1.0])


def test_the_temperature_answers_were_drawn_with_is_recovered() -> None:
    rng = np.random.default_rng(0)
    d = np.sort(rng.uniform(1.0, 3.0, (4000, WIDE)), axis=1)
    codes = rng.integers(0, 3, (4000, WIDE))
    p = soft_vote(d, codes, 3, 0.7)
    truth = (rng.uniform(size=(4000, 1)) > np.cumsum(p, axis=1)).sum(axis=1)
    assert fit_temperature(d, codes, truth, 3) == pytest.approx(0.7, rel=0.1)


def _people(rng: np.random.Generator, people: int, per: int) -> tuple[np.ndarray, np.ndarray,
                                                                       np.ndarray]:  # fmt: skip
    """``people`` persons' clips, ``per`` of each activity: points ``(n, 2)``, labels and
    persons ``(n,)``."""
    x = MEANS[None, :, None, :] + rng.normal(0.0, SIGMA, (people, 3, per, 2))
    who = np.broadcast_to(np.arange(people)[:, None, None], (people, 3, per))
    labels = np.broadcast_to(CLASSES[None, :, None], (people, 3, per))
    return x.reshape(-1, 2), labels.reshape(-1), who.reshape(-1)


def _nearest(queries: np.ndarray, cases: np.ndarray, same: np.ndarray | None,
             n: int) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Distances and positions ``(q, n)`` of the nearest cases, nearest first (``same``
    ``(q, cases)``: pairs left out)."""
    d = np.linalg.norm(queries[:, None, :] - cases[None, :, :], axis=2)
    if same is not None:
        d = np.where(same, np.inf, d)
    idx = np.argsort(d, axis=1, kind="stable")[:, :n]
    return np.take_along_axis(d, idx, axis=1), idx


def _posterior(x: np.ndarray) -> np.ndarray:
    """``(q, 3)``: P(activity | x) for a new person, equal priors, isotropic Gaussians of
    variance SIGMA^2 around the means."""
    e = -((x[:, None, :] - MEANS[None]) ** 2).sum(axis=2) / (2.0 * SIGMA**2)
    w = np.exp(e - e.max(axis=1, keepdims=True))
    return w / w.sum(axis=1, keepdims=True)


def _gap_to_truth(conf: np.ndarray, truth: np.ndarray, bins: int = 10) -> float:
    """The ECE against the true probability of being right (no outcome noise)."""
    which = np.clip((conf * bins).astype(int), 0, bins - 1)
    return float(sum((which == b).mean() * abs(truth[which == b].mean() - conf[which == b].mean())
                     for b in range(bins) if (which == b).any()))  # fmt: skip


@pytest.mark.parametrize("seed", [0, 1])
def test_the_soft_confidence_is_the_chance_of_being_right_for_new_people(seed: int) -> None:
    rng = np.random.default_rng(seed)
    x, y, who = _people(rng, 6, 60)
    codes = np.searchsorted(CLASSES, y)
    # every training clip held out by person, as fit does
    d, idx = _nearest(x, x, who[:, None] == who[None, :], WIDE)
    h = held_out_votes(d, codes[idx], CLASSES, y, K)
    cal = calibrate_soft(h, 3, "leave-one-person-out", WIDE)
    new, _, _ = _people(rng, 20, 50)
    d, idx = _nearest(new, x, None, WIDE)
    answer = vote(d[:, :K], codes[idx][:, :K], 3).argmax(axis=1)
    conf = np.array([cal(cal.score(d[i], codes[idx][i], 3, answer[i], float("nan")))
                     for i in range(len(new))])  # fmt: skip
    truth = _posterior(new)[np.arange(len(new)), answer]
    # the goal for the expected calibration error, here against the true chance
    assert _gap_to_truth(conf, truth) <= 0.05
    # and not by a constant: the confidence follows the chance (wrong-side clips score low)
    assert np.corrcoef(conf, truth)[0, 1] > 0.5


def test_a_calibration_round_trips_and_an_old_one_maps_the_share() -> None:
    share = np.array([0.4, 0.6, 0.8, 1.0, 1.0, 0.6])
    right = np.array([False, True, True, True, True, False])
    cal = calibrate_confidence(share, right, "x")
    soft = ConfidenceCalibration(cal.x, cal.y, "x", 6, 4 / 6, 0.5, 10)
    assert ConfidenceCalibration.from_dict(soft.to_dict()) == soft
    old = {k: v for k, v in cal.to_dict().items() if k not in ("temperature", "neighbours")}
    loaded = ConfidenceCalibration.from_dict(old)
    assert loaded.neighbours == 0
    assert loaded.score(np.array([1.0, 2.0]), np.array([0, 1]), 2, 0, 0.8) == 0.8


@pytest.mark.parametrize(
    "damage", [{"temperature": 0.0}, {"temperature": -1.0}, {"neighbours": -3}]
)
def test_a_damaged_soft_vote_is_refused(damage: dict[str, float]) -> None:
    # a temperature that is not positive would divide by zero or flip the weights (the
    # farthest case weighing most); a negative neighbourhood has no cases
    cal = calibrate_confidence(np.array([0.4, 1.0]), np.array([False, True]), "x")
    stored = {**ConfidenceCalibration(cal.x, cal.y, "x", 2, 0.5, 0.5, 10).to_dict(), **damage}
    with pytest.raises(ValueError, match="positive temperature and neighbourhood"):
        ConfidenceCalibration.from_dict(stored)


def test_scores_of_many_queries_are_each_querys_soft_vote_for_its_answer() -> None:
    # by hand, T = 1, 2 neighbours read: query 0 d/d1 = 1, 2 (classes 0, 1): weights e^-1,
    # e^-4; query 1 d/d1 = 1, 1 (classes 1, 1): all of it for class 1
    cal = ConfidenceCalibration((), (), "subject", 0, 0.0, 1.0, 2)
    d = np.array([[1.0, 2.0, 9.0], [3.0, 3.0, 9.0]])
    c = np.array([[0, 1, 0], [1, 1, 0]])
    got = cal.scores(d, c, 2, [1, 1], [0.5, 1.0])
    total = math.exp(-1) + math.exp(-4)
    assert got == pytest.approx([math.exp(-4) / total, 1.0])
    assert cal.score(d[0], c[0], 2, 1, 0.5) == pytest.approx(math.exp(-4) / total)
    # a calibration of the vote share maps the shares given
    shares = ConfidenceCalibration((), (), "subject", 0, 0.0, 1.0, 0)
    assert shares.scores(d, c, 2, [1, 1], [0.25, 0.75]) == pytest.approx([0.25, 0.75])


def test_a_clip_no_case_could_answer_is_left_out_of_the_calibration() -> None:
    # the training clips of two people held out by person; the second person's clips are
    # then held out again against a case base of the first person only, as a case base edited
    # down to one subject is: those clips have no case (all inf) and say nothing of how often
    # an answer is right. The calibration is the one of the answered clips alone, with no
    # NaN on the way (it was NaN-poisoned: an all-inf row's soft vote was 0/0)
    rng = np.random.default_rng(3)
    x, y, who = _people(rng, 2, 40)
    codes = np.searchsorted(CLASSES, y)
    d, idx = _nearest(x, x, who[:, None] == who[None, :], WIDE)
    answered = held_out_votes(d, codes[idx], CLASSES, y, K)
    none = np.full((10, WIDE), np.inf)
    with np.errstate(invalid="raise"):  # no NaN made (underflow of far weights is fine)
        assert soft_vote(none, np.zeros((10, WIDE), dtype=int), 3, 1.0).tolist() == [[0.0] * 3] * 10
        mixed = held_out_votes(np.vstack([d, none]), np.vstack([codes[idx], np.zeros_like(
            none, dtype=int)]), CLASSES, np.concatenate([y, y[:10]]), K)  # fmt: skip
        cal = calibrate_soft(mixed, 3, "leave-one-person-out", WIDE)
    alone = calibrate_soft(answered, 3, "leave-one-person-out", WIDE)
    assert cal.n == alone.n == len(x)
    assert cal.temperature == pytest.approx(alone.temperature)
    assert cal.y == pytest.approx(alone.y)


def test_pieces_of_one_recording_are_held_out_with_those_overlapping_them() -> None:
    """Windows cut every 0.5 s from one recording overlap their neighbours, near copies of
    them: held out one by one, a window's nearest case was its neighbour. With the frames,
    the cases overlapping a query leave with it. Cases on a line, problem (x, 0), so every
    distance is |x_i - x_j|: three overlapping A windows at x 0, 0.1, 0.2 (frames 0-240,
    60-300, 120-360), two more A at 1.0 and 1.1 later on (600-840, 900-1140), B at 5.0
    (1200-1440). The window at x = 0 lies 0.1 from its neighbour, 1.0 from the first A it
    does not overlap."""
    from cbr.calibration import held_out
    from cbr.casebase import CaseBase
    from cbr.problem import FeatureConfig
    from cbr.similarity import Euclidean

    xs = [0.0, 0.1, 0.2, 1.0, 1.1, 5.0]
    labels = ["A", "A", "A", "A", "A", "B"]
    spans = [(0, 240), (60, 300), (120, 360), (600, 840), (900, 1140), (1200, 1440)]
    p = np.array([[x, 0.0] for x in xs])
    cb = CaseBase(FeatureConfig(), Euclidean(exact=True), p, np.array(labels, dtype=object),
                  ("x", "y"), ("x", "y"), frames=tuple(spans))  # fmt: skip
    frames = np.array(spans)
    queries, groups = p[[0, 3]], np.array([0, 3], dtype=object)
    case_groups = np.arange(6).astype(object)
    alone = held_out(cb, queries, np.array(["A", "A"]), groups, case_groups, k=1)
    np.testing.assert_allclose(alone.nearest, [0.1, 0.1])  # its neighbour; 1.1's window
    with_frames = held_out(cb, queries, np.array(["A", "A"]), groups, case_groups, k=1,
                           frames=(frames[[0, 3]], frames))  # fmt: skip
    # x = 0: 0.1 and 0.2 overlap it, the nearest left is 1.0; x = 1.0 overlaps nothing
    np.testing.assert_allclose(with_frames.nearest, [1.0, 0.1])
    assert with_frames.right.tolist() == [True, True]
    # a query whose every other case of its label overlaps it cannot be answered right
    lone = held_out(cb, p[[0]], np.array(["A"]), np.array([0], dtype=object), case_groups, k=1,
                    frames=(np.array([[0, 1200]]), frames))  # fmt: skip
    assert lone.truth.tolist() == [-1] and lone.nearest.tolist() == [5.0]
