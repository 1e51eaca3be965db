"""``posecbr dad POSEFILE``: which activity the clip shows, by the ADD's expert rules (DAD).

No training data: the QMPs fitted over sliding windows are checked against the Action
Description Database, every activity is scored by the weighted share of its QMPs seen in order,
and each one lists what was executed as expected and what was not.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from features.errors import ConfigError, PosecbrError
from features.text import counted, percent, shown
from posecbr.arguments import path_arg
from posecbr.recordings import (
    NUMPY_BELOW_FRAMES,
    add_recording_options,
    assumed_rates,
    check_asf,
    load_clip_as_asked,
    note_assumed_rates,
)

if TYPE_CHECKING:
    from features.fluents import Backend

MAX_SECONDS = 3600.0  # a window of an hour is no single movement

TOP = 5
"""The activities the text output details when ``--top`` is left out."""

LONG_CLIP_S = 10.0
"""A clip longer than this is noted: DAD gives it one answer, as ``classify`` notes a clip
longer than 10 s against a case base of windows (a clip of one exercise's repetitions lasts
less)."""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "dad",
        epilog="example: posecbr dad squat.npz --top 3",
        help="recognise the activity in a pose file with the expert rules of the ADD (DAD)",
        description="Dynamic Action Detection: fit QMPs over sliding windows, score every ADD "
        "activity by the weighted ratio of its QMPs detected in order, and list which QMPs "
        "were met and which were not.",
    )
    p.add_argument("posefile", type=path_arg, help="pose file (.npz) or a clip the loaders read")
    add_recording_options(p)  # as reps and segment read an AMC file or a rate given
    p.add_argument(
        "--add",
        type=path_arg,
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
        "--step",
        type=float,
        default=None,
        metavar="S",
        help="window step in seconds (default 1, or the window's length when shorter)",
    )
    p.add_argument(
        "--top",
        type=int,
        default=None,
        metavar="N",
        help=f"activities to detail in the text output (default {TOP}; 0 = all)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from cbr.dad import detect
    from features.qmp.add import load_add

    if args.top is not None and args.top < 0:
        raise ConfigError(f"must be >= 0, got {args.top}", "--top")
    if args.top is not None and args.json:  # as classify refuses it: it was ignored
        raise ConfigError("goes without --json (its document holds every activity)", "--top")
    config = _windows(args.window, args.step)
    check_asf(args.asf, [args.posefile])
    add = load_add(args.add)
    seq = load_clip_as_asked(args.posefile, args.asf, args.fps)
    # as describe: a short clip's state signals by the numpy reference, sooner than numba
    # loads its compiled kernels
    backend: Backend = "numpy" if seq.n_frames < NUMPY_BELOW_FRAMES else "numba"
    result = detect(seq, add, config, backend=backend)
    note_assumed_rates(assumed_rates([seq]))  # its windows, in seconds, stand on it
    if args.json:  # the document says why, for a clip DAD cannot judge too
        doc = {**result.to_dict(), "window_s": config.window_s, "step_s": config.step_s}
        json.dump(doc, sys.stdout, indent=2)
        sys.stdout.write("\n")
    if result.status != "ok":  # too short, nobody in it: nothing asked for could be done
        raise PosecbrError(f"{result.status}: {result.message}", args.posefile)
    if result.duration_s > LONG_CLIP_S:
        _note_long_clip(args.posefile.name, result.duration_s)
    if args.json:
        return 0
    # Every line quotes the clip's name and the ADD's words: printed escaped.
    for line in _text_lines(args, result, config):
        print(shown(line))
    return 0


def _note_long_clip(name: str, seconds: float) -> None:
    """Note, on stderr, that a long clip gets one answer: its activities' QMPs are sought in
    order across all its windows, so a recording of several exercises meets many activities
    in full, not its own among them (docs/measurements.md, "Figures behind the code's rules:
    DAD on a long recording")."""
    print(
        shown(
            f"note: {name} lasts {seconds:.1f} s, longer than {LONG_CLIP_S:g} s: DAD gives the"
            " whole clip one answer, each activity's QMPs sought in order across all its"
            " windows, so a recording of several activities can meet many in full; posecbr"
            " segment labels each activity of a long recording (with a case base)"
        ),
        file=sys.stderr,
    )


def _text_lines(args: argparse.Namespace, result: Any, config: Any) -> Iterator[str]:
    name = args.posefile.name
    yield (
        f"{name}: {result.duration_s:.1f} s, {counted(len(result.windows_s), 'window')} of up to "
        f"{config.window_s:g} s"
    )
    best = result.best
    if best is not None:
        tied = [a.words for a in result.tied]
        also = f"; tied with {', '.join(tied)}" if tied else ""
        unseen = best.total_weight - best.observable_weight
        seen = f"; {unseen} of its {best.total_weight} weight not observable" if unseen > 0 else ""
        share = percent(best.score, 0)
        yield f"best match: {best.words} ({share} of its QMPs in order{seen}{also})"
    else:
        yield "best match: none (no activity has any of its QMPs met in order)"
    yield ""
    yield "ranking:"
    for i, act in enumerate(result.activities, 1):
        score = f"{percent(act.score, 0):>5}" if act.score == act.score else "   - "
        yield f"  {i:2d}. {score}  {act.words}  [{', '.join(act.labels)}]"
    top = TOP if args.top is None else args.top
    detail = result.activities if top == 0 else result.activities[:top]
    mark = {"met": "+", "not met": "-", "out of order": "~", "not observable": "?"}
    for act in detail:
        yield ""
        unseen = act.total_weight - act.observable_weight
        if act.score != act.score:  # NaN: too little of it observable to score
            yield (
                f"{act.words}: not scored: only {act.observable_weight} of its "
                f"{act.total_weight} weight observable"
            )
        else:
            also = f" ({unseen} of {act.total_weight} not observable)" if unseen > 0 else ""
            yield f"{act.words}: {act.met_weight}/{act.observable_weight} weight in order{also}"
        for q in act.qmps:
            when = f" (at {q.window_s[0]:.1f}-{q.window_s[1]:.1f} s)" if q.window_s else ""
            yield f"  {mark[q.status]} {q.words} [w {q.weight}]: {q.status}{when}"
            for reason in q.reasons:
                lead = "needs " if q.status == "not met" else ""
                yield f"      {lead}{reason}"


def _windows(window: float, step: float | None) -> Any:
    """The DAD configuration of ``--window`` and ``--step`` (None: 1 s, or the window when
    shorter), or a one-line refusal of windows DAD cannot judge or that leave gaps."""
    from cbr.dad import DADConfig
    from cbr.dad.detection import default_step

    step = default_step(window) if step is None else step
    for flag, value in (("--window", window), ("--step", step)):
        if not (math.isfinite(value) and 0 < value <= MAX_SECONDS):
            raise ConfigError(f"must be in (0, {MAX_SECONDS:g}] seconds, got {value}", flag)
    shortest = DADConfig().min_duration_s
    if window < shortest:  # every window would be too short to judge
        raise ConfigError(
            f"must be at least {shortest:g} s, the shortest stretch DAD judges, got {window:g}",
            "--window",
        )
    if step > window:  # windows every --step: what lies between two is in none
        raise ConfigError(
            f"must not be longer than --window ({window:g} s), got {step:g} s: the clip"
            " between two windows would be judged by none",
            "--step",
        )
    return DADConfig(window_s=window, step_s=step)
