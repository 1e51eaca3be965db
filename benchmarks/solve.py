"""Classifying many clips at once: one batched retrieval against one retrieval per clip.

Run: ``python -m benchmarks.solve [--grow 100000] [--explain 40]``

The case base: the default classifier (fluents, Euclidean, k = 5) trained on the UI-PRMD
Kinect clips of subjects s01-s06; the queries: every clip of s07-s08 (people it has never
seen). Then the same classifier with its case base grown to ``--grow`` cases (the real cases
resampled with replacement and jittered, sd 0.05, clipped to [0, 1]), the size where a search
costs. Methods, in rounds with the order rotated (medians):

- ``solve_batched``: ``CaseBaseClassifier.solve(all clips)``: one ``nearest_many`` call;
- ``solve_per_clip``: ``solve([clip])`` for each clip (the retrieval ``solve`` did before);
- ``classify_batched`` / ``classify_per_clip``: what ``posecbr classify`` does after loading
  (``cbr.classification.classify_clips``, solve and explanation in words) on the first
  ``--explain`` clips, batched as now and one solve per clip as before.

Both sides compute every clip's features; the difference is the retrieval. The answers are
checked identical (neighbours and labels). One thread (BLAS and numba), the load recorded.
Writes ``benchmarks/results/solve.json``.
"""

from __future__ import annotations

from benchmarks import _common as C  # first: pins the thread pools before numpy loads

# isort: split
import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from types import SimpleNamespace  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import json_out, write_json  # noqa: E402

RESULTS = C.RESULTS / "solve.json"


def grown(clf: Any, n: int) -> Any:
    """A copy of the fitted ``clf`` whose case base holds ``n`` jittered resampled cases."""
    import copy

    from cbr.casebase import CaseBase

    cb = clf.case_base_
    rng = np.random.default_rng(0)
    pick = rng.integers(0, len(cb), n)
    problems = C.grow(np.asarray(cb.problems), n, rng, 0.05, (0.0, 1.0))
    big = copy.copy(clf)
    big.case_base_ = CaseBase(cb.config, cb.measure, problems, cb.labels[pick], cb.names, cb.words)
    return big


def timed(methods: dict[str, Callable[[], Any]], rounds: int) -> dict[str, float]:
    """Median seconds of each method over ``rounds``, the order rotated each round."""
    names = list(methods)
    times: dict[str, list[float]] = {n: [] for n in names}
    for r in range(rounds):
        for s in range(len(names)):
            name = names[(r + s) % len(names)]
            t0 = time.perf_counter()
            methods[name]()
            times[name].append(time.perf_counter() - t0)
    return {n: statistics.median(t) for n, t in times.items()}


def same_answers(a: list[Any], b: list[Any]) -> bool:
    """Whether two lists of ``Solved`` have the same neighbours, distances and labels."""
    return all(
        np.array_equal(x.retrieval.indices, y.retrieval.indices)
        and np.array_equal(x.retrieval.distances, y.retrieval.distances)
        and x.solution.label == y.solution.label
        for x, y in zip(a, b, strict=True)
    )


def run_one(label: str, clf: Any, queries: list[Any], n_explain: int, rounds: int) -> dict:
    """Batched against per-clip solve (and classify) with ``clf``: seconds and the check."""
    from cbr.classification import _solve, classify_clips

    stored = SimpleNamespace(classifier=clf)
    few = queries[:n_explain]
    clf.solve(queries[:2])  # the index is built once, outside the timings
    methods: dict[str, Callable[[], Any]] = {
        "solve_batched": lambda: clf.solve(queries),
        "solve_per_clip": lambda: [clf.solve([q])[0] for q in queries],
    }
    if n_explain:
        methods["classify_batched"] = lambda: classify_clips(stored, few, [None] * len(few))
        methods["classify_per_clip"] = lambda: [_solve(stored, q, None, "label") for q in few]  # type: ignore[arg-type]
    load_before = C.load()
    secs = timed(methods, rounds)
    identical = same_answers(clf.solve(queries), [clf.solve([q])[0] for q in queries])
    return {
        "case_base": label,
        "cases": len(clf.case_base_),
        "dims": int(np.prod(clf.case_base_.problems.shape[1:])),
        "clips": len(queries),
        "explained_clips": len(few),
        "seconds": {k: round(v, 3) for k, v in secs.items()},
        "identical_answers": identical,
        "load_avg": [load_before, C.load()],
    }


def print_row(r: dict[str, Any]) -> None:
    s = r["seconds"]
    cb, cl = s.get("classify_batched", float("nan")), s.get("classify_per_clip", float("nan"))
    print(
        f"{r['case_base']:<22} {r['cases']:>7} {r['dims']:>5} {r['clips']:>5} "
        f"{s['solve_per_clip']:>9.2f} {s['solve_batched']:>9.2f} "
        f"{s['solve_per_clip'] / s['solve_batched']:>6.1f}x {cl:>9.2f} {cb:>9.2f} "
        f"{str(r['identical_answers']):>5} {r['load_avg'][0]:>5.2f}",
        flush=True,
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grow", type=int, default=100000, help="cases of the grown case base")
    ap.add_argument("--explain", type=int, default=40, help="clips classified with words")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", type=json_out, default=RESULTS)
    args = ap.parse_args(argv)
    threads = C.pin_one_thread()
    from cbr.estimator import CaseBaseClassifier

    clips = C.uiprmd_clips()
    case, query = C.subject_split(clips)
    train = [c for c, m in zip(clips, case, strict=True) if m]
    queries = [c.seq for c, m in zip(clips, query, strict=True) if m]
    started = time.perf_counter()
    clf = CaseBaseClassifier(k=5).fit([c.seq for c in train], [c.label for c in train])
    print(
        f"{'case base':<22} {'cases':>7} {'dims':>5} {'clips':>5} {'per clip':>9} "
        f"{'batched':>9} {'ratio':>7} {'cls/clip':>9} {'cls batch':>9} {'same':>5} {'load':>5}"
        "   (seconds for all clips, one thread)"
    )
    rows = [run_one("UI-PRMD s01-s06", clf, queries, args.explain, args.rounds)]
    print_row(rows[-1])
    if args.grow:
        big = grown(clf, args.grow)
        rows.append(run_one("grown + jitter 0.05", big, queries, args.explain, args.rounds))
        print_row(rows[-1])
    doc = {
        "benchmark": "solve",
        "command": "python -m benchmarks.solve " + " ".join(argv or sys.argv[1:]),
        "what": "seconds to solve (and classify with explanations) the s07-s08 UI-PRMD clips: "
        "one batched retrieval against one retrieval per clip (medians of rounds)",
        "threads": threads,
        "versions": C.versions("numpy", "numba", "scikit-learn"),
        "results": rows,
        "seconds": round(time.perf_counter() - started, 1),
    }
    write_json(doc, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
