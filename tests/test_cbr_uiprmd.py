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
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
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
