"""Hunt 39b: label files and labels CSVs refused at the first command that reads them, in
one line naming the file and line, before the pose model runs and with nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused

SQUAT = Path("videos") / "squat" / "tfjs_pose_squats_pexels4838220.mp4"  # 65 frames, 5 fps


# ---------------------------------------------------------------- extract: overlapping rows


@pytest.mark.parametrize(
    ("rows", "needles"),
    [
        (["{v},squat,s01,0,30", "{v},lunge,s01,20,50"],
         ["lines 2 and 3 give tfjs_pose_squats_pexels4838220.mp4 frames 0,30 ('squat')",
          "and frames 20,50 ('lunge'): frames 20-29 would be cases of two activities"]),
        (["{v},squat,s01,10,20", "{v},squat_all,s02,,"],
         ["lines 2 and 3 give tfjs_pose_squats_pexels4838220.mp4 frames 10,20 ('squat') and"
          " whole ('squat_all'): frames 10-19 would be cases of two activities"]),
    ],
    ids=["overlapping start,end", "a stretch and the whole video"],
)  # fmt: skip
def test_extract_refuses_rows_giving_frames_of_a_video_two_labels(
    tmp_path: Path,
    shared_data: Path,
    capsys: pytest.CaptureFixture[str],
    rows: list[str],
    needles: list[str],
) -> None:
    """``extract`` of a labels CSV wrote the pose files of both rows (frames 20-29 under
    squat/ and lunge/), which ``train``, ``compare`` and ``convert`` of that CSV refuse and a
    ``train`` of the folder written takes as cases of two activities: refused as they refuse
    it, naming both lines, before the pose model runs."""
    video = shared_data / SQUAT
    csv = tmp_path / "labels.csv"
    body = "\n".join(r.format(v=video) for r in rows)
    csv.write_text(f"path,label,subject,start,end\n{body}\n", encoding="utf-8")
    refused(["extract", str(csv), "--out", str(tmp_path / "poses")], tmp_path, capsys,
            f"{csv}: ", *needles)  # fmt: skip


def test_extract_takes_overlapping_rows_of_one_label(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Rows of one label may overlap (as train takes them): not refused by the check."""
    from posecbr.commands.extract import find_jobs

    video = shared_data / SQUAT
    csv = tmp_path / "labels.csv"
    csv.write_text(f"path,label,start,end\n{video},squat,0,30\n{video},squat,20,50\n")
    jobs = find_jobs(csv, tmp_path / "poses", None)
    assert [(j.label, j.start, j.end) for j in jobs] == [("squat", 0, 30), ("squat", 20, 50)]
