"""One fitted model: what `posecbr train` stores is the classifier `CaseBaseClassifier.fit`
learns in Python, and loading it back answers exactly as that classifier does."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from cbr.estimator import CaseBaseClassifier
from cbr.retrieve import retrieve
from cbr.stored import load_classifier
from features.datasets import load_dataset
from posecbr.cli import main
from tests.test_feedback_safety import trained  # noqa: F401 (a fixture)

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd" / "labels.csv"
QMP_LABELS = ("deep_squat", "inline_lunge", "standing_shoulder_abduction", "sit_to_stand")


# on one xdist worker: the module's demo_split made once, not once per worker
pytestmark = pytest.mark.xdist_group("stored_model")


@pytest.fixture(scope="module")
def demo_split() -> tuple[list, list, list]:
    train = load_dataset(DEMO, subjects={"s01", "s02"})
    test = load_dataset(DEMO, subjects={"s03"})
    return [c.seq for c in train], [c.label for c in train], [c.seq for c in test]


@pytest.mark.parametrize(
    ("argv", "params"),
    [
        ([], {}),  # the default: clip summaries under euclidean, side and weights by inner LOSO
        (["--similarity", "dtw", "-k", "3"], {"similarity": "dtw", "k": 3}),
        # QMPs fit SINDy models to every clip, twice here: four movements' clips will do
        (
            ["--features", "qmp", "--trim", "0.6", "--labels", ",".join(QMP_LABELS)],
            {"features": "qmp", "trim": 0.6},
        ),
    ],
)
def test_train_and_python_fit_give_identical_answers(
    demo_split: tuple[list, list, list],
    tmp_path: Path,
    argv: list[str],
    params: dict[str, object],
    request: pytest.FixtureRequest,
) -> None:
    X, y, X_test = demo_split
    if "--labels" in argv:
        X, y = zip(*[(x, v) for x, v in zip(X, y, strict=True) if v in QMP_LABELS], strict=True)
    if argv:
        db = tmp_path / "cb.sqlite"
        assert main(["train", str(DEMO), "--db", str(db), "--subjects", "s01,s02", *argv]) == 0
    else:  # this command made tests/test_feedback_safety.py's case base (once a session)
        db = tmp_path / "cb.sqlite"
        db.write_bytes(request.getfixturevalue("trained").read_bytes())
    store = open_store(db, readonly=True)
    try:
        stored = load_classifier(store, "default").classifier
    finally:
        store.close()
    fitted = CaseBaseClassifier(**params).fit(X, y)  # type: ignore[arg-type]
    assert stored.get_params() == fitted.get_params()
    assert (stored.side_, stored.weighting_, stored.phases_) == (
        fitted.side_,
        fitted.weighting_,
        fitted.phases_,
    )
    assert stored.selection_ == fitted.selection_
    assert len(stored.case_base_) == len(fitted.case_base_)
    np.testing.assert_array_equal(stored.case_base_.problems, fitted.case_base_.problems)
    assert stored.novelty_ == fitted.novelty_
    assert stored.confidence_ == fitted.confidence_
    np.testing.assert_array_equal(stored.predict(X_test), fitted.predict(X_test))
    np.testing.assert_array_equal(stored.predict_proba(X_test), fitted.predict_proba(X_test))
    a, b = stored.solve(X_test[:3]), fitted.solve(X_test[:3])
    for s, f in zip(a, b, strict=True):
        assert s.novelty == f.novelty and s.unlike_cases == f.unlike_cases
        assert s.solution.confidence == f.solution.confidence
        np.testing.assert_array_equal(s.retrieval.distances, f.retrieval.distances)
        # the same explanation, counterfactual included (case ids aside: only stored cases
        # have them)
        es, ef = stored.explain_solved(s), fitted.explain_solved(f)
        assert [c.to_dict() for c in es.claims] == [c.to_dict() for c in ef.claims]


def test_a_stored_classifier_keeps_its_k_and_vote(tmp_path: Path) -> None:
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(DEMO), "--db", str(db), "--subjects", "s01,s02", "-k", "1"]
    assert main(argv) == 0
    store = open_store(db, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    assert clf.k == 1 and clf.weights == "distance"
    # k = 1: every retrieval holds exactly one case and the vote is that case's label
    X = [c.seq for c in load_dataset(DEMO, subjects={"s03"}, labels={"deep_squat"})]
    for s in clf.solve(X):
        assert len(s.retrieval.indices) == 1
        assert s.solution.label == s.retrieval.labels[0] and s.solution.vote_share == 1.0
        # the confidence is the stored curve at the answer's soft vote over the 10 nearest
        # cases (each weighing exp(-(d / d_1)^2 / T)), worked out here from the retrieval
        cal = clf.confidence_
        assert cal.neighbours == 10 and cal.temperature > 0
        near = retrieve(clf.case_base_, s.problem, cal.neighbours)
        w = np.exp(-((near.distances / max(near.distances[0], 1e-12)) ** 2) / cal.temperature)
        soft = w[near.labels == s.solution.label].sum() / w.sum()
        assert s.solution.confidence == pytest.approx(float(np.interp(soft, cal.x, cal.y)))
