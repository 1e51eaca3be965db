"""A strength coach's walkthrough of ``reps``, ``segment`` and ``classify`` on the workout
videos: what such a user saw that was wrong, each checked against values worked out by hand."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from posecbr.cli import main

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def test_the_reps_picture_says_1_repetition_not_1_repetitions(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``reps --plot`` of one deep squat (a UI-PRMD episode is one repetition; the command
    prints "1 repetition"): the picture's title says "1 repetition" too, where it said
    "1 repetitions"."""
    import features.timeline

    titles: list[str] = []
    plot = features.timeline.plot_timeline

    def plotting(*args: Any, **kwargs: Any) -> Any:
        titles.append(kwargs["title"])
        return plot(*args, **kwargs)

    monkeypatch.setattr(features.timeline, "plot_timeline", plotting)
    clip = DEMO / "m01_s01_e01.npz"
    picture = tmp_path / "reps.png"
    assert main(["reps", str(clip), "--plot", str(picture)]) == 0
    assert capsys.readouterr().out.startswith(f"{clip}: 1 repetition (")
    assert titles == ["m01_s01_e01.npz: 1 repetition over the fluent timeline"]
    assert picture.is_file()
