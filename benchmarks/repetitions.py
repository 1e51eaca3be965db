"""Repetition counts with exact ground truth, from people other than CMU subject 13.

Run: ``python -m benchmarks.repetitions [--no-videos] [--per-group N] [--seed S]`` (about a
minute without the videos). Writes ``benchmarks/results/repetitions.json``.

Data: K real single repetitions (K drawn from 2..12, at most as many as the person recorded)
of one person and one movement, played one after the other
(:func:`features.joining.join_repetitions`: each repetition turned and shifted along the floor
to stand where the previous one ended, the remaining jump bridged by 0.1 s of linear
blending; the jumps are reported). The count is K by construction.

- UI-PRMD Kinect (30 Hz): the correct and incorrect repetitions of each subject and movement
  (10 + 10 per subject and movement, ``m01``-``m10``, subjects ``s01``-``s08``);
- UI-PRMD Vicon (about 100 Hz, joint centres from markers): the correct repetitions;
- HDM05 (120 Hz): the one-repetition clips of squat, elbow to knee, front kick, arm circles
  backward and hop (actors bd, bk, dg).

Subjects ``s01``-``s04`` of UI-PRMD are the only data any choice of the counting method may
look at ("train"); ``s05``-``s08``, HDM05 and the hand counts of
``tests/fixtures/repetition_counts.json`` (CMU subject 13 and the videos) are held out.

Measured per dataset, movement and split, as the repetition-counting literature reports
(RepNet, PoseRAC): mean absolute error of the count (MAE), off-by-one accuracy (|error| <= 1,
OBO) and the share counted exactly; and beside :func:`features.repetitions.count_repetitions`
in the same run the plain period baseline: the clip's duration over the period of the
autocorrelation of its angle velocities (what a period estimator alone gives).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import re  # noqa: E402
import time  # noqa: E402
from collections import defaultdict  # noqa: E402
from collections.abc import Callable, Collection, Iterator  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
from benchmarks._common import one_thread_machine, versions  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results" / "repetitions.json"
UIPRMD = DATA / "ui-prmd" / "data"
HDM05 = DATA / "hdm05" / "train"
HDM05_ACTIONS = (
    "squat1Reps",
    "elbowToKnee1RepsLelbowStart",
    "kickLFront1Reps",
    "rotateArmsBothBackward1Reps",
    "hopBothLegs1hops",
)
TRAIN_SUBJECTS = ("s01", "s02", "s03", "s04")
"""UI-PRMD subjects whose joined repetitions may guide choices; all else is held out."""
K_RANGE = (2, 12)


@dataclass(frozen=True)
class Group:
    """The single repetitions of one person doing one movement."""

    dataset: str
    person: str
    movement: str
    files: tuple[Path, ...]

    @property
    def split(self) -> str:
        return "train" if self.person in TRAIN_SUBJECTS else "held-out"


def uiprmd_groups(sensor: str) -> list[Group]:
    """UI-PRMD repetitions by subject and movement (Kinect: correct and incorrect)."""
    folders = [UIPRMD / "Segmented Movements" / sensor / "Positions"]
    if sensor == "Kinect":
        folders.append(UIPRMD / "Incorrect Segmented Movements" / sensor / "Positions")
    found: dict[tuple[str, str], list[Path]] = defaultdict(list)
    for folder in folders:
        for path in sorted(folder.glob("m*_s*_e*_positions*.txt.gz")):
            movement, subject = path.name.split("_")[:2]
            found[(subject, movement)].append(path)
    name = f"ui-prmd-{sensor.lower()}"
    return [Group(name, s, m, tuple(f)) for (s, m), f in sorted(found.items())]


def hdm05_groups(actions: Collection[str] = HDM05_ACTIONS) -> list[Group]:
    """HDM05 clips of ``actions`` (by default the one-repetition ones,
    :data:`HDM05_ACTIONS`) by actor and action."""
    found: dict[tuple[str, str], list[Path]] = defaultdict(list)
    pattern = re.compile(r"HDM_([a-z]+)_([A-Za-z0-9]+)_\d+_120\.amc$", re.IGNORECASE)
    for path in sorted(HDM05.glob("*/HDM_*")):
        m = pattern.match(path.name)
        if m and m.group(2) in actions:
            found[(m.group(1), m.group(2))].append(path)
    return [Group("hdm05", a, m, tuple(f)) for (a, m), f in sorted(found.items())]


def read_one(group: Group, path: Path) -> Any:
    from features.readers.asfamc import read_asf_amc
    from features.readers.uiprmd import read_uiprmd_kinect, read_uiprmd_vicon

    if group.dataset == "hdm05":
        return read_asf_amc(path.parent / f"HDM_{group.person}.asf", path)
    if group.dataset == "ui-prmd-vicon":
        return read_uiprmd_vicon(path)
    return read_uiprmd_kinect(path)


def take_name(path: Path) -> str:
    """The part of a repetition's file name that tells it from the person's others: the
    episode of UI-PRMD (``e03``, ``e03_inc`` for an incorrect one), the take of HDM05."""
    parts = path.name.split(".")[0].split("_")
    if path.name.startswith("HDM_"):
        return parts[-2]
    return parts[2] + ("_inc" if parts[-1] == "inc" else "")


@dataclass(frozen=True)
class Joined:
    group: Group
    k: int
    seq: Any  # PoseSequence
    max_jump_m: float
    files: tuple[str, ...]


def joined_sequences(groups: list[Group], per_group: int, seed: int) -> Iterator[Joined]:
    """``per_group`` joined recordings of every group: K repetitions drawn without
    replacement, K uniform in :data:`K_RANGE` (capped at the group's size)."""
    from features.joining import join_repetitions

    rng = np.random.default_rng(seed)
    for group in groups:
        cache: dict[Path, Any] = {}
        for _ in range(per_group):
            k = int(rng.integers(K_RANGE[0], K_RANGE[1] + 1))
            k = min(k, len(group.files))
            picks = rng.choice(len(group.files), size=k, replace=False)
            reps, names = [], []
            for i in picks:
                path = group.files[int(i)]
                if path not in cache:
                    cache[path] = read_one(group, path)
                reps.append(cache[path])
                names.append(take_name(path))
            joined = join_repetitions(reps)
            jump = float(joined.jumps_m.max()) if len(joined.jumps_m) else 0.0
            yield Joined(group, k, joined.seq, jump, tuple(names))


def period_baseline(seq: Any) -> int:
    """Duration over the autocorrelation period of the angle velocities (0 when none)."""
    from features.repetitions import find_period, movement_signals

    sig = movement_signals(seq)
    period, _ = find_period(np.diff(sig.values, axis=0), sig.fps)
    return 0 if period is None else int(round(seq.duration_s / period))


def ours(seq: Any) -> int:
    from features.repetitions import count_repetitions

    return int(count_repetitions(seq).count)


METHODS: dict[str, Callable[[Any], int]] = {"ours": ours, "period_baseline": period_baseline}


def scores(errors: np.ndarray) -> dict[str, float]:
    """MAE, off-by-one accuracy and exact share of signed count errors ``(n,)``."""
    err = np.abs(errors)
    return {
        "n": int(len(err)),
        "mae": float(err.mean()),
        "obo": float((err <= 1).mean()),
        "exact": float((err == 0).mean()),
        "mean_signed_error": float(np.mean(errors)),
    }


def run_joined(per_group: int, seed: int) -> tuple[list[dict[str, Any]], dict[str, float]]:
    from features.progress import progress

    groups = uiprmd_groups("Kinect") + uiprmd_groups("Vicon") + hdm05_groups()
    rows = []
    seconds: dict[str, float] = defaultdict(float)
    total = len(groups) * per_group
    for item in progress(joined_sequences(groups, per_group, seed), total=total, desc="count"):
        row: dict[str, Any] = {
            "dataset": item.group.dataset,
            "person": item.group.person,
            "movement": item.group.movement,
            "split": item.group.split,
            "k": item.k,
            "frames": item.seq.n_frames,
            "max_jump_m": round(item.max_jump_m, 4),
            "takes": list(item.files),
        }
        for name, method in METHODS.items():
            t0 = time.process_time()
            row[name] = method(item.seq)
            seconds[name] += time.process_time() - t0
        rows.append(row)
    return rows, dict(seconds)


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Scores of every method by dataset and split, and by dataset, split and movement."""
    out: dict[str, Any] = {}
    keys: dict[str, Callable[[dict[str, Any]], str]] = {
        "by_dataset": lambda r: f"{r['dataset']} {r['split']}",
        "by_movement": lambda r: f"{r['dataset']} {r['split']} {r['movement']}",
    }
    for part, key in keys.items():
        grouped: dict[str, list[dict[str, Any]]] = defaultdict(list)
        for r in rows:
            grouped[key(r)].append(r)
        out[part] = {
            k: {m: scores(np.array([r[m] - r["k"] for r in v])) for m in METHODS}
            for k, v in sorted(grouped.items())
        }
    held = [r for r in rows if r["split"] == "held-out"]
    out["held_out_all"] = {m: scores(np.array([r[m] - r["k"] for r in held])) for m in METHODS}
    return out


def _print_table(summary: dict[str, Any], hand: dict[str, Any]) -> None:
    print(f"\n{'data (joined, count known)':<34} {'n':>4}  {'MAE':>5} {'OBO':>6} {'exact':>6}"
          f"  | period baseline MAE OBO exact")  # fmt: skip
    for name, s in summary["by_dataset"].items():
        o, b = s["ours"], s["period_baseline"]
        print(f"{name:<34} {o['n']:>4}  {o['mae']:>5.2f} {o['obo']:>6.1%} {o['exact']:>6.1%}"
              f"  | {b['mae']:>5.2f} {b['obo']:>6.1%} {b['exact']:>6.1%}")  # fmt: skip
    o = summary["held_out_all"]["ours"]
    print(f"{'all held out':<34} {o['n']:>4}  {o['mae']:>5.2f} {o['obo']:>6.1%} {o['exact']:>6.1%}")
    for part in ("mocap", "videos", "all"):
        if part in hand:
            h = hand[part]
            b = h["period_baseline"]
            print(f"{'hand counts, ' + part:<34} {h['clips']:>4}  {h['mae']:>5.2f} "
                  f"{h['obo']:>6.1%} {h['exact']:>6.1%}  | {b['mae']:>5.2f} {b['obo']:>6.1%} "
                  f"{b['exact']:>6.1%}")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.repetitions", description=__doc__)
    parser.add_argument("--per-group", type=int, default=3, help="joined recordings per group")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-videos", action="store_true", help="hand counts: skip the videos")
    args = parser.parse_args(argv)
    if not UIPRMD.is_dir() or not HDM05.is_dir():
        print(f"no ui-prmd or hdm05 data under {DATA}: nothing to measure")
        return 1
    from benchmarks.segment import bench_repetitions

    rows, seconds = run_joined(args.per_group, args.seed)
    summary = summarise(rows)
    hand = bench_repetitions(not args.no_videos, {"period_baseline": period_baseline})
    _print_table(summary, hand)
    result = {
        "benchmark": "repetitions",
        "command": "python -m benchmarks.repetitions"
        + (" --no-videos" if args.no_videos else "")
        + f" --per-group {args.per_group} --seed {args.seed}",
        "train_subjects": list(TRAIN_SUBJECTS),
        "k_range": list(K_RANGE),
        "machine": one_thread_machine(),
        "versions": versions("posecbr", "numpy", "scipy"),
        "cpu_seconds": seconds,
        "summary": summary,
        "hand_counts": hand,
        "joined": rows,
    }
    write_json(result, RESULTS)
    print(f"\nwrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
