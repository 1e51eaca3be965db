"""Defects found hunting the coach's commands besides train/classify/segment (dad, describe,
thresholds, report), on real UI-PRMD data."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cbr.dad import detect
from features.datasets import load_clip
from features.poses import PoseSequence, save_pose
from features.skeleton import JOINT_INDEX
from posecbr.cli import main
from tests.badinput import refused

KINECT_SQUAT = "ui-prmd/data/Segmented Movements/Kinect/Positions/m01_s01_e01_positions.txt.gz"


@pytest.fixture(scope="module")
def squat(shared_data: Path) -> PoseSequence:
    return load_clip(shared_data / KINECT_SQUAT)


def _without(seq: PoseSequence, joint: str) -> PoseSequence:
    pos = seq.positions.copy()
    pos[:, JOINT_INDEX[joint], :] = np.nan
    return replace(seq, positions=pos)


def test_dad_does_not_score_an_activity_mostly_unobservable(squat: PoseSequence) -> None:
    """A deep squat with its left knee missing throughout: the left kick's QMPs (weights 10, 5
    and 2 in add.toml) are observable only through "arms held steady" (2 of 17), which used to
    score the kick 100 % and tie it for best match. An activity is scored only when at least
    half its weight is observable."""
    result = detect(_without(squat, "left_knee"))
    kick = next(a for a in result.activities if a.activity == "kick_left_front")
    assert (kick.observable_weight, kick.total_weight) == (2, 17)
    assert math.isnan(kick.score)
    for act in result.activities:
        seen = act.observable_weight / act.total_weight
        assert math.isnan(act.score) == (seen < 0.5), act.activity
    assert result.best is not None and result.best.activity != "kick_left_front"
    # The whole clip keeps every activity scored as before (Kinect lacks only the heels).
    whole = detect(squat)
    assert all(np.isfinite(a.score) for a in whole.activities)
    assert whole.best is not None and whole.best.activity == "deep_squat"


def test_dad_text_and_json_say_how_much_was_not_observable(
    squat: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = tmp_path / "no_left_knee.npz"
    save_pose(_without(squat, "left_knee"), clip)
    assert main(["dad", str(clip), "--top", "0"]) == 0
    out = capsys.readouterr().out
    assert "tied with" not in out.splitlines()[1]  # no 100 % tie of squat, kick, lunges...
    assert "kicking forward with the left leg: not scored: only 2 of its 17 weight observable" in (
        out
    )
    assert main(["dad", str(clip), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    kick = next(a for a in doc["activities"] if a["activity"] == "kick_left_front")
    assert kick["score"] is None and kick["total_weight"] == 17
    # The deep squat seen whole: its squat reads 33 of 38 weight observable (no heels).
    whole = tmp_path / "whole.npz"
    save_pose(squat, whole)
    assert main(["dad", str(whole), "--top", "2"]) == 0
    out = capsys.readouterr().out
    assert "squat: 33/33 weight in order (5 of 38 not observable)" in out


def test_dad_refuses_a_clip_where_no_activity_is_half_observable(
    squat: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Both hips missing throughout: no activity has half its weight observable, and one used
    to be crowned from the few QMPs left."""
    seq = _without(_without(squat, "left_hip"), "right_hip")
    result = detect(seq)
    assert result.status == "not enough data" and result.best is None
    assert "of its QMPs' weight observable" in result.message
    clip = tmp_path / "legless.npz"
    save_pose(seq, clip)
    capsys.readouterr()
    refused(["dad", str(clip)], tmp_path, capsys, "legless.npz", "not enough data")


def _resampled(seq: PoseSequence, fps: float) -> PoseSequence:
    """``seq`` at ``fps``, each coordinate linearly interpolated in time (the same movement)."""
    t0 = np.arange(seq.n_frames) / seq.fps
    t1 = np.arange(0.0, t0[-1] + 1e-9, 1.0 / fps)
    flat = seq.positions.reshape(seq.n_frames, -1)
    cols = [np.interp(t1, t0, flat[:, c]) for c in range(flat.shape[1])]
    pos = np.stack(cols, axis=1).reshape(len(t1), *seq.positions.shape[1:])
    return replace(seq, positions=pos, fps=fps, confidence=None)


def _spans_s(doc: dict, words: str) -> list[tuple[float, float]]:
    return [
        (r["start_s"], r["end_s"]) for r in doc["runs"] for s in r["states"] if s["words"] == words
    ]


def test_describe_default_min_run_is_a_time_not_a_frame_count(
    squat: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The deep squat's left knee bends from 0.60 to 0.93 s at 30 fps (10 frames). At 10 fps
    those are 3-4 frames, and the default --min-run of 5 frames dropped the bending (and the
    straightening) from the description; at 240 fps 5 frames (21 ms) let flicker split the
    straightening in two. The default is 1/6 s: 5 frames at 30, 2 at 10, 40 at 240 fps."""
    from posecbr.commands.describe import default_min_run

    assert [default_min_run(f) for f in (10.0, 30.0, 240.0, 100.0)] == [2, 5, 40, 17]
    docs = {}
    for fps in (30.0, 10.0, 240.0):
        clip = save_pose(_resampled(squat, fps), tmp_path / f"squat_{fps:g}.npz")
        assert main(["describe", str(clip), "--json"]) == 0
        docs[fps] = json.loads(capsys.readouterr().out)
    for words in ("left knee bending", "left knee straightening"):
        ((start, end),) = _spans_s(docs[30.0], words)
        for fps in (10.0, 240.0):
            spans = _spans_s(docs[fps], words)
            assert len(spans) == 1, (fps, words, spans)
            # the same stretch of time: overlapping at least half the 30-fps span
            overlap = min(spans[0][1], end) - max(spans[0][0], start)
            assert overlap >= 0.5 * (end - start), (fps, words, spans, (start, end))
    # at 30 fps the default is the 5 frames it was: the same lines as --min-run 5
    clip = tmp_path / "squat_30.npz"
    assert main(["describe", str(clip)]) == 0
    default = capsys.readouterr().out
    assert main(["describe", str(clip), "--min-run", "5"]) == 0
    assert capsys.readouterr().out == default


def test_dad_says_a_window_has_too_few_frames_not_that_joints_are_missing(
    squat: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """At 5 fps (the bundled squat video's rate) a 2-s window is 10 frames and the QMP fit
    needs 12 (twice its six basis functions): every window was "not enough data" and DAD
    said "no QMP could be observed (joints missing, or gaps too long)" of a clip with every
    joint in every frame."""
    slow = _resampled(squat, 5.0)  # 2.4 s: 12 frames
    assert not np.isnan(slow.positions[:, JOINT_INDEX["left_knee"]]).any()
    clip = save_pose(slow, tmp_path / "slow.npz")
    capsys.readouterr()
    line = refused(["dad", str(clip), "--window", "2"], tmp_path, capsys)
    assert line == (
        f"posecbr dad: error: {clip}: not enough data: a window of 2 s is 10 frames at 5 fps; "
        "fitting QMPs needs at least 12 frames (2.4 s at this rate)"
    )
    # the whole clip cut to 10 frames (2 s, more than DAD's 0.5 s) is named as the clip
    short = save_pose(slow.slice_frames(0, 10), tmp_path / "short.npz")
    result = detect(load_clip(short))
    assert result.status == "not enough data" and "joints missing" not in result.message
    assert result.message.startswith("the clip is 10 frames at 5 fps")
    # with 12 frames a window is judged
    assert main(["dad", str(clip), "--window", "2.4"]) == 0
    assert "best match: " in capsys.readouterr().out


def test_describe_a_joint_seen_every_other_frame_is_still_described(
    squat: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The left knee tracked in every other frame (a joint at the edge of a video): each
    frame without it counted as a frame its states did not hold, so "left knee bent" never
    held five frames running and vanished from the description, while "right knee bent"
    (frames 17-61) was there, and the knee was not listed as unavailable either."""
    pos = squat.positions.copy()
    pos[1::2, JOINT_INDEX["left_knee"]] = np.nan
    clip = save_pose(replace(squat, positions=pos), tmp_path / "flicker.npz")
    capsys.readouterr()
    assert main(["describe", str(clip), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    ((start, end),) = [
        (r["start_frame"], r["end_frame"])
        for r in doc["runs"]
        for s in r["states"]
        if s["words"] == "left knee bent"
    ]
    whole = save_pose(squat, tmp_path / "whole.npz")
    assert main(["describe", str(whole), "--json"]) == 0
    ((s0, e0),) = [
        (r["start_frame"], r["end_frame"])
        for r in json.loads(capsys.readouterr().out)["runs"]
        for s in r["states"]
        if s["words"] == "left knee bent"
    ]
    assert abs(start - s0) <= 1 and abs(end - e0) <= 1, ((start, end), (s0, e0))


def test_describe_claims_no_state_in_frames_where_nobody_was_seen(
    squat: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Every joint missing in frames 10-19: no span of any state may include them (the
    missing frames are bridged only inside a run, never at its edge)."""
    pos = squat.positions.copy()
    pos[10:20] = np.nan
    clip = save_pose(replace(squat, positions=pos), tmp_path / "gap.npz")
    capsys.readouterr()
    for extra in ([], ["--min-run", "9"]):
        assert main(["describe", str(clip), "--json", *extra]) == 0
        doc = json.loads(capsys.readouterr().out)
        assert doc["runs"]
        for r in doc["runs"]:  # end_frame exclusive
            assert r["end_frame"] <= 10 or r["start_frame"] >= 20, r


def test_describe_per_frame_says_when_nobody_was_seen(
    squat: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A frame with every joint missing read "(no state above the threshold)", as if the
    person had been seen doing nothing in particular."""
    pos = squat.positions.copy()
    pos[10:20] = np.nan
    clip = save_pose(replace(squat, positions=pos), tmp_path / "gap.npz")
    capsys.readouterr()
    assert main(["describe", str(clip), "--per-frame"]) == 0
    lines = {
        int(line.split(":")[0].split()[1]): line
        for line in capsys.readouterr().out.splitlines()
        if line.startswith("frame ")
    }
    assert len(lines) == squat.n_frames
    for k in range(10, 20):
        assert lines[k] == f"frame {k}: (nobody seen: every joint missing)"
    assert "nobody" not in lines[9] and "nobody" not in lines[20]


@pytest.mark.parametrize("min_run", [2, 5, 8])
def test_cleaning_with_every_frame_known_is_scipys_running_median(min_run: int) -> None:
    """With every frame known the running majority is the running median of the on/off
    tracks that scipy's ``median_filter`` (ends repeated: ``mode="nearest"``) gives, of an
    odd window of ``min_run`` frames (one more when even)."""
    from scipy.ndimage import median_filter

    from features.timeline import _clean

    on = np.random.default_rng(min_run).random((200, 7)) < 0.5
    size = min_run if min_run % 2 else min_run + 1
    expected = median_filter(on.astype(np.uint8), size=(size, 1), mode="nearest").astype(bool)
    np.testing.assert_array_equal(_clean(on, min_run), expected)
