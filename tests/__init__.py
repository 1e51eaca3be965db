"""posecbr's tests."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def docs_text() -> str:
    """README.md and the pages of docs/ it links for the measurements (docs/*.md), as one
    text: a figure the README sums up may be quoted in full from either."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    return "\n\n".join(page.read_text(encoding="utf-8") for page in pages)
