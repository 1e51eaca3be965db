"""Hunt 38v: README's "Long recordings" run as written on today's code. The paragraph on a
case base of CMU subject 13's three recordings segmenting the filmed videos said the half
jumping jacks of ``jumping_jack_two_people`` came out ArmCircle "with 1.7 s unknown"; since
4df3570 (the running median cut at the clip's ends, which moved the repetition windows) they
come out ArmCircle throughout, 6 repetitions, 6 by hand (tests/fixtures/repetition_counts.json).
The segments are worked out here from a run of the command, and the README's sentence read
back (from docs/measurements.md, where it now lives)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from features.poses import PoseSequence, save_pose
from features.readers.asfamc import read_asf_amc
from posecbr.cli import main
from tests import docs_text

NAMES = ("JumpJack", "Jog", "Squat", "KneeRaise", "ArmCircle", "Twist", "SideReach", "Box",
         "UpDown", "ToeTouchOneHand", "SideBend", "ToeTouchTwoHands")  # fmt: skip


def test_cmu_case_base_calls_the_half_jumping_jacks_arm_circles_throughout(
    shared_data: Path,
    bundled_poses: Callable[[str], PoseSequence],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``segment`` reads the video's poses as extract finds them, estimated once in the
    session (tests/test_dad_video.py reads them too): its --json of the video but for the
    path (checked with this case base), without the pose model again."""
    cmu = tmp_path / "cmu"
    cmu.mkdir()
    (cmu / "names.txt").write_text("".join(f"{i} {n}\n" for i, n in enumerate(NAMES, 1)))
    rows = ["path,label_file,label_block_s,label_names"]
    for r in ("13_29", "13_30", "13_31"):
        seq = read_asf_amc(
            shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
            shared_data / "cmu-mocap6" / "amc" / f"{r}.amc",
        )
        save_pose(seq, cmu / f"{r}.npz")
        labels = shared_data / "cmu-mocap6" / "truelabels" / f"{r}.txt"
        rows.append(f"{r}.npz,{labels},0.1,names.txt")
    (cmu / "all.csv").write_text("\n".join(rows) + "\n")
    db = tmp_path / "cmu-all.sqlite"
    assert main(["train", str(cmu / "all.csv"), "--db", str(db)]) == 0
    video = "edge/jumping_jack_two_people_pexels8402086.mp4"
    poses = save_pose(bundled_poses(video), tmp_path / "jumping_jack_two_people_pexels8402086.npz")
    capsys.readouterr()
    assert main(["segment", str(poses), "--db", str(db), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    # 250 frames at 25 fps; one segment over all of them, ArmCircle, its 6 arm raises
    # counted (the hand count: arms up at 1.25, 2.9, 4.65, 6.35, 8.2 and 9.9 s)
    assert doc["frames"] == 250
    assert [(s["start_frame"], s["end_frame"], s["label"], s["repetitions"])
            for s in doc["segments"]] == [(0, 250, "ArmCircle", 6)]  # fmt: skip
    readme = " ".join(docs_text().split())
    assert (
        "keep them) come out ArmCircle throughout, 6 repetitions (6 by hand; 1.7 s of them "
        "unknown before the running median was cut at the clip's ends, 6 December)"
    ) in readme
