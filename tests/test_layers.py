"""The layers run one way, checked by import-linter from the contracts in pyproject.toml:
posecbr > cbr > casebase_store > features, inside cbr the core imports neither the
evaluation harness nor the DAD baseline (nor DAD the harness), inside casebase_store the
repository stands on the connection, never the other way, the judges of unknown stand on
their calibration, and the Euclidean measure on its search, codes and row kernel."""

from __future__ import annotations

from pathlib import Path

import pytest
from importlinter.cli import lint_imports

ROOT = Path(__file__).resolve().parents[1]


def test_import_contracts_are_kept(capsys: pytest.CaptureFixture[str]) -> None:
    code = lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True, no_logo=True)
    out = capsys.readouterr().out
    assert code == 0, out
    # every contract was checked (a contract that is not found cannot fail)
    assert "Contracts: 5 kept, 0 broken." in out
