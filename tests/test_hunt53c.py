"""A refusal of a file or option comes before the modules only the work needs are imported
(hunt 53c): ``train``, ``classify`` and ``segment`` refusing a missing input, a ``--db``
that is a folder or a case base file that does not exist, or an unknown ``--similarity``,
import neither SQLAlchemy (the store's connection, about half a second) nor the classifier's
modules (``cbr.estimator``, ``cbr.training``, ``cbr.stored``); nor does
``casebase_store.open_store`` refusing a file that is not there. Run in one new process,
whose ``sys.modules`` holds only what the refusals before imported."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests import ROOT

#: runs posecbr's entry point on each command line given (one per argument, words split on
#: "|"), then the store's ``open_store`` on a missing file, printing after each its exit
#: status, the modules asked about that are imported by then, and what it said
RUN = """
import contextlib, io, sys
from posecbr.cli import main
asked = ("sqlalchemy", "cbr.estimator", "cbr.training", "cbr.stored")
for line in sys.argv[1:-1]:
    said = io.StringIO()
    with contextlib.redirect_stderr(said):
        status = main(line.split("|"))
    print(status, [m for m in asked if m in sys.modules], said.getvalue().strip())
import casebase_store
try:
    casebase_store.open_store(sys.argv[-1], readonly=True)
except casebase_store.StoreError as exc:
    print("StoreError", [m for m in asked if m in sys.modules], exc)
"""


def test_refusals_of_files_and_options_import_neither_the_store_nor_the_classifier(
    tmp_path: Path,
) -> None:
    demo = ROOT / "posecbr" / "demo_data" / "uiprmd"
    clip, listing = demo / "m01_s01_e01.npz", demo / "labels.csv"
    missing, new, none = tmp_path / "nosuch.npz", tmp_path / "new.sqlite", tmp_path / "none.sqlite"
    lines = {
        f"train|{missing}|--db|{new}": f"posecbr train: error: {missing}: no such file or folder",
        f"train|{listing}|--db|{tmp_path}": (
            f"posecbr train: error: {tmp_path}: is a folder, not a case base file"
        ),
        f"train|{listing}|--db|{new}|--similarity|nosuch": (
            "posecbr train: error: --similarity: unknown similarity 'nosuch' (known: dtw,"
            " euclidean, signature)"
        ),
        f"train|{listing}|--db|{none}|--append": (
            f"posecbr train: error: {none}: no such case base file"
        ),
        f"classify|{clip}|--db|{none}": f"posecbr classify: error: {none}: no such case base file",
        f"segment|{clip}|--db|{tmp_path}": (
            f"posecbr segment: error: {tmp_path}: is a folder, not a case base file"
        ),
    }
    done = subprocess.run([sys.executable, "-c", RUN, *lines, str(none)], cwd=ROOT,
                          capture_output=True, text=True, timeout=60, check=False)  # fmt: skip
    said = done.stdout.splitlines()
    expected = [f"1 [] {text}" for text in lines.values()]
    expected.append(f"StoreError [] {none}: no such case base file")
    assert said == expected, done.stdout + done.stderr
    assert not new.exists() and not none.exists()  # nothing written by a refusal
