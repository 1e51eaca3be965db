"""Correct vs incorrect repetitions of new people, per movement, with and without class-balanced
voting (``CaseBaseClassifier(class_weight=...)``).

UI-PRMD Kinect (``../shared/data/ui-prmd``; its incorrect Vicon repetitions are not staged, so
correctness is measured on Kinect alone): one case base per movement trained on subjects
s01-s05 with the ``correct`` column as its target, every repetition of s06-s08 (held-out
people, 10 correct and 10 incorrect each: 60 per movement) classified. Two training mixes:

- ``all``: every repetition of the training subjects (10 correct, 10 incorrect each);
- ``few incorrect``: every correct repetition but only episodes 1-2 of the incorrect ones
  (50 correct against 10 incorrect cases), the way a physiotherapist's recordings lean.

Each fitted case base answers twice, its vote class-balanced (each class's votes divided by
its share of the cases: what ``train --target`` and ``compare --target`` use for a column other
than the activity) and not (``class_weight="none"``, the vote before): the cases, feature
weights and side handling are the same, only the vote differs. Figures:
balanced accuracy (the mean of the two recalls; the commonest-class rate of the held-out
repetitions is 50 %), and the share of answers "correct" (an all-"correct" case base shows
100 %), per movement and configuration (fluents under euclidean, dtw and signature; QMPs
under euclidean).

The activity check: HDM05 actions (9-36 clips each, so a balanced vote can move them),
leave-one-actor-out accuracy of every configuration, balanced against not (activities keep the
plain vote; UI-PRMD's movements have equal counts, where the two votes are the same).

Prints the tables and writes ``benchmarks/results/correctness.json`` with machine and versions.

    python -m benchmarks.correctness    # about 15 min on 2 cores (907 s at load 16-17)
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import no_options, write_json

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = Path(__file__).resolve().parent / "results" / "correctness.json"

TRAIN = ("s01", "s02", "s03", "s04", "s05")
CONFIGS = (
    ("fluents", "euclidean"),
    ("fluents", "dtw"),
    ("fluents", "signature"),
    ("qmp", "euclidean"),
)
#: incorrect episodes kept in the "few incorrect" mix (of 10)
FEW_INCORRECT = 2
VOTES = ("balanced", "none")


def scores(truth: np.ndarray, answers: np.ndarray) -> dict[str, float]:
    """Balanced accuracy, accuracy, each class's recall and the share answered "correct"."""
    recall = {c: float(np.mean(answers[truth == c] == c)) for c in ("correct", "incorrect")}
    return {
        "balanced_accuracy": float(np.mean(list(recall.values()))),
        "accuracy": float(np.mean(answers == truth)),
        "recall_correct": recall["correct"],
        "recall_incorrect": recall["incorrect"],
        "share_answered_correct": float(np.mean(answers == "correct")),
        "commonest_class_rate": float(max(np.mean(truth == c) for c in ("correct", "incorrect"))),
    }


def correctness_rows() -> list[dict[str, Any]]:
    """One row per configuration, training mix, movement and vote."""
    from cbr.estimator import CaseBaseClassifier
    from features.datasets import load_dataset
    from features.targets import clip_target

    clips = load_dataset(SHARED / "ui-prmd", sensor="kinect", progress_desc="ui-prmd kinect")
    rows = []
    for features, similarity in CONFIGS:
        for movement in sorted({c.label for c in clips}):
            mine = [c for c in clips if c.label == movement]
            test = [c for c in mine if c.subject not in TRAIN]
            truth = np.array([clip_target(c, "correct") for c in test], dtype=object)
            for mix in ("all", "few incorrect"):
                train = [
                    c
                    for c in mine
                    if c.subject in TRAIN
                    and (
                        mix == "all"
                        or clip_target(c, "correct") == "correct"
                        or int(c.extras["episode"]) <= FEW_INCORRECT
                    )
                ]
                y = [clip_target(c, "correct") for c in train]
                start = time.perf_counter()
                clf = CaseBaseClassifier(features=features, similarity=similarity)
                clf.fit([c.seq for c in train], y)
                fit_s = time.perf_counter() - start
                for vote in VOTES:
                    clf.set_params(class_weight=vote)
                    answers = np.asarray(clf.predict([c.seq for c in test])).astype(object)
                    row = {
                        "configuration": f"{features}/{similarity}",
                        "movement": movement,
                        "mix": mix,
                        "vote": vote,
                        "train_correct": int(sum(v == "correct" for v in y)),
                        "train_incorrect": int(sum(v == "incorrect" for v in y)),
                        "test": len(test),
                        "fit_s": round(fit_s, 1),
                        **scores(truth, answers),
                    }
                    rows.append(row)
                    print(
                        f"{row['configuration']:18} {movement:45} {mix:13} {vote:8}"
                        f" BA {row['balanced_accuracy']:.3f}"
                        f" answered correct {row['share_answered_correct']:.2f}",
                        flush=True,
                    )
    return rows


def activity_rows() -> list[dict[str, Any]]:
    """HDM05 leave-one-actor-out activity accuracy of every configuration, balanced and not."""
    from cbr.evaluation.compare import run_compare
    from cbr.evaluation.settings import CompareSettings
    from features.datasets import load_dataset

    rows = []
    clips = load_dataset(SHARED / "hdm05", progress_desc="hdm05")
    for vote in VOTES:
        settings = CompareSettings(
            dad=False, peers=(), cbr_params={"class_weight": vote}, explain=0
        )
        start = time.perf_counter()
        results = run_compare(clips, settings).results
        seconds = round(time.perf_counter() - start, 1)
        for method in results.methods:
            if method.scores is None:
                continue
            rows.append(
                {
                    "task": "hdm05 action",
                    "configuration": method.name,
                    "vote": vote,
                    "clips": len(clips),
                    "accuracy": float(method.scores.accuracy),
                    "correct": [bool(v) for v in method.scores.correct],
                    "seconds": seconds,
                }
            )
            print(f"hdm05 {method.name:24} {vote:8} accuracy {method.scores.accuracy:.4f}")
    return rows


def summary(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Mean balanced accuracy and the movements answered "correct" 90 % of the time or more,
    per configuration, mix and vote."""
    out = []
    keys = sorted({(r["configuration"], r["mix"], r["vote"]) for r in rows})
    for conf, mix, vote in keys:
        mine = [r for r in rows if (r["configuration"], r["mix"], r["vote"]) == (conf, mix, vote)]
        out.append(
            {
                "configuration": conf,
                "mix": mix,
                "vote": vote,
                "mean_balanced_accuracy": float(np.mean([r["balanced_accuracy"] for r in mine])),
                "movements_answered_correct_90": [
                    r["movement"] for r in mine if r["share_answered_correct"] >= 0.9
                ],
            }
        )
    return out


def print_tables(rows: list[dict[str, Any]], means: list[dict[str, Any]]) -> None:
    print("\nbalanced accuracy per movement (held-out s06-s08; commonest class 50 %)")
    confs = sorted({r["configuration"] for r in rows})
    for mix in ("all", "few incorrect"):
        print(f"\ntraining mix: {mix}; each cell balanced / none")
        print("| movement | " + " | ".join(confs) + " |")
        print("|---|" + "---:|" * len(confs))
        for movement in sorted({r["movement"] for r in rows}):
            cells = []
            for conf in confs:
                got = {
                    r["vote"]: r["balanced_accuracy"]
                    for r in rows
                    if (r["configuration"], r["mix"], r["movement"]) == (conf, mix, movement)
                }
                cells.append(f"{100 * got['balanced']:.1f} / {100 * got['none']:.1f} %")
            print(f"| {movement} | " + " | ".join(cells) + " |")
    print("\n| configuration | mix | vote | mean balanced accuracy | answered 'correct' >= 90 % |")
    print("|---|---|---|---:|---|")
    for m in means:
        print(
            f"| {m['configuration']} | {m['mix']} | {m['vote']} |"
            f" {100 * m['mean_balanced_accuracy']:.1f} % |"
            f" {', '.join(m['movements_answered_correct_90']) or '-'} |"
        )


def main(argv: list[str] | None = None) -> int:
    no_options("correctness", __doc__, argv)
    from cbr.evaluation.machine import machine_info

    start = time.perf_counter()
    rows = correctness_rows()
    means = summary(rows)
    print_tables(rows, means)
    activity = activity_rows()
    doc = {
        "benchmark": "correctness",
        "machine": machine_info(),
        "protocol": {
            "dataset": str(SHARED / "ui-prmd"),
            "sensor": "kinect",
            "train_subjects": list(TRAIN),
            "test_subjects": ["s06", "s07", "s08"],
            "few_incorrect_episodes": FEW_INCORRECT,
        },
        "summary": means,
        "rows": rows,
        "activity": activity,
        "seconds": round(time.perf_counter() - start, 1),
        "load_average": list(os.getloadavg()),
    }
    write_json(doc, RESULTS)
    print(f"\nwritten to {RESULTS}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
