"""``posecbr classify CLIP... --db cb.sqlite``: label, confidence, most similar cases and an
explanation for each clip; with labelled input (a labels CSV, a class folder, labelled pose
files) also the accuracy. ``--feedback LABEL`` revises and retains (one transaction per
clip)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from casebase_store import open_store
from cbr.build import classify_clips
from features.errors import ConfigError, DataError
from features.poses import PoseSequence

#: nearest-case distance, in units of the case base's usual nearest-neighbour distance, above
#: which a clip is flagged as unlike anything stored. On UI-PRMD (train s01-s05, fluents,
#: euclidean) 99 % of the held-out subjects' clips lay below 2.7, whole exercise videos at 3.3+.
UNUSUAL = 3.0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "classify",
        help="classify clips with a case base, with explanations",
        description="Retrieve the most similar cases for each clip, vote, and explain.",
    )
    p.add_argument("clips", nargs="+", type=Path, help="pose files, videos, folders or labels CSVs")
    p.add_argument("--db", required=True, help="case base file (SQLite) or SQLAlchemy URL")
    p.add_argument("--name", default=None, help="case base name (default: the only one)")
    p.add_argument("-k", "--k", type=int, default=5, help="number of retrieved cases")
    p.add_argument("--top", type=int, default=3, help="similar cases to print per clip")
    p.add_argument(
        "--feedback",
        metavar="LABEL",
        help="the true label of the clips: revise the case base and retain novel, beneficial cases",
    )
    p.add_argument("--novelty", type=float, default=0.5, help="retain novelty threshold")
    p.add_argument("--benefit", type=float, default=0.2, help="retain benefit threshold")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--sensor", default="kinect", help="UI-PRMD sensor (kinect or vicon)")
    p.add_argument("--subjects", help="datasets: only these subjects, comma-separated")
    p.add_argument(
        "--target",
        default="label",
        help="the column labelled clips are checked against: label (default) or the column "
        "the case base was trained on (posecbr train --target), e.g. correct",
    )
    p.set_defaults(func=run)


def load_inputs(
    paths: list[Path], sensor: str, subjects: list[str] | None = None, target: str = "label"
) -> list[tuple[PoseSequence, str | None]]:
    """Every clip named by ``paths`` with its value of ``target`` (the label, or another
    column such as ``correct``) when the input carries one."""
    from features.datasets import (
        CLIP_SUFFIXES,
        Clip,
        clip_target,
        detect_kind,
        iter_dataset,
        load_clip,
    )

    def of_file(seq: PoseSequence) -> Clip:
        subject = seq.metadata.get("subject")
        return Clip(seq=seq, label=seq.label or "", subject=subject, extras={})

    out: list[tuple[PoseSequence, str | None]] = []
    for path in paths:
        kind = detect_kind(path)
        if kind == "pose_file":
            seq = load_clip(path)
            out.append((seq, clip_target(of_file(seq), target)))
        elif kind == "pose_folder":
            # may hold unlabelled clips: read them one by one
            for f in sorted(q for q in path.iterdir() if q.suffix.lower() in CLIP_SUFFIXES):
                seq = load_clip(f)
                out.append((seq, clip_target(of_file(seq), target)))
        else:
            clips = iter_dataset(
                path, sensor=sensor, subjects=subjects, progress_desc=f"loading {path.name}"
            )
            for clip in clips:
                out.append((clip.seq, clip_target(clip, target)))
    if not out:
        raise DataError("no clips found", " ".join(str(p) for p in paths))
    return out


def run(args: argparse.Namespace) -> int:
    if args.k < 1:
        raise ConfigError(f"-k must be >= 1, got {args.k}", "-k")
    store = open_store(args.db, create=False)
    try:
        name = args.name
        if name is None:
            names = [cb.name for cb in store.list_case_bases()]
            if len(names) != 1:
                raise ConfigError(
                    "the store holds "
                    + (
                        f"case bases {', '.join(names)}: choose one with --name"
                        if names
                        else "no case base (run posecbr train)"
                    ),
                    store.where,
                )
            name = names[0]
        subjects = [s.strip() for s in args.subjects.split(",")] if args.subjects else None
        inputs = load_inputs(args.clips, args.sensor, subjects, args.target)
        results = classify_clips(
            store,
            name,
            [s for s, _ in inputs],
            [t for _, t in inputs],
            k=args.k,
            feedback=args.feedback,
            novelty_threshold=args.novelty,
            benefit_threshold=args.benefit,
        )
    finally:
        store.close()
    labelled = [r for r in results if r.true_label is not None]
    accuracy = (
        sum(r.true_label == r.explanation.label for r in labelled) / len(labelled)
        if labelled
        else None
    )
    if args.json:
        doc = {"db": store.where, "case_base": name, "results": [r.to_dict() for r in results]}
        if accuracy is not None:
            doc["accuracy"] = accuracy
            doc["n_labelled"] = len(labelled)
        json.dump(doc, sys.stdout, indent=2, ensure_ascii=False)
        print()
        return 0
    for r in results:
        e = r.explanation
        head = f"{r.source}: {e.label} (confidence {e.confidence:.2f})"
        if r.true_label is not None:
            head += "  [right]" if r.true_label == e.label else f"  [wrong: {r.true_label}]"
        print(head)
        if r.novelty is not None and r.novelty > UNUSUAL:
            print(
                f"  note: this clip is unlike the stored cases (nearest case at {r.novelty:.1f}x "
                "the usual distance between neighbouring cases): treat the label with caution"
            )
        for n in e.neighbours[: args.top]:
            print(
                f"  case #{n['case_id']} {n['label']}  distance {n['distance']:.4g}  {n['source']}"
            )
        for line in e.text.splitlines()[1:]:
            print(f"  {line}")
        if r.retention is not None:
            print(f"  feedback: {r.retention.reason}")
        if r.revision is not None:
            print(
                f"  feedback: revised case #{r.revision.case_id} ({r.revision.action}): "
                f"{r.revision.reason}"
            )
    if accuracy is not None:
        right = sum(r.true_label == r.explanation.label for r in labelled)
        print(f"accuracy: {accuracy:.3f} ({right}/{len(labelled)} labelled clips)")
    return 0
