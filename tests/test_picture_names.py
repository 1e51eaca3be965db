"""A picture's name says its format: `reps --plot` and `describe --plot` write SVG or PDF when
asked by the name, and refuse a name matplotlib writes no format for (a PNG under "x.txt" or
a name without a suffix), in one line before any work."""

from __future__ import annotations

from pathlib import Path

import pytest

from features.poses import save_pose
from posecbr.cli import main
from tests.badinput import refused, standing_clip


@pytest.fixture
def clip(tmp_path: Path) -> Path:
    return save_pose(standing_clip(frames=30), tmp_path / "standing.npz")


@pytest.mark.parametrize("command", ["reps", "describe"])
@pytest.mark.parametrize("name", ["picture.txt", "picture", "picture.mp4"])
def test_a_picture_name_no_format_has_is_refused(
    command: str, name: str, clip: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    line = refused([command, str(clip), "--plot", str(tmp_path / name)], tmp_path, capsys,
                   "the picture must be a file name ending in a format", name)  # fmt: skip
    suffix = Path(name).suffix
    assert (repr(suffix) if suffix else "no suffix") in line


@pytest.mark.parametrize("command", ["reps", "describe"])
def test_an_svg_name_gets_an_svg(
    command: str, clip: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "timeline.svg"
    assert main([command, str(clip), "--plot", str(out)]) == 0
    capsys.readouterr()
    text = out.read_text(encoding="utf-8")
    assert "<svg" in text[:2000] and text.rstrip().endswith("</svg>")
