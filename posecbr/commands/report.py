"""``posecbr report RESULTS --out report.html``: one self-contained HTML page of a comparison."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from features.text import shown
from posecbr.arguments import path_arg


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "report",
        epilog="example: posecbr report results/ --out report.html",
        help="turn `posecbr compare` results into one self-contained HTML page",
        description="Render the results of `posecbr compare` (its --out folder or --json file) "
        "as one HTML page with the table, the pictures inlined and explanations of "
        "misclassified clips. Pictures missing from a --json-only run are drawn from the "
        "results (accuracy, confusion matrices).",
    )
    p.add_argument("results", type=path_arg, help="compare --out folder or results JSON file")
    p.add_argument(
        "--out",
        type=path_arg,
        default=Path("report.html"),
        metavar="HTML",
        help="where to write the page (default report.html)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from cbr.evaluation.report import write_report

    dest, failures = write_report(args.results, args.out)
    for line in failures:
        print(shown(line), file=sys.stderr)  # a label's character it names, escaped
    print(f"report written to {shown(dest)}", file=sys.stderr)  # as every "written to"
    return 0
