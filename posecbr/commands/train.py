"""``posecbr train DATA --db cb.sqlite``: build a case base from labelled clips.

DATA is anything :func:`features.datasets.load_dataset` reads: a folder per class, a labels
CSV, a UI-PRMD or HDM05 folder, or a folder of labelled pose files. The whole case base is
written in one transaction: an interrupted train leaves the store as it was.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Collection, Sequence
from pathlib import Path
from typing import Any

from cbr.similarity import available_measures, get_measure
from features.cluster import SCHEDULER_HELP, check_scheduler
from features.errors import ConfigError, DataError, PosecbrError
from features.fileio import check_output
from features.text import counted, first_few, percent, shown, spelt_among
from posecbr.arguments import (
    DB,
    NAME,
    SCHEDULER,
    add_k_option,
    as_options,
    check_found,
    param_value,
    path_arg,
    said_as_options,
)
from posecbr.recordings import (
    GIVE_FPS,
    add_recording_options,
    add_sensor_option,
    assumed_rates_note,
    check_asf,
    check_fps,
    give_fps_by_converting,
    load_recording,
    sensor_for,
)


def parse_params(items: list[str] | None) -> dict[str, Any]:
    """``key=value`` pairs; values parsed as JSON when they can be (numbers, true, null)."""
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ConfigError(f"expected KEY=VALUE, got {item!r}", "--param")
        out[key] = param_value(key, value)
    return out


def _phases(value: str) -> int | str:
    if value == "auto":
        return value
    try:
        return int(value)
    except ValueError:
        msg = f"must be auto or a whole number, got {value!r}"
        raise ConfigError(msg, "--phases") from None


#: the name of a case base ``train`` makes when ``--name`` is left out
DEFAULT_NAME = "default"


class MeasureNames:
    """The names of every similarity measure (:func:`cbr.similarity.available_measures`),
    as argparse puts them in a help text: ``%(measures)s``, looked up when shown."""

    def __str__(self) -> str:
        return ", ".join(available_measures())


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "train",
        epilog="example: posecbr train labels.csv --db cb.sqlite",
        help="build a case base from labelled clips",
        description="Compute qualitative features of every clip and store them as cases "
        "(problem = features, solution = label) in a case base file.",
    )
    p.add_argument("data", type=path_arg, help="dataset folder, labels CSV or pose file folder")
    p.add_argument("--db", required=True, help="case base file (SQLite) or SQLAlchemy URL")
    p.add_argument(
        "--name",
        default=None,
        help=f"case base name in the store (default: {DEFAULT_NAME}; with --append, the store's"
        " only one, as classify, segment and watch take it)",
    )
    p.add_argument(
        "--features",
        choices=("fluents", "qmp"),
        default=None,
        help="feature level (default fluents)",
    )
    similarity = p.add_argument(
        "--similarity",
        default=None,
        help="similarity measure: %(measures)s (default euclidean)",
    )
    # named when the help is shown: looking up the installed plugins' measures (their entry
    # points) imports importlib.metadata and reads every installed package's metadata, which
    # every other command, built with this parser, has no use for
    similarity.measures = MeasureNames()  # type: ignore[attr-defined]
    p.add_argument(
        "--param",
        action="append",
        metavar="KEY=VALUE",
        help="similarity parameter, e.g. --similarity dtw --param band=0.2 (repeatable)",
    )
    p.add_argument(
        "--length", type=int, default=None, help="frames per fluent sequence (default 32)"
    )
    p.add_argument(
        "--states",
        default=None,
        help="fluent states: angles, instantaneous, all (default angles)",
    )
    p.add_argument(
        "--trim",
        metavar="KEEP",
        type=float,
        help="novelty/benefit trimming: keep this fraction of each activity (default: keep all)",
    )
    p.add_argument(
        "--editor",
        choices=("novelty-benefit", "cnn", "renn", "icf"),
        help="maintenance editor to run at build time (default with --trim: novelty-benefit)",
    )
    p.add_argument(
        "--mirror",
        choices=("auto", "off", "canonical", "augment"),
        default=None,
        help="side handling: clips as recorded (off), left-side clips mirrored (canonical), "
        "mirror images as further cases (augment); auto (the default): chosen by "
        "leave-one-subject-out "
        "inside the training clips (euclidean on clip summaries or QMPs)",
    )
    p.add_argument(
        "--feature-weights",
        choices=("auto", "fisher", "none"),
        default=None,
        help="learned feature weights (fisher: between/within-activity variance), chosen like "
        "--mirror when auto (default: auto; none with --split windows)",
    )
    p.add_argument(
        "--phases",
        default=None,
        help="clip summaries: also the mean of every feature over this many equal stretches of "
        "the clip (0: none); auto (the default): 3 or none, chosen like --mirror",
    )
    p.add_argument(
        "--no-positions",
        action="store_true",
        help="leave out the joint positions in the person's own frame (angles and fluents only)",
    )
    p.add_argument(
        "--no-summary",
        action="store_true",
        help="euclidean on the resampled fluent sequence instead of per-feature clip summaries",
    )
    add_k_option(p, None, " (default 5), kept with the case base: classify's default")
    p.add_argument(
        "--subjects", help="only these subjects, comma-separated, e.g. s01,s02 (default all)"
    )
    p.add_argument(
        "--labels", help="only these activities, comma-separated, e.g. deep_squat (default all)"
    )
    p.add_argument(
        "--target",
        default=None,
        help="what the cases' solution is: the activity label (default; with --append the "
        "case base's own) or another column of "
        "the labels, e.g. correct (UI-PRMD: correct / incorrect repetition); train one case "
        "base per activity with --labels",
    )
    add_sensor_option(p)
    p.add_argument(
        "--split",
        choices=("clips", "repetitions", "windows"),
        default=None,
        help="repetitions: cut every clip into its repetitions, each a case (a video of ten "
        "squats gives ten cases); windows: into the 2-s windows every 0.5 s that posecbr "
        "segment classifies (the case base for segmenting long recordings; feature weights "
        "none unless --feature-weights says otherwise); clips: one case per clip; default: "
        "windows for recordings labelled over time (--frame-labels, a label_file column), "
        "else clips, or with --append as the case base was trained",
    )
    p.add_argument(
        "--frame-labels",
        type=path_arg,
        metavar="FILE",
        help="DATA is one recording labelled over time: one label per frame, or per "
        "--label-block seconds; each labelled stretch becomes a clip (several recordings: a "
        "labels CSV with a label_file column)",
    )
    p.add_argument(
        "--label-block",
        type=float,
        metavar="SECONDS",
        help="seconds per label (default: one label per frame)",
    )
    p.add_argument("--label-names", type=path_arg, metavar="FILE", help="'code name' per line")
    add_recording_options(p)
    g = p.add_mutually_exclusive_group()
    g.add_argument("--replace", action="store_true", help="replace a case base of that name")
    g.add_argument(
        "--append",
        action="store_true",
        help="add the clips to an existing case base (same feature configuration)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS|local:N", help=SCHEDULER_HELP)
    p.add_argument("--json", action="store_true", help="machine-readable summary")
    p.set_defaults(func=run)


#: the options that define what is learned; `--append` keeps the stored model, so refuses them
MODEL_OPTIONS = {
    "features": "--features",
    "similarity": "--similarity",
    "param": "--param",
    "length": "--length",
    "states": "--states",
    "trim": "--trim",
    "editor": "--editor",
    "mirror": "--mirror",
    "feature_weights": "--feature-weights",
    "phases": "--phases",
    "no_positions": "--no-positions",
    "no_summary": "--no-summary",
    "k": "-k",
}
DEFAULTS: dict[str, Any] = {
    "features": "fluents",
    "similarity": "euclidean",
    "length": 32,
    "states": "angles",
    "mirror": "auto",
    "feature_weights": "auto",
    "phases": "auto",
    "k": 5,
}


def _estimator(args: argparse.Namespace) -> Any:
    o = {k: (DEFAULTS[k] if getattr(args, k) is None else getattr(args, k)) for k in DEFAULTS}
    if args.split == "windows" and args.feature_weights is None:
        # overlapping windows of one stretch are near copies: the within-activity spread that
        # Fisher weights divide by would be that of one performance, not of the activity
        o["feature_weights"] = "none"
    params = parse_params(args.param)
    try:
        measure = get_measure(o["similarity"], **params)
    except ConfigError as exc:  # the registry names its field; the user gave an option: the
        # measure's name, or a parameter's name or value (band=-1 was blamed on --similarity)
        named = exc.message.startswith("unknown similarity") or not params
        raise ConfigError(exc.message, "--similarity" if named else "--param") from None
    if o["features"] == "qmp" and measure.compares_sequences:
        raise ConfigError(
            f"similarity {measure.name!r} compares sequences; QMP features are "
            "one vector per clip (use euclidean)",
            "--similarity",
        )
    if args.trim is not None and not 0.0 < args.trim <= 1.0:
        raise ConfigError(f"must be in (0, 1], got {args.trim}", "--trim")
    if args.trim is not None and args.editor not in (None, "novelty-benefit"):
        raise ConfigError(  # as casebase trim's --keep: it was ignored
            f"goes with --editor novelty-benefit; {args.editor} decides how many cases it keeps",
            "--trim",
        )
    _check_fluent_options(args, o["features"], measure.name)
    from cbr.estimator import CaseBaseClassifier  # after the refusals of the options above

    estimator = CaseBaseClassifier(
        features=o["features"],
        similarity=o["similarity"],
        similarity_params=params or None,
        k=o["k"],
        length=o["length"],
        states=o["states"],
        summary=False if args.no_summary else "auto",
        mirror=o["mirror"],
        feature_weights=o["feature_weights"],
        phases=_phases(str(o["phases"])),
        positions=not args.no_positions,
        trim=args.trim,
        editor=args.editor,
        # a repetition check (--target correct): what was recorded, not how often each class
        # occurs, sets its counts (many correct repetitions, few incorrect), so each class's
        # votes count by its share of the cases; activities vote as they occur
        class_weight="none" if args.target == "label" else "balanced",
    )
    try:  # bad --states / --length / -k: one line before any clip is read
        estimator.wanted_config()
        estimator.describe_plan()
    except ConfigError as exc:
        raise _as_option(exc) from None
    return estimator


#: the arguments of cbr.training's refusals of the clips and of an append (and of the store
#: it opens), as the options of `train` that set them
CLIP_OPTIONS = {**SCHEDULER, **DB, "target": "--target", "cases": "--split"}


#: the estimator's parameters, as the options of `train` that set them
PARAMETER_OPTIONS = {
    "states": "--states",
    "length": "--length",
    "k": "-k",
    "feature_weights": "--feature-weights",
    "mirror": "--mirror",
    "phases": "--phases",
    "editor": "--editor",
    "trim": "--trim",
}


def _as_option(exc: ConfigError) -> ConfigError:
    """A refusal of the estimator's parameter ("states: must be one of ...") as one of the
    option typed ("--states: must be one of ...")."""
    option = PARAMETER_OPTIONS.get(exc.source or "")
    if option is None:
        return exc
    message = exc.message
    if exc.source == "feature_weights" and "vector problems" in message:  # Python's words
        message = (
            "learned feature weights need clip summaries or QMP features under euclidean"
            " similarity (not dtw, signature or --no-summary)"
        )
    return ConfigError(message, option)


def _check_fluent_options(args: argparse.Namespace, features: str, similarity: str) -> None:
    """Refuse the options of fluent features and their clip summaries where they would be
    ignored: ``--no-positions`` and ``--no-summary`` with QMP features, ``--phases`` without
    clip summaries (QMP features, ``--no-summary``, or a similarity other than euclidean)."""
    if features != "fluents":
        for flag, given in (("--no-positions", args.no_positions),
                            ("--no-summary", args.no_summary)):  # fmt: skip
            if given:
                raise ConfigError(f"goes with fluent features, not {features}", flag)
    summaries = features == "fluents" and similarity == "euclidean" and not args.no_summary
    if args.phases is not None and not summaries:
        raise ConfigError(
            "goes with clip summaries (fluent features, euclidean similarity, no --no-summary)",
            "--phases",
        )


def _check_append(args: argparse.Namespace) -> None:
    given = [flag for key, flag in MODEL_OPTIONS.items() if getattr(args, key) not in (None, False)]
    if given:
        raise ConfigError(
            f"--append adds cases to the stored model as it is; it does not take "
            f"{', '.join(given)} (use --replace to train anew)",
            given[0],
        )


def _recording_clips(args: argparse.Namespace, activities: list[str] | None) -> list[Any]:
    """The labelled stretches of one recording (``--frame-labels``), read as ``segment``
    reads it (``--asf``, ``--fps``), each of the person its metadata names (a pose file's
    subject, an HDM05 name's actor), as a labels CSV's recording and
    :func:`cbr.training.cut_recording` keep it."""
    from cbr.casebase import subject_of
    from features.label_tracks import LabelTrack
    from features.stretches import recording_clips

    track = LabelTrack(args.frame_labels, args.label_block, args.label_names)
    seq = load_recording(args.data, args.asf, args.fps)
    stretches = recording_clips(seq, track, subject_of(seq))
    clips = [c for c in stretches if not activities or spelt_among(c.label, activities)]
    return _long_enough(args, clips)


def _note(args: argparse.Namespace, text: str) -> None:
    """A note on how the data was read, said on stderr once the training is done (a refusal
    after it is then the one line it is, not a note and a refusal)."""
    args.notes.append(text)


def _long_enough(args: argparse.Namespace, clips: list[Any]) -> list[Any]:
    """The labelled stretches that last at least the shortest repetition
    (:func:`features.repetitions.long_enough`, as :func:`cbr.training.cut_recording` keeps
    them); those left out are said on stderr."""
    from features.repetitions import MIN_PERIOD_S, long_enough

    kept, short = long_enough(clips)
    args.short_only = sorted({c.label for c in short} - {c.label for c in kept})
    if short:
        labels = ", ".join(sorted({shown(c.label) for c in short}))
        stretches = "stretch" if len(short) == 1 else "stretches"
        _note(
            args,
            f"left out {len(short)} labelled {stretches} shorter than {MIN_PERIOD_S:g} s"
            f" ({labels})",
        )
    return kept


def _cut(args: argparse.Namespace, clips: list[Any]) -> list[Any]:
    """``--split repetitions`` / ``windows``: every clip cut as
    :func:`features.repetitions.cut_clips` cuts it (as :func:`cbr.training.cut` does), said
    on stderr."""
    from features.repetitions import WINDOW_HOP_S, WINDOW_S, cut_clips

    cut = cut_clips(clips, args.split)
    n_cut = len(clips) - len(cut.kept_whole)
    n_pieces = len(cut.clips) - len(cut.kept_whole)
    if args.split == "repetitions":
        args.kept_whole = {c.seq.source for c in cut.kept_whole}
        if not n_cut:
            _note(args, f"kept {counted(len(clips), 'clip')} whole: no repetition found in any")
            return cut.clips
        kept = [shown(Path(c.seq.source or "a clip").name) for c in cut.kept_whole]
        whole = (  # named: which exercise video found no repetition is for the user to check
            f"; {counted(len(kept), 'clip')} without a repetition kept whole ({first_few(kept)})"
            if kept
            else ""
        )
        _note(
            args, f"cut {counted(n_cut, 'clip')} into {_repetitions(n_pieces, cut.cycles)}{whole}"
        )
        return cut.clips
    if not n_cut:
        _note(args, f"kept {counted(len(clips), 'clip')} whole: each shorter than a window "
                    f"of {WINDOW_S:g} s")  # fmt: skip
        return cut.clips
    whole = (
        f"; {counted(len(cut.kept_whole), 'clip')} shorter than a window kept whole"
        if cut.kept_whole
        else ""
    )
    _note(
        args,
        f"cut {counted(n_cut, 'clip')} into {counted(n_pieces, 'window')} of "
        f"{WINDOW_S:g} s every {WINDOW_HOP_S:g} s{whole}",
    )
    return cut.clips


def _repetitions(n_pieces: int, cycles: int) -> str:
    """``n_pieces`` cut into repetitions, ``cycles`` of them left-and-right cycles of a
    movement that alternates sides (:func:`features.repetitions.case_spans`), in words."""
    if not cycles:
        return counted(n_pieces, "repetition")
    return (
        f"{counted(n_pieces, 'case')}: {counted(n_pieces - cycles, 'repetition')} and"
        f" {counted(cycles, 'left-and-right cycle')} of a movement that alternates sides"
    )


def _in_memory(args: argparse.Namespace) -> bool:
    """Whether DATA is read here as a whole: one recording cut by its frame labels, or clips cut
    into repetitions or windows (each needs the clips before it knows the cases)."""
    return bool(args.frame_labels) or args.split in ("repetitions", "windows")


def _clips(args: argparse.Namespace) -> list[Any]:
    """The clips of ``--frame-labels`` / ``--split``, read in this process."""
    from features.datasets import load_dataset

    subjects = [s.strip() for s in args.subjects.split(",")] if args.subjects else None
    activities = [s.strip() for s in args.labels.split(",")] if args.labels else None
    clips = (
        _recording_clips(args, activities)
        if args.frame_labels
        else load_dataset(
            args.data,
            sensor=args.sensor,
            subjects=subjects,
            labels=activities,
            progress_desc="loading clips",
        )
    )
    check_found([c.label for c in clips], activities, "--labels", "labelled", args.data,
                lambda: _held_labels(args))  # fmt: skip
    check_found([c.subject for c in clips], subjects, "--subjects", "of subject", args.data,
                lambda: _held_subjects(args))  # fmt: skip
    stretches = bool(clips) and not args.frame_labels and args.over_time
    if stretches:  # a labels CSV's recordings: its flickers left out as --frame-labels' are
        clips = _long_enough(args, clips)
    if clips and not args.append:  # before the cutting is said: the refusal is one line
        from features.targets import clip_target

        values = [clip_target(c, args.target) for c in clips]
        _one_activity(args, [v for v in values if v is not None])
    if args.split in ("repetitions", "windows") and clips:
        clips = _cut(args, clips)
    if not clips:
        raise _no_clips(args, stretches)
    return clips


def _check_asked(args: argparse.Namespace, clips: list[Any], solutions: list[str]) -> None:
    """Refuse a ``--labels`` or ``--subjects`` entry no clip read has (mistyped), before
    anything is stored: a case base of the others alone was trained without a word. The
    labels are the solutions when the case base predicts them (``--target label``)."""
    if args.labels and args.target == "label":
        asked = [s.strip() for s in args.labels.split(",")]
        check_found(solutions, asked, "--labels", "labelled", args.data, lambda: _held_labels(args))
    if args.subjects:
        asked = [s.strip() for s in args.subjects.split(",")]
        check_found([c.subject for c in clips], asked, "--subjects", "of subject", args.data,
                    lambda: _held_subjects(args))  # fmt: skip


def _held_labels(args: argparse.Namespace) -> list[str]:
    """The labels DATA's clips have, found without decoding one (a ``--labels`` entry none
    has is refused naming them): ``--frame-labels``' file's, else the dataset's."""
    from features.datasets import dataset_labels
    from features.label_tracks import LabelTrack, track_labels

    if args.frame_labels:
        return track_labels(LabelTrack(args.frame_labels, args.label_block, args.label_names))
    return dataset_labels(args.data, sensor=args.sensor)


def _held_subjects(args: argparse.Namespace) -> list[str]:
    """The subjects DATA's clips have, found without decoding one (a ``--subjects`` entry
    none has is refused naming them; ``--frame-labels`` takes no ``--subjects``)."""
    from features.datasets import dataset_subjects

    return dataset_subjects(args.data, sensor=args.sensor)


def _no_clips(args: argparse.Namespace, stretches: bool = False) -> DataError:
    """Nothing to train from: said with the options that left everything out, if any.
    ``stretches``: the clips were the labelled stretches of recordings labelled over time
    (as with ``--frame-labels``)."""
    from features.repetitions import MIN_PERIOD_S

    given = [o for o, v in (("--labels", args.labels), ("--subjects", args.subjects)) if v]
    what = (
        f"no labelled stretch of {MIN_PERIOD_S:g} s or more"
        if args.frame_labels or stretches
        else "no clips found"
    )
    return DataError(what + (f" (check {' and '.join(given)})" if given else ""), str(args.data))


def _check_k(args: argparse.Namespace, clips: list[Any]) -> None:
    """Refuse ``-k`` above the cases the training will make: the clips that can be cases
    (:func:`cbr.training.usable`; a window of a recording where nobody is seen is none). None
    usable is left to the training's own refusal."""
    from cbr.stored import CASE_KINDS
    from cbr.training import usable

    n = len(usable(clips)[0])
    if args.k is None or not 0 < n < args.k:
        return
    left_out = len(clips) - n
    why = (
        f" ({counted(left_out, CASE_KINDS.get(args.split, 'clip'))} left out: no person seen"
        " or too short)"
        if left_out
        else ""
    )
    raise ConfigError(f"must be at most the {n} cases{why}, got {args.k}", "-k")


def _one_activity(args: argparse.Namespace, solutions: list[str]) -> None:
    """A new case base needs two activities: refused naming DATA, before any fitting."""
    from features.repetitions import MIN_PERIOD_S

    values = sorted(set(solutions))
    if len(values) == 1:
        short = getattr(args, "short_only", [])  # labels whose every stretch was left out
        why = (
            f" (the stretches labelled {first_few([shown(v) for v in short])} are all shorter than"
            f" {MIN_PERIOD_S:g} s: left out)"
            if short and args.target == "label"
            else ""
        )
        raise DataError(
            f"the training data hold only one {'activity' if args.target == 'label' else 'value'}"
            f" ({shown(repr(values[0]))}); a classifier needs at least two{why}",
            str(args.data),
        )


def _one_listed_activity(args: argparse.Namespace, entries: list[Any]) -> None:
    """:func:`_one_activity` of the activities DATA's entries name (a folder per class, a
    labels CSV's label column), before any clip is read: the clips read hold no other. Not
    of a recording labelled over time, nor of a file whose label is its own metadata's, nor
    under ``--subjects`` (a file's metadata may name another subject: none left is said),
    nor of an ``--append`` (cases added to a case base that holds others)."""
    if args.append or args.target != "label" or args.subjects or not entries:
        return
    if all(e.entry.pieces is None and e.entry.label is not None for e in entries):
        _one_activity(args, [str(e.entry.label) for e in entries])


def _described_in_memory(args: argparse.Namespace, plan: Any) -> tuple[list[Any], list[str]]:
    from cbr.training import describe, no_target_value
    from features.progress import progress
    from features.targets import clip_target

    clips = _clips(args)
    solutions = []
    for clip in clips:
        value = clip_target(clip, args.target)
        if value is None:
            with as_options(CLIP_OPTIONS):
                raise no_target_value(clip, args.target)
        solutions.append(value)
    seqs = progress([c.seq for c in clips], desc="features", total=len(clips), unit="clip")
    return [describe(s, plan) for s in seqs], solutions


def _entries(args: argparse.Namespace) -> list[Any]:
    """The clips DATA names (not read yet), filtered by --subjects and --labels; a pose file
    (.npz) among them that is no archive of well-formed arrays within the read limits
    (truncated, renamed, empty) refused before the first clip is worked on, not when its
    turn comes (:func:`features.datasets.iter_dataset` reads lazily); several such files
    named each, as :class:`cbr.training.ClipsFailed` names the clips a cluster could not read."""
    from cbr.training import ClipsFailed
    from features.datasets import dataset_entries
    from features.errors import PoseFileError
    from features.poses import check_archive

    subjects = [s.strip() for s in args.subjects.split(",")] if args.subjects else None
    activities = [s.strip() for s in args.labels.split(",")] if args.labels else None
    entries = dataset_entries(args.data, sensor=args.sensor, subjects=subjects, labels=activities)
    if not entries:
        if activities:  # a label no clip has, named with those the clips have (else the
            held = _held_labels(args)  # other filters left them all out: said below)
            check_found(held, activities, "--labels", "labelled", args.data, lambda: held)
        if subjects:  # as for a label
            people = _held_subjects(args)
            check_found(people, subjects, "--subjects", "of subject", args.data, lambda: people)
        raise _no_clips(args)
    broken = []
    for e in entries:
        path = e.entry.path  # a pipe or device is left to the reader, which refuses it unread
        if path.suffix.lower() == ".npz" and path.is_file():
            try:
                check_archive(path, ("positions",))
            except PoseFileError as exc:
                broken.append((e, exc))
    if len(broken) == 1:
        raise broken[0][1]
    if broken:  # every one named, as a cluster names the clips that failed
        raise ClipsFailed([f"{e.name}: {exc}" for e, exc in broken])
    return entries


def _check_new_store(args: argparse.Namespace) -> None:
    """Refuse, before any clip is read, a ``--db`` the training could not store into: a
    folder, a file in a missing folder or with too long a name, one of the inputs, a file
    that is not a case base store, or one that already holds ``--name`` (neither --replace
    nor --append given). An empty database is left to the training, which creates the store;
    the transaction that stores the model checks again."""
    from casebase_store import EMPTY_DB, EmptyStore, Seen, StoreError, check_store_file, sqlite_file

    # what --replace will replace: none, unless one is read below (checked when it is stored)
    args.seen = Seen() if args.replace else None
    if not str(args.db).strip():
        raise StoreError(EMPTY_DB, "--db")
    file = sqlite_file(args.db)
    if file is not None:
        check_store_file(file)
        inputs = (args.data, args.frame_labels, args.label_names)
        check_output(file, inputs=[p for p in inputs if p is not None], what="case base file")
        if not file.exists() or file.stat().st_size == 0:
            return  # a new database
    from casebase_store import open_store  # SQLAlchemy: for a store there to read

    try:
        store = open_store(args.db, create=False, readonly=True)
    except EmptyStore:
        return
    try:
        if not args.replace and store.has_case_base(args.name):
            raise StoreError(
                f"a case base named {args.name!r} already exists (choose another --name,"
                " --replace it or --append to it)",
                store.where,
            )
        if args.replace and store.has_case_base(args.name):
            info = store.get_case_base(args.name)
            args.seen = Seen(info.uid, info.version)
    finally:
        store.close()


def _note_shared_names(args: argparse.Namespace, path: Path) -> None:
    """Read a label names file (a bad line: one error, at once) and note which codes share a
    name: their stretches become one activity (meant, to merge two variants of a movement,
    or a slip of the pen). Said with the other notes, once the training is done."""
    from collections import defaultdict

    from features.label_tracks import read_label_names

    codes: dict[str, list[str]] = defaultdict(list)
    for code, name in read_label_names(path).items():
        codes[name].append(code)
    for name, shared in codes.items():
        if len(shared) > 1:
            _note(
                args,
                f"note: codes {', '.join(shared[:-1])} and {shared[-1]} of {shown(path)} are "
                f"{'both' if len(shared) == 2 else 'all'} named {shown(name)}: one activity",
            )


def _note_csv_names(args: argparse.Namespace) -> None:
    """The codes that share a name in the ``label_names`` files of a labels CSV's recordings
    labelled over time, each file once, as ``--label-names`` (the stretches of such codes
    were merged in silence)."""
    from features.datasets import detect_kind
    from features.labels_csv import read_labels_csv

    data = Path(args.data)
    if args.frame_labels is not None or detect_kind(data) != "csv":
        return
    files: list[Path] = []
    for rec in read_labels_csv(data if data.is_file() else data / "labels.csv"):
        names = rec["track"].names if rec["track"] is not None else None
        if names is not None and names not in files:
            files.append(names)
    for names in files:
        _note_shared_names(args, names)


def _note_several_activities(args: argparse.Namespace, entries: list[Any]) -> None:
    """A note when a repetition check (``--target`` another column than the activity) is
    trained on clips of several activities: each repetition is then judged among every
    activity's cases, where ``compare --target`` trains one case base per activity, which
    judged held-out people's repetitions better (README, "A patient's session"). Not said
    of an ``--append``, which adds to a case base as it was trained."""
    if args.target == "label" or args.append:
        return
    activities = sorted({str(e.entry.label) for e in entries})
    if len(activities) < 2:
        return
    _note(
        args,
        shown(
            f"note: a case base predicting {args.target!r} of {len(activities)} activities "
            f"({first_few(activities)}): each repetition is judged among every activity's "
            "cases; one per activity (posecbr train DATA --labels ACTIVITY --target "
            f"{args.target}, as compare --target {args.target} trains them) judges it among "
            "its own activity's cases only: expect more of a new person's repetitions judged "
            'right (README, "A patient\'s session, repetition by repetition")'
        ),
    )


def _note_unlisted(args: argparse.Namespace) -> None:
    """A note naming a few of the pose files in DATA, a folder read through its labels.csv,
    that labels.csv does not list (copied in by hand beside the listed ones): the training
    leaves them out (it reads labels.csv and walks nothing), which it did in silence.
    ``extract`` and ``convert`` refuse to make such a folder; one made by hand is trained as
    its labels.csv says, and said."""
    from features.datasets import unlisted_pose_files

    if args.frame_labels is not None:
        return
    unlisted = unlisted_pose_files(args.data)
    if unlisted:
        listing = Path(args.data) / "labels.csv"
        _note(
            args,
            f"note: {shown(listing)} does not list {counted(len(unlisted), 'pose file')} in"
            f" {shown(args.data)} ({shown(first_few(unlisted))}): train reads it alone and"
            " left them out; add a row for each to it (path,label[,subject]) to train with"
            " them",
        )


def _read_frame_labels(args: argparse.Namespace) -> None:
    """Read the ``--frame-labels`` file (and its names) before the recording: a malformed or
    empty label file is one error at once, not after the recording is decoded (a video's
    poses estimated); so is a count that does not fit a pose file's or a constant-rate
    video's frames (:func:`features.stretches.check_track`). Other recordings' counts are
    checked once read."""
    from features.label_tracks import LabelTrack
    from features.stretches import check_track

    track = LabelTrack(args.frame_labels, args.label_block, args.label_names)
    check_track(Path(args.data), track, args.fps)


def _check_overlaps(args: argparse.Namespace) -> None:
    """Refuse, before any clip is read, a labels CSV giving frames of one file two labels
    (rows whose start,end overlap; among the --labels asked for)."""
    from features.datasets import check_no_overlaps

    if args.frame_labels is None:
        activities = [s.strip() for s in args.labels.split(",")] if args.labels else None
        check_no_overlaps(args.data, activities)


def _over_time(args: argparse.Namespace) -> bool:
    """Whether DATA is recordings labelled over time: ``--frame-labels``, or a labels CSV with
    a ``label_file`` (read once, after the store is checked)."""
    from features.datasets import labelled_over_time

    return args.frame_labels is not None or labelled_over_time(args.data)


def _default_split(args: argparse.Namespace) -> str:
    """What a case is when ``--split`` is left out: a window for recordings labelled over time
    (``--frame-labels``, a labels CSV with a ``label_file``), as ``segment`` and ``watch`` cut
    the recordings they label, else the clip. A labelled stretch of a long recording is many
    repetitions: as one case, the few cases of each activity lie far from any window, and
    from a new stretch too, and both segment and classify far worse than with a case per
    window (docs/measurements.md, "Figures behind the code's rules: A case per labelled
    stretch against a case per window")."""
    if not args.over_time:
        return "clips"
    if args.scheduler is not None:
        raise ConfigError(
            "recordings labelled over time are cut into windows in this process: leave out "
            "--scheduler, or give --split clips to keep each labelled stretch one case",
            "--scheduler",
        )
    _note(
        args,
        "recordings labelled over time: a case per window, as segment and watch cut "
        "recordings (--split clips: a case per labelled stretch)",
    )
    return "windows"


def _note_cut_stretches(args: argparse.Namespace, entries: list[Any]) -> None:
    """A note when the clips, one case each by default, are labelled stretches that
    ``convert`` cut from recordings labelled over time (pose files whose metadata names the
    recording they came from and where in it they start), each long enough to hold several
    repetitions: such a stretch as one case lies far from any window (:func:`_default_split`),
    so ``train`` of the labels CSV that cut them makes a case per window. A file that cannot
    be read is left to the training to refuse."""
    from features.clips import POSE_SUFFIXES
    from features.errors import PoseFileError
    from features.poses import pose_file_length, pose_file_metadata
    from features.repetitions import WINDOW_S

    if args.split != "clips":
        return
    starts: dict[str, set[int]] = {}
    seconds: list[float] = []
    try:
        for e in entries:
            path = Path(e.entry.path)
            if path.suffix.lower() not in POSE_SUFFIXES:
                continue
            meta = pose_file_metadata(path)
            if meta.get("origin") is None or meta.get("frame_offset") is None:
                continue
            starts.setdefault(str(meta["origin"]), set()).add(int(meta["frame_offset"]))
            n_frames, fps = pose_file_length(path)
            seconds.append(n_frames / fps)
    except (PoseFileError, TypeError, ValueError):
        return
    cut = {origin: s for origin, s in starts.items() if len(s) > 1}
    n = sum(len(s) for s in cut.values())
    if not cut or sorted(seconds)[len(seconds) // 2] < 2 * WINDOW_S:
        return
    _note(
        args,
        f"note: {counted(n, 'clip')} are labelled stretches cut from"
        f" {counted(len(cut), 'recording')} (their metadata says so), one case each;"
        f" --split windows makes a case per {WINDOW_S:g}-s window, as segment and watch cut"
        " recordings and as train does of a recording with its label file",
    )


def _check_one_recording(args: argparse.Namespace) -> None:
    """``--frame-labels`` labels DATA, one recording: not a labels CSV (it names a label file
    per recording), and one person's (no --subjects)."""
    if Path(args.data).suffix.lower() == ".csv":
        raise ConfigError(
            "labels one recording, and DATA is a labels CSV: name each recording's label file"
            " in its label_file column (with label_block_s, label_names) instead",
            "--frame-labels",
        )
    if args.subjects is not None:
        raise ConfigError(
            "--frame-labels labels one recording: its stretches are one person's (a labels "
            "CSV with a label_file column takes --subjects over several)",
            "--subjects",
        )


def _data_columns(args: argparse.Namespace) -> list[str]:
    """The columns the clips to train on may have a value of, found from names and labels
    CSVs alone (:func:`features.datasets.dataset_columns`), for a mistyped ``--target``'s
    guess; none of data that cannot be listed (what is wrong with it is told when it is
    read)."""
    from features.datasets import dataset_columns

    try:
        return dataset_columns(args.data, sensor=args.sensor)
    except (PosecbrError, OSError):
        return []


def _append_name(args: argparse.Namespace) -> str:
    """The case base ``--append`` adds to: ``--name``, else the store's only one, as
    ``classify``, ``segment`` and ``watch`` take it. A store of several is refused naming
    them ("choose one with --name"), as they refuse it: the cases went to the one named
    :data:`DEFAULT_NAME` without a word, whichever the user meant. A store of none: the
    append refuses :data:`DEFAULT_NAME` (no case base to add to)."""
    from casebase_store import open_store

    if args.name is not None:
        return str(args.name)
    with as_options(DB):
        store = open_store(args.db, create=False, readonly=True)
    try:
        names = [cb.name for cb in store.list_case_bases()]
        with as_options(NAME):
            return store.choose(None) if names else DEFAULT_NAME
    finally:
        store.close()


def _check_name(args: argparse.Namespace) -> None:
    """``--name``: :data:`DEFAULT_NAME` for a new case base when left out (``--append``'s
    is found once the store is open, :func:`_append_name`); an empty one refused, and a new
    one no store can hold, before training."""
    if args.name is None and not args.append:
        args.name = DEFAULT_NAME
    if args.name is not None and not args.name.strip():
        raise ConfigError("the case base name is empty", "--name")
    if not args.append:
        from casebase_store import check_case_base_name

        check_case_base_name(args.name, "--name")


def _check_options(args: argparse.Namespace) -> None:
    """Refuse options that cannot work together, in one line, before any clip is read."""
    _check_name(args)
    in_csv = "a labels CSV gives it in its label_block_s or label_names column"
    converted = "the one recording it labels; convert a dataset's recordings first: "
    converted += "posecbr convert --asf --fps"
    for option, value, instead in (
        ("--label-block", args.label_block, in_csv),
        ("--label-names", args.label_names, in_csv),
        ("--asf", args.asf, converted),
        ("--fps", args.fps, converted),
    ):
        if value is not None and args.frame_labels is None:
            raise ConfigError(f"goes with --frame-labels ({instead})", option)
    block = args.label_block
    if block is not None and not (math.isfinite(block) and block > 0):
        raise ConfigError(f"must be a finite number of seconds > 0, got {block:g}", "--label-block")
    check_asf(args.asf, [args.data])
    if args.frame_labels is not None:
        _check_one_recording(args)
    check_fps(args.fps)
    args.sensor = sensor_for(args.sensor, [args.data])
    if args.label_names is not None:
        _note_shared_names(args, args.label_names)
    if args.frame_labels is not None:
        _read_frame_labels(args)
    with as_options(SCHEDULER):
        check_scheduler(args.scheduler)
    if args.scheduler is not None and _in_memory(args):
        raise ConfigError(
            "--frame-labels and --split read DATA in this process; leave out --scheduler "
            "(or extract and cut the clips first)",
            "--scheduler",
        )


def run(args: argparse.Namespace) -> int:
    args.notes = []
    args.kept_whole = set()  # --split repetitions: the clips with none, kept whole
    _check_options(args)  # before the training's imports (seconds): a bad option at once
    from casebase_store import prepare_write

    split_defaulted = args.split is None and not args.append
    if str(args.db).strip():  # a writer: refused where it cannot write, before any work
        prepare_write(args.db)
    if args.append:
        _check_append(args)
        args.name = _append_name(args)
        columns = _data_columns(args) if args.target is not None else []
        from cbr.training import append_plan

        with as_options(CLIP_OPTIONS):
            plan, uid, args.split, args.target = append_plan(
                args.db, args.name, args.target, args.split, columns
            )
        args.over_time = _over_time(args)
        _note_csv_names(args)
        _note_unlisted(args)
        _check_overlaps(args)
    else:
        args.target = args.target or "label"
        _check_new_store(args)
        args.over_time = _over_time(args)
        _note_csv_names(args)
        _note_unlisted(args)
        _check_overlaps(args)
        args.split = args.split or _default_split(args)
        estimator = _estimator(args)
        from cbr.training import fit_plan  # the training's modules: after the refusals above

        plan = fit_plan(estimator)
    from cbr.training import ClipsFailed, append_described, describe_entries, train_described

    try:
        if _in_memory(args):
            clips, solutions = _described_in_memory(args, plan)
        else:
            entries = _entries(args)
            _one_listed_activity(args, entries)
            if split_defaulted:
                _note_cut_stretches(args, entries)
            _note_several_activities(args, entries)
            with as_options(CLIP_OPTIONS):  # a clip without a target, a lost scheduler
                clips, solutions = describe_entries(entries, plan, args.target, args.scheduler)
            _check_asked(args, clips, solutions)
    except ClipsFailed as exc:
        for line in exc.lines:
            said = said_as_options(line, CLIP_OPTIONS)
            print(f"posecbr train: error: {shown(said)}", file=sys.stderr)
        raise
    if not clips:
        raise _no_clips(args)
    # why each clip that shows no torso is skipped, in the order training names them
    args.no_torso = [c.no_torso for c in clips if c.torso_share == 0.0]
    _note_assumed_rates(args, clips)
    if args.append:
        result = append_described(args.db, args.name, clips, solutions, plan, uid)
    else:
        _one_activity(args, solutions)
        _check_k(args, clips)
        with as_options(PARAMETER_OPTIONS):  # trimmed below k
            result = train_described(args.db, args.name, clips, solutions, estimator,
                                     target=args.target, cases=args.split,
                                     replace=args.replace, seen=args.seen)  # fmt: skip
    for text in args.notes:
        print(text, file=sys.stderr)
    _report(args, result)
    return 0


def _note_assumed_rates(args: argparse.Namespace, clips: list[Any]) -> None:
    """The clips' recordings read at a rate their reader assumed (an AMC file carries none,
    :func:`posecbr.recordings.assumed_rates_note`), said with the other notes once trained:
    given with ``--fps`` for ``--frame-labels``' one recording, else by converting DATA."""
    how = GIVE_FPS if args.frame_labels else give_fps_by_converting(args.data)
    note = assumed_rates_note([(c.source, *c.rate) for c in clips if c.rate is not None], how)
    if note is not None:
        _note(args, note)


def _skipped(
    nobody: list[str],
    short: list[str],
    split: str,
    kept_whole: Collection[str] = (),
    no_torso: Sequence[str] = (),
) -> str:
    """The pieces that show no person, by their file (a recording cut into windows has many:
    each file once, with how many of its pieces), and those shorter than one movement can be
    (:func:`cbr.training.usable` names them with their length). Cut into repetitions, a
    piece that shows no person, or a short one, from a clip in ``kept_whole`` is that clip
    (one with no repetition: it was said to be "kept whole", not a repetition); another is
    a repetition (one with the hips out of view is cut into repetitions counted from the
    arms: it was said to be as many clips).
    ``no_torso``: each of ``nobody``'s :attr:`cbr.described.DescribedClip.no_torso`, in
    order: those that show some of the torso's joints (the hips out of view) are said to
    show no torso, naming the joints, as ``classify`` and ``segment`` say it (they were said
    to show no person)."""
    whole = [n for n in short if n.rsplit(" (lasts ", 1)[0] in kept_whole]
    cut = [n for n in short if n not in whole]
    shorter = _shorter()
    why_none: dict[tuple[str, str], list[str]] = {}
    for name, why in zip(nobody, _skipped_reasons(nobody, [], no_torso), strict=True):
        kind = "clips" if name in kept_whole else split
        why_none.setdefault((why, kind), []).append(name)
    lines = [
        _listed(
            names, kind, "that " + (why if len(names) == 1 else why.replace("shows ", "show ", 1))
        )
        for (why, kind), names in why_none.items()
    ]
    lines += [
        _listed(names, kind, why)
        for names, kind, why in ((whole, "clips", shorter), (cut, split, shorter))
        if names
    ]
    return "\n".join(lines)


def _shorter() -> str:
    """Why a piece shorter than one movement can be is skipped, in :func:`_skipped`'s words."""
    from features.repetitions import MIN_PERIOD_S

    return f"shorter than one movement can be ({MIN_PERIOD_S:g} s)"


def _skipped_reasons(
    nobody: Sequence[str], short: Sequence[str], no_torso: Sequence[str] = ()
) -> list[str]:
    """Why each of ``nobody``, then each of ``short``, was skipped, in :func:`_skipped`'s
    words: "shows no person", "shows no torso (no frame shows its left hip, right hip)"
    (``no_torso``: each of ``nobody``'s, as :func:`_skipped` takes them), "shorter than one
    movement can be (0.4 s)"."""
    reasons = no_torso if len(no_torso) == len(nobody) else [""] * len(nobody)
    return [why or "shows no person" for why in reasons] + [_shorter()] * len(short)


def _no_case(args: argparse.Namespace, result: Any) -> list[str]:
    """The activities (or another target's classes) this run gave clips of and made no case
    of: every clip of them skipped in training (``result.lost_labels``), and, of activities,
    every labelled stretch of them left out before it as shorter than one movement can be
    (:func:`_long_enough`)."""
    short = getattr(args, "short_only", []) if args.target == "label" else []
    return sorted(set(result.lost_labels) | set(short))


def _lost(labels: list[str], noun: str) -> str:
    """The line naming the ``labels`` (activities, or another target's classes: ``noun``)
    every clip of which was skipped: the case base holds no case of them."""
    them = "it" if len(labels) == 1 else "them"
    names = ", ".join(shown(repr(v)) for v in labels)
    return f"no case of the {noun} {names}: every piece of {them} was skipped, as said above"


def _listed(sources: list[str], split: str, why: str) -> str:
    from collections import Counter

    from cbr.stored import CASE_KINDS

    per_file = Counter(sources)
    names = [shown(f) + (f" ({n})" if n > 1 else "") for f, n in list(per_file.items())[:5]]
    more = " ..." if len(per_file) > 5 else ""
    piece = counted(len(sources), CASE_KINDS.get(split, "clip"))
    return f"skipped {piece} {why}: {', '.join(names)}{more}"


def _indistinct(pairs: list[str], split: str, target: str | None = None) -> str:
    """The note on cases nothing tells apart from a case of another activity (or class, for
    another ``target``)."""
    from cbr.explain import class_noun
    from cbr.stored import CASE_KINDS

    kind = counted(len(pairs), CASE_KINDS.get(split, "clip"))
    more = f" (and {len(pairs) - 1} more)" if len(pairs) > 1 else ""
    return (
        f"note: {kind} with the same features as a case of another {class_noun(target)}: "
        "nothing tells "
        f"them apart (a still stretch, or a file copied under another label?): "
        f"{shown(pairs[0])}{more}"
    )


def _alike_labels(labels: Any) -> list[list[str]]:
    """The groups of two or more ``labels`` that differ only in case or in spaces, hyphens
    and underscores ("deep_squat", "Deep Squat"), or in how Unicode writes the same letters
    ("Plié" with its é as one character or as e and an accent, as some systems save file
    names): most likely one activity spelt two ways."""
    import re
    import unicodedata
    from collections import defaultdict

    groups: dict[str, list[str]] = defaultdict(list)
    for label in labels:
        key = unicodedata.normalize("NFKC", str(label))
        groups[re.sub(r"[\s_\-]+", " ", key).strip().casefold()].append(str(label))
    return [sorted(g) for g in groups.values() if len(g) > 1]


def _notes(args: argparse.Namespace, result: Any) -> None:
    """What the user should know of the case base stored, on stderr: activities spelt two
    ways, cases nothing tells apart, and a case base segment cannot judge unknown
    with. Activities are called classes when the case base predicts another column
    (``--target correct``)."""
    import unicodedata

    from cbr.explain import class_noun

    for group in _alike_labels(result.label_counts):
        # labels that read alike on screen are told apart by their characters' codes
        encoded = len({unicodedata.normalize("NFC", g) for g in group}) == 1
        said = ascii if encoded else repr
        names = " and ".join(", ".join(said(g) for g in group).rsplit(", ", 1))
        how = (
            "are the same letters written with other Unicode characters (an accented letter"
            " as one character or two)"
            if encoded
            else "differ only in case or spacing"
        )
        print(
            shown(
                f"note: {names} {how}: they are {len(group)} "
                f"{class_noun(args.target, len(group))} (one spelt two ways in the labels?)"
            ),
            file=sys.stderr,
        )
    if result.indistinct:
        print(_indistinct(result.indistinct, args.split, args.target), file=sys.stderr)
    if result.new_labels:
        n = len(result.new_labels)
        print(
            shown(
                f"note: {n} {class_noun(args.target, n)} the case base did not hold, added as "
                f"new: {', '.join(result.new_labels)}{_named_by_file(result.file_named_labels)}"
            ),
            file=sys.stderr,
        )
    if result.learned.get("confidence_calibrated_on") == 0:
        from cbr.stored import CASE_KINDS

        pieces = CASE_KINDS.get(args.split, "clip") + "s"
        print(
            f"note: the confidence is the vote share, not calibrated: each "
            f"{class_noun(args.target)}'s training {pieces} came from one recording or person,"
            " so none could be classified held out of it (a second recording or person per"
            f" {class_noun(args.target)} calibrates it)",
            file=sys.stderr,
        )
    _note_chance(args, result)
    if not args.append and not result.judges_unknown:
        # said whatever a case is (the refusal came as a surprise in segment for a case base
        # of clips or repetitions): segment and watch refuse it by default
        from cbr.stored import CASE_KINDS

        why = (
            f"fewer than three {class_noun(args.target, 3)}"
            if len(result.label_counts) < 3
            else f"no {class_noun(args.target)} with {CASE_KINDS.get(args.split, 'clip')}s apart"
            " from each other"
        )
        print(
            f"note: segment and watch cannot tell stretches unlike every {class_noun(args.target)}"
            " with this case"
            f" base ({why}) by default: run them with --unknown held-out",
            file=sys.stderr,
        )


def _named_by_file(labels: list[str]) -> str:
    """Why a new label may be no activity: it is the name of its clip's file, as a pose file
    converted alone is labelled ("" when none is: a labels CSV's or folder's activity)."""
    if not labels:
        return ""
    return (
        f" ({', '.join(labels)}: the name of its file, as a pose file converted alone is labelled)"
    )


def _note_chance(args: argparse.Namespace, result: Any) -> None:
    """A note when the training clips, each classified held out (by subject, recording or
    non-overlapping piece) as the confidence is calibrated, were answered right no more
    often than always answering the commonest class would be: the case base tells its
    classes apart no better than a guess, however sure its explanations read."""
    from cbr.explain import class_noun, label_words
    from cbr.stored import CASE_KINDS

    n = int(result.learned.get("confidence_calibrated_on") or 0)
    accuracy = result.learned.get("held_out_accuracy")
    # the clips held out, not the cases stored: --editor or --trim changes their shares
    counts = result.trained_counts
    if args.append or not n or accuracy is None or len(counts) < 2:
        return
    balanced = result.learned.get("held_out_balanced_accuracy")
    if balanced is not None and len(set(counts.values())) > 1:
        # classes of unequal counts, a class-balanced vote: judged by the mean of each class's
        # share answered right, which always answering one class scores one over the classes
        # (50 correct and 10 incorrect: 83 % for always "correct" by plain accuracy, which a
        # balanced vote that finds the incorrect ones may not beat)
        chance = 1 / len(counts)
        if balanced > chance:
            return
        print(
            shown(
                f"note: held out in turn, the training {CASE_KINDS.get(args.split, 'clip')}s "
                f"of each {class_noun(args.target)} were answered right {percent(balanced, 0)}"
                f" of the time on average, no better than always answering one of the "
                f"{len(counts)} ({percent(chance, 0)}): this case base does not tell its "
                f"{class_noun(args.target, 2)} apart (more people, or clips of one movement "
                "per case base, may)"
            ),
            file=sys.stderr,
        )
        return
    commonest = max(counts, key=lambda k: counts[k])
    share = counts[commonest] / sum(counts.values())
    if accuracy > share:
        return
    right = round(accuracy * n)
    said = label_words(commonest, args.target)
    said = repr(said) if said == commonest else said  # a correct repetition: said in words
    print(
        shown(
            f"note: held out in turn, the training {CASE_KINDS.get(args.split, 'clip')}s were "
            f"answered right {percent(accuracy, 0)} of the time ({right} of {n}), no better "
            f"than always answering {said} ({percent(share, 0)}): this case base does not "
            f"tell its "
            f"{class_noun(args.target, 2)} apart (more people, or clips of one movement per "
            "case base, may)"
        ),
        file=sys.stderr,
    )


def _summary(args: argparse.Namespace, result: Any) -> dict[str, Any]:
    """What ``train --json`` prints."""
    from casebase_store import shown_db

    summary: dict[str, Any] = {
        "db": shown_db(args.db),  # a URL without its password
        "name": result.name,
        "cases": result.n_cases,
        "active_cases": result.n_active,
        "split": args.split,  # what a case is: a clip, a repetition or a window
        "labels": result.label_counts,
        "features": result.config.to_dict(),  # as casebase info --json gives them
        "similarity": result.similarity,
        "learned": result.learned,
        "skipped": result.skipped + result.too_short,
        # each of them with why, as the text's "skipped" lines say it
        "skipped_reasons": [
            {"clip": clip, "reason": reason}
            for clip, reason in zip(
                result.skipped + result.too_short,
                _skipped_reasons(result.skipped, result.too_short, args.no_torso),
                strict=True,
            )
        ],
    }
    if result.maintenance is not None:
        summary["trim"] = result.maintenance.summary()
    if result.indistinct:
        summary["indistinct"] = result.indistinct
    if _no_case(args, result):
        summary["no_case"] = _no_case(args, result)  # every clip of them skipped
    if args.append:
        summary["new_labels"] = result.new_labels
    return summary


def _report(args: argparse.Namespace, result: Any) -> None:
    summary = _summary(args, result)
    _notes(args, result)
    if args.json:
        json.dump(summary, sys.stdout, indent=2, ensure_ascii=False)
        print()
        return
    from cbr.explain import class_noun
    from features.text import shown

    if result.skipped or result.too_short:
        print(
            _skipped(result.skipped, result.too_short, args.split, args.kept_whole, args.no_torso)
        )
    lost = _no_case(args, result)
    if lost:
        print(_lost(lost, class_noun(args.target, len(lost))))

    n = len(result.label_counts)
    activities = f"{n} {class_noun(args.target, n)}"  # classes of another --target
    made = (
        f"({result.n_cases} added, of {activities})"  # the case base may hold more
        if args.append
        else f"({result.n_cases} trained) from {activities}"
    )
    print(
        f"case base {shown(repr(result.name))} in {shown(summary['db'])}: {result.n_active} cases"
        f" {made}"
    )
    print(f"  features: {result.config.describe()}; similarity: {result.similarity['name']}")
    learned = result.learned
    if learned:
        chosen = f"  side handling: {learned['side']}; feature weights: "
        chosen += str(learned["feature_weights"])
        if learned["phases"]:
            chosen += f"; means over {learned['phases']} phases"
        if learned["mirror_cases"]:
            chosen += f"; {learned['mirror_cases']} mirror-image cases"
        print(chosen)
    for lab, n in result.label_counts.items():
        print(f"  {n:5d}  {shown(lab)}")
    if result.maintenance is not None:
        print(f"  {result.maintenance.summary()}")
