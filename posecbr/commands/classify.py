"""``posecbr classify CLIP... --db cb.sqlite``: label, confidence, most similar cases and an
explanation for each clip; with labelled input (a labels CSV, a class folder, labelled pose
files) also the accuracy. ``--feedback LABEL`` revises and retains (one transaction per
clip)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from features.errors import ConfigError, DataError

if TYPE_CHECKING:
    from features.poses import PoseSequence


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "classify",
        help="classify clips with a case base, with explanations",
        description="Retrieve the most similar cases for each clip, vote, and explain.",
    )
    p.add_argument("clips", nargs="+", type=Path, help="pose files, videos, folders or labels CSVs")
    p.add_argument("--db", required=True, help="case base file (SQLite) or SQLAlchemy URL")
    p.add_argument("--name", default=None, help="case base name (default: the only one)")
    p.add_argument(
        "-k", "--k", type=int, default=None, help="retrieved cases (default: as trained)"
    )
    p.add_argument("--top", type=int, default=3, help="similar cases to print per clip")
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
    p.add_argument("--novelty", type=float, default=0.5, help="retain novelty threshold")
    p.add_argument("--benefit", type=float, default=0.2, help="retain benefit threshold")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--sensor", default="kinect", help="UI-PRMD sensor (kinect or vicon)")
    p.add_argument("--subjects", help="datasets: only these subjects, comma-separated")
    p.add_argument(
        "--target",
        default=None,
        help="the column labelled clips are checked against (default: the one the case base "
        "was trained on, posecbr train --target)",
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


def _check_args(args: argparse.Namespace) -> None:
    if args.k is not None and args.k < 1:
        raise ConfigError(f"-k must be >= 1, got {args.k}", "-k")
    if args.top < 0:
        raise ConfigError(f"--top must be >= 0, got {args.top}", "--top")
    if args.new_label and args.feedback is None:
        raise ConfigError("--new-label goes with --feedback LABEL", "--new-label")


def run(args: argparse.Namespace) -> int:
    from casebase_store import open_store
    from cbr.classification import (
        FeedbackSettings,
        check_feedback_label,
        classify_clips,
        classify_with_feedback,
    )
    from cbr.stored import load_classifier

    _check_args(args)
    settings = FeedbackSettings(args.novelty, args.benefit)
    store = open_store(args.db, create=False, readonly=args.feedback is None)
    try:
        name = store.choose(args.name)
        stored = load_classifier(store, name)
        if args.k is not None:
            stored.classifier.set_params(k=args.k)
        target = stored.target if args.target is None else args.target
        if target != stored.target:
            raise ConfigError(
                f"case base {name!r} predicts {stored.target!r}; to check clips against "
                f"{target!r}, train a case base with --target {target}",
                "--target",
            )
        subjects = [s.strip() for s in args.subjects.split(",")] if args.subjects else None
        inputs = load_inputs(args.clips, args.sensor, subjects, target)
        clips, truths = [s for s, _ in inputs], [t for _, t in inputs]
        if args.feedback is None:
            results = classify_clips(stored, clips, truths)
        else:
            known = sorted(set(stored.classifier.case_base_.labels.tolist()))
            label = check_feedback_label(args.feedback, known, args.new_label)
            results = classify_with_feedback(store, stored, clips, truths, label, settings)
    finally:
        store.close()
    _print(args, store.where, name, results)
    return 0


def _print(args: argparse.Namespace, where: str, name: str, results: list[Any]) -> None:
    labelled = [r for r in results if r.true_label is not None]
    right = sum(r.true_label == r.label for r in labelled)
    accuracy = right / len(labelled) if labelled else None
    if args.json:
        doc: dict[str, Any] = {
            "db": where,
            "case_base": name,
            "results": [r.to_dict() for r in results],
        }
        if accuracy is not None:
            doc["accuracy"] = accuracy
            doc["n_labelled"] = len(labelled)
        json.dump(doc, sys.stdout, indent=2, ensure_ascii=False)
        print()
        return
    for r in results:
        _print_one(r, args.top)
    if accuracy is not None:
        print(f"accuracy: {accuracy:.3f} ({right}/{len(labelled)} labelled clips)")


def _print_one(r: Any, top: int) -> None:
    if r.solved is None:
        print(f"{r.source}: unclassifiable ({r.unclassifiable})")
        return
    e, solved = r.explanation, r.solved
    head = f"{r.source}: {e.label} (confidence {e.confidence:.2f})"
    if r.true_label is not None:
        head += "  [right]" if r.true_label == e.label else f"  [wrong: {r.true_label}]"
    print(head)
    if solved.unlike_cases:
        print(
            f"  note: this clip is unlike the stored cases (nearest case at {solved.novelty:.1f}x "
            "the usual held-out distance): treat the label with caution"
        )
    if solved.torso_share < 0.5:
        print(f"  note: the person is seen in only {100 * solved.torso_share:.0f} % of the frames")
    for n in e.neighbours[:top]:
        print(f"  case #{n['case_id']} {n['label']}  distance {n['distance']:.4g}  {n['source']}")
    for line in e.text.splitlines()[1:]:
        print(f"  {line}")
    if r.retention is not None:
        print(f"  feedback: {r.retention.reason}")
    if r.revision is not None:
        print(
            f"  feedback: revised case #{r.revision.case_id} ({r.revision.action}): "
            f"{r.revision.reason}"
        )
