"""Success lines print the paths the user gave with control characters escaped (README: "names
and paths are printed with control characters escaped"): a folder named with a terminal
escape sequence does not reach the terminal raw."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from features.poses import save_pose
from posecbr.cli import main
from tests.badinput import small_case_base, standing_clip

WEIRD = "set-title\x1b]0;pwned\x07"


def test_reps_says_where_the_picture_went_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / WEIRD
    folder.mkdir()
    clip = save_pose(standing_clip(30), tmp_path / "clip.npz")
    assert main(["reps", str(clip), "--plot", str(folder / "reps.png")]) == 0
    err = capsys.readouterr().err  # said on stderr, as every "written to"
    assert (folder / "reps.png").exists()
    assert "\x1b" not in err and "\x07" not in err
    assert "picture written to" in err and "set-title\\x1b]0;pwned\\x07" in err


def test_casebase_upgrade_names_the_database_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = small_case_base(tmp_path / "cb")
    folder = tmp_path / WEIRD
    folder.mkdir()
    weird = Path(shutil.copy(db, folder / "cb.sqlite"))
    capsys.readouterr()
    assert main(["casebase", "upgrade", "--db", str(weird)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out
    assert "set-title\\x1b]0;pwned\\x07" in out and "nothing to do" in out
