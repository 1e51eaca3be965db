"""How far can any classifier go on UI-PRMD correct-versus-incorrect across unseen subjects?

``posecbr compare --target correct`` reaches about 82 % with the case base (goal: 90 %). This
benchmark asks whether the gap is the method's or the data's: the same clip features the case
base uses (angle and fluent summaries and joint positions in the person's own frame, canonical
side; :class:`cbr.problem.FeatureConfig`) go to well-tuned off-the-shelf classifiers from
scikit-learn, one model per movement, on the same leave-one-subject-out folds:

- ``1-NN fisher``: 1-nearest neighbour with Fisher-ratio weights (the case base's retrieval);
- ``logistic``: L2 logistic regression (C = 0.1) on standardised features;
- ``boosting``: histogram gradient boosting (200 trees, learning rate 0.05);
- ``svm-rbf``: RBF support-vector machine (C = 0.3) on standardised features.

Two reference protocols bound the problem from above (neither is something a user can deploy on
a new person's first clips):

- ``within-subject``: logistic regression with 5-fold stratified CV inside each subject and
  movement: no new person at test time;
- ``person-centred (transductive)``: every person's features minus that person's mean over all
  their clips of the movement, test person included. It uses the test person's whole batch and
  assumes the batch mixes correct and incorrect repetitions.

Prints the accuracy (Wilson 95 % interval) and per movement for each, and writes
``benchmarks/results/ceiling.json`` with machine and versions.

    python -m benchmarks.ceiling        # about 4 min on 2 cores (260 s at load 1-5, 2026-12-04)
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import no_options, write_json

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = Path(__file__).resolve().parent / "results" / "ceiling.json"
COMPARE = RESULTS.with_name("compare.json")


class FisherNN:
    """1-NN under the case base's feature weights (:func:`cbr.weights.learn_weights`, fisher)."""

    def fit(self, X: np.ndarray, y: np.ndarray) -> FisherNN:
        from sklearn.neighbors import KNeighborsClassifier

        from cbr.weights import learn_weights

        self.weights = learn_weights(X, y)
        self.knn = KNeighborsClassifier(1).fit(self.weights.apply(X), y)
        return self

    def predict(self, X: np.ndarray) -> np.ndarray:
        return self.knn.predict(self.weights.apply(X))


def classifiers() -> dict[str, Callable[[], Any]]:
    from sklearn.ensemble import HistGradientBoostingClassifier
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    return {
        "1-NN fisher": FisherNN,
        "logistic": lambda: make_pipeline(
            StandardScaler(), LogisticRegression(C=0.1, max_iter=5000)
        ),
        "boosting": lambda: HistGradientBoostingClassifier(
            max_iter=200, learning_rate=0.05, random_state=0
        ),
        "svm-rbf": lambda: make_pipeline(StandardScaler(), SVC(C=0.3)),
    }


def features(clips: list[Any]) -> tuple[np.ndarray, list[str]]:
    """The case base's clip summaries (no phase means), every clip, as one matrix."""
    from cbr.problem import FeatureConfig, extract_problem, resolve_config

    config = FeatureConfig(angles=True, positions=True, summary=True, phases=0, side="canonical")
    config = resolve_config(config, [c.seq for c in clips])
    rows = [extract_problem(c.seq, config) for c in clips]
    X = np.stack([r.values for r in rows]).astype(np.float64)
    return np.nan_to_num(X, nan=0.0), list(rows[0].names)


def loso(
    X: np.ndarray, y: np.ndarray, movement: np.ndarray, subject: np.ndarray, make: Callable
) -> np.ndarray:
    """Correct (bool) per clip: one model per movement, leave one subject out."""
    correct = np.zeros(len(y), dtype=bool)
    for m in np.unique(movement):
        idx = np.flatnonzero(movement == m)
        for s in np.unique(subject[idx]):
            test, train = idx[subject[idx] == s], idx[subject[idx] != s]
            model = make().fit(X[train], y[train])
            correct[test] = model.predict(X[test]) == y[test]
    return correct


def within_subject(
    X: np.ndarray, y: np.ndarray, movement: np.ndarray, subject: np.ndarray, make: Callable
) -> np.ndarray:
    """Correct per clip: 5-fold stratified CV inside each subject and movement."""
    from sklearn.model_selection import StratifiedKFold

    correct = np.zeros(len(y), dtype=bool)
    for m in np.unique(movement):
        for s in np.unique(subject):
            idx = np.flatnonzero((movement == m) & (subject == s))
            folds = StratifiedKFold(5, shuffle=True, random_state=0)
            for train, test in folds.split(X[idx], y[idx]):
                model = make().fit(X[idx[train]], y[idx[train]])
                correct[idx[test]] = model.predict(X[idx[test]]) == y[idx[test]]
    return correct


def person_centred(X: np.ndarray, movement: np.ndarray, subject: np.ndarray) -> np.ndarray:
    """Every clip's features minus its person's mean over their clips of the same movement."""
    out = X.copy()
    for m in np.unique(movement):
        for s in np.unique(subject):
            idx = (movement == m) & (subject == s)
            out[idx] -= X[idx].mean(axis=0)
    return out


def summary(correct: np.ndarray, movement: np.ndarray, names: dict[str, str]) -> dict[str, Any]:
    from cbr.evaluation.stats import wilson_interval

    n, k = len(correct), int(correct.sum())
    return {
        "accuracy": k / n,
        "accuracy_ci": list(wilson_interval(k, n)),
        "per_movement": {
            names.get(m, m): float(correct[movement == m].mean()) for m in np.unique(movement)
        },
    }


def main(argv: list[str] | None = None) -> int:
    no_options("ceiling", __doc__, argv)
    os.environ.setdefault("POSECBR_NO_PROGRESS", "1")
    warnings.filterwarnings("ignore", category=RuntimeWarning)
    from cbr.evaluation.machine import machine_info
    from features.datasets import load_dataset

    path = SHARED / "ui-prmd"
    if not path.exists():
        print(f"skipped: {path} is not on this machine")
        return 0
    t0 = time.perf_counter()
    clips = load_dataset(path)
    X, names = features(clips)
    t_features = time.perf_counter() - t0
    y = np.array([int(bool(c.extras["correct"])) for c in clips])
    movement = np.array([str(c.extras["movement"]) for c in clips])
    subject = np.array([str(c.subject) for c in clips])
    label_of = {str(c.extras["movement"]): str(c.label) for c in clips}

    makers = classifiers()
    rows: list[tuple[str, str, np.ndarray]] = []
    for name, make in makers.items():
        rows.append((name, "leave one subject out", loso(X, y, movement, subject, make)))
    logistic = makers["logistic"]
    rows.append(("logistic", "within-subject", within_subject(X, y, movement, subject, logistic)))
    centred = person_centred(X, movement, subject)
    rows.append(
        ("logistic", "person-centred (transductive)", loso(centred, y, movement, subject, logistic))
    )
    rows.append(
        (
            "1-NN fisher",
            "person-centred (transductive)",
            loso(centred, y, movement, subject, FisherNN),
        )
    )

    results = []
    for name, protocol, correct in rows:
        results.append(
            {"classifier": name, "protocol": protocol, **summary(correct, movement, label_of)}
        )
    case_base = None
    if COMPARE.exists():
        task = json.loads(COMPARE.read_text()).get("tasks", {}).get("ui-prmd correct", {})
        best = task.get("best_interpretable")
        for m in task.get("methods", []):
            if m.get("name") == best:
                case_base = {"method": best, "accuracy": m.get("accuracy")}

    movements = sorted(label_of)
    short = [label_of[m].replace("standing_", "").replace("shoulder_", "")[:10] for m in movements]
    print(
        f"UI-PRMD correct vs incorrect, {len(clips)} clips, {len(names)} features "
        f"({t_features:.0f} s to load and describe)"
    )
    print(
        f"{'classifier':12s} {'protocol':31s} {'acc %':>6s} {'95 % CI':>12s}  "
        + " ".join(f"{s:>10s}" for s in short)
    )
    for r in results:
        lo, hi = r["accuracy_ci"]
        per = " ".join(f"{100 * r['per_movement'][label_of[m]]:10.1f}" for m in movements)
        print(
            f"{r['classifier']:12s} {r['protocol']:31s} {100 * r['accuracy']:6.1f} "
            f"[{100 * lo:4.1f},{100 * hi:5.1f}]  {per}"
        )
    if case_base:
        print(
            f"case base ({case_base['method']}, posecbr compare): "
            f"{100 * case_base['accuracy']:.1f} %"
        )
    out = {
        "benchmark": "ceiling",
        "task": "ui-prmd correct vs incorrect, one model per movement",
        "n_clips": len(clips),
        "n_features": len(names),
        "features_s": round(t_features, 1),
        "results": results,
        "case_base": case_base,
        "machine": machine_info(("scikit-learn",)),
    }
    write_json(out, RESULTS)
    print(f"written {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
