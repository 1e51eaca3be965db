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
    # (the far point's mark named after the count since hunt 37g)
    assert titles == ["m01_s01_e01.npz: 1 repetition (\u25b2 far point) over the fluent timeline"]
    assert picture.is_file()


def test_the_segment_table_keeps_its_columns_in_line_past_a_long_activity(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``segment``'s table of a video with a gap: "(no frames in the video)" (24 characters)
    and an activity named "standing_shoulder_internal_external_rotation" (UI-PRMD's, 44) ran
    into the confidence column, 20 characters wide, so "conf" and "reps" stood over nothing.
    Each row's confidence and count now end where their headings do."""
    from cbr.segmentation import NO_FRAMES, Segment, Segmentation
    from posecbr.commands.segment import _print

    long = "standing_shoulder_internal_external_rotation"
    segments = (
        Segment(0, 50, "squat", 0.91, (), "3 of the 5 most similar cases are squat", None),
        Segment(50, 100, None, 1.0, (), NO_FRAMES, None),
        Segment(100, 150, long, 0.5, (), f"5 of the 5 most similar cases are {long}", None),
    )
    _print(Segmentation("gap.mkv", 25.0, 150, segments, ()))
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "gap.mkv: 150 frames at 25 fps (6.00 s), 3 segments"
    head = lines[1]
    rows = [line for line in lines[2:] if line[:10].strip()]  # not an explanation
    assert len(rows) == 3
    conf_end, reps_end = head.index("conf") + 4, head.index("reps") + 4
    for row, conf in zip(rows, ("0.91", "1.00", "0.50"), strict=True):
        assert row[conf_end - 4 : conf_end] == conf, row
        assert row[reps_end - 1 : reps_end] == "0" and len(row) == reps_end, row
    assert "(no frames in the video)" in rows[1] and long in rows[2]
