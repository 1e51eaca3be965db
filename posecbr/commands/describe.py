"""``posecbr describe POSEFILE``: what the person is doing, in words, frame by frame."""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from typing import TYPE_CHECKING, Any, TextIO

from features.errors import ConfigError, DataError
from features.text import counted, shown
from posecbr.arguments import add_plot_option, check_plot, path_arg
from posecbr.recordings import (
    NUMPY_BELOW_FRAMES,
    add_recording_options,
    assumed_rates,
    check_asf,
    load_clip_as_asked,
    note_assumed_rates,
)

if TYPE_CHECKING:
    from pathlib import Path

    from features.fluents import Backend, FluentResult
    from features.poses import PoseSequence
    from features.timeline import Run, Timeline


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "describe",
        epilog="example: posecbr describe squat.npz --plot timeline.png",
        help="describe a pose file's posture in words, in spans of frames or frame by frame",
        description="Print when each fluent state holds (confidence >= --min-confidence): "
        "spans of frames in order of their start, states with the same span on one line; or "
        "frame by frame. A fluent whose joints the clip lacks in every frame is listed as "
        "unavailable. A clip no frame of which shows the torso (both shoulders and both hips, "
        "which place the body frame) is described by the states that need none (an elbow, "
        "a knee without the shoulders, near pairs), after a line naming the torso joints "
        'missing (--json: "no_torso", null when it is seen); one of which nothing can be '
        "described, or at micrometre scale (not metres), is refused.",
    )
    p.add_argument("posefile", type=path_arg, help="pose file (.npz) or a clip the loaders read")
    add_recording_options(p)  # as reps and segment read an AMC file or a rate given
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
        default=None,  # None: not given (refused with --per-frame, which has no spans)
        metavar="N",
        help="ignore flicker: drop spans shorter than N frames (default: 5 at 30 fps, as many "
        "as last 1/6 s at the clip's rate: 2 at 10 fps, 40 at 240 fps)",
    )
    p.add_argument(
        "--all",
        action="store_true",
        help='also show background states: no motion ("bend steady") and "far from"',
    )
    p.add_argument(
        "--thresholds",
        type=path_arg,
        metavar="FILE",
        help="JSON/TOML file overriding fluent thresholds (see `posecbr thresholds`)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    add_plot_option(p, "write a fluent timeline picture")
    p.set_defaults(func=run)


DEFAULT_MIN_RUN_S = 1 / 6
"""``--min-run``'s default as a time: five frames at 30 fps."""


def default_min_run(fps: float) -> int:
    """The frames of ``--min-run``'s default at ``fps``: :data:`DEFAULT_MIN_RUN_S`, so the
    same movement reads the same at any rate (five frames at 10 fps were half a second and
    dropped a knee's bending; at 240 fps a fiftieth and let flicker through)."""
    return max(1, round(DEFAULT_MIN_RUN_S * fps))


def _min_run(args: argparse.Namespace, fps: float) -> int:
    """The frames a span must last: 1 frame by frame, ``--min-run`` given, or the default."""
    if args.per_frame:
        return 1
    if args.min_run is None:
        return default_min_run(fps)
    return int(args.min_run)


def _check_args(args: argparse.Namespace) -> None:
    """Everything about the arguments that can be refused before any work."""
    if not 0.0 < args.min_confidence <= 1.0:
        raise ConfigError(f"must be in (0, 1], got {args.min_confidence}", "--min-confidence")
    if args.min_run is not None and args.min_run < 1:
        raise ConfigError(f"must be at least 1 frame, got {args.min_run}", "--min-run")
    if args.min_run is not None and args.per_frame:
        raise ConfigError(
            "drops short spans; --per-frame shows every frame, not spans", "--min-run"
        )
    check_asf(args.asf, [args.posefile])
    if args.plot is not None:
        inputs = [args.posefile, *[f for f in (args.thresholds, args.asf) if f is not None]]
        # a folder: <clip>.png in it
        args.plot = check_plot(args.plot, args.plot_folder, [args.posefile], inputs, "describe")[0]


NOBODY = "(nobody seen: every joint missing)"


def _run_line(r: Run, layout: FluentResult) -> str:
    from features.timeline import phrase_list

    span = f"frame {r.start}" if r.start == r.end else f"frames {r.start}–{r.end}"
    text = phrase_list(r.states, layout) if r.states else "(no state above the threshold)"
    return f"{span}: {text}"


def _header(args: argparse.Namespace, seq: PoseSequence) -> None:
    label = f", label {shown(seq.label)}" if seq.label else ""
    # the figure after each state is a confidence (0-1), said once here (as classify's
    # "confidence 0.59"): read without it, "torso upright 0.97" could be a share or a length
    print(f"{shown(args.posefile)}: {counted(seq.n_frames, 'frame')} at {seq.fps:g} fps"
          f" ({seq.duration_s:.1f} s){label}; each state with its confidence, 0-1")  # fmt: skip


def _missing_torso(seq: PoseSequence, where: Path) -> str | None:
    """None when some frame of ``seq`` shows the torso; else the torso joints it lacks in
    every frame, in words ("left hip, right hip"): what needs no body frame (an elbow, a knee
    without its shoulders, the near pairs) is still described, as the SPEC has a fluent
    whose joints a skeleton lacks reported unavailable, the others kept. A clip with every
    torso joint seen but no torso (at micrometre scale, or the four never in one frame) is
    refused as ``reps`` and ``segment`` refuse it: its states would be wrong, not missing."""
    from features.body import no_person, torso_missing, torso_share

    if torso_share(seq) > 0.0:
        return None
    gone = torso_missing(seq)
    if not gone:
        raise DataError(f"{no_person(seq)}: nothing to describe", where)
    return ", ".join(j.replace("_", " ") for j in gone)


def _nothing_to_describe(missing: str, where: Path) -> DataError:
    """The refusal of a clip that shows no person: ``missing`` (in words, "every joint" or
    the torso joints :func:`_missing_torso` names) is missing in every frame, and no state
    is left to describe."""
    return DataError(
        f"shows no person ({missing} missing in every frame): nothing to describe", where
    )


def _no_torso_line(missing: str, arms: bool) -> str:
    """The line saying what a clip without a torso is described by (``missing``: the torso
    joints it lacks, :func:`_missing_torso`; ``arms``: its arms are seen without the hips,
    :func:`features.body.arms_alone`: described in the frame of the shoulders,
    :data:`features.signals.HIPLESS`, and judged on them)."""
    if arms:
        return (
            f"no torso ({missing} missing in every frame): the arms and head are described in"
            " the frame of the shoulders and the world's up where the head is upright (not"
            " lying or bent over), nothing that needs the hips"
            " (classify, segment and reps judge the arms alone)"
        )
    return (
        f"no torso ({missing} missing in every frame): no body frame, so only the states that"
        " need none are described (classify, reps and segment refuse the clip)"
    )


def _unavailable_line(missing: list[str]) -> str:
    near = [m for m in missing if m.startswith("near:")]
    other = [m.replace("_", " ") for m in missing if not m.startswith("near:")]
    parts = other + ([f"{len(near)} near pairs"] if near else [])
    return f"unavailable (joints missing or the angle undefined in every frame): {', '.join(parts)}"


class _Spool:
    """Per-frame output kept on disk (past 32 MB) until the header is known: a long clip's
    frames are never all held in memory."""

    def __init__(self, as_json: bool, layout: FluentResult, fps: float, unseen: Any = None) -> None:
        self.as_json, self.layout, self.fps, self.unseen = as_json, layout, fps, unseen
        self.file = tempfile.SpooledTemporaryFile(max_size=32 * 1024**2, mode="w+")
        self.empty = True

    def __call__(self, run: Run) -> None:
        from features.timeline import runs_to_json

        if self.as_json:
            item = json.dumps(runs_to_json([run], self.fps)[0])
            self.file.write(item if self.empty else ",\n" + item)
        else:
            nobody = self.unseen is not None and not run.states and self.unseen[run.start]
            self.file.write(
                (f"frame {run.start}: {NOBODY}" if nobody else _run_line(run, self.layout)) + "\n"
            )
        self.empty = False

    def copy_to(self, out: TextIO) -> None:
        out.flush()
        self.file.seek(0)
        shutil.copyfileobj(self.file, out)
        self.file.close()


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from features.body import arms_alone
    from features.fluents import DEFAULT_TABLE, FluentTable, evaluate
    from features.timeline import describe_clip, picture_mark, plot_timeline

    _check_args(args)
    table = FluentTable.from_file(args.thresholds) if args.thresholds else DEFAULT_TABLE
    seq = load_clip_as_asked(args.posefile, args.asf, args.fps)
    if np.isnan(seq.positions).all():  # as classify, dad, reps and segment refuse it
        raise _nothing_to_describe("every joint", args.posefile)
    missing = _missing_torso(seq, args.posefile)
    backend: Backend = "numpy" if seq.n_frames < NUMPY_BELOW_FRAMES else "numba"
    spool = None
    if args.per_frame:  # the state names and words, from the first frame
        first = evaluate(seq.slice_frames(0, 1), table, backend="numpy")
        unseen = np.isnan(seq.positions).all(axis=(1, 2))  # (frames,): nobody in the frame
        spool = _Spool(args.json, first, seq.fps, unseen)
    min_run = _min_run(args, seq.fps)
    tl = describe_clip(
        seq, table, args.min_confidence, min_run, args.all, per_frame=spool, backend=backend
    )
    if missing is not None and len(tl.unavailable()) == len(table.specs):
        raise _nothing_to_describe(missing, args.posefile)
    note_assumed_rates(assumed_rates([seq]))  # its fluents' speeds and runs stand on it
    if args.plot:
        mark = picture_mark("describe", args.posefile)
        plot_timeline(tl, args.plot, args.min_confidence, title=args.posefile.name, mark=mark)
        # on stderr, as every command's "written to": stdout holds only the answer (--json)
        print(f"timeline written to {shown(args.plot)}", file=sys.stderr)
    if args.json:
        _print_json(args, seq, tl, spool, missing)
        return 0
    _header(args, seq)
    if missing is not None:
        print(_no_torso_line(missing, arms_alone(seq)))
    if tl.unavailable():
        print(_unavailable_line(tl.unavailable()))
    if spool is not None:
        spool.copy_to(sys.stdout)
    for r in tl.runs:
        print(_run_line(r, tl.layout))
    return 0


def _print_json(
    args: argparse.Namespace,
    seq: PoseSequence,
    tl: Timeline,
    spool: _Spool | None,
    missing: str | None,
) -> None:
    from features.timeline import runs_to_json

    out: dict[str, object] = {
        "clip": str(args.posefile),  # as classify and reps name it
        "source": str(args.posefile),  # the name it had first, kept
        "fps": seq.fps,
        "frames": seq.n_frames,
        "min_confidence": args.min_confidence,
        "unavailable": tl.unavailable(),
        # null, or the torso joints missing in every frame: only what needs no body frame
        "no_torso": missing,
        "runs": runs_to_json(tl.runs, seq.fps),
    }
    if args.plot:
        out["plot"] = str(args.plot)
    if spool is None:
        json.dump(out, sys.stdout, indent=1)
        print()
        return
    # The runs, one per frame, come from the spool into the same document.
    head = json.dumps({k: v for k, v in out.items() if k != "runs"}, indent=1)
    sys.stdout.write(head[:-2] + ',\n "runs": [\n')
    spool.copy_to(sys.stdout)
    sys.stdout.write("\n ]\n}\n")
