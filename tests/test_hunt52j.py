"""Landmarks the pose model places inside the frame but judges not in the picture (hunt 52j).

The bundled legs-cropped jumping-jack video cut to a 9:16 portrait (columns 438-842, its
first three frames): the thighs run off the bottom edge, the knees below it. BlazePose puts
the knees at the bottom edge (both inside the frame in the first two), at a presence of
0.1-0.3 (the model's own
probability that the landmark is in the picture): before, their positions were kept and
`describe` said "left leg lowered", "right leg in front" of knees nobody saw.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.once import made_once

VIDEO = "edge/jumping_jack_legs_cropped_pexels5034331.mp4"
COLUMNS = (438, 843)
FRAMES = 3
KNEES = ("left_knee", "right_knee")


def _portrait(shared_data: Path, dest: Path) -> Path:
    """The first FRAMES frames of VIDEO, columns COLUMNS, as an mp4 at its rate."""
    import cv2

    cap = cv2.VideoCapture(str(shared_data / "videos" / VIDEO))
    fps = cap.get(cv2.CAP_PROP_FPS)
    frames = [cap.read()[1][:, COLUMNS[0] : COLUMNS[1]] for _ in range(FRAMES)]
    cap.release()
    height, width = frames[0].shape[:2]
    out = cv2.VideoWriter(str(dest), cv2.VideoWriter_fourcc(*"mp4v"), fps, (width, height))
    for frame in frames:
        out.write(frame)
    out.release()
    return dest


@pytest.fixture(scope="module")
def portrait(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The portrait crop and its pose file as `posecbr extract` writes it (defaults)."""

    def make(root: Path) -> tuple[Path, Path]:
        from posecbr.cli import main

        video = _portrait(shared_data, root / "portrait.mp4")
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("POSECBR_NO_PROGRESS", "1")
            assert main(["extract", str(video), "--out", str(root / "portrait.npz")]) == 0
        return video, root / "portrait.npz"

    return made_once(tmp_path_factory, "hunt52j-portrait", make)


def test_knees_the_model_judges_not_in_the_picture_are_missing_and_no_leg_fluent_is_said(
    portrait: tuple[Path, Path],
) -> None:
    """The knees below the bottom edge: stored missing, as a landmark placed outside the
    frame is; the image landmarks keep the model's guess (on the edge) and its presence; no
    fluent of a leg is stated, the arms' are."""
    from features.fluents import evaluate
    from features.poses import load_pose, load_pose_arrays
    from features.skeleton import JOINT_INDEX

    _video, pose_file = portrait
    seq = load_pose(pose_file)
    image = load_pose_arrays(pose_file)["image_landmarks"]
    knees = [JOINT_INDEX[k] for k in KNEES]
    assert seq.n_frames == FRAMES
    # the model's guess: in the first two frames inside the 405 x 720 frame, its lower
    # tenth; in all three unlikely in the picture
    assert np.all((image[:2, knees, 1] > 650) & (image[:2, knees, 1] < 720))
    assert np.all((image[:2, knees, 0] >= 0) & (image[:2, knees, 0] < 405))
    assert np.all(image[:, knees, 4] < 0.5)
    assert np.isnan(seq.positions[:, knees]).all()
    hips = [JOINT_INDEX["left_hip"], JOINT_INDEX["right_hip"]]
    assert np.isfinite(seq.positions[:, hips]).all()  # in the picture: kept
    assert json.loads(json.dumps(seq.metadata))["n_joint_samples_not_present"] >= 4
    result = evaluate(seq, backend="numpy")  # three frames: no compiling
    conf = np.asarray(result.confidence)
    legs = [i for i, w in enumerate(result.words) if "knee" in w or " leg " in f" {w} "]
    arms = [i for i, w in enumerate(result.words) if w in ("left elbow bent", "right elbow bent")]
    assert legs and arms
    assert np.isnan(conf[:, legs]).all()
    assert np.isfinite(conf[:, arms]).all()


def test_an_older_pose_file_that_kept_them_is_said_and_extracted_again(
    portrait: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A pose file an older posecbr made of the same crop (version 3: the knees kept where
    the model judged them not in the picture): reading it says so once, on stderr, with the
    count; `extract` takes it as stale and makes it again without them."""
    from dataclasses import replace

    from features.datasets import load_clip
    from features.poses import load_pose, load_pose_arrays, save_pose
    from features.skeleton import JOINT_INDEX
    from posecbr.cli import main

    video, pose_file = portrait
    seq = load_pose(pose_file)
    arrays = load_pose_arrays(pose_file)
    positions = seq.positions.copy()
    for knee, hip in (("left_knee", "left_hip"), ("right_knee", "right_hip")):
        positions[:, JOINT_INDEX[knee]] = positions[:, JOINT_INDEX[hip]] - [0.0, 0.4, 0.0]
    older = tmp_path / "portrait.npz"
    meta = {**seq.metadata, "extraction_version": 3}
    save_pose(replace(seq, positions=positions, metadata=meta), older, extra_arrays=arrays)
    capsys.readouterr()
    load_clip(older)
    err = capsys.readouterr().err
    assert f"kept {2 * FRAMES} joint positions the pose model judged not in the picture" in err
    load_clip(pose_file)  # today's: nothing said
    assert capsys.readouterr().err == ""
    assert main(["extract", str(video), "--out", str(older)]) == 0
    out = capsys.readouterr().out
    assert "which kept joints the model judged not in the picture: extracted again" in out
    again = load_pose(older)
    assert again.metadata["extraction_version"] == 4
    assert np.isnan(again.positions[:, [JOINT_INDEX[k] for k in KNEES]]).all()
