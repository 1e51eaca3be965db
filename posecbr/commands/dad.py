"""``posecbr dad POSEFILE``: which activity the clip shows, by the ADD's expert rules (DAD).

No training data: the QMPs fitted over sliding windows are checked against the Action
Description Database, every activity is scored by the weighted share of its QMPs seen in order,
and each one lists what was executed as expected and what was not.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from features.errors import PosecbrError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "dad",
        help="recognise the activity in a pose file with the expert rules of the ADD (DAD)",
        description="Dynamic Action Detection: fit QMPs over sliding windows, score every ADD "
        "activity by the weighted ratio of its QMPs detected in order, and list which QMPs "
        "were met and which were not.",
    )
    p.add_argument("posefile", type=Path, help="pose file (.npz) or a clip the loaders read")
    p.add_argument(
        "--add",
        type=Path,
        metavar="FILE",
        help="Action Description Database (TOML) to use instead of the shipped one",
    )
    p.add_argument(
        "--window",
        type=float,
        default=4.0,
        metavar="S",
        help="window length in seconds (default 4)",
    )
    p.add_argument(
        "--step", type=float, default=1.0, metavar="S", help="window step in seconds (default 1)"
    )
    p.add_argument(
        "--top",
        type=int,
        default=5,
        metavar="N",
        help="activities to detail in the text output (default 5; 0 = all)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from cbr.dad import DADConfig, detect
    from features.datasets import load_clip
    from features.qmp.add import load_add

    if args.top < 0:
        raise PosecbrError(f"--top must be >= 0, got {args.top}")
    for flag, value in (("--window", args.window), ("--step", args.step)):
        if not value > 0:
            raise PosecbrError(f"{flag} must be > 0 seconds, got {value}")
    add = load_add(args.add)
    config = DADConfig(window_s=args.window, step_s=args.step)
    seq = load_clip(args.posefile)
    result = detect(seq, add, config)
    out = sys.stdout
    if args.json:
        json.dump(result.to_dict(), out, indent=2)
        out.write("\n")
        return 0
    name = args.posefile.name
    if result.status != "ok":
        out.write(f"{name}: {result.status}: {result.message}\n")
        return 0
    out.write(
        f"{name}: {result.duration_s:.1f} s, {len(result.windows_s)} window(s) of up to "
        f"{config.window_s:g} s\n"
    )
    best = result.best
    if best is not None:
        out.write(f"best match: {best.words} ({best.score:.0%} of its QMPs in order)\n")
    out.write("\nranking:\n")
    for i, act in enumerate(result.activities, 1):
        score = f"{act.score:4.0%}" if act.score == act.score else "  - "
        out.write(f"  {i:2d}. {score}  {act.words}  [{', '.join(act.labels)}]\n")
    detail = result.activities if args.top == 0 else result.activities[: args.top]
    for act in detail:
        out.write(f"\n{act.words}: {act.met_weight}/{act.observable_weight} weight in order\n")
        for q in act.qmps:
            mark = {"met": "+", "not met": "-", "out of order": "~", "not observable": "?"}
            when = f" (at {q.window_s[0]:.1f}-{q.window_s[1]:.1f} s)" if q.window_s else ""
            out.write(f"  {mark[q.status]} {q.words} [w {q.weight}]: {q.status}{when}\n")
            for reason in q.reasons:
                lead = "needs " if q.status == "not met" else ""
                out.write(f"      {lead}{reason}\n")
    return 0
