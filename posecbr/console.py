"""The ``posecbr`` console script: :func:`posecbr.cli.main`, with a Ctrl-C that comes while
the command line's modules are still being imported said as the stop it is."""

from __future__ import annotations

import sys
from typing import NoReturn


def run() -> NoReturn:
    """Import :mod:`posecbr.cli` and run its ``main``. A Ctrl-C while the import runs (the
    first tenths of a second, before ``main`` handles interrupts) is "posecbr: interrupted",
    exit 130, as one later is; before, the console script printed Python's traceback of a
    KeyboardInterrupt and ended by SIGINT."""
    try:
        from posecbr.cli import main
    except KeyboardInterrupt:
        print("posecbr: interrupted", file=sys.stderr)
        sys.exit(130)
    sys.exit(main())
