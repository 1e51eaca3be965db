"""Bad input found by hunting as a new user would: training from long recordings with label
files, ``watch`` on streams and videos that go wrong, ``reps`` and ``segment`` on clips that
are too short, empty or of the wrong shape. Each refusal is one line, exit 1, nothing
written (:func:`tests.badinput.refused`), and comes before the expensive work."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from features.poses import save_pose
from tests.badinput import refused, standing_clip

# ---- (a) a labels CSV of recordings labelled over time -------------------------------------


def _recordings(folder: Path) -> tuple[Path, Path]:
    """Two recordings of one person standing, 2 s and 3 s at 30 fps."""
    folder.mkdir(parents=True, exist_ok=True)
    return (
        save_pose(standing_clip(60), folder / "first.npz"),
        save_pose(standing_clip(90), folder / "second.npz"),
    )


@pytest.fixture
def described(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The files ``train`` described (read and reduced to features): each name, in order."""
    import cbr.training

    seen: list[str] = []
    real = cbr.training.describe_entry

    def describe_entry(entry: Any, *args: Any) -> Any:
        seen.append(entry.name)
        return real(entry, *args)

    monkeypatch.setattr(cbr.training, "describe_entry", describe_entry)
    return seen


def test_one_label_file_for_two_recordings_is_refused_before_either_is_described(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], described: list[str]
) -> None:
    """A labels CSV naming one label file (4 labels of 0.5 s: the 2-s recording) for both
    recordings: refused naming the label file and the 3-s recording it does not fit, before
    the first recording was read and described (the refusal came only when the second was
    read, after the first's features: 30 s on CMU's 13_29 and 13_30)."""
    first, second = _recordings(tmp_path / "data")
    labels = tmp_path / "data" / "labels.txt"
    labels.write_text("1 1 2 2\n", encoding="utf-8")
    csv = tmp_path / "data" / "recordings.csv"
    csv.write_text(
        f"path,label_file,label_block_s\n{first.name},labels.txt,0.5\n"
        f"{second.name},labels.txt,0.5\n",
        encoding="utf-8",
    )
    db = tmp_path / "cb.sqlite"
    refused(["train", str(csv), "--db", str(db)], tmp_path, capsys,
            f"{labels}: 4 labels (one per 0.5 s) do not fit the recording second.npz: "
            "90 frames at 30 fps need 6")  # fmt: skip
    assert described == []


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("", "the label file holds no labels"),
        ("1 1 1 1 1 1 x\n", "line 1: label code(s) x not in the label names"),
        ("\ufeff1,1\r\n1,1\r\n2,2\r\n", "line 3: label code(s) 2 not in the label names"),
    ],
)
def test_a_later_recordings_malformed_label_file_is_refused_first(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    described: list[str],
    text: str,
    problem: str,
) -> None:
    """The second recording's label file empty, or holding a code its names file lacks
    (also with a byte order mark and CRLF line ends, read as any other): refused naming
    that label file before the first recording was described."""
    first, second = _recordings(tmp_path / "data")
    (tmp_path / "data" / "good.txt").write_text("1 1 1 1\n", encoding="utf-8")
    bad = tmp_path / "data" / "bad.txt"
    bad.write_text(text, encoding="utf-8", newline="")
    (tmp_path / "data" / "names.txt").write_text("1 Stand\n", encoding="utf-8")
    csv = tmp_path / "data" / "recordings.csv"
    csv.write_text(
        "path,label_file,label_block_s,label_names\n"
        f"{first.name},good.txt,0.5,names.txt\n{second.name},bad.txt,0.5,names.txt\n",
        encoding="utf-8",
    )
    refused(["train", str(csv), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
            f"{bad}: {problem}")  # fmt: skip
    assert described == []


def test_frame_labels_are_read_before_the_recording(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``train RECORDING --frame-labels EMPTY``: the label file is refused before the
    recording is read (a video's poses were estimated first, minutes for a long one)."""
    import posecbr.commands.train as train

    first, _ = _recordings(tmp_path / "data")
    empty = tmp_path / "data" / "labels.txt"
    empty.write_text("\n", encoding="utf-8")
    read: list[Path] = []
    real = train.load_recording

    def load_recording(path: Path, *args: Any) -> Any:
        read.append(path)
        return real(path, *args)

    monkeypatch.setattr(train, "load_recording", load_recording)
    argv = ["train", str(first), "--frame-labels", str(empty), "--label-block", "0.5",
            "--db", str(tmp_path / "cb.sqlite")]  # fmt: skip
    refused(argv, tmp_path, capsys, f"{empty}: the label file holds no labels")
    assert read == []


# ---- (c) segment given several recordings, one it cannot segment ---------------------------


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from tests.badinput import small_case_base

    return small_case_base(tmp_path_factory.mktemp("cb"))


def _spoiled(kind: str, path: Path) -> tuple[Path, str]:
    """A recording ``segment`` cannot segment, and what its refusal says."""
    from dataclasses import replace

    import numpy as np

    from tests.badinput import pose_file

    if kind == "one frame":
        return save_pose(standing_clip(1), path), "the recording lasts 0.03 s, shorter than"
    if kind == "no joints":
        seq = standing_clip(60)
        nan = replace(seq, positions=np.full_like(seq.positions, np.nan), confidence=None)
        return save_pose(nan, path), "shows no person (no frame with a torso)"
    positions = standing_clip().positions[:, :, :2]
    return pose_file(path, positions=positions), "positions must have shape (frames, joints, 3)"


@pytest.mark.parametrize("kind", ["one frame", "no joints", "wrong shape"])
def test_segment_refuses_a_bad_recording_among_several_before_segmenting_any(
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    kind: str,
) -> None:
    """``segment good.npz bad.npz --json``: the second, a 1-frame clip, a clip of NaN joints
    or a pose file of 2-D positions, is refused in one line before the first is segmented
    (it was segmented, minutes for a long recording, and then thrown away)."""
    import cbr.segmentation

    data = tmp_path / "data"
    data.mkdir()
    good = save_pose(standing_clip(90), data / "good.npz")
    bad, problem = _spoiled(kind, data / "bad.npz")
    segmented: list[str] = []
    real = cbr.segmentation.segment

    def segment(clf: Any, rec: Any, *args: Any, **kwargs: Any) -> Any:
        segmented.append(rec.source)
        return real(clf, rec, *args, **kwargs)

    monkeypatch.setattr(cbr.segmentation, "segment", segment)
    argv = ["segment", str(good), str(bad), "--db", str(case_base), "--json"]
    refused(argv, tmp_path, capsys, str(bad), problem)
    assert segmented == []


def test_an_amc_recording_without_its_skeleton_is_refused_before_the_others_are_described(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], described: list[str]
) -> None:
    """A labels CSV listing a pose file, then an AMC recording with no .asf beside it (as
    cmu-mocap6/amc ships): refused naming the AMC file before the pose file was described
    (it was described first, and the skeleton looked for only when the AMC was read)."""
    first, _ = _recordings(tmp_path / "data")
    amc = tmp_path / "data" / "13_30.amc"
    amc.write_text(":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\n", encoding="utf-8")
    (tmp_path / "data" / "labels.txt").write_text("1 1 1 1\n", encoding="utf-8")
    csv = tmp_path / "data" / "recordings.csv"
    csv.write_text(
        f"path,label_file,label_block_s\n{first.name},labels.txt,0.5\n{amc.name},labels.txt,0.5\n",
        encoding="utf-8",
    )
    refused(["train", str(csv), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
            f"{amc}: no .asf skeleton file beside it")  # fmt: skip
    assert described == []


# ---- (b) watch ------------------------------------------------------------------------------


def test_watch_of_a_folder_says_it_is_a_folder(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch FOLDER``: the folder exists, and is no video (it was "no such video file")."""
    folder = tmp_path / "videos"
    folder.mkdir()
    refused(["watch", str(folder), "--db", str(case_base)], tmp_path, capsys,
            f"{folder}: is a folder, not a video file")  # fmt: skip
