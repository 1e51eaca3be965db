"""Repetitions of a stretch of one exercise cut into segments: does a cut change the count?

Run: ``python -m benchmarks.segment_cuts`` (about half a minute). Writes
``benchmarks/results/segment_cuts.json``.

The CMU stretches counted by hand (``tests/fixtures/repetition_counts.json``: subject 13, one
exercise each) are cut as a segmentation could cut them: once, at every 0.2 s (at least
0.5 s from either end), and into three with a 1-s segment between (a fragment shorter than
most repetitions), at every 0.2 s. The repetitions of the pieces are added up and compared
with the count of the whole stretch (a cut inside one exercise should change nothing):
``per_segment``, each piece counted on its own (:func:`cbr.segmentation._repetitions`, as
``segment`` counted before), and ``once``, each repetition in the one piece that holds where
the movement turns (:func:`cbr.segmentation.counted_segments`). Reported per stretch and
pooled: the share of cuts that leave the count as it was, and the mean difference (pieces
minus whole: above 0, repetitions counted twice).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import no_options, write_json
from benchmarks.segment import DATA, FIXTURE

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "segment_cuts.json"
HOP_S, EDGE_S, FRAGMENT_S = 0.2, 0.5, 1.0


def _cuts(n: int, fps: float) -> tuple[list[list[tuple[int, int]]], list[list[tuple[int, int]]]]:
    """Frame bounds of the stretch of ``n`` frames cut once, and cut around a 1-s fragment."""
    hop, edge, frag = int(HOP_S * fps), int(EDGE_S * fps), int(FRAGMENT_S * fps)
    once = [[(0, c), (c, n)] for c in range(edge, n - edge, hop)]
    fragment = [[(0, c), (c, c + frag), (c + frag, n)] for c in range(edge, n - edge - frag, hop)]
    return once, fragment


def _differences(
    sig: Any, cuts: list[list[tuple[int, int]]], n: int, whole: int
) -> dict[str, list[int]]:
    from cbr.segmentation import _repetitions, counted_segments

    return {
        "per_segment": [sum(len(_repetitions(sig, a, b)) for a, b in c) - whole for c in cuts],
        "once": [sum(len(r) for r in counted_segments(sig, c, n)) - whole for c in cuts],
    }


def _scores(diffs: list[int]) -> dict[str, float] | None:
    """Share of cuts leaving the count unchanged and the mean difference (None: no cut)."""
    if not diffs:
        return None  # a stretch too short to cut this way
    d = np.asarray(diffs, dtype=np.float64)
    return {"cuts": len(d), "unchanged": float(np.mean(d == 0)), "mean_difference": float(d.mean())}


def main(argv: list[str] | None = None) -> int:
    no_options("segment_cuts", __doc__, argv)
    from cbr.segmentation import counted_segments
    from features.readers.asfamc import read_asf_amc
    from features.repetitions import movement_signals

    clips = [c for c in json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
             if c["source"].endswith(".amc")]  # fmt: skip
    cache: dict[str, Any] = {}
    rows = []
    pooled: dict[str, dict[str, list[int]]] = {"cut once": {}, "1-s fragment": {}}
    for c in clips:
        if c["source"] not in cache:
            cache[c["source"]] = read_asf_amc(DATA / c["asf"], DATA / c["source"])
        seq = cache[c["source"]].slice_frames(c["start_frame"], c["end_frame"]).to_canonical()
        n, sig = seq.n_frames, movement_signals(seq)
        whole = len(counted_segments(sig, [(0, n)], n)[0])
        row: dict[str, Any] = {"source": c["source"], "activity": c["activity"], "hand": c["count"],
                               "whole": whole}  # fmt: skip
        for name, cuts in zip(pooled, _cuts(n, seq.fps), strict=True):
            diffs = _differences(sig, cuts, n, whole)
            row[name] = {k: _scores(v) for k, v in diffs.items()}
            for k, v in diffs.items():
                pooled[name].setdefault(k, []).extend(v)
        rows.append(row)
    summary = {name: {k: _scores(v) for k, v in d.items()} for name, d in pooled.items()}
    for name, d in summary.items():
        for k, s in d.items():
            assert s is not None
            print(f"{name:14s} {k:12s} count unchanged by the cut {s['unchanged']:6.1%}"
                  f"  mean difference {s['mean_difference']:+.2f}  ({s['cuts']} cuts)")  # fmt: skip
    write_json({"benchmark": "segment_cuts", "command": "python -m benchmarks.segment_cuts",
                "summary": summary, "stretches": rows}, RESULTS)  # fmt: skip
    print(f"wrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
