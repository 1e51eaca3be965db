"""Hunt 38t: the command line's options, one idea under one name across commands, and what
each command says it did.

- ``compare -k 3`` was refused ("unrecognized arguments: -k 3") where ``train``,
  ``classify``, ``segment`` and ``casebase trim`` take ``-k``: compare now takes it too.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from posecbr.cli import main

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


def test_compare_takes_k_as_the_other_commands_spell_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``-k 1``: the one case-base configuration retrieves 1 case, as ``--k 1`` says."""
    out = tmp_path / "results.json"
    argv = [
        "compare", str(DEMO), "--similarities", "euclidean", "--features", "fluents",
        "--no-dad", "--peers", "none", "--labels", "deep_squat,hurdle_step",
        "--explain", "0", "-k", "1", "--json", str(out),
    ]  # fmt: skip
    assert main(argv) == 0, capsys.readouterr().err
    assert json.loads(out.read_text())["settings"]["k"] == 1
