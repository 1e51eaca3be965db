"""A long clip's problem computed a piece at a time (cbr.long_clip) equals the whole-clip one.

Real data: UI-PRMD Kinect repetitions from the bundled demo set, ten movements one after
the other (so the pieces differ), with joints missing over stretches that cross piece
boundaries, at the very start and end, and one joint missing throughout.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import cbr.problem as cbr_problem
import features.body as features_body
from cbr import long_clip
from cbr.long_clip import SampledColumns, chunk_for
from cbr.problem import (
    FeatureConfig,
    availability,
    candidate_config,
    extract_problem,
    fill_nan_time,
    mirror_problem,
)
from features.body import mirrored, moves_left_more
from features.derived import fluents_of
from features.poses import PoseSequence, load_pose

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
CHUNK = 97  # frames: the clip spans over ten pieces, none aligned with a gap


def _long_clip() -> PoseSequence:
    parts = [load_pose(DEMO / f"m{m:02d}_s01_e{e:02d}.npz") for m in range(1, 11) for e in (1, 2)]
    pos = np.concatenate([p.positions for p in parts])
    names = parts[0].joint_names
    j = {n: i for i, n in enumerate(names)}
    pos[150:420, j["left_wrist"]] = np.nan  # across several piece boundaries
    pos[:40, j["right_knee"]] = np.nan  # from the first frame
    pos[-25:, j["left_ankle"]] = np.nan  # to the last frame
    pos[:, j["right_ankle"]] = np.nan  # never seen: its angles and positions are the fill
    pos[300:305] = np.nan  # a few frames with no person at all
    return PoseSequence(pos, names, parts[0].fps, source="ten movements")


def _copy(seq: PoseSequence) -> PoseSequence:
    """An equal clip as a new object (nothing cached for it)."""
    return dataclasses.replace(seq, positions=seq.positions.copy())


CONFIGS = {
    "summary with phases, angles, positions": FeatureConfig(
        states="all", angles=True, positions=True, summary=True, phases=3
    ),
    "sequence of 64 frames": FeatureConfig(states="angles", length=64, angles=True),
    "canonical side, left clip": FeatureConfig(
        states="instantaneous", angles=True, positions=True, summary=True, side="canonical"
    ),
}


@pytest.mark.parametrize("name", list(CONFIGS))
def test_pieces_equal_whole_clip(name: str) -> None:
    seq = _long_clip()
    if "left" in name and not moves_left_more(seq):  # the clip or its mirror image
        seq = mirrored(seq)
    config = candidate_config(CONFIGS[name])
    whole = extract_problem(_copy(seq), config, chunk_frames=0)
    pieces = extract_problem(_copy(seq), config, chunk_frames=CHUNK)
    assert seq.n_frames > 8 * CHUNK
    assert pieces.names == whole.names and pieces.words == whole.words
    assert pieces.mirrored == whole.mirrored == ("left" in name)
    assert np.array_equal(np.isnan(pieces.values), np.isnan(whole.values))
    np.testing.assert_allclose(pieces.values, whole.values, rtol=0, atol=1e-12)


QMP_CONFIGS = {
    "qmp values": FeatureConfig(level="qmp", qmp_part="values"),
    "qmp binary, canonical side, left clip": FeatureConfig(level="qmp", side="canonical"),
}


@pytest.mark.parametrize("name", list(QMP_CONFIGS))
def test_qmp_in_pieces_equals_whole_clip(name: str) -> None:
    # the QMP fit is one SINDy fit over every frame: in pieces its normal equations are sums
    # over the pieces, so the fitted parameters agree to rounding (a few ulp of the Gram
    # matrix, times its condition number), the criteria exactly
    seq = _long_clip()
    if "left" in name and not moves_left_more(seq):
        seq = mirrored(seq)
    whole = extract_problem(_copy(seq), QMP_CONFIGS[name], chunk_frames=0)
    pieces = extract_problem(_copy(seq), QMP_CONFIGS[name], chunk_frames=CHUNK)
    assert pieces.names == whole.names and pieces.words == whole.words
    assert pieces.mirrored == whole.mirrored == ("left" in name)
    binary = [i for i, n in enumerate(whole.names) if "." not in n]
    assert np.array_equal(pieces.values[binary], whole.values[binary])
    assert 0 < whole.values[binary].sum() < len(binary)  # some criteria met, some not
    np.testing.assert_allclose(pieces.values, whole.values, rtol=1e-9, atol=1e-12)


def test_available_columns_in_pieces_equal_whole_clip() -> None:
    seq = _long_clip()
    config = candidate_config(CONFIGS["summary with phases, angles, positions"])
    whole = availability(_copy(seq), config, chunk_frames=0)
    pieces = availability(_copy(seq), config, chunk_frames=CHUNK)
    np.testing.assert_array_equal(pieces, whole)
    states = list(config.states)
    # the right ankle is never seen: its knee angle and positions are not there; the left
    # ankle (missing at the end only) is
    assert not pieces[states.index("angle:right_knee")]
    assert not pieces[states.index("pos:right_ankle.height")]
    assert pieces[states.index("pos:left_ankle.height")] and pieces[states.index("angle:left_knee")]


@pytest.mark.parametrize("config", [CONFIGS["sequence of 64 frames"], QMP_CONFIGS["qmp values"]])
def test_mirror_image_problem_in_pieces_equals_whole_mirror_image(config: FeatureConfig) -> None:
    seq = _long_clip()
    whole = extract_problem(mirrored(_copy(seq)), candidate_config(config), chunk_frames=0)
    pieces = mirror_problem(_copy(seq), candidate_config(config), chunk_frames=CHUNK)
    assert pieces.names == whole.names
    np.testing.assert_allclose(pieces.values, whole.values, rtol=1e-9, atol=1e-12)


def _labelled_long_clips() -> tuple[list[PoseSequence], list[str]]:
    """Two subjects' deep squats and hurdle steps, each subject's six repetitions of a
    movement (three done well, three not) joined into one clip."""
    seqs, labels = [], []
    for movement, label in (("m01", "deep_squat"), ("m02", "hurdle_step")):
        for subject in ("s01", "s02"):
            parts = [load_pose(DEMO / f"{movement}_{subject}_e{e:02d}{inc}.npz")
                     for e in (1, 2, 3) for inc in ("", "_inc")]  # fmt: skip
            pos = np.concatenate([p.positions for p in parts])
            seqs.append(PoseSequence(pos, parts[0].joint_names, parts[0].fps,
                                     source=f"{movement} {subject}",
                                     metadata={"subject": subject}))  # fmt: skip
            labels.append(label)
    return seqs, labels


def test_training_on_long_clips_goes_in_pieces_and_equals_whole_clips(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Clips longer than CHUNK_FRAMES (made 53 here) are described a piece at a time: no
    fluents or state signals of a whole clip are computed, and the case base (mirror images
    and favoured sides included) is the one the whole clips give."""
    from cbr.estimator import CaseBaseClassifier

    seqs, labels = _labelled_long_clips()
    assert min(s.n_frames for s in seqs) > 6 * 53

    def fit() -> CaseBaseClassifier:
        clf = CaseBaseClassifier(mirror="canonical", feature_weights="none", phases=3)
        return clf.fit([_copy(s) for s in seqs], labels)

    whole = fit()
    monkeypatch.setattr(long_clip, "CHUNK_FRAMES", 53)

    def refuse(seq: PoseSequence) -> None:
        raise AssertionError(f"computed over a whole clip of {seq.n_frames} frames")

    for module in (cbr_problem, features_body):
        for name in ("fluents_of", "signals_of"):
            if hasattr(module, name):
                monkeypatch.setattr(module, name, refuse)
    pieces = fit()
    assert pieces.feature_config_ == whole.feature_config_
    assert pieces.feature_config_.side == "canonical"
    assert list(pieces.case_base_.labels) == list(whole.case_base_.labels)
    np.testing.assert_allclose(
        pieces.case_base_.problems, whole.case_base_.problems, rtol=0, atol=1e-12
    )


def test_never_seen_joint_reads_its_fill_in_pieces() -> None:
    config = candidate_config(CONFIGS["summary with phases, angles, positions"])
    p = extract_problem(_long_clip(), config, chunk_frames=CHUNK)
    cols = [i for i, n in enumerate(p.names) if n.startswith("pos:right_ankle.")]
    assert len(cols) == 3 * 7  # three axes, four statistics and three phases
    assert np.all(p.values[cols] == 0.0)
    seen = [i for i, n in enumerate(p.names) if n.startswith("pos:left_ankle.")]
    assert np.all(np.isfinite(p.values[seen])) and np.any(p.values[seen] != 0.0)


def test_long_clip_goes_in_pieces_unless_its_fluents_are_known() -> None:
    seq = _long_clip()
    assert chunk_for(seq, None) == 0  # shorter than CHUNK_FRAMES
    assert chunk_for(seq, 50) == 50
    long = dataclasses.replace(seq, positions=np.tile(seq.positions, (30, 1, 1)))
    assert chunk_for(long, None) > 0
    fluents_of(long)
    assert chunk_for(long, None) == 0  # computed already: the cached fluents are used


def test_sampled_columns_by_hand() -> None:
    # column 0: defined at frames 1 (1.0) and 4 (4.0): frames 2, 3 lie on the line between,
    # frame 0 holds the first value and frame 5 the last; column 1 is never defined (fill 7)
    x = np.array([[np.nan, np.nan], [1.0, np.nan], [np.nan, np.nan],
                  [np.nan, np.nan], [4.0, np.nan], [np.nan, np.nan]])  # fmt: skip
    s = SampledColumns(np.array([0, 2, 3, 5]), np.array([0.0, 7.0]))
    s.feed(0, x[:3])  # frame 2's next defined frame comes in the second piece
    s.feed(3, x[3:])
    np.testing.assert_allclose(s.values(), [[1.0, 7.0], [2.0, 7.0], [3.0, 7.0], [4.0, 7.0]])


def test_sampled_columns_match_interpolation_on_random_gaps() -> None:
    rng = np.random.default_rng(5)
    x = rng.normal(size=(500, 6))
    x[rng.random(x.shape) < 0.6] = np.nan
    x[:, 2] = np.nan
    x[:120, 3] = np.nan
    x[380:, 4] = np.nan
    at = np.unique(rng.integers(0, 500, 40))
    fills = np.arange(6.0)
    s = SampledColumns(at, fills)
    for start in range(0, 500, 33):
        s.feed(start, x[start : start + 33])
    np.testing.assert_allclose(s.values(), fill_nan_time(x, fills)[at], rtol=0, atol=1e-12)
