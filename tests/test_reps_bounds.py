"""Where a lone repetition starts and ends: where the movement leaves and returns to rest, not
anywhere in a flat, noisy rest before or after it (features.repetitions._bounds)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from features.datasets import Clip
from features.poses import PoseSequence, save_pose
from features.readers.uiprmd import read_uiprmd_kinect
from features.repetitions import _bounds, count_repetitions, split_repetitions
from features.skeleton import JOINT_INDEX
from posecbr.cli import main
from tests.bodies import rot_z, rotate, standing, to_sequence

FPS = 30.0
ARM = ("elbow", "wrist", "pinky", "index", "thumb")
REST = 60  # 2 s of standing before and after the repetition
RISE = 37  # 1.2 s: up and back down


def _bump(n: int) -> np.ndarray:
    """One excursion out and back over ``n`` samples: 0 -> 1 -> 0 (sin squared)."""
    return np.sin(np.pi * np.arange(n) / (n - 1)) ** 2


def _leaves(n: int, share: float = 0.1) -> float:
    """Samples from the start of a sin-squared excursion of ``n`` samples to where it first
    stands ``share`` of its height above rest: sin^2(pi t / (n - 1)) = share."""
    return (n - 1) * float(np.arcsin(np.sqrt(share))) / np.pi


def test_a_lone_excursion_on_a_noisy_line_starts_and_ends_where_it_leaves_rest() -> None:
    """A movement line: 90 samples of noisy rest (sd 1 % of the excursion), one sin-squared
    excursion of 37 samples, 90 of rest again; no period, so the rest is sought over the
    whole line. Its lowest point lies somewhere in either rest."""
    rng = np.random.default_rng(3)
    rest, n = 90, RISE
    line = np.concatenate([np.zeros(rest), _bump(n), np.zeros(rest)])
    line = line + rng.normal(0.0, 0.01, len(line))
    peak = rest + (n - 1) // 2
    [(start, end)] = _bounds(line, np.array([peak]), len(line))
    # leaves a tenth of its height at 36 * asin(sqrt(0.1)) / pi = 3.7 samples in, returns
    # there 3.7 samples before its end (end exclusive); the rest's noise moves it a sample
    assert start == pytest.approx(rest + _leaves(n), abs=1.5)
    assert end - 1 == pytest.approx(rest + n - 1 - _leaves(n), abs=1.5)
    # none of the 90 samples of rest before or after
    assert rest <= start <= peak < end <= rest + n


def _lone_arm_raise(seed: int = 0) -> PoseSequence:
    """Both arms raised sideways by 90 degrees and lowered once over ``RISE`` frames, with
    ``REST`` frames of standing before and after; every joint jitters by 5 mm (sd) in every
    frame, as a tracker does on a person standing still."""
    rng = np.random.default_rng(seed)
    angle = np.concatenate([np.zeros(REST), 90.0 * _bump(RISE), np.zeros(REST)])
    body = standing()
    frames = []
    for a in angle:
        raised = rotate(body, tuple(f"left_{j}" for j in ARM), rot_z(-a), body["left_shoulder"])
        raised = rotate(raised, tuple(f"right_{j}" for j in ARM), rot_z(a), body["right_shoulder"])
        frames.append({k: v + rng.normal(0.0, 0.005, 3) for k, v in raised.items()})
    return to_sequence(*frames, fps=FPS)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_lone_arm_raise_between_two_rests(seed: int) -> None:
    """The repetition of a lone arm raise holds the raise, not the 2 s of standing before and
    after it: it starts within 0.1 s of where the arms have risen a tenth of the way (3.7
    frames into the raise, :func:`_leaves`) and ends as far from where they are back down."""
    seq = _lone_arm_raise(seed)
    [rep] = count_repetitions(seq).repetitions
    tolerance = 0.1 * FPS
    assert rep.start_frame == pytest.approx(REST + _leaves(RISE), abs=tolerance)
    assert rep.end_frame - 1 == pytest.approx(REST + RISE - 1 - _leaves(RISE), abs=tolerance)
    # the arms are highest at the raise's middle frame
    assert rep.peak_frame == pytest.approx(REST + (RISE - 1) / 2, abs=2)


def test_reps_json_of_a_lone_repetition_leaves_out_the_rests(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``posecbr reps CLIP --json`` on the lone arm raise: the repetition starts and ends
    within the raise (2.0 s to 3.23 s), not seconds before or after it."""
    path = save_pose(_lone_arm_raise(), tmp_path / "raise.npz")
    assert main(["reps", str(path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["count"] == 1
    [rep] = doc["repetitions"]
    assert REST / FPS - 0.1 <= rep["start_s"] <= (REST + 0.25 * RISE) / FPS
    assert (REST + 0.75 * RISE) / FPS <= rep["end_s"] <= (REST + RISE) / FPS + 0.1


def test_split_repetitions_cuts_the_movement_out_of_the_rests() -> None:
    """``train --split repetitions`` makes a case of the movement: the case of the lone arm
    raise lasts about as long as the raise (1.2 s), not the 5.2-s clip."""
    clip = Clip(seq=_lone_arm_raise(), label="raise", subject="synthetic")
    split = split_repetitions([clip])
    [case] = split.clips
    assert split.kept_whole == 0
    assert RISE / FPS - 0.4 <= case.seq.duration_s <= RISE / FPS + 0.2


# ---- real data: UI-PRMD shoulder abduction (m07), one repetition per file ------------------

UIPRMD = Path("ui-prmd") / "data" / "Segmented Movements"
ABDUCTION_CLIPS = [
    *(f"m07_s02_e{e:02d}" for e in (2, 3, 4, 6, 7, 8, 9, 10)),
    "m07_s03_e04",
    "m07_s03_e09",
    "m07_s07_e02",
]
"""The Kinect clips of subjects s02, s03 and s07 with at least a quarter of a second of
standing before and after the abduction (the arm within :data:`SWAY_DEG` of where it hung):
the others of s02 and s03 keep less at one end, as UI-PRMD's Vicon clips keep 0.15-0.2 s,
too little to tell a start in the rest from one where the arm leaves it."""
SWAY_DEG = 5.0
"""An arm hanging at rest sways and jitters by a few degrees; raised by more than this from
where it hung at the clip's first (or last) frame, it is moving."""


def _arm_elevation_deg(seq: PoseSequence) -> np.ndarray:
    """The higher arm's angle from the trunk's side (shoulder to elbow against shoulder to
    hip), degrees ``(frames,)``: read off the positions, not from the counted angles."""
    p = seq.to_canonical().positions
    out = []
    for side in ("left", "right"):
        shoulder = p[:, JOINT_INDEX[f"{side}_shoulder"]]
        arm = p[:, JOINT_INDEX[f"{side}_elbow"]] - shoulder
        down = p[:, JOINT_INDEX[f"{side}_hip"]] - shoulder
        cos = np.einsum("ij,ij->i", arm, down) / np.linalg.norm(arm, axis=1)
        out.append(np.degrees(np.arccos(np.clip(cos / np.linalg.norm(down, axis=1), -1, 1))))
    return np.asarray(np.max(out, axis=0))


@pytest.mark.parametrize("name", ABDUCTION_CLIPS)
def test_a_real_abduction_starts_and_ends_where_the_arm_leaves_and_returns_to_rest(
    shared_data: Path, name: str
) -> None:
    """One shoulder abduction per file, with 0.25-0.45 s of standing, arm down, before and
    after: the arm's elevation read off the positions stays within :data:`SWAY_DEG` of its
    first (last) frame's until it leaves (after it returns to) rest. The repetition starts
    no earlier than 0.1 s before the arm leaves that rest and ends no later than 0.1 s after
    it is back: the standing is left out; and it holds the abduction itself."""
    seq = read_uiprmd_kinect(
        shared_data / UIPRMD / "Kinect" / "Positions" / f"{name}_positions.txt.gz"
    )
    elevation = _arm_elevation_deg(seq)
    left = int(np.argmax(np.abs(elevation - elevation[0]) > SWAY_DEG))
    back = len(elevation) - 1 - int(np.argmax(np.abs(elevation - elevation[-1])[::-1] > SWAY_DEG))
    assert min(left, seq.n_frames - 1 - back) >= 0.25 * seq.fps  # standing to leave out
    [rep] = count_repetitions(seq).repetitions
    tolerance = 0.1 * seq.fps
    # the standing before and after is left out
    assert rep.start_frame >= left - tolerance
    assert rep.end_frame - 1 <= back + tolerance
    # and the abduction kept: every frame with the arm raised a quarter of the way or more
    raised = np.flatnonzero(elevation - elevation[[0, -1]].max() >= 0.25 * np.ptp(elevation))
    assert rep.start_frame <= raised[0] and raised[-1] < rep.end_frame
