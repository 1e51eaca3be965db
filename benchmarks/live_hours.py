"""A robot's hours through ``watch``'s live decoder (:class:`cbr.live.LiveSegmenter`), fed
poses from Python in a loop (what ``watch`` runs after the pose model; the pose model's own
~30 ms a frame left out, so that hours of frames take minutes).

Run: ``python -m benchmarks.live_hours [MINUTES]`` (default 120: two hours at 30 fps, 216,000
frames; about 1 ms of CPU a frame). Writes ``benchmarks/results/live_hours_MINUTES.json``.

The stream, of the bundled UI-PRMD demo poses (each clip one repetition): subject s01's
first episode of each of the ten movements, looped. A quarter of it the movements in turn (8
repetitions each, then 10 s with nobody in view: the person leaves and comes back every 30
s), half of it deep squats only (one exercise in one segment), a quarter the movements in
turn again. Every fixed window votes for the movement most of its frames are of (every
activity alike where most show nobody), as a perfect classifier would, the repetition
windows left out: the decoders, counting, tally and memory are the segmenter's own.
``current()`` is asked at every frame, as ``watch --out`` draws it. Every 5 minutes of
stream: resident memory (MB), CPU ms a frame over those 5 minutes, frames kept, segments
given, the segment in progress. At the end every segment, and the squats pushed.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"  # not OpenBLAS's: the counter's own setting is what is measured

import csv  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections import deque  # noqa: E402
from collections.abc import Iterator  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
FPS = 30.0
EVERY = int(5 * 60 * FPS)


def _rss_mb() -> float:
    with open("/proc/self/statm", encoding="ascii") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def _clips() -> dict[str, np.ndarray]:
    """Subject s01's first episode of each movement, done right: one repetition each."""
    from features.poses import load_pose

    rows = list(csv.DictReader(open(DEMO / "labels.csv", encoding="utf-8")))
    return {
        r["label"]: load_pose(DEMO / r["path"]).positions
        for r in rows
        if r["subject"] == "s01" and r["episode"] == "1" and r["correct"] == "true"
    }


def _in_turn(clips: dict[str, np.ndarray]) -> Iterator[tuple[np.ndarray, str | None]]:
    gone = np.full((33, 3), np.nan)
    while True:
        for m in sorted(clips):
            for _ in range(8):
                yield from ((f, m) for f in clips[m])
            yield from ((gone, None) for _ in range(int(10 * FPS)))


def _stream(clips: dict[str, np.ndarray], total: int) -> Iterator[tuple[np.ndarray, str | None]]:
    """The stream's frames and the movement each is of (None: nobody in view)."""
    turns, n = _in_turn(clips), 0
    while n < total // 4:
        yield next(turns)
        n += 1
    while n < total // 4 + total // 2:  # whole squats: a clip begun is finished
        yield from ((f, "deep_squat") for f in clips["deep_squat"])
        n += len(clips["deep_squat"])
    turns = _in_turn(clips)
    while n < total:
        yield next(turns)
        n += 1


def _oracle(labels: np.ndarray, truth: deque[str | None]) -> Any:
    """A live segmenter whose fixed windows vote for the movement most of their frames (the
    latest in ``truth``) are of, every activity alike where most show nobody; no repetition
    windows."""
    from cbr.live import LiveSegmenter

    class Oracle(LiveSegmenter):
        def _vote(self, n: int) -> tuple[np.ndarray, float]:  # noqa: ARG002 (the latest)
            shown = [w for w in list(truth)[-self.window :] if w is not None]
            if 2 * len(shown) <= self.window:
                return np.full(self.unknown, 1.0 / self.unknown), 0.5
            vote = np.zeros(self.unknown)
            vote[self.classes.index(max(set(shown), key=shown.count))] = 1.0
            return vote, 0.0

        def _repetition_windows(self, n: int) -> None:
            """The fixed windows only."""

    case_base = type("CaseBase", (), {"labels": labels})()
    clf = type("Votes", (), {"classes_": labels, "case_base_": case_base})()
    return Oracle(clf, FPS, judge=type("Judge", (), {})())


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if args and args[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    if len(args) > 1 or (args and not (args[0].isdigit() and int(args[0]) > 0)):
        print(f"python -m benchmarks.live_hours: MINUTES must be a whole number > 0, got {args}")
        return 2
    minutes = int(args[0]) if args else 120
    total = int(minutes * 60 * FPS)
    clips = _clips()
    truth: deque[str | None] = deque(maxlen=300)
    live = _oracle(np.array(sorted(clips)), truth)
    segments: list[dict[str, Any]] = []
    log = []
    start = last = time.process_time()
    for i, (frame, what) in enumerate(_stream(clips, total)):
        truth.append(what)
        segments += [{**s.to_dict(FPS), "given_at_frame": i} for s in live.push(frame)]
        live.current()
        if (i + 1) % EVERY == 0:
            now, cur = time.process_time(), live.current()
            log.append({"minute": (i + 1) / FPS / 60, "rss_mb": round(_rss_mb(), 1),
                        "cpu_ms_a_frame": round(1000 * (now - last) / EVERY, 3),
                        "frames_kept": len(live.frames), "segments": len(segments),
                        "in_progress": None if cur is None else
                        [cur.start_frame, cur.label, cur.repetitions]})  # fmt: skip
            print(log[-1], flush=True)
            last = now
    n = live.n
    segments += [{**s.to_dict(FPS), "given_at_frame": n} for s in live.finish()]
    squat_frames = total // 2 + (-(total // 2)) % len(clips["deep_squat"])
    out = {
        "minutes": minutes,
        "frames": n,
        "every_5_minutes": log,
        "segments": segments,
        "squats_pushed": squat_frames // len(clips["deep_squat"]),
        "squats_from_frame": total // 4,
        "cpu_s": time.process_time() - start,
    }
    write_json(out, ROOT / "benchmarks" / "results" / f"live_hours_{minutes}.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
