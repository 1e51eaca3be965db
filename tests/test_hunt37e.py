"""Hunt 37e: a physiotherapist's first hour with their own videos (extract, train a case base
of repetitions, classify, segment, reps, watch): what read wrong or could not be done."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.segmentation import told
from features.poses import PoseSequence, load_pose, save_pose
from features.repetitions import count_repetitions
from posecbr.cli import main
from tests.badinput import refused, standing_clip
from tests.test_hunt34e import _raises, raises_case_base
from tests.test_repetitions import _movement

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def test_reps_gives_no_period_beside_one_repetition(capsys: pytest.CaptureFixture[str]) -> None:
    """A UI-PRMD file holds one repetition by the data set's design (one episode each). On
    m01_s02_e02 ``reps`` said "1 repetition (period 0.80 s; ...)" and ``--json`` gave
    ``"period_s": 0.8``: one far point repeats nothing, and the 0.80 s (read from the
    autocorrelation's first weak peak, periodicity 0.06) is not even the repetition's own
    length, frames 12-63 (1.73 s). Now neither gives a period; two arm raises of designed
    period 1.8 s (1.2 s up and down, 0.6 s of rest) keep theirs."""
    clip = DEMO / "m01_s02_e02.npz"
    assert main(["reps", str(clip)]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert head.startswith(f"{clip}: 1 repetition ("), head
    assert "period" not in head
    assert main(["reps", str(clip), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["count"], doc["period_s"], doc["periodicity"]) == (1, None, None)
    two = count_repetitions(_movement(["both"] * 2))
    assert two.count == 2
    assert two.repeated_period_s == pytest.approx(1.8, abs=0.1)
    assert two.to_dict()["period_s"] == pytest.approx(1.8, abs=0.1)


def test_one_similar_case_of_the_answer_is_said_in_the_singular() -> None:
    """One deep squat among four hurdle steps, k = 5: the squat itself has that one squat
    nearest (its own copy) and the four hurdle steps after it, and wins the distance vote.
    ``classify --verbose`` said "Vote: 1 of the 5 most similar clips are deep_squat" and
    ``segment``/``watch`` explained a segment "1 of the 5 most similar cases are lunge"
    (seen on a joined video of the bundled exercises); now "is", and "are" for four. The
    vote's line says "cases", as the lines under it list them ("case #3 ..."), and as
    ``segment`` says: a case may be a repetition or a window, not a clip."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    squats = [r for r in rows if r["label"] == "deep_squat"]
    steps = [r for r in rows if r["label"] == "hurdle_step"][:4]
    X = [load_pose(DEMO / r["path"]) for r in [squats[0], *steps]]
    clf = CaseBaseClassifier(k=5).fit(X, ["deep_squat"] + ["hurdle_step"] * 4)
    verbose = clf.explain([X[0]])[0].verbose
    assert "Vote: 1 of the 5 most similar cases is deep_squat (" in verbose, verbose
    solved = clf.solve([X[0]])[0]
    assert told(clf, solved, "deep_squat").startswith("1 of the 5 most similar cases is deep_squat")
    assert told(clf, solved, "hurdle_step").startswith(
        "4 of the 5 most similar cases are hurdle_step"
    )


def _six_clip_case_base(tmp_path: Path) -> Path:
    """A case base of six bundled demo clips: three deep squats and three hurdle steps."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    train_rows = [r for r in rows if r["label"] == "deep_squat"][6:12:2]
    train_rows += [r for r in rows if r["label"] == "hurdle_step"][:6:2]
    lines = ["path,label"] + [f"{DEMO / r['path']},{r['label']}" for r in train_rows]
    (tmp_path / "train.csv").write_text("\n".join(lines) + "\n")
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(tmp_path / "train.csv"), "--db", str(db)]) == 0
    return db


def test_classify_takes_a_labels_csv_row_left_unlabelled(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``classify``'s note for a clip of several repetitions says to give them "as rows
    path,label,start,end of a labels CSV", but a new patient's video has no label, and a
    row with an empty one was refused ("line 2: empty label"): a label had to be made up,
    then counted wrong. Now a row may leave it empty: the clip is classified and checked
    against its pose file's own label when it holds one (m01_s01_e02, a deep squat), else
    not at all. ``train`` still refuses the row, in one line, writing nothing."""
    db = _six_clip_case_base(tmp_path)
    capsys.readouterr()
    squat = load_pose(DEMO / "m01_s02_e01.npz")
    new = save_pose(
        PoseSequence(squat.positions, squat.joint_names, squat.fps), tmp_path / "new.npz"
    )
    assert load_pose(new).label is None  # a clip nobody labelled
    (tmp_path / "pieces.csv").write_text(
        "path,label,start,end\n"
        f"new.npz,,0,40\n"
        f"new.npz,,30,{squat.n_frames}\n"
        f"{DEMO / 'm01_s01_e02.npz'},,0,60\n"
    )
    assert main(["classify", str(tmp_path / "pieces.csv"), "--db", str(db), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    got = [(r["start_frame"], r["end_frame"], r["true_label"]) for r in doc["results"]]
    assert got == [(0, 40, None), (30, squat.n_frames, None), (0, 60, "deep_squat")]
    assert all(r["label"] in ("deep_squat", "hurdle_step") for r in doc["results"])
    assert (doc["summary"]["clips"], doc["summary"]["labelled"]) == (3, 1)
    refused(
        ["train", str(tmp_path / "pieces.csv"), "--db", str(tmp_path / "x.sqlite")],
        tmp_path,
        capsys,
        "pieces.csv: line 2: empty label",
    )


def test_the_repetition_note_names_pieces_of_a_file_with_their_frames(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two pieces of one file, each of three arm raises by construction, classified from a
    labels CSV against a case base of repetitions: the note said "2 clips hold several
    (six.npz: 3, six.npz: 3)", one name for two clips; it names each piece with its frames
    now, as the clip's own lines and the summary do (end inclusive)."""
    db = raises_case_base(tmp_path)
    rest = 15  # 0.5 s of standing before, between and after the raises (_raises)
    each = _raises(85.0, 1).n_frames - rest  # one raise and the rest after it
    save_pose(_raises(85.0, 6), tmp_path / "six.npz")
    half = rest + 3 * each  # the first three raises and their rests
    (tmp_path / "pieces.csv").write_text(
        "path,label,start,end\n"
        f"six.npz,high,0,{half}\nsix.npz,high,{half - rest},{rest + 6 * each}\n"
    )
    capsys.readouterr()
    assert main(["classify", str(tmp_path / "pieces.csv"), "--db", str(db), "-q"]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "per repetition" in line]
    assert len(notes) == 1
    first, second = f"six.npz frames 0-{half - 1}", f"six.npz frames {half - rest}-{6 * each + 14}"
    assert f"2 clips hold several ({first}: 3, {second}: 3)" in notes[0], notes[0]


def test_a_range_with_a_negative_end_is_said_with_to() -> None:
    """The jumping jacks classified against the bundled exercises: "right knee height
    (lowest) -0.85 torso lengths (its cases: -0.85–-0.84)", the dash and the minus sign side
    by side. A range with a negative end reads "-0.85 to -0.84" now; others as before."""
    from cbr.explain import Claim, _claim_text

    knee = Claim("why", "c", "f", "right knee height (lowest)", -0.85, "torso lengths",
                 low=-0.852, high=-0.84)  # fmt: skip
    assert _claim_text(knee, "its cases") == (
        "right knee height (lowest) -0.85 torso lengths (its cases: -0.85 to -0.84)"
    )
    nose = Claim("why", "c", "f", "nose height", 1.30, "torso lengths", low=1.28, high=1.31)
    assert _claim_text(nose, "its cases") == "nose height 1.30 torso lengths (its cases: 1.28–1.31)"


def test_classify_json_names_true_label_and_correct_for_every_clip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A script reading ``classify --json`` takes ``r["true_label"]`` and ``r["correct"]``
    of each record; both were absent from an unlabelled clip's record (a new video's pose
    file, no label in it), so the script failed on the first such clip with a KeyError.
    Both are in every record now: null when the clip has no label; the labelled clip's as
    before (m01_s01_e02 is a deep squat by its file's label)."""
    db = _six_clip_case_base(tmp_path)
    squat = load_pose(DEMO / "m01_s02_e01.npz")
    new = save_pose(
        PoseSequence(squat.positions, squat.joint_names, squat.fps), tmp_path / "new.npz"
    )
    capsys.readouterr()
    labelled = DEMO / "m01_s01_e02.npz"
    assert main(["classify", str(new), str(labelled), "--db", str(db), "--json"]) == 0
    first, second = json.loads(capsys.readouterr().out)["results"]
    assert (first["true_label"], first["correct"]) == (None, None)
    assert second["true_label"] == "deep_squat"
    assert second["correct"] == (second["label"] == "deep_squat")


def test_casebase_info_says_the_summary_features_flag_nothing_with_few_clips(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Six training clips (three deep squats, three hurdle steps): too few held-out clips to
    tell a 1-in-50 one, so only the distance flags a clip unlike the stored cases (README:
    below 49 held-out clips). ``casebase info`` said the clip is also flagged when "its
    summary features ... less usual than 100.0 % of held-out clips' (one statistic of all the
    scores: 2 % of held-out clips flagged)", a rule that flags nothing. It says so now."""
    db = _six_clip_case_base(tmp_path)
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db)]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "unlike the stored" in x)
    assert "less usual than" not in line, line
    assert line.endswith(
        "; its summary features flag no clip: 6 held-out clips are too few to tell a 1-in-50 one"
    ), line


def test_train_names_the_clips_without_a_repetition(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two clips of two arm raises each per label, and one of a person standing still (no
    repetition by construction), trained ``--split repetitions``: ``train`` said "cut 4
    clips into 8 repetitions; 1 clip without a repetition kept whole" without saying which,
    so a physiotherapist could not tell which exercise video found none (a held side plank,
    or one the tracker lost). It names it now."""
    rows = ["path,label"]
    for k, (label, top) in enumerate(
        (("high", 90.0), ("low", 40.0), ("high", 95.0), ("low", 45.0))
    ):
        save_pose(_raises(top, 2), tmp_path / f"{label}{k}.npz")
        rows.append(f"{label}{k}.npz,{label}")
    save_pose(standing_clip(60), tmp_path / "still.npz")
    rows.append("still.npz,low")
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    argv = ["train", str(tmp_path / "labels.csv"), "--db", str(tmp_path / "cb.sqlite")]
    assert main([*argv, "--split", "repetitions"]) == 0
    err = capsys.readouterr().err
    assert (
        "cut 4 clips into 8 repetitions; 1 clip without a repetition kept whole (still.npz)" in err
    ), err
