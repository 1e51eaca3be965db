"""``posecbr describe`` end to end: words, JSON, a timeline picture, and bad input."""

from __future__ import annotations

import json
import math
import zipfile
from pathlib import Path

import numpy as np
import pytest

from features.poses import PoseSequence, save_pose
from features.skeleton import BLAZEPOSE_33
from posecbr.cli import main
from tests.bodies import standing, to_sequence


def _squat(frames: int = 60) -> PoseSequence:
    """Both knees bend from straight to about 70 degrees and back, thighs swinging forward."""
    out = []
    for k in range(frames):
        body = standing()
        knee = math.radians(180 - 110 * math.sin(math.pi * k / (frames - 1)))
        half = (math.pi - knee) / 2  # thigh forward and shank back by the same amount
        for side, x in (("left", 0.15), ("right", -0.15)):
            body[f"{side}_knee"] = np.array([x, 1.0 - 0.45 * math.cos(half), 0.45 * math.sin(half)])
            body[f"{side}_ankle"] = body[f"{side}_knee"] + 0.45 * np.array(
                [0, -math.cos(half), -math.sin(half)]
            )
        out.append(body)
    return to_sequence(*out)


def test_describe_prints_runs_in_words(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = save_pose(_squat(), tmp_path / "squat.npz")
    assert main(["describe", str(path)]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0].startswith(f"{path}: 60 frames at 30 fps")
    assert "left knee straight" in lines[1]  # starts standing
    at_30 = []
    for line in lines[1:]:
        span = line.split(":")[0].split(" ")[1].split("–")
        if int(span[0]) <= 30 <= int(span[-1]):
            at_30.append(line)
    assert any("left knee bent" in line for line in at_30)
    assert any("right knee bent" in line for line in at_30)
    assert not any("knee straight " in line for line in at_30)
    assert "bending" in out and "straightening" in out


def test_describe_json_and_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = save_pose(_squat(), tmp_path / "squat.npz")
    png = tmp_path / "timeline.png"
    assert main(["describe", str(path), "--json", "--plot", str(png)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["frames"] == 60 and data["fps"] == 30
    # at the deepest frame (30) both knees are bent
    names = {s["name"] for r in data["runs"] if r["start_frame"] <= 30 < r["end_frame"]
             for s in r["states"]}  # fmt: skip
    assert {"left_leg_bent.bent", "right_leg_bent.bent"} <= names
    assert "left_leg_bent.straight" not in names
    assert min(r["start_frame"] for r in data["runs"]) == 0
    # the last span ends with the clip: frame 60 exclusive, 2.0 s, as segment's and reps'
    assert max(r["end_frame"] for r in data["runs"]) == 60
    for r in data["runs"]:
        assert r["end_s"] == pytest.approx(r["end_frame"] / 30, abs=1e-4)
        assert r["start_frame"] < r["end_frame"]
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


def test_per_frame_lists_every_frame(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = save_pose(_squat(20), tmp_path / "squat.npz")
    assert main(["describe", str(path), "--per-frame", "--json"]) == 0
    runs = json.loads(capsys.readouterr().out)["runs"]
    assert [r["start_frame"] for r in runs] == list(range(20))


def test_describe_reports_unavailable_fluents(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    body = standing()
    for j in ("nose", "left_ear", "right_ear"):
        del body[j]
    path = save_pose(to_sequence(body, body), tmp_path / "noface.npz")
    assert main(["describe", str(path)]) == 0
    out = capsys.readouterr().out
    missing = (
        "unavailable (joints missing or the angle undefined in every frame): head tilted forward,"
        " head tilted left, head twisted"
    )
    assert missing in out
    # head-lengths need the ears: near/far are unavailable, touching (raw metres) is not
    assert main(["describe", str(path), "--json", "--all"]) == 0
    states = json.loads(capsys.readouterr().out)["runs"][0]["states"]
    names = {s["name"] for s in states}
    assert not any(n.endswith((".near", ".far_from")) for n in names)
    assert "near:left_index~right_index.touching" not in names  # 0 is not >= 0.8


def _bad(tmp_path: Path) -> dict[str, Path]:
    files: dict[str, Path] = {}
    good = save_pose(to_sequence(standing(), standing()), tmp_path / "good.npz")
    data = good.read_bytes()
    files["truncated"] = tmp_path / "truncated.npz"
    files["truncated"].write_bytes(data[: len(data) // 2])
    files["not a pose file"] = tmp_path / "text.npz"
    files["not a pose file"].write_text("hello")
    files["missing"] = tmp_path / "nope.npz"
    wrong = tmp_path / "wrong_shape.npz"
    np.savez(wrong, positions=np.zeros((5, 33, 2)), joint_names=np.array(BLAZEPOSE_33), fps=30.0)
    files["shape"] = wrong
    unknown = tmp_path / "unknown_skeleton.npz"
    np.savez(unknown, positions=np.zeros((5, 33, 3)), joint_names=np.array(BLAZEPOSE_33),
             fps=30.0, skeleton="octopus8")  # fmt: skip
    files["skeleton"] = unknown
    empty = tmp_path / "empty.npz"
    np.savez(empty, positions=np.zeros((0, 33, 3)), joint_names=np.array(BLAZEPOSE_33), fps=30.0)
    files["no frames"] = empty
    nofps = tmp_path / "nofps.npz"
    with zipfile.ZipFile(nofps, "w"):
        pass
    files["empty zip"] = nofps
    return files


@pytest.mark.parametrize(
    ("case", "needle"),
    [
        ("truncated", "cannot read pose file"),
        ("not a pose file", "cannot read pose file"),
        ("missing", "no such file"),
        ("shape", "shape (frames, joints, 3)"),
        ("skeleton", "unknown skeleton 'octopus8'"),
        ("no frames", "no frames"),
        ("empty zip", "missing fps, joint_names, positions"),
    ],
)
def test_bad_pose_files_give_one_clear_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str, needle: str
) -> None:
    path = _bad(tmp_path)[case]
    assert main(["describe", str(path)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert str(path) in err and needle in err
    assert "Traceback" not in err


def test_nan_joints_and_one_frame_clip_are_described(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    body = standing()
    body["left_wrist"] = np.array([np.nan, np.nan, np.nan])
    path = save_pose(to_sequence(body), tmp_path / "one.npz")
    assert main(["describe", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["frames"] == 1
    names = {s["name"] for s in data["runs"][0]["states"]}
    assert "right_arm_bent.straight" in names and "left_arm_bent.straight" not in names


def test_thresholds_round_trip(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["thresholds"]) == 0
    table = json.loads(capsys.readouterr().out)
    assert table["fluents"]["left_leg_bent"]["lower"]["tau"] == pytest.approx(19 * math.pi / 24)
    # a user lowers the knee threshold so a 150-degree knee reads bent
    table["fluents"] = {"leg_bent": {"lower": {"tau": "7pi/8", "delta": "pi/48"}}}
    custom = tmp_path / "mine.json"
    custom.write_text(json.dumps(table))
    body = standing()
    body["left_ankle"] = body["left_knee"] + 0.45 * np.array(
        [0, -math.cos(math.radians(30)), -math.sin(math.radians(30))]
    )
    path = save_pose(to_sequence(body), tmp_path / "knee150.npz")
    assert main(["describe", str(path), "--json"]) == 0
    default = {s["name"] for s in json.loads(capsys.readouterr().out)["runs"][0]["states"]}
    assert "left_leg_bent.straight" in default
    assert main(["describe", str(path), "--json", "--thresholds", str(custom)]) == 0
    mine = {s["name"] for s in json.loads(capsys.readouterr().out)["runs"][0]["states"]}
    assert "left_leg_bent.bent" in mine


def test_pose_files_are_written_with_ordinary_permissions(tmp_path: Path) -> None:
    import os

    mask = os.umask(0o022)
    try:
        path = save_pose(to_sequence(standing()), tmp_path / "p.npz")
    finally:
        os.umask(mask)
    assert oct(path.stat().st_mode & 0o777) == "0o644"
    assert not list(tmp_path.glob(".*.tmp"))  # no temporary file left behind


def test_an_angle_undefined_with_every_joint_present_is_not_blamed_on_missing_joints(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Both arms held exactly sideways (a T-pose) for the whole clip, every joint present: "arm
    in front" reads the arm's projection on the sagittal plane, which has no length there
    (SPEC.md), so the fluent is unavailable; the line must not say the joints are missing."""
    from tests.bodies import rot_z, rotate

    arm = tuple(
        f"{s}_{j}" for s in ("left",) for j in ("elbow", "wrist", "pinky", "index", "thumb")
    )
    body = standing()
    body = rotate(body, arm, rot_z(-90.0), body["left_shoulder"])
    right = tuple(a.replace("left_", "right_") for a in arm)
    body = rotate(body, right, rot_z(90.0), body["right_shoulder"])
    path = save_pose(to_sequence(body, body, body), tmp_path / "tpose.npz")
    assert main(["describe", str(path)]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("unavailable"))
    assert "left arm in front" in line and "right arm in front" in line
    assert line.startswith("unavailable (joints missing or the angle undefined in every frame)")
