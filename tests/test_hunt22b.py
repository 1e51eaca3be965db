"""Bugs found by hunting as a new user would in the less-tested commands (``report``, ...).
Each refusal is one line naming the file and the problem, exit 1, nothing written
(:func:`tests.badinput.refused`); each answer is checked against a value worked out by hand."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused

# ---- report ---------------------------------------------------------------------------------


def test_report_on_a_results_file_nested_too_deeply_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A results file of 100,000 nested lists (JSON, but no comparison's results): json's
    decoder ran out of recursion and the command ended in a RecursionError traceback."""
    results = tmp_path / "results.json"
    results.write_text("[" * 100_000 + "]" * 100_000, encoding="utf-8")
    refused(["report", str(results), "--out", str(tmp_path / "report.html")], tmp_path, capsys,
            f"{results}: not a JSON results file (nested too deeply)")  # fmt: skip
