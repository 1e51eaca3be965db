"""``posecbr compare DATA``: cross-validate every similarity x feature level, DAD and peer
classifiers on a labelled dataset and print the table (JSON, CSV and pictures on request)."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shlex
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from features.cluster import SCHEDULER_HELP, check_scheduler
from features.errors import ConfigError, DataError, PosecbrError
from features.fileio import check_output, stdout_gone, write_json_atomic, write_together
from features.interrupts import interrupts_held
from features.text import shown
from posecbr.arguments import (
    add_k_option,
    as_options,
    check_each_found,
    param_value,
    path_arg,
)
from posecbr.recordings import (
    add_sensor_option,
    assumed_rates,
    assumed_rates_note,
    give_fps_by_converting,
    sensor_for,
)


def _names(text: str) -> tuple[str, ...]:
    return tuple(s.strip() for s in text.split(",") if s.strip())


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "compare",
        epilog="example: posecbr compare labels.csv --out results/",
        help="cross-validate similarity measures x feature levels, DAD and peers on a dataset",
        description="Cross-validation by subject (leave-one-subject-out by default) of every "
        "case-base configuration (similarity x feature level), the DAD expert system and "
        "peer classifiers on the same folds. Prints accuracy and macro-F1 with 95 % "
        "intervals, times, case-base sizes and McNemar's exact test against the best method. "
        "With --target other than label (e.g. correct), one model is trained per activity.",
    )
    p.add_argument(
        "data",
        type=path_arg,
        help="dataset: UI-PRMD or HDM05 folder, labels CSV, folder per class, ...",
    )
    p.add_argument(
        "--target",
        default="label",
        help="what to predict: label (default), correct, or another metadata column",
    )
    p.add_argument(
        "--within",
        default="auto",
        metavar="COLUMN",
        help="train one model per value of COLUMN (default: per activity label when "
        "--target is not label); 'none' for one model over all clips",
    )
    p.add_argument(
        "--cv",
        choices=("loso", "kfold"),
        default=None,
        help="leave-one-subject-out (default; falls back to stratified k-fold, with a "
        "note, when there is a single subject, and is refused then when asked for by "
        "--cv loso) or stratified k-fold over clips",
    )
    p.add_argument(
        "--folds",
        type=int,
        default=None,
        metavar="K",
        help="folds for kfold, also the k-fold a dataset of one subject falls back to "
        "(default 5); refused with --cv loso, whose folds are the subjects",
    )
    p.add_argument(
        "--similarities",
        default="euclidean,dtw,signature",
        metavar="LIST",
        help="comma-separated similarity measures (default: all three)",
    )
    p.add_argument(
        "--features",
        default="fluents,qmp",
        metavar="LIST",
        help="comma-separated feature levels (default: fluents,qmp)",
    )
    p.add_argument("--no-dad", action="store_true", help="leave out the DAD baseline")
    p.add_argument(
        "--peers",
        default=None,
        metavar="LIST",
        help="peer classifiers: dtw-knn (tslearn), minirocket (needs sktime or "
        "aeon: named here without them, refused before the run); default: both, "
        "minirocket skipped with a note when it cannot run; 'none' for no peers",
    )
    add_k_option(p, 5, ", in the case-base classifier (default 5), as train -k")
    p.add_argument(
        "--trim",
        type=float,
        default=None,
        metavar="F",
        help="keep fraction F of each activity's cases (novelty/benefit trimming) in "
        "every fold (default: keep all)",
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a further CaseBaseClassifier parameter for every case-base configuration "
        "(repeatable; VALUE is JSON or a plain string), e.g. --param states=all --param length=48",
    )
    add_sensor_option(p)
    p.add_argument(
        "--labels",
        default=None,
        metavar="LIST",
        help="only these activities, comma-separated, e.g. deep_squat,hurdle_step (default all)",
    )
    p.add_argument(
        "--subjects",
        default=None,
        metavar="LIST",
        help="only these subjects, comma-separated, e.g. s01,s02 (default all)",
    )
    p.add_argument(
        "--jobs",
        "--workers",  # as extract's worker processes are asked for
        dest="jobs",
        type=int,
        default=1,
        metavar="N",
        help="worker processes for the folds (default 1: all in this process)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS|local:N", help=SCHEDULER_HELP)
    p.add_argument(
        "--seed", type=int, default=0, help="seed for k-fold, bootstrap, MiniRocket (default 0)"
    )
    p.add_argument(
        "--explain",
        type=int,
        default=5,
        metavar="N",
        help="explain N misclassified clips of the best case-base configuration (default 5)",
    )
    p.add_argument(
        "--json",
        type=path_arg,
        metavar="FILE",
        help="write all results as JSON to FILE (a file, unlike other commands' --json: the "
        "table still goes to standard output)",
    )
    p.add_argument("--csv", type=path_arg, metavar="FILE", help="write one row per method as CSV")
    p.add_argument(
        "--out",
        type=path_arg,
        metavar="DIR",
        help="write results.json, results.csv and the pictures to DIR "
        "(then `posecbr report DIR --out report.html`)",
    )
    p.set_defaults(func=run)


def parse_params(items: list[str]) -> dict[str, Any]:
    """``KEY=VALUE`` pairs; VALUE read as JSON when it parses (numbers, lists), else a string."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"expected KEY=VALUE, got {item!r}", "--param")
        out[key.strip()] = param_value(key.strip(), raw)
    return out


def _load(args: argparse.Namespace, settings: Any) -> list[Any]:
    """The clips of DATA that ``--labels`` and ``--subjects`` keep, read; what the listing
    (labels CSV rows, file and folder names, a pose file's metadata) shows wrong refused
    before the first clip is decoded (:func:`_check_listed`)."""
    from features.datasets import dataset_entries
    from features.progress import progress

    if not args.data.exists():
        raise DataError("no such dataset (file or folder)", args.data)
    kw: dict[str, Any] = {"sensor": sensor_for(args.sensor, [args.data])}
    if args.labels:
        kw["labels"] = set(_names(args.labels))
    if args.subjects:
        kw["subjects"] = set(_names(args.subjects))
    entries = dataset_entries(args.data, **kw)
    _check_listed(args, settings, entries, kw)
    from cbr.casebase import frames_of  # after the refusals: the store's modules come with it
    from cbr.training import check_listed_once

    clips = [c for e in progress(entries, "loading", total=len(entries), unit="clip")
             for c in e.read()]  # fmt: skip
    # as train and classify: a clip listed twice would be tested twice, and in k-fold folds
    # one copy could be a training case of the other
    check_listed_once([(c.seq.source, *frames_of(c.seq)) for c in clips], str(args.data),
                      "it would be tested twice, or be a training case of itself")  # fmt: skip
    _check_found(args, [c.label for c in clips], [c.subject for c in clips], kw)
    return clips


def _check_found(
    args: argparse.Namespace, labels: list[Any], subjects: list[Any], kw: dict[str, Any]
) -> None:
    """Refuse a ``--labels`` or ``--subjects`` entry none of the clips (their ``labels`` and
    ``subjects``) has, naming those the data hold."""
    from features.datasets import dataset_labels, dataset_subjects

    def held_labels() -> Sequence[str]:
        return list(dataset_labels(args.data, sensor=kw["sensor"]))

    def held_subjects() -> Sequence[str]:
        return list(dataset_subjects(args.data, sensor=kw["sensor"]))

    check_each_found(
        [
            (labels, kw.get("labels"), "--labels", "labelled", held_labels),
            (subjects, kw.get("subjects"), "--subjects", "of subject", held_subjects),
        ],
        args.data,
    )


def _check_listed(
    args: argparse.Namespace, settings: Any, entries: list[Any], kw: dict[str, Any]
) -> None:
    """Before any clip is decoded, when the listing tells every clip's label and subject
    (:meth:`features.datasets.DatasetEntry.listed`): the refusals of a ``--labels`` or
    ``--subjects`` entry no clip has, of ``--cv loso`` on one subject, of one class
    (``--labels deep_squat``), of a ``--target`` the clips lack and of a ``-k`` above the
    smallest training fold (:func:`cbr.evaluation.folds.check_listed`), in the words they
    had once every clip was read (seconds to minutes of decoding for a typo). Otherwise
    they come after it. The pose files' metadata is read only when the names and rows do
    not tell (a tenth of a second for the demo's 180 files, a quarter of their decoding)."""
    from cbr.evaluation.folds import check_listed

    for metadata in (False, True):
        listed = [e.listed(metadata) for e in entries]
        if any(one is None for one in listed):
            continue
        clips = [c for one in listed for c in one]
        _check_found(args, [c.label for c in clips], [c.subject for c in clips], kw)
        with as_options(OPTIONS):
            check_loso_possible(settings, clips, args.data)
            if check_listed(clips, settings, str(args.data)):
                return


def _dataset_files(args: argparse.Namespace) -> list[str | Path]:
    """Every file of the dataset, from names and listings (no clip read): each clip's file,
    also those ``--labels`` and ``--subjects`` leave out, the labels CSV and the label files
    of recordings labelled over time; an output is none of them."""
    from features.datasets import dataset_files

    if not args.data.exists():
        raise DataError("no such dataset (file or folder)", args.data)
    return [*dataset_files(args.data, sensor=sensor_for(args.sensor, [args.data]))]


def _peers(given: str | None) -> tuple[str, ...]:
    """The peers ``--peers`` names (``None``: not given, every peer)."""
    from cbr.evaluation.settings import PEERS

    if given is None:
        return tuple(PEERS)
    return () if given.strip().lower() == "none" else _names(given)


def check_peers_can_run(args: argparse.Namespace, settings: Any) -> None:
    """Refuse, before any clip is read, a peer ``--peers`` names that cannot run here
    (MiniRocket without sktime or aeon): the run would take its minutes and leave out the
    method asked for in a note. Not given, the peers that cannot run are skipped so."""
    from cbr.evaluation.methods import methods_for, why_unavailable

    if args.peers is None:
        return
    for method in methods_for(settings):
        why = why_unavailable(method, [], settings.target) if method.kind == "peer" else None
        if why:
            raise ConfigError(f"{method.name} cannot run here: {why}", "--peers")


def check_folds_given_with_kfold(args: argparse.Namespace) -> None:
    """Refuse ``--folds`` with ``--cv loso``: its folds are the subjects, and the k-fold a
    dataset of one subject falls back to is refused by name (it was ignored in silence)."""
    if args.cv == "loso" and args.folds is not None:
        raise ConfigError(
            "goes with --cv kfold (or with no --cv, for the k-fold a dataset of one subject"
            " falls back to); --cv loso holds out one subject per fold",
            "--folds",
        )


def check_loso_possible(settings: Any, clips: list[Any], data: Path) -> None:
    """Refuse ``--cv loso`` asked for by name on clips (of ``data``) it cannot hold out by
    subject (one subject, or clips without one): the run fell back to k-fold over clips,
    whose figures (the same person in training and test) pass for a person's never seen. Not
    given, the fallback is taken and said in a note. Said of ``cv`` (:func:`as_options` says it of
    ``--cv``); the clips the comparison leaves out are refused so once read, naming them
    (:func:`cbr.evaluation.folds.make_folds`)."""
    from cbr.evaluation.folds import loso_refusal

    if settings.cv != "loso":
        return
    refused = loso_refusal([c.subject for c in clips], str(data))
    if refused is not None:
        raise refused


def check_kept(settings: Any, clips: list[Any], data: Path) -> None:
    """The refusals of the clips read of ``data`` the comparison keeps (those showing no
    person, too short, or of a class of a single clip left out:
    :func:`cbr.evaluation.data.prepare`) under leave-one-subject-out, before the comparison's
    modules (scikit-learn among them) are imported, in its words: ``--cv loso`` asked for by
    name on clips of one subject, naming the clips of the subjects left out (it fell back
    to k-fold over clips with a note, as when ``--cv`` is not given), a ``-k`` above the
    smallest fold's training clips and ``--within`` groups each inside one fold
    (:func:`cbr.evaluation.folds.check_k`, :func:`~cbr.evaluation.folds.check_within`).
    K-fold's folds are left to the comparison, which imports scikit-learn for them."""
    from cbr.evaluation.data import prepare
    from cbr.evaluation.folds import check_k, check_within, loso_impossible, make_folds

    if settings.cv == "kfold":
        return
    kept = prepare(clips, settings, str(data))
    if settings.cv is None and loso_impossible(kept.subjects) is not None:
        return
    _, folds, _ = make_folds(kept, settings, str(data))  # "loso", or refused
    check_k(settings, folds)
    check_within(kept.within, folds, settings.within_column)


#: the arguments of CompareSettings (and of the checks of its values) as compare's options
OPTIONS = {
    "cv": "--cv",
    "folds": "--folds",
    "similarities": "--similarities",
    "features": "--features",
    "peers": "--peers",
    "k": "--k",
    "trim": "--trim",
    "cbr_params": "--param",
    "jobs": "--jobs",
    "scheduler": "--scheduler",
    "seed": "--seed",
    "explain": "--explain",
    "within": "--within",
}


def _settings(args: argparse.Namespace) -> Any:
    from cbr.evaluation.settings import CompareSettings

    return CompareSettings(
        target=args.target,
        cv=args.cv,  # None: leave one subject out, or k-fold with a note when impossible
        folds=5 if args.folds is None else args.folds,
        similarities=_names(args.similarities),
        features=_names(args.features),
        dad=not args.no_dad,
        peers=_peers(args.peers),
        k=args.k,
        trim=args.trim,
        cbr_params=parse_params(args.param),
        within=None if args.within.lower() == "none" else args.within,
        jobs=args.jobs,
        scheduler=args.scheduler,
        seed=args.seed,
        explain=args.explain,
    )


@dataclass(frozen=True)
class Output:
    """A file the run writes: what it is (for messages), where, and as "json" or "csv";
    ``in_out_folder``: a file in the folder ``--out`` makes (which may not exist yet)."""

    what: str
    path: Path
    format: str
    in_out_folder: bool = False


def _check_out_folder(out: Path, data: Path) -> None:
    """``--out``: a folder, or a new one in a folder that exists; not the data folder (the
    results and pictures would be written among the clips)."""
    if str(out) == "-":  # standard output's name, not a folder "-"
        raise DataError("--out is a folder for the results and pictures: name the folder", out)
    if out.exists() and not out.is_dir():
        raise DataError("--out must be a folder, and this is a file", out)
    if not out.parent.is_dir():
        raise DataError("the folder for --out does not exist", out.parent)
    if data.exists() and out.resolve() == data.resolve():
        raise DataError(
            "--out is the data folder: the results and pictures would be written among the"
            " clips; choose another folder",
            out,
        )
    _check_results_are_ours(out)


def _is_compare_results(path: Path) -> bool:
    """Whether ``path`` is a results file ``compare`` wrote (its ``kind``), of any version."""
    from cbr.evaluation.report import MAX_RESULTS_BYTES
    from cbr.evaluation.results import KIND

    try:
        if not path.is_file() or path.stat().st_size > MAX_RESULTS_BYTES:
            return False
        doc = json.loads(path.read_bytes())
    except (OSError, ValueError, RecursionError):  # unreadable, not JSON (nor UTF-8)
        return False
    return isinstance(doc, dict) and doc.get("kind") == KIND


def _check_results_are_ours(out: Path) -> None:
    """Refuse an ``--out`` folder whose ``results.json`` or ``results.csv`` an earlier
    ``compare`` did not write (another tool's, the user's own): a run replaces its own
    results there, never someone else's file of the same name (it did, silently)."""
    ours = _is_compare_results(out / "results.json")
    for name in ("results.json", "results.csv"):
        path = out / name
        if (path.exists() or path.is_symlink()) and not ours:
            raise DataError(
                f"holds {name}, not written by posecbr compare, which would replace it:"
                " choose another --out",
                out,
            )


def _outputs(args: argparse.Namespace) -> list[Output]:
    """Every file the run will write; ``--out`` is checked to be a folder, or a new one in a
    folder that exists."""
    out = []
    new_out = args.out is not None and not args.out.exists()  # made before anything is written

    def inside(path: Path) -> bool:
        return new_out and path.parent.resolve() == args.out.resolve()

    if args.json:
        out.append(Output("JSON output", args.json, "json", inside(args.json)))
    if args.csv:
        out.append(Output("CSV output", args.csv, "csv", inside(args.csv)))
    if args.out:
        _check_out_folder(args.out, args.data)
        out.append(Output("results file", args.out / "results.json", "json", True))
        out.append(Output("results table", args.out / "results.csv", "csv", True))
    for i, o in enumerate(out):  # the second written would replace the first
        for other in out[:i]:
            if o.path.resolve() == other.path.resolve():
                raise DataError(f"the {other.what} and the {o.what} are the same file", o.path)
    return out


def check_outputs(outputs: list[Output], inputs: list[str | Path]) -> None:
    """Refuse, before any work, an output that is a folder, lies in a missing folder (a new
    ``--out`` folder is made), in a folder that cannot be written, or would overwrite an
    input."""
    for o in outputs:
        new_folder = o.in_out_folder and not o.path.parent.exists()
        check_output(o.path, inputs=inputs, what=o.what, make_parents=new_folder)


def _pictures_seen_from(pictures: Any, results_file: Path, out: Path) -> Any:
    """``pictures`` (named in the ``--out`` folder) as a results file at ``results_file``
    names them: from its own folder, which ``posecbr report`` reads them from; none when
    ``--out`` is not inside that folder (the report draws what the results hold)."""
    from cbr.evaluation.results import Pictures, is_inside_name

    try:
        rel = Path(os.path.relpath(out.resolve(), results_file.parent.resolve())).as_posix()
    except ValueError:  # another drive
        return Pictures()
    if rel == ".":
        return pictures
    return pictures.under(rel) if is_inside_name(rel) else Pictures()


def _write_results(
    results: Any, outputs: list[Output], out: Path | None = None, before: str = "the earlier"
) -> None:
    """The results as JSON and CSV to every output asked for, as one write: each staged
    under a temporary name beside it, then all renamed into place (before, each was written
    in turn: a disk full or a write refused on results.csv left the new results.json beside
    the earlier run's table); a failure leaves every one as it was (``before``: what the
    refusal calls them). A JSON file names the pictures drawn into ``out`` from its own
    folder."""
    from cbr.evaluation.tables import csv_rows, write_csv

    def writer(o: Output) -> Callable[[Path], object]:
        if o.format == "csv":
            return lambda path: write_csv(csv_rows(results), path)
        doc = results.to_dict()
        if out is not None:
            doc["pictures"] = _pictures_seen_from(results.pictures, o.path, out).to_dict()
        return lambda path: write_json_atomic(path, doc)

    write_together([(o.path, writer(o)) for o in outputs], before)


def _draw_pictures(run_: Any, out: Path, trim: float | None) -> None:
    """Every picture into ``out``, one at a time; one that fails is a note and a line on
    stderr, never the end of the run."""
    from cbr.evaluation.pictures import Drawing, data_pictures, result_pictures
    from cbr.evaluation.results import Pictures

    drawing = Drawing()
    # named as each is drawn: a run interrupted meanwhile names those on disk (_interrupted)
    run_.results.pictures = pics = Pictures()
    try:
        result_pictures(run_.results, out, drawing, into=pics)
        data_pictures(run_, out, trim, drawing, into=pics)
    except KeyboardInterrupt:  # the picture being drawn may be on disk, not yet named: gone
        if drawing.drawing is not None and drawing.drawing.name not in pics.files():
            drawing.drawing.unlink(missing_ok=True)
        raise
    for line in drawing.failures:
        print(shown(line), file=sys.stderr)  # a label's character it names, escaped
    run_.results.notes += drawing.failures


def _earlier_pictures(out: Path) -> list[str]:
    """The pictures the results file of an earlier comparison in ``out`` names (none when
    there is none, or it cannot be read): those this run does not draw again are removed
    after it has drawn its own (:func:`_remove_stale`)."""
    from cbr.evaluation.report import load_results

    if not (out / "results.json").is_file():
        return []
    try:
        return load_results(out / "results.json")[0].pictures.files()
    except PosecbrError:
        return []


def _remove_stale(out: Path, earlier: list[str], drawn: list[str]) -> None:
    """Remove the PNG pictures of an earlier comparison in ``out`` this one did not draw
    again: a confusion matrix of a method this run has not, or a timeline of an activity it
    has not, lay beside its results as if it were one of them."""
    from cbr.evaluation.report import PNG_MAGIC

    for name in sorted(set(earlier) - set(drawn)):
        path = out / name
        if path.parent != out or path.is_symlink() or not path.is_file():
            continue  # in a folder of its own: another run's, which its results name
        with open(path, "rb") as fh:
            if fh.read(len(PNG_MAGIC)) != PNG_MAGIC:
                continue
        path.unlink(missing_ok=True)


def _write_outputs(
    run_: Any, args: argparse.Namespace, outputs: list[Output], earlier: list[str]
) -> None:
    """The results files; with ``--out`` (made first) the pictures into it, then the results
    file again, naming them, the earlier run's pictures not drawn again removed.

    The results files are all whole before any picture is drawn: Ctrl-C or SIGTERM while
    they are written is held until every one is (before: one between results.json and
    results.csv left the new JSON beside the earlier run's table; in a new ``--out`` folder,
    one while results.json was written left the folder empty), then said as one while the
    pictures are drawn (:func:`_interrupted`)."""
    results = run_.results
    try:
        with interrupts_held():
            _write_first(results, outputs, args.out)
        for given, what in ((args.json, "results"), (args.csv, "results table")):
            if given:  # the files named by --json / --csv, as every command's "written to"
                print(f"{what} written to {shown(given)}", file=sys.stderr)
        if args.out:
            _draw_pictures(run_, args.out, args.trim)
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: the results are whole
        if args.out:
            raise KeyboardInterrupt(_interrupted(results, outputs, args.out, earlier)) from None
        written = " and ".join(shown(str(o.path)) for o in outputs)
        raise KeyboardInterrupt(f"results written to {written}" if outputs else "") from None
    if args.out:
        _name_pictures(results, outputs, args.out, earlier)


def _write_first(results: Any, outputs: list[Output], out: Path | None) -> None:
    """The results files, before any picture, with ``--out`` made first; when they cannot be
    written (each left as it was) an ``--out`` folder made for them is removed again."""
    made = out is not None and not out.exists()
    if out is not None:
        out.mkdir(exist_ok=True)
    try:
        _write_results(results, outputs)
    except PosecbrError:
        if out is not None and made:
            with contextlib.suppress(OSError):
                out.rmdir()  # empty: nothing was written in it
        raise


def _name_pictures(results: Any, outputs: list[Output], out: Path, earlier: list[str]) -> None:
    """Once every picture is drawn: the earlier run's not drawn again removed, and the JSON
    written again, naming the pictures (the CSV holds none). Ctrl-C or SIGTERM meanwhile is
    held until both are done (before: one there left every picture drawn but none named, and
    said "interrupted" alone), then said. A JSON file that cannot be written again is left
    as this run first wrote it, naming no picture, and is refused saying so (before: "the
    earlier results.json kept", as if the earlier run's were)."""
    n = len(results.pictures.files())
    try:
        with interrupts_held():
            _remove_stale(out, earlier, results.pictures.files())
            json_outputs = [o for o in outputs if o.format == "json"]
            _write_results(results, json_outputs, out, "this run's")
    except DataError as e:
        drawn = f"the {n} picture{'s' * (n != 1)} drawn into {out}"
        raise DataError(f"{e.message}; no results file names {drawn}", e.source) from None
    except KeyboardInterrupt:
        raise KeyboardInterrupt(
            f"results in {out}, with the {n} picture{'s' * (n != 1)} drawn before it: all of them"
        ) from None


def _interrupted(results: Any, outputs: list[Output], out: Path, earlier: list[str]) -> str:
    """After an interrupt while the pictures were drawn: the results file names the pictures
    drawn (before: none, while they lay in ``out``), those of an earlier run not drawn again
    are removed (as a whole run removes them: no results file names them any more); returns
    what is said after "interrupted". Keeping the drawn pictures, not removing them: each is
    whole (written under a temporary name, then renamed), and ``posecbr report`` shows those
    a results file names."""
    drawn = results.pictures.files()
    _remove_stale(out, earlier, drawn)
    results.notes.append(
        f"interrupted while drawing the pictures: {len(drawn)} drawn, the rest not (run the "
        "comparison again for them)"
    )
    _write_results(results, [o for o in outputs if o.format == "json"], out)
    return (
        f"results in {out}, with the {len(drawn)} picture{'s' * (len(drawn) != 1)} drawn before"
        " it; the rest were not drawn"
    )


def _print_explanations(explained: list[Any]) -> None:
    """Why the clips explained (``--explain``) were got wrong, each its explanation's text
    under a line naming the clip, its true label and the answer."""

    for e in explained:
        print(f"\n{shown(e.name)}: {shown(e.true)}, answered {shown(e.predicted)} by {e.method}")
        for line in e.text.splitlines():
            print(f"  {shown(line)}")


#: what is compared on recordings labelled over time, said beside the figures
STRETCHES_NOTE = (
    "each labelled stretch of a recording labelled over time is one clip here, not cut into"
    " the 2-s windows train makes its cases of by default: these figures are those of train"
    " --split clips (a case base of windows is measured by segmenting a recording it has not"
    " seen)"
)


def run(args: argparse.Namespace) -> int:
    from cbr.evaluation.methods import check_cbr_params
    from features.datasets import check_no_overlaps, labelled_over_time
    from features.poses import check_not_poses

    with as_options(OPTIONS):
        check_scheduler(args.scheduler)
        check_folds_given_with_kfold(args)
        settings = _settings(args)
        check_cbr_params(settings)
    check_peers_can_run(args, settings)
    outputs = _outputs(args)
    check_outputs(outputs, [args.data])
    if outputs:  # clips --labels/--subjects leave out are the data's too
        check_outputs(outputs, _dataset_files(args))
    for o in outputs:  # a pose file of other data (one of these is named as an input above)
        check_not_poses(o.path, o.what)
    # rows giving frames two labels: refused before any clip is read, as train refuses them
    check_no_overlaps(args.data, set(_names(args.labels)) if args.labels else None)
    clips = _load(args, settings)
    # said with the results' notes (a refusal on the way is then the one line it is)
    rate_note = assumed_rates_note(assumed_rates(c.seq for c in clips),
                                   give_fps_by_converting(args.data))  # fmt: skip
    with as_options(OPTIONS):
        check_loso_possible(settings, clips, args.data)
    check_outputs(outputs, [args.data, *(c.seq.source for c in clips if c.seq.source)])
    with as_options(OPTIONS):
        check_kept(settings, clips, args.data)
    # the run's modules (scikit-learn among them) after the refusals, which need none of them
    from cbr.evaluation.compare import run_compare
    from cbr.evaluation.misclassified import explain_dad_errors, explain_errors
    from cbr.evaluation.tables import format_table

    with as_options(OPTIONS):  # a k or --within the folds cannot take, a scheduler lost
        run_ = run_compare(clips, settings, source=str(args.data))
    results = run_.results
    if labelled_over_time(args.data):
        results.notes.insert(0, STRETCHES_NOTE)
    results.explanations = explain_errors(run_, settings.explain)
    results.explanations += explain_dad_errors(run_, min(settings.explain, 3))
    if rate_note is not None:
        print(rate_note, file=sys.stderr)
    for note in results.notes:
        print(f"note: {shown(note)}", file=sys.stderr)
    try:
        print(format_table(results))
        if results.best:
            print(f"best: {results.best}; best interpretable (*): {results.best_interpretable}")
        _print_explanations(results.explanations)
    except BrokenPipeError:  # the reader stopped reading (`| head`): the files are still written
        stdout_gone()
    if results.best is None:  # each row failed or was skipped: nothing measured to write
        raise DataError(
            "no method could be scored: every one failed or was skipped (the notes say why);"
            " no results written",
            args.data,
        )
    earlier = _earlier_pictures(args.out) if args.out else []  # before results.json is new
    _write_outputs(run_, args, outputs, earlier)
    if args.out:
        # the command as it can be pasted into a shell: a folder named with a space quoted
        out, report = shlex.quote(str(args.out)), shlex.quote(str(args.out / "report.html"))
        said = f"results and pictures in {args.out}; report: posecbr report {out} --out {report}"
        print(shown(said), file=sys.stderr)  # as every "written to": stdout holds the table
    return 0
