"""Hunt 33g: a review of the still-window rule, the last segment's repetitions, watch's
pacing and the stale-matrix sweep.

The still rule called a window unknown when it moved less than half as much as the case
base's least-moving case. A case base whose activities are themselves still (postures held)
has a least-moving case that moves only by its sensor's jitter: a person holding one of its
postures with less jitter (a steadier camera, a frozen frame) was "unknown: still", though
the case base holds exactly that posture."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.poses import PoseSequence
from features.readers.asfamc import read_asf_amc

CMU_FPS = 120.0


def _held(seq: PoseSequence, frame: int, seconds: float, seed: int, jitter_m: float) -> np.ndarray:
    """``seconds`` of the posture at ``frame`` of ``seq``, each joint jittered by ``jitter_m``
    metres (a person holding it, as a sensor sees one)."""
    n = int(round(seconds * seq.fps))
    rng = np.random.default_rng(seed)
    return np.repeat(seq.positions[frame : frame + 1], n, axis=0) + rng.normal(
        0.0, jitter_m, (n, *seq.positions.shape[1:])
    )


# on one xdist worker: the module's held_postures made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt33g")


@pytest.fixture(scope="module")
def held_postures(shared_data: Path) -> tuple[PoseSequence, object]:
    """CMU 13_29 and a classifier of ``train --split windows`` over three of its postures
    held 6 s each with 3 mm of jitter (Stand: its last frame; Bend: frame 2000; Reach:
    frame 3000): every case of it is still."""
    from cbr.estimator import CaseBaseClassifier
    from features.datasets import Clip
    from features.repetitions import split_windows

    src = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_29.amc",
    )
    clips = []
    for seed, (label, frame) in enumerate(
        (("Stand", src.n_frames - 1), ("Bend", 2000), ("Reach", 3000)), start=1
    ):
        seq = PoseSequence(_held(src, frame, 6.0, seed, 0.003), src.joint_names, CMU_FPS)
        clips.append(Clip(seq.with_metadata(label=label, subject="13"), label, "13", {}))
    windows = split_windows(clips).clips
    clf = CaseBaseClassifier(feature_weights="none").fit(
        [c.seq for c in windows], [c.label for c in windows]
    )
    return src, clf


@pytest.mark.parametrize("jitter_m", [0.001, 0.0])
def test_a_posture_held_is_its_activity_when_every_case_is_still(
    held_postures: tuple[PoseSequence, object], jitter_m: float
) -> None:
    """8 s of the Stand posture held with 1 mm of jitter (a third of the cases', so its
    joint angles vary about a third as much) or none at all: Stand from start to end, as
    ``segment`` and as ``watch`` (the live segmenter, every 4th frame: 30 fps). Before, both
    said unknown, "still: its joint angles vary less than half as much as in the
    least-moving case of the case base", every case of which is a posture held."""
    from cbr.live import LiveSegmenter
    from cbr.segmentation import segment

    src, clf = held_postures
    seq = PoseSequence(_held(src, src.n_frames - 1, 8.0, 5, jitter_m), src.joint_names, CMU_FPS)
    offline = segment(clf, seq)
    assert [(s.label, s.start_frame, s.end_frame) for s in offline.segments] == [
        ("Stand", 0, seq.n_frames)
    ]
    live = LiveSegmenter(clf, 30.0)
    found = []
    for frame in seq.to_canonical().positions[::4]:
        found += live.push(frame)
    found += live.finish()
    assert [s.label for s in found] == ["Stand"], found


@pytest.mark.parametrize(
    "text",
    [
        "path,label\nclip.npz,Plié\n",  # a label not in ASCII
        "\ufeffpath,label\nclip.npz,stand\n",  # as Excel saves a CSV: UTF-8 with a BOM
        # an é whose two bytes are the 512th and 513th: the first 512 bytes end part-way
        "path,label\n" + "clip.npz,stand\n" * 32 + "clip.npz," + "x" * 11 + "é\n",
    ],
    ids=["accented", "bom", "split"],
)
def test_db_given_a_labels_csv_in_utf8_says_it_is_a_text_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str
) -> None:
    """``classify clip --db labels.csv`` (the two swapped) with a labels CSV that is UTF-8
    text but not ASCII said only "not a readable SQLite database (corrupt or not a
    database)"; it says what an ASCII one gets: a text file, and that --db takes the case
    base file."""
    from tests.badinput import refused
    from tests.test_hunt33e import good_pose_file

    clip = good_pose_file(tmp_path / "clip.npz", frames=12)
    db = tmp_path / "labels.csv"
    db.write_bytes(text.encode("utf-8"))
    refused(["classify", str(clip), "--db", str(db)], tmp_path, capsys,
            "labels.csv: not a readable SQLite database (a text file, such as a labels CSV:"
            " --db takes the case base file)")  # fmt: skip
