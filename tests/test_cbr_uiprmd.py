"""End to end on real UI-PRMD (Kinect): train on subjects s01-s05, classify s06-s08.

Ten movements (chance = 0.10). Accuracies measured when this was written (k = 5; fluents: angle
states, 32 frames): fluents+euclidean 0.81, fluents+dtw 0.81, fluents+signature 0.65, qmp
(binary ADD criteria)+euclidean 0.79 (on every clip); on episodes 1, 5 and 9 of every subject
and movement (2026-12-04), as all but fluents/euclidean are tested to cut the suite's costliest
steps to a third: dtw 0.84, signature 0.68, qmp 0.87. Since 2026-12-05 only the odd episodes
are read, and fluents/euclidean is tested on them (half the clips; 0.97 on every clip and on
the odd ones). Later that day the costlier three read episodes 1 and 9 alone (a fifth of the
clips): dtw 0.86, signature 0.70, qmp 0.83. Since 2026-12-07 qmp, by far the costliest (its
fit and predict 72.8 -> 30.8 s at load 15), reads episode 1 alone (a tenth of the clips; 60
held-out clips): 0.78 (dtw 0.80 there, signature 0.60, too near its floor; both cost little
and keep episodes 1 and 9). The floors below are conservative so a regression in features or
retrieval shows, not run-to-run noise. The module's tests run on one xdist worker: the data set
is read once.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import cbr.counterfactual as cfm
from cbr.casebase import CaseBase
from cbr.estimator import CaseBaseClassifier
from cbr.profiles import view_of
from features.datasets import load_dataset

TRAIN = ["s01", "s02", "s03", "s04", "s05"]
TEST = ["s06", "s07", "s08"]
SHARED = ("fluents", "euclidean")  # on every clip read; shared with the explanation test
ODD = (1, 3, 5, 7, 9)  # the episodes read: half of every subject's and movement's clips
# the episodes the costlier configurations read: 1 and 9 (a fifth of the clips) or 1 (a tenth)
SOME = {("fluents", "dtw"): (1, 9), ("fluents", "signature"): (1, 9), ("qmp", "euclidean"): (1,)}
FLOORS = {
    ("fluents", "euclidean"): 0.70,
    ("fluents", "dtw"): 0.70,
    ("fluents", "signature"): 0.55,
    ("qmp", "euclidean"): 0.65,
}


@pytest.fixture(scope="module")
def uiprmd(shared_data: Path) -> tuple[list, list, list, list]:
    root = shared_data / "ui-prmd"
    tr = load_dataset(root, subjects=TRAIN, episodes=ODD)
    te = load_dataset(root, subjects=TEST, episodes=ODD)
    assert {c.subject for c in tr} == set(TRAIN) and {c.subject for c in te} == set(TEST)
    return [c.seq for c in tr], [c.label for c in tr], [c.seq for c in te], [c.label for c in te]


def _some_episodes(seqs: list, labels: list, episodes: tuple[int, ...]) -> tuple[list, list]:
    """The clips of ``episodes`` (:data:`SOME`; correct and incorrect alike): every subject
    and movement, one or two clips in ten. QMP features fit a SINDy model per signal of every
    clip, DTW and signatures compare whole sequences: the suite's costliest steps; a fifth
    or a tenth of the clips of the same people measure the same thing. The fluents/euclidean model,
    which the explanation test shares, reads every clip read (:data:`ODD`)."""
    keep = [i for i, s in enumerate(seqs) if s.metadata["episode"] in episodes]
    return [seqs[i] for i in keep], [labels[i] for i in keep]


@pytest.fixture(scope="module")
def fitted(uiprmd: tuple) -> Callable[[str, str], CaseBaseClassifier]:
    """The classifier of a configuration fitted on the training subjects, fitted once for the
    module: the explanation test reads the fluents/euclidean one the accuracy test measures
    (the tests only predict and explain with it, which changes nothing in it)."""
    Xtr, ytr, _, _ = uiprmd
    models: dict[tuple[str, str], CaseBaseClassifier] = {}

    def get(features: str, similarity: str) -> CaseBaseClassifier:
        if (features, similarity) not in models:
            clf = CaseBaseClassifier(features=features, similarity=similarity, k=5)
            X, y = (Xtr, ytr)
            if (features, similarity) != SHARED:
                X, y = _some_episodes(Xtr, ytr, SOME[features, similarity])
            models[features, similarity] = clf.fit(X, y)
        return models[features, similarity]

    return get


# Under pytest-xdist the module runs on one worker: UI-PRMD is read once, and the
# fluents/euclidean model the explanation test shares is fitted once.
pytestmark = pytest.mark.xdist_group("uiprmd")


@pytest.mark.parametrize(("features", "similarity"), list(FLOORS))
def test_held_out_subjects_accuracy(
    features: str, similarity: str, uiprmd: tuple, fitted: Callable[[str, str], Any]
) -> None:
    _, _, Xte, yte = uiprmd
    if (features, similarity) != SHARED:
        Xte, yte = _some_episodes(Xte, yte, SOME[features, similarity])
    pred = fitted(features, similarity).predict(Xte)
    acc = float(np.mean(pred == np.asarray(yte)))
    assert acc >= FLOORS[features, similarity], f"{features}/{similarity}: accuracy {acc:.3f}"
    # every movement is recognised at least sometimes (no activity collapses)
    assert set(pred) == set(yte)


def test_real_explanation_names_fluents(
    uiprmd: tuple, fitted: Callable[[str, str], CaseBaseClassifier]
) -> None:
    _, _, Xte, yte = uiprmd
    clf = fitted("fluents", "euclidean")
    squats = [x for x, v in zip(Xte, yte, strict=True) if v == "deep_squat"]
    # explain() is solve() then explain_solved() per clip; the counterfactual search of the
    # latter is the costly part, and only one squat's explanation is read
    recognised = [s for s in clf.solve(squats) if s.solution.label == "deep_squat"]
    assert len(recognised) >= len(squats) // 2  # most held-out squats are recognised
    words = set(clf.case_base_.words)
    # a deep squat bends both knees far below the 19pi/24 knee threshold
    knees = {"left knee bent", "right knee bent", "left knee bending", "right knee bending"}
    exp = clf.explain_solved(recognised[0])  # the first held-out squat recognised as one
    assert exp.label == "deep_squat"
    # a state held only part of the time is said with "(at times)" after its words
    matched = {m.removesuffix(" (at times)") for m in exp.matched}
    assert matched and matched <= words
    assert knees & (matched | set(exp.not_seen))


# The counterfactual search of vector problems, fast and the same (session 52): its beam
# search follows the classifier's vote over every candidate change (the problem with one
# feature's values taken from a guide case). A plain search builds every candidate problem
# and measures it against every case, as written below, and must find the very changes the
# fast search finds (which adds per-feature changes of the squared distances); each step of
# the fast search votes once over every candidate of every kept set. On the fitted case base
# cut to two movements; a query is one of its cases, its clip's cases left out.

K = 5  # the fitted classifier's k
MOVEMENTS = ("deep_squat", "sit_to_stand")


class _Plain:
    """Candidate problems of query ``q`` toward ``label`` with guide ``guide``'s values, each
    built and compared with every case (weighted squared distance), its k nearest cases
    voting 1/distance."""

    def __init__(self, cb: CaseBase, q: np.ndarray, guide: int, label: str) -> None:
        self.cb, self.q, self.guide, self.label = cb, q, guide, label
        self.view = view_of(cb)
        mult = cb.measure.multiplier
        self.w = np.ones(cb.problems.shape[1]) if mult is None else np.asarray(mult) ** 2
        self.labels = cb.labels.astype(str)
        self.classes = sorted(set(self.labels))
        self.target = self.classes.index(label)

    def changed(self, chosen: tuple[int, ...]) -> np.ndarray:
        p = self.q.copy()
        for f in chosen:
            cols = self.view.columns[self.view.feature == f]
            p[cols] = self.cb.problems[self.guide, cols]
        return p

    def margin_gap(self, chosen: tuple[int, ...]) -> tuple[float, float]:
        """The label's vote share minus the best other one; the guide's squared distance
        minus the mean of the k nearest cases of other labels."""
        d2 = ((self.cb.problems - self.changed(chosen)) ** 2 * self.w).sum(axis=1)
        share = np.zeros(len(self.classes))
        for i in np.argsort(d2)[:K]:
            share[self.classes.index(self.labels[i])] += 1.0 / np.sqrt(d2[i])
        share /= share.sum()
        rivals = np.sort(d2[self.labels != self.label])[:K].mean()
        margin = share[self.target] - np.delete(share, self.target).max()
        return float(margin), float(d2[self.guide] - rivals)

    def wins(self, chosen: tuple[int, ...]) -> bool:
        m = self.margin_gap(chosen)[0]
        return m > 0 or (m == 0 and self.target == 0)  # a tie: the first class


def _plain(cb: CaseBase, q: np.ndarray, guide: int, label: str) -> list[int] | None:
    """The beam search written plainly (:class:`_Plain`): extensions of every kept set by
    one feature ranked by margin, then by gap; the first size at which the label wins is
    kept, and every change it wins without undone (the last first)."""
    plain = _Plain(cb, q, guide, label)
    n_features = len(plain.view.features)
    assert n_features <= 4 * cfm.BEAM  # every feature is a candidate at every step
    beam: list[tuple[int, ...]] = [()]
    for _ in range(cfm.MAX_CHANGES):
        scored: dict[frozenset[int], tuple[float, float, tuple[int, ...]]] = {}
        for chosen in beam:
            got = {f: plain.margin_gap((*chosen, f)) for f in range(n_features) if f not in chosen}
            for f in sorted(got, key=lambda f: -got[f][0]):  # stable: ties keep feature order
                scored.setdefault(frozenset((*chosen, f)), (*got[f], (*chosen, f)))
        ranked = sorted(scored.values(), key=lambda t: (-t[0], t[1]))[: cfm.BEAM]
        beam = [c for _, _, c in ranked]
        won = [c for c in beam if plain.wins(c)]
        if won:
            chosen = won[0]
            for f in reversed(won[0]):
                rest = tuple(c for c in chosen if c != f)
                if rest and plain.wins(rest):
                    chosen = rest
            return list(chosen)
    return None


@pytest.fixture(scope="module")
def two_movements(fitted: Callable[[str, str], CaseBaseClassifier]) -> CaseBase:
    """The fitted UI-PRMD case base's cases of :data:`MOVEMENTS` (its measure and weights)."""
    cb = fitted("fluents", "euclidean").case_base_
    keep = np.flatnonzero(np.isin(cb.labels.astype(str), MOVEMENTS))
    return _subset(cb, keep)


def _subset(cb: CaseBase, keep: np.ndarray) -> CaseBase:
    return replace(cb, problems=cb.problems[keep], labels=cb.labels[keep],
                   sources=tuple(cb.sources[i] for i in keep), ids=None, subjects=(), origins=(),
                   frames=(), skeletons=(), poses=(), reps=None, _index=None, cache={})  # fmt: skip


def _query(cb: CaseBase, i: int) -> tuple[CaseBase, np.ndarray, str]:
    """Case ``i``'s problem, the case base without its clip's cases, and the other label."""
    rest = np.flatnonzero(np.asarray(cb.sources) != cb.sources[i])
    other = next(m for m in MOVEMENTS if m != str(cb.labels[i]))
    return _subset(cb, rest), np.array(cb.problems[i]), other


@pytest.mark.parametrize("i", [7, 21, 91])  # searches of one to three steps: cheap to check
def test_the_fast_counterfactual_search_finds_what_the_plain_search_finds(
    two_movements: CaseBase, i: int
) -> None:
    cb, q, label = _query(two_movements, i)
    fast = cfm._Vectors(cb, view_of(cb), q, K, "distance", False)
    guides, _ = cfm._nearest(cb, q, label, 3)
    found = [fast.search(g, label) for g in guides]
    assert found == [_plain(cb, q, g, label) for g in guides]
    assert any(f is not None for f in found)  # a search that finds nothing proves little


def test_each_step_of_the_counterfactual_search_votes_once(
    two_movements: CaseBase, monkeypatch: pytest.MonkeyPatch
) -> None:
    cb, q, label = _query(two_movements, 21)
    fast = cfm._Vectors(cb, view_of(cb), q, K, "distance", False)
    (guide,), _ = cfm._nearest(cb, q, label, 1)
    calls: list[int] = []
    vote = cfm.vote

    def counted(d: np.ndarray, *args: object) -> np.ndarray:
        calls.append(len(d))
        return vote(d, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(cfm, "vote", counted)
    found = fast.search(guide, label)
    assert found is not None and len(found) >= 2  # two steps at least
    steps = [n for n in calls if n > 1]  # a step's vote: every candidate of every kept set
    assert len(steps) <= cfm.MAX_CHANGES
    # then one vote per change tried away (a winner of s changes: at most s)
    assert len(calls) - len(steps) <= len(steps)


def _hipless_s06(uiprmd: tuple) -> list[tuple[Any, str]]:
    """s06's episode 1 of shoulder abduction, extension and scaption (correct and incorrect)
    with the hips and everything below them missing in every frame, as a close-up leaves
    them, and their labels."""
    from features.skeleton import JOINT_INDEX

    below = [i for n, i in JOINT_INDEX.items()
             if n.split("_", 1)[-1] in {"hip", "knee", "ankle", "heel", "foot_index"}]  # fmt: skip
    _, _, Xte, yte = uiprmd
    arms = ("m07", "m08", "m10")
    names = [Path(x.source).name for x in Xte]
    picked = [(x, y) for x, y, n in zip(Xte, yte, names, strict=True)
              if n[:3] in arms and "_s06_e01_" in n]  # fmt: skip
    assert len(picked) == 6  # three movements, correct and incorrect
    hipless = []
    for x, y in picked:
        c = x.to_canonical()
        p = c.positions.copy()
        p[:, below] = np.nan
        hipless.append((replace(c, positions=p), y))
    return hipless


def test_arm_exercises_with_the_hips_out_of_view_are_classified(
    uiprmd: tuple, fitted: Callable[[str, str], Any]
) -> None:
    """A held-out subject's shoulder abduction, extension and scaption (s06, episode 1,
    correct and incorrect) with the hips and everything below them missing in every frame, as
    a close-up leaves them, against the case base of s01-s05's whole-body clips: each is
    classified as its movement, from its arms (in the frame of its shoulders and the world's
    up), and the answer says it was judged on the arms alone. On main's code each was refused
    ("shows no torso"). Measured over s06-s08's odd episodes (90 clips): 78 right without the
    hips, 83 with them (docs/measurements.md, hunt 53g)."""
    picked = _hipless_s06(uiprmd)
    hipless = [x for x, _ in picked]
    solved = fitted(*SHARED).solve(hipless)
    assert [s.solution.label for s in solved] == [y for _, y in picked]
    assert all(s.arms_alone and s.torso_share == 0.0 for s in solved)
    from cbr.explain import ARMS_ALONE, _head  # the answer's first line

    assert ARMS_ALONE in _head(solved[0], "x", True)


def test_the_counterfactual_of_a_clip_without_hips_changes_only_what_it_shows(
    uiprmd: tuple, fitted: Callable[[str, str], Any]
) -> None:
    """The counterfactual of a clip that never shows its hips or legs changes only what it
    shows (its arms): "had your legs moved so" tells the person filmed above the waist
    nothing, and the changed clip is checked the way the clip itself is classified, its
    never-shown columns left out (hunt 53a). On main's code (hunt 53g) the incorrect
    abduction's counterfactual changed its left leg's fill ("left leg bent steady"), and
    s03's abduction against s01-s02's case base read "torso twist steady not seen -> mean
    confidence 1.00; left leg height steady not seen -> 1.00"."""
    clf = fitted(*SHARED)
    clips = [x for x, _ in _hipless_s06(uiprmd)]
    for x, solved in zip(clips, clf.solve(clips), strict=True):
        unseen = solved.problem.unseen
        assert any(n.startswith(("left_leg", "torso")) for n in unseen)  # the test's premise
        contrast = clf.explain_solved(solved).contrast
        assert contrast is not None and contrast.changes, x.source
        changed = {c.column.split("@", 1)[0] for c in contrast.changes}
        assert not changed & unseen, (x.source, sorted(changed & unseen))
        assert contrast.valid, x.source
