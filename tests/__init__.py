"""posecbr's tests."""

from __future__ import annotations

import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def docs_text() -> str:
    """README.md and the pages of docs/ it links for the measurements (docs/*.md), as one
    text: a figure the README sums up may be quoted in full from either."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    return "\n\n".join(page.read_text(encoding="utf-8") for page in pages)


def two_activities(data: Path) -> Path:
    """``data`` made a folder of one bundled demo clip of each of two activities (a folder
    per class), the least ``train`` takes: for refusals that come before any clip is read."""
    demo = ROOT / "posecbr" / "demo_data" / "uiprmd"
    for activity, clip in (("deep_squat", "m01_s01_e01.npz"), ("hurdle_step", "m02_s01_e01.npz")):
        (data / activity).mkdir(parents=True)
        shutil.copy(demo / clip, data / activity)
    return data
