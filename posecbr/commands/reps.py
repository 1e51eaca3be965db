"""``posecbr reps CLIP``: how many times the movement in a clip is repeated, and where each
repetition starts and ends (:mod:`features.repetitions`).

A repetition is one excursion from the rest posture to the far point of the movement and back
(a squat: down and up); a movement that alternates sides (knee raises, twists, jogging steps)
has one repetition per side. ``--json`` gives ``{"clip", "fps", "frames", "count",
"repetitions": [{"start_frame", "end_frame", "start_s", "end_s", "peak_frame", "side"}],
"period_s", "periodicity", "alternating", "moving", "partial", "cases": [{"start_frame",
"end_frame", "repetitions"}]}`` (end frames exclusive; ``"partial": true`` when no
repetition is whole but part of one is there, which does not count: a clip of the way down
of a squat counts 0, with a note on stderr; ``"cases"``: the pieces ``train --split
repetitions`` cuts the clip into, one per repetition, or of a quick movement that alternates
sides, a jog's steps, whole left-and-right cycles, a short step left over joined to the
cycle before: rows of a labels CSV that ``classify`` takes); ``--plot`` draws the
repetitions over the clip's fluent timeline.

A clip no frame of which shows the person (the torso: both shoulders and both hips) is
refused, as ``segment`` refuses it; below 5 fps a note on stderr says that a movement
repeating within two frames is not followed (its repetitions may be miscounted).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from features.text import counted, shown
from posecbr.arguments import add_plot_option, check_plot, path_arg
from posecbr.recordings import (
    NUMPY_BELOW_FRAMES,
    add_recording_options,
    assumed_rates,
    check_asf,
    load_recording,
    note_assumed_rates,
    note_low_rate,
)


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "reps",
        epilog="example: posecbr reps squat.npz --plot reps.png",
        help="count the repetitions in a clip, with each one's start and end",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("clip", type=path_arg, help="pose file, video, BVH, .amc or UI-PRMD file")
    add_recording_options(p)
    p.add_argument("--json", action="store_true", help="machine-readable output")
    add_plot_option(p, "repetitions over the fluent timeline")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from features.body import arms_alone, check_person

    check_asf(args.asf, [args.clip])
    if args.plot is not None:
        inputs = [args.clip, *([args.asf] if args.asf else [])]
        # a folder: <clip>.png in it
        args.plot = check_plot(args.plot, args.plot_folder, [args.clip], inputs, "reps")[0]
    seq = load_recording(args.clip, args.asf, args.fps)
    check_person(seq, "count", arms=True)  # as segment refuses it: a long one is not counted whole
    note_assumed_rates(assumed_rates([seq]))
    result = _count(seq)
    # how it was counted, once it was: a clip refused (shorter than one repetition can be)
    # gets its one line alone, not "counted from the arms alone" before it
    note_low_rate(seq.source, seq.fps, seq.confidence is not None)
    if arms_alone(seq):
        print(
            f"note: {shown(args.clip)}: the hips are seen in no frame (out of view): counted"
            " from the arms alone",
            file=sys.stderr,
        )
    if result.partial:
        print(
            f"note: {shown(args.clip)}: no whole repetition: the clip starts or ends part-way"
            " through the movement, and part of a repetition is not counted",
            file=sys.stderr,
        )
    if args.plot is not None:
        _plot(seq, result, args.plot, args.clip)
        # on stderr, as every command's "written to": stdout holds only the answer (--json)
        print(f"picture written to {shown(args.plot)}", file=sys.stderr)
    if args.json:
        doc = {"clip": str(args.clip), "fps": seq.fps, "frames": seq.n_frames, **result.to_dict()}
        doc["cases"] = _cases(result)
        if args.plot is not None:
            doc["plot"] = str(args.plot)
        json.dump(doc, sys.stdout, indent=1)
        print()
        return 0
    _print(args.clip, seq.fps, result)
    return 0


def _cases(result: Any) -> list[dict[str, int]]:
    """The pieces ``train --split repetitions`` cuts the clip counted ``result`` into
    (:func:`features.repetitions.case_spans`), as ``--json`` gives them: the rows of a labels
    CSV that ``classify`` takes one at a time (a jog's step alone is too short)."""
    from features.repetitions import case_spans

    return [{"start_frame": a, "end_frame": b, "repetitions": n} for a, b, n in case_spans(result)]


def _count(seq: Any) -> Any:
    """The repetitions of ``seq`` (:func:`_count_one`), counted apart on either side of each
    frame where the pose jumped to another person (:func:`features.repetitions.count_apart`)."""
    from features.repetitions import count_apart, person_jumps

    rec = seq.to_canonical()
    jumps = person_jumps(rec)
    if jumps:  # the pose jumped to another person: no movement, counted as at a cut
        return count_apart(rec, jumps, _count_one)
    return _count_one(rec)


def _count_one(rec: Any) -> Any:
    """:func:`features.repetitions.count_repetitions` of canonical ``rec``; a recording longer than
    :data:`cbr.long_clip.CHUNK_FRAMES` has its joint angles computed that many frames at a
    time, as ``segment`` reads it (the same counts in the memory of one piece: before, a
    42-minute recording at 120 fps took 1 GB, a million frames would take 3). A clip under
    :data:`posecbr.recordings.NUMPY_BELOW_FRAMES` frames has them computed by the numpy
    reference, as ``describe`` does."""
    from cbr import long_clip
    from features.derived import derived
    from features.repetitions import count_in_signals, count_repetitions, count_seen, seen_frames
    from features.signals import state_signals

    chunk = long_clip.chunk_for(rec, None)
    if not chunk:
        if rec.n_frames < NUMPY_BELOW_FRAMES:
            # as describe: a short clip's joint angles by the numpy reference (the same
            # within 1e-15), sooner than numba loads its compiled kernels (0.03 s vs 0.5 s)
            derived(rec, "signals", lambda s: state_signals(s.to_canonical(), backend="numpy"))
        return count_repetitions(rec)
    sig = long_clip.movement_signals(rec, chunk)
    a, b = seen_frames(rec, sig)  # the person lost for good: counted up to there
    if (a, b) != (0, rec.n_frames):
        return count_seen(rec, a, b, _count_one)
    return count_in_signals(sig, rec.n_frames, rec.fps)


def _print(clip: Path, fps: float, result: object) -> None:
    from features.repetitions import RepetitionCount

    assert isinstance(result, RepetitionCount)
    how = []
    if result.alternating:
        how.append("alternating sides")
    if result.repeated_period_s is not None:  # none below two repetitions, as --json
        how.append(f"period {result.repeated_period_s:.2f} s")
    if result.moving:
        how.append("moving " + ", ".join(m.replace("_", " ") for m in result.moving))
    plural = "" if result.count == 1 else "s"
    said = f" ({'; '.join(how)})" if how else ""
    print(f"{shown(clip)}: {result.count} repetition{plural}{said}")  # a name escaped
    if not result.repetitions:
        return
    print(f"  {'#':>3}  {'start s':>8}  {'end s':>7}  {'frames':>13}  {'far point s':>11}  side")
    for i, r in enumerate(result.repetitions, start=1):
        frames = f"{r.start_frame}-{r.end_frame - 1}"
        print(
            f"  {i:>3}  {r.start_frame / fps:8.2f}  {r.end_frame / fps:7.2f}  {frames:>13}"
            f"  {r.peak_frame / fps:11.2f}  {r.side or ''}"
        )


def _plot(seq: object, result: object, path: Path, clip: Path) -> None:
    from features.repetitions import RepetitionCount
    from features.timeline import Band, picture_mark, plot_timeline, timeline_of

    assert isinstance(result, RepetitionCount)
    fps = result.fps
    bands = [
        Band(
            r.start_frame / fps,
            r.end_frame / fps,
            str(i),
            r.side or ("odd" if i % 2 else "even"),
            mark_s=r.peak_frame / fps,
        )  # fmt: skip
        for i, r in enumerate(result.repetitions, start=1)
    ]
    plot_timeline(
        timeline_of(seq),  # type: ignore[arg-type]
        path,
        title=f"{clip.name}: {counted(result.count, 'repetition')} (\u25b2 far point) over the"
        " fluent timeline",
        bands=bands,
        band_title="repetitions",
        # the colours are the sides: named (odd and even ones need no legend)
        band_legend="always" if any(r.side for r in result.repetitions) else "never",
        mark=picture_mark("reps", clip),
    )
