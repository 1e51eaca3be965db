"""The README's mocap example ("Mocap labelled over time trains the same way"), run as it is
written: two of CMU subject 13's recordings labelled every 0.1 s train a case base, the third
is segmented. Its stretches are checked against the recording's own label file and the hand
counts, and the README's table against what the commands print."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LEAD = "Mocap labelled over time trains the same way."
NAMES = (
    "JumpJack Jog Squat KneeRaise ArmCircle Twist SideReach Box UpDown ToeTouchOneHand "
    "SideBend ToeTouchTwoHands"
).split()  # fmt: skip  (the dataset README's order)


def _blocks(after: str) -> tuple[str, str]:
    """The bash block and the output block that follow ``after`` in the README."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    rest = text[text.index(after) :]
    blocks = re.findall(r"```(\w*)\n(.*?)```", rest, re.S)
    assert blocks[0][0] == "bash" and blocks[1][0] == ""
    return blocks[0][1], blocks[1][1]


def _stretches(shared_data: Path) -> list[tuple[float, float, str]]:
    codes = (shared_data / "cmu-mocap6" / "truelabels" / "13_31.txt").read_text().split()
    out, start = [], 0
    for i in range(1, len(codes) + 1):
        if i == len(codes) or codes[i] != codes[start]:
            out.append((0.1 * start, 0.1 * i, NAMES[int(codes[start]) - 1]))
            start = i
    return out


def test_the_mocap_example_segments_the_third_recording_as_labelled(
    shared_data: Path, tmp_path: Path
) -> None:
    script, shown = _blocks(LEAD)
    work = tmp_path / "work"
    work.mkdir()
    (tmp_path / "shared").symlink_to(shared_data.parent)  # ../shared beside, as the README has
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    proc = subprocess.run(["bash", "-e", "-c", script], cwd=work, capture_output=True,
                          text=True, timeout=300, env=env)  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = re.findall(r"^ +([\d.]+) +([\d.]+) +\d+-\d+ +(\S+) +[\d.]+ +(\d+)$", proc.stdout, re.M)
    truth = _stretches(shared_data)
    # the seven labelled stretches in order, each change within 1 s of the label file's
    assert [r[2] for r in rows] == [t[2] for t in truth]
    for (start, _, _, _), (t_start, _, _) in zip(rows, truth, strict=True):
        assert abs(float(start) - t_start) <= 1.0, (start, t_start)
    # each stretch's count within one of the hand count (13_31: 2, 4, 2, 1, 7, 5, 2)
    hand = [2, 4, 2, 1, 7, 5, 2]
    assert all(abs(int(r[3]) - h) <= 1 for r, h in zip(rows, hand, strict=True)), rows
    # what the README shows is what the commands print
    printed = proc.stdout + proc.stderr
    for line in shown.splitlines():
        if line.strip() and line.strip() != "...":
            assert line.rstrip() in printed, line
    assert "recordings labelled over time: a case per window" in proc.stderr
    # "How to score your own": the third recording scored against its label file, as shown
    score, scored = _blocks("**How to score your own.**")
    proc = subprocess.run(["bash", "-e", "-c", "D=../shared/data/cmu-mocap6\n" + score],
                          cwd=work, capture_output=True, text=True, timeout=300,
                          env=env)  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    for line in scored.splitlines():
        if line.strip() and line.strip() != "...":
            assert line.rstrip() in proc.stdout, line
