"""A PoseSequence owns what it holds: the caller's arrays can change afterwards without
changing the sequence or what was worked out from it (the caches key on the sequence), and
its constructor and slicing refuse, in one error, what they cannot hold."""

from __future__ import annotations

import numpy as np
import pytest

from features.errors import ConfigError, PoseFileError
from features.poses import PoseSequence, load_pose, save_pose
from features.repetitions import count_repetitions
from features.skeleton import BLAZEPOSE_33

J = BLAZEPOSE_33.index


def _squats(n_reps: int, fps: float = 30.0) -> np.ndarray:
    """Hips dropping and rising ``n_reps`` times (1 s each) on a standing figure: every knee
    bends with the hip height, so a repetition counter sees ``n_reps`` repetitions."""
    t = np.arange(int(n_reps * fps)) / fps
    drop = 0.25 * (1 - np.cos(2 * np.pi * t)) / 2  # 0 .. 0.25 m
    pos = np.full((t.size, 33, 3), np.nan)
    for side, x in (("left", 0.1), ("right", -0.1)):
        pos[:, J(f"{side}_shoulder")] = np.stack([np.full_like(t, x), 1.4 - drop, 0 * t], 1)
        pos[:, J(f"{side}_hip")] = np.stack([np.full_like(t, x), 0.95 - drop, 0 * t], 1)
        # knee forward as the hip drops: thigh and shin of 0.45 m
        fwd = np.sqrt(np.clip(0.45**2 - ((0.95 - drop - 0.05) / 2) ** 2, 0, None))
        pos[:, J(f"{side}_knee")] = np.stack([np.full_like(t, x), (0.95 - drop + 0.05) / 2, fwd], 1)
        pos[:, J(f"{side}_ankle")] = np.stack([np.full_like(t, x), 0.05 + 0 * t, 0 * t], 1)
        pos[:, J(f"{side}_elbow")] = np.stack([np.full_like(t, x * 2), 1.15 - drop, 0 * t], 1)
        pos[:, J(f"{side}_wrist")] = np.stack([np.full_like(t, x * 2), 0.9 - drop, 0 * t], 1)
    return pos


def test_changing_the_callers_array_changes_neither_the_sequence_nor_its_count() -> None:
    buf = _squats(4)
    seq = PoseSequence(buf, BLAZEPOSE_33, 30.0)
    before = count_repetitions(seq).count
    buf[:] = buf[0]  # the caller reuses its buffer: now a figure standing still
    assert np.array_equal(seq.positions, _squats(4), equal_nan=True)
    assert count_repetitions(seq).count == before
    assert count_repetitions(PoseSequence(buf, BLAZEPOSE_33, 30.0)).count == 0


def test_positions_cannot_be_written_through_the_sequence_and_slices_share_its_memory() -> None:
    seq = PoseSequence(_squats(2), BLAZEPOSE_33, 30.0)
    with pytest.raises(ValueError):
        seq.positions[0, 0, 0] = 1.0
    part = seq.slice_frames(10, 20)
    assert np.shares_memory(part.positions, seq.positions)  # a slice is not copied
    view = _squats(2)[::2]  # a view of memory the caller still holds: copied
    assert not np.shares_memory(PoseSequence(view, BLAZEPOSE_33, 15.0).positions, view)


def test_slice_frames_takes_numpy_whole_numbers_and_refuses_fractions() -> None:
    seq = PoseSequence(_squats(2), BLAZEPOSE_33, 30.0)
    part = seq.slice_frames(np.int64(5), np.int32(20))
    assert part.n_frames == 15 and part.metadata["frame_offset"] == 5
    assert seq.slice_frames(-10, None).metadata["frame_offset"] == 50  # 60 frames, last 10
    with pytest.raises(ConfigError, match="whole number"):
        seq.slice_frames(2.0, 10)  # type: ignore[arg-type]


def test_numpy_numbers_in_metadata_are_stored_and_read_back(tmp_path) -> None:
    seq = PoseSequence(_squats(1), BLAZEPOSE_33, 30.0, metadata={"subject": np.int64(3)})
    back = load_pose(save_pose(seq.with_metadata(weight=np.float32(0.5)), tmp_path / "a.npz"))
    assert back.metadata["subject"] == 3 and back.metadata["weight"] == 0.5


def test_saving_onto_a_folder_is_refused_and_writes_nothing(tmp_path) -> None:
    (tmp_path / "clips").mkdir()
    with pytest.raises(PoseFileError, match="is a folder"):
        save_pose(PoseSequence(_squats(1), BLAZEPOSE_33, 30.0), tmp_path / "clips")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clips"]
    assert list((tmp_path / "clips").iterdir()) == []


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"metadata": None}, "metadata must be a mapping"),
        ({"metadata": [1, 2]}, "metadata must be a mapping"),
        ({"joint_names": "nose"}, "one string"),
        ({"joint_names": (1, 2, 3, 4)}, "must be text"),
    ],
)
def test_constructor_refuses_what_it_cannot_hold(kwargs: dict, message: str) -> None:
    args = {"positions": np.zeros((5, 4, 3)), "joint_names": BLAZEPOSE_33[:4], "fps": 30.0}
    with pytest.raises(PoseFileError, match=message):
        PoseSequence(**{**args, **kwargs})


def test_byte_joint_names_are_the_names_they_spell() -> None:
    names = [n.encode() for n in BLAZEPOSE_33[:4]]
    seq = PoseSequence(np.ones((5, 4, 3)), names, 30.0)
    assert seq.joint_names == BLAZEPOSE_33[:4]
    assert not np.isnan(seq.to_canonical().positions[:, :4]).any()


def test_absent_joints_have_unknown_confidence_on_the_canonical_skeleton() -> None:
    names = ("left_hip", "nose")
    seq = PoseSequence(np.ones((3, 2, 3)), names, 30.0, confidence=np.full((3, 2), 0.5))
    conf = seq.to_canonical().confidence
    assert conf is not None
    assert np.all(conf[:, J("left_hip")] == 0.5) and np.all(conf[:, J("nose")] == 0.5)
    others = [i for i in range(33) if BLAZEPOSE_33[i] not in names]
    assert np.isnan(conf[:, others]).all()
