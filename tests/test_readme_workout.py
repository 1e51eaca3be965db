"""The README's workout example ("Long recordings"), run as it is written: four real exercise
clips of ../shared/data/videos joined into one video by tools/make_workout.py, a case base of
windows trained on their earlier parts, the workout segmented. Its segments are checked
against the truth file make_workout writes and the hand counts, and the README's output block
against what the commands print."""

from __future__ import annotations

import csv
import os
import re
import subprocess
import sys
from pathlib import Path

from tests.test_readme_mocap import _blocks

ROOT = Path(__file__).resolve().parents[1]
LEAD = "A workout video holds several exercises"


def test_the_workout_example_prints_what_the_readme_shows(
    shared_data: Path, tmp_path: Path
) -> None:
    script, shown = _blocks(LEAD)
    assert "python tools/make_workout.py workout/" in script
    script = script.replace("python tools/", f"{sys.executable} {ROOT}/tools/")
    env = {
        **os.environ,
        "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
        "POSECBR_SHARED_DATA": str(shared_data),
    }
    proc = subprocess.run(["bash", "-e", "-c", script], cwd=tmp_path, capture_output=True,
                          text=True, timeout=600, env=env)  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = re.findall(r"^ +([\d.]+) +([\d.]+) +\d+-\d+ +(\S+) +[\d.]+ +(\d+)$", proc.stdout, re.M)
    with open(tmp_path / "workout" / "workout_truth.csv", newline="") as fh:
        truth = [(float(r["start_s"]), r["label"]) for r in csv.DictReader(fh)]
    # the four exercises in order, each found within 1 s of where it starts
    assert [r[2] for r in rows] == [label for _, label in truth]
    for (start, _, _, _), (t_start, _) in zip(rows, truth, strict=True):
        assert abs(float(start) - t_start) <= 1.0, (start, t_start)
    # counted by hand: 3 jumping jacks, 2 squats, 2 push-ups, 2 bridges (README)
    assert [int(r[3]) for r in rows] == [3, 2, 2, 2]
    # what the README shows is what the commands print
    printed = proc.stdout + proc.stderr
    for line in shown.splitlines():
        if line.strip():
            assert line.rstrip() in printed, line
    # and every note segment prints is shown (hunt 39h: the pose jumping to another person at
    # the cut from the jumping jacks to the squats was printed, not shown)
    notes = [ln for ln in proc.stderr.splitlines() if ln.startswith("note: workout/workout.mp4")]
    assert notes, proc.stderr
    for note in notes:
        assert note in shown.splitlines(), note
    assert (tmp_path / "timeline.png").stat().st_size > 0
    assert (tmp_path / "seen.mp4").stat().st_size > 0
