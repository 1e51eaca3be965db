"""``posecbr describe POSEFILE``: what the person is doing, in words, frame by frame."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from features.errors import PosecbrError

# describe evaluates one clip in a new process: below this many frames the numpy reference
# computes the fluents sooner than numba loads its compiled kernels (measured for the whole
# command: 73 frames 0.3 s vs 0.7 s of CPU, 5000 frames 0.72 s vs 0.81 s, 10000 frames 1.04 s
# vs 0.93 s). Both give the same confidences (tests/test_fluents_fast.py).
NUMPY_BELOW_FRAMES = 5000


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "describe",
        help="describe a pose file's posture in words, in spans of frames or frame by frame",
        description="Print when each fluent state holds (confidence >= --min-confidence): "
        "spans of frames in order of their start, states with the same span on one line; or "
        "frame by frame.",
    )
    p.add_argument("posefile", type=Path, help="pose file (.npz) or a clip the loaders read")
    p.add_argument(
        "--min-confidence",
        type=float,
        default=0.8,
        metavar="C",
        help="a state is shown when its confidence is at least C (default 0.8)",
    )
    p.add_argument("--per-frame", action="store_true", help="one line per frame, not spans")
    p.add_argument(
        "--min-run",
        type=int,
        default=5,
        metavar="N",
        help="ignore flicker: drop spans shorter than N frames (default 5)",
    )
    p.add_argument(
        "--all",
        action="store_true",
        help='also show background states: no motion ("bend steady") and "far from"',
    )
    p.add_argument(
        "--thresholds",
        type=Path,
        metavar="FILE",
        help="JSON/TOML file overriding fluent thresholds (see `posecbr thresholds`)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--plot", type=Path, metavar="PNG", help="write a fluent timeline picture")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from features.datasets import load_clip
    from features.fluents import DEFAULT_TABLE, FluentTable, evaluate
    from features.timeline import (
        frame_states,
        phrase_list,
        plot_timeline,
        runs_to_json,
        state_runs,
        unavailable_fluents,
    )

    if not 0.0 < args.min_confidence <= 1.0:
        raise PosecbrError(f"--min-confidence must be in (0, 1], got {args.min_confidence}")
    table = FluentTable.from_file(args.thresholds) if args.thresholds else DEFAULT_TABLE
    seq = load_clip(args.posefile)
    result = evaluate(seq, table, backend="numpy" if seq.n_frames < NUMPY_BELOW_FRAMES else "numba")
    if args.per_frame:
        runs = frame_states(result, args.min_confidence, include_background=args.all)
    else:
        runs = state_runs(result, args.min_confidence, max(1, args.min_run), args.all)
    missing = unavailable_fluents(result)
    if args.plot:
        plot_timeline(result, args.plot, args.min_confidence, title=f"{args.posefile.name}")
    if args.json:
        out = {
            "source": str(args.posefile),
            "fps": seq.fps,
            "frames": seq.n_frames,
            "min_confidence": args.min_confidence,
            "unavailable": missing,
            "runs": runs_to_json(runs, seq.fps),
        }
        if args.plot:
            out["plot"] = str(args.plot)
        json.dump(out, sys.stdout, indent=1)
        print()
        return 0
    label = f", label {seq.label}" if seq.label else ""
    print(f"{args.posefile}: {seq.n_frames} frames at {seq.fps:g} fps ({seq.duration_s:.1f} s)"
          f"{label}")  # fmt: skip
    if missing:
        near = [m for m in missing if m.startswith("near:")]
        other = [m.replace("_", " ") for m in missing if not m.startswith("near:")]
        parts = other + ([f"{len(near)} near pairs"] if near else [])
        print(f"unavailable (joints missing): {', '.join(parts)}")
    for r in runs:
        span = f"frame {r.start}" if r.start == r.end else f"frames {r.start}–{r.end}"
        text = phrase_list(r.states, result) if r.states else "(no state above the threshold)"
        print(f"{span}: {text}")
    if args.plot:
        print(f"timeline written to {args.plot}")
    return 0
