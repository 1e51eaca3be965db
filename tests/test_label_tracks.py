"""Training from long recordings: per-frame or per-block label files (cmu-mocap6/truelabels),
one clip per labelled stretch, ``train --split repetitions``, and label files that do not fit."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from features.datasets import iter_recording, load_dataset
from features.errors import DataError
from features.label_tracks import (
    LabelTrack,
    frame_labels,
    labelled_stretches,
    read_label_names,
    read_label_track,
)
from features.poses import PoseSequence, load_pose, save_pose
from features.readers.asfamc import read_asf_amc
from features.repetitions import count_repetitions, split_repetitions
from posecbr.cli import main

NAMES = (
    "1 JumpJack\n2 Jog\n3 Squat\n4 KneeRaise\n5 ArmCircle\n6 Twist\n7 SideReach\n8 Box\n"
    "9 UpDown\n10 ToeTouchOneHand\n11 SideBend\n12 ToeTouchTwoHands\n"
)


def test_block_labels_land_on_their_frames() -> None:
    # 120 fps, 0.1-s blocks: label t covers frames 12t..12t+11
    labels = ["a", "b", "c"]
    got = frame_labels(labels, 30, 120.0, 0.1, "x")  # 2.5 blocks: the last partial
    assert list(got) == ["a"] * 12 + ["b"] * 12 + ["c"] * 6
    assert labelled_stretches(got) == [(0, 12, "a"), (12, 24, "b"), (24, 30, "c")]
    # frames that fill the last block exactly: one more label is accepted (the cmu-mocap6
    # files were made so) and lands on no frame
    assert list(frame_labels(["a", "b", "c"], 24, 120.0, 0.1, "x")) == ["a"] * 12 + ["b"] * 12
    # one label per frame; one more, for the end time, as with blocks, lands on no frame
    assert list(frame_labels(["a", "a", "b"], 3, 30.0, None, "x")) == ["a", "a", "b"]
    assert list(frame_labels(["a", "a", "b", "c"], 3, 30.0, None, "x")) == ["a", "a", "b"]


@pytest.mark.parametrize(
    ("n_labels", "frames", "block"),
    [(4, 24, 0.1), (1, 24, 0.1), (2, 3, None), (5, 3, None), (7, 3, None), (10, 24, 0.1)],
)
def test_a_label_count_that_does_not_fit_is_refused(
    n_labels: int, frames: int, block: float | None
) -> None:
    with pytest.raises(DataError, match="not fit the recording") as info:
        frame_labels(["a"] * n_labels, frames, 120.0, block, "labels.txt")
    assert info.value.source == "labels.txt"


def _names(tmp_path: Path) -> Path:
    path = tmp_path / "names.txt"
    path.write_text(NAMES, encoding="utf-8")
    return path


def test_label_names_and_tracks_read_errors(tmp_path: Path) -> None:
    assert read_label_names(_names(tmp_path))["10"] == "ToeTouchOneHand"
    bad = tmp_path / "bad.txt"
    bad.write_text("1 JumpJack\n2\n", encoding="utf-8")
    with pytest.raises(DataError, match="line 2"):
        read_label_names(bad)
    track = tmp_path / "t.txt"
    track.write_text("1 1 13\n", encoding="utf-8")
    with pytest.raises(DataError, match="13"):
        read_label_track(track, read_label_names(_names(tmp_path)))
    empty = tmp_path / "empty.txt"
    empty.write_text("\n", encoding="utf-8")
    with pytest.raises(DataError, match="no labels"):
        read_label_track(empty)
    with pytest.raises(DataError, match="seconds > 0"):
        LabelTrack(track, -0.1)


# on one xdist worker: the module's recording made once, not once per worker
pytestmark = pytest.mark.xdist_group("label_tracks")


@pytest.fixture(scope="module")
def recording(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """CMU 13_30 (JumpJack, Twist, KneeRaise, Squat, Jog) as a pose file."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    return save_pose(seq, tmp_path_factory.mktemp("rec") / "13_30.npz")


def _truth(shared_data: Path) -> tuple[list[str], list[int]]:
    """The stretches of 13_30 worked out from its label file by hand: codes and change
    positions (label index x 12 frames)."""
    codes = (shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt").read_text().split()
    changes = [i for i in range(1, len(codes)) if codes[i] != codes[i - 1]]
    return [codes[0]] + [codes[i] for i in changes], [12 * i for i in changes]


def test_a_recording_becomes_one_clip_per_stretch(
    shared_data: Path, recording: Path, tmp_path: Path
) -> None:
    codes, changes = _truth(shared_data)
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    clips = list(iter_recording(recording, LabelTrack(labels, 0.1, _names(tmp_path))))
    names = read_label_names(_names(tmp_path))
    assert [c.label for c in clips] == [names[c] for c in codes]
    assert [c.label for c in clips] == ["JumpJack", "Twist", "KneeRaise", "Squat", "Jog"]
    offsets = [int(c.seq.metadata["frame_offset"]) for c in clips]
    assert offsets == [0, *changes]
    assert sum(c.seq.n_frames for c in clips) == 2465
    # the same through a labels CSV with a label_file column (what train and compare read)
    csv = tmp_path / "recordings.csv"
    csv.write_text(
        "path,label_file,label_block_s,label_names,subject\n"
        f"{recording},{labels},0.1,names.txt,13\n",
        encoding="utf-8",
    )
    from_csv = load_dataset(csv)
    assert [c.label for c in from_csv] == [c.label for c in clips]
    assert {c.subject for c in from_csv} == {"13"}
    assert [c.seq.n_frames for c in from_csv] == [c.seq.n_frames for c in clips]


def test_split_repetitions_gives_each_repetition_as_a_clip(
    shared_data: Path, recording: Path, tmp_path: Path
) -> None:
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    clips = list(iter_recording(recording, LabelTrack(labels, 0.1, _names(tmp_path))))
    split = split_repetitions(clips)
    counts = [count_repetitions(c.seq) for c in clips]
    assert split.kept_whole == 0
    # the jog's steps (0.30-0.40 s each) in left-and-right cycles, two to a clip; the twist's
    # and knee raises' turns (1-2 s) one to a clip, as every other repetition
    assert [r.alternating for r in counts] == [False, True, True, False, True]
    expected = [(r.count + 1) // 2 if c.label == "Jog" else r.count
                for c, r in zip(clips, counts, strict=True)]  # fmt: skip
    assert len(split.clips) == sum(expected)
    squats = [c for c in split.clips if c.label == "Squat"]
    assert len(squats) == 2  # two squats by hand (tests/fixtures/repetition_counts.json)
    assert [c.extras["repetition"] for c in squats] == [1, 2]
    squat_stretch = next(c for c in clips if c.label == "Squat")
    start = int(squat_stretch.seq.metadata["frame_offset"])
    first, second = (int(c.seq.metadata["frame_offset"]) for c in squats)
    assert start <= first < second < start + squat_stretch.seq.n_frames


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _count_cases(db: Path) -> int:
    from casebase_store import open_store

    store = open_store(db, create=False, readonly=True)
    try:
        return store.count_cases("default")
    finally:
        store.close()


def test_train_from_one_recording_with_split_repetitions(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    db = tmp_path / "cb.sqlite"
    names = str(_names(tmp_path))
    argv = ["train", str(recording), "--frame-labels", str(labels), "--label-block", "0.1",
            "--label-names", names, "--split", "repetitions", "--db", str(db)]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr()
    assert "cut 5 clips into" in out.err
    assert "5 activities" in out.out and db.is_file()
    assert main(["casebase", "info", "--db", str(db)]) == 0
    assert "model: predicts label, a case per repetition; k = 5" in capsys.readouterr().out
    # windows are cases of another kind: --append with another --split is refused, in one
    # line, before the recording is read again, and the case base is left as it was
    stored = _sha(db)
    argv[argv.index("repetitions")] = "windows"
    assert main([*argv, "--append"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "holds repetitions (trained with --split repetitions), not windows" in err
    assert _sha(db) == stored
    # the same recording again is refused: its stretches are already cases
    argv.remove("--split")
    argv.remove("windows")
    assert main([*argv, "--append"]) == 1
    err = capsys.readouterr().err.splitlines()[-1]
    assert f"{recording} frames " in err and "is already case " in err
    assert err.endswith("(added before?): nothing added") and _sha(db) == stored
    # so is a copy of it under another name (the same frames and features: tests/test_hunt46f)
    copy = tmp_path / "again.npz"
    copy.write_bytes(recording.read_bytes())
    argv[argv.index(str(recording))] = str(copy)
    assert main([*argv, "--append"]) == 1
    assert "a copy of its file?" in capsys.readouterr().err and _sha(db) == stored
    # without --split, --append cuts as the case base was trained: the recording with its
    # left wrist 1 cm further right gives as many repetitions again
    n = _count_cases(db)
    seq = load_pose(recording)
    moved = seq.positions.copy()
    moved[:, 15, 0] += 0.01  # the left wrist (the mocap has no nose)
    save_pose(dataclasses.replace(seq, positions=moved), copy)
    assert main([*argv, "--append"]) == 0
    assert "cut 5 clips into" in capsys.readouterr().err
    assert _count_cases(db) == 2 * n


def test_train_refuses_a_label_file_that_does_not_fit(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    wrong = shared_data / "cmu-mocap6" / "truelabels" / "13_29.txt"  # 383 labels, 2465 frames
    db = tmp_path / "cb.sqlite"
    before = {p: _sha(p) for p in (recording, wrong)}
    argv = ["train", str(recording), "--frame-labels", str(wrong), "--label-block", "0.1",
            "--db", str(db)]  # fmt: skip
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    # the recording named too: one label file may be named for several (a labels CSV)
    assert (
        "383 labels (one per 0.1 s) do not fit the recording 13_30.npz: 2465 frames at 120 fps"
        in err
    )
    assert str(wrong) in err
    assert not db.exists()
    assert before == {p: _sha(p) for p in (recording, wrong)}


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--asf", "HDM_bd.asf"], "--asf: goes with an AMC recording, not "),
        (["--subjects", "s09"], "--subjects: --frame-labels labels one recording"),
    ],
)
def test_train_refuses_recording_options_it_would_ignore(
    shared_data: Path,
    recording: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    extra: list[str],
    message: str,
) -> None:
    """A skeleton for a recording that is a pose file, and a subject filter over one
    recording's stretches: accepted and ignored before (every case had no subject, the
    skeleton file need not even exist), now one line each, no case base."""
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    before = {p: _sha(p) for p in (recording, labels)}
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(recording), "--frame-labels", str(labels), "--label-block", "0.1",
            "--db", str(db), *extra]  # fmt: skip
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert not db.exists()
    assert before == {p: _sha(p) for p in (recording, labels)}


def test_a_wrong_frame_rate_shows_as_a_label_count_that_does_not_fit(
    recording: Path, shared_data: Path
) -> None:
    """A CMU recording read at 30 fps (the trial number taken for a rate) has a quarter of
    the frames per 0.1 s: its labels no longer fit."""
    from features.poses import load_pose

    seq = load_pose(recording)
    slow = PoseSequence(seq.positions, seq.joint_names, 30.0, source=str(recording))
    labels = read_label_track(shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt")
    with pytest.raises(DataError, match="at 30 fps need 822 "):
        frame_labels(labels, slow.n_frames, slow.fps, 0.1, "13_30.txt")
    assert np.ceil(2465 / 3) == 822


def test_train_leaves_out_a_label_that_flickers_for_a_frame(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """13_30's per-0.1-s labels made per frame (12 frames a label), with one frame in the
    jumping jacks labelled Box and one in the twists labelled Squat: those two one-frame
    stretches are left out, and said so (Box became an activity of one one-frame case);
    the twist around the flicker gives two stretches, as any change of label does."""
    from casebase_store import open_store

    codes = (shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt").read_text().split()
    per_frame = np.repeat(np.array(codes, dtype=object), 12)[:2465]
    assert per_frame[100] == "1" and per_frame[400] == "6"  # jumping jacks, twists
    per_frame[100], per_frame[400] = "8", "3"  # Box, Squat for one frame each
    labels = tmp_path / "frames.txt"
    labels.write_text(" ".join(per_frame.tolist()))
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(recording), "--frame-labels", str(labels), "--label-names",
            str(_names(tmp_path)), "--db", str(db), "--split", "clips"]  # fmt: skip
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "left out 2 labelled stretches shorter than 0.4 s (Box, Squat)" in err
    store = open_store(db, readonly=True)
    info = store.list_case_bases()[0]
    store.close()
    assert info.n_cases == 7  # 5 stretches, the jumping jacks and the twists cut in two


def _cases(db: Path) -> tuple[list[str], np.ndarray, list[tuple[int | None, int | None]]]:
    from casebase_store import open_store

    store = open_store(db, create=False, readonly=True)
    try:
        a = store.load_cases("default")
    finally:
        store.close()
    return list(a.labels), a.features, list(a.frame_ranges)


def test_train_reads_an_amc_recording_with_its_skeleton(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train 13_30.amc --asf HDM_bd.asf --frame-labels ...`` reads the recording as
    ``segment`` does (it had no --asf: convert first): the same cases as from the pose file
    converted from it, stretch for stretch. --asf and --fps without --frame-labels are
    refused in one line (they would apply to no recording)."""
    amc = shared_data / "cmu-mocap6" / "amc" / "13_30.amc"
    asf = shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf"
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    track = ["--frame-labels", str(labels), "--label-block", "0.1", "--split", "clips"]
    from_amc, from_pose = tmp_path / "amc.sqlite", tmp_path / "pose.sqlite"
    assert main(["train", str(amc), "--asf", str(asf), *track, "--db", str(from_amc)]) == 0
    assert main(["train", str(recording), *track, "--db", str(from_pose)]) == 0
    (a_labels, a_features, a_ranges), (p_labels, p_features, p_ranges) = (
        _cases(from_amc),
        _cases(from_pose),
    )
    codes, _ = _truth(shared_data)
    assert sorted(a_labels) == sorted(codes) == sorted(p_labels)
    assert a_ranges == p_ranges
    np.testing.assert_allclose(a_features, p_features, rtol=1e-9, atol=1e-12)
    capsys.readouterr()
    for option, value in (("--asf", str(asf)), ("--fps", "120")):
        db = tmp_path / f"x{option}.sqlite"
        assert main(["train", str(recording), option, value, "--db", str(db)]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"{option}: goes with --frame-labels" in err
        assert not db.exists()


def test_a_recording_too_short_for_any_stretch_says_so(
    recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """0.3 s of 13_30 labelled JumpJack: its one stretch is shorter than a repetition (0.4 s)
    and left out; the error says there is no stretch long enough, not "check --labels and
    --subjects" (neither was given)."""
    from features.poses import load_pose

    seq = load_pose(recording)
    short = save_pose(seq.slice_frames(0, 36), tmp_path / "short.npz")
    labels = tmp_path / "labels.txt"
    labels.write_text("1 1 1\n", encoding="utf-8")
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(short), "--frame-labels", str(labels), "--label-block", "0.1",
            "--db", str(db)]  # fmt: skip
    assert main(argv) == 1
    # the one line (the note on the stretch left out came first: two lines)
    err = capsys.readouterr().err.splitlines()
    assert err == [f"posecbr train: error: {short}: no labelled stretch of 0.4 s or more"]
    assert not db.exists()


def test_windows_that_show_no_person_are_counted_as_windows_of_their_file(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """13_30 with its first 10 s blanked, cut into windows: the windows inside the blank are
    skipped, said as windows of that one file ("skipped 10 clip(s) ...: nan.npz, nan.npz,
    nan.npz, nan.npz, nan.npz ..." counted windows as clips and repeated the file)."""
    import re

    from features.poses import load_pose

    seq = load_pose(recording)
    positions = seq.positions.copy()
    positions[: int(10 * seq.fps)] = np.nan
    path = save_pose(PoseSequence(positions, seq.joint_names, seq.fps), tmp_path / "nan.npz")
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    argv = ["train", str(path), "--frame-labels", str(labels), "--label-block", "0.1",
            "--split", "windows", "--db", str(tmp_path / "cb.sqlite")]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    m = re.search(r"^skipped (\d+) windows that show no person: (.+) \((\d+)\)$", out, re.M)
    assert m is not None, out
    assert m.group(2) == str(path) and m.group(1) == m.group(3) and int(m.group(1)) > 1


def test_codes_that_share_a_name_are_one_activity_and_said_so(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """13_30 (codes 1 JumpJack, 2 Jog, 3 Squat, 4 KneeRaise, 6 Twist) with names that call
    1 and 3 both "Hop": their two stretches are one activity, as asked, and train says so
    (it merged them without a word: a slip of the pen would go unseen)."""
    names = tmp_path / "names.txt"
    names.write_text("1 Hop\n2 Jog\n3 Hop\n4 KneeRaise\n6 Twist\n", encoding="utf-8")
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(recording), "--frame-labels", str(labels), "--label-block", "0.1",
            "--label-names", str(names), "--db", str(db), "--split", "clips"]  # fmt: skip
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert f"note: codes 1 and 3 of {names} are both named Hop: one activity" in err
    assert sorted(_cases(db)[0]) == ["Hop", "Hop", "Jog", "KneeRaise", "Twist"]


def test_a_still_recording_labelled_as_several_activities_is_noted(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """13_30's first frame held for the whole recording, with 13_30's five labelled stretches:
    five cases of one pose, nothing tells them apart; the four after the first (JumpJack,
    frames 0-215) are each said to equal an earlier case of another activity (trained in
    silence before). 13_30 itself, moving, gives no such note."""
    from features.poses import load_pose

    seq = load_pose(recording)
    held = np.repeat(seq.positions[:1], seq.n_frames, axis=0)
    still = save_pose(PoseSequence(held, seq.joint_names, seq.fps), tmp_path / "still.npz")
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    for path, note in ((still, True), (recording, False)):
        db = tmp_path / f"{path.stem}.sqlite"
        argv = ["train", str(path), "--frame-labels", str(labels), "--label-block", "0.1",
                "--db", str(db), "--split", "clips"]  # fmt: skip
        assert main(argv) == 0
        err = capsys.readouterr().err
        assert (
            "note: 4 clips with the same features as a case of another activity: nothing tells "
            f"them apart (a still stretch, or a file copied under another label?): {path} "
            "frames 216-803 (6) = " in err  # end inclusive, as classify and segment
        ) is note, err
        assert ("same features" in err) is note
        assert len(_cases(db)[0]) == 5  # trained all the same


def test_train_makes_a_case_per_window_of_recordings_labelled_over_time(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without --split, a recording labelled over time (``--frame-labels``, or a labels CSV
    row with a label_file) trains a case per 2-s window every 0.5 s, the windows segment
    labels: each of 13_30's five stretches gives its whole windows, ``1 + (frames - 240) //
    60`` at 120 fps, each inside its stretch and named as it; one shorter than a window (the
    jumping jacks, 1.9 s) is kept whole.
    ``--split clips`` keeps a case per stretch; clips labelled one label each stay clips."""
    from casebase_store import open_store
    from cbr.stored import load_classifier

    codes, changes = _truth(shared_data)
    bounds = [0, *changes, 2465]
    names = read_label_names(_names(tmp_path))
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    csv = tmp_path / "recordings.csv"
    csv.write_text(
        f"path,label_file,label_block_s,label_names\n{recording},{labels},0.1,names.txt\n",
        encoding="utf-8",
    )
    lengths = [b - a for a, b in zip(bounds, bounds[1:], strict=False)]
    expected = [1 + (n - 240) // 60 if n >= 240 else 1 for n in lengths]
    for data, extra in ((str(recording), ["--frame-labels", str(labels), "--label-block", "0.1",
                                          "--label-names", str(_names(tmp_path))]),
                        (str(csv), ["--json"])):  # fmt: skip
        db = tmp_path / f"{len(extra)}.sqlite"
        assert main(["train", data, *extra, "--db", str(db)]) == 0
        out, err = capsys.readouterr()
        assert "recordings labelled over time: a case per window" in err, err
        if extra == ["--json"]:
            assert json.loads(out)["split"] == "windows"
        cases, _, ranges = _cases(db)
        assert len(cases) == sum(expected) and len(ranges) == len(cases)
        for label, (start, end) in zip(cases, ranges, strict=True):
            assert start is not None and end is not None
            i = int(np.searchsorted(bounds, start, side="right")) - 1
            assert end - start == min(240, lengths[i]) and end <= bounds[i + 1]
            assert label == names[codes[i]], (label, start, end)
        store = open_store(db, create=False, readonly=True)
        try:
            assert load_classifier(store, "default").cases == "windows"
        finally:
            store.close()
    db = tmp_path / "clips.sqlite"
    assert main(["train", str(csv), "--db", str(db), "--split", "clips", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["split"] == "clips"
    assert len(_cases(db)[0]) == 5
    # a labels CSV of clips with one label each stays a case per clip
    plain = tmp_path / "plain.csv"
    plain.write_text(
        f"path,label,start,end\n{recording},Mixed,0,600\n{recording},Other,600,1200\n",
        encoding="utf-8",
    )
    db = tmp_path / "plain.sqlite"
    capsys.readouterr()
    assert main(["train", str(plain), "--db", str(db)]) == 0
    assert "labelled over time" not in capsys.readouterr().err
    assert len(_cases(db)[0]) == 2


def test_train_of_recordings_labelled_over_time_on_a_cluster_asks_for_split_clips(
    recording: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.badinput import refused

    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    csv = tmp_path / "recordings.csv"
    csv.write_text(f"path,label_file,label_block_s\n{recording},{labels},0.1\n", encoding="utf-8")
    argv = ["train", str(csv), "--db", str(tmp_path / "cb.sqlite"), "--scheduler", "local:1"]
    refused(argv, tmp_path, capsys, "--scheduler", "--split clips")


def test_train_k_is_held_to_the_windows_that_become_cases(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """13_30 with its jumping jacks and twists blanked (nobody seen): their windows are no
    cases, so -k is held to the windows of the other three stretches, worked out from the
    label file (``1 + (frames - 240) // 60`` each at 120 fps). It was held to every window cut,
    blank ones too: a k above the cases was stored (every case voting)."""
    from features.poses import load_pose
    from tests.badinput import refused

    codes, changes = _truth(shared_data)
    bounds = [0, *changes, 2465]
    seq = load_pose(recording)
    positions = seq.positions.copy()
    positions[: bounds[2]] = np.nan  # JumpJack and Twist, the first two stretches
    path = save_pose(PoseSequence(positions, seq.joint_names, seq.fps), tmp_path / "blank.npz")
    lengths = [b - a for a, b in zip(bounds, bounds[1:], strict=False)]
    windows = [1 + (n - 240) // 60 if n >= 240 else 1 for n in lengths]
    seen, blank = sum(windows[2:]), sum(windows[:2])
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    argv = ["train", str(path), "--frame-labels", str(labels), "--label-block", "0.1",
            "--db", str(tmp_path / "cb.sqlite")]  # fmt: skip
    need = f"-k: must be at most the {seen} cases ({blank} windows left out"
    refused([*argv, "-k", str(seen + 1)], tmp_path, capsys, need, f"got {seen + 1}")
    assert main([*argv, "-k", str(seen)]) == 0
    assert _count_cases(tmp_path / "cb.sqlite") == seen


def test_codes_that_share_a_name_in_a_labels_csv_are_said_and_a_refusal_is_one_line(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV's label_names file that names codes 1 and 3 "Hop" merges their stretches
    as --label-names does, and says so as --label-names does (it merged them in silence).
    With a refusal after the names are read (-k above the cases), the refusal is the one
    line: --label-names' note came before it."""
    from tests.badinput import refused

    names = tmp_path / "names.txt"
    names.write_text("1 Hop\n2 Jog\n3 Hop\n4 KneeRaise\n6 Twist\n", encoding="utf-8")
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    csv = tmp_path / "recordings.csv"
    csv.write_text(
        f"path,label_file,label_block_s,label_names\n{recording},{labels},0.1,names.txt\n",
        encoding="utf-8",
    )
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(csv), "--db", str(db), "--split", "clips"]) == 0
    err = capsys.readouterr().err
    assert err.count(f"note: codes 1 and 3 of {names} are both named Hop: one activity") == 1
    assert sorted(_cases(db)[0]) == ["Hop", "Hop", "Jog", "KneeRaise", "Twist"]
    db.unlink()
    for data, extra in ((str(csv), []), (str(recording), ["--frame-labels", str(labels),
                        "--label-block", "0.1", "--label-names", str(names)])):  # fmt: skip
        argv = ["train", data, *extra, "--db", str(db), "--split", "clips", "-k", "6"]
        refused(argv, tmp_path, capsys, "-k: must be at most the 5 cases, got 6")


def test_a_labels_csv_leaves_out_a_flicker_as_frame_labels_does(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """13_30's labels with one 0.1-s block in the twists labelled Squat, named in a labels
    CSV and cut into windows: the 12-frame stretch is left out and said as a labelled
    stretch, as with --frame-labels (it was kept whole as a "window" and then "skipped 1
    window shorter than one movement can be ... (lasts 0.10 s)"). The cases: the windows
    of the six stretches around it, ``1 + (frames - 240) // 60`` each at 120 fps (whole
    when shorter than 240 frames)."""
    codes = (shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt").read_text().split()
    assert codes[40] == "6"  # in the twists (blocks 18-66)
    codes[40] = "3"
    labels = tmp_path / "flicker.txt"
    labels.write_text(" ".join(codes), encoding="utf-8")
    csv = tmp_path / "recordings.csv"
    csv.write_text(
        f"path,label_file,label_block_s,label_names\n{recording},{labels},0.1,names.txt\n",
        encoding="utf-8",
    )
    _names(tmp_path)
    changes = [i for i in range(1, len(codes)) if codes[i] != codes[i - 1]]
    bounds = [0, *(12 * i for i in changes), 2465]
    lengths = [b - a for a, b in zip(bounds, bounds[1:], strict=False) if b - a != 12]
    assert len(lengths) == 6  # JumpJack, Twist, Twist, KneeRaise, Squat, Jog
    windows = sum(1 + (n - 240) // 60 if n >= 240 else 1 for n in lengths)
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(csv), "--db", str(db)]) == 0
    out, err = capsys.readouterr()
    assert "left out 1 labelled stretch shorter than 0.4 s (Squat)" in err
    # six stretches of 0.4 s or more; the jumping jacks' (216 frames) under a window, whole
    assert "cut 5 clips into " in err and "skipped" not in out
    assert "; 1 clip shorter than a window kept whole" in err
    assert _count_cases(db) == windows


def test_compare_on_recordings_labelled_over_time_says_it_compares_stretches(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """compare cross-validates a clip per labelled stretch, while train makes a case per 2-s
    window of the same CSV by default: its figures are those of --split clips, and it says
    so (nothing did: they read as the figures of the case base train makes). A labels CSV of
    clips with one label each gets no such note."""
    copy = tmp_path / "13_30_again.npz"
    copy.write_bytes(recording.read_bytes())
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    _names(tmp_path)
    csv = tmp_path / "recordings.csv"
    csv.write_text(
        "path,label_file,label_block_s,label_names,subject\n"
        f"{recording},{labels},0.1,names.txt,a\n{copy},{labels},0.1,names.txt,b\n",
        encoding="utf-8",
    )
    plain = tmp_path / "plain.csv"
    plain.write_text(
        f"path,label,subject,start,end\n{recording},Twist,a,216,804\n"
        f"{recording},Squat,a,1416,1932\n{copy},Twist,b,216,804\n{copy},Squat,b,1416,1932\n",
        encoding="utf-8",
    )
    fast = ["--similarities", "euclidean", "--features", "fluents", "--no-dad", "--peers",
            "none", "--explain", "0", "--k", "1"]  # fmt: skip
    for data, said in ((csv, True), (plain, False)):
        assert main(["compare", str(data), *fast]) == 0
        err = capsys.readouterr().err
        assert ("one clip here, not cut into the 2-s windows" in err) is said, err
        assert ("those of train --split clips" in err) is said


def test_a_labels_csv_of_flickers_alone_says_no_stretch_is_long_enough(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """13_30's 206 blocks labelled 1, 3, 1, 3, ...: every stretch is 0.1 s, all left out; the
    refusal says no stretch is long enough, as --frame-labels', not "no clips found"."""
    from tests.badinput import refused

    labels = tmp_path / "flicker.txt"
    labels.write_text(" ".join(["1", "3"] * 103), encoding="utf-8")
    csv = tmp_path / "recordings.csv"
    csv.write_text(f"path,label_file,label_block_s\n{recording},{labels},0.1\n", encoding="utf-8")
    argv = ["train", str(csv), "--db", str(tmp_path / "cb.sqlite")]
    refused(argv, tmp_path, capsys, f"{csv}: no labelled stretch of 0.4 s or more")


def test_classify_notes_a_whole_recording_against_a_case_base_of_windows(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case base of 2-s windows gives a whole recording (13_30: 2465 frames at 120 fps,
    20.5 s, five activities) one answer: said, pointing to segment; a 4-s stretch of it
    (480 frames) is not noted, nor is anything against a case base of clips."""
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    track = ["--frame-labels", str(labels), "--label-block", "0.1"]
    windows, clips = tmp_path / "w.sqlite", tmp_path / "c.sqlite"
    assert main(["train", str(recording), *track, "--db", str(windows)]) == 0
    assert main(["train", str(recording), *track, "--db", str(clips), "--split", "clips"]) == 0
    csv = tmp_path / "part.csv"
    csv.write_text(f"path,label,start,end\n{recording},Twist,300,780\n", encoding="utf-8")
    capsys.readouterr()
    assert main(["classify", str(recording), "--db", str(windows)]) == 0
    err = capsys.readouterr().err
    assert "holds a case per 2-s window and 1 clip lasts longer than 10 s (20.5 s)" in err, err
    assert "posecbr segment" in err
    for db, data in ((windows, csv), (clips, recording)):
        assert main(["classify", str(data), "--db", str(db)]) == 0
        out, err = capsys.readouterr()
        assert "holds a case per" not in err
        # the part's label, Twist, is no activity of the case base (its codes 1-6 unnamed)
        assert ("has no case of 'Twist'" in err) == (data == csv), err
        # a piece of a file is named with its frames (end inclusive); the whole file alone
        first = out.splitlines()[0]
        assert first.startswith(f"{recording} "), first
        assert ("frames 300-779" in first) == (data == csv), first
    assert main(["classify", str(csv), "--db", str(windows), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["results"][0]["frames"] == [300, 780]


def test_windows_of_one_recording_are_calibrated_held_out_from_their_overlapping_ones(
    shared_data: Path, recording: Path, tmp_path: Path
) -> None:
    """Windows cut from one recording every 0.5 s were held out one at a time for the
    confidence and the "unlike" calibration: a window's nearest cases were the windows
    overlapping it, so every held-out answer was right and every later answer got the
    confidence of a sure one (0.96). They are now held out with the windows they overlap."""
    from casebase_store import open_store
    from cbr.stored import load_classifier

    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    db = tmp_path / "w.sqlite"
    argv = ["train", str(recording), "--frame-labels", str(labels), "--label-block", "0.1"]
    assert main([*argv, "--db", str(db)]) == 0
    store = open_store(db, create=False, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    assert clf.confidence_.basis == clf.novelty_.basis == "leave-overlapping-out"
    # 13_30's stretches (1.8-5.1 s) are its activities' only ones: only the windows of the
    # stretches long enough to hold two windows that do not overlap can be answered, and
    # not all are right
    assert clf.confidence_.n < len(clf.case_base_) and clf.confidence_.accuracy < 1.0


def _converted_stretches(shared_data: Path, recording: Path, tmp_path: Path) -> Path:
    """13_30's labelled stretches, each written by ``convert`` to a pose file of its own in
    ``tmp_path/pieces`` (with a ``labels.csv`` naming them)."""
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    _names(tmp_path)
    listing = tmp_path / "recordings.csv"
    listing.write_text(
        f"path,label_file,label_block_s,label_names\n{recording},{labels},0.1,names.txt\n",
        encoding="utf-8",
    )
    assert main(["convert", str(listing), "--out", str(tmp_path / "pieces")]) == 0
    return tmp_path / "pieces"


def test_train_notes_stretches_that_convert_cut_from_a_recording(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``convert`` of a labels CSV with a label_file writes each labelled stretch as a pose
    file of its own; ``train`` on those made a case per stretch without a word, where ``train``
    of the CSV itself makes a case per window (a stretch as one case lies far from any
    window). 13_30's label file has 5 stretches (worked out from it here), all but the first
    (1.8 s) longer than two windows: the note names 5 clips cut from 1 recording. Given
    ``--split clips``, or trained on a labels CSV's rows of the recording, there is no note."""
    codes, _ = _truth(shared_data)
    _converted_stretches(shared_data, recording, tmp_path)
    capsys.readouterr()
    pieces = tmp_path / "pieces" / "labels.csv"
    assert main(["train", str(pieces), "--db", str(tmp_path / "a.sqlite"), "-k", "1"]) == 0
    err = capsys.readouterr().err
    assert f"note: {len(codes)} clips are labelled stretches cut from 1 recording" in err
    assert "--split windows makes a case per 2-s window" in err
    argv = ["train", str(pieces), "--db", str(tmp_path / "b.sqlite"), "-k", "1"]
    assert main([*argv, "--split", "clips"]) == 0
    assert "labelled stretches cut from" not in capsys.readouterr().err
    whole = tmp_path / "whole.csv"  # rows of the recording itself: no file cut from it
    whole.write_text(
        f"path,label,start,end\n{recording},a,0,600\n{recording},b,600,1200\n", encoding="utf-8"
    )
    assert main(["train", str(whole), "--db", str(tmp_path / "c.sqlite"), "-k", "1"]) == 0
    assert "labelled stretches cut from" not in capsys.readouterr().err


def test_classify_names_a_stretch_file_by_the_frames_of_its_recording(
    shared_data: Path, recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A stretch ``convert`` wrote (the third of 13_30: KneeRaise) keeps where it lay in its
    recording; ``classify`` named it "13_30_3.npz frames 804-1415", frames the 612-frame
    file does not have. It now says whose frames they are: "... of <recording>" (the change
    positions worked out from the label file, 12 frames a label)."""
    _, changes = _truth(shared_data)
    _converted_stretches(shared_data, recording, tmp_path)
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(tmp_path / "pieces" / "labels.csv"), "--db", str(db), "-k", "1"]) == 0
    capsys.readouterr()
    third = tmp_path / "pieces" / "13_30_3.npz"
    assert main(["classify", str(third), "--db", str(db)]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith(f"{third} frames {changes[1]}-{changes[2] - 1} of ")
    origin = f"{recording.parent.name}/{recording.name}"  # convert keeps the folder above
    assert f"{changes[2] - 1} of {origin} " in first
    assert main(["classify", str(third), "--db", str(db), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)["results"][0]
    assert result["frames"] == [changes[1], changes[2]]
    assert result["origin"] == origin


def test_label_codes_not_named_are_listed_by_number(tmp_path: Path) -> None:
    """Codes 10, 3 and 1 not in a names file naming 2 only: listed 1, 3, 10 (by value), not
    1, 10, 3 (as text); a code that is no number comes after them."""
    names = tmp_path / "names.txt"
    names.write_text("2 Jog\n", encoding="utf-8")
    track = tmp_path / "track.txt"
    track.write_text("10 3 2 1 x 10\n", encoding="utf-8")
    with pytest.raises(DataError, match=r"label code\(s\) 1, 3, 10, x not in the label names"):
        read_label_track(track, read_label_names(names))
