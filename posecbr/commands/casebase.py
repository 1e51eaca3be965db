"""``posecbr casebase info|list|export|copy|trim --db cb.sqlite``: inspect and maintain a
store."""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING, Any

from features.errors import ConfigError, DataError
from features.fileio import atomic_path, check_lookup, check_output
from features.interrupts import stored_before
from features.text import counted, percent, shown
from posecbr.arguments import DB, NAME, as_options, path_arg

if TYPE_CHECKING:
    from casebase_store import CaseBaseInfo, CaseStore


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "casebase",
        epilog="example: posecbr casebase info --db cb.sqlite",
        help="inspect, export, copy and trim case bases",
        description="Inspect, export and maintain the case bases in a store.",
    )
    act = p.add_subparsers(dest="action", metavar="ACTION", required=True)

    def common(q: argparse.ArgumentParser) -> None:
        q.add_argument("--db", required=True, help="case base file (SQLite) or SQLAlchemy URL")
        q.add_argument("--name", default=None, help="case base name (default: the only one)")
        q.add_argument("--json", action="store_true", help="machine-readable output")

    q = act.add_parser(
        "info",
        epilog="example: posecbr casebase info --db cb.sqlite --json",
        help="case bases, configuration, cases per activity, history",
    )
    common(q)
    q = act.add_parser(
        "list",
        epilog="example: posecbr casebase list --db cb.sqlite --all",
        help="the cases of a case base",
    )
    common(q)
    q.add_argument("--all", action="store_true", help="include trimmed cases")
    q = act.add_parser(
        "export",
        epilog="example: posecbr casebase export --db cb.sqlite --out cases.npz",
        help="write the cases (problems, labels, provenance) to .npz",
    )
    common(q)
    q.add_argument(
        "--out", required=True, type=path_arg, metavar="FILE.npz", help="output .npz file"
    )
    q = act.add_parser(
        "copy",
        epilog="example: posecbr casebase copy --db cb.sqlite --to backup.sqlite",
        help="copy a case base whole to another store, or under another name",
        description="Copy a case base whole (its configuration and fitted model, every case "
        "in use or trimmed with its labels and provenance, its history) to another store in "
        "one transaction: classify and segment answer on the copy as on the case base. The "
        "store it is read from is opened read-only.",
    )
    common(q)
    q.add_argument(
        "--to",
        required=True,
        help="the store to copy it to: a case base file (SQLite; made when there is none) or "
        "SQLAlchemy URL",
    )
    q.add_argument(
        "--as",
        dest="as_name",
        default=None,
        metavar="NAME",
        help="the copy's name (default: the case base's own)",
    )
    q = act.add_parser(
        "trim",
        epilog="example: posecbr casebase trim --db cb.sqlite --keep 0.5 --dry-run",
        help="run a maintenance editor and deactivate dropped cases",
    )
    common(q)
    q.add_argument(
        "--editor",
        choices=("novelty-benefit", "cnn", "renn", "icf"),
        default="novelty-benefit",
        help="the maintenance editor: novelty-benefit (default; keeps --keep of each "
        "activity), cnn, renn or icf (each decides how many it keeps)",
    )
    q.add_argument(
        "--keep",
        type=float,
        default=None,
        help="novelty-benefit: fraction of each activity to keep (default 0.7)",
    )
    q.add_argument(
        "-k",
        "--k",
        type=int,
        default=None,
        help="neighbours each editor judges with and reports the accuracy with (default: "
        "novelty-benefit the case base's own k, RENN and ICF 3, CNN 1)",
    )
    q.add_argument("--dry-run", action="store_true", help="report only, change nothing")
    q = act.add_parser(
        "upgrade",
        epilog="example: posecbr casebase upgrade --db old.sqlite",
        help="convert a case base file written by an older posecbr, in place",
    )
    q.add_argument("--db", required=True, help="case base file (SQLite) or SQLAlchemy URL")
    q.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)


def _emit(doc: Any) -> None:
    json.dump(doc, sys.stdout, indent=2, ensure_ascii=False, default=str)
    print()


def run(args: argparse.Namespace) -> int:
    from casebase_store import EMPTY_DB, StoreError, open_store, prepare_write

    if not str(args.db).strip():  # as open_store says it, before any action reads a path
        raise StoreError(EMPTY_DB, "--db")
    if args.action == "upgrade":
        return _upgrade(args)
    if args.action == "copy":
        return _copy(args)
    if args.action == "export":
        _check_export(args)  # before the store is opened: a refusal touches nothing
    if args.action == "trim" and not args.dry_run:  # a writer: one that cannot is refused
        prepare_write(args.db)
    # read-only for trim too: loading fills in nothing (a writable store would store the
    # representations missing from it) and trim may still refuse; it opens the writer itself
    with as_options(DB):
        store = open_store(args.db, create=False, readonly=True)
    try:
        return {"info": _info, "list": _list, "export": _export, "trim": _trim}[args.action](
            store, args
        )
    finally:
        store.close()


def _upgrade(args: argparse.Namespace) -> int:
    from casebase_store import (
        SCHEMA_VERSION,
        in_wal_mode,
        missing_columns,
        missing_indexes,
        roll_back_interrupted,
        shown_db,
        sqlite_file,
        upgrade_store,
    )

    file = sqlite_file(args.db)
    rolled_back = roll_back_interrupted(args.db)  # a change a killed writer left half-made
    wal = file is not None and in_wal_mode(file)
    lacking = missing_indexes(args.db)
    lacking_columns = missing_columns(args.db)
    found = upgrade_store(args.db)  # a writer: it also leaves WAL mode (posecbr 0.1's)
    journal = wal and file is not None and not in_wal_mode(file)
    converted = [f"from schema version {found} to {SCHEMA_VERSION}"] * (found != SCHEMA_VERSION)
    converted += ["from WAL mode to a rollback journal"] * journal
    added = [f"the index {name}" for name in lacking if name not in missing_indexes(args.db)]
    if found == SCHEMA_VERSION:  # a conversion makes today's tables, these columns with them
        now = missing_columns(args.db)
        added += [f"the column {name}" for name in lacking_columns if name not in now]
    if args.json:
        _emit(
            {
                "db": shown_db(args.db),
                "schema_version_before": found,
                "schema_version": SCHEMA_VERSION,
                "left_wal_mode": bool(journal),
                "rolled_back_interrupted_change": rolled_back,
                "changed": bool(converted or added) or rolled_back,
            }
        )
        return 0
    if rolled_back:
        print(
            f"{shown(shown_db(args.db))}: rolled back the change a killed process left half-made"
            " (the case bases are as its last whole change left them)"
        )
    if converted:
        print(f"{shown(shown_db(args.db))}: converted {', and '.join(converted)}")
    if added:
        print(
            f"{shown(shown_db(args.db))}: added {' and '.join(added)} of a newer schema (no"
            " case changed)"
        )
    if not (converted or added or rolled_back):
        print(f"{shown(shown_db(args.db))}: already schema version {SCHEMA_VERSION}, nothing to do")
    return 0


def _copy(args: argparse.Namespace) -> int:
    """Case base ``--name`` of ``--db`` written whole to ``--to`` as ``--as``, in one
    transaction of the store written (a new case base file appears only when complete); the
    store read is opened read-only. Refused in one line, nothing written, when the store read
    cannot be (missing, damaged, locked), when ``--to`` holds a case base of that name, or
    names the very case base."""
    from casebase_store import (
        EMPTY_DB,
        StoreError,
        check_case_base_name,
        open_store,
        prepare_write,
        same_store,
        shown_db,
        write_store,
    )

    if not str(args.to).strip():
        raise StoreError(EMPTY_DB, "--to")
    if args.as_name is not None:
        check_case_base_name(args.as_name, "--as")
    with as_options(DB):
        store = open_store(args.db, create=False, readonly=True)
    try:
        with as_options(NAME):
            name = store.choose(args.name)
        new = name if args.as_name is None else args.as_name
        if new == name and same_store(args.db, args.to):
            raise StoreError(
                f"--to names the store case base {name!r} is in: that is the case base "
                "itself (copy it to another store, or under another name with --as)",
                store.where,
            )
        whole = store.read_whole(name)
        source = store.where
    finally:
        store.close()
    prepare_write(args.to)  # a store that cannot be written is refused before any write
    with as_options({"name": "--as"}):  # the copy's name
        info, ids = write_store(args.to, lambda tx: tx.copy_case_base(whole, new))
    old = [int(c["id"]) for c in whole.cases]
    trimmed = sum(not c["active"] for c in whole.cases)
    with stored_before(
        f"the copy {info.name!r} was stored before it (casebase info --db shows it)"
    ):
        _copy_matrices(args.to, new, len(old) - trimmed)
    in_use = len(old) - trimmed
    doc: dict[str, Any] = {
        "db": source,
        "case_base": name,
        "to": shown_db(args.to),
        "as": new,
        "cases": in_use,
        "trimmed_cases": trimmed,
        "representations": len(whole.representations),
        "history": len(whole.log),
        "version": info.version,
        "case_ids_kept": ids == old,
    }
    if args.json:
        _emit(doc)
        return 0
    ids_said = (
        "case ids kept"
        if ids == old
        else f"case ids numbered after the store's own (#{old[0]}-#{old[-1]} are "
        f"#{ids[0]}-#{ids[-1]} there)"
    )
    print(
        f"copied case base {shown(repr(name))} of {shown(source)} to {shown(doc['to'])}"
        f"{'' if new == name else f' as {shown(repr(new))}'}: "
        f"{counted(in_use, 'case')} in use, {trimmed} trimmed, "
        f"{len(whole.log)} history {'entry' if len(whole.log) == 1 else 'entries'}; {ids_said}"
    )
    return 0


def _copy_matrices(to: str, name: str, in_use: int) -> None:
    """The memory-mapped matrices of a large copy in a SQLite file, as every command that
    changes a case base writes them (nothing for a small one, ``in_use`` cases, or another
    backend: the classifier's modules are then not even loaded)."""
    from casebase_store import case_matrix, open_store, sqlite_file

    if sqlite_file(to) is None or in_use < case_matrix.MAPPED_MIN_CASES:
        return
    from cbr.stored import write_matrices

    writer = open_store(to, create=False)
    try:
        write_matrices(writer, name)
    finally:
        writer.close()


def _info(store: CaseStore, args: argparse.Namespace) -> int:
    infos = store.list_case_bases() if args.name is None else [store.get_case_base(args.name)]
    docs = [_info_document(store, i) for i in infos]
    if args.json:
        _emit({"db": store.where, "case_bases": docs})
        return 0
    if not docs:
        print(f"{shown(store.where)}: no case bases")
    for d in docs:
        _print_info(d)
    return 0


def _info_document(store: CaseStore, i: CaseBaseInfo) -> dict[str, Any]:
    """What ``casebase info --json`` says about one case base."""
    return {
        "name": i.name,
        "cases": i.n_cases,
        "labels": i.label_counts,
        "features": i.feature_config,
        "feature_hash": i.feature_hash,
        "n_features": len(i.feature_names),
        "similarity": i.similarity,
        "code_version": i.code_version,
        "created": i.created_at.isoformat(),
        "version": i.version,
        "model": {**_model_summary(i.model, i.feature_words), **_judges_summary(i)},
        **_history(store.maintenance_log(i.name)),
    }


def _history(log: list[Any]) -> dict[str, Any]:
    """How often each maintenance action ran, in the order they first ran (``maintenance``:
    a trim once, however many cases it dropped; a clip retained once, one not retained not
    at all), with the cases trims dropped and the feedback clips not retained."""
    from cbr.words import DROPPED

    runs: Counter[str] = Counter()
    dropped = not_retained = 0
    for e in log:
        if e.action == "trim" and e.reason.endswith(DROPPED):  # one per case it dropped
            dropped += 1
        elif e.action == "retain" and e.case_id is None:  # the decision not to
            not_retained += 1
        else:
            runs[e.action] += 1
    return {"maintenance": dict(runs), "trimmed_cases": dropped, "not_retained": not_retained}


def _judges_summary(i: CaseBaseInfo) -> dict[str, Any]:
    """The unknown judges stored with the model (``segment --unknown``), each with its
    fields (those stored apart from its record, ``activities``, with them:
    :func:`cbr.stored.judges_document`), and whether they hold for the cases as they are now
    (``current``: else ``segment`` calibrates at run time)."""
    stored = i.model.get("judges")
    if not isinstance(stored, dict):
        return {}
    current = stored.get("case_base_version") == i.version
    calibrated, apart = stored.get("calibrated"), stored.get("added_fields")
    if isinstance(calibrated, dict) and isinstance(apart, dict):
        calibrated = {
            name: {**record, **apart[name]}
            if isinstance(record, dict) and isinstance(apart.get(name), dict)
            else record
            for name, record in calibrated.items()
        }
    return {"unknown_judges": {"current": current, "calibrated": calibrated}}


def _print_info(d: dict[str, Any]) -> None:
    """One case base's :func:`_info_document` for people."""
    feats = d["features"]
    states = feats.get("states")
    n_states = len(states) if isinstance(states, list) else states
    from cbr.words import class_noun

    n = len(d["labels"])
    print(
        f"{shown(d['name'])}: {d['cases']} cases, {n} {class_noun(d['model'].get('target'), n)} "
        f"(created {d['created']}, posecbr {d['code_version']})"
    )
    # a QMP case base has no states or length of its own: one column per QMP
    shape = (
        f"qmp ({feats.get('qmp_part', 'binary')}), {counted(d['n_features'], 'QMP column')}"
        if feats["level"] == "qmp"
        else f"{feats['level']}, {n_states} states, length {feats['length']}"
    )
    print(f"  features: {shape}; hash {d['feature_hash'][:12]}")
    print(f"  similarity: {_measure_words(d['similarity'])}")
    _print_model(d["model"], n, _changed_since_training(d["maintenance"]))
    for lab, n in d["labels"].items():
        print(f"  {n:6d}  {shown(lab)}")
    if d["maintenance"] or d["not_retained"]:
        notes = {
            "trim": f" ({counted(d['trimmed_cases'], 'case')} dropped)",
            "retain": f" ({counted(d['not_retained'], 'clip')} not retained)"
            if d["not_retained"]
            else "",
        }
        words = [f"{k} x{v}{notes.get(k, '')}" for k, v in d["maintenance"].items()]
        if d["not_retained"] and "retain" not in d["maintenance"]:
            words.append(f"{counted(d['not_retained'], 'feedback clip')} not retained")
        print("  history: " + ", ".join(words))


#: maintenance actions that add, change or drop cases after training (trim calibrates the
#: unknown judges anew, not the unlike-the-cases flag or the confidence)
CHANGES = ("append", "retain", "revise", "trim")
SINCE = "cases added, changed or dropped since are not taken into account"


def _changed_since_training(history: dict[str, int]) -> bool:
    """Whether cases were added, changed or dropped since the model was fitted: its
    calibrations (unlike the stored cases, confidence) are of the cases it was trained on."""
    return any(history.get(a) for a in CHANGES)


def _print_model(m: dict[str, Any], n_activities: int, changed: bool = False) -> None:
    """What fit learned (:func:`_model_summary`), the lines that apply; ``changed``: cases
    were added, changed or dropped since (the calibrations are of the training's cases)."""
    pieces = str(m.get("cases") or "clips")
    since = f" (at training: {SINCE})" if changed else ""
    if m.get("k") is not None:
        from cbr.words import CASE_KINDS

        kind = CASE_KINDS.get(m.get("cases") or "")
        each = f", a case per {kind}" if kind else ""
        phases = m.get("phases")
        means = f"; means over {phases} phases" if isinstance(phases, int) and phases else ""
        balanced = ", balanced by class" if m.get("class_weight") == "balanced" else ""
        print(
            f"  model: predicts {m['target']}{each}; k = {m['k']}, {m['vote']} vote{balanced};"
            f" side handling {m['side']}; feature weights {m['feature_weights']}{means}"
        )
    if m.get("weighted_most"):
        print(f"  weighted most: {shown(', '.join(m['weighted_most']))}")
    if m.get("unlike_cases"):
        u = m["unlike_cases"]
        sensors = u.get("skeletons") or []
        rule = f", or recorded with a skeleton other than {', '.join(sensors)}" if sensors else ""
        f, c = u.get("features"), u.get("combined")
        n_held = int((c or {}).get("scores", {}).get("summary", 0))
        few = (
            f": {n_held} held-out {pieces} are too few to tell a 1-in-{round(1 / c['budget'])} one"
            if c and c["budget"] * (n_held + 1) < 1.0
            else ""
        )
        # a threshold of 0 flags nothing (too few held-out clips: cbr.novelty.combine);
        # "less usual than 100.0 % of held-out clips' (... 2 % flagged)" said otherwise
        none = bool(f and c and c["threshold"] <= 0.0)
        tail = f"; its summary features flag no clip{few}" if none else ""
        feats = (
            ""
            if none
            else f", or its summary features (outside the cases' ranges, far from every training "
            f"clip) less usual than {percent(1 - c['threshold'])} of held-out clips' (one "
            f"statistic of all the scores: {percent(c['budget'], 0)} of held-out clips flagged)"
            if f and c
            else f", or its summary features outside the cases' ranges beyond "
            f"{f['unlike_ratio']:.2f}x what held-out clips of its answer show"
            if f
            else ""
        )
        print(
            f"  unlike the stored cases beyond {u['unlike_ratio']:.2f}x the usual held-out "
            f"distance ({percent(u['quantile'])} of {u['basis']} training {pieces} lie within)"
            f"{feats}"
            f"{rule}{tail}{since}"
        )
    if m.get("unknown_judges"):
        j = m["unknown_judges"]
        when = "" if j["current"] else " (the cases changed since: calibrated at run time)"
        print(f"  unknown judges stored: {', '.join(sorted(j['calibrated'] or {}))}{when}")
    elif m.get("k") is not None:
        from cbr.words import class_noun

        print(
            f"  unknown judges: none (fewer than three {class_noun(m.get('target'), 3)}: segment"
            " and watch need --unknown held-out)"
            if n_activities < 3
            else "  unknown judges: none stored (the cases changed since training, or a model "
            "stored before they were): segment and watch calibrate them as they start"
        )
    if m.get("confidence") and not m["confidence"].get("n"):
        print(
            f"  confidence: the vote share, not calibrated (each activity's training {pieces} "
            "came from one recording or person: none could be classified held out of it"
            f"{f'; {SINCE}' if changed else ''})"
        )
    elif m.get("confidence"):
        c = m["confidence"]
        score = (
            f"the soft vote of the {c['neighbours']} nearest cases (temperature "
            f"{c['temperature']:.3g})"
            if c.get("neighbours")
            else "the vote share"
        )
        print(
            f"  confidence: {score} calibrated on {c['n']} {c['basis']} training "
            f"{pieces} (their accuracy {percent(c['accuracy'])}"
            f"{f'; {SINCE}' if changed else ''})"
        )


def _measure_words(similarity: dict[str, Any]) -> str:
    """The measure and its settings; its learned weights (one per column) are summed up by
    "weighted most" instead of printed."""
    rest = {k: v for k, v in similarity.items() if k not in ("name", "centre", "multiplier")}
    learned = " with learned feature weights" if similarity.get("multiplier") else ""
    settings = ", ".join(f"{k}={v}" for k, v in sorted(rest.items()))
    return f"{similarity.get('name', '?')}{learned}" + (f" ({settings})" if settings else "")


def _novelty_summary(stored: dict[str, Any] | None) -> dict[str, Any] | None:
    """The stored novelty calibration without its feature ranges' arrays (what a person
    reads; :meth:`cbr.novelty.NoveltyCalibration.describe`)."""
    from cbr.novelty import NoveltyCalibration

    if not stored:
        return stored
    try:
        return NoveltyCalibration.from_dict(stored).describe()
    except (KeyError, TypeError, ValueError):
        return {k: v for k, v in stored.items() if k != "features"}


def _confidence_summary(stored: dict[str, Any] | None) -> dict[str, Any] | None:
    """The stored confidence calibration, its accuracy None where no training piece could be
    classified held out (``n`` 0: NaN, which JSON has not)."""
    if not isinstance(stored, dict) or stored.get("n"):
        return stored
    return {**stored, "accuracy": None}


def _model_summary(model: dict[str, Any], words: tuple[str, ...]) -> dict[str, Any]:
    """What fit learned, for people: k, vote, target, side handling, weighting, the heaviest
    feature weights and the novelty calibration."""
    import numpy as np

    params = model.get("params") or {}
    out: dict[str, Any] = {
        "k": params.get("k"),
        "vote": params.get("weights"),
        # each vote divided by its class's share of the cases (train --target correct); a
        # model stored before the vote could be balanced votes as it was calibrated: none
        "class_weight": params.get("class_weight", "none"),
        "target": model.get("target", "label"),
        "cases": model.get("cases"),
        "side": model.get("side"),
        "feature_weights": model.get("weighting"),
        # what fit chose, as side and feature_weights (and train --json) give it: the
        # parameter ("auto") for a model stored before the choice was
        "phases": model.get("phases", params.get("phases")),
        "unlike_cases": _novelty_summary(model.get("novelty")),
        "confidence": _confidence_summary(model.get("confidence")),
    }
    fw = model.get("feature_weights")
    if fw and len(fw.get("weight", ())) == len(words):
        w = np.asarray(fw["weight"], dtype=float)
        order = np.argsort(-w, kind="stable")[:5]
        out["weighted_most"] = [words[j] for j in order if w[j] > 0]
    return out


def _list(store: CaseStore, args: argparse.Namespace) -> int:
    from cbr.words import MIRRORED

    with as_options(NAME):
        name = store.choose(args.name)
    a = store.load_cases(name, include_inactive=args.all)
    rows: list[dict[str, Any]] = [
        {
            "case_id": int(a.ids[i]),
            "label": str(a.labels[i]),
            "origin": a.origins[i],
            "active": bool(a.active[i]),
            "subject": a.subjects[i],
            "source": a.sources[i],
            # the case is its clip's mirror image: ``source`` then ends " (mirrored)"
            "mirrored": a.sources[i].endswith(MIRRORED),
            "frames": list(a.frame_ranges[i]),  # [start, end]: kept; elsewhere a count
            "start_frame": a.frame_ranges[i][0],
            "end_frame": a.frame_ranges[i][1],
        }
        for i in range(len(a.ids))
    ]
    if args.json:
        _emit({"db": store.where, "case_base": name, "cases": rows})
        return 0
    for r in rows:
        fr = r["frames"]
        # end inclusive, as segment's and reps' tables and classify's pieces (JSON: exclusive)
        span = f"{fr[0]}-{fr[1] - 1}" if fr[0] is not None else "-"
        origin = r["origin"] if r["active"] else f"{r['origin']}, trimmed"
        print(
            f"#{r['case_id']}\t{shown(r['label'])}\t{origin}\t{shown(r['subject'] or '-')}\t"
            f"{span}\t{shown(r['source'])}"
        )
    return 0


def _export_path(args: argparse.Namespace) -> Path:
    """``--out``, with ``.npz`` added when it has another ending. A folder is refused as
    named, before the ending is added: ``--out cases/`` is no ``cases.npz`` beside it, and
    ``--out .`` has no name to add it to."""
    out = Path(args.out)
    if str(args.out) == "-":  # standard output's name, not "-.npz"
        raise DataError("the export file goes to a file, not standard output: name the file", out)
    check_lookup(out, "export file")
    if out.is_dir() or not out.name:
        raise DataError("the export file is a folder, not a file", out)
    return out if out.name.lower().endswith(".npz") else out.with_name(out.name + ".npz")


def _check_export(args: argparse.Namespace) -> None:
    """The export file is not a folder, never the store's files (the database, its
    journals: ``--db X.npz --out X.npz`` would replace the case base by its export) and never
    a pose file (``--out poses/squat.npz`` replaced a recording, as likely one its own cases
    were taken from, by the cases' features)."""
    from casebase_store import store_files
    from features.poses import holds_poses

    out = check_output(_export_path(args), inputs=store_files(args.db), what="export file")
    if holds_poses(out):
        raise DataError(
            "is a pose file: the export would replace that recording by the cases' features"
            " (name another file)",
            out,
        )


def _frames(ranges: tuple[tuple[int | None, int | None], ...]) -> Any:
    """``(n, 2)`` each case's first frame and end frame (exclusive) in its recording, as
    ``list`` shows them; NaN where the case has none (a case added by the Python API)."""
    import numpy as np

    rows = [[np.nan if v is None else v for v in r] for r in ranges]
    return np.asarray(rows, dtype=np.float64).reshape(len(rows), 2)


def _export(store: CaseStore, args: argparse.Namespace) -> int:
    import numpy as np

    from casebase_store import check_width

    out = _export_path(args)
    with as_options(NAME):
        name = store.choose(args.name)
    info, a = store.load_case_base(name)
    if len(a.ids):
        check_width(info, a.features.shape[-1], store.where)
    arrays: dict[str, Any] = {
        "problems": a.features,
        "labels": np.asarray(a.labels, dtype=str),
        "case_ids": a.ids,
        "sources": np.asarray(a.sources, dtype=str),
        "subjects": np.asarray([s or "" for s in a.subjects], dtype=str),
        "origins": np.asarray(a.origins, dtype=str),
        "frames": _frames(a.frame_ranges),
        "feature_names": np.asarray(info.feature_names, dtype=str),
        "feature_words": np.asarray(info.feature_words, dtype=str),
        "feature_config": np.asarray(json.dumps(info.feature_config)),
        "similarity": np.asarray(json.dumps(info.similarity)),
    }
    with atomic_path(out) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    msg = {
        "db": store.where,  # as info, list and upgrade say which store, and list which case base
        "case_base": name,
        "out": str(out),
        "cases": int(len(a.ids)),
        "problem_shape": list(a.features.shape[1:]),
    }
    if args.json:
        _emit(msg)
    else:
        print(f"wrote {len(a.ids)} cases of {shown(repr(name))} to {shown(out)}")
    return 0


def _trim_keep(args: argparse.Namespace) -> float:
    """``--keep`` (novelty-benefit's share of each activity, 0.7 unless given), checked with
    ``-k``'s range: refused for the other editors, which decide how many cases they keep."""
    if args.keep is not None and args.editor != "novelty-benefit":
        raise ConfigError(
            f"goes with --editor novelty-benefit; {args.editor} decides how many cases it keeps",
            "--keep",
        )
    keep = 0.7 if args.keep is None else args.keep
    if not 0.0 < keep <= 1.0:
        raise ConfigError(f"must be in (0, 1], got {keep}", "--keep")
    if args.k is not None and args.k < 1:
        raise ConfigError(f"must be >= 1, got {args.k}", "-k")
    return float(keep)


def _edited(args: argparse.Namespace, clf: Any, name: str, keep: float, where: str) -> Any:
    """The editor's report on the case base of ``clf`` (nothing written). Each case is left
    out in turn, so the k it is judged with (``-k``, or novelty-benefit's the case base's
    own) must leave cases to vote."""
    from cbr.maintenance import EDITORS

    cb = clf.case_base_
    if args.k is not None and args.k >= len(cb):
        raise ConfigError(
            f"must be less than the {len(cb)} cases of {name!r} (each is left out in turn), "
            f"got {args.k}",
            "-k",
        )
    fn = EDITORS[args.editor]
    if args.editor == "novelty-benefit":
        if args.k is None and int(clf.k) >= len(cb):
            raise DataError(
                f"case base {name!r} votes with k = {int(clf.k)}, not less than its "
                f"{len(cb)} cases (each is left out in turn): give -k",
                where,
            )
        return fn(cb, keep, int(clf.k) if args.k is None else args.k, clf.weights)
    if args.k is None:
        return fn(cb, weights=clf.weights)
    return fn(cb, k=args.k, weights=clf.weights)


def _unchanged(dry_run: bool, dropped: bool) -> str:
    """What the trim's summary line adds when it changed nothing."""
    if dry_run:
        return " (dry run: nothing changed)"
    return "" if dropped else " (nothing dropped: nothing changed)"


def _trim(store: CaseStore, args: argparse.Namespace) -> int:
    from casebase_store import open_store
    from cbr.maintenance import record_trim
    from cbr.stored import judges_after_change, load_classifier, recalibrated, write_matrices

    with as_options(NAME):
        name = store.choose(args.name)
    keep = _trim_keep(args)
    stored = load_classifier(store, name)
    clf = stored.classifier
    report = _edited(args, clf, name, keep, store.where)
    if report.size_after < int(clf.k):
        raise DataError(
            f"trimming would leave {report.size_after} cases, fewer than the {int(clf.k)} that "
            f"case base {name!r} votes with (k): nothing trimmed"
            + (" (keep more: --keep)" if args.editor == "novelty-benefit" else ""),
            store.where,
        )
    dropped = report.size_after < report.size_before
    if dropped and not args.dry_run:  # a trim that drops nothing writes nothing
        judges = recalibrated(clf, report.casebase)
        writer = open_store(args.db, create=False)
        try:
            with writer.transaction() as tx:
                info = tx.expect(name, stored.uid, stored.version)
                record_trim(tx, info, report)
                judges_after_change(tx, info, judges)
            with stored_before(_trim_stored(report.size_before, report.size_after)):
                write_matrices(writer, name)
        finally:
            writer.close()
    with stored_before(
        _trim_stored(report.size_before, report.size_after), stored=dropped and not args.dry_run
    ):
        return _trim_said(args, store, name, report, stored.target, dropped)


def _trim_stored(before: int, after: int) -> str:
    """What a trim stopped after its commit says (:func:`features.interrupts.stored_before`):
    said "interrupted" alone, it was taken for a trim not made, and run again trimmed the
    case base a second time."""
    return (
        f"the trim was stored before it ({before} -> {after} cases: casebase info shows it);"
        " run again, it would trim the case base again"
    )


def _trim_said(
    args: argparse.Namespace,
    store: CaseStore,
    name: str,
    report: Any,
    target: str,
    dropped: bool,
) -> int:
    """The trim's report: one line (``--json``: a record)."""
    doc = {
        "db": store.where,  # as info, list and upgrade say which store, and list which case base
        "case_base": name,
        "editor": args.editor,  # as --editor spells it ("method" kept: "CNN" for cnn)
        "method": report.method,
        "size_before": report.size_before,
        "size_after": report.size_after,
        "accuracy_before": report.accuracy_before,
        "accuracy_after": report.accuracy_after,
        "distribution_shift": report.distribution_shift,
        "measured": report.measured,
        "kept_alone": list(report.kept_alone),
        "dry_run": bool(args.dry_run),
        "changed": dropped and not args.dry_run,
    }
    if args.json:
        _emit(doc)
    else:
        print(report.summary() + _unchanged(args.dry_run, dropped))
        if dropped and not args.dry_run:  # where the change went, as export and copy say
            gone = report.size_before - report.size_after
            print(
                f"  case base {shown(repr(name))} in {shown(store.where)}:"
                f" {counted(gone, 'case')} deactivated (casebase list --all lists them)"
            )
        if report.distribution_shift is not None:
            from cbr.words import class_noun

            print(
                f"  largest per-{class_noun(target)} mean shift:"
                f" {report.distribution_shift:.3f} "
                "pooled standard deviations"
            )
    return 0
