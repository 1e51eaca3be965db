"""README.md sends readers to docs/measurements.md for how each figure was measured (its
narratives moved there whole), one sentence and a link in each place: every link between the
pages must find its file and heading, and every section of the measurements be linked from the
README. A heading renamed on either side would break a link without a word."""

from __future__ import annotations

import re
from collections import Counter
from functools import cache
from pathlib import Path

from tests import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@cache
def _anchors(page: Path) -> set[str]:
    """GitHub's anchors of a page's headings (outside code blocks): lower case, punctuation
    but hyphens and underscores dropped, spaces as hyphens; a repeated one gets -1, -2, ..."""
    seen: Counter[str] = Counter()
    out = set()
    fence = False
    for line in page.read_text(encoding="utf-8").splitlines():
        fence ^= line.startswith("```")
        found = None if fence else re.match(r"#{1,6} (.*)", line)
        if found:
            slug = re.sub(r"[^\w\- ]", "", found.group(1).strip().lower()).replace(" ", "-")
            out.add(f"{slug}-{seen[slug]}" if seen[slug] else slug)
            seen[slug] += 1
    return out


def _links(page: Path) -> list[tuple[Path, str]]:
    """Each link of the page into the repository: the file it names and its #fragment."""
    out = []
    for target in re.findall(r"\]\(([^)\s]+)\)", page.read_text(encoding="utf-8")):
        if re.match(r"[a-z]+:", target):  # https:, mailto:
            continue
        path, _, fragment = target.partition("#")
        out.append(((page.parent / path).resolve() if path else page, fragment))
    return out


def test_every_link_of_the_readme_and_the_docs_finds_its_file_and_heading() -> None:
    broken = []
    for page in PAGES:
        for dest, fragment in _links(page):
            if not dest.exists():
                broken.append(f"{page.name}: {dest.name}: no such file")
            elif fragment and fragment not in _anchors(dest):
                broken.append(f"{page.name}: {dest.name}#{fragment}: no such heading")
    assert broken == []


def test_every_section_of_the_measurements_is_linked_from_the_readme() -> None:
    measurements = ROOT / "docs" / "measurements.md"
    text = measurements.read_text(encoding="utf-8")
    sections = {
        re.sub(r"[^\w\- ]", "", line[3:].strip().lower()).replace(" ", "-")
        for line in text.splitlines()
        if line.startswith("## ")
    }
    linked = {f for dest, f in _links(ROOT / "README.md") if dest == measurements.resolve()}
    assert len(sections) >= 10
    assert sections - linked == set()
