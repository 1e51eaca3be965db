"""A physiotherapist's session judged repetition by repetition (issue 14): ``classify
--split repetitions`` cuts a recording into the repetitions ``reps`` counts and answers and
explains each alone; ``cbr.training.cut`` cuts a clip not labelled; a recording joined from
repetitions says of itself only what they all say."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cbr.training import cut
from features.joining import join_repetitions
from features.poses import save_pose
from posecbr.cli import main
from tests.bodies import squat_clip
from tests.once import made_once
from tests.test_classify_output import _data_and_stores

# a session of a new person: deep squats are the correct repetitions, shallow ones the
# incorrect (as the case base's training clips are labelled), in this order
ORDER = ((0.95, "correct"), (0.5, "incorrect"), (0.92, "correct"))


@pytest.fixture(scope="module")
def stores(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """test_classify_output's case bases (deep squats correct, shallow incorrect), made once
    in the whole run."""
    return made_once(tmp_path_factory, "classify-output", _data_and_stores)[1]


def _session(tmp_path: Path) -> tuple[Path, list[tuple[int, int]]]:
    """The session as one pose file, and each repetition's frames [start, end) in it."""
    reps = [squat_clip(depth, 50, 40.0, 10.0, f"rep{i}.npz") for i, (depth, _) in enumerate(ORDER)]
    joined = join_repetitions(reps)
    path = tmp_path / "session.npz"
    save_pose(replace(joined.seq, source=""), path)  # a recording of its own, made of nothing
    return path, [(int(s), int(s) + 50) for s in joined.starts]


def _covering(spans: list[tuple[int, int]], a: int, b: int) -> int:
    """The true repetition the piece [a, b) covers most of."""
    return int(np.argmax([max(0, min(b, d) - max(a, c)) for c, d in spans]))


def test_a_session_is_judged_and_explained_repetition_by_repetition(
    stores: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    session, spans = _session(tmp_path)
    argv = ["classify", str(session), "--db", stores["correct"], "--split", "repetitions"]
    assert main([*argv, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    got = doc["results"]
    assert len(got) == len(ORDER) and doc["clips_given"] == 1
    for r, (a, b), (_, verdict) in zip(got, spans, ORDER, strict=True):
        # each answer is of one repetition: the piece lies over it, at least half of it
        assert _covering(spans, r["start_frame"], r["end_frame"]) == spans.index((a, b))
        assert min(b, r["end_frame"]) - max(a, r["start_frame"]) >= 0.5 * (b - a)
        assert r["label"] == verdict, r["text"]
        assert r["true_label"] is None  # the session is not labelled
    assert doc["summary"]["answers"] == {"correct": 2, "incorrect": 1}
    # a shallow squat is said to be done differently from the correct repetitions
    wrong = [r for r in got if r["label"] == "incorrect"]
    assert all("Done differently from correct repetitions: " in r["text"] for r in wrong)
    assert all(any(c["part"] == "outside" for c in r["claims"]) for r in wrong)
    # and a deep one why it is correct, against the range of the correct repetitions
    right = [r for r in got if r["label"] == "correct"]
    assert all("Why: " in r["text"] and "(correct ones: " in r["text"] for r in right)
    assert not any("its cases" in r["text"] for r in got)

    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "\n1 clip cut into 3 repetitions: 3 classified; " in out
    assert "\nanswers: a correct repetition 2, an incorrect repetition 1\n" in out
    for a, b in [(r["start_frame"], r["end_frame"]) for r in got]:
        assert f"session.npz frames {a}-{b - 1}: " in out  # end inclusive, as reps prints it


def test_a_clip_without_a_repetition_is_classified_whole_and_said(
    stores: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    still = tmp_path / "still.npz"
    save_pose(squat_clip(0.0, 60), still)  # standing still for 2 s: nothing repeats
    argv = ["classify", str(still), "--db", stores["correct"], "--split", "repetitions"]
    assert main([*argv, "--json"]) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert len(doc["results"]) == 1 and "start_frame" not in doc["results"][0]
    assert "note: no repetition found in 1 clip (still.npz): it is classified whole" in (
        captured.err
    )


def test_split_repetitions_with_feedback_is_refused_in_one_line(
    stores: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    session, _ = _session(tmp_path)
    argv = ["classify", str(session), "--db", stores["correct"], "--split", "repetitions"]
    assert main([*argv, "--feedback", "correct"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "goes without --feedback" in err


def test_cut_takes_clips_not_labelled() -> None:
    reps = [squat_clip(depth, 50) for depth, _ in ORDER]
    joined = join_repetitions(reps)
    pieces, labels = cut([joined.seq], None, "repetitions")
    assert labels == [None] * len(ORDER) and len(pieces) == len(ORDER)
    spans = [(int(s), int(s) + 50) for s in joined.starts]
    for k, piece in enumerate(pieces):  # each piece lies over its own repetition, most of it
        a = int(piece.metadata["frame_offset"])
        b = a + piece.n_frames
        assert _covering(spans, a, b) == k
        assert min(b, spans[k][1]) - max(a, spans[k][0]) >= 0.5 * 50


def test_a_joined_recording_keeps_only_what_its_repetitions_share() -> None:
    def rep(episode: int, correct: bool) -> object:
        seq = squat_clip(0.9, 40, source=f"m01_s09_e{episode:02d}.npz")
        meta = {"subject": "s09", "label": "deep_squat", "episode": episode,
                "correct": correct, "origin": f"raw/e{episode}.txt", "frame_offset": 0}  # fmt: skip
        return seq.with_metadata(**meta)

    joined = join_repetitions([rep(1, False), rep(2, True), rep(3, True)]).seq
    # the subject and the movement hold for the whole recording
    assert joined.metadata["subject"] == "s09" and joined.label == "deep_squat"
    # the first repetition's verdict, episode and file are not the recording's
    for key in ("correct", "episode", "origin", "frame_offset"):
        assert key not in joined.metadata, key


def test_each_record_says_right_beside_a_verdict_it_cannot_be_taken_for(
    tmp_path_factory: pytest.TempPathFactory, capsys: pytest.CaptureFixture[str]
) -> None:
    (_, test), stores = made_once(tmp_path_factory, "classify-output", _data_and_stores)
    assert main(["classify", str(test), "--db", stores["correct"], "--json"]) == 0
    records = json.loads(capsys.readouterr().out)["results"]
    assert len(records) == 4
    for r in records:
        truth = "correct" if "_deep_" in r["clip"] else "incorrect"  # as the CSV labels them
        assert r["true_label"] == truth
        assert r["right"] is (r["label"] == truth)


def test_segment_of_a_session_against_a_repetition_check_points_to_each_repetition(
    stores: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A repetition check has two classes: segment's default judge of unknown is refused
    (as before), and with --unknown held-out it labels 2-s windows correct or incorrect;
    both now say how each repetition is judged (where the note said to train windows)."""
    session, _ = _session(tmp_path)
    db = stores["correct"]
    hint = f"posecbr classify RECORDING --db {db} --split repetitions"
    assert main(["segment", str(session), "--db", db]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cannot judge unknown" in err and hint in err
    assert main(["segment", str(session), "--db", db, "--unknown", "held-out"]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if line.startswith("note:")]
    assert [n for n in notes if "predicts 'correct', not activities" in n and hint in n]
    assert not [n for n in notes if "--split windows" in n]


def test_a_repetition_check_of_several_activities_is_noted(
    tmp_path_factory: pytest.TempPathFactory, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The test clips: two activities (deep and shallow squats), correct and incorrect.
    Trained as one repetition check, a note says one per activity judges better."""
    (_, test), _ = made_once(tmp_path_factory, "classify-output", _data_and_stores)
    capsys.readouterr()  # the notes of the fixture's own training, when made here
    db = str(tmp_path / "check.sqlite")
    assert main(["train", str(test), "--db", db, "--target", "correct"]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "activities (" in line]
    assert len(notes) == 1
    assert notes[0].startswith(
        "note: a case base predicting 'correct' of 2 activities (deep squat, shallow squat): "
        "each repetition is judged among every activity's cases; one per activity (posecbr "
        "train DATA --labels ACTIVITY --target correct, as compare --target correct trains "
        "them) judges it among its own activity's cases only: expect more of a new person's "
        'repetitions judged right (README, "A patient\'s session, repetition by repetition")'
    )
    assert main(["train", str(test), "--db", str(tmp_path / "labels.sqlite")]) == 0
    assert "activities (" not in capsys.readouterr().err
