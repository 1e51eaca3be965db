"""Dataset loaders: labels CSV, class folders, pose folders, single files, UI-PRMD, HDM05."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.datasets import (
    detect_kind,
    iter_dataset,
    load_clip,
    load_dataset,
    read_labels_csv,
)
from features.errors import DataError, PosecbrError
from features.poses import PoseSequence, save_pose
from features.skeleton import BLAZEPOSE_33, JOINT_INDEX


def _seq(frames: int = 6, offset: float = 0.0, **meta: object) -> PoseSequence:
    """A canonical sequence whose nose x equals the frame number (+ offset), so slices show."""
    pos = np.zeros((frames, len(BLAZEPOSE_33), 3))
    pos[:, JOINT_INDEX["nose"], 0] = np.arange(frames) + offset
    return PoseSequence(pos, BLAZEPOSE_33, 30.0, metadata=meta)


@pytest.fixture()
def pose_files(tmp_path: Path) -> Path:
    save_pose(_seq(), tmp_path / "a.npz")
    save_pose(_seq(offset=100), tmp_path / "b, with comma.npz")
    return tmp_path


def _write_csv(folder: Path, text: str, name: str = "labels.csv") -> Path:
    p = folder / name
    p.write_text(text, encoding="utf-8")
    return p


def test_csv_quotes_unicode_slices(pose_files: Path) -> None:
    csv = _write_csv(
        pose_files,
        "path,label,subject,start,end,correct\n"
        'a.npz,"Kniebeuge, tief",s1,2,5,true\n'
        '"b, with comma.npz",스쿼트,,,,false\n',
    )
    assert detect_kind(csv) == "csv" and detect_kind(pose_files) == "csv"
    clips = load_dataset(csv)
    assert [c.label for c in clips] == ["Kniebeuge, tief", "스쿼트"]
    assert [c.subject for c in clips] == ["s1", None]
    assert clips[0].extras["correct"] is True and clips[1].extras["correct"] is False
    # start/end are frame indices, end exclusive: frames 2, 3, 4
    np.testing.assert_array_equal(clips[0].seq.joint("nose")[:, 0], [2, 3, 4])
    assert clips[1].seq.n_frames == 6 and clips[1].seq.joint("nose")[0, 0] == 100
    assert clips[0].seq.metadata["label"] == "Kniebeuge, tief"
    assert clips[0].seq.metadata["subject"] == "s1"


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("a.npz,squat\n", "line 1: header"),
        ("path,label\na.npz,squat,extra\n", "line 2: 3 fields"),
        ("path,label\na.npz,squat\n,squat\n", "line 3: empty path"),
        ("path,label\na.npz,\n", "line 2: empty label"),
        ("path,label\nmissing.npz,squat\n", "line 2: no such file missing.npz"),
        ("path,label,start,end\na.npz,squat,x,3\n", "line 2: start and end"),
        ("path,label,start,end\na.npz,squat,4,2\n", "line 2: need 0 <= start < end"),
        ("path,label,start\na.npz,squat,4\n", "start and end go together"),
        ('path,label\n"a.npz,squat\n', "line 2: malformed CSV"),
        ("", "empty CSV"),
    ],
)
def test_csv_malformed_rows_name_file_and_line(pose_files: Path, text: str, match: str) -> None:
    csv = _write_csv(pose_files, text, "bad.csv")
    with pytest.raises(DataError, match=match) as info:
        load_dataset(csv)
    assert info.value.source == str(csv)


def test_csv_end_past_clip(pose_files: Path) -> None:
    csv = _write_csv(pose_files, "path,label,start,end\na.npz,squat,2,60\n", "x.csv")
    with pytest.raises(DataError, match="line 2: end 60 is past the clip's 6 frames"):
        load_dataset(csv)


def test_csv_latin1_is_refused_clearly(pose_files: Path) -> None:
    p = pose_files / "l1.csv"
    p.write_bytes("path,label\na.npz,caf\xe9\n".encode("latin-1"))
    with pytest.raises(DataError, match="not UTF-8"):
        read_labels_csv(p)


def test_class_folders_and_pose_folder(tmp_path: Path) -> None:
    for label, n in (("squat", 2), ("lunge", 3)):
        (tmp_path / label).mkdir()
        for i in range(n):
            save_pose(_seq(subject=f"p{i}"), tmp_path / label / f"{i}.npz")
    (tmp_path / "notes.txt").write_text("ignored")
    assert detect_kind(tmp_path) == "class_folders"
    clips = load_dataset(tmp_path)
    assert sorted(c.label for c in clips) == ["lunge"] * 3 + ["squat"] * 2
    assert {c.subject for c in clips} == {"p0", "p1", "p2"}  # from each file's metadata
    assert len(load_dataset(tmp_path, subjects={"p0"})) == 2
    assert len(load_dataset(tmp_path, limit=1)) == 1

    flat = tmp_path / "flat"
    flat.mkdir()
    save_pose(_seq(label="jump", subject="x"), flat / "j.npz")
    assert detect_kind(flat) == "pose_folder"
    (clip,) = load_dataset(flat)
    assert (clip.label, clip.subject) == ("jump", "x")
    save_pose(_seq(), flat / "unlabelled.npz")
    with pytest.raises(DataError, match="no label"):
        load_dataset(flat)


def test_single_pose_file_and_errors(tmp_path: Path) -> None:
    f = save_pose(_seq(label="wave"), tmp_path / "one.npz")
    assert detect_kind(f) == "pose_file"
    (clip,) = load_dataset(f)
    assert clip.label == "wave" and clip.seq.positions.shape == (6, 33, 3)
    with pytest.raises(DataError, match="no such file or folder"):
        load_dataset(tmp_path / "nope")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(DataError, match="cannot tell what dataset"):
        load_dataset(empty)
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(PosecbrError) as info:
        load_clip(bad)
    assert info.value.source == str(bad)
    with pytest.raises(DataError, match="unknown clip format"):
        load_clip(_write_csv(tmp_path, "x", "clip.xyz"))


def test_float32_pose_file_is_cast(tmp_path: Path) -> None:
    seq = _seq(label="a")
    p = tmp_path / "f32.npz"
    np.savez_compressed(
        p,
        positions=seq.positions.astype(np.float32),
        joint_names=np.array(BLAZEPOSE_33),
        fps=np.float64(30),
    )
    loaded = load_clip(p)
    assert loaded.positions.dtype == np.float64
    np.testing.assert_array_equal(loaded.joint("nose")[:, 0], np.arange(6))


def test_video_without_estimator_or_bad_video(tmp_path: Path) -> None:
    video = tmp_path / "clip.mp4"
    video.write_bytes(b"not really a video")
    try:
        from features.pose_estimation import estimate_poses  # noqa: F401
    except ImportError:
        with pytest.raises(DataError, match="video input needs the pose estimator"):
            load_clip(video)
    else:
        with pytest.raises(PosecbrError):
            load_clip(video)


# ---- real data -------------------------------------------------------------------------


def test_uiprmd_folder(shared_data: Path) -> None:
    root = shared_data / "ui-prmd"
    assert detect_kind(root) == "uiprmd"
    clips = load_dataset(root, subjects={"s02"}, movements={"m01", "m10"}, episodes={1, 2, 3})
    assert len(clips) == 12  # 2 movements x 3 episodes x correct/incorrect
    assert {c.label for c in clips} == {"deep_squat", "standing_shoulder_scaption"}
    assert sum(c.extras["correct"] for c in clips) == 6
    first = clips[0]
    assert first.subject == "s02" and first.extras["movement"] == "m01"
    assert first.extras["episode"] == 1 and first.extras["sensor"] == "kinect"
    assert first.seq.metadata["label"] == "deep_squat" and first.seq.fps == 30.0
    incorrect = [c for c in clips if not c.extras["correct"]]
    assert all("_inc" in Path(c.seq.source).name for c in incorrect)
    vicon = load_dataset(root, sensor="vicon", subjects={"s01"}, movements={"m07"}, limit=2)
    assert len(vicon) == 2 and all(c.extras["sensor"] == "vicon" for c in vicon)
    assert vicon[0].seq.fps == 100.0 and vicon[0].label == "standing_shoulder_abduction"
    with pytest.raises(DataError, match="sensor"):
        load_dataset(root, sensor="xsens")


def test_hdm05_folder(shared_data: Path, tmp_path: Path) -> None:
    root = shared_data / "hdm05"
    assert detect_kind(root) == "asf_amc"
    clips = load_dataset(root, labels={"squat1Reps"}, subjects={"dg"})
    assert clips and all(c.label == "squat1Reps" and c.subject == "dg" for c in clips)
    assert all(c.extras["dataset"] == "hdm05" and c.seq.fps == 120.0 for c in clips)
    takes = sorted(c.extras["take"] for c in clips)
    assert takes == sorted(set(takes))
    # an AMC without its actor's skeleton
    amc = next(root.glob("train/*/HDM_bd_squat1Reps_*.amc"))
    lonely = tmp_path / "lonely"
    lonely.mkdir()
    (lonely / amc.name).write_bytes(amc.read_bytes())
    with pytest.raises(DataError, match="no .asf skeleton"):
        load_dataset(lonely)


def test_iter_dataset_is_lazy(pose_files: Path) -> None:
    (pose_files / "broken.npz").write_bytes(b"PK\x03\x04 truncated")
    csv = _write_csv(pose_files, "path,label\na.npz,one\nbroken.npz,two\n", "lazy.csv")
    clips = iter_dataset(csv)
    assert next(clips).label == "one"  # the first clip arrives before the broken one is read
    with pytest.raises(PosecbrError) as info:
        next(clips)
    assert info.value.source == str(pose_files / "broken.npz")


def test_video_class_folder(shared_data: Path) -> None:
    # videos/<class>/<clip>.mp4 is a class-folder dataset; the video runs through BlazePose.
    pytest.importorskip("features.pose_estimation")
    root = shared_data / "videos"
    assert detect_kind(root) == "class_folders"
    (clip,) = load_dataset(root, labels={"squat"})
    assert clip.label == "squat" and clip.seq.fps == 5.0  # the squat clip is 5 fps
    assert clip.seq.positions.shape[1:] == (33, 3)
    hips = clip.seq.joints(["left_hip", "right_hip"])
    assert np.isfinite(hips).any()
