"""A physiotherapist's walkthrough with real videos (hunt 35f): extract, train, classify,
segment, reps and watch on their own folders, phone-like videos and hand-typed label CSVs."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import good_pose_file, refused, small_case_base

# what `posecbr extract clip.mp4 --out clip.npz` writes in a pose file's metadata (no label)
_EXTRACTED = {
    "source_video": "new_patient.mp4",
    "made_from": "new_patient.mp4",
    "video_fps": 24.0,
    "pose_model": "blazepose-full",
    "extraction_version": 2,
}


@pytest.mark.parametrize("append", [False, True])
def test_train_of_an_unlabelled_pose_file_says_it_has_no_label(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], append: bool
) -> None:
    """A pose file `extract` made of one video carries no label. Given alone to `train`
    (new or `--append`, as `classify --feedback` on a case base of repetitions advises),
    it was refused with "no value for --target 'label' (columns: label, subject,
    source_video, ...) (did you mean 'label'?)": a --target the user never typed, a
    column list naming the very columns the file lacks, and a guess of the same name."""
    db = small_case_base(tmp_path) if append else tmp_path / "new.sqlite"
    capsys.readouterr()
    clip = good_pose_file(tmp_path / "new_patient.npz", frames=60, **_EXTRACTED)
    line = refused(
        ["train", str(clip), "--db", str(db), *(["--append"] if append else [])],
        tmp_path, capsys,
        "new_patient.npz: no label: its metadata has none",
        "labels CSV", "folder named after its activity",
    )  # fmt: skip
    assert "--target" not in line and "did you mean" not in line


def test_train_target_missing_lists_only_the_columns_the_clip_has(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A --target column the clip lacks lists the columns it does have: before, `label`
    and `subject` were listed whether or not the clip had them."""
    clip = good_pose_file(tmp_path / "clip.npz", frames=60, label="squat", **_EXTRACTED)
    line = refused(
        ["train", str(clip), "--db", str(tmp_path / "cb.sqlite"), "--target", "correct"],
        tmp_path, capsys,
        "clip.npz: no value for --target 'correct' (columns: label, extraction_version,",
    )  # fmt: skip
    assert "subject" not in line


def _tiny_video(path: Path, seed: int = 0) -> Path:
    """A few MJPG frames (no person: only the file's bytes matter here)."""
    import cv2
    import numpy as np

    rng = np.random.default_rng(seed)
    out = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (32, 32))
    for _ in range(4):
        out.write(rng.integers(0, 255, (32, 32, 3), dtype=np.uint8))
    out.release()
    return path


def _twin_folder(tmp_path: Path, sha_of: Path | None = None) -> Path:
    """data/squat/take.avi beside data/squat/take.npz, the pose file as `posecbr extract
    videos/ --out videos/squat/` writes it (its metadata names the video, relative to the
    folder extract ran in, with the video's SHA-256), and data/lunge/other.npz."""
    import hashlib

    data = tmp_path / "data"
    (data / "squat").mkdir(parents=True)
    (data / "lunge").mkdir()
    video = _tiny_video(data / "squat" / "take.avi")
    sha = hashlib.sha256((sha_of or video).read_bytes()).hexdigest()
    meta = {**_EXTRACTED, "source_video": "videos/squat/take.avi", "made_from": "take.avi"}
    good_pose_file(data / "squat" / "take.npz", frames=60, label="squat", video_sha256=sha,
                   **{k: v for k, v in meta.items()})  # fmt: skip
    good_pose_file(data / "lunge" / "other.npz", frames=60, label="lunge")
    return data


@pytest.mark.parametrize("command", ["train", "compare", "classify"])
def test_a_video_and_its_own_pose_file_in_one_folder_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    """A class folder holding a video and the pose file extract made of it (extracted
    into the videos' folder, or copied there) was read as two clips of one recording:
    `train` stored two cases of one take and calibrated the confidence on them, each the
    other's held-out neighbour ("calibrated on 2 leave-one-recording-out training clips
    (their accuracy 100.0 %)", the unlike-the-cases threshold "beyond 1.00x"), and
    `classify` answered and counted the take twice."""
    data = _twin_folder(tmp_path)
    if command == "classify":
        small_case_base(tmp_path)
        capsys.readouterr()
    argv = {
        "train": ["train", str(data), "--db", str(tmp_path / "cb.sqlite")],
        "compare": ["compare", str(data)],
        "classify": ["classify", str(data / "squat"), "--db", str(tmp_path / "cb.sqlite")],
    }[command]
    refused(argv, tmp_path, capsys,
            "data/squat: take.npz holds the poses of the video take.avi beside it",
            "read twice", "not both")  # fmt: skip


def test_a_labels_csv_listing_a_video_and_its_own_pose_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same through a labels CSV typed by hand: rows for take.avi and for the take.npz
    extract made of it trained two cases of one take."""
    _twin_folder(tmp_path)
    labels = tmp_path / "labels.csv"
    labels.write_text(
        "\ufeffpath,label\r\ndata/squat/take.avi,squat\r\ndata/lunge/other.npz,lunge\r\n"
        "data/squat/take.npz,squat\r\n\r\n",
        encoding="utf-8",
    )
    refused(["train", str(labels), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
            "labels.csv: line 4: take.npz holds the poses of the video take.avi of line 2",
            "read twice")  # fmt: skip


def test_a_pose_file_of_another_video_of_the_same_name_is_no_twin(tmp_path: Path) -> None:
    """A pose file made from another video that had the same name (its recorded SHA-256
    differs: a phone's IMG_0001.MOV of another day) is a recording of its own."""
    from features.datasets import check_no_extracted_twin, clip_files

    other = _tiny_video(tmp_path / "other_day.avi", seed=1)
    data = _twin_folder(tmp_path, sha_of=other)
    check_no_extracted_twin(clip_files(data / "squat"))  # no error
    (data / "squat" / "take.avi").write_bytes(other.read_bytes())  # now it is that video
    with pytest.raises(Exception, match="holds the poses of the video take.avi"):
        check_no_extracted_twin(clip_files(data / "squat"))


def test_extract_overlay_of_up_to_date_pose_files_does_not_count_them_extracted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Rerun with `--overlay` after the pose files were made, `extract` drew the overlays
    from the stored landmarks and left the pose files as they were, but said "2 extracted,
    0 up to date" (and, for one video, "done: clip.npz"): the pose model had not run."""
    import hashlib

    from posecbr.cli import main
    from tests.test_hunt31c import _grey_video

    videos, poses = tmp_path / "videos", tmp_path / "poses"
    _grey_video(videos / "squat" / "a.avi")
    _grey_video(videos / "lunge" / "b.avi", frames=5)
    assert main(["extract", str(videos), "--out", str(poses)]) == 0
    assert "2 extracted, 0 up to date, 0 failed" in capsys.readouterr().out
    files = sorted(poses.rglob("*.npz"))
    before = [hashlib.sha256(f.read_bytes()).hexdigest() for f in files]
    overlays = tmp_path / "overlays"
    assert main(["extract", str(videos), "--out", str(poses), "--overlay", str(overlays)]) == 0
    out = capsys.readouterr().out
    assert (
        out.strip()
        == f"0 extracted, 2 up to date (2 overlays drawn from them), 0 failed -> {poses}"
    )
    assert [hashlib.sha256(f.read_bytes()).hexdigest() for f in files] == before
    assert (overlays / "squat" / "a.mp4").is_file() and (overlays / "lunge" / "b.mp4").is_file()
    # one video: its pose file skipped, its overlay written
    one, pose = tmp_path / "one.mp4", tmp_path / "a.npz"
    video = videos / "squat" / "a.avi"
    assert main(["extract", str(video), "--out", str(pose)]) == 0
    assert capsys.readouterr().out.startswith("done: ")
    kept = hashlib.sha256(pose.read_bytes()).hexdigest()
    assert main(["extract", str(video), "--out", str(pose), "--overlay", str(one)]) == 0
    printed = capsys.readouterr()
    assert printed.out == (
        f"skipped: {pose} (up to date, 4 frames at 10 fps, 4 without a person; its overlay drawn)\n"
    )
    assert printed.err == f"overlay written to {one}\n" and one.is_file()
    assert hashlib.sha256(pose.read_bytes()).hexdigest() == kept


def test_verbose_differences_from_the_other_label_are_differences_a_reader_can_see(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`classify --verbose` lists the features that differ most from the nearest case of
    another label. A state no case holds (its cases' spread next to nothing) differing by
    a hair in a real, noisy clip outranked every real difference: "Differs from it most in:
    left knee bent mean confidence 0.00 here, 0.00 there; ..." (on the walkthrough's
    videos 9 of 108 items read so; here, clips with 2-30 mm of noise, 22 of 81). Every item
    shown now reads two different values."""
    import dataclasses
    import re

    import numpy as np

    from features.poses import load_pose, save_pose
    from posecbr.cli import main

    db = small_case_base(tmp_path)
    rng = np.random.default_rng(0)
    queries = []
    for k, clip in enumerate(sorted((tmp_path / "train").rglob("*.npz"))):
        seq = load_pose(clip)
        for sd in (0.002, 0.01, 0.03):
            noisy = seq.positions + rng.normal(0.0, sd, seq.positions.shape)
            path = tmp_path / f"q{k}_{sd}.npz"
            queries.append(str(save_pose(dataclasses.replace(seq, positions=noisy), path)))
    capsys.readouterr()
    assert main(["classify", *queries, "--db", str(db), "--verbose"]) == 0
    lines = [x for x in capsys.readouterr().out.splitlines() if "Differs from it most in" in x]
    items = [it for x in lines for it in x.split(": ", 1)[1].rstrip(".").split("; ")]
    assert len(lines) == len(queries) and len(items) >= len(queries)
    for item in items:
        values = re.search(r"(-?\d+(?:\.\d+)?)[^\d]*? here, (-?\d+(?:\.\d+)?)", item)
        assert values is not None, item
        assert values.group(1) != values.group(2), item


def test_extract_of_a_labels_csv_whose_end_is_past_the_video_names_the_csv_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV typed by hand with an end frame past its video named the video alone
    ("clip.avi: end frame 10 is past the video's 4 frames"): which row of which CSV said
    so was left to find. It now says where: "... end frame 10 (as labels.csv, line 3 gives
    it) is past the video's 4 frames"; the other row's pose file is written, whole."""
    from posecbr.cli import main
    from tests.test_hunt31c import _grey_video

    _grey_video(tmp_path / "videos" / "a.avi")
    _grey_video(tmp_path / "videos" / "b.avi")
    labels = tmp_path / "labels.csv"
    labels.write_text(
        "\ufeffpath,label,start,end\r\nvideos/a.avi,squat,0,4\r\nvideos/b.avi,lunge,1,10\r\n\r\n",
        encoding="utf-8",
    )
    out = tmp_path / "poses"
    assert main(["extract", str(labels), "--out", str(out)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"posecbr extract: error: {tmp_path / 'videos' / 'b.avi'}: end frame 10 (as labels.csv,"
        " line 3 gives it) is past the video's 4 frames",
        f"1 extracted, 0 up to date, 1 failed -> {out}",
    ]
    assert sorted(p.name for p in out.rglob("*") if p.is_file()) == ["a_0-4.npz"]
