"""Hunt 31c, the video path as a physiotherapist or coach meets it: one video of each exercise
with several repetitions, trained with ``--split repetitions``.

- Each activity's cases then come from one recording, so no training repetition can be
  classified held out of its recording with a case of its activity left, and the confidence
  is the plain vote share: ``train`` said nothing of it, ``casebase info`` said "calibrated
  on 0 none training repetitions (their accuracy nan)", its ``--json`` wrote ``NaN``, which
  is not JSON, and ``classify --verbose`` called the confidence "the nearest cases' soft
  vote calibrated on the training clips".
- A class folder whose only video shows nobody: ``train`` called the clip kept whole "1
  repetition that shows no person"; and when it left one activity, refused with "y: the
  training set has only one activity" (scikit-learn's argument), without naming the clip.
- ``casebase list`` showed a case's frames end exclusive, every other table end inclusive.
- A class folder whose clips lie in a subfolder (``lunge/day1/``) was dropped without a word
  by ``extract`` and ``train``.
- ``watch --out`` stopped before its first frame exited 0 in silence, without ``--out`` 1 with
  a line.
- ``.3gp`` and ``.MTS`` videos in class folders were skipped without a word.

Synthetic arm movements (three activities, three pieces of one recording each) stand in for
the videos: the same grouping, a second to train.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from features.poses import save_pose
from posecbr.cli import main
from tests.badinput import refused, snapshot, standing_clip
from tests.test_cbr_clips import arm_dataset
from tests.test_json_hunt import strict

# on one xdist worker: the module's one_recording_each made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt31c")


@pytest.fixture(scope="module")
def one_recording_each(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A case base of three activities, each three pieces of one recording (a labels CSV's
    start,end rows)."""
    root = tmp_path_factory.mktemp("one_recording_each")
    clips, labels = arm_dataset(3, 5)
    rows = ["path,label,start,end"]
    for k, label in enumerate(sorted(set(labels))):
        pieces = [c for c, lab in zip(clips, labels, strict=True) if lab == label]
        positions = np.concatenate([c.positions for c in pieces])
        save_pose(
            dataclasses.replace(pieces[0], positions=positions, confidence=None),
            root / f"rec{k}.npz",
        )
        start = 0
        for c in pieces:
            rows.append(f"rec{k}.npz,activity{k},{start},{start + len(c.positions)}")
            start += len(c.positions)
    (root / "labels.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    db = root / "cb.sqlite"
    argv = ["train", str(root / "labels.csv"), "--db", str(db), "--mirror", "off",
            "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    assert main(argv) == 0
    return db


def test_train_says_when_the_confidence_could_not_be_calibrated(
    one_recording_each: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train`` said nothing of it: the README promises a calibrated confidence."""
    csv = one_recording_each.parent / "labels.csv"
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(csv), "--db", str(db), "--mirror", "off", "--feature-weights", "none",
            "--phases", "0", "--json"]  # fmt: skip
    capsys.readouterr()
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert strict(out)["learned"]["confidence_calibrated_on"] == 0
    assert (
        "note: the confidence is the vote share, not calibrated: each activity's training clips"
        " came from one recording or person, so none could be classified held out of it (a "
        "second recording or person per activity calibrates it)\n"
    ) in err
    # each clip its own recording: calibrated leave-one-recording-out, no note
    clips, labels = arm_dataset(3, 5)
    for i, (seq, label) in enumerate(zip(clips, labels, strict=True)):
        save_pose(seq, tmp_path / "own" / f"a{sorted(set(labels)).index(label)}" / f"{i}.npz")
    argv[1:4] = [str(tmp_path / "own"), "--db", str(tmp_path / "own.sqlite")]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert strict(out)["learned"]["confidence_calibrated_on"] == 9
    assert "not calibrated" not in err


def test_info_of_a_case_base_whose_confidence_could_not_be_calibrated(
    one_recording_each: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(one_recording_each)]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("  confidence: "))
    assert line == (
        "  confidence: the vote share, not calibrated (each activity's training clips came "
        "from one recording or person: none could be classified held out of it)"
    )
    assert "nan" not in out

    assert main(["casebase", "info", "--db", str(one_recording_each), "--json"]) == 0
    doc = strict(capsys.readouterr().out)
    confidence = doc["case_bases"][0]["model"]["confidence"]
    assert confidence["n"] == 0 and confidence["accuracy"] is None


def test_verbose_explanation_of_an_uncalibrated_confidence_says_so(
    one_recording_each: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The verbose lines said "the confidence is the nearest cases' soft vote calibrated on
    the training clips" where it is the plain vote share."""
    clip = one_recording_each.parent / "rec0.npz"
    capsys.readouterr()
    argv = ["classify", str(clip), "--db", str(one_recording_each), "--verbose", "--json"]
    assert main(argv) == 0
    result = strict(capsys.readouterr().out)["results"][0]
    assert result["confidence"] == result["vote_share"]  # nothing maps it
    vote = next(x for x in result["verbose"].splitlines() if x.startswith("Vote: "))
    assert vote.endswith("; the confidence is the vote share, not calibrated).")


def _nobody(path: Path) -> Path:
    """A pose file of 2 s in which no frame shows anybody (every joint missing)."""
    seq = standing_clip(60)
    return save_pose(dataclasses.replace(seq, positions=np.full_like(seq.positions, np.nan)), path)


def _classes(root: Path, n_activities: int) -> Path:
    """A folder per class: ``n_activities`` of the arm movements (three clips each) and
    ``walk``, whose only clip shows nobody."""
    clips, labels = arm_dataset(3, 5)
    for i, (seq, label) in enumerate(zip(clips, labels, strict=True)):
        if label in sorted(set(labels))[:n_activities]:
            save_pose(seq, root / f"a{sorted(set(labels)).index(label)}" / f"clip{i:02d}.npz")
    _nobody(root / "walk" / "empty.npz")
    return root


def test_train_names_the_class_whose_every_clip_shows_nobody(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = _classes(tmp_path / "data", 1)
    line = refused(
        ["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--split", "repetitions"],
        tmp_path,
        capsys,
    )
    assert line == (
        "posecbr train: error: training set: only one activity ('a0') is left to learn from, a "
        "classifier needs two or more: every clip of 'walk' shows no person's torso (both "
        f"shoulders and hips): {data / 'walk' / 'empty.npz'}"
    )


def test_train_split_repetitions_calls_a_clip_that_shows_nobody_a_clip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = _classes(tmp_path / "data", 3)
    argv = ["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--split", "repetitions",
            "--mirror", "off", "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert f"skipped 1 clip that shows no person: {data / 'walk' / 'empty.npz'}\n" in out
    assert "from 3 activities" in out


def test_casebase_list_shows_a_case_s_frames_end_inclusive_as_every_table_does(
    one_recording_each: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``casebase list`` showed a repetition of frames 3-24 (``reps``' table, end inclusive)
    as 3-25, and the next one's start as 25: two cases seemingly sharing frame 25."""
    rows = (one_recording_each.parent / "labels.csv").read_text().splitlines()[1:]
    spans = {(path, int(start), int(end)) for path, _, start, end in (r.split(",") for r in rows)}
    capsys.readouterr()
    assert main(["casebase", "list", "--db", str(one_recording_each)]) == 0
    shown = {
        (Path(f[5]).name, f[4])
        for f in (x.split("\t") for x in capsys.readouterr().out.splitlines())
    }
    assert shown == {(path, f"{start}-{end - 1}") for path, start, end in spans}
    assert main(["casebase", "list", "--db", str(one_recording_each), "--json"]) == 0
    cases = strict(capsys.readouterr().out)["cases"]
    assert {(Path(c["source"]).name, *c["frames"]) for c in cases} == spans  # end exclusive


def _grey_video(path: Path, frames: int = 4) -> Path:
    """A small MJPG AVI of grey frames (nobody in view)."""
    import cv2

    path.parent.mkdir(parents=True, exist_ok=True)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 10.0, (32, 32))
    for k in range(frames):
        writer.write(np.full((32, 32, 3), 10 * k, np.uint8))
    writer.release()
    return path


def test_train_refuses_a_class_folder_whose_clips_lie_in_a_subfolder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``squat/clip.npz`` beside ``lunge/day1/clip.npz``: the lunges were dropped without a
    word and train refused "the training data hold only one activity ('squat')"."""
    clips, _ = arm_dataset(1, 5)
    data = tmp_path / "data"
    save_pose(clips[0], data / "squat" / "a.npz")
    save_pose(clips[1], data / "lunge" / "day1" / "b.npz")
    refused(
        ["train", str(data), "--db", str(tmp_path / "cb.sqlite")],
        tmp_path,
        capsys,
        f"{data / 'lunge'}: this class folder holds no clip itself, its subfolder 'day1' does",
    )


def test_extract_refuses_a_class_folder_whose_videos_lie_in_a_subfolder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Extracted, the lunges in ``lunge/day1/`` were skipped without a word."""
    videos = tmp_path / "videos"
    _grey_video(videos / "squat" / "a.avi")
    _grey_video(videos / "lunge" / "day1" / "b.avi")
    _grey_video(videos / "lunge" / "day2" / "c.avi")
    refused(
        ["extract", str(videos), "--out", str(tmp_path / "poses")],
        tmp_path,
        capsys,
        f"{videos / 'lunge'}: this class folder holds no clip itself, its subfolder 'day1' does"
        " (and 1 more): class folders are read one level deep",
    )


def test_info_of_an_uncalibrated_case_base_appended_to_says_the_cases_changed_since(
    one_recording_each: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """After ``train --append``, the activity may come from two recordings: the line says it
    is of the training's cases, as the line of a calibrated confidence does."""
    import shutil

    db = shutil.copy(one_recording_each, tmp_path / "cb.sqlite")
    clips, _ = arm_dataset(1, 9)
    save_pose(clips[0], tmp_path / "more" / "activity0" / "new.npz")
    assert main(["train", str(tmp_path / "more"), "--db", str(db), "--append"]) == 0
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db)]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "  confidence: " in x)
    assert line.endswith(
        "none could be classified held out of it; cases added, changed or dropped since are "
        "not taken into account)"
    )


def watch_stops_before_its_first_window(
    db: Path,
    folder: Path,
    capsys: pytest.CaptureFixture[str],
    status: int,
    said: str,
    options: list[str],
) -> None:
    """``watch`` of a grey clip made in ``folder``, with ``options``, stopped at its start
    (how: the caller's patch of ``watch.stop_on_interrupt``): exit ``status``, one line saying
    it was ``said`` before the shortest window, and nothing in ``folder`` written or changed
    (an ``--out`` there included). Shared with hunt 40o."""
    video = _grey_video(folder / "clip.avi")
    before = snapshot(folder)
    capsys.readouterr()
    assert main(["watch", str(video), "--db", str(db), "--speed", "0", *options]) == status
    assert capsys.readouterr().err.splitlines() == [
        f"posecbr watch: {said}: {video}: stopped after 0 frames (0.00 s), before the shortest"
        " window (1 s) of the stream was seen: no segment to give"
    ]
    assert snapshot(folder) == before


@pytest.mark.parametrize("out", [False, True])
def test_watch_stopped_before_its_first_frame_says_so_with_or_without_out(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    out: bool,
) -> None:
    """Ctrl-C while the pose model loads (the stop event set before the first frame): without
    ``--out``, "the stream ended after 0 frames ... no segment to give", exit 1; with
    ``--out`` it exited 0 and said nothing. The same line now, and no video either way: said
    as interrupted, exit 130 (hunt 40o: it was blamed on the stream, exit 1)."""
    import signal
    from contextlib import contextmanager
    from threading import Event

    import posecbr.commands.watch as watch
    from tests.badinput import small_case_base

    @contextmanager
    def stopped(also: Event | None = None) -> Any:
        event = watch.Stop()
        event.stop(signal.SIGINT)
        yield event

    monkeypatch.setattr(watch, "stop_on_interrupt", stopped)
    db = small_case_base(tmp_path / "cb")
    options = ["--out", str(tmp_path / "in" / "seen.mp4")] if out else []
    watch_stops_before_its_first_window(db, tmp_path / "in", capsys, 130, "interrupted", options)


def test_phone_and_camcorder_videos_in_class_folders_are_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An Android ``.3gp`` and an AVCHD camcorder's ``.MTS`` in class folders were skipped
    without a word (``extract`` of one of them named alone worked; ``reps`` refused it as
    "unknown clip format"). FFmpeg reads a file by its content: MJPG AVIs so named stand in."""
    from features.datasets import clip_files

    videos = tmp_path / "videos"
    a = _grey_video(videos / "squat" / "a.avi").rename(videos / "squat" / "a.3gp")
    b = _grey_video(videos / "lunge" / "b.avi").rename(videos / "lunge" / "b.MTS")
    assert clip_files(a.parent) == [a] and clip_files(b.parent) == [b]
    capsys.readouterr()
    assert main(["extract", str(videos), "--out", str(tmp_path / "poses")]) == 0
    assert "2 extracted, 0 up to date, 0 failed" in capsys.readouterr().out
    assert (tmp_path / "poses" / "squat" / "a.npz").is_file()
    assert (tmp_path / "poses" / "lunge" / "b.npz").is_file()
