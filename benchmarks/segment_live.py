"""``watch``'s live decoder (:class:`cbr.live.LiveSegmenter`) on CMU subject 13, leave one
recording out, as ``benchmarks.segment`` measures the offline one.

Run: ``python -m benchmarks.segment_live`` (a few minutes). Writes
``benchmarks/results/segment_live.json``.

The case base is that of ``benchmarks.segment`` (the two training recordings cut into
windows); the third recording is streamed frame by frame at 30 fps (every 4th of its 120-fps
frames), as a camera would deliver it. Measured: the share of its 0.1-s blocks labelled with
their exercise by the printed segments, the number of segments against the labelled
stretches, and the repetitions of all segments against the hand counts of its stretches
(``tests/fixtures/repetition_counts.json``). ONE PERSON: the figures overstate what other
people get.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import json  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
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


def main() -> int:
    recs = load_recordings()
    clips = json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
    rows = []
    for test in RECORDINGS:
        rec = recs[test]
        clf = fit(training_clips([recs[n] for n in RECORDINGS if n != test]))
        fps = rec.seq.fps / STEP
        segments = watch(clf, rec.seq.positions[::STEP], fps)
        pred = np.full(len(rec.blocks), None, dtype=object)
        for s in segments:
            pred[int(round(s.start_frame / fps / 0.1)) : int(round(s.end_frame / fps / 0.1))] = (
                s.label
            )
        hand = sum(c["count"] for c in clips if c["source"].endswith(f"{test}.amc"))
        rows.append({
            "recording": test,
            "blocks": len(rec.blocks),
            "blocks_right": int(np.sum(pred == rec.blocks)),
            "segments": len(segments),
            "labelled_stretches": 1 + int(np.sum(rec.blocks[1:] != rec.blocks[:-1])),
            "repetitions": sum(s.repetitions for s in segments),
            "hand_count": hand,
        })  # fmt: skip
        r = rows[-1]
        print(f"{test}: blocks right {r['blocks_right'] / r['blocks']:.1%}, segments "
              f"{r['segments']} (labelled {r['labelled_stretches']}), repetitions "
              f"{r['repetitions']} (by hand {r['hand_count']})", flush=True)  # fmt: skip
    total = {k: sum(r[k] for r in rows) for k in rows[0] if k != "recording"}
    print(f"all: blocks right {total['blocks_right'] / total['blocks']:.1%}, segments "
          f"{total['segments']} (labelled {total['labelled_stretches']}), repetitions "
          f"{total['repetitions']} (by hand {total['hand_count']})")  # fmt: skip
    write_json({"benchmark": "segment_live", "command": "python -m benchmarks.segment_live",
                "total": total, "recordings": rows}, RESULTS)  # fmt: skip
    print(f"wrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
