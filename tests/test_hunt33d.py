"""Hunt 33d: repetition counting and segmentation on odd recordings.

A clip without one whole repetition (the way down of a squat, half an arm circle) counted
as one repetition: its one far point was cut off by the clip's start or end, and with no
whole far point to be measured against it counted anyway."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.segmentation import counted_segments
from features.geometry import angle_between
from features.poses import PoseSequence, save_pose
from features.readers.asfamc import read_asf_amc
from features.readers.uiprmd import read_uiprmd_vicon
from features.repetitions import count_repetitions, movement_signals
from features.skeleton import JOINT_INDEX
from posecbr.cli import main
from tests.once import made_once

CMU_FPS = 120


@pytest.fixture(scope="module")
def cmu_13_29(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> PoseSequence:
    """CMU 13_29, read once in the run (the tests only read it)."""
    return made_once(
        tmp_path_factory, "hunt33d-cmu-13-29", lambda _: _read_cmu(shared_data, "13_29")
    )


def _read_cmu(shared_data: Path, take: str) -> PoseSequence:
    return read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / f"{take}.amc",
    )


def _cut(rec: PoseSequence, a_s: float, b_s: float) -> PoseSequence:
    return rec.slice_frames(int(round(a_s * CMU_FPS)), int(round(b_s * CMU_FPS)))


def _angle(seq: PoseSequence, a: str, b: str, c: str) -> np.ndarray:
    """The angle at joint ``b`` between ``a`` and ``c``, degrees, from the positions alone."""
    p = seq.to_canonical().positions
    at = p[:, JOINT_INDEX[b]]
    return np.degrees(angle_between(p[:, JOINT_INDEX[a]] - at, p[:, JOINT_INDEX[c]] - at))


# CMU 13_29's squats (labelled 31.7-38.3 s): knee troughs at 33.25 and 36.3 s by hand
# (tests/fixtures/repetition_counts.json), standing at 31.7, 34.6 and 37.5 s.
@pytest.mark.parametrize(
    ("a_s", "b_s", "count", "what"),
    [
        (31.7, 33.3, 0, "standing to the bottom of the first squat: only the way down"),
        (32.5, 33.25, 0, "the way down from half-way"),
        (31.7, 33.6, 1, "down and turned back up by 43 of 234 degrees: its far point passed"),
        (33.25, 35.0, 0, "the way up, then the next squat's way down begins"),
        (31.7, 34.8, 1, "one whole squat, standing to standing"),
        (31.7, 34.0, 1, "down and two thirds of the way up: a squat (the rest of it is missing)"),
        (31.7, 38.3, 2, "the labelled stretch: two squats"),
    ],
)
def test_a_squat_cut_short_counts_only_whole_repetitions(
    cmu_13_29: PoseSequence, a_s: float, b_s: float, count: int, what: str
) -> None:
    seq = _cut(cmu_13_29, a_s, b_s)
    knee = _angle(seq, "left_hip", "left_knee", "left_ankle")
    if count == 0 and a_s < 33.0:  # hand check: the knee is at its deepest at the end
        assert knee[-1] < knee.min() + 0.05 * (knee.max() - knee.min()), what
    result = count_repetitions(seq)
    assert result.count == count, what
    assert result.partial == (count == 0), what


# 13_29's arm circles: wrist-height peaks (arms up) at 12.2, 13.4 and 14.6 s by hand.
@pytest.mark.parametrize(
    ("a_s", "b_s"), [(12.8, 13.4), (13.0, 13.4), (13.4, 14.0)], ids=["up", "up-late", "down"]
)
def test_half_an_arm_circle_counts_none(cmu_13_29: PoseSequence, a_s: float, b_s: float) -> None:
    seq = _cut(cmu_13_29, a_s, b_s)
    wrist = seq.to_canonical().positions[:, JOINT_INDEX["left_wrist"], 1]  # height (y up)
    top = int(np.argmax(wrist))
    assert top in (0, seq.n_frames - 1) or min(top, seq.n_frames - top) < 0.1 * CMU_FPS
    result = count_repetitions(seq)
    assert result.count == 0 and result.partial


def test_a_whole_arm_circle_still_counts(cmu_13_29: PoseSequence) -> None:
    """The first circle of the stretch (arms up at 10.4 s, labelled from 10.1 s) cut from
    9.9 to 10.8 s: one whole circle."""
    assert count_repetitions(_cut(cmu_13_29, 9.9, 10.8)).count == 1


VICON = ("ui-prmd", "data", "Segmented Movements", "Vicon", "Positions")


@pytest.mark.parametrize(
    ("movement", "joints", "deepest"),
    [
        ("m01", ("left_hip", "left_knee", "left_ankle"), np.argmin),  # deep squat
        ("m07", ("right_elbow", "right_shoulder", "right_hip"), np.argmax),  # arm abduction
    ],
)
def test_uiprmd_single_repetitions_cut_at_their_far_point_count_none(
    shared_data: Path, movement: str, joints: tuple[str, str, str], deepest: object
) -> None:
    """UI-PRMD Vicon, subject s01's ten correct repetitions of the deep squat and of the
    shoulder abduction: each whole counts 1; cut at its far point (the knee's smallest angle,
    the arm's widest, read off the positions here), the way out alone counts 0, and so does
    the way back alone."""
    folder = shared_data.joinpath(*VICON)
    for e in range(1, 11):
        seq = read_uiprmd_vicon(folder / f"{movement}_s01_e{e:02d}_positions.txt.gz")
        far = int(deepest(_angle(seq, *joints)))  # type: ignore[operator]
        assert count_repetitions(seq).count == 1, e
        if min(far, seq.n_frames - far) < 0.5 * seq.fps:
            continue  # a far point near the file's end: one half is too short to count
        out, back = seq.slice_frames(0, far + 1), seq.slice_frames(far, seq.n_frames)
        assert count_repetitions(out).count == 0, (e, "out")
        assert count_repetitions(back).count == 0, (e, "back")


def test_segment_counts_no_repetition_in_half_a_squat(cmu_13_29: PoseSequence) -> None:
    """``segment``'s count of a recording that is one segment: the way down of a squat is
    none (before: 1); a whole squat is one."""
    for b_s, count in ((33.3, 0), (34.8, 1)):
        seq = _cut(cmu_13_29, 31.7, b_s).to_canonical()
        sig = movement_signals(seq)
        (reps,) = counted_segments(sig, [(0, seq.n_frames)], seq.n_frames)
        assert len(reps) == count, b_s


def test_reps_command_says_no_whole_repetition(
    cmu_13_29: PoseSequence, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Exit 0, "0 repetitions", and one note line on stderr naming the file; ``--json``
    has ``"partial": true`` (a count of 0 is an answer, not a refusal)."""
    path = save_pose(_cut(cmu_13_29, 31.7, 33.3), tmp_path / "half_squat.npz")
    assert main(["reps", str(path)]) == 0
    out, err = capsys.readouterr()
    assert out.splitlines()[0].startswith(f"{path}: 0 repetitions")
    (note,) = err.strip().splitlines()
    assert note.startswith(f"note: {path}: no whole repetition")
    assert main(["reps", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert doc["count"] == 0 and doc["partial"] is True and doc["repetitions"] == []
    assert len(err.strip().splitlines()) == 1
    whole = save_pose(_cut(cmu_13_29, 31.7, 34.8), tmp_path / "squat.npz")
    assert main(["reps", str(whole), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["partial"] is False and json.loads(out)["count"] == 1 and not err


# Standing still before exercising was labelled as the exercise whose labelled stretch ends
# standing: a case base of CMU 13_29's and 13_30's windows holds 13_30's jog, whose last
# second is standing, and 5 s of standing still came out "Jog 0.99".


def _still(seq: PoseSequence, frame: int, seconds: float, seed: int) -> np.ndarray:
    """``seconds`` of the posture at ``frame`` of ``seq``, each joint jittered by 3 mm (a
    person standing nearly still, as a mocap system sees one)."""
    n = int(round(seconds * seq.fps))
    rng = np.random.default_rng(seed)
    return np.repeat(seq.positions[frame : frame + 1], n, axis=0) + rng.normal(
        0.0, 0.003, (n, *seq.positions.shape[1:])
    )


@pytest.fixture(scope="module")
def cmu(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, PoseSequence]:
    """CMU 13_29, 13_30 and 13_31, read once in the run (the tests only read them)."""

    def read(_: Path) -> dict[str, PoseSequence]:
        return {t: _read_cmu(shared_data, t) for t in ("13_29", "13_30", "13_31")}

    return made_once(tmp_path_factory, "hunt33d-cmu", read)


def _windows_classifier(
    cmu: dict[str, PoseSequence], shared_data: Path, tmp_path: Path, extra: list[Any]
) -> Any:
    """The classifier ``train --split windows`` makes of 13_29's and 13_30's labelled
    stretches (and ``extra`` clips)."""
    from cbr.estimator import CaseBaseClassifier
    from features.datasets import Clip, split_by_track
    from features.label_tracks import LabelTrack
    from features.repetitions import split_windows

    names = tmp_path / "names.txt"
    names.write_text("1 JumpJack\n2 Jog\n3 Squat\n4 KneeRaise\n5 ArmCircle\n6 Twist\n"
                     "10 ToeTouchOneHand\n", encoding="utf-8")  # fmt: skip
    clips = list(extra)
    for t in ("13_29", "13_30"):
        track = LabelTrack(shared_data / "cmu-mocap6" / "truelabels" / f"{t}.txt", 0.1, names)
        for part, label in split_by_track(cmu[t], track):
            clips.append(Clip(part.with_metadata(label=label, subject="13"), label, "13", {}))
    windows = split_windows(clips).clips
    return CaseBaseClassifier(feature_weights="none").fit(
        [c.seq for c in windows], [c.label for c in windows]
    )


def test_standing_still_is_no_exercise_whose_cases_all_move(
    cmu: dict[str, PoseSequence], shared_data: Path, tmp_path: Path
) -> None:
    """5 s of 13_31's first posture held (3 mm of jitter), then 13_31's twists and knee
    raises (labelled 0-3.3 and 3.3-8.2 s there): the still stretch is unknown, told as
    still; the exercises after it keep their labels. Every Jog case moves its joint angles
    at least 0.034 pi rad (the mean standard deviation), the still stretch 0.004."""
    from cbr.segmentation import STILL_TEXT, segment

    clf = _windows_classifier(cmu, shared_data, tmp_path, [])
    rec = cmu["13_31"]
    still = _still(rec, 0, 5.0, 0)
    seq = PoseSequence(np.concatenate([still, rec.positions[: int(8.2 * 120)]]),
                       rec.joint_names, 120.0)  # fmt: skip
    result = segment(clf, seq)
    blocks = result.blocks
    assert all(b is None for b in blocks[:45]), blocks[:50]  # 0-4.5 s
    first = result.segments[0]
    assert first.label is None and first.explanation == STILL_TEXT
    assert first.end_frame <= int(5.6 * 120)
    assert blocks[int(6.5 / 0.1)] == "Twist" and blocks[int(11.0 / 0.1)] == "KneeRaise"


def test_standing_still_stays_an_activity_whose_cases_are_still(
    cmu: dict[str, PoseSequence], shared_data: Path, tmp_path: Path
) -> None:
    """With a stored activity that is itself still (6 s of 13_29's last posture held,
    labelled Stand), the still stretch is Stand: only the activities whose every case moves
    much more are ruled out."""
    from cbr.segmentation import segment
    from features.datasets import Clip

    src = cmu["13_29"]
    stand = PoseSequence(_still(src, src.n_frames - 1, 6.0, 1), src.joint_names, 120.0)
    extra = [Clip(stand.with_metadata(label="Stand", subject="13"), "Stand", "13", {})]
    clf = _windows_classifier(cmu, shared_data, tmp_path, extra)
    rec = cmu["13_31"]
    seq = PoseSequence(np.concatenate([_still(rec, 0, 5.0, 0), rec.positions[: int(8.2 * 120)]]),
                       rec.joint_names, 120.0)  # fmt: skip
    blocks = segment(clf, seq).blocks
    assert all(b == "Stand" for b in blocks[:45]), blocks[:50]


def test_watch_tells_standing_still_as_segment_does(
    cmu: dict[str, PoseSequence], shared_data: Path, tmp_path: Path
) -> None:
    """``watch`` (the live segmenter) on the same stream, read at 30 fps: the standing is
    unknown and told as still, as ``segment`` tells it, then the twists."""
    from cbr.live import LiveSegmenter
    from cbr.segmentation import STILL_TEXT

    clf = _windows_classifier(cmu, shared_data, tmp_path, [])
    rec = cmu["13_31"]
    seq = PoseSequence(np.concatenate([_still(rec, 0, 5.0, 0), rec.positions[: int(8.2 * 120)]]),
                       rec.joint_names, 120.0)  # fmt: skip
    frames = seq.to_canonical().positions[::4]
    live = LiveSegmenter(clf, 30.0)
    segments = []
    for f in frames:
        segments += live.push(f)
    segments += live.finish()
    first = segments[0]
    assert first.label is None and first.explanation == STILL_TEXT, segments
    assert 4.0 * 30 <= first.end_frame <= 5.6 * 30, segments
    assert "Twist" in [s.label for s in segments[1:]], segments


@pytest.mark.parametrize(("b_s", "count"), [(23.5, 0), (24.0, 0), (25.0, 1), (31.7, 6)])
def test_knee_raises_cut_before_the_first_comes_back(
    cmu_13_29: PoseSequence, b_s: float, count: int
) -> None:
    """13_29's knee raises (labelled from 22.5 s; by hand the right knee up at 24.1 s, the
    left at 25.4 s, six in all by 31.7 s) cut to end before the first knee is down again
    count none (before: 1 at 23.5 s, 2 at 24.0 s), and one once it is."""
    assert count_repetitions(_cut(cmu_13_29, 22.5, b_s)).count == count


@pytest.mark.parametrize(("a_s", "b_s"), [(3.9, 8.7), (22.5, 30.75)], ids=["twist", "knee"])
def test_segment_counts_a_recording_of_one_segment_as_reps_does(
    cmu_13_29: PoseSequence, a_s: float, b_s: float
) -> None:
    """``segment``'s count of a recording that is one segment is ``reps``' count of it: the
    segment is read to the recording's last analysis sample, as ``reps`` reads it. Before, it
    was read to the last whole one (frames // 4 at 120 fps) and lost a far point there:
    13_29's twists cut at 8.65 s, whose third turn (left, 8.6 s by hand) lies in the clip,
    counted 3 by ``reps`` and 2 by ``segment``; its knee raises cut at 30.75 s, as the sixth
    rises, 6 and 5. (Cut at 8.7 s now: at 8.65 s the turn lies in the clip's last 0.02 s, and
    since the running median reads only the clip's own frames there both count 2, 3 from
    8.7 s on; before, 3 at 8.65 and 8.7 s, 2 from 8.75 to 8.9 s, 3 again from 9.0 s.)"""
    seq = _cut(cmu_13_29, a_s, b_s).to_canonical()
    whole = count_repetitions(seq).count
    (reps,) = counted_segments(movement_signals(seq), [(0, seq.n_frames)], seq.n_frames)
    assert len(reps) == whole
    if a_s == 3.9:
        assert whole == 3  # twists at 5.1, 6.75 and 8.6 s by hand
