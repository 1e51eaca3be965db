"""Segmenting long recordings, against a 1-NN DTW window classifier in the same run.

Run: ``python -m benchmarks.segment [--no-videos] [--repeats N] [--cases windows|repetitions]``
(about 2-3 minutes; one core: BLAS, OpenMP and numba threads pinned to 1). Writes
``benchmarks/results/segment.json`` (``segment-repetitions.json`` with ``--cases
repetitions``).

Data: the three CMU recordings of subject 13 in ``cmu-mocap6`` (120 fps, per-0.1-s labels),
leave one recording out: a case base of the labelled stretches of two recordings cut into
windows (``train --split windows``: 2-s windows every 0.5 s, feature weights none) or into
their repetitions (``--cases repetitions``: ``train --split repetitions``, default
classifier), the third segmented. ALL THREE RECORDINGS ARE ONE PERSON: the figures overstate
what other people get. Every threshold is learned from the case base (the two training
recordings), never from the recording segmented.

Measured, per test recording and overall:
- block accuracy: share of 0.1-s blocks given their labelled exercise (every exercise of a test
  recording is in the other two, so all are "seen"; a block called unknown counts as wrong);
- unknown: each exercise of the test recording in turn is left out of the case base; the share
  of its blocks labelled unknown (1-NN DTW has no unknown: 0 by construction), for each way
  of judging unknown (:data:`cbr.unknown.JUDGES`: spread-margin, the default,
  activity-margin, margin, held-out, activities, margin-distance; and the margin at the equal-error
  point, to compare);
- boundaries: for every labelled change of exercise, the distance to the nearest segment
  boundary (seconds), median;
- repetitions: counts of :func:`features.repetitions.count_repetitions` against the hand
  counts of ``tests/fixtures/repetition_counts.json`` (mocap stretches cut at the labels, and
  the videos through BlazePose): mean absolute error and off-by-one accuracy;
- speed: segmentation after feature extraction (the recording's fluents, state signals and
  the joint angles repetitions are counted on computed first and timed apart), in times real
  time on one core, by the process's CPU time (what one core spends, whatever else the shared
  machine runs) and by the wall clock; the baseline's classification time likewise (its
  angles are computed beforehand). The median of ``--repeats`` rounds, each round timing every
  recording's segmentation and the baseline once in turn (a slow spell of a shared machine
  falls on all alike).

Baseline: tslearn's DTW 1-NN on 2-s windows of the eight limb joint angles (elbows, knees,
armpits, hips) at 30 Hz; training windows every 0.5 s of the training recordings labelled by
the block at their centre; a test window centred on every block.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
from benchmarks._common import one_thread_machine, versions  # noqa: E402
from cbr.judges import JUDGES as UNKNOWN_JUDGES  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results" / "segment.json"
CASES = ("windows", "repetitions")
FIXTURE = ROOT / "tests" / "fixtures" / "repetition_counts.json"
RECORDINGS = ("13_29", "13_30", "13_31")
# the label codes as the dataset's README lists them
CODES = dict(enumerate(("JumpJack Jog Squat KneeRaise ArmCircle Twist SideReach Box UpDown "
                        "ToeTouchOneHand SideBend ToeTouchTwoHands").split(), start=1))  # fmt: skip
LIMB_ANGLES = tuple(
    f"{s}_{j}" for j in ("elbow", "knee", "armpit", "hip") for s in ("left", "right")
)
DTW_FPS, DTW_WINDOW_S, DTW_TRAIN_HOP_S = 30.0, 2.0, 0.5


@dataclass
class Recording:
    name: str
    seq: Any  # PoseSequence
    blocks: np.ndarray  # (n_blocks,) exercise names, one per 0.1 s


def load_recordings() -> dict[str, Recording]:
    from cbr.evaluation.segments import truth_blocks
    from cbr.segmentation import BLOCK_S
    from features.label_tracks import frame_labels, read_label_track
    from features.readers.asfamc import read_asf_amc

    names = {str(k): v for k, v in CODES.items()}
    asf = DATA / "hdm05" / "train" / "3" / "HDM_bd.asf"
    out = {}
    for name in RECORDINGS:
        seq = read_asf_amc(asf, DATA / "cmu-mocap6" / "amc" / f"{name}.amc")
        labels = read_label_track(DATA / "cmu-mocap6" / "truelabels" / f"{name}.txt", names)
        per_frame = frame_labels(labels, seq.n_frames, seq.fps, 0.1, name)
        out[name] = Recording(name, seq, truth_blocks(per_frame, seq.fps, BLOCK_S))
    return out


def training_clips(
    recs: list[Recording], leave_out: str | None = None, cases: str = CASES[0]
) -> list[Any]:
    """The labelled stretches of ``recs`` cut into windows or repetitions (``train --split``)."""
    from features.clips import Clip
    from features.derived import stretch
    from features.label_tracks import labelled_stretches
    from features.repetitions import split_repetitions, split_windows

    clips = []
    for r in recs:
        per_frame = np.repeat(r.blocks, int(round(0.1 * r.seq.fps)))[: r.seq.n_frames]
        for a, b, label in labelled_stretches(per_frame):
            if label != leave_out:
                part = stretch(r.seq, a, b).with_metadata(label=label, subject="13")
                clips.append(Clip(part, label, "13", {}))
    split = split_windows if cases == "windows" else split_repetitions
    return split(clips).clips


def fit(clips: list[Any], cases: str = CASES[0]) -> Any:
    """The classifier ``posecbr train --split CASES`` makes (windows: feature weights none)."""
    from cbr.estimator import CaseBaseClassifier

    params = {"feature_weights": "none"} if cases == "windows" else {}
    return CaseBaseClassifier(**params).fit([c.seq for c in clips], [c.label for c in clips])


def _timed_in_rounds(
    calls: dict[tuple[str, str], Callable[[], Any]], repeats: int
) -> dict[tuple[str, str], tuple[float, float]]:
    """Median wall-clock and CPU seconds of every call over ``repeats`` rounds, each round
    calling each once in turn: a spell of a shared machine running slow then falls on every
    call alike, not on the few repeats of one. The CPU time of this one-threaded process is
    what one core spends, whatever else the machine runs."""
    wall: dict[tuple[str, str], list[float]] = {key: [] for key in calls}
    cpu: dict[tuple[str, str], list[float]] = {key: [] for key in calls}
    for _ in range(repeats):
        for key, fn in calls.items():
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall[key].append(time.perf_counter() - t0)
            cpu[key].append(time.process_time() - c0)
    return {key: (statistics.median(wall[key]), statistics.median(cpu[key])) for key in calls}


JUDGES = (*UNKNOWN_JUDGES, "margin-equal-error")
"""How "unknown" is judged (cbr.unknown.JUDGES, the default first): SpreadMargin (ActivityMargin's
margin times the nearest distance in the nearest activity's own spread; with a case base of
one person, as CMU subject 13's, ActivityMargin itself), ActivityMargin (the margin
between the two nearest activities against the nearest activity's own threshold, from its
rightly named held-out cases, shrunk to the pooled one by a weight chosen on the case base,
cbr.unknown.choose_weight), the margin against one threshold (exceeded by 5 % of held-out known
cases of the case base), the classifier's
stored calibration (the 99th percentile of held-out training clips' nearest-case distances,
cbr.novelty), Familiarity (a stretch as far from its nearest cases as the case base's
activities lie from each other), or MarginDistance (the margin alone, or a smaller margin with
a far nearest case, sharing the 5 %); and, for comparison, the margin at the point where
held-out known and novel cases err equally (the default before the false-unknown budget)."""


def judge_named(clf: Any, name: str) -> Any:
    from cbr.unknown import judge_of
    from cbr.unknown_judges import Margin
    from cbr.unknown_thresholds import calibration_margins, equal_error_threshold

    if name == "margin-equal-error":
        known, novel, basis = calibration_margins(clf.case_base_)
        return Margin(equal_error_threshold(known, novel), basis, len(known), len(novel))
    return judge_of(clf, name)


def bench_ours(
    recs: dict[str, Recording], test: str, cases: str
) -> tuple[dict[str, Any], Callable[[], Any]]:
    """The figures of segmenting ``test`` with a case base of the other recordings, by every
    judge, and the call to time (the default judge's segmentation)."""
    from cbr.evaluation.segments import score_segmentation
    from cbr.problem import warm
    from cbr.segmentation import BLOCK_S, segment
    from features.derived import movement_signals_of

    train = [recs[n] for n in RECORDINGS if n != test]
    rec = recs[test]
    clf = fit(training_clips(train, cases=cases), cases)
    t0 = time.perf_counter()
    warm(rec.seq, clf.feature_config_.level, mirror=clf.feature_config_.side == "canonical")
    movement_signals_of(rec.seq)
    extraction_s = time.perf_counter() - t0
    out: dict[str, Any] = {"cases": len(clf.case_base_), "feature_extraction_s": extraction_s}
    for name in JUDGES:
        judge = judge_named(clf, name)
        result = segment(clf, rec.seq, judge)
        # scored as `posecbr segment --truth` scores: every exercise of the test recording is
        # in the other two, so every block is of a label the case base has
        scores = score_segmentation(result, rec.blocks, clf.classes_, BLOCK_S)
        fps = rec.seq.fps
        out[name] = {
            "blocks": scores.blocks,
            "block_accuracy": scores.seen_accuracy,
            "blocks_called_unknown": scores.called_unknown / scores.blocks,
            "boundary_errors_s": list(scores.boundary_errors_s),
            "segments": [s.to_dict(fps) for s in result.segments],
            "windows": result.windows,
        }
    judge = judge_named(clf, JUDGES[0])  # calibrated once per case base, not per recording
    out["blocks"] = len(rec.blocks)
    return out, lambda: segment(clf, rec.seq, judge)


def bench_unknown(recs: dict[str, Recording], test: str, cases: str) -> dict[str, dict[str, float]]:
    """Each exercise of ``test`` left out of the case base in turn: share of its blocks called
    unknown, per judge."""
    from cbr.evaluation.segments import score_segmentation
    from cbr.segmentation import BLOCK_S, finish, solve_recording

    train = [recs[n] for n in RECORDINGS if n != test]
    rec = recs[test]
    out: dict[str, dict[str, float]] = {name: {} for name in JUDGES}
    for exercise in sorted(set(rec.blocks)):
        clf = fit(training_clips(train, leave_out=exercise, cases=cases), cases)
        done = solve_recording(clf, rec.seq)  # solved once, finished by every judge
        for name in JUDGES:
            result = finish(clf, done, judge_named(clf, name))
            # the left-out exercise's blocks are those of the label the case base lacks
            scores = score_segmentation(result, rec.blocks, clf.classes_, BLOCK_S)
            share = scores.unseen_called_unknown
            assert scores.unseen_labels == (str(exercise),) and share is not None
            out[name][str(exercise)] = share
    return out


def _angles(seq: Any) -> np.ndarray:
    """The eight limb angles at about DTW_FPS, gaps interpolated: ``(n, 8)``."""
    from cbr.problem import fill_nan_time
    from features.derived import signals_of

    sig = signals_of(seq)
    step = max(1, int(round(seq.fps / DTW_FPS)))
    values = sig.values[:, [sig.names.index(n) for n in LIMB_ANGLES]]
    return np.asarray(fill_nan_time(values, 0.0)[::step])


def _windows(angles: np.ndarray, centres: np.ndarray) -> np.ndarray:
    width = int(DTW_WINDOW_S * DTW_FPS)
    starts = np.clip((centres - width // 2).astype(int), 0, len(angles) - width)
    return np.stack([angles[s : s + width] for s in starts])


def bench_dtw(recs: dict[str, Recording], test: str) -> tuple[dict[str, Any], Callable[[], Any]]:
    """The baseline's block accuracy on ``test`` and the call to time (its classification)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # tslearn warns that optional h5py is missing
        from tslearn.metrics import cdist_dtw

    X, y = [], []
    for name in RECORDINGS:
        if name == test:
            continue
        r = recs[name]
        a = _angles(r.seq)
        centres_s = np.arange(
            DTW_WINDOW_S / 2, r.seq.duration_s - DTW_WINDOW_S / 2, DTW_TRAIN_HOP_S
        )
        X.append(_windows(a, centres_s * DTW_FPS))
        y.append(r.blocks[np.minimum((centres_s / 0.1).astype(int), len(r.blocks) - 1)])
    X_train, y_train = np.concatenate(X), np.concatenate(y)
    rec = recs[test]
    angles = _angles(rec.seq)
    centres = (np.arange(len(rec.blocks)) + 0.5) * 0.1 * DTW_FPS

    def classify() -> np.ndarray:
        d = cdist_dtw(_windows(angles, centres), X_train)
        return np.asarray(y_train[np.argmin(d, axis=1)])

    pred = classify()
    return {
        "training_windows": len(X_train),
        "block_accuracy": float(np.mean(pred == rec.blocks)),
    }, classify


def bench_repetitions(
    with_videos: bool, others: dict[str, Callable[[Any], int]] | None = None
) -> dict[str, Any]:
    """:func:`features.repetitions.count_repetitions` (``counted``) and any ``others``
    (name: count of a PoseSequence) against the hand counts of FIXTURE: every clip's counts,
    and MAE, off-by-one accuracy and exact share for mocap, videos and all (of ``others``
    under their names)."""
    from features.clips import load_clip
    from features.readers.asfamc import read_asf_amc
    from features.repetitions import count_repetitions

    methods: dict[str, Callable[[Any], int]] = {
        "counted": lambda seq: count_repetitions(seq).count,
        **(others or {}),
    }
    clips = json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
    cache: dict[str, Any] = {}
    rows = []
    for c in clips:
        video = not c["source"].endswith(".amc")
        if video and not with_videos:
            continue
        if c["source"] not in cache:
            path = DATA / c["source"]
            cache[c["source"]] = load_clip(path) if video else read_asf_amc(DATA / c["asf"], path)
        seq = cache[c["source"]]
        if not video:
            seq = seq.slice_frames(c["start_frame"], c["end_frame"])
        row = {"source": c["source"], "activity": c.get("activity"), "hand": c["count"]}
        rows.append({**row, **{k: m(seq) for k, m in methods.items()}, "video": video})
    out: dict[str, Any] = {"clips": rows}
    for part, keep in (("mocap", False), ("videos", True), ("all", None)):
        mine = [r for r in rows if keep is None or r["video"] == keep]
        if mine:
            out[part] = _count_scores(mine, "counted")
            out[part].update({k: _count_scores(mine, k) for k in others or {}})
    return out


def _count_scores(rows: list[dict[str, Any]], key: str) -> dict[str, Any]:
    err = np.array([abs(r[key] - r["hand"]) for r in rows])
    return {
        "clips": len(err),
        "mae": float(err.mean()),
        "obo": float((err <= 1).mean()),
        "exact": float((err == 0).mean()),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.segment", description=__doc__)
    parser.add_argument(
        "--repeats", type=int, default=9, help="timing rounds (median; each times every call)"
    )
    parser.add_argument("--no-videos", action="store_true", help="skip the videos (BlazePose)")
    parser.add_argument(
        "--cases", choices=CASES, default=CASES[0], help="how the training stretches are cut"
    )
    args = parser.parse_args(argv)
    results = RESULTS if args.cases == CASES[0] else RESULTS.with_name(f"segment-{args.cases}.json")
    if not (DATA / "cmu-mocap6").is_dir():
        print(f"no cmu-mocap6 data under {DATA}: nothing to measure")
        return 1
    import numba

    numba.set_num_threads(1)
    load_at_start = [round(x, 2) for x in os.getloadavg()]
    recs = load_recordings()
    folds: dict[str, Any] = {}
    calls: dict[tuple[str, str], Callable[[], Any]] = {}
    for test in RECORDINGS:
        ours, calls[(test, "ours")] = bench_ours(recs, test, args.cases)
        dtw, calls[(test, "dtw")] = bench_dtw(recs, test)
        unknown = bench_unknown(recs, test, args.cases)
        folds[test] = {"ours": ours, "dtw": dtw, "unknown_share_when_left_out": unknown}
        for name in JUDGES:
            o = ours[name]
            print(
                f"test {test}, unknown by {name}: ours {o['block_accuracy']:.1%} "
                f"(unknown {o['blocks_called_unknown']:.1%}), DTW {dtw['block_accuracy']:.1%};"
                " left out and called unknown: "
                + ", ".join(f"{k} {v:.0%}" for k, v in unknown[name].items()),
                flush=True,
            )
    for (test, who), (seconds, cpu) in _timed_in_rounds(calls, args.repeats).items():
        duration = recs[test].seq.duration_s
        folds[test][who].update({
            "segmentation_s" if who == "ours" else "classification_s": seconds,
            "segmentation_cpu_s" if who == "ours" else "classification_cpu_s": cpu,
            "x_real_time": duration / seconds,
            "x_real_time_cpu": duration / cpu,
        })  # fmt: skip
    reps = bench_repetitions(not args.no_videos)
    summary = _summary(folds, recs)
    _print_table(summary, reps, args.cases)
    result = {
        "benchmark": "segment",
        "command": f"python -m benchmarks.segment --repeats {args.repeats} --cases {args.cases}"
        + (" --no-videos" if args.no_videos else ""),
        "note": "all three recordings are one person (CMU subject 13): the figures overstate "
        "what other people get",
        "cases": args.cases,
        "machine": one_thread_machine(),
        "load_average_at_start": load_at_start,
        "versions": versions(
            "posecbr",
            "numpy",
            "scipy",
            "scikit-learn",
            "tslearn",
            "numba",
            "opencv-python-headless",
        ),
        "repeats": args.repeats,
        "summary": summary,
        "folds": folds,
        "repetitions": reps,
    }
    write_json(result, results)
    print(f"\nwrote {results.relative_to(ROOT)}")
    return 0


def _summary(folds: dict[str, Any], recs: dict[str, Recording]) -> dict[str, Any]:
    n_blocks = sum(f["ours"]["blocks"] for f in folds.values())

    def pooled(values: list[tuple[float, int]]) -> float:
        return sum(v * n for v, n in values) / sum(n for _, n in values)

    out: dict[str, Any] = {
        "dtw_1nn": {
            "block_accuracy": sum(
                f["dtw"]["block_accuracy"] * f["ours"]["blocks"] for f in folds.values()
            )
            / n_blocks,  # fmt: skip
            "x_real_time_median": statistics.median(
                f["dtw"]["x_real_time"] for f in folds.values()
            ),
            "x_real_time_cpu_median": statistics.median(
                f["dtw"]["x_real_time_cpu"] for f in folds.values()
            ),
        },
        "x_real_time_median": statistics.median(f["ours"]["x_real_time"] for f in folds.values()),
        "x_real_time_cpu_median": statistics.median(
            f["ours"]["x_real_time_cpu"] for f in folds.values()
        ),
    }
    for name in JUDGES:
        left_out = [
            (share, int(np.sum(recs[test].blocks == exercise)))
            for test, f in folds.items()
            for exercise, share in f["unknown_share_when_left_out"][name].items()
        ]
        errors = [e for f in folds.values() for e in f["ours"][name]["boundary_errors_s"]]
        out[name] = {
            "block_accuracy": pooled(
                [(f["ours"][name]["block_accuracy"], f["ours"]["blocks"]) for f in folds.values()]
            ),
            "blocks_called_unknown_when_exercise_left_out": pooled(left_out),
            "median_boundary_error_s": float(np.median(errors)),
        }
    return out


def _print_table(summary: dict[str, Any], reps: dict[str, Any], cases: str) -> None:
    s = summary
    print(
        f"\nSegmenting CMU subject 13, leave one recording out, a case base of {cases}"
        " (ONE PERSON: optimistic)"
    )
    head = "".join(f"{n:>22s}" for n in JUDGES)  # the names fit; "unknown by " + name did not
    print(f"  {'unknown judged by':48s}{head}{'DTW 1-NN':>10s}")
    rows = (
        ("block accuracy, exercises in the case base", "block_accuracy", "{:22.1%}"),
        ("left-out exercise's blocks called unknown",
         "blocks_called_unknown_when_exercise_left_out", "{:22.1%}"),
        ("median boundary error (s)", "median_boundary_error_s", "{:22.2f}"),
    )  # fmt: skip
    for text, key, fmt in rows:
        cells = "".join(fmt.format(s[n][key]) for n in JUDGES)
        dtw = (
            f"{s['dtw_1nn']['block_accuracy']:10.1%}"
            if key == "block_accuracy"
            else (f"{0.0:10.1%}" if "unknown" in key else "")
        )
        print(f"  {text:48s}{cells}{dtw}")
    gap = " " * 22 * (len(JUDGES) - 1)
    print(f"  {'x real time by CPU time, one core, after features':48s}"
          f"{s['x_real_time_cpu_median']:22.0f}{gap}"
          f"{s['dtw_1nn']['x_real_time_cpu_median']:10.0f}")  # fmt: skip
    print(f"  {'x real time by wall clock (load: see the JSON)':48s}"
          f"{s['x_real_time_median']:22.0f}{gap}"
          f"{s['dtw_1nn']['x_real_time_median']:10.0f}")  # fmt: skip
    for part in ("mocap", "videos", "all"):
        if part in reps:
            r = reps[part]
            print(f"  repetitions, {part:6s} ({r['clips']} clips): MAE {r['mae']:.2f}, "
                  f"off-by-one {r['obo']:.0%}, exact {r['exact']:.0%}")  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
