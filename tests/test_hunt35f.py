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
