"""Segmenting long recordings of people NOT in the case base, against a 1-NN DTW window
classifier in the same run.

Run: ``python -m benchmarks.segment_people [--datasets ...] [--per-person N] [--seed S]
[--train-people N [--rotate]] [--mirror SIDE] [--feature-weights fisher]``
(``--train-people 1``: case bases of one person, as one of CMU subject 13 alone, the first
training person's; written to
``segment_people_1.json``; ``--rotate``: each training person's in turn, every recording
segmented by each, pooled, ``segment_people_1_rotate.json``; ``--mirror``: their side
handling, as ``train --mirror``, written to ``segment_people[_N]_SIDE.json``;
``--feature-weights fisher``: Fisher-weighted case bases, as ``train --split windows
--feature-weights fisher``, written to ``segment_people[...]_fisher.json``)
(about 19 minutes of wall clock at load 6-10 on 2 cores, most of it the DTW baseline and
the case bases of UI-PRMD Kinect; each window is solved once and finished by every judge;
one core: BLAS, OpenMP and numba threads pinned to 1; ``--datasets hdm05`` alone takes about
a minute). Writes ``benchmarks/results/segment_people.json``.

There is no long recording of several exercises from anyone but CMU subject 13, so the
recordings are made, with labels known exactly, from other people's real single
repetitions (:func:`features.joining.join_repetitions`): a sequence of 3-4 different
movements of one held-out person, K of their repetitions of each (K drawn from 3-6, at most
as many as they recorded), each repetition turned and moved along the floor to stand where
the previous one ended, the jump between two rest postures bridged by 0.1 s of linear
blending. The joins (0.1 s, straight from one rest posture to the next) and the rest at
each repetition's ends differ from a real session: no walking to a new place, no pause,
no drifting from one exercise into the next.

- UI-PRMD Vicon (about 100 Hz) and Kinect (30 Hz; correct and incorrect repetitions, one
  label per movement), ten movements: case base from subjects s01-s04 (the subjects
  ``benchmarks.repetitions`` lets the method's choices look at), recordings of s05-s08;
- HDM05 (120 Hz), seven movements done in single repetitions (squat, elbow to knee, front
  kick, arm circles backward, hop, deposit on the floor, grab high): case base from two
  actors, recordings of the third, each actor in turn.

The case base is the one ``posecbr train --split windows`` makes (the split the README
recommends for segmenting: 2-s windows every 0.5 s, feature weights none) from each
training person's repetitions of a movement joined into one clip (joined as the test
recordings are, in the order of the files: the windows across two repetitions are among the
cases, as they are among the queries). Every threshold is learned from the case base.

Measured per dataset, as ``benchmarks.segment`` measures CMU subject 13:
- block accuracy: the share of 0.1-s blocks given their labelled movement (every movement
  in the case base; a block called unknown counts as wrong); a block's label is that of the
  frame at its centre;
- unknown: each movement left out of the case base in turn, the recordings that contain it
  segmented; the share of its blocks called unknown, per judge (:data:`cbr.unknown.JUDGES`);
- boundaries: for every labelled change of movement, the distance to the nearest segment
  boundary (seconds), median.

Baseline: tslearn's DTW 1-NN on 2-s windows of the eight limb joint angles at 30 Hz
(``benchmarks.segment``'s): training windows every 0.5 s of the same joined training clips,
labelled by their clip; a test window centred on every block.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from collections import defaultdict  # noqa: E402
from collections.abc import Iterator  # noqa: E402
from dataclasses import dataclass, replace  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
from benchmarks._common import one_thread_machine, versions  # noqa: E402
from benchmarks.repetitions import (  # noqa: E402
    HDM05,
    HDM05_ACTIONS,
    TRAIN_SUBJECTS,
    UIPRMD,
    Group,
    hdm05_groups,
    read_one,
    uiprmd_groups,
)
from benchmarks.segment import DTW_FPS, DTW_TRAIN_HOP_S, DTW_WINDOW_S, JUDGES, judge_named  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "segment_people.json"
DATASETS = ("ui-prmd-vicon", "ui-prmd-kinect", "hdm05")
HDM05_MOVEMENTS = (*HDM05_ACTIONS, "depositFloorR", "grabHighR")
"""HDM05 actions each clip of which is one repetition that starts and ends standing."""
HDM05_ACTORS = ("bd", "bk", "dg")
K_RANGE = (3, 6)
MOVEMENTS_RANGE = (3, 4)
BLOCK_S = 0.1


@dataclass(frozen=True)
class Recording:
    """A joined recording of one held-out person: the sequence, each 0.1-s block's movement
    ``(n_blocks,)`` and the movements in it, in order."""

    name: str
    person: str
    seq: Any  # PoseSequence
    blocks: np.ndarray
    movements: tuple[str, ...]
    max_jump_m: float


@dataclass(frozen=True)
class Fold:
    """One case base (the training people's groups) and the recordings segmented with it."""

    dataset: str
    name: str
    train: list[Group]
    recordings: list[Recording]


class Reader:
    """Reads each repetition file once."""

    def __init__(self) -> None:
        self.cache: dict[Path, Any] = {}

    def __call__(self, group: Group, path: Path) -> Any:
        if path not in self.cache:
            self.cache[path] = read_one(group, path).to_canonical()
        return self.cache[path]


def block_labels(frame_labels: np.ndarray, fps: float) -> np.ndarray:
    """The label of the frame at the centre of every 0.1-s block ``(n_blocks,)``, the blocks
    ``cbr.segmentation`` labels (``ceil(frames / (fps * 0.1))`` of them)."""
    n = len(frame_labels)
    n_blocks = int(np.ceil(n / (fps * BLOCK_S) - 1e-9))
    centres = np.minimum(((np.arange(n_blocks) + 0.5) * BLOCK_S * fps).astype(np.int64), n - 1)
    return np.asarray(frame_labels[centres])


def test_recordings(
    groups: list[Group], per_person: int, rng: np.random.Generator, read: Reader
) -> list[Recording]:
    """``per_person`` joined recordings of every person of ``groups``: 3-4 movements in a
    random order, K (3-6, at most as many as recorded) random repetitions of each."""
    by_person: dict[str, list[Group]] = defaultdict(list)
    for g in groups:
        by_person[g.person].append(g)
    out = []
    for person, mine in sorted(by_person.items()):
        for r in range(per_person):
            n_moves = int(rng.integers(MOVEMENTS_RANGE[0], MOVEMENTS_RANGE[1] + 1))
            chosen = [mine[int(i)] for i in rng.choice(len(mine), size=n_moves, replace=False)]
            out.append(joined_recording(f"{person}-{r + 1}", person, chosen, rng, read))
    return out


def joined_recording(
    name: str, person: str, chosen: list[Group], rng: np.random.Generator, read: Reader
) -> Recording:
    """The recording ``name`` of ``person``: K (3-6, at most as many as recorded) random
    repetitions of each movement of ``chosen`` in turn, joined
    (:func:`features.joining.join_repetitions`)."""
    from features.joining import join_repetitions

    reps, labels = [], []
    for g in chosen:
        k = min(int(rng.integers(K_RANGE[0], K_RANGE[1] + 1)), len(g.files))
        for i in rng.choice(len(g.files), size=k, replace=False):
            reps.append(read(g, g.files[int(i)]))
            labels.append(g.movement)
    joined = join_repetitions(reps, labels=labels)
    assert joined.labels is not None
    seq = replace(joined.seq, source=name)
    jump = float(joined.jumps_m.max()) if len(joined.jumps_m) else 0.0
    blocks = block_labels(joined.labels, seq.fps)
    return Recording(name, person, seq, blocks, tuple(g.movement for g in chosen), jump)


def folds(
    dataset: str,
    per_person: int,
    seed: int,
    read: Reader,
    train_people: int | None = None,
    rotate: bool = False,
) -> Iterator[Fold]:
    """The folds of ``dataset``: UI-PRMD one (s01-s04 train, s05-s08 test), HDM05 one per
    actor tested; ``train_people``: the case base of only the first that many training people
    (by name), as one trained on CMU subject 13 alone is; with ``rotate``, of every that many
    in turn (1: each training person alone), the same recordings segmented by each."""
    rng = np.random.default_rng(seed)
    if dataset == "hdm05":
        groups = hdm05_groups(HDM05_MOVEMENTS)
        for actor in HDM05_ACTORS:
            test = test_recordings([g for g in groups if g.person == actor], per_person, rng, read)
            for train in _people([g for g in groups if g.person != actor], train_people, rotate):
                yield Fold(dataset, f"test {actor}{_trained_on(train, rotate)}", train, test)
        return
    groups = uiprmd_groups(dataset.split("-")[-1].capitalize())
    test = test_recordings([g for g in groups if g.person not in TRAIN_SUBJECTS], per_person,
                           rng, read)  # fmt: skip
    for train in _people([g for g in groups if g.person in TRAIN_SUBJECTS], train_people, rotate):
        yield Fold(dataset, f"test s05-s08{_trained_on(train, rotate)}", train, test)


def _people(groups: list[Group], n: int | None, rotate: bool) -> Iterator[list[Group]]:
    """The ``groups`` of the first ``n`` people by name (all when ``n`` is None); with
    ``rotate``, of every ``n`` people by name in turn."""
    people = sorted({g.person for g in groups})
    if n is None:
        yield groups
        return
    for first in range(0, len(people) if rotate else 1, n):
        chosen = people[first : first + n]
        if len(chosen) == n:
            yield [g for g in groups if g.person in chosen]


def _trained_on(train: list[Group], rotate: bool) -> str:
    """A fold's name's ending when the case bases rotate: whose they are."""
    return f", trained on {'+'.join(sorted({g.person for g in train}))}" if rotate else ""


def joined_training(train: list[Group], read: Reader) -> list[tuple[Any, Group]]:
    """Each training person's repetitions of a movement joined into one clip, in the order of
    the files, with its group (made once per fold: what its frames yield is computed once)."""
    from features.joining import join_repetitions

    out = []
    for g in train:
        seq = join_repetitions([read(g, p) for p in g.files]).seq
        seq = replace(seq, source=f"{g.person}_{g.movement}")
        out.append((seq.with_metadata(label=g.movement, subject=g.person), g))
    return out


def training_clips(joined: list[tuple[Any, Group]], leave_out: str | None = None) -> list[Any]:
    """The joined training clips but ``leave_out``'s, cut into windows as ``train --split
    windows`` cuts."""
    from features.clips import Clip
    from features.repetitions import split_windows

    clips = [Clip(seq, g.movement, g.person, {}) for seq, g in joined if g.movement != leave_out]
    return split_windows(clips).clips


def fit(
    clips: list[Any], mirror: str = "auto", feature_weights: str = "none", **params: Any
) -> Any:
    """The classifier ``posecbr train --split windows [--mirror MIRROR]`` makes (feature
    weights none unless ``feature_weights``; further :class:`cbr.estimator.CaseBaseClassifier`
    ``params``, as ``velocity=True``)."""
    from cbr.estimator import CaseBaseClassifier

    return CaseBaseClassifier(feature_weights=feature_weights, mirror=mirror, **params).fit(
        [c.seq for c in clips], [c.label for c in clips]
    )


def _boundary_errors(truth: np.ndarray, starts_s: np.ndarray) -> list[float]:
    """For every labelled change of movement in ``truth`` (block labels), the distance in
    seconds to the nearest segment start ``starts_s`` (inf when there is none)."""
    true_b = (np.flatnonzero(truth[1:] != truth[:-1]) + 1) * BLOCK_S
    if not len(starts_s):
        return [float("inf")] * len(true_b)
    return [float(np.min(np.abs(starts_s - b))) for b in true_b]


def ours(clf: Any, rec: Recording, judges: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """One recording segmented with each judge: predicted blocks, accuracy, boundary errors,
    seconds. The windows are solved once (:func:`cbr.segmentation.solve_recording`) and
    finished by every judge (:func:`cbr.segmentation.finish`); each judge's time is the
    solving plus its own finishing."""
    from cbr.segmentation import finish, solve_recording

    t0, c0 = time.perf_counter(), time.process_time()
    done = solve_recording(clf, rec.seq)
    solve_s, solve_cpu = time.perf_counter() - t0, time.process_time() - c0
    out = {}
    for name, judge in judges.items():
        t0, c0 = time.perf_counter(), time.process_time()
        result = finish(clf, done, judge)
        seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
        pred = np.array(result.blocks[: len(rec.blocks)], dtype=object)
        truth = rec.blocks[: len(pred)]
        starts = np.array([s.start_frame / rec.seq.fps for s in result.segments[1:]])
        out[name] = {
            "pred": pred,
            "correct": int(np.sum(pred == truth)),
            "unknown": int(sum(p is None for p in pred)),
            "boundary_errors_s": _boundary_errors(truth, starts),
            "segments": [[s.start_frame, s.end_frame, s.label] for s in result.segments],
            "seconds": solve_s + seconds,
            "cpu_s": solve_cpu + cpu,
        }
    return out


def _angles(seq: Any) -> np.ndarray:
    from benchmarks.segment import _angles as angles

    return angles(seq)


def _windows(angles: np.ndarray, centres: np.ndarray) -> np.ndarray:
    from benchmarks.segment import _windows as windows

    return windows(angles, centres)


def dtw_training(clips_by_group: list[tuple[Any, str]]) -> tuple[np.ndarray, np.ndarray]:
    """2-s windows every 0.5 s of each joined training clip ``(seq, label)`` (a clip shorter
    than one window gives none), ``(n, 60, 8)`` and their labels ``(n,)``."""
    X, y = [], []
    width = int(DTW_WINDOW_S * DTW_FPS)
    for seq, label in clips_by_group:
        a = _angles(seq)
        if len(a) < width:
            continue
        centres_s = np.arange(DTW_WINDOW_S / 2, len(a) / DTW_FPS - DTW_WINDOW_S / 2 + 1e-9,
                              DTW_TRAIN_HOP_S)  # fmt: skip
        X.append(_windows(a, centres_s * DTW_FPS))
        y.append(np.full(len(centres_s), label, dtype=object))
    return np.concatenate(X), np.concatenate(y)


def dtw(X: np.ndarray, y: np.ndarray, rec: Recording) -> dict[str, Any]:
    """1-NN DTW label of a 2-s window centred on every block of ``rec``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # tslearn warns that optional h5py is missing
        from tslearn.metrics import cdist_dtw

    angles = _angles(rec.seq)
    centres = (np.arange(len(rec.blocks)) + 0.5) * BLOCK_S * DTW_FPS
    cdist_dtw(X[:1], X[:1])  # compiled (numba) before the clock starts, as ours is warmed
    t0, c0 = time.perf_counter(), time.process_time()
    pred = y[np.argmin(cdist_dtw(_windows(angles, centres), X), axis=1)]
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    truth = rec.blocks
    starts = (np.flatnonzero(pred[1:] != pred[:-1]) + 1) * BLOCK_S
    return {
        "correct": int(np.sum(pred == truth)),
        "boundary_errors_s": _boundary_errors(truth, starts),
        "seconds": seconds,
        "cpu_s": cpu,
    }


def run_fold(
    fold: Fold, read: Reader, mirror: str = "auto", feature_weights: str = "none"
) -> dict[str, Any]:
    """Seen accuracy and boundaries (ours per judge, DTW), and the unknown share of every
    movement left out in turn, per judge (the case bases' side handling ``mirror`` and
    ``feature_weights``, as ``train``'s options)."""
    from cbr.problem import warm
    from features.progress import progress

    joined = joined_training(fold.train, read)
    t0 = time.perf_counter()
    clf = fit(training_clips(joined), mirror, feature_weights)
    fit_s = time.perf_counter() - t0
    judges = {name: judge_named(clf, name) for name in JUDGES}
    warm_up(clf, joined[0][0], judges)
    X, y = dtw_training([(seq, g.movement) for seq, g in joined])
    recs: list[dict[str, Any]] = []
    for rec in progress(fold.recordings, f"{fold.dataset} {fold.name}: seen", unit="recording"):
        t0 = time.process_time()  # what every frame yields, computed once and timed apart
        warm(rec.seq, clf.feature_config_.level, mirror=clf.feature_config_.side == "canonical")
        extraction_cpu_s = time.process_time() - t0
        row: dict[str, Any] = {
            "name": rec.name,
            "movements": list(rec.movements),
            "blocks": len(rec.blocks),
            "seconds": rec.seq.duration_s,
            "max_jump_m": round(rec.max_jump_m, 3),
            "feature_extraction_cpu_s": extraction_cpu_s,
            "truth": _runs(rec.blocks),
            "dtw": dtw(X, y, rec),
        }
        for name, o in ours(clf, rec, judges).items():
            row[name] = {k: v for k, v in o.items() if k != "pred"}
        recs.append(row)
    unknown = run_unknown(fold, joined, mirror, feature_weights)
    return {
        "fold": fold.name,
        "cases": len(clf.case_base_),
        "dtw_training_windows": len(X),
        "fit_s": fit_s,
        "recordings": recs,
        "unknown": unknown,
    }


def warm_up(clf: Any, seq: Any, judges: dict[str, Any]) -> None:
    """One training clip ``seq`` segmented and finished by every judge, untimed, as the DTW
    baseline is compiled before its clock starts: what a process does once, at its first
    segmentation (numba's retrieval kernels compiled when their cache is cold, SciPy's
    signal module imported), is not timed with the first recording (it made that
    recording's time 2.3 s against 0.5 s warm, the dataset's times real time a third)."""
    from cbr.segmentation import finish, solve_recording

    done = solve_recording(clf, seq)
    for judge in judges.values():
        finish(clf, done, judge)


def run_unknown(
    fold: Fold,
    joined: list[tuple[Any, Group]],
    mirror: str = "auto",
    feature_weights: str = "none",
) -> dict[str, Any]:
    """Each movement of the test recordings left out of the case base in turn: per judge,
    its blocks in the recordings that contain it, and how many were called unknown."""
    from cbr.segmentation import finish, solve_recording
    from features.progress import progress

    movements = sorted({m for r in fold.recordings for m in r.movements})
    out: dict[str, Any] = {}
    for movement in progress(movements, f"{fold.dataset} {fold.name}: left out", unit="movement"):
        clf = fit(training_clips(joined, leave_out=movement), mirror, feature_weights)
        judges = {name: judge_named(clf, name) for name in JUDGES}
        counts = {name: [0, 0] for name in JUDGES}
        for rec in fold.recordings:
            if movement not in rec.movements:
                continue
            done = solve_recording(clf, rec.seq)  # solved once, finished by every judge
            for name, judge in judges.items():
                pred = np.array(finish(clf, done, judge).blocks[: len(rec.blocks)], dtype=object)
                mine = rec.blocks[: len(pred)] == movement
                counts[name][0] += int(np.sum(mine))
                counts[name][1] += int(sum(p is None for p in pred[mine]))
        out[movement] = {name: {"blocks": b, "unknown": u} for name, (b, u) in counts.items()}
    return out


def _runs(blocks: np.ndarray) -> list[list[Any]]:
    """``[[first block, end block, label], ...]`` of a block labelling."""
    change = np.flatnonzero(blocks[1:] != blocks[:-1]) + 1
    starts, ends = np.r_[0, change], np.r_[change, len(blocks)]
    return [[int(a), int(b), str(blocks[a])] for a, b in zip(starts, ends, strict=True)]


def summarise(dataset_folds: list[dict[str, Any]]) -> dict[str, Any]:
    """Pooled over a dataset's folds: block accuracy, left-out blocks called unknown and the
    median boundary error, per judge and for DTW; speed as times real time (CPU)."""
    recs = [r for f in dataset_folds for r in f["recordings"]]
    blocks = sum(r["blocks"] for r in recs)
    seconds = sum(r["seconds"] for r in recs)
    out: dict[str, Any] = {"recordings": len(recs), "blocks": blocks, "seconds": seconds}
    for name in JUDGES:
        left = [u[name] for f in dataset_folds for u in f["unknown"].values()]
        errors = [e for r in recs for e in r[name]["boundary_errors_s"]]
        out[name] = {
            "block_accuracy": sum(r[name]["correct"] for r in recs) / blocks,
            "blocks_called_unknown": sum(r[name]["unknown"] for r in recs) / blocks,
            "blocks_called_unknown_when_movement_left_out": sum(x["unknown"] for x in left)
            / max(1, sum(x["blocks"] for x in left)),
            "median_boundary_error_s": float(np.median(errors)),
            "x_real_time_cpu": seconds / sum(r[name]["cpu_s"] for r in recs),
        }
    errors = [e for r in recs for e in r["dtw"]["boundary_errors_s"]]
    out["dtw_1nn"] = {
        "block_accuracy": sum(r["dtw"]["correct"] for r in recs) / blocks,
        "median_boundary_error_s": float(np.median(errors)),
        "x_real_time_cpu": seconds / sum(r["dtw"]["cpu_s"] for r in recs),
    }
    return out


def print_table(summary: dict[str, dict[str, Any]]) -> None:
    print("\nSegmenting joined real repetitions of people NOT in the case base")
    print(f"  {'dataset, method':44s}{'seen blocks right':>18s}{'left out: unknown':>18s}"
          f"{'median boundary':>16s}{'x real time':>12s}")  # fmt: skip
    for dataset, s in summary.items():
        for name in JUDGES:
            o = s[name]
            print(f"  {dataset + ', unknown by ' + name:44s}{o['block_accuracy']:18.1%}"
                  f"{o['blocks_called_unknown_when_movement_left_out']:18.1%}"
                  f"{o['median_boundary_error_s']:15.2f}s{o['x_real_time_cpu']:12.0f}")  # fmt: skip
        d = s["dtw_1nn"]
        print(f"  {dataset + ', DTW 1-NN':44s}{d['block_accuracy']:18.1%}{'0 % (cannot)':>18s}"
              f"{d['median_boundary_error_s']:15.2f}s{d['x_real_time_cpu']:12.0f}")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.segment_people", description=__doc__
    )
    parser.add_argument("--datasets", nargs="+", choices=DATASETS, default=list(DATASETS))
    parser.add_argument("--per-person", type=int, default=1, help="recordings per person")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--train-people",
        type=int,
        default=None,
        help="case bases of only the first N training people (1: one person, as a case base "
        "of CMU subject 13 alone); results go to segment_people_N.json",
    )
    parser.add_argument(
        "--rotate",
        action="store_true",
        help="with --train-people N: the case bases of every N training people in turn (1: "
        "each alone), not only the first N; results go to segment_people_N_rotate.json",
    )
    parser.add_argument(
        "--mirror",
        choices=("auto", "off", "canonical", "augment"),
        default="auto",
        help="the case bases' side handling, as train's --mirror (given: results go to "
        "segment_people[_N]_MIRROR.json)",
    )
    parser.add_argument(
        "--feature-weights",
        choices=("none", "fisher"),
        default="none",
        help="the case bases' feature weights, as train's --feature-weights (default none, "
        "as train --split windows; fisher: results go to segment_people[_N]_fisher.json)",
    )
    args = parser.parse_args(argv)
    if args.rotate and not args.train_people:
        parser.error("--rotate needs --train-people N")
    if not UIPRMD.is_dir() or not HDM05.is_dir():
        print(f"no ui-prmd or hdm05 data under {UIPRMD.parents[1]}: nothing to measure")
        return 1
    import numba

    numba.set_num_threads(1)
    load_at_start = [round(x, 2) for x in os.getloadavg()]
    results: dict[str, Any] = {}
    summary: dict[str, Any] = {}
    for dataset in args.datasets:
        read = Reader()
        t0 = time.perf_counter()
        chosen = folds(dataset, args.per_person, args.seed, read, args.train_people, args.rotate)
        done = [run_fold(f, read, args.mirror, args.feature_weights) for f in chosen]
        results[dataset] = done
        summary[dataset] = {**summarise(done), "wall_s": time.perf_counter() - t0}
        print_table({dataset: summary[dataset]})
    print_table(summary)
    result = {
        "benchmark": "segment_people",
        "command": "python -m benchmarks.segment_people --datasets "
        + " ".join(args.datasets)
        + f" --per-person {args.per_person} --seed {args.seed}"
        + (f" --train-people {args.train_people}" if args.train_people else "")
        + (" --rotate" if args.rotate else "")
        + (f" --mirror {args.mirror}" if args.mirror != "auto" else "")
        + (f" --feature-weights {args.feature_weights}" if args.feature_weights != "none" else ""),
        "note": "joined real single repetitions of people not in the case base: the joins "
        "(0.1 s of blending) and the rest at each repetition's ends differ from a real session",
        "machine": one_thread_machine(),
        "load_average_at_start": load_at_start,
        "versions": versions("posecbr", "numpy", "scipy", "scikit-learn", "tslearn", "numba"),
        "summary": summary,
        "folds": results,
    }
    out = RESULTS
    if args.train_people:
        out = RESULTS.with_name(f"segment_people_{args.train_people}.json")
    if args.rotate:
        out = out.with_name(f"{out.stem}_rotate.json")
    if args.mirror != "auto":
        out = out.with_name(f"{out.stem}_{args.mirror}.json")
    if args.feature_weights != "none":
        out = out.with_name(f"{out.stem}_{args.feature_weights}.json")
    write_json(result, out)
    print(f"\nwrote {out.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
