"""Correct vs incorrect, per repetition, in a held-out person's session: the physiotherapist's
workflow of issue 14, against tslearn's DTW 1-NN in the same run.

Run: ``python -m benchmarks.repetition_verdicts [--quick] [--all-movements] [--seed S]``
(``--quick``: two movements, deep squat and shoulder abduction, three held-out people;
written to ``repetition_verdicts_quick.json``; ``--all-movements``: one case base per
held-out person of every movement, as ``train --target correct`` without ``--labels``
makes it, written to ``repetition_verdicts_all_movements.json``). Writes
``benchmarks/results/repetition_verdicts.json`` (about 18 minutes at load 12 on 2 cores).

UI-PRMD Kinect (30 Hz; 8 people, 10 movements, 10 correct and 10 incorrect repetitions each;
its Vicon repetitions are all correct, so there is nothing to tell apart there), leave one
person out, one case base per movement as the README's repetition check trains it
(``posecbr train DATA --labels MOVEMENT --target correct``: the other seven people's
repetitions, a case per clip, the vote class-balanced). The held-out person's session is
made, as ``benchmarks.segment_people`` makes its recordings, from their own 20 repetitions of
the movement in a random order, joined (:func:`features.joining.join_repetitions`: each
turned and moved to stand where the one before ended, 0.1 s of blending between): the
verdict of every repetition is known exactly.

Each session is judged as the command does it (``posecbr classify SESSION --split
repetitions``): cut into the repetitions ``posecbr reps`` counts
(:func:`cbr.training.cut`), each classified and explained alone. A true repetition's verdict
is that of the piece overlapping it most; one no piece covers by half is missed (counted
wrong). Figures per method:

- ``cut``: per-repetition accuracy on the pieces found (missed repetitions wrong), its
  balanced accuracy (the mean of the two recalls; always answering one verdict scores 50 %);
- ``true``: the same case base on the session cut at the true joins, which is what
  ``compare --target correct`` measures per clip: the cost of cutting is the difference;
- the share of repetitions found, and of sessions counted exactly;
- the explanations: of the pieces judged incorrect, the share whose explanation names what
  was done differently from the correct repetitions (a feature outside their range, the
  ``Done differently from correct repetitions:`` line), and the mean number named.

Baseline: tslearn's DTW 1-NN on the eight limb angles resampled to 64 frames
(:class:`cbr.evaluation.peers.DTWKNNPeer`, ``compare``'s peer), trained on the same clips and
given the same pieces.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
import zlib  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import json_out, write_json  # noqa: E402
from benchmarks._common import one_thread_machine, versions  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results" / "repetition_verdicts.json"
QUICK_MOVEMENTS = ("deep_squat", "standing_shoulder_abduction")
QUICK_PEOPLE = ("s01", "s05", "s08")
MIN_COVER = 0.5
"""A true repetition is found when one piece covers at least this share of its frames."""
VERDICTS = ("correct", "incorrect")


def session(
    clips: list[Any], rng: np.random.Generator, name: str
) -> tuple[Any, list[tuple[int, int]], list[str]]:
    """The held-out person's ``clips`` (one movement) in a random order, joined: the
    recording, each repetition's frames ``[start, end)`` and its verdict."""
    from features.joining import join_repetitions
    from features.targets import clip_target

    order = [clips[int(i)] for i in rng.permutation(len(clips))]
    joined = join_repetitions([c.seq for c in order])
    spans = [(int(s), int(s) + c.seq.n_frames) for s, c in zip(joined.starts, order, strict=True)]
    seq = replace(joined.seq, source=name)
    return seq, spans, [str(clip_target(c, "correct")) for c in order]


def matched(spans: list[tuple[int, int]], pieces: list[tuple[int, int]]) -> list[int | None]:
    """For each true repetition, the piece overlapping it most (its index), None when no
    piece covers :data:`MIN_COVER` of it."""
    out: list[int | None] = []
    for a, b in spans:
        cover = [max(0, min(b, d) - max(a, c)) for c, d in pieces]
        best = int(np.argmax(cover)) if cover else -1
        out.append(best if best >= 0 and cover[best] >= MIN_COVER * (b - a) else None)
    return out


def scores(truth: list[str], answers: list[str | None]) -> dict[str, Any]:
    """Accuracy (with its Wilson 95 % interval) and balanced accuracy over the true
    repetitions (None: missed, wrong)."""
    from cbr.evaluation.stats import wilson_interval

    t = np.asarray(truth, dtype=object)
    a = np.asarray(answers, dtype=object)
    right = t == a
    recall = [float(np.mean(right[t == v])) for v in VERDICTS if np.any(t == v)]
    return {
        "accuracy": float(np.mean(right)),
        "wilson_95": list(wilson_interval(int(right.sum()), len(right))),
        "balanced_accuracy": float(np.mean(recall)),
    }


def mcnemar(truth: list[str], ours: list[str | None], other: list[str | None]) -> dict[str, Any]:
    """Exact McNemar's test of two methods' answers to the same repetitions: how many only
    ours got right, only the other, and the two-sided p-value."""
    from cbr.evaluation.stats import mcnemar_exact

    a = [t == x for t, x in zip(truth, ours, strict=True)]
    b = [t == x for t, x in zip(truth, other, strict=True)]
    only_ours = sum(x and not y for x, y in zip(a, b, strict=True))
    only_other = sum(y and not x for x, y in zip(a, b, strict=True))
    return {
        "only_ours": only_ours,
        "only_other": only_other,
        "p": mcnemar_exact(only_ours, only_other),
    }


def fitted(train: list[Any]) -> tuple[Any, Any, float]:
    """The case base (as ``train --target correct`` fits it) and the DTW peer, fitted on the
    ``train`` clips' verdicts, and the case base's fit time (s)."""
    from cbr.estimator import CaseBaseClassifier
    from cbr.evaluation.peers import DTWKNNPeer
    from features.targets import clip_target

    y = [str(clip_target(c, "correct")) for c in train]
    start = time.perf_counter()
    ours = CaseBaseClassifier(class_weight="balanced").fit([c.seq for c in train], y)
    fit_s = time.perf_counter() - start
    return ours, DTWKNNPeer().fit([c.seq for c in train], y), fit_s


def one_fold(
    movement: str,
    person: str,
    mine: list[Any],
    models: tuple[Any, Any, float],
    seed: int,
    explain: bool,
) -> dict[str, Any]:
    """``person``'s session of ``movement`` (``mine``: their repetitions of it) judged by the
    ``models`` (:func:`fitted` on other people's repetitions)."""
    from cbr.training import cut

    ours, peer, fit_s = models
    rng = np.random.default_rng([seed, zlib.crc32(f"{movement}/{person}".encode())])
    rec, spans, truth = session(mine, rng, f"{person}-{movement}")
    cut_seqs, _ = cut([rec], None, "repetitions")
    pieces = [(int(s.metadata.get("frame_offset", 0)), 0) for s in cut_seqs]
    pieces = [(a, a + s.n_frames) for (a, _), s in zip(pieces, cut_seqs, strict=True)]
    true_seqs = [rec.slice_frames(a, b) for a, b in spans]
    found = matched(spans, pieces)
    row: dict[str, Any] = {
        "movement": movement,
        "person": person,
        "repetitions": len(spans),
        "pieces": len(pieces),
        "found": int(sum(f is not None for f in found)),
        "fit_s": round(fit_s, 1),
        "truth": truth,
    }
    start = time.perf_counter()
    for method, model in (("ours", ours), ("dtw_1nn", peer)):
        on_pieces = [str(v) for v in model.predict(cut_seqs)] if cut_seqs else []
        on_true = [str(v) for v in model.predict(true_seqs)]
        row[method] = {
            "cut": scores(truth, [None if f is None else on_pieces[f] for f in found]),
            "true": scores(truth, on_true),
            "answers_cut": [None if f is None else on_pieces[f] for f in found],
            "answers_true": on_true,
        }
    row["predict_s"] = round(time.perf_counter() - start, 1)
    if explain and cut_seqs:
        said = []
        for e in ours.explain(cut_seqs, target="correct"):
            if e.label == "incorrect":
                said.append(sum(c.part == "outside" for c in e.claims))
        row["explained_incorrect"] = said
    return row


def summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Pooled over every session: each method's per-repetition accuracy and balanced accuracy
    (cut and true), the repetitions found, the sessions counted exactly, the explanations."""
    out: dict[str, Any] = {
        "sessions": len(rows),
        "repetitions": int(sum(r["repetitions"] for r in rows)),
        "found": float(sum(r["found"] for r in rows) / sum(r["repetitions"] for r in rows)),
        "counted_exactly": float(np.mean([r["pieces"] == r["repetitions"] for r in rows])),
    }
    truth = [t for r in rows for t in r["truth"]]
    for method in ("ours", "dtw_1nn"):
        out[method] = {
            how: scores(truth, [a for r in rows for a in r[method][f"answers_{how}"]])
            for how in ("cut", "true")
        }
    out["mcnemar_cut"] = mcnemar(
        truth,
        [a for r in rows for a in r["ours"]["answers_cut"]],
        [a for r in rows for a in r["dtw_1nn"]["answers_cut"]],
    )
    said = [n for r in rows for n in r.get("explained_incorrect", [])]
    if said:
        out["incorrect_explained"] = {
            "pieces": len(said),
            "naming_what_differed": float(np.mean([n > 0 for n in said])),
            "mean_named": float(np.mean(said)),
        }
    movements = sorted({r["movement"] for r in rows})
    out["per_movement"] = {
        m: {
            method: scores(
                [t for r in rows if r["movement"] == m for t in r["truth"]],
                [a for r in rows if r["movement"] == m for a in r[method]["answers_cut"]],
            )["balanced_accuracy"]
            for method in ("ours", "dtw_1nn")
        }
        for m in movements
    }
    return out


def print_table(s: dict[str, Any]) -> None:
    print(
        f"\n{s['sessions']} sessions, {s['repetitions']} repetitions; found "
        f"{100 * s['found']:.1f} %, sessions counted exactly {100 * s['counted_exactly']:.1f} %"
    )
    print("| method | cut by reps: accuracy [95 %] | balanced | true cuts: accuracy | balanced |")
    print("|---|---:|---:|---:|---:|")
    for method in ("ours", "dtw_1nn"):
        m = s[method]
        lo, hi = m["cut"]["wilson_95"]
        print(
            f"| {method} | {100 * m['cut']['accuracy']:.1f} % [{100 * lo:.1f}, {100 * hi:.1f}] |"
            f" {100 * m['cut']['balanced_accuracy']:.1f} % |"
            f" {100 * m['true']['accuracy']:.1f} % | {100 * m['true']['balanced_accuracy']:.1f} % |"
        )
    mc = s["mcnemar_cut"]
    print(
        f"McNemar (cut): only ours right {mc['only_ours']}, only dtw_1nn {mc['only_other']},"
        f" p = {mc['p']:.2g}"
    )
    print("\n| movement | ours (balanced, cut) | dtw_1nn |")
    print("|---|---:|---:|")
    for movement, v in s["per_movement"].items():
        print(f"| {movement} | {100 * v['ours']:.1f} % | {100 * v['dtw_1nn']:.1f} % |")
    if "incorrect_explained" in s:
        e = s["incorrect_explained"]
        print(
            f"\njudged incorrect: {e['pieces']} pieces; the explanation names what differed from"
            f" the correct repetitions in {100 * e['naming_what_differed']:.1f} % (mean"
            f" {e['mean_named']:.2f} features)"
        )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m benchmarks.repetition_verdicts",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--quick", action="store_true", help="two movements, three people")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-explain", action="store_true", help="skip the explanations' count")
    p.add_argument(
        "--all-movements",
        action="store_true",
        help="one case base of every movement per held-out person (train --target correct "
        "without --labels), not one per movement; written to repetition_verdicts_all_movements"
        "[_quick].json",
    )
    p.add_argument("--out", type=json_out, default=None)
    args = p.parse_args(argv)
    from features.datasets import load_dataset

    start = time.perf_counter()
    clips = load_dataset(DATA / "ui-prmd", sensor="kinect", progress_desc="ui-prmd kinect")
    movements = QUICK_MOVEMENTS if args.quick else tuple(sorted({c.label for c in clips}))
    people = sorted({str(c.subject) for c in clips})
    if args.quick:
        people = [s for s in people if s in QUICK_PEOPLE]
    rows = []

    def judge(movement: str, person: str, models: tuple[Any, Any, float]) -> None:
        mine = [c for c in clips if c.label == movement and c.subject == person]
        row = one_fold(movement, person, mine, models, args.seed, not args.no_explain)
        rows.append(row)
        print(
            f"{movement:45} {person}: {row['pieces']:2d} pieces of {row['repetitions']};"
            f" ours {100 * row['ours']['cut']['accuracy']:.0f} %"
            f" (true cuts {100 * row['ours']['true']['accuracy']:.0f} %),"
            f" dtw {100 * row['dtw_1nn']['cut']['accuracy']:.0f} %",
            flush=True,
        )

    if args.all_movements:  # one case base per held-out person, of every movement
        for person in people:
            models = fitted([c for c in clips if c.subject != person])
            for movement in movements:
                judge(movement, person, models)
    else:  # one per movement and held-out person, as the README trains it
        for movement in movements:
            for person in people:
                judge(movement, person, fitted(
                    [c for c in clips if c.label == movement and c.subject != person]
                ))  # fmt: skip
    s = summary(rows)
    print_table(s)
    stem = RESULTS.stem + ("_all_movements" if args.all_movements else "")
    out = args.out or RESULTS.with_name(f"{stem}{'_quick' if args.quick else ''}.json")
    doc = {
        "benchmark": "repetition_verdicts",
        "command": "python -m benchmarks.repetition_verdicts"
        + (" --quick" if args.quick else "")
        + (" --all-movements" if args.all_movements else ""),
        "machine": one_thread_machine(),
        "versions": versions("numpy", "scipy", "tslearn", "scikit-learn"),
        "protocol": {
            "dataset": "ui-prmd kinect",
            "movements": list(movements),
            "held_out_people": people,
            "seed": args.seed,
            "min_cover": MIN_COVER,
            "case_base": "every movement" if args.all_movements else "one per movement",
        },
        "summary": s,
        "rows": rows,
        "seconds": round(time.perf_counter() - start, 1),
    }
    write_json(doc, out)
    print(f"\nwritten to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
