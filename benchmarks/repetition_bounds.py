"""Repetition counts of a stretch whose start and end are moved: how much does a count depend
on where the stretch was cut?

Run: ``python -m benchmarks.repetition_bounds [--shifts S ...]`` (about a minute).
Writes ``benchmarks/results/repetition_bounds.json``.

Segmentation puts a boundary within about half a second of the labelled change (the
segment benchmarks judge a boundary good within 0.5 s), so a count must not fall apart when
its stretch starts or ends up to half a second into the neighbouring exercise or inside its
own. Every CMU stretch counted by hand (``tests/fixtures/repetition_counts.json``: subject
13, one exercise each) is counted with its start and its end each moved by every shift
(default -0.5, -0.25, 0, 0.25, 0.5 s; negative = earlier, so a negative start and a positive
end reach into the neighbours; moves past the recording's ends are skipped), with the
fixture's skeleton (HDM05 ``bd``) and the other two HDM05 actors' (``bk``, ``dg``: the
recordings come without one), in two ways:

- ``clip``: the moved stretch as a clip of its own (:func:`features.repetitions.count_repetitions`,
  as ``posecbr reps`` and the hand-count benchmark count);
- ``segment``: as ``posecbr segment`` counts a segment of the recording, on the recording's
  signals, each repetition in the one piece that holds where it turns
  (:func:`cbr.segmentation.counted_segments` over the pieces before, the stretch, after).

Reported per stretch and pooled: the share of moved counts equal to the unmoved one, their
mean absolute error against the hand count, and the share outside what the hand counts allow
for the moved stretch: at least the hand-marked far points (:data:`FAR_POINTS_S`, read off
the fixture's ``how``) lying 0.25 s or more inside it, at most every hand-marked far point
inside it, the neighbours' included (a stretch moved into a neighbour may take one of its
repetitions). Moving a boundary inward legitimately drops the repetitions left outside, so
"unchanged" alone overstates the fragility; the allowed range does not.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import write_json
from benchmarks.segment import DATA, FIXTURE

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "repetition_bounds.json"
SHIFTS_S = (-0.5, -0.25, 0.0, 0.25, 0.5)
SKELETONS = ("hdm05/train/3/HDM_bd.asf", "hdm05/train/1/HDM_bk.asf", "hdm05/train/1/HDM_dg.asf")
SURE_S = 0.25
"""A hand-marked far point at least this far inside a moved stretch must be counted."""

FAR_POINTS_S: dict[tuple[str, int], tuple[float, ...]] = {
    ("13_29", 0): (0.6, 1.65, 2.75, 3.8),
    ("13_29", 468): (5.1, 6.75, 8.6),
    ("13_29", 1212): (10.4, 11.3, 12.2, 13.4, 14.6, 15.6),
    ("13_29", 1920): (17.0, 19.2, 21.2),
    ("13_29", 2700): (24.1, 25.4, 26.6, 28.0, 29.5, 30.8),
    ("13_29", 3804): (33.25, 36.3),
    ("13_30", 0): (0.0, 0.95),
    ("13_30", 216): (2.65, 4.2, 5.8),
    ("13_30", 804): (7.5, 8.7, 9.9, 11.0),
    ("13_30", 1416): (13.0, 15.4),
    ("13_30", 1932): (16.5, 16.9, 17.2, 17.6, 18.0, 18.4, 18.75, 19.05, 19.45),
    ("13_31", 0): (1.0, 2.5),
    ("13_31", 396): (4.0, 5.2, 6.4, 7.6),
    ("13_31", 984): (8.9, 10.6),
    ("13_31", 1392): (12.5,),
    # the fixture gives "13.7-16.0 s" for these 7 steps: the knee troughs, read off the
    # knee angles (left 13.79, 14.48, 15.25, 16.02 s; right 14.1, 14.86, 15.64 s)
    ("13_31", 1608): (13.79, 14.1, 14.48, 14.86, 15.25, 15.64, 16.02),
    ("13_31", 2052): (17.7, 18.6, 19.15, 20.05, 21.15),
    ("13_31", 2724): (23.35, 24.4),
}
"""Far points (seconds into the recording) of each hand-counted stretch, by recording and
start frame, as the fixture's ``how`` gives them."""


def allowed(recording: str, start_frame: int, t0: float, t1: float) -> tuple[int, int]:
    """The counts the hand counts allow for the stretch's moved version [t0, t1) seconds:
    its own far points at least :data:`SURE_S` inside, up to every far point inside (any
    stretch's of the recording). The arms up at 13_30's first frame count when the stretch
    starts there (the fixture counts that one)."""
    own = FAR_POINTS_S[(recording, start_frame)]
    every = [t for (r, _), ts in FAR_POINTS_S.items() if r == recording for t in ts]
    sure = sum(t0 + SURE_S <= t < t1 - SURE_S for t in own)
    sure += int(t0 == 0.0 and 0.0 in own)
    return sure, max(sure, sum(t0 <= t < t1 for t in every))


def _scores(rows: list[dict[str, Any]], way: str) -> dict[str, float]:
    """Pooled figures of ``rows`` for one way of counting."""
    base = {(r["skeleton"], r["recording"], r["start_frame"]): r[way] for r in rows
            if r["start_shift_s"] == 0.0 and r["end_shift_s"] == 0.0}  # fmt: skip
    counts = np.array([r[way] for r in rows])
    hand = np.array([r["hand"] for r in rows])
    unmoved = np.array([base[(r["skeleton"], r["recording"], r["start_frame"])] for r in rows])
    lo, hi = np.array([r["allowed"][0] for r in rows]), np.array([r["allowed"][1] for r in rows])
    off = np.maximum(lo - counts, 0) + np.maximum(counts - hi, 0)
    return {
        "counts": len(rows),
        "unchanged": float(np.mean(counts == unmoved)),
        "mae_vs_hand": float(np.mean(np.abs(counts - hand))),
        "outside_allowed": float(np.mean(off > 0)),
        "outside_allowed_by": float(off.sum()),
    }


def count_moved(shifts: list[float]) -> list[dict[str, Any]]:
    """Every hand-counted CMU stretch, with every skeleton, counted both ways with its start
    and end moved by every pair of ``shifts`` (seconds)."""
    from cbr.segmentation import counted_segments
    from features.readers.asfamc import read_asf_amc
    from features.repetitions import MIN_PERIOD_S, count_repetitions, movement_signals

    clips = [c for c in json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
             if c["source"].endswith(".amc")]  # fmt: skip
    rows: list[dict[str, Any]] = []
    for asf in SKELETONS:
        recs: dict[str, Any] = {}
        for c in clips:
            if c["source"] not in recs:
                seq = read_asf_amc(DATA / asf, DATA / c["source"])
                recs[c["source"]] = (seq, movement_signals(seq))
            seq, sig = recs[c["source"]]
            n, recording = seq.n_frames, Path(c["source"]).stem
            for ds, de in ((ds, de) for ds in shifts for de in shifts):
                a = c["start_frame"] + int(round(ds * seq.fps))
                b = c["end_frame"] + int(round(de * seq.fps))
                if a < 0 or b > n or b - a < MIN_PERIOD_S * seq.fps:
                    continue
                pieces = [(0, a)] * (a > 0) + [(a, b)] + [(b, n)] * (b < n)
                rows.append({
                    "skeleton": Path(asf).stem.removeprefix("HDM_"), "recording": recording,
                    "activity": c["activity"], "start_frame": c["start_frame"],
                    "end_frame": c["end_frame"], "hand": c["count"],
                    "start_shift_s": ds, "end_shift_s": de,
                    "allowed": allowed(recording, c["start_frame"], a / seq.fps, b / seq.fps),
                    "clip": count_repetitions(seq.slice_frames(a, b)).count,
                    "segment": len(counted_segments(sig, pieces, n)[int(a > 0)]),
                })  # fmt: skip
    return rows


WAYS = ("clip", "segment")


def _grids(rows: list[dict[str, Any]]) -> dict[str, dict[str, list[str]]]:
    """The moved counts of one stretch by skeleton and way, a line per start shift (first
    the earliest), a column per end shift ("-": moved past the recording's start or end)."""
    starts = sorted({r["start_shift_s"] for r in rows})
    ends = sorted({r["end_shift_s"] for r in rows})
    out: dict[str, dict[str, list[str]]] = {}
    for k in sorted({r["skeleton"] for r in rows}):
        at = {(r["start_shift_s"], r["end_shift_s"]): r for r in rows if r["skeleton"] == k}
        out[k] = {
            w: [" ".join(str(at[(a, b)][w]) if (a, b) in at else "-" for b in ends)
                for a in starts]
            for w in WAYS
        }  # fmt: skip
    return out


def per_stretch(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The figures of every stretch (all skeletons together), printed as a table."""
    stretches: dict[tuple[str, str, int], list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        stretches[(r["recording"], r["activity"], r["start_frame"])].append(r)
    out = []
    print(f"{'stretch':<26} {'hand':>4}  "
          + "  ".join(f"{w}: unmoved unchanged MAE outside" for w in WAYS))  # fmt: skip
    for (recording, activity, start), rs in stretches.items():
        s = {w: _scores(rs, w) for w in WAYS}
        unmoved = {w: sorted({r[w] for r in rs if r["start_shift_s"] == r["end_shift_s"] == 0})
                   for w in WAYS}  # fmt: skip
        out.append({"recording": recording, "activity": activity, "start_frame": start,
                    "hand": rs[0]["hand"], "unmoved": unmoved, **s,
                    "grids": _grids(rs)})  # fmt: skip
        cells = [
            f"{w}: {','.join(map(str, unmoved[w])):>7} {s[w]['unchanged']:>9.0%} "
            f"{s[w]['mae_vs_hand']:>3.2f} {s[w]['outside_allowed']:>7.0%}"
            for w in WAYS
        ]
        print(f"{recording} {activity:<20} {rs[0]['hand']:>4}  " + "  ".join(cells))
    return out


def pooled(rows: list[dict[str, Any]]) -> dict[str, dict[str, dict[str, float]]]:
    """The figures of all counts together and by skeleton, for each way, printed."""
    skeletons = sorted({r["skeleton"] for r in rows})
    out = {w: {"all": _scores(rows, w),
               **{k: _scores([r for r in rows if r["skeleton"] == k], w) for k in skeletons}}
           for w in WAYS}  # fmt: skip
    for w, parts in out.items():
        for part, f in parts.items():
            print(f"pooled {w:<8} {part:<4} {f['counts']:>5} counts: "
                  f"unchanged {f['unchanged']:6.1%}  MAE vs hand {f['mae_vs_hand']:.3f}  "
                  f"outside the allowed {f['outside_allowed']:6.1%}"
                  f" (by {f['outside_allowed_by']:g} in all)")  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.repetition_bounds",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--shifts", type=float, nargs="+", default=list(SHIFTS_S),
                        help="seconds each boundary is moved by (%(default)s)")  # fmt: skip
    args = parser.parse_args(argv)
    if not (DATA / "cmu-mocap6").is_dir():
        print(f"no cmu-mocap6 data under {DATA}: nothing to measure")
        return 1
    rows = count_moved(args.shifts)
    stretches = per_stretch(rows)
    summary = pooled(rows)
    default = tuple(args.shifts) == SHIFTS_S
    shifts = " ".join(f"{s:g}" for s in args.shifts)
    command = "python -m benchmarks.repetition_bounds" + ("" if default else f" --shifts {shifts}")
    out = (
        RESULTS
        if default
        else RESULTS.with_name(f"repetition_bounds_{shifts.replace(' ', '_')}.json")
    )
    write_json({"benchmark": "repetition_bounds", "command": command, "shifts_s": args.shifts,
                "summary": summary, "stretches": stretches}, out)  # fmt: skip
    print(f"wrote {out.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
