"""``watch``'s live decoder (:class:`cbr.live.LiveSegmenter`) on CMU subject 13, leave one
recording out, as ``benchmarks.segment`` measures the offline one.

Run: ``python -m benchmarks.segment_live`` (a few minutes). Writes
``benchmarks/results/segment_live.json``.

The case base is that of ``benchmarks.segment`` (the two training recordings cut into
windows); the third recording is streamed frame by frame at 30 fps (every 4th of its 120-fps
frames), as a camera would deliver it. Measured: the share of its 0.1-s blocks labelled with
their exercise by the printed segments, the number of segments against the labelled
stretches, and the repetitions of all segments against the hand counts of its stretches
(``tests/fixtures/repetition_counts.json``); and, each exercise of the streamed recording
left out of the case base in turn, the share of its blocks called unknown. ONE PERSON: the
figures overstate what other people get.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import json  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import no_options, write_json  # noqa: E402
from benchmarks.segment import FIXTURE, RECORDINGS, fit, load_recordings, training_clips  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "segment_live.json"
STEP = 4  # 120 fps streamed at 30


def watch(clf: Any, world: np.ndarray, fps: float) -> list[Any]:
    """The segments ``watch`` prints for a stream of ``world`` frames ``(n, 33, 3)``."""
    from cbr.live import LiveSegmenter

    live = LiveSegmenter(clf, fps)
    segments = []
    for frame in world:
        segments += live.push(frame)
    return segments + live.finish()


def block_labels(segments: list[Any], n_blocks: int, fps: float) -> np.ndarray:
    """The label of every 0.1-s block by the ``segments`` (None: unknown; "" where none lies)."""
    pred = np.full(n_blocks, "", dtype=object)
    for s in segments:
        pred[int(round(s.start_frame / fps / 0.1)) : int(round(s.end_frame / fps / 0.1))] = s.label
    return pred


def left_out_unknown(recs: dict[str, Any], test: str) -> dict[str, list[int]]:
    """Each exercise of ``test`` left out of the case base in turn, ``test`` streamed: per
    exercise, [its blocks called unknown, its blocks]."""
    rec = recs[test]
    train = [recs[n] for n in RECORDINGS if n != test]
    fps = rec.seq.fps / STEP
    out = {}
    for exercise in sorted(set(rec.blocks)):
        clf = fit(training_clips(train, leave_out=exercise))
        pred = block_labels(watch(clf, rec.seq.positions[::STEP], fps), len(rec.blocks), fps)
        mine = rec.blocks == exercise
        out[str(exercise)] = [sum(p is None for p in pred[mine]), int(mine.sum())]
    return out


def main(argv: list[str] | None = None) -> int:
    no_options("segment_live", __doc__, argv)
    recs = load_recordings()
    clips = json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
    rows = []
    for test in RECORDINGS:
        rec = recs[test]
        clf = fit(training_clips([recs[n] for n in RECORDINGS if n != test]))
        fps = rec.seq.fps / STEP
        segments = watch(clf, rec.seq.positions[::STEP], fps)
        pred = block_labels(segments, len(rec.blocks), fps)
        left_out = left_out_unknown(recs, test)
        hand = sum(c["count"] for c in clips if c["source"].endswith(f"{test}.amc"))
        rows.append({
            "recording": test,
            "blocks": len(rec.blocks),
            "blocks_right": int(np.sum(pred == rec.blocks)),
            "segments": len(segments),
            "labelled_stretches": 1 + int(np.sum(rec.blocks[1:] != rec.blocks[:-1])),
            "repetitions": sum(s.repetitions for s in segments),
            "hand_count": hand,
            "left_out_blocks": sum(n for _, n in left_out.values()),
            "left_out_blocks_unknown": sum(k for k, _ in left_out.values()),
            "left_out_unknown_by_exercise": {e: k / n for e, (k, n) in left_out.items()},
        })  # fmt: skip
        r = rows[-1]
        print(f"{test}: blocks right {r['blocks_right'] / r['blocks']:.1%}, segments "
              f"{r['segments']} (labelled {r['labelled_stretches']}), repetitions "
              f"{r['repetitions']} (by hand {r['hand_count']}); left out and called unknown "
              f"{r['left_out_blocks_unknown'] / r['left_out_blocks']:.1%}", flush=True)  # fmt: skip
    total = {k: sum(r[k] for r in rows) for k in rows[0] if k != "recording" and "_by_" not in k}
    print(f"all: blocks right {total['blocks_right'] / total['blocks']:.1%}, segments "
          f"{total['segments']} (labelled {total['labelled_stretches']}), repetitions "
          f"{total['repetitions']} (by hand {total['hand_count']}); left out and called "
          f"unknown {total['left_out_blocks_unknown'] / total['left_out_blocks']:.1%}")  # fmt: skip
    write_json({"benchmark": "segment_live", "command": "python -m benchmarks.segment_live",
                "total": total, "recordings": rows}, RESULTS)  # fmt: skip
    print(f"wrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
