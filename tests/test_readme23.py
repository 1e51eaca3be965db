"""README audit: what the README's commands promise, checked where the code fell short."""

from __future__ import annotations

import importlib

import pytest

# benchmarks that take no options: `python -m benchmarks.<name> --help` ran the whole
# benchmark (ceiling: about 4 minutes) and overwrote its results file
NO_OPTIONS = ("segment_cuts", "segment_live", "ceiling", "inner_sample", "correctness")


@pytest.mark.parametrize("name", NO_OPTIONS)
def test_a_benchmark_without_options_answers_help_without_running(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    module = importlib.import_module(f"benchmarks.{name}")
    with pytest.raises(SystemExit) as stop:
        module.main(["--help"])
    assert stop.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: python -m benchmarks.{name}")
    assert "benchmarks/results/" in out  # the docstring: what it writes


@pytest.mark.parametrize("name", NO_OPTIONS)
def test_a_benchmark_without_options_refuses_an_unknown_option(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    module = importlib.import_module(f"benchmarks.{name}")
    with pytest.raises(SystemExit) as stop:
        module.main(["--no-such-option"])
    assert stop.value.code == 2
    assert "unrecognized arguments: --no-such-option" in capsys.readouterr().err


def test_every_section_is_in_the_contents_and_every_link_there_finds_its_heading() -> None:
    """The README's contents line links each ``##`` section by GitHub's anchor (lower case,
    punctuation but hyphens dropped, spaces as hyphens): a section renamed or added without
    it is caught here."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    headings = [line[3:].strip() for line in text.splitlines() if line.startswith("## ")]
    anchors = {re.sub(r"[^\w\- ]", "", h.lower()).replace(" ", "-"): h for h in headings}
    block = text[text.index("**Contents:**") : text.index("\n\n", text.index("**Contents:**"))]
    links = re.findall(r"\[([^\]]+)\]\(#([^)]+)\)", block)
    assert [anchors.get(a) for _, a in links] == headings
    assert [name for name, _ in links] == headings
