"""``posecbr segment RECORDING... --db CB``: what was done when in a long recording, and how
many times (:mod:`cbr.segmentation`, with the classifier ``posecbr train`` stored).

Every stretch of the recording gets an activity of the case base or "unknown" (like none of
its activities, judged by the case base's own calibration), with its start and end in seconds
and frames, a confidence, the number of repetitions and a short explanation. A case base of
windows (``posecbr train ... --split windows``) matches how the recording's windows are cut;
one whose model says its cases are whole clips or repetitions is noted once on stderr
(:func:`note_not_windows`, which ``watch`` says too).

``--json`` prints ``{"recording", "fps", "frames", "segments": [{"start_s", "end_s",
"start_frame", "end_frame", "label" (null when unknown), "confidence", "unknown" (why: "nobody
in view", "no frames in the video", "unlike every activity"; null when labelled),
"repetitions", "explanation", "novelty", "repetition_frames", "count"}]}`` (a list of those for
several recordings; end frames exclusive; ``count``: the number of repetitions, as
``reps --json`` names it, and as ``repetitions`` gives it, kept from before; ``"plot"`` and
``"overlay"``: the files written, when asked for; ``"scores"``: with ``--truth``, below);
``--plot`` draws the
segments over the fluent timeline; ``--overlay`` writes a video recording with the stick figure,
the current activity and its repetition count on every frame (as ``extract --overlay`` does):
an .mp4 file, or a folder (several recordings: one ``<recording>.mp4`` each), as ``--plot``.

``--truth LABELS`` scores the segmentation against a label file of the recording (one per
recording, in order: ``--truth a.txt b.txt``, or ``--truth`` once per file; a file named as
a recording after it, ``.npz``, ``.bvh``, ``.amc`` or a video, is a recording), read as
``train --frame-labels`` reads one (one label per frame, or per ``--label-block`` seconds,
codes named by ``--label-names``), over its 0.1-s blocks. Labels of ``--label-block`` seconds
are per time: each block takes the label at its own time, so a recording thinned to a few
frames a second (``--fps 2``) is scored on the same blocks as at its full rate, the labels
fitting it when they reach its last frame's time (a file cut short is refused). The figures:
the share of blocks of activities the case base has that got their label (a block called
unknown counts wrong), the share of blocks of labels it lacks that were called unknown, and
each labelled change's distance to the nearest segment boundary (median), as ``python -m
benchmarks.segment`` scores them (:func:`cbr.evaluation.segments.score_segmentation`).
``--json`` gives them as
``"scores": {"truth", "blocks", "block_s", "seen_blocks", "seen_right", "seen_accuracy",
"unseen_labels", "unseen_blocks", "unseen_called_unknown", "unseen_unknown_share",
"blocks_called_unknown", "boundary_errors_s", "median_boundary_error_s"}`` (a share of no
blocks, and a distance when no segment boundary was found: null). A label file with no label
of the case base's is noted on stderr (codes without ``--label-names``?).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from cbr.judges import JUDGES
from features.errors import ConfigError, DataError
from features.fileio import check_output, path_exists
from features.formats import SHOWN_VIDEO_SUFFIXES
from features.text import counted, shown
from posecbr.arguments import (
    DB,
    PathOption,
    add_k_option,
    add_plot_option,
    as_options,
    check_mp4_name,
    check_plot,
    path_arg,
    plot_targets,
)
from posecbr.recordings import (
    add_recording_options,
    assumed_rates,
    check_asf,
    check_fps,
    load_recording,
    note_assumed_rates,
    note_low_rate,
)


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "segment",
        epilog="example: posecbr segment workout.npz --db windows.sqlite --plot timeline.png",
        help="label every stretch of long recordings with an activity or unknown, and count",
        description=__doc__,
        formatter_class=_Formatter,
    )
    p.add_argument(
        "recordings",
        nargs="*",  # a recording may come after --truth (_Truth): checked given in run
        action=_Recordings,
        default=[],
        type=path_arg,
        metavar="RECORDING",
        help="pose file, video, BVH, .amc",
    )
    p.add_argument("--db", required=True, help="case base file (SQLite) or SQLAlchemy URL")
    p.add_argument("--name", default=None, help="case base name (default: the only one)")
    add_recording_options(p)
    add_k_option(
        p,
        1,
        ", in each window, as classify -k N in a clip (default 1; at most the case base's own"
        " k, the nearest cases a window retrieves, which `posecbr casebase info` shows and"
        " the explanations count)",
    )
    p.add_argument(
        "--unknown",
        choices=JUDGES,
        default=JUDGES[0],
        metavar="RULE",
        help="what makes a stretch unknown: its nearest activity is hardly nearer than the "
        "next, times how far the window lies from that activity in its own spread, beyond "
        "that activity's own threshold, from its rightly named training cases held out of "
        "their own recording or person (spread-margin, the default: calibrated on the case "
        "base, at most 5 %% of those lie beyond; with a case base of one person the same as "
        "activity-margin), the margin alone against such thresholds (activity-margin), or "
        "beyond one threshold for all activities (margin), farther from its nearest case than "
        "held-out training clips lie (held-out, the flag classify gives), as far as the case "
        "base's activities lie from each other (activities), or the margin alone or a smaller "
        "margin with a far nearest case, sharing the 5 %% (margin-distance), or spread-margin "
        "or a nearest case farther than 5 %% of those lie (spread-far)",
    )
    p.add_argument(
        "--truth",
        type=path_arg,
        nargs="+",
        action=_Truth,
        metavar="LABELS",
        help="score the segments against the recording's true labels: a label file as train"
        " --frame-labels reads (one label per frame, or per --label-block seconds); several"
        " recordings: one file each, in their order (--truth a.txt b.txt, or --truth a.txt"
        " --truth b.txt); a file named as a recording (.npz, .bvh, .amc, a video) after it is"
        " a recording, not a label file",
    )
    p.add_argument(
        "--label-block",
        type=float,
        metavar="SECONDS",
        help="seconds per label of --truth (default: one label per frame); labels per time fit"
        " the recording at any frame rate (thinned to 2 fps, --fps 2)",
    )
    p.add_argument(
        "--label-names", type=path_arg, metavar="FILE", help="'code name' per line, for --truth"
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    add_plot_option(p, "segments over the fluent timeline", several=True)
    p.add_argument(
        "--overlay",
        action=PathOption,
        metavar="OUT.mp4|DIR",
        help="a video recording with the stick figure, activity and count drawn: an .mp4"
        " file, or a folder (one there, a name ending in /, or several recordings): one"
        " <recording>.mp4 each in it, the folder made if it is not there, as --plot",
    )
    p.set_defaults(func=_given(p), overlay_folder=False)


#: what a file named as a recording ends in: never a label file (text), so one after
#: ``--truth`` is a recording (``segment --truth L.txt REC.npz``), not read as labels
RECORDING_SUFFIXES = frozenset({".npz", ".bvh", ".amc", *SHOWN_VIDEO_SUFFIXES})


class _Recordings(argparse.Action):
    """RECORDING...: added to those already given after ``--truth`` (:class:`_Truth`), in the
    order of the command line. ``needed``: missing when none is given, said with the other
    arguments missing (:meth:`posecbr.cli.Parser.error`), though argparse takes it as
    optional."""

    needed = True

    def __call__(
        self, _parser: Any, namespace: argparse.Namespace, values: Any, _option: Any = None
    ) -> None:
        setattr(namespace, self.dest, [*getattr(namespace, self.dest), *values])


class _Truth(argparse.Action):
    """``--truth LABELS...`` (repeatable): the label files, and any file after it named as a
    recording (:data:`RECORDING_SUFFIXES`) given back to the recordings. It took every name
    after it: ``segment --truth L.txt REC.npz --db CB`` read REC.npz as a label file."""

    repeatable = True  # --truth a.txt --truth b.txt: one label file per recording

    def __call__(
        self, _parser: Any, namespace: argparse.Namespace, values: Any, _option: Any = None
    ) -> None:
        truth = list(namespace.truth or [])
        for path in values:
            if path.suffix.lower() in RECORDING_SUFFIXES:
                namespace.recordings = [*namespace.recordings, path]
            else:
                truth.append(path)
        if len(truth) == len(namespace.truth or []):  # every name after it a recording
            raise argparse.ArgumentError(
                self, f"{values[0]} is named as a recording, not a label file: give LABELS"
            )
        namespace.truth = truth


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """The usage says RECORDING is needed (it is ``nargs="*"`` to argparse: see :class:`_Truth`)."""

    def _format_args(self, action: argparse.Action, default_metavar: str) -> str:
        if action.dest == "recordings":
            return "RECORDING [RECORDING ...]"
        return super()._format_args(action, default_metavar)


def _given(parser: argparse.ArgumentParser) -> Any:
    """:func:`run`, after the check argparse made when RECORDING was ``nargs="+"``: a command
    line without a recording is refused as one that cannot be read (exit 2)."""

    def given(args: argparse.Namespace) -> int:
        if not args.recordings:
            parser.error("the following arguments are required: RECORDING")
        return run(args)

    return given


def _inputs_given(args: argparse.Namespace) -> None:
    """Refuse options that do not fit the recordings, and missing recordings, before any
    is read."""
    check_fps(args.fps)
    check_asf(args.asf, args.recordings)
    _truth_options(args)
    for path in args.recordings:
        if not path_exists(path):
            raise DataError("no such file", path)


def _truth_options(args: argparse.Namespace) -> None:
    """Refuse ``--label-block`` / ``--label-names`` without ``--truth``, a block that is no
    length, and a count of label files other than the recordings'."""
    for option, value in (("--label-block", args.label_block), ("--label-names", args.label_names)):
        if value is not None and args.truth is None:
            raise ConfigError("goes with --truth (the label files it reads)", option)
    block = args.label_block
    if block is not None and not (math.isfinite(block) and block > 0):
        raise ConfigError(f"must be a finite number of seconds > 0, got {block:g}", "--label-block")
    if args.truth is not None and len(args.truth) != len(args.recordings):
        raise ConfigError(
            f"{counted(len(args.truth), 'label file')} for"
            f" {counted(len(args.recordings), 'recording')}: --truth takes one per recording,"
            " in their order",
            "--truth",
        )


def _read_truths(args: argparse.Namespace) -> list[list[str]] | None:
    """The labels of every ``--truth`` file (through ``--label-names``), read as ``train
    --frame-labels`` reads one, before any recording is read: a malformed file is one error
    at once, not after a video's poses are estimated."""
    from features.label_tracks import read_label_names, read_label_track

    if args.truth is None:
        return None
    names = read_label_names(args.label_names) if args.label_names is not None else None
    return [read_label_track(path, names) for path in args.truth]


def _check_truths_fit(args: argparse.Namespace, labels: list[list[str]] | None) -> None:
    """Refuse a ``--truth`` file whose count does not fit its recording where the frames are
    known before the recording is read (a pose file's header, a constant-rate video's
    container: :func:`features.stretches.check_fits_before_read`), before a video's poses are
    estimated; the others are checked once read (:func:`_fitted_truths`)."""
    from features.stretches import check_fits_before_read

    for track, path, recording in zip(
        labels or [], args.truth or [], args.recordings, strict=False
    ):
        check_fits_before_read(
            recording, len(track), args.label_block, path, shown(recording), args.fps
        )


def _fitted_truths(
    args: argparse.Namespace, labels: list[list[str]] | None, recs: list[Any]
) -> list[Any]:
    """Every recording's true label per :data:`cbr.segmentation.BLOCK_S` block (None without
    ``--truth``); a label file whose count does not fit its recording is refused naming it,
    before any recording is segmented."""
    if labels is None:
        return [None] * len(recs)
    from cbr.evaluation.segments import label_blocks, truth_blocks
    from cbr.segmentation import BLOCK_S
    from features.label_tracks import assumed_rate, frame_labels

    out = []
    for track, rec, path, recording in zip(labels, recs, args.truth, args.recordings, strict=True):
        per_frame = frame_labels(
            track, rec.n_frames, rec.fps, args.label_block, path, shown(recording),
            assumed_rate(rec.metadata),
        )  # fmt: skip
        if args.label_block is None:  # one label per frame
            out.append(truth_blocks(per_frame, rec.fps, BLOCK_S))
        else:  # one per time: read at each block's time, whatever the frame rate
            out.append(label_blocks(track, args.label_block, rec.n_frames, rec.fps, BLOCK_S))
    return out


def _outputs(args: argparse.Namespace) -> list[Path | None]:
    """Refuse bad output paths before any work; where each recording's overlay goes (None
    without ``--overlay``: :func:`_overlay_targets`)."""
    if args.k < 1:
        raise ConfigError(f"must be >= 1, got {args.k}", "-k")
    if args.plot is not None:
        if len(args.recordings) > 1:  # a folder for their pictures, made if not there
            if args.plot.exists() and not args.plot.is_dir():
                raise DataError(
                    "with several recordings --plot names a folder for their pictures; this"
                    " one is a file",
                    args.plot,
                )
            args.plot_folder = True
        check_plot(args.plot, args.plot_folder, args.recordings, _inputs(args), "segment")
    return _overlay_targets(args)


def _overlay_targets(args: argparse.Namespace) -> list[Path | None]:
    """Where each recording's ``--overlay`` goes, refused before any work: the .mp4 file
    named, or in a folder (one there, a name ending in "/", or several recordings: made if
    it is not there) one ``<recording>.mp4`` each, named as ``--plot DIR`` names pictures
    (:func:`plot_targets`). A recording that is no video has nothing to draw on; an overlay
    may not be an input; a file at an overlay's place in the folder is replaced only when it
    is the overlay segment drew there of that same recording (:func:`overlay_mark`), as
    ``extract --overlay DIR`` replaces only its own. Before, a folder was refused ("name the
    .mp4 file to write in it") and so were several recordings ("--overlay takes one
    recording")."""
    from features.clips import VIDEO_SUFFIXES

    overlay = args.overlay
    if overlay is None:
        return [None] * len(args.recordings)
    inputs = _inputs(args)
    several = len(args.recordings) > 1
    if not (args.overlay_folder or overlay.is_dir() or several):
        try:
            check_mp4_name(overlay, False, "overlay")
        except DataError as exc:
            if overlay.suffix or overlay.exists():
                raise
            made = f"; a folder to be made for it is written ending in / ({overlay}/)"
            raise DataError(exc.message + made, overlay) from None
        check_output(overlay, inputs=inputs, what="overlay")
        targets = [overlay]
    else:
        targets = _overlay_folder(args, inputs, several)
    for path in args.recordings:
        if path.suffix.lower() not in VIDEO_SUFFIXES:
            raise DataError("--overlay needs a video recording", path)
    return list(targets)


def _overlay_folder(args: argparse.Namespace, inputs: list[Path], several: bool) -> list[Path]:
    """The overlays in the folder ``--overlay`` names (:func:`_overlay_targets`)."""
    overlay = args.overlay
    if several and overlay.exists() and not overlay.is_dir():
        raise DataError(
            "with several recordings --overlay names a folder for their overlays; this one"
            " is a file",
            overlay,
        )
    if several and overlay.suffix.lower() in SHOWN_VIDEO_SUFFIXES and not overlay.is_dir():
        raise DataError(
            "with several recordings --overlay names the folder for their overlays"
            " (<recording>.mp4 each), not one video file",
            overlay,
        )
    targets = plot_targets(overlay, args.recordings, True, ".mp4")
    for target, recording in zip(targets, args.recordings, strict=True):
        check_output(target, inputs=inputs, what="overlay", make_parents=True)
        _check_own_overlay(overlay, target, recording)
    return targets


def overlay_mark(recording: Path) -> str:
    """What an overlay segment draws of ``recording`` is marked with
    (:func:`features.pose_estimation.overlay.mark_mp4`), as ``extract``'s overlays and the
    pictures ``--plot`` draws are (:func:`features.timeline.picture_mark`): the command and
    a digest of the recording's resolved path."""
    from features.timeline import picture_mark

    return picture_mark("segment", recording)


def _check_own_overlay(folder: Path, target: Path, recording: Path) -> None:
    """Refuse a file at ``target``, the place the folder ``folder`` (``--overlay DIR``)
    gives ``recording``'s overlay, unless it is the overlay segment drew there of that same
    recording (run again: brought up to date): another command's overlay (``extract``'s),
    another recording's, a link or a file of the user's is not replaced in silence."""
    from features.pose_estimation.overlay import mp4_mark

    if not (target.exists() or target.is_symlink()):
        return
    if target.is_symlink() or mp4_mark(target) != overlay_mark(recording):
        raise DataError(
            f"is already there, not an overlay posecbr segment drew of"
            f" {shown(recording)}: --overlay {shown(folder)} would replace it; move it"
            " away, or choose another folder",
            target,
        )


def _inputs(args: argparse.Namespace) -> list[Path]:
    """What segmenting reads: the recordings, the case base's files (a ``sqlite:///`` URL's
    too) and the skeleton file."""
    from casebase_store import store_files

    asf = [args.asf] if args.asf is not None else []
    truth = [*(args.truth or []), *([args.label_names] if args.label_names is not None else [])]
    return [*args.recordings, *store_files(args.db), *asf, *truth]


def check_k_option(clf: Any, k: int) -> None:
    """:func:`cbr.segmentation.check_k` of ``-k``: its refusal names the option typed, where
    a Python caller's names the argument ``k``."""
    from cbr.segmentation import check_k

    with as_options({"k": "-k"}):
        check_k(clf, k)


#: the arguments :func:`cbr.unknown.judge_of`'s refusals name, as the options that set them
JUDGE_OPTIONS = {"name": "--unknown", "cases": "--split"}


def judge_named(clf: Any, name: str, db: str, command: str | None = None) -> Any:
    """The judge called ``name`` (``--unknown``) of the model stored in ``db``; a case base
    it cannot be calibrated on is refused naming the database (of a repetition check, for
    ``command`` "segment", with how its recording is judged repetition by repetition)."""
    from casebase_store import shown_db
    from cbr.unknown import judge_of

    try:
        with as_options(JUDGE_OPTIONS):  # its advice: --unknown held-out, train --split windows
            return judge_of(clf, name)
    except DataError as exc:
        if exc.source != "case base":
            raise
        message = f"its case base cannot judge unknown: {exc.message}"
        if command == "segment" and is_repetition_check(clf):
            message += f"; {each_repetition_hint(db)}"
        raise DataError(message, shown_db(db)) from None


def is_repetition_check(clf: Any) -> bool:
    """Whether ``clf`` judges repetitions (trained with ``--target`` another column than the
    activity, ``train --target correct``) rather than naming activities."""
    return getattr(clf, "target_", None) not in (None, "label")


def each_repetition_hint(db: str) -> str:
    """How a recording is judged repetition by repetition against the case base of ``db``,
    a repetition check (:func:`is_repetition_check`)."""
    from casebase_store import shown_db

    return (
        "to judge and explain each repetition by itself: posecbr classify RECORDING --db "
        f"{shown_db(db)} --split repetitions"
    )


def run(args: argparse.Namespace) -> int:
    _inputs_given(args)
    overlays = _outputs(args)
    stored = load_case_base(args.db, args.name)  # a case base file not there: before the imports
    from cbr.segmentation import check_segmentable, segment, shoulders_up

    clf = stored.classifier
    check_k_option(clf, args.k)  # before any recording is read (a video's poses take seconds)
    judge = judge_named(clf, args.unknown, args.db, "segment")
    labels = _read_truths(args)
    _check_truths_fit(args, labels)
    # every recording read and checked before any is segmented (a bad one among several is
    # refused before the work on the others), and segmented before any picture is drawn (it
    # leaves no picture of the others behind)
    read = [
        _read(path, args, overlay) for path, overlay in zip(args.recordings, overlays, strict=True)
    ]
    for rec, _ in read:
        check_segmentable(rec)
    truths = _fitted_truths(args, labels, [rec for rec, _ in read])
    note_assumed_rates(assumed_rates(rec for rec, _ in read))  # one line for them all
    for (rec, _), path in zip(read, args.recordings, strict=True):
        note_low_rate(rec.source, rec.fps, rec.confidence is not None)
        if shoulders_up(rec):  # as reps says it: the labels stand on the arms alone
            print(
                f"note: {shown(path)}: the hips are seen in no frame (out of view): labelled"
                " from the arms alone",
                file=sys.stderr,
            )
    done = [
        (rec, video, _named(segment(clf, rec, judge, k=args.k), path))
        for (rec, video), path in zip(read, args.recordings, strict=True)
    ]
    scores = _all_scores(args, [result for _, _, result in done], truths, clf.classes_)
    targets: list[Path | None] = [None] * len(done)
    if args.plot is not None:
        targets = list(plot_targets(args.plot, args.recordings, args.plot_folder))
    _write_all(done, args.recordings, targets, overlays, [str(c) for c in clf.classes_])
    # once, for every recording, when all is done (interrupted or refused on the way: one line)
    note_not_windows(stored, args.db, "segment")
    docs = [result for _, _, result in done]
    truth_files: list[Path | None] = list(args.truth) if args.truth else [None] * len(docs)
    if args.json:
        out = [
            _document(r, target, overlay, score, truth)
            for r, target, overlay, score, truth in zip(
                docs, targets, overlays, scores, truth_files, strict=True
            )
        ]
        json.dump(out[0] if len(out) == 1 else out, sys.stdout, indent=1, ensure_ascii=False)
        print()
        return 0
    for result, score, truth in zip(docs, scores, truth_files, strict=True):
        _print(result)
        if score is not None and truth is not None:
            _print_scores(score, truth)
    return 0


def _all_scores(
    args: argparse.Namespace, results: list[Any], truths: list[Any], classes: Any
) -> list[Any]:
    """Each recording's ``--truth`` scores (None without), a truth with no label of the case
    base's noted on stderr."""
    scores = [
        _scores(result, truth, classes) if truth is not None else None
        for result, truth in zip(results, truths, strict=True)
    ]
    for score, truth_file in zip(scores, args.truth or [], strict=False):
        _note_none_known(score, truth_file, [str(c) for c in classes], args.label_names)
    return scores


def _scores(result: Any, truth: Any, classes: Any) -> Any:
    from cbr.evaluation.segments import score_segmentation
    from cbr.segmentation import BLOCK_S

    return score_segmentation(result, truth, [str(c) for c in classes], BLOCK_S)


def _note_none_known(scores: Any, truth: Path, activities: list[str], names: Path | None) -> None:
    """Say on stderr when none of the ``truth`` file's labels is one of the case base's
    ``activities``: every block is then scored as a label the case base lacks, which a
    label file of codes read without its names (``--label-names``) gives without a word."""
    from posecbr.arguments import listed, whole_numbers

    if scores.seen_blocks or not scores.blocks:
        return
    labels = list(scores.unseen_labels)  # 1, 2, 10: as a user counts them
    text = (
        f"note: {shown(truth)}: none of its labels ({listed(labels)}) is an activity of the"
        f" case base ({listed(activities)}): every block is scored as a label it lacks"
    )
    if names is None and whole_numbers(labels):
        text += "; if they are codes, --label-names FILE names them"
    print(text, file=sys.stderr)


def _document(
    result: Any,
    plot: Path | None,
    overlay: Path | None,
    scores: Any = None,
    truth: Path | None = None,
) -> dict[str, Any]:
    """One recording's ``--json`` document, with the files written for it named, as
    ``describe`` and ``reps`` name their picture, and its ``--truth`` scores."""
    doc: dict[str, Any] = result.to_dict()
    if plot is not None:
        doc["plot"] = str(plot)
    if overlay is not None:
        doc["overlay"] = str(overlay)
    if scores is not None:
        doc["scores"] = {"truth": str(truth), **scores.to_dict()}
    return doc


def _share(part: int, whole: int, what: str) -> str:
    return f"{part} of {whole} blocks {what} ({100 * part / whole:.1f} %)"


def _print_scores(scores: Any, truth: Path) -> None:
    """The ``--truth`` scores, under the segments."""
    print(f"  against {shown(truth)}: {counted(scores.blocks, 'block')} of {scores.block_s:g} s")
    if scores.seen_blocks:
        right = _share(scores.seen_right, scores.seen_blocks, "labelled right")
        print(f"    labels the case base has: {right}")
    else:
        print("    labels the case base has: none in the truth")
    if scores.unseen_blocks:
        lacks = ", ".join(shown(label) for label in scores.unseen_labels)
        unknown = _share(scores.unseen_unknown, scores.unseen_blocks, "called unknown")
        print(f"    labels it lacks ({lacks}): {unknown}")
    else:
        print("    labels it lacks: none in the truth")
    errors = scores.boundary_errors_s
    if not errors:
        print("    labelled changes: none")
    elif not math.isfinite(max(errors)):
        print(f"    labelled changes: {len(errors)}; no segment boundary found")
    else:
        print(
            f"    labelled changes: {len(errors)}, the nearest segment boundary a median"
            f" {scores.median_boundary_error_s:.2f} s away (at most {max(errors):.2f} s)"
        )


def _read(path: Path, args: argparse.Namespace, overlay: Path | None) -> tuple[Any, Any]:
    """The recording (canonical) and, for a video with an ``overlay`` to draw (a video:
    :func:`_overlay_targets`), its image landmarks."""
    if overlay is not None:
        from features.pose_estimation import estimate_video, open_video
        from features.pose_estimation.overlay import check_mp4_size

        cap, info = open_video(path)  # a size MP4 cannot take is refused before the model runs
        cap.release()
        check_mp4_size(info.width, info.height, overlay)
        found = estimate_video(path)
        seq = found.sequence.to_canonical()
        return (seq if args.fps is None else dataclasses.replace(seq, fps=args.fps)), found
    return load_recording(path, args.asf, args.fps), None


def _named(result: Any, path: Path) -> Any:
    return dataclasses.replace(result, recording=str(path))


def _print(result: Any) -> None:
    fps = result.fps
    print(
        f"{shown(result.recording)}: {result.n_frames} frames at {fps:g} fps "
        f"({result.n_frames / fps:.2f} s), {counted(len(result.segments), 'segment')}"
    )
    labels = [shown(s.label) if s.label is not None else f"({_shown(s)})" for s in result.segments]
    # as wide as the longest (an activity's long name, "(no frames in the video)"): the
    # columns after it stay in line
    wide = max([20, *(len(label) for label in labels)])
    print(
        f"  {'start s':>8}  {'end s':>7}  {'frames':>12}  {'activity':<{wide}} {'conf':>5}"
        f"  {'reps':>4}"
    )
    for s, label in zip(result.segments, labels, strict=True):
        frames = f"{s.start_frame}-{s.end_frame - 1}"
        print(
            f"  {s.start_frame / fps:8.2f}  {s.end_frame / fps:7.2f}  {frames:>12}  "
            f"{label:<{wide}} {s.confidence:5.2f}  {len(s.repetitions):>4}"
        )
        if s.explanation and s.explanation != _shown(s):
            print(f"  {'':8}  {'':7}  {'':12}  {shown(s.explanation)}")


def _shown(segment: Any) -> str:
    """What a segment is called on pictures: its activity, "nobody in view", "no frames in
    the video", or unknown."""
    from cbr.segmentation import NO_FRAMES, NOBODY

    if segment.label is not None:
        return str(segment.label)
    return segment.explanation if segment.explanation in (NOBODY, NO_FRAMES) else "unknown"


def _bands(result: Any) -> list[Any]:
    from features.timeline import Band

    fps = result.fps
    return [
        Band(s.start_frame / fps, s.end_frame / fps, f"{_shown(s)} x{len(s.repetitions)}", s.label)
        for s in result.segments
    ]


def _write_all(
    done: list[tuple[Any, Any, Any]],
    recordings: list[Path],
    targets: list[Path | None],
    overlays: list[Path | None],
    activities: Sequence[str],
) -> None:
    """Every picture (``targets``) and overlay of the recordings segmented (``done``:
    recording, video, result) written as one (:func:`features.fileio.write_together`): all
    of them or, one failing (a full disk, Ctrl-C, SIGTERM), none, each file there before
    left as it was and a folder made for them removed, as a recording refused leaves no
    output of the others (:func:`run`). Each is said once all are in place. Before, they
    were written in turn: the files of the recordings before one that failed were left."""
    from features.fileio import folders_to_make, remove_empty, write_together
    from features.pose_estimation.overlay import padding_words

    files: list[tuple[Path, Callable[[Path], object]]] = []
    said: list[str] = []
    for (rec, video, result), path, target, overlay in zip(
        done, recordings, targets, overlays, strict=True
    ):
        if target is not None:
            files.append((target, functools.partial(_plot, rec, result, recording=path,
                                                     activities=activities)))  # fmt: skip
            said.append(f"timeline written to {shown(target)}")
        if overlay is not None:
            files.append((overlay, functools.partial(_overlay, path, video, result,
                                                     activities=activities)))  # fmt: skip
            padded = padding_words(video.info.width, video.info.height)
            said += [f"note: {shown(overlay)}: {padded}"] if padded else []
            said.append(f"overlay written to {shown(overlay)}")
    if not files:
        return
    made = folders_to_make([dest for dest, _ in files])  # --plot DIR/, --overlay DIR/
    try:
        write_together(files, suffixed=True, make_parents=True)
    except BaseException:
        remove_empty(made)
        raise
    for line in said:
        print(line, file=sys.stderr)


def _plot(
    rec: Any, result: Any, path: Path, recording: Path, activities: Sequence[str] = ()
) -> None:
    """The timeline picture of ``result`` (of ``recording``); ``activities``: the case base's,
    in the order that gives each its colour (one colour per activity in every picture of one
    case base)."""
    from features.timeline import picture_mark, plot_timeline, timeline_of

    plot_timeline(
        timeline_of(rec),
        path,
        title=f"{recording.name}: activities and repetition counts over the fluent timeline",
        bands=_bands(result),
        band_title="activity",
        max_rows=30,
        band_keys=activities,
        band_legend="hidden",
        mark=picture_mark("segment", recording),
    )


def overlay_label(text: str, key: str | None, colours: Mapping[str, Any]) -> str:
    """``text`` as the overlays write an activity: on a box of ``key``'s colour in ``segment
    --plot`` (``colours``: :func:`features.timeline.band_colours`, the case base's activities
    in order), the plot's light grey when no activity is known (unknown, nobody in view, no
    frames). Before, every label was white: an unknown stretch looked like any activity."""
    from matplotlib.colors import to_rgb

    from features.pose_estimation.overlay import Label
    from features.timeline import UNKNOWN_COLOUR

    colour = colours.get(key, UNKNOWN_COLOUR) if key is not None else UNKNOWN_COLOUR
    return Label(text, tuple(round(255 * c) for c in to_rgb(colour)))


def frame_words(
    result: Any, gaps: Any = None, unseen: Any = None, activities: Sequence[str] = ()
) -> list[list[str]]:
    """Per frame: the current activity (or unknown, or nobody in view) and how many of its
    repetitions are done: a repetition counts from its last frame (ends are exclusive; one
    that runs to its segment's end is done within the segment, as ``segment`` counts it).
    ``gaps``: per frame, whether it lies inside a gap of the video's frames
    (:func:`features.poses.gap_rows`): such a frame says "no frames in the video" in place of
    the activity, as ``watch`` draws it. ``unseen``: per frame, whether no landmark is there
    to draw: in a stretch with nobody in view such a frame says "no person" alone (the
    overlay writes it where the stick figure would be), as ``watch`` draws it, not "nobody
    in view" below it as well. The activity is an :func:`overlay_label`, coloured as
    ``segment --plot`` colours it (``activities``: the case base's, in order)."""
    import numpy as np

    from cbr.segmentation import NO_FRAMES, NOBODY
    from features.timeline import band_colours

    colours = band_colours(_bands(result), activities)
    words: list[list[str]] = [[] for _ in range(result.n_frames)]
    gap_word = overlay_label(NO_FRAMES, None, colours)
    for s in result.segments:
        label = overlay_label(_shown(s), s.label, colours)
        ends = np.sort([r.end_frame - 1 for r in s.repetitions]).astype(np.int64)
        frames = np.arange(s.start_frame, s.end_frame)
        done = np.searchsorted(ends, frames, side="right")
        for f, n in zip(frames.tolist(), done.tolist(), strict=True):
            shown_label = gap_word if gaps is not None and gaps[f] else label
            words[f] = [shown_label, f"repetitions: {n}"]
            if shown_label == NOBODY and unseen is not None and unseen[f]:
                words[f] = words[f][1:]  # draw_pose says "no person"
    return words


def load_stored(db: str, name: str | None) -> Any:
    """The classifier stored as case base ``name`` in ``db`` (the only one when None)."""
    return load_case_base(db, name).classifier


def load_case_base(db: str, name: str | None) -> Any:
    """The case base ``name`` stored in ``db`` (the only one when None), as
    :func:`cbr.stored.load_classifier` loads it: its classifier and what its cases are."""
    from casebase_store import open_store

    with as_options(DB):
        store = open_store(db, create=False, readonly=True)
    try:
        if name is None:
            names = [cb.name for cb in store.list_case_bases()]
            if len(names) != 1:
                held = (
                    f"case bases {', '.join(names)}: choose one with --name"
                    if names
                    else ("no case base (run posecbr train)")
                )
                raise ConfigError(f"the store holds {held}", store.where)
            name = names[0]
        from cbr.stored import load_classifier  # the classifier's modules: the store opened

        return load_classifier(store, name)
    finally:
        store.close()


def note_not_windows(stored: Any, db: str, command: str, each: bool = False) -> None:
    """Note, on stderr, a case base whose cases are whole clips or repetitions (``train``
    without ``--split`` or ``--split repetitions``; its model records it): ``command``
    (``segment``, ``watch``) classifies 2-s windows, which such cases answer worse, why, and
    how to train a case base of windows. Said once per command; a case base stored before
    its cases were recorded (``cases`` None) or of windows says nothing. A repetition check
    (``train --target correct``) is noted by ``segment`` instead with how each repetition is
    judged (``classify --split repetitions``): windows of it would not help; by ``watch``
    with how it judges each (``--split repetitions``), unless it does (``each``)."""
    from casebase_store import shown_db
    from cbr.words import CASE_KINDS
    from features.repetitions import WINDOW_S

    why = {  # the figures: README, "Training from long recordings" (hunt 39m, 44j)
        "clips": "a clip of many repetitions is one case, far from any window of it: expect "
        "far fewer windows labelled right than",
        "repetitions": "a repetition is one case from rest to rest, where a window starts "
        "anywhere in a movement: expect fewer windows labelled right than",
    }
    if command == "watch" and is_repetition_check(stored.classifier):
        if not each:  # --split repetitions: each repetition judged by the case base as trained
            print(
                f"note: case base {stored.name!r} of {shown_db(db)} predicts {stored.target!r},"
                " not activities: watch labels 2-s windows with it; to judge and explain each"
                " repetition as it finishes: add --split repetitions",
                file=sys.stderr,
            )
        return
    if command == "segment" and is_repetition_check(stored.classifier):
        print(
            f"note: case base {stored.name!r} of {shown_db(db)} predicts {stored.target!r}, "
            f"not activities: segment labels 2-s windows with it; "
            f"{each_repetition_hint(db)}",
            file=sys.stderr,
        )
        return
    if stored.cases not in why:
        return
    where = shown_db(db)
    source = "the stream" if command == "watch" else "a recording"
    print(
        f"note: case base {stored.name!r} of {where} holds a case per "
        f"{CASE_KINDS[stored.cases]}: {command} classifies {WINDOW_S:g}-s windows of "
        f"{source}, not whole {stored.cases} ({why[stored.cases]} with a case per window;"
        ' README, "Training from long recordings"); to train a case base of windows: '
        f"posecbr train DATA --db {where} --name NAME --split windows",
        file=sys.stderr,
    )


def _overlay(
    path: Path, video: Any, result: Any, out: Path, activities: Sequence[str] = ()
) -> None:
    """The overlay video of ``result`` (of the video ``path``), marked as segment's
    (:func:`overlay_mark`); ``activities``: the case base's, in the order that gives each
    its colour, as in ``segment --plot``."""
    import numpy as np

    from features.pose_estimation.overlay import write_overlay
    from features.poses import gap_rows

    gaps = gap_rows(video.sequence)  # no frames there: said so, not "no person"
    write_overlay(
        path,
        video.image_landmarks,
        out,
        result.fps,
        frame_words(
            result, gaps, np.isnan(video.image_landmarks[..., :2]).all(axis=(1, 2)), activities
        ),
        video_frames=video.video_frames,
        gaps=gaps,
        mark=overlay_mark(path),
    )
