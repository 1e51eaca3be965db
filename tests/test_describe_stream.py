"""Long clips are described a piece at a time: the pieces give the confidences, runs and
per-frame states of the whole clip (issue 15: a pose file of a million frames took 7.5 GB)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_clip
from features.fluents import evaluate, evaluate_chunks
from features.poses import PoseSequence
from features.readers.asfamc import read_asf_amc
from features.readers.uiprmd import read_uiprmd_vicon
from features.timeline import Run, describe_clip
from tests.bodies import standing, to_sequence

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def _pieces(seq: PoseSequence, chunk: int, margin: int = 0) -> np.ndarray:
    out = [r.confidence[s - first : t - first] for s, t, first, r in
           evaluate_chunks(seq, chunk_frames=chunk, margin=margin)]  # fmt: skip
    return np.concatenate(out)


def _assert_same(whole: np.ndarray, pieces: np.ndarray) -> None:
    assert whole.shape == pieces.shape
    np.testing.assert_array_equal(np.isnan(whole), np.isnan(pieces))
    np.testing.assert_allclose(pieces, whole, rtol=0, atol=1e-12, equal_nan=True)


@pytest.mark.parametrize("chunk", [1, 7, 30])
def test_pieces_give_the_confidences_of_the_whole_clip_at_30_fps(chunk: int) -> None:
    seq = load_clip(DEMO / "m01_s02_e01.npz")  # a real Kinect deep squat, 30 fps
    _assert_same(evaluate(seq).confidence, _pieces(seq, chunk, margin=3))


def test_pieces_at_120_and_100_fps(shared_data: Path) -> None:
    """Other rates read their temporal history over fps/30 frames (4 at 120 fps, 3.33 at 100
    fps, interpolated): each piece must bring that much history with it."""
    hdm = shared_data / "hdm05" / "train" / "1"
    amc = sorted(hdm.glob("*.amc"))[0]
    asf = next(hdm.glob(f"HDM_{amc.name.split('_')[1]}.asf"))
    vicon = shared_data / "ui-prmd" / "data" / "Segmented Movements" / "Vicon" / "Positions"
    for seq in (read_asf_amc(asf, amc), read_uiprmd_vicon(vicon / "m01_s01_e01_positions.txt.gz")):
        _assert_same(evaluate(seq).confidence, _pieces(seq, 50))


def _knee_bent_between(first: int, last: int, frames: int) -> PoseSequence:
    """Standing, the left knee bent to 90 degrees (shank straight back) in frames
    ``first``..``last``: "left knee bent" holds exactly there (90 deg is far below the
    threshold of 142.5 +- 7.5 deg, a straight knee far above)."""
    out = []
    for k in range(frames):
        body = standing()
        if first <= k <= last:
            body["left_ankle"] = body["left_knee"] + np.array([0.0, 0.0, -0.45])
            body["left_heel"] = body["left_ankle"] + np.array([0.0, -0.05, -0.05])
            body["left_foot_index"] = body["left_ankle"] + np.array([0.0, -0.15, 0.0])
        out.append(body)
    return to_sequence(*out)


def _spans(runs: list[Run], state: str) -> list[tuple[int, int]]:
    return [(r.start, r.end) for r in runs if any(s.name == state for s in r.states)]


@pytest.mark.parametrize("chunk", [5, 16, 100])
def test_a_run_across_pieces_is_one_run(chunk: int) -> None:
    seq = _knee_bent_between(10, 29, 45)
    tl = describe_clip(seq, chunk_frames=chunk)
    assert _spans(tl.runs, "left_leg_bent.bent") == [(10, 29)]
    assert _spans(tl.runs, "left_leg_bent.straight") == [(0, 9), (30, 44)]
    bent = next(s for r in tl.runs for s in r.states if s.name == "left_leg_bent.bent")
    assert bent.confidence == pytest.approx(1.0)
    assert _spans(tl.runs, "right_leg_bent.straight") == [(0, 44)]


@pytest.mark.parametrize(("chunk", "min_run"), [(7, 5), (13, 1), (20, 9)])
def test_describe_in_pieces_equals_describe_at_once(chunk: int, min_run: int) -> None:
    seq = load_clip(DEMO / "m05_s01_e02_inc.npz")  # a real sit-to-stand
    whole = describe_clip(evaluate(seq), min_run=min_run)
    pieces = describe_clip(seq, min_run=min_run, chunk_frames=chunk)

    def plain(runs: list[Run]) -> list[tuple[int, int, list[tuple[str, float]]]]:
        return [(r.start, r.end, [(s.name, round(s.confidence, 9)) for s in r.states])
                for r in runs]  # fmt: skip

    assert plain(pieces.runs) == plain(whole.runs)
    assert pieces.unavailable() == whole.unavailable()
    np.testing.assert_allclose(pieces.share, whole.share)
    np.testing.assert_allclose(pieces.columns, whole.columns, atol=1e-12)
    frames_whole: list[Run] = []
    frames_pieces: list[Run] = []
    describe_clip(evaluate(seq), per_frame=frames_whole.append)
    describe_clip(seq, per_frame=frames_pieces.append, chunk_frames=chunk)
    assert plain(frames_pieces) == plain(frames_whole)
    assert [r.start for r in frames_pieces] == list(range(seq.n_frames))


def test_picture_columns_average_a_long_clip() -> None:
    """Over PLOT_COLUMNS frames, each picture column is the mean of its stretch of frames:
    a knee bent in the first half of 4000 frames is column-wise 1 then 0 for "bent"."""
    seq = _knee_bent_between(0, 1999, 4000)
    tl = describe_clip(seq, chunk_frames=1500)
    col = tl.layout.state_names.index("left_leg_bent.bent")
    assert tl.columns.shape[0] == 2000
    np.testing.assert_allclose(tl.columns[:1000, col], 1.0, atol=1e-9)
    np.testing.assert_allclose(tl.columns[1000:, col], 0.0, atol=1e-9)
    assert tl.share[col] == pytest.approx(0.5)
    assert math.isclose(tl.n_frames / tl.fps, 4000 / 30)
