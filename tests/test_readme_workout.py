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
ROW = re.compile(
    r"^ +(?P<start>[\d.]+) +(?P<end>[\d.]+) +(?P<first>\d+)-(?P<last>\d+) +(?P<label>\S+)"
    r" +(?P<conf>[\d.]+) +(?P<reps>\d+)$"
)
EXPLAINED = re.compile(r"^ +\d+ of the \d+ most similar cases are \S+; matched: ")


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
    # what the README shows is what the commands print: word for word, but for what the pose
    # model's last digits move from one CPU to another (README: onnxruntime's kernels; on one
    # machine the last boundary 3 frames later, confidences up to 0.08 apart, other fluents
    # named): a segment's times within 0.2 s, frames within 5, confidence within 0.1, its
    # explanation up to the fluents it names
    printed = proc.stdout + proc.stderr
    segments = [ROW.match(ln) for ln in printed.splitlines()]
    explained = [EXPLAINED.match(ln) for ln in printed.splitlines()]
    said = {m[0] for m in explained if m}
    shown_rows = [m for m in map(ROW.match, shown.splitlines()) if m]
    assert len(shown_rows) == len(rows)
    for want, got in zip(shown_rows, [m for m in segments if m], strict=True):
        assert (want["label"], want["reps"]) == (got["label"], got["reps"]), (want[0], got[0])
        for key, tol in (("start", 0.2), ("end", 0.2), ("first", 5), ("last", 5), ("conf", 0.1)):
            assert abs(float(want[key]) - float(got[key])) <= tol, (key, want[0], got[0])
    for line in shown.splitlines():
        if ROW.match(line):
            continue
        if m := EXPLAINED.match(line):
            assert m[0] in said, line
        elif line.strip():
            assert line.rstrip() in printed, line
    # and every note segment prints is shown (hunt 39h: the pose jumping to another person at
    # the cut from the jumping jacks to the squats was printed, not shown)
    notes = [ln for ln in proc.stderr.splitlines() if ln.startswith("note: workout/workout.mp4")]
    assert notes, proc.stderr
    for note in notes:
        assert note in shown.splitlines(), note
    # the label of every frame, as segment --truth reads a label file (hunt 49h: the truth
    # CSV alone, a table of stretches, is refused there): each frame's the stretch's it lies
    # in, one per frame of the workout as segment counts them
    labels = (tmp_path / "workout" / "workout_labels.txt").read_text().split("\n")
    assert labels[-1] == "" and len(labels) - 1 == int(
        re.findall(r": (\d+) frames at 25", printed)[0]
    )
    ends = [
        (float(r["end_s"]), r["label"])
        for r in csv.DictReader(
            (tmp_path / "workout" / "workout_truth.csv").read_text().splitlines()
        )
    ]
    assert labels[:-1] == [
        next(lab for end, lab in ends if i / 25 < end) for i in range(len(labels) - 1)
    ]
    assert (tmp_path / "timeline.png").stat().st_size > 0
    assert (tmp_path / "seen.mp4").stat().st_size > 0
