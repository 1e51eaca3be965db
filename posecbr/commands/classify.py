"""``posecbr classify CLIP... --db cb.sqlite``: for each clip, four lines (the answer and its
confidence, why, the nearest cases, what would make it the nearest other label;
``--verbose``: everything), then a summary (clips, flagged clips, and with labelled input
the accuracy, recall per class and the wrong clips; ``--quiet``: the summary alone).
``--feedback LABEL`` revises and retains (one transaction per clip)."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from contextlib import suppress
from pathlib import Path
from typing import TYPE_CHECKING, Any

from features.errors import ConfigError, DataError, PosecbrError
from features.text import counted, did_you_mean, first_few, percent
from posecbr.arguments import DB, NAME, add_k_option, as_options, check_each_found, path_arg
from posecbr.recordings import (
    GIVE_FPS,
    add_recording_options,
    add_sensor_option,
    assumed_rates,
    check_asf,
    check_fps,
    give_fps_by_converting,
    load_clip_as_asked,
    note_assumed_rates,
    sensor_for,
)

if TYPE_CHECKING:
    from casebase_store import CaseStore
    from features.poses import PoseSequence


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "classify",
        epilog="example: posecbr classify squat.npz lunge.mp4 --db cb.sqlite",
        help="classify clips with a case base, with explanations",
        description="Retrieve the most similar cases for each clip, vote, and explain.",
    )
    p.add_argument(
        "clips", nargs="+", type=path_arg, help="pose files, videos, folders or labels CSVs"
    )
    p.add_argument("--db", required=True, help="case base file (SQLite) or SQLAlchemy URL")
    p.add_argument("--name", default=None, help="case base name (default: the only one)")
    add_k_option(p, None, " (default: the case base's own, train -k; at most its cases)")
    p.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="everything the explanation holds: the vote, every similar case, what the clip "
        "shares with them and what not, the counterfactual's checks",
    )
    p.add_argument(
        "-q", "--quiet", action="store_true", help="the closing summary alone, no clip by clip"
    )
    p.add_argument(
        "--top",
        type=int,
        default=None,
        metavar="N",
        help="with --verbose: similar cases to list, 1 or more (default all)",
    )
    p.add_argument(
        "--feedback",
        metavar="LABEL",
        help="the true label of the clips: revise the case base and retain novel, beneficial cases",
    )
    p.add_argument(
        "--new-label",
        action="store_true",
        help="with --feedback: the label may be a new activity (otherwise it must be one of the "
        "case base's)",
    )
    p.add_argument(
        "--novelty",
        type=float,
        default=None,
        help="with --feedback: retain novelty threshold (default 0.5)",
    )
    p.add_argument(
        "--benefit",
        type=float,
        default=None,
        help="with --feedback: retain benefit threshold (default 0.2)",
    )
    p.add_argument(
        "--split",
        choices=("clips", "repetitions"),
        default="clips",
        help="repetitions: cut every clip into the repetitions posecbr reps counts and classify"
        " and explain each alone (a session of ten squats gives ten answers; the pieces train "
        "--split repetitions cuts); clips: one answer per clip (default)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    add_recording_options(p)  # as train, segment and describe read an AMC file or a rate given
    add_sensor_option(p)
    p.add_argument(
        "--subjects", help="datasets: only these subjects, comma-separated (default all)"
    )
    p.add_argument(  # as train and compare choose activities
        "--labels",
        help="datasets: only these activities, comma-separated, e.g. deep_squat (default all)",
    )
    p.add_argument(
        "--target",
        default=None,
        help="the column labelled clips are checked against (default: the one the case base "
        "was trained on, posecbr train --target)",
    )
    p.set_defaults(func=run)


FILES = ("pose_file", "pose_folder")  # kinds of input classified as given, not filtered


def load_inputs(
    paths: list[Path],
    sensor: str,
    subjects: list[str] | None = None,
    target: str = "label",
    labels: list[str] | None = None,
    asf: Path | None = None,
    fps: float | None = None,
) -> list[tuple[PoseSequence, str | None]]:
    """Every clip named by ``paths`` with its value of ``target`` (the label, or another
    column such as ``correct``) when the input carries one; of a labels CSV or dataset, those
    of ``subjects`` and ``labels`` (activities) alone. A clip file is read with ``asf`` (an
    AMC file's skeleton) and at ``fps`` when given, as ``segment`` reads a recording."""
    from cbr.casebase import frames_of
    from cbr.training import check_listed_once
    from features.clip_folders import check_no_extracted_twin, clip_files
    from features.clips import Clip, load_clip
    from features.datasets import detect_kind, iter_dataset
    from features.targets import clip_target

    def of_file(seq: PoseSequence) -> Clip:
        subject = seq.metadata.get("subject")
        return Clip(seq=seq, label=seq.label or "", subject=subject, extras={})

    kinds = [detect_kind(path) for path in paths]
    _check_files_alone(paths, kinds, asf, fps)
    for flag, asked in (("--subjects", subjects), ("--labels", labels)):
        if asked is not None and all(k in FILES for k in kinds):
            raise ConfigError(
                "filters the clips of a labels CSV or dataset, and none is given (pose files "
                "are classified as given)",
                flag,
            )
    out: list[tuple[PoseSequence, str | None]] = []
    seen: set[str | None] = set()  # the subjects of the clips the filter kept
    seen_labels: set[str] = set()  # and their labels
    for path, kind in zip(paths, kinds, strict=True):
        if kind == "pose_file":
            seq = load_clip_as_asked(path, asf, fps)
            out.append((seq, clip_target(of_file(seq), target)))
        elif kind == "pose_folder":
            # may hold unlabelled clips: read them one by one
            check_no_extracted_twin(clip_files(path))
            for f in clip_files(path):
                seq = load_clip(f)
                out.append((seq, clip_target(of_file(seq), target)))
        else:
            clips = list(
                iter_dataset(
                    path,
                    sensor=sensor,
                    subjects=subjects,
                    labels=labels,
                    progress_desc=f"loading {path.name}",
                    unlabelled=True,  # a row left unlabelled: classified, not checked
                )
            )
            # as train: a clip listed twice in one labels CSV would count twice
            check_listed_once([(c.seq.source, *frames_of(c.seq)) for c in clips], str(path),
                              "it would be classified and counted twice")  # fmt: skip
            for clip in clips:
                out.append((clip.seq, clip_target(clip, target)))
                seen.add(clip.subject)
                seen_labels.add(clip.label)
    datasets = [p for p, k in zip(paths, kinds, strict=True) if k not in FILES]
    # before "no clips found": the filter said why
    _check_asked(datasets, sensor, (subjects, seen), (labels, seen_labels))
    if not out:
        raise DataError("no clips found", " ".join(str(p) for p in paths))
    return out


def _how_fps(paths: list[Path]) -> str:
    """How the clips ``paths`` name are given their frame rate: ``--fps`` for clip files
    alone (:func:`_check_files_alone`), else by converting the first folder or labels CSV."""
    from features.datasets import detect_kind

    datasets = [p for p in paths if detect_kind(p) != "pose_file"]
    return give_fps_by_converting(datasets[0]) if datasets else GIVE_FPS


def _check_files_alone(
    paths: list[Path], kinds: list[str], asf: Path | None, fps: float | None
) -> None:
    """Refuse ``--asf`` and ``--fps`` with a folder or labels CSV among the clips: they say
    how one recording file is read, as ``train --frame-labels`` takes them for its one
    recording; a dataset's clips would each be read otherwise."""
    for flag, value in (("--asf", asf), ("--fps", fps)):
        for path, kind in zip(paths, kinds, strict=True):
            if value is not None and kind != "pose_file":
                raise ConfigError(
                    f"goes with clip files, not the {'folder' if path.is_dir() else 'dataset'}"
                    f" {path.name} (convert a dataset's recordings first: posecbr convert"
                    " --asf --fps)",
                    flag,
                )


def _check_asked(
    datasets: list[Path],
    sensor: str,
    subjects: tuple[list[str] | None, set[str | None]],
    labels: tuple[list[str] | None, set[str]],
) -> None:
    """Refuse a ``--subjects`` or ``--labels`` entry (each with the values of the clips the
    filters kept) no clip has (mistyped, or a stray comma's empty one): the clips of the
    others alone would be classified and counted as if all had been. Named with the values
    the ``datasets`` hold, as train and compare name them."""
    from features.datasets import dataset_labels, dataset_subjects
    from features.label_tracks import code_order

    def held(values: Callable[..., list[str]]) -> Callable[[], list[str]]:
        return lambda: sorted(
            {v for p in datasets for v in values(p, sensor=sensor)}, key=code_order
        )

    check_each_found(
        [
            (subjects[1], subjects[0], "--subjects", "of subject", held(dataset_subjects)),
            (labels[1], labels[0], "--labels", "labelled", held(dataset_labels)),
        ],
        datasets[0] if len(datasets) == 1 else "the clips given",
    )


def _check_args(args: argparse.Namespace) -> None:
    check_fps(args.fps)
    check_asf(args.asf, args.clips)
    if args.k is not None and args.k < 1:
        raise ConfigError(f"must be >= 1, got {args.k}", "-k")
    if args.top is not None and args.top < 1:  # 0 listed none, where dad --top 0 is all
        raise ConfigError(
            f"must be >= 1, got {args.top}: leave it out to list every similar case (0 listed"
            " none, where dad --top 0 details every activity)",
            "--top",
        )
    if args.split == "repetitions" and args.feedback is not None:
        raise ConfigError(
            "goes without --feedback (feedback retains and revises whole clips; to add "
            "repetitions to a case base: posecbr train CLIP --split repetitions --append)",
            "--split repetitions",
        )
    for flag, given in (("--new-label", args.new_label), ("--novelty", args.novelty is not None),
                        ("--benefit", args.benefit is not None)):  # fmt: skip
        if given and args.feedback is None:
            raise ConfigError("goes with --feedback LABEL: nothing is retained without it", flag)
    if args.top is not None and not args.verbose:
        raise ConfigError("goes with --verbose (the similar cases it lists)", "--top")
    if args.quiet and args.verbose:
        raise ConfigError("excludes --verbose", "--quiet")
    for flag, given, holds in (("--quiet", args.quiet, "every clip's record"),
                               ("--top", args.top is not None, "every similar case")):  # fmt: skip
        if given and args.json:
            raise ConfigError(f"goes without --json (its document holds {holds})", flag)


LONG_CLIP_WINDOWS = 5
"""A clip longer than this many windows, classified against a case base of windows, is noted:
one answer for a recording that may hold several activities."""


def _notes(
    name: str, target: str, stored: Any, clips: list[Any], results: list[Any], feedback: bool
) -> None:
    """What the user should know of the answers, on stderr: clips longer or of more
    repetitions than the case base's cases, and labels it has no case of."""
    if stored.cases == "windows":
        _note_long_clips(name, clips)
    if stored.cases == "repetitions":
        _note_repeated_clips(name, clips)
    # with --feedback the clips' label is the feedback's, checked or added as a new activity
    held = None if feedback else stored.classifier.case_base_.labels.tolist()
    _note_unknown_truths(name, target, results, held)


def _note_long_clips(name: str, clips: list[Any]) -> None:
    """Note, on stderr, clips much longer than the windows a case base of windows holds: each
    gets one answer, where ``segment`` labels each stretch."""
    from features.repetitions import WINDOW_S

    seconds = [c.n_frames / c.fps for c in clips]
    long = [t for t in seconds if t > LONG_CLIP_WINDOWS * WINDOW_S]
    if long:
        print(
            f"note: case base {name!r} holds a case per {WINDOW_S:g}-s window and "
            f"{counted(len(long), 'clip')} {'lasts' if len(long) == 1 else 'last'} longer than "
            f"{LONG_CLIP_WINDOWS * WINDOW_S:g} s ({'' if len(long) == 1 else 'up to '}"
            f"{max(long):.1f} s): each gets one answer "
            "here; posecbr segment labels each activity of a long recording",
            file=sys.stderr,
        )


def _note_repeated_clips(name: str, clips: list[Any]) -> None:
    """Note, on stderr, clips of several repetitions classified against a case base of
    single repetitions (``train --split repetitions``): each gets one answer, its
    repetitions' summary held against cases of one; how to classify each instead. A clip is
    of several when ``train`` would cut it into several cases (one left-and-right cycle of a
    movement that alternates sides is one case, :func:`features.repetitions.case_spans`):
    such a clip's rows are its cycles, a repetition alone (one step of a jog) being shorter
    than ``classify`` takes: ``reps --json``'s ``"cases"`` gives them as ``train`` cuts them
    (a short step left over joined to the cycle before)."""
    from cbr.casebase import frames_of, piece_name
    from features.errors import DataError
    from features.repetitions import MIN_PERIOD_S, case_spans, count_repetitions
    from features.text import shown

    several: list[str] = []
    cycled: list[str] = []
    for clip in clips:
        try:
            count = count_repetitions(clip)
        except DataError:  # too short to count, nobody seen: classify says what it can
            continue
        spans = case_spans(count)
        if len(spans) > 1:  # a piece of its file (a labels CSV's start,end row)
            piece = frames_of(clip) if "frame_offset" in clip.metadata else None  # its frames
            src = shown(piece_name(Path(clip.source or "a clip").name, piece))
            cycles = sum(n > 1 for _, _, n in spans)
            several.append(f"{src}: {count.count}" + (f" in {cycles} left-and-right cycles"
                                                       if cycles else ""))  # fmt: skip
            if cycles:
                cycled.append(src)
    if not several:
        return
    pairs = (
        f"; of a movement that alternates sides in repetitions shorter than {MIN_PERIOD_S:g} s"
        f" ({first_few(cycled)}), one row per left-and-right cycle, as train cuts them:"
        ' the "cases" of reps --json (one step alone is too short to classify)'
        if cycled
        else ""
    )
    print(
        f"note: case base {name!r} holds a case per repetition and "
        f"{counted(len(several), 'clip')} {'holds' if len(several) == 1 else 'hold'} several "
        f"({first_few(several)}): each gets one answer here; to classify each repetition, "
        "add --split repetitions (or give them as rows path,label,start,end of a labels CSV, "
        "a label may be left empty; posecbr reps CLIP --json: each one's start_frame and "
        f"end_frame{pairs})",
        file=sys.stderr,
    )


def _each_repetition(
    clips: list[PoseSequence], truths: list[str | None]
) -> tuple[list[PoseSequence], list[str | None]]:
    """Every clip cut into the repetitions ``reps`` counts, the pieces ``train --split
    repetitions`` cuts (:func:`cbr.training.cut`: a movement that alternates sides in turns
    too short alone, a jog, in left-and-right cycles), each with its clip's value to check
    against; a clip in which none is found stays whole, and a note on stderr names it."""
    from cbr.casebase import frames_of, piece_name
    from cbr.training import cut
    from features.text import shown

    out: list[PoseSequence] = []
    out_truths: list[str | None] = []
    whole: list[str] = []
    for clip, truth in zip(clips, truths, strict=True):
        pieces, _ = cut([clip], None, "repetitions")
        if len(pieces) == 1 and pieces[0] is clip:
            piece = frames_of(clip) if "frame_offset" in clip.metadata else None
            whole.append(shown(piece_name(Path(clip.source or "a clip").name, piece)))
        out += pieces
        out_truths += [truth] * len(pieces)
    if whole:
        print(
            f"note: no repetition found in {counted(len(whole), 'clip')} "
            f"({first_few(whole)}): {'it is' if len(whole) == 1 else 'each is'} classified "
            "whole (posecbr reps CLIP says what it counts)",
            file=sys.stderr,
        )
    return out, out_truths


def _chosen(args: argparse.Namespace, store: CaseStore) -> str:
    """The case base ``--name`` (the store's only one when left out), and every clip there
    (:func:`load_inputs`' first look at them), before the classifier is loaded."""
    from features.datasets import detect_kind

    with as_options(NAME):
        name = store.choose(args.name)
    for path in args.clips:
        detect_kind(path)
    return str(name)


def _feedback_settings(args: argparse.Namespace) -> Any:
    """``--feedback``'s thresholds (``--novelty``, ``--benefit``; the defaults when left out),
    refused before the store is opened."""
    from cbr.classification import FeedbackSettings

    defaults = FeedbackSettings()
    with as_options(FEEDBACK_OPTIONS):
        return FeedbackSettings(
            defaults.novelty_threshold if args.novelty is None else args.novelty,
            defaults.benefit_threshold if args.benefit is None else args.benefit,
        )


def _open_reader(args: argparse.Namespace) -> CaseStore:
    """The store, read-only even with --feedback: loading fills in nothing (a writable store
    would store the representations missing from it) and every check may still refuse; the
    writer is opened for the feedback alone. With --feedback, a change a killed writer left
    half-made is undone first, which a read-only look cannot."""
    from casebase_store import open_store, prepare_write

    if args.feedback is not None:
        prepare_write(args.db)
    with as_options(DB):
        return open_store(args.db, create=False, readonly=True)


def _input_columns(args: argparse.Namespace) -> list[str]:
    """The columns the clips to classify may have a value of, found from names and labels
    CSVs alone (:func:`features.datasets.dataset_columns`), for a mistyped ``--target``'s
    guess; none of an input that cannot be listed (what is wrong with it is told when it is
    read)."""
    from features.datasets import dataset_columns

    found: set[str] = set()
    for path in args.clips:
        with suppress(PosecbrError, OSError):
            found.update(dataset_columns(path, sensor=args.sensor or "kinect"))
    return sorted(found)


#: the arguments of cbr.classification's feedback checks as classify's options
FEEDBACK_OPTIONS = {
    "novelty_threshold": "--novelty",
    "benefit_threshold": "--benefit",
    "label": "--feedback",
    "new_label": "--new-label",
    "stored": "--feedback",
    "cases": "--split",  # what train --split made the case base's cases
}


def run(args: argparse.Namespace) -> int:
    _check_args(args)
    settings = _feedback_settings(args) if args.feedback is not None else None
    store = _open_reader(args)
    label = None
    try:
        name = _chosen(args, store)
        # the classifier's modules (numba's kernels among them): after the refusals above
        from cbr.classification import check_feedback_cases, check_feedback_label, classify_clips
        from cbr.stored import load_classifier

        stored = load_classifier(store, name)
        n_cases = len(stored.classifier.case_base_)
        if args.k is not None:
            if args.k > n_cases:
                raise ConfigError(
                    f"must be at most the {n_cases} cases of {name!r}, got {args.k}", "-k"
                )
            stored.classifier.set_params(k=args.k)
        elif int(stored.classifier.k) > n_cases:  # trained or trimmed below it
            print(
                f"note: case base {name!r} holds {n_cases} cases, fewer than the "
                f"{int(stored.classifier.k)} it votes with (k): every case votes",
                file=sys.stderr,
            )
        target = stored.target if args.target is None else args.target
        if target != stored.target:
            raise ConfigError(
                f"case base {name!r} predicts {stored.target!r}; to check clips against "
                f"{target!r}, train a case base with --target {target}"
                + did_you_mean(target, [stored.target, *_input_columns(args)]),
                "--target",
            )
        if args.feedback is not None:  # before the clips are read (a video's poses: minutes)
            known = sorted(set(stored.classifier.case_base_.labels.tolist()))
            with as_options(FEEDBACK_OPTIONS):
                check_feedback_cases(stored)
                label = check_feedback_label(args.feedback, known, args.new_label, target)
        subjects = [s.strip() for s in args.subjects.split(",")] if args.subjects else None
        labels = [s.strip() for s in args.labels.split(",")] if args.labels else None
        sensor = sensor_for(args.sensor, args.clips)
        inputs = load_inputs(args.clips, sensor, subjects, target, labels, args.asf, args.fps)
        clips, truths = [s for s, _ in inputs], [t for _, t in inputs]
        given = len(clips)
        if args.split == "repetitions":
            clips, truths = _each_repetition(clips, truths)
        if args.feedback is None:
            results = classify_clips(stored, clips, truths, target)
    finally:
        store.close()
    gone: list[str] | None = None  # with feedback: the labels it left without a case
    if label is not None:
        results, gone = _with_feedback(args.db, stored, clips, label, settings, target, known)
    _notes(name, target, stored, clips, results, label is not None)
    note_assumed_rates(assumed_rates(clips), _how_fps(args.clips))
    _print(args, store.where, name, target, results, gone, given)
    if all(r.solved is None for r in results):  # nothing the user asked for could be done
        print(
            f"posecbr classify: error: no clip could be classified "
            f"({counted(len(results), 'clip')}, each unclassifiable: see above)",
            file=sys.stderr,
        )
        return 1
    return 0


def _with_feedback(
    db: Path,
    stored: Any,
    clips: list[Any],
    label: str,
    settings: Any,
    target: str,
    known: list[str],
) -> tuple[list[Any], list[str]]:
    """The clips classified and learnt from (a writer opened for the feedback alone), and the
    labels of ``known`` the feedback left without any case (a note names them)."""
    from casebase_store import open_store
    from cbr.classification import classify_with_feedback

    writer = open_store(db, create=False)
    try:
        results = classify_with_feedback(writer, stored, clips, label, settings, target)
    except KeyboardInterrupt:  # the feedback stored before it may have left them so
        _note_gone(stored.name, target, _gone(known, stored))
        raise
    finally:
        writer.close()
    gone = _gone(known, stored)
    _note_gone(stored.name, target, gone)
    return results, gone


def _gone(known: list[str], stored: Any) -> list[str]:
    """The labels of ``known`` (the case base's before the feedback) no active case of
    ``stored`` carries now: feedback relabelled the last case of each."""
    now = set(stored.classifier.case_base_.labels.tolist())
    return [lab for lab in known if lab not in now]


def _note_gone(name: str, target: str, gone: list[str]) -> None:
    """One note line naming the labels the feedback left without a case: the user's
    correction stands (``casebase trim`` keeps an activity's last case; feedback does not), but
    the case base no longer predicts them."""
    from cbr.explain import class_noun
    from features.text import shown

    if not gone:
        return
    noun = class_noun(target, len(gone))
    names = ", ".join(repr(lab) for lab in gone)
    one = len(gone) == 1
    print(
        shown(
            f"note: case base {name!r} no longer has any case of the {noun} {names}: the "
            f"feedback relabelled {'its last case' if one else 'the last case of each'}, so "
            f"{'it is' if one else 'they are'} no longer predicted (to add "
            f"{'it' if one else 'one'} again: --feedback LABEL --new-label)"
        ),
        file=sys.stderr,
    )


def _note_unknown_truths(
    name: str, target: str, results: list[Any], known: list[Any] | None
) -> None:
    """A note on stderr naming the true labels of the clips that the case base holds no case
    of: such a clip is counted wrong whatever it is answered (a clip of an activity never
    trained, or labelled by its folder's name, as ``extract`` labels a folder's videos)."""
    from cbr.explain import class_noun, label_words
    from features.text import shown

    if known is None:
        return
    have = {str(k) for k in known}
    missing: dict[str, int] = {}
    for r in results:
        if r.solved is not None and r.true_label is not None and str(r.true_label) not in have:
            missing[str(r.true_label)] = missing.get(str(r.true_label), 0) + 1
    if not missing:
        return
    labels = ", ".join(
        f"{shown(label_words(lab, target))!r} ({counted(n, 'clip')})"
        for lab, n in sorted(missing.items())
    )
    ours = ", ".join(shown(label_words(k, target)) for k in sorted(have))
    these = "that clip" if sum(missing.values()) == 1 else "those clips"
    counts = "counts" if sum(missing.values()) == 1 else "count"
    print(
        f"note: case base {name!r} has no case of {labels}: {these} cannot be answered right "
        f"and {counts} as wrong (its {class_noun(target, 2)}: {ours})",
        file=sys.stderr,
    )


def _print(
    args: argparse.Namespace,
    where: str,
    name: str,
    target: str,
    results: list[Any],
    gone: list[str] | None = None,
    given: int | None = None,
) -> None:
    """Every clip's record and the summary (``given``: the clips given, before ``--split
    repetitions`` cut them into the records)."""
    from cbr.classification import summarise

    summary = summarise(results, target)
    if args.json:
        doc: dict[str, Any] = {
            "db": where,
            "case_base": name,
            "target": target,
            "split": args.split,
            "results": [r.to_dict() for r in results],
            "summary": summary,
        }
        if args.split == "repetitions":  # the records are pieces of these many clips
            doc["clips_given"] = given
        if gone is not None:  # with --feedback: the labels it left without any case
            doc["left_without_cases"] = gone
        if summary.get("accuracy") is not None:  # the names of posecbr 0.2
            doc["accuracy"] = summary["accuracy"]
            doc["n_labelled"] = summary["labelled"]
        json.dump(doc, sys.stdout, indent=2, ensure_ascii=False)
        print()
        return
    if not args.quiet:
        for r in results:
            _print_one(r, args, target)
    _print_summary(summary, target, results, given if args.split == "repetitions" else None)
    if args.feedback is not None:  # where it went, as every command that writes says
        _print_stored(where, name, results)


def _print_stored(where: str, name: str, results: list[Any]) -> None:
    """The line saying what the feedback changed in which case base of which store (--quiet
    too: the clips' own feedback lines are not printed then)."""
    from features.text import shown

    retained = sum(r.retention is not None and r.retention.retained for r in results)
    revised = sum(r.revision is not None and r.revision.case_id >= 0 for r in results)
    print(
        f"feedback stored in case base {shown(repr(name))} of {shown(where)}: "
        f"{counted(retained, 'clip')} retained as new cases, {counted(revised, 'case')} revised"
    )


def _print_one(r: Any, args: argparse.Namespace, target: str) -> None:
    """One clip: four lines by default (--verbose: everything the explanation holds). Labels,
    file names and words from the user's files are printed through ``shown``."""
    from cbr.explain import label_words
    from features.text import shown

    made = f" (from {shown(r.made_from)})" if r.made_from else ""
    if r.solved is None:
        print(f"{shown(r.name)}{made}: unclassifiable ({shown(r.unclassifiable)})")
        return
    e = r.explanation
    lines = (e.verbose if args.verbose else e.text).splitlines()
    if args.verbose and args.top is not None:  # the similar cases are the "  case " lines
        cases = [i for i, line in enumerate(lines) if line.startswith("  case ")]
        lines = [line for i, line in enumerate(lines) if i not in cases[args.top :]]
    head = f"{shown(r.name)}{made}: {shown(lines[0])}"
    if r.true_label is not None:
        right = r.true_label == e.label
        head += "  [right]" if right else f"  [wrong: {shown(label_words(r.true_label, target))}]"
    print(head)
    for line in lines[1:]:
        print(f"  {shown(line)}")
    if r.retention is not None:
        print(f"  feedback: {shown(r.retention.reason)}")
    if r.revision is not None:
        print(
            f"  feedback: revised case #{r.revision.case_id} ({r.revision.action}): "
            f"{shown(r.revision.reason)}"
        )


def _print_counts(s: dict[str, Any], said: Callable[[str], str], cut_from: int | None) -> None:
    """The summary's first lines: the clips (``cut_from``: the clips ``--split repetitions``
    cut into them), classified, unclassifiable and flagged; of more than one classified, how
    many got each answer (of a session's repetitions: how many judged correct, incorrect)."""
    what = counted(s["clips"], "clip")
    if cut_from is not None:
        what = f"{counted(cut_from, 'clip')} cut into {counted(s['clips'], 'repetition')}"
    print(f"\n{what}: {s['classified']} classified", end="")
    if s["unclassifiable"]:
        print(f", {len(s['unclassifiable'])} unclassifiable", end="")
    print(f"; {len(s['unlike_cases'])} unlike the stored cases.")
    if s["classified"] > 1:
        print("answers: " + ", ".join(f"{said(lab)} {n}" for lab, n in s["answers"].items()))


def _print_summary(
    s: dict[str, Any], target: str, results: list[Any], cut_from: int | None = None
) -> None:
    """The closing summary: clips (``cut_from``: the clips ``--split repetitions`` cut into
    them), the answers, accuracy and recall per class, flagged and wrong clips (each named
    with its frames when a piece of its file: ``results``' names)."""
    from cbr.casebase import piece_name
    from cbr.explain import label_words
    from features.text import shown

    def said(label: str) -> str:
        return shown(label_words(label, target))

    _print_counts(s, said, cut_from)
    if s.get("accuracy") is not None:
        accuracy = percent(s["accuracy"])  # as compare's table: a percentage (--json: 0-1)
        print(f"accuracy: {accuracy} ({s['right']}/{s['labelled']} labelled clips)")
        recall = "; ".join(
            f"{said(lab)} {v['right']}/{v['clips']}" for lab, v in s["recall"].items()
        )
        print(f"recall per class: {recall}")
        if s["expected_accuracy"] is not None:
            plain = (
                " (vote shares, not calibrated)" if s.get("confidence_calibrated") is False else ""
            )
            print(f"mean confidence: {s['expected_accuracy']:.3f}{plain}")
    for w in s["wrong"]:
        clip = piece_name(w["clip"], w.get("frames"), w.get("origin"))
        print(f"wrong: {shown(clip)}: {said(w['label'])}, true {said(w['true_label'])}")
    flagged = [r for r in results if r.solved is not None and r.solved.unlike_cases]
    for r in flagged:
        print(f"unlike the stored cases: {shown(r.name)}")
    for r in results:
        if r.solved is None:
            # why, as the clip's own line says it: under --quiet the summary is all there is
            print(f"unclassifiable: {shown(r.name)} ({shown(r.unclassifiable)})")
