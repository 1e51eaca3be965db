"""``posecbr thresholds``: print the fluent parameter table, the file users edit to override."""

from __future__ import annotations

import argparse
import json
import sys

from posecbr.arguments import path_arg


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "thresholds",
        epilog="example: posecbr thresholds > mine.json",
        help="print the fluent thresholds table as JSON (edit it and pass it to describe "
        "--thresholds FILE)",
    )
    p.add_argument(
        "--from",
        "--thresholds",  # as describe names the file of overrides
        dest="source",
        type=path_arg,
        metavar="FILE",
        help="show the table after the overrides in FILE (validates FILE; --thresholds FILE:"
        " the same, as describe names it)",
    )
    p.add_argument(
        "--json",
        action="store_true",
        help="the table is JSON already (taken, as the other commands take it, and changes"
        " nothing)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from features.fluents import DEFAULT_TABLE, FluentTable

    table = FluentTable.from_file(args.source) if args.source else DEFAULT_TABLE
    json.dump(table.to_dict(), sys.stdout, indent=1)
    print()
    return 0
